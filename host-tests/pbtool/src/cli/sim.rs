//! `pbtool sim`.

use std::io::{self, IsTerminal, Write};
use std::process::ExitCode;

use clap::Args;
use pbtool::sim::{Console, ConsoleOptions};

use super::{UnitArgs, simulated_unit, stdin_lines};

#[derive(Args)]
pub struct SimArgs {
    #[command(flatten)]
    pub unit: UnitArgs,
    /// Virtual time: no waiting, the same output on every run (scripts and tests).
    #[arg(long, alias = "virtual")]
    pub fast: bool,
    /// Log every change of the discrete outputs (START, ARC_OK, READY, FAULT) with its
    /// reason on stderr.
    #[arg(short, long)]
    pub verbose: bool,
}

pub fn sim(args: &SimArgs) -> ExitCode {
    let (model, fault) = match simulated_unit("sim", &args.unit.model, args.unit.fault.as_deref()) {
        Ok(unit) => unit,
        Err(status) => return status,
    };
    let mut console = Console::new(ConsoleOptions {
        model,
        fault,
        events: args.unit.events,
        seed: args.unit.seed,
        verbose: args.verbose,
    });
    let interactive = io::stdin().is_terminal();
    if interactive || args.verbose {
        eprintln!(
            "pbtool sim: the bridge against a simulated {model}{}; CNC protocol on stdin/stdout. \
             HELP lists the commands, TORCH ON|OFF drives torch-on (simulator only), \
             end of input (Ctrl-D) quits.",
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
