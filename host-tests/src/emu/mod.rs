//! The firmware itself, running on an emulated board: QEMU's `b-l475e-iot01a` machine
//! (STM32L475VG) runs the `plasma-bridge-emu` image, and the harness here plays the rest of
//! the machine in real time.
//!
//! - [`qemu`]: starts QEMU with the board's sockets (PS and CNC serial ports, qtest, QMP) and
//!   the semihosting log file; kills it when dropped. A missing or old `qemu-system-arm` is
//!   an error that says how to install QEMU 10 (Debian bookworm-backports).
//! - [`qtest`]: drives the input pins and reads registers; streams the output edges of one
//!   port. [`pins`] is the board's pin map.
//! - [`sim_port`]: a simulated unit ([`plasma_sim`]) on the PS socket, with the baud-accurate
//!   [`Line`](plasma_sim::line::Line) in between, in real time.
//! - [`cnc`]: the CNC's end of the CNC port: commands, replies, `!` events.
//! - [`usart`]: the USARTs' registers, and the framing the firmware set in them.
//! - [`log`]: the firmware's defmt log, decoded against the ELF.
//! - [`image`]: builds the image (`cargo emu-fw`) once per process.
//! - [`board`]: all of it as one [`Board`], with the safety rules of [`safety`] checked on
//!   what it observed.
//!
//! `pbtool emu` (crate pbtool) is its console, with the CNC port on stdin/stdout, and its
//! measurements under QEMU's instruction counting (`--measure`).
//!
//! ```no_run
//! use std::time::Duration;
//! use host_tests::emu::{Board, BoardOptions};
//! use plasma_sim::Model;
//! use plasma_firmware::io::{Input, Output};
//!
//! let mut board = Board::boot(BoardOptions::new(Model::Sync65)).unwrap();
//! board
//!     .wait_status(Duration::from_secs(20), |s| s.contains("link=UP"))
//!     .unwrap();
//! board.set_input(Input::TorchOn, true).unwrap();
//! board.wait_output(Output::Start, true, Duration::from_secs(2)).unwrap();
//! ```

pub mod board;
pub mod cnc;
pub mod error;
pub mod image;
pub mod log;
pub mod pins;
pub mod qemu;
pub mod qmp;
pub mod qtest;
pub mod safety;
pub mod sim_port;
pub mod usart;

pub use board::{Board, BoardOptions, Wiring};
pub use error::{Error, Result};
pub use pins::TestHook;
