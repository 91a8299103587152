//! `pbtool emu`.

use std::io::{self, IsTerminal};
use std::process::ExitCode;

use clap::Args;
use pbtool::emu::EmuUnit;
use pbtool::emu::cnc_port::{self, CncPortOptions, RelayError};
use pbtool::emu::console::EmuConsoleOptions;
use pbtool::emu::measure::{MeasureOptions, measure};

use plasma_protocol::serial::PortConfig;

use super::sim::{CNC_FRAMING_DEFAULT, cnc_framing};
use super::{USAGE, UnitArgs, serial_failure, stdin_lines};

#[derive(Args)]
pub struct EmuArgs {
    #[command(flatten)]
    pub unit: UnitArgs,
    /// The firmware's own log (defmt, decoded) on stderr.
    #[arg(long)]
    pub log: bool,
    /// Measure instead: TORCH_ON edge to START in guest instructions, and idle behaviour.
    #[arg(long)]
    pub measure: bool,
    /// With --measure: TORCH_ON cycles.
    #[arg(long, default_value_t = 20, requires = "measure")]
    pub toggles: usize,
    /// With --measure: pmx485 cycles (six reads each, after its three writes) on the CNC port.
    #[arg(long, default_value_t = 10, requires = "measure")]
    pub modbus_cycles: usize,
    /// With --measure: idle windows of 10 s of guest time to report.
    #[arg(long, default_value_t = 1, requires = "measure")]
    pub idle_windows: usize,
    /// The board's CNC port on this serial device instead of stdin/stdout (a pty, an adapter):
    /// CNC software talks to the firmware itself.
    #[arg(long, value_name = "DEV", conflicts_with = "measure")]
    pub cnc_port: Option<String>,
    /// With --cnc-port: the CNC's framing, BAUD:DPS (data bits 7|8, parity N|E|O, stop bits 1|2); the board is set to it at start
    /// (`CONFIG cnc_baud`, `cnc_parity`, `cnc_stop_bits`). 19200:8E1 for LinuxCNC's pmx485.
    #[arg(long, value_name = "FRAMING", default_value = CNC_FRAMING_DEFAULT, value_parser = cnc_framing, requires = "cnc_port")]
    pub cnc_framing: PortConfig,
    /// Set the board's wall clock to the PC's at start (`pbtool run`, which is the bridge).
    #[arg(skip)]
    pub own_clock: bool,
}

/// The firmware on the emulated board: the CNC console, or the measurements.
pub fn emu(args: &EmuArgs) -> ExitCode {
    let (models, fault) = match args.unit.units("emu") {
        Ok(units) => units,
        Err(status) => return status,
    };
    let Some((&model, more_units)) = models.split_first() else {
        return ExitCode::from(USAGE);
    };
    let unit = EmuUnit {
        model,
        more_units: more_units.to_vec(),
        fault,
        seed: args.unit.seed,
    };
    // Refused here, before QEMU starts, in `pbtool sim`'s words.
    let named = match unit.line() {
        Ok((_, named)) => named,
        Err(e) => return args.unit.refuse_line("emu", &e),
    };
    if args.measure && !more_units.is_empty() {
        // The figures are one unit's: its START path, and the board's idle time polling it;
        // a second unit's polls would change the idle figures the reports are compared by.
        eprintln!(
            "pbtool emu --measure: one --ps only: the figures are those of one unit's START \
             path and of the board polling that unit alone"
        );
        return ExitCode::from(USAGE);
    }
    if args.measure {
        let options = MeasureOptions {
            model,
            toggles: args.toggles,
            modbus_cycles: args.modbus_cycles,
            idle_windows: args.idle_windows,
        };
        return match measure(&options, |note| eprintln!("pbtool emu: {note}")) {
            Ok(figures) => {
                print!("{}", figures.report());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("pbtool emu --measure: {e}");
                ExitCode::FAILURE
            }
        };
    }
    if let Some(device) = &args.cnc_port {
        let options = CncPortOptions {
            unit,
            log: args.log,
            framing: args.cnc_framing,
        };
        return match cnc_port::run(&options, device, &mut io::stderr()) {
            RelayError::Serial(e) => serial_failure("emu", &e),
            RelayError::Board(e) => {
                eprintln!("pbtool emu: {e}");
                ExitCode::FAILURE
            }
        };
    }
    if io::stdin().is_terminal() {
        let (against, torch) = match &named {
            None => (
                format!("a simulated {model}"),
                "TORCH ON|OFF drives the TORCH_ON pin",
            ),
            Some(named) => (
                format!("{} simulated units on one line ({named})", unit.count()),
                "@N addresses unit N, [@N] TORCH ON|OFF drives unit N's TORCH_ON pin",
            ),
        };
        eprintln!(
            "pbtool emu: the firmware on an emulated board (QEMU) against {against}; CNC \
             port on stdin/stdout. HELP lists the commands, {torch}, \
             end of input (Ctrl-D) quits."
        );
    }
    let options = EmuConsoleOptions {
        unit,
        events: args.unit.events,
        log: args.log,
        clock: args.own_clock.then(pbtool::history::pc_unix_seconds),
    };
    let mut out = io::stdout().lock();
    match pbtool::emu::console::run(&options, stdin_lines(), &mut out, &mut io::stderr()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(host_tests::emu::Error::Io { source, .. })
            if source.kind() == io::ErrorKind::BrokenPipe =>
        {
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("pbtool emu: {e}");
            ExitCode::FAILURE
        }
    }
}
