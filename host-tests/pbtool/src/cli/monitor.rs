//! `pbtool monitor`.

use std::io::{self, Write};
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use pbtool::monitor::transport::Source;
use pbtool::monitor::{Session, run, snapshot};
use pbtool::serial::describe;
use plasma_protocol::serial::PortConfig;

use super::sim::cnc_framing;
use super::{USAGE, simulated_unit};

#[derive(Args)]
#[command(group = clap::ArgGroup::new("source").required(true).args(["port", "emu", "sim"]))]
pub struct MonitorArgs {
    /// A board's CNC port.
    #[arg(long, value_name = "DEV")]
    pub port: Option<String>,
    /// With --port: the CNC port's framing, BAUD:DPS (data bits 7|8, parity N|E|O, stop bits 1|2).
    #[arg(long, value_name = "FRAMING", default_value = "115200:8N1", value_parser = cnc_framing)]
    pub framing: PortConfig,
    /// The emulated board (`pbtool emu --ps MODEL --events` as a child).
    #[arg(long)]
    pub emu: bool,
    /// With --emu: the simulated unit.
    #[arg(
        long = "ps",
        value_name = "MODEL",
        default_value = "sync65",
        requires = "emu"
    )]
    pub emu_model: String,
    /// The simulator with this unit (`pbtool sim --ps MODEL --events` as a child).
    #[arg(long, value_name = "MODEL")]
    pub sim: Option<String>,
    /// With --emu or --sim: start the unit with this fault (`0-50-0`, HPR `044`).
    #[arg(long, value_name = "CODE", conflicts_with = "port")]
    pub fault: Option<String>,
    /// Print one frame to stdout once the picture is complete, and exit; after 20 s without
    /// one, the frame as it is and exit status 1.
    #[arg(long)]
    pub snapshot: bool,
    /// With --snapshot: the frame's size, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "100x30", value_parser = size, requires = "snapshot")]
    pub size: (u16, u16),
}

fn size(text: &str) -> Result<(u16, u16), String> {
    let bad = || format!("{text}: expected WIDTHxHEIGHT, e.g. 100x30");
    let (w, h) = text.split_once('x').ok_or_else(bad)?;
    Ok((w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?))
}

pub fn monitor(args: &MonitorArgs) -> ExitCode {
    let (source, framing) = if let Some(device) = &args.port {
        let source = Source::Port {
            device: device.clone(),
            framing: args.framing,
        };
        (source, Some(describe(args.framing)))
    } else {
        let (subcommand, model) = match &args.sim {
            Some(model) => ("sim", model.as_str()),
            None => ("emu", args.emu_model.as_str()),
        };
        // Say what is wrong with the model or fault here, not as a child that keeps exiting.
        if let Err(status) = simulated_unit("monitor", model, args.fault.as_deref()) {
            return status;
        }
        (
            Source::child(subcommand, model, args.fault.as_deref()),
            None,
        )
    };
    let exe = match std::env::current_exe() {
        Ok(exe) => exe,
        Err(e) => {
            eprintln!("pbtool monitor: where is pbtool itself? {e}");
            return ExitCode::from(USAGE);
        }
    };
    let mut session = Session::new(source, &exe, framing);
    if args.snapshot {
        let (width, height) = args.size;
        let (text, complete) = snapshot(&mut session, width, height, Duration::from_secs(20));
        let _ = io::stdout().lock().write_all(text.as_bytes());
        // A frame of a bridge that did not answer is still printed: it says what is wrong.
        return if complete {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        };
    }
    let mut terminal = ratatui::init();
    let result = run(&mut terminal, &mut session);
    ratatui::restore();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pbtool monitor: {e}");
            ExitCode::FAILURE
        }
    }
}
