//! `pbtool probe`.

use std::process::ExitCode;
use std::time::Duration;

use clap::Args;
use pbtool::probe::report::{to_json_report, to_text};
use pbtool::probe::{DEFAULT_NODE, FRAMINGS, probe};
use pbtool::serial::Port;

use super::serial_failure;

#[derive(Args)]
pub struct ProbeArgs {
    /// The serial port (/dev/ttyUSB0, COM3).
    #[arg(long, value_name = "DEV")]
    port: String,
    /// One JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// The Powermax's Modbus node address (1-247).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_NODE,
          value_parser = clap::value_parser!(u8).range(1..=247))]
    address: u8,
    /// How long to look for a unit.
    #[arg(long, value_name = "SECONDS", default_value_t = 15)]
    seconds: u64,
}

/// Exit 0 when a unit answered, 1 when none did, 2 on a port error.
pub fn probe_command(args: &ProbeArgs) -> ExitCode {
    let port = match Port::open(&args.port, FRAMINGS[0]) {
        Ok(port) => port,
        Err(e) => return serial_failure("probe", &e),
    };
    let mut progress = |step: &str| eprintln!("pbtool probe: {step}");
    let seconds = Duration::from_secs(args.seconds);
    let found = match probe(port, seconds, args.address, &mut progress) {
        Ok(found) => found,
        Err(e) => return serial_failure("probe", &e),
    };
    if args.json {
        println!("{}", to_json_report(&found));
    } else {
        print!("{}", to_text(&found));
    }
    if found.found.is_some() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
