//! `pbtool config`.

use std::process::ExitCode;

use clap::Args;
use pbtool::config::{ConfigError, set_cnc_framing};
use pbtool::serial::describe;
use plasma_protocol::serial::PortConfig;

use super::serial_failure;
use super::sim::cnc_framing;

#[derive(Args)]
pub struct ConfigArgs {
    /// The bridge's CNC port (the Nucleo's ST-LINK USB serial port: /dev/ttyACM0, or better
    /// its /dev/serial/by-id/ name; COM5).
    #[arg(long, value_name = "DEV")]
    port: String,
    /// The framing to set, BAUD:DPS (data bits, parity, stop bits): 19200:8E1 for LinuxCNC's
    /// pmx485, 9600:7E1 for a Phoenix CNC set so, 115200:8N1 (the default) for a terminal.
    #[arg(long, value_name = "FRAMING", value_parser = cnc_framing)]
    cnc_framing: PortConfig,
    /// Store it in the board's flash (`CONFIG SAVE`): the board then starts at it. Without
    /// it, a reset of the board returns to the saved framing.
    #[arg(long)]
    save: bool,
}

/// Exit 0 when the board runs (and, with `--save`, stored) the framing; 1 when no board
/// answered or it refused; 2 on a port error.
pub fn config(args: &ConfigArgs) -> ExitCode {
    let mut progress = |step: &str| eprintln!("pbtool config: {step}");
    match set_cnc_framing(&args.port, args.cnc_framing, args.save, &mut progress) {
        Ok(outcome) => {
            let kept = if outcome.saved {
                "saved: the board starts at it after a reset"
            } else {
                "not saved: a reset of the board returns to the saved framing (add --save)"
            };
            let before = if outcome.found == outcome.now {
                "already".to_string()
            } else {
                format!("was {}", describe(outcome.found))
            };
            println!(
                "the bridge's CNC port on {} runs {} ({before}); {kept}",
                args.port,
                describe(outcome.now),
            );
            ExitCode::SUCCESS
        }
        Err(ConfigError::Port(e)) => serial_failure("config", &e),
        Err(e) => {
            eprintln!("pbtool config: {e}");
            ExitCode::FAILURE
        }
    }
}
