//! `pbtool history --sim MODEL | --emu [--ps MODEL] | --port DEV`.

use std::process::ExitCode;

use clap::Args;
use pbtool::emu::EmuUnit;
use pbtool::history::{csv, from_emu, from_sim, json, over_port, rows, table};
use plasma_protocol::cnc::HISTORY_MAX;
use plasma_protocol::serial::PortConfig;

use super::sim::cnc_framing;
use super::{USAGE, simulated_unit};

#[derive(Args)]
#[command(group(clap::ArgGroup::new("bridge").required(true).args(["port", "sim", "emu"])))]
pub struct HistoryArgs {
    /// The board's CNC port.
    #[arg(long, value_name = "DEV")]
    pub port: Option<String>,
    /// A simulated bridge against this simulated unit (sync65, hpr260, ...; virtual time).
    #[arg(long, value_name = "MODEL")]
    pub sim: Option<String>,
    /// The firmware on the emulated board (QEMU, real time) against a simulated unit.
    #[arg(long)]
    pub emu: bool,
    /// With `--emu`: the simulated unit.
    #[arg(
        long = "ps",
        value_name = "MODEL",
        default_value = "sync65",
        requires = "emu"
    )]
    pub emu_model: String,
    /// With `--sim` or `--emu`: the unit starts with this fault (`0-50-0`, HPR error number).
    #[arg(long, value_name = "CODE", conflicts_with = "port")]
    pub fault: Option<String>,
    /// The CNC port's framing, BAUD:DPS (data bits 7|8, parity N|E|O, stop bits 1|2).
    #[arg(long, value_name = "FRAMING", default_value = "115200:8N1", value_parser = cnc_framing)]
    pub cnc_framing: PortConfig,
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
    let answer = match (&args.port, &args.sim) {
        (Some(port), _) => over_port(port, args.cnc_framing, args.count),
        (None, Some(model)) => {
            let (model, fault) = match simulated_unit("history", model, args.fault.as_deref()) {
                Ok(unit) => unit,
                Err(status) => return status,
            };
            Ok(from_sim(model, fault, args.count))
        }
        (None, None) if args.emu => {
            let (model, fault) =
                match simulated_unit("history", &args.emu_model, args.fault.as_deref()) {
                    Ok(unit) => unit,
                    Err(status) => return status,
                };
            let unit = EmuUnit {
                model,
                fault,
                seed: 1,
            };
            from_emu(&unit, args.count)
        }
        (None, None) => return ExitCode::from(USAGE),
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
