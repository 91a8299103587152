//! `pbtool emu`: the firmware image on the emulated board of [`host_tests::emu`].
//!
//! - [`console`]: the board's CNC port on stdin/stdout, TORCH ON|OFF on its input pin.
//! - [`cnc_port`]: `--cnc-port DEV`, the board's CNC port on a serial device for CNC software.
//! - [`measure`]: `--measure`, the `emu-probe` figures (instructions from a TORCH_ON edge to
//!   START, idle time) under QEMU's instruction counting.

pub mod cnc_port;
pub mod console;
pub mod measure;

use std::io::{self, Write};

use host_tests::emu::{Board, BoardOptions, Result};
use plasma_sim::{Model, SimOptions};

/// The simulated unit the emulated board is wired to, as pbtool's `--ps`, `--fault` and
/// `--seed` give it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmuUnit {
    /// The model.
    pub model: Model,
    /// A fault the unit has from the start.
    pub fault: Option<u16>,
    /// Seed of the simulator.
    pub seed: u64,
}

impl EmuUnit {
    /// Boots the emulated board wired to this unit.
    pub fn boot(&self) -> Result<Board> {
        Board::boot(BoardOptions {
            fault_at_power_up: self.fault,
            sim: SimOptions {
                seed: self.seed,
                ..SimOptions::default()
            },
            ..BoardOptions::new(self.model)
        })
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
