//! `pbtool monitor`.

use std::io::{self, Write};
use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use pbtool::monitor::transport::Source;
use pbtool::monitor::{Session, run, snapshot};
use pbtool::serial::describe;

use super::bridge::{Bridge, BridgeArgs};
use super::{USAGE, simulated_unit};

#[derive(Args)]
pub struct MonitorArgs {
    #[command(flatten)]
    pub bridge: BridgeArgs,
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
    let (source, framing) = match args.bridge.bridge() {
        Bridge::Port(device) => {
            let framing = args.bridge.cnc_framing;
            let source = Source::Port {
                device: device.to_owned(),
                framing,
            };
            (source, Some(describe(framing)))
        }
        Bridge::Simulated { model, emulated } => {
            let fault = args.bridge.fault.as_deref();
            // Say what is wrong with the model or fault here, not as a child that keeps exiting.
            if let Err(status) = simulated_unit("monitor", model, fault) {
                return status;
            }
            let subcommand = if emulated { "emu" } else { "sim" };
            (Source::child(subcommand, model, fault), None)
        }
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
