//! `pbtool sim`.

use std::io::{self, IsTerminal, Write};
use std::process::ExitCode;

use clap::Args;
use pbtool::sim::{Console, ConsoleOptions};

use pbtool::realtime::spawn_reader;
use pbtool::serial::{Port, describe};
use plasma_firmware::settings::CNC_BAUDS;
use plasma_protocol::serial::PortConfig;

use super::{UnitArgs, serial_failure, stdin_lines};

#[derive(Args)]
pub struct SimArgs {
    #[command(flatten)]
    pub unit: UnitArgs,
    /// Virtual time: no waiting, the same output on every run (scripts and tests).
    #[arg(long, alias = "virtual")]
    pub fast: bool,
    /// The CNC side on this serial port instead of stdin/stdout, in real time: CNC software
    /// talks to the simulated bridge and unit (`run` without `--ps-port`: to the firmware on
    /// the emulated board when QEMU is there, as `emu --cnc-port`).
    #[arg(long, value_name = "DEV", conflicts_with = "fast")]
    pub cnc_port: Option<String>,
    /// The CNC port's framing, BAUD:DPS, e.g. 9600:7E1 (the bridge's `cnc_baud`,
    /// `cnc_data_bits`, `cnc_parity`, `cnc_stop_bits`): 115200:8N1 by default, 19200:8E1 for LinuxCNC's pmx485.
    #[arg(long, value_name = "FRAMING", default_value = CNC_FRAMING_DEFAULT, value_parser = cnc_framing)]
    pub cnc_framing: PortConfig,
    /// Keep the bridge's flash (stored settings and history) in FILE: read at start (a power
    /// cycle of the board: settings and history as the last run left them), written when
    /// the run ends (`run --ps-port`: also every second it changed). Restarting `pbtool sim
    /// --flash FILE` or `pbtool run --flash FILE` is a power cycle of the board; `run` with
    /// it runs the bridge on this PC (the simulator, or `--ps-port`), never a board.
    #[arg(long, value_name = "FILE")]
    pub flash: Option<std::path::PathBuf>,
    /// Log every change of the discrete outputs (START, ARC_OK, READY, FAULT) with its
    /// reason on stderr.
    #[arg(short, long)]
    pub verbose: bool,
}

pub fn sim(args: &SimArgs) -> ExitCode {
    sim_bridge(args, false)
}

/// `pbtool sim`, or `pbtool run` on the simulator: with `own_clock`, the bridge's wall clock
/// is set to the PC's at start (after the boot from `--flash`, which clears it as a reset does).
pub fn sim_bridge(args: &SimArgs, own_clock: bool) -> ExitCode {
    let (models, fault) = match args.unit.units("sim") {
        Ok(units) => units,
        Err(status) => return status,
    };
    let console = Console::new(ConsoleOptions {
        models,
        fault,
        events: args.unit.events,
        seed: args.unit.seed,
        verbose: args.verbose,
        cnc_framing: args.cnc_framing,
    });
    let mut console = match console {
        Ok(console) => console,
        Err(e) => return args.unit.refuse_line("sim", &e),
    };
    let units = console.describe_units();
    if let Some(path) = &args.flash
        && let Err(e) = boot_from_flash(&mut console, path)
    {
        eprintln!("pbtool sim: --flash {}: {e}", path.display());
        return ExitCode::from(super::USAGE);
    }
    if own_clock {
        let reply = console.set_clock(pbtool::history::pc_unix_seconds());
        if args.verbose {
            eprintln!("pbtool run: the bridge's clock from the PC's: {reply}");
        }
    }
    if let Some(name) = &args.cnc_port {
        return on_cnc_port(&mut console, name, &units);
    }
    let interactive = io::stdin().is_terminal();
    if interactive || args.verbose {
        let torch = match console.world().pin_sets() {
            1 => "TORCH ON|OFF drives torch-on",
            _ => "[@N] TORCH ON|OFF drives unit N's torch-on",
        };
        eprintln!(
            "pbtool sim: the bridge against {units}{}; CNC protocol on stdin/stdout. \
             HELP lists the commands, {torch} (simulator only), end of input (Ctrl-D) quits.",
            if args.fast { " in virtual time" } else { "" },
        );
    }
    let mut out = io::stdout().lock();
    let mut err = io::stderr();
    let result = if args.fast {
        console.run_virtual(&mut io::stdin().lock(), &mut out, &mut err)
    } else {
        console.run_realtime(stdin_lines(), &mut out, &mut err)
    };
    let _ = out.flush();
    if let Some(path) = &args.flash
        && let Err(e) = std::fs::write(path, console.flash_image())
    {
        eprintln!("pbtool sim: --flash {}: {e}", path.display());
        return ExitCode::FAILURE;
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A closed stdout (`| head`) ends the simulation quietly.
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pbtool sim: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The flash of an earlier run, if `path` exists (a new file starts erased).
fn boot_from_flash(console: &mut Console, path: &std::path::Path) -> Result<(), String> {
    match std::fs::read(path) {
        Ok(image) => console.boot_from_flash(&image),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(e.to_string()),
    }
}

/// The simulator with its CNC side on the serial port `name`, until the port fails.
fn on_cnc_port(console: &mut Console, name: &str, units: &str) -> ExitCode {
    let framing = console.cnc_port_config();
    let opened = Port::open(name, framing).and_then(|port| Ok((port.try_clone()?, port)));
    let (reader, mut port) = match opened {
        Ok(ports) => ports,
        Err(e) => return serial_failure("sim", &e),
    };
    let (inbox, arrivals) = std::sync::mpsc::channel();
    spawn_reader(reader, 0, inbox);
    eprintln!(
        "pbtool sim: the bridge against {units}; CNC protocol on {name} at {}. \
         Ctrl-C quits.",
        describe(framing)
    );
    let e = console.run_cnc_port(&arrivals, &mut port);
    serial_failure("sim", &e)
}

/// `--cnc-framing`'s default: the board's CNC port out of the box (a test ties the two).
pub(super) const CNC_FRAMING_DEFAULT: &str = "115200:8N1";

/// `--cnc-framing`: `BAUD:DPS` (data bits 7 or 8, parity, stop bits) with a baud `cnc_baud`
/// accepts.
pub(super) fn cnc_framing(text: &str) -> Result<PortConfig, String> {
    let bad = || {
        format!("{text}: expected BAUD:DPS, e.g. 19200:8E1 or 9600:7E1 (baud one of {CNC_BAUDS:?})")
    };
    let (baud, framing) = text.split_once(':').ok_or_else(bad)?;
    let baud: u32 = baud.parse().map_err(|_| bad())?;
    if !CNC_BAUDS.contains(&baud) {
        return Err(bad());
    }
    PortConfig::from_framing(baud, framing).ok_or_else(bad)
}

#[cfg(test)]
mod tests {
    use plasma_firmware::settings::CncPort;

    use super::*;

    #[test]
    fn the_default_cnc_framing_is_the_boards() {
        assert_eq!(
            cnc_framing(CNC_FRAMING_DEFAULT),
            Ok(CncPort::DEFAULT.framing)
        );
    }
}
