//! `pbtool emu`: the firmware image on the emulated board of [`host_tests::emu`].
//!
//! - [`console`]: the board's CNC port on stdin/stdout, `[@N] TORCH ON|OFF` on unit N's input
//!   pin.
//! - [`cnc_port`]: `--cnc-port DEV`, the board's CNC port on a serial device for CNC software.
//! - [`measure`]: `--measure`, the `emu-probe` figures (instructions from a TORCH_ON edge to
//!   START, idle time) under QEMU's instruction counting.

pub mod cnc_port;
pub mod console;
pub mod measure;

use std::io::{self, Write};

use host_tests::emu::{Board, BoardOptions, Error, Result};
use host_tests::harness::{SharedLineError, named_units_on_line};
use plasma_firmware::link::NamedUnits;
use plasma_firmware::settings::Settings;
use plasma_sim::{Model, SimOptions};

/// The simulated units the emulated board is wired to, as pbtool's `--ps` (once or more),
/// `--fault` and `--seed` give them: several share the board's power-supply line and the
/// board is told them as a CNC tells it (`CONFIG units`), unit N on the board's unit set N
/// (docs/board.md: two sets; a third and fourth unit have no discrete I/O).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EmuUnit {
    /// The (first) unit's model.
    pub model: Model,
    /// Further units on the same line, in order.
    pub more_units: Vec<Model>,
    /// A fault the first unit has from the start.
    pub fault: Option<u16>,
    /// Seed of the simulator.
    pub seed: u64,
}

impl EmuUnit {
    /// How many units share the line.
    pub fn count(&self) -> usize {
        1 + self.more_units.len()
    }

    /// The simulator options the units are built with and, for several, the `CONFIG units`
    /// value naming them (with the board's default link settings); refused, with the reason,
    /// as `pbtool sim` refuses them when they cannot share a line.
    pub fn line(&self) -> std::result::Result<(SimOptions, Option<NamedUnits>), SharedLineError> {
        let sim = SimOptions {
            seed: self.seed,
            ..SimOptions::default()
        };
        if self.more_units.is_empty() {
            return Ok((sim, None));
        }
        let models: Vec<Model> = std::iter::once(self.model)
            .chain(self.more_units.iter().copied())
            .collect();
        let (named, sim) = named_units_on_line(&models, sim, Settings::default().link)?;
        Ok((sim, Some(named)))
    }

    /// Boots the emulated board wired to these units and, for several, tells it which it
    /// drives (`CONFIG units`) before anything else is sent.
    pub fn boot(&self) -> Result<Board> {
        let (sim, named) = self
            .line()
            .map_err(|e| Error::Protocol(format!("the simulated line: {e}")))?;
        let mut board = Board::boot(BoardOptions {
            fault_at_power_up: self.fault,
            sim,
            more_units: self.more_units.clone(),
            ..BoardOptions::new(self.model)
        })?;
        if let Some(named) = named {
            let command = format!("CONFIG units {named}");
            let reply = board.command(&command, console::REPLY_TIMEOUT)?;
            if !reply.starts_with("OK units=") {
                return Err(Error::Protocol(format!("{command}: {reply}")));
            }
        }
        Ok(board)
    }
}

/// Writes the firmware's log lines after the first `printed` to `err` (`[fw] ...`), counting
/// them in `printed`.
pub fn print_log(board: &Board, printed: &mut usize, err: &mut dyn Write) -> io::Result<()> {
    for line in board.log().since(*printed) {
        writeln!(err, "[fw] {line}")?;
        *printed += 1;
    }
    Ok(())
}
