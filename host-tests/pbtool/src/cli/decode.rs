//! `pbtool decode`.

use std::process::ExitCode;

use clap::Args;
use pbtool::decode::{all_valid, decode_frames, to_json, to_text};

#[derive(Args)]
pub struct DecodeArgs {
    /// Print one JSON object per frame, one per line.
    #[arg(long)]
    json: bool,
    /// Frames, e.g. `:010430440004<CR><LF>` `:010408007900790000000001`.
    #[arg(required = true, value_name = "FRAME")]
    frames: Vec<String>,
}

pub fn decode(args: &DecodeArgs) -> ExitCode {
    let reports = decode_frames(&args.frames);
    if args.json {
        for report in &reports {
            println!("{}", to_json(report));
        }
    } else {
        print!("{}", to_text(&reports));
    }
    if all_valid(&reports) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
