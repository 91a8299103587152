//! `pbtool unit`.

use std::io;
use std::process::ExitCode;

use clap::Args;
use pbtool::realtime::{Clock, spawn_reader, spawn_stdin};
use pbtool::serial::Port;
use pbtool::unit::{UnitOptions, UnitServer, build_line};
use plasma_sim::{Family, SimOptions};

use super::{USAGE, serial_failure, simulated_unit};

#[derive(Args)]
pub struct ServeArgs {
    /// The simulated unit: sync45 sync65 sync85 sync105 pm45xp pm65 pm85 pm105 pm125 hpr130
    /// hpr260 hpr400 hpr130xd hpr260xd hpr400xd maxpro200. Given again, several units share
    /// the port as one line: HPRs with ids in order (SLEEP/WAKE), Powermax units at node
    /// addresses in order from --address.
    #[arg(long = "ps", value_name = "MODEL", required = true)]
    models: Vec<String>,
    /// The serial port (/dev/ttyUSB0, COM3).
    #[arg(long, value_name = "DEV")]
    port: String,
    /// Start with a fault (on the first unit): Powermax `0-50-0` (or decimal `500`), HPR
    /// error number.
    #[arg(long, value_name = "CODE")]
    fault: Option<String>,
    /// Powermax: the Modbus node address (1-247; default: learnt from the first request,
    /// for a single unit only). HPR: the id switch (0-3, default 0). The first unit's; the
    /// others' follow.
    #[arg(long, value_name = "N", value_parser = unit_address)]
    address: Option<u8>,
    /// Each frame (time, direction, decoded) on stderr.
    #[arg(long)]
    log: bool,
    /// Seed of the unit's response-time jitter.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Serves the unit until the port fails or the process is stopped.
pub fn unit(args: &ServeArgs) -> ExitCode {
    let mut models = Vec::with_capacity(args.models.len());
    for name in &args.models {
        match simulated_unit("unit", name, None) {
            Ok((model, _)) => models.push(model),
            Err(status) => return status,
        }
    }
    let (model, fault) = match simulated_unit("unit", &args.models[0], args.fault.as_deref()) {
        Ok(unit) => unit,
        Err(status) => return status,
    };
    let mut sim = SimOptions {
        seed: args.seed,
        ..SimOptions::default()
    };
    match (model.family(), args.address) {
        (_, None) => {}
        (Family::Hpr, Some(id @ 0..=3)) => sim.hpr_id = id,
        (Family::Sync | Family::Legacy, Some(node @ 1..=247)) => sim.modbus_address = node,
        (_, Some(n)) => {
            eprintln!(
                "pbtool unit: address {n} is not one a {model} can have (Powermax 1-247, HPR 0-3)"
            );
            return ExitCode::from(USAGE);
        }
    }
    let options = UnitOptions {
        models,
        fault,
        sim,
        log: args.log,
    };
    let line = match build_line(&options) {
        Ok(line) => line,
        Err(e) => {
            eprintln!("pbtool unit: {e}");
            return ExitCode::from(USAGE);
        }
    };
    let clock = Clock::start();
    let opened = Port::open(&args.port, line.port())
        .and_then(|port| Ok((port.try_clone()?, port)))
        .and_then(|(reader, port)| Ok((reader, UnitServer::new(&options, line, port, clock)?)));
    let (reader, mut server) = match opened {
        Ok(opened) => opened,
        Err(e) => return serial_failure("unit", &e),
    };
    eprintln!("{}", server.banner());
    let (inbox, arrivals) = std::sync::mpsc::channel();
    spawn_reader(reader, 0, inbox.clone());
    spawn_stdin(inbox);
    match server.run(&arrivals, &mut io::stderr()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => serial_failure("unit", &e),
    }
}

/// `--address`: a number a unit of some family can have; which family is checked with the model.
fn unit_address(text: &str) -> Result<u8, String> {
    text.parse::<u8>()
        .ok()
        .filter(|n| *n <= 247)
        .ok_or_else(|| "a Powermax's node address is 1-247, an HPR's id 0-3".to_string())
}

#[cfg(test)]
mod tests {
    use super::unit_address;

    #[test]
    fn an_address_no_unit_can_have_says_which_ones_can() {
        assert_eq!(unit_address("247"), Ok(247));
        assert_eq!(unit_address("0"), Ok(0));
        for bad in ["248", "300", "-1", "x"] {
            assert_eq!(
                unit_address(bad),
                Err("a Powermax's node address is 1-247, an HPR's id 0-3".to_string())
            );
        }
    }
}
