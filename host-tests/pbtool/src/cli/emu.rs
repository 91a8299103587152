//! `pbtool emu`.

use std::io::{self, IsTerminal};
use std::process::ExitCode;

use clap::Args;
use pbtool::emu::console::EmuConsoleOptions;
use pbtool::emu::measure::{MeasureOptions, measure};

use super::{UnitArgs, simulated_unit, stdin_lines};

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
    /// With --measure: idle windows of 10 s of guest time to report.
    #[arg(long, default_value_t = 1, requires = "measure")]
    pub idle_windows: usize,
}

/// The firmware on the emulated board: the CNC console, or the measurements.
pub fn emu(args: &EmuArgs) -> ExitCode {
    let (model, fault) = match simulated_unit("emu", &args.unit.model, args.unit.fault.as_deref()) {
        Ok(unit) => unit,
        Err(status) => return status,
    };
    if args.measure {
        let options = MeasureOptions {
            model,
            toggles: args.toggles,
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
    if io::stdin().is_terminal() {
        eprintln!(
            "pbtool emu: the firmware on an emulated board (QEMU) against a simulated {model}; \
             CNC port on stdin/stdout. HELP lists the commands, TORCH ON|OFF drives the \
             TORCH_ON pin, end of input (Ctrl-D) quits."
        );
    }
    let options = EmuConsoleOptions {
        model,
        fault,
        events: args.unit.events,
        log: args.log,
        seed: args.unit.seed,
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
