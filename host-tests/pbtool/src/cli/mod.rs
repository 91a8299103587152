//! The subcommands: their arguments and how each maps onto the library.

pub mod bridge;
pub mod config;
pub mod decode;
pub mod emu;
pub mod history;
mod line;
pub mod monitor;
pub mod probe;
pub mod run;
pub mod sim;
pub mod sniff;
pub mod unit;

use std::io::{self, BufRead};
use std::process::ExitCode;
use std::sync::mpsc::Receiver;

use clap::Args;
use host_tests::harness::SharedLineError;
use pbtool::serial::SerialError;
use pbtool::sim::{parse_fault, read_line};
use plasma_sim::Model;

/// Exit status for a bad argument (as clap uses).
pub const USAGE: u8 = 2;

/// The simulated unit and the session's start, common to `sim`, `emu` and `run`.
#[derive(Args, Clone)]
pub struct UnitArgs {
    /// The simulated unit: sync45 sync65 sync85 sync105 pm45xp pm65 pm85 pm105 pm125 hpr130
    /// hpr260 hpr400 hpr130xd hpr260xd hpr400xd maxpro200. Given again, several units share
    /// one line as `CONFIG units` names them: HPRs with ids 0, 1... (SLEEP/WAKE), Powermax
    /// units at nodes 1, 2...; `@N` addresses unit N, `@N TORCH ON` drives its TORCH_ON.
    #[arg(long = "ps", value_name = "MODEL", default_value = "sync65")]
    pub models: Vec<String>,
    /// Start the (first) unit with a fault: Powermax `0-50-0` (or decimal `500`), HPR error
    /// number.
    #[arg(long, value_name = "CODE")]
    pub fault: Option<String>,
    /// Event lines (`!LINK UP ...`, `!ARC ON`) on from the start.
    #[arg(long)]
    pub events: bool,
    /// Seed of the simulator's response-time jitter and the line model.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

fn model_list() -> String {
    Model::ALL.map(Model::name).join(" ")
}

/// The unit `--ps` names and its `--fault`, or the usage status after saying what is wrong.
pub fn simulated_unit(
    command: &str,
    model: &str,
    fault: Option<&str>,
) -> Result<(Model, Option<u16>), ExitCode> {
    let Some(unit) = Model::from_name(model) else {
        eprintln!(
            "pbtool {command}: unknown model {model:?}; models: {}",
            model_list()
        );
        return Err(ExitCode::from(USAGE));
    };
    match fault.map(|f| parse_fault(unit, f)).transpose() {
        Ok(fault) => Ok((unit, fault)),
        Err(e) => {
            eprintln!("pbtool {command}: {e}");
            Err(ExitCode::from(USAGE))
        }
    }
}

impl UnitArgs {
    /// The `--ps` models as given, space-separated (for messages).
    pub fn model_names(&self) -> String {
        self.models.join(" ")
    }

    /// The `--ps` arguments again, as a hint prints them (`--ps hpr260 --ps hpr130`).
    pub fn ps_args(&self) -> String {
        self.models
            .iter()
            .map(|m| format!("--ps {m}"))
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Says that the `--ps` units cannot share a line, and why (`sim`, `emu` and `run` in the
    /// same words); the usage status.
    pub fn refuse_line(&self, command: &str, why: &SharedLineError) -> ExitCode {
        eprintln!("pbtool {command}: --ps {}: {why}", self.model_names());
        ExitCode::from(USAGE)
    }

    /// Every unit `--ps` names (at least one) and the first one's `--fault`, or the usage
    /// status after saying what is wrong.
    pub fn units(&self, command: &str) -> Result<(Vec<Model>, Option<u16>), ExitCode> {
        let mut models = Vec::with_capacity(self.models.len());
        for name in &self.models {
            models.push(simulated_unit(command, name, None)?.0);
        }
        let first = self.models.first().map_or("", String::as_str);
        let (_, fault) = simulated_unit(command, first, self.fault.as_deref())?;
        Ok((models, fault))
    }
}

/// Stdin's lines on a channel, from a reader thread; the channel closes at end of input.
pub fn stdin_lines() -> Receiver<Vec<u8>> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut stdin = io::stdin().lock();
        while let Ok(Some(line)) = read_line(&mut stdin as &mut dyn BufRead) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// Exit status for a port that cannot be opened or fails.
pub const PORT_ERROR: u8 = 2;

/// Says what is wrong with the port; the exit status for it.
pub fn serial_failure(command: &str, e: &SerialError) -> ExitCode {
    eprintln!("pbtool {command}: {e}");
    ExitCode::from(PORT_ERROR)
}
