//! `pbtool history --sim MODEL | --emu [--ps MODEL] | --port DEV`.

use std::process::ExitCode;

use clap::Args;
use pbtool::emu::EmuUnit;
use pbtool::history::{csv, from_emu, from_sim, json, over_port, rows, table};
use plasma_protocol::cnc::HISTORY_MAX;

use super::bridge::{Bridge, BridgeArgs};
use super::{USAGE, simulated_unit};

#[derive(Args)]
pub struct HistoryArgs {
    #[command(flatten)]
    pub bridge: BridgeArgs,
    /// How many of the newest entries (1..16).
    #[arg(long, short = 'n', default_value_t = HISTORY_MAX)]
    pub count: u8,
    /// JSON instead of a table.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// CSV instead of a table.
    #[arg(long)]
    pub csv: bool,
}

/// Exit 0 with the entries printed; 1 when the bridge refused; 2 on a port or argument error.
pub fn history(args: &HistoryArgs) -> ExitCode {
    if !(1..=HISTORY_MAX).contains(&args.count) {
        eprintln!("pbtool history: --count is 1..{HISTORY_MAX}");
        return ExitCode::from(USAGE);
    }
    let answer = match args.bridge.bridge() {
        Bridge::Port(port) => over_port(port, args.bridge.cnc_framing, args.count),
        Bridge::Simulated { model, emulated } => {
            let (model, fault) =
                match simulated_unit("history", model, args.bridge.fault.as_deref()) {
                    Ok(unit) => unit,
                    Err(status) => return status,
                };
            if emulated {
                let unit = EmuUnit {
                    model,
                    more_units: Vec::new(),
                    fault,
                    seed: 1,
                };
                from_emu(&unit, args.count)
            } else {
                Ok(from_sim(model, fault, args.count))
            }
        }
    };
    let (lines, reply) = match answer {
        Ok(answer) => answer,
        Err(e) => {
            eprintln!("pbtool history: {e}");
            return ExitCode::from(super::PORT_ERROR);
        }
    };
    if !reply.starts_with("OK") {
        eprintln!("pbtool history: the bridge answered {reply}");
        return ExitCode::FAILURE;
    }
    let rows = rows(lines.iter().map(String::as_str));
    let text = if args.json {
        json(&rows)
    } else if args.csv {
        csv(&rows)
    } else {
        table(&rows)
    };
    print!("{text}");
    ExitCode::SUCCESS
}
