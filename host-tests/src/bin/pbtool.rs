//! pbtool: the plasma-bridge technician's tool.
//!
//! `pbtool decode FRAME...` explains Modbus ASCII (`:`) and HPR (`>`) frames. Subcommands are
//! a clap enum so more tools (a simulator) slot in next to `decode`.

use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use host_tests::decode::{all_valid, decode_frames, to_json, to_text};

#[derive(Parser)]
#[command(
    name = "pbtool",
    version,
    about = "Tools for the plasma-bridge and Hypertherm power supplies"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Explain Modbus ASCII (`:...`) and HPR (`>...<`) frames.
    ///
    /// Each argument is one frame, with or without CR LF or the manuals' `<CR><LF>`. A frame
    /// right after a request is read as its reply. Exit status 1 when any frame is invalid.
    Decode(DecodeArgs),
}

#[derive(Args)]
struct DecodeArgs {
    /// Print one JSON object per frame, one per line.
    #[arg(long)]
    json: bool,
    /// Frames, e.g. `:010430440004<CR><LF>` `:010408007900790000000001`.
    #[arg(required = true, value_name = "FRAME")]
    frames: Vec<String>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Decode(args) => decode(&args),
    }
}

fn decode(args: &DecodeArgs) -> ExitCode {
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
