//! `pbtool sniff`.

use std::io;
use std::process::ExitCode;

use clap::Args;
use pbtool::realtime::{Clock, spawn_reader};
use pbtool::serial::{Port, describe};
use pbtool::sniff::{Sniffer, Stop};
use plasma_protocol::serial::{DataBits, PortConfig};

use super::{USAGE, serial_failure};

#[derive(Args)]
pub struct SniffArgs {
    /// The port to listen on; twice for the two pairs of a 4-wire line.
    #[arg(long, value_name = "DEV", required = true, num_args = 1)]
    port: Vec<String>,
    /// The line's framing: 8E1 (Powermax default), 8O1, 8N1 (HPR), 8E2, 8O2, 8N2.
    #[arg(long, default_value = "8E1")]
    framing: String,
    /// The line's baud rate.
    #[arg(long, default_value_t = 19_200)]
    baud: u32,
    /// One JSON object per frame, one per line.
    #[arg(long)]
    json: bool,
}

/// Parses `8E1` and the like: a power-supply line runs 8 data bits.
pub(super) fn framing(text: &str, baud: u32) -> Option<PortConfig> {
    PortConfig::from_framing(baud, text).filter(|port| port.data_bits == DataBits::Eight)
}

/// Listens until a port goes away or the process is stopped.
pub fn sniff(args: &SniffArgs) -> ExitCode {
    if args.port.len() > 2 {
        eprintln!(
            "pbtool sniff: one port (2-wire) or two (4-wire), not {}",
            args.port.len()
        );
        return ExitCode::from(USAGE);
    }
    let Some(config) = framing(&args.framing, args.baud) else {
        eprintln!(
            "pbtool sniff: framing {:?}: 8E1, 8O1, 8N1, 8E2, 8O2 or 8N2",
            args.framing
        );
        return ExitCode::from(USAGE);
    };
    let clock = Clock::start();
    let (inbox, arrivals) = std::sync::mpsc::channel();
    for (index, name) in args.port.iter().enumerate() {
        match Port::open(name, config) {
            Ok(port) => spawn_reader(port, index, inbox.clone()),
            Err(e) => return serial_failure("sniff", &e),
        }
    }
    drop(inbox);
    eprintln!(
        "pbtool sniff: listening on {} at {} (never transmits); Ctrl-C stops",
        args.port.join(" and "),
        describe(config)
    );
    let mut sniffer = Sniffer::new(args.port.clone(), args.json, clock);
    match sniffer.run(&arrivals, &mut io::stdout()) {
        Stop::Port(e) => serial_failure("sniff", &e),
        Stop::Output(e) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Stop::Output(e) => {
            eprintln!("pbtool sniff: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::serial::{Parity, StopBits};

    #[test]
    fn framings_are_read() {
        assert_eq!(framing("8e1", 19_200), Some(PortConfig::MODBUS_DEFAULT));
        assert_eq!(framing("8N1", 19_200), Some(PortConfig::HPR));
        assert_eq!(
            framing("8O2", 9600),
            Some(PortConfig::new(9600, Parity::Odd, StopBits::Two))
        );
        assert_eq!(framing("7E1", 19_200), None);
        assert_eq!(framing("8E", 19_200), None);
    }
}
