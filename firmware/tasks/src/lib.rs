//! The tasks of the board image, shared by every board: the Nucleo-L476RG
//! (`firmware/boards/nucleo`, bin `plasma-bridge`) and the emulated STM32L475VG under QEMU
//! (`firmware/boards/emu`, bin `plasma-bridge-emu`).
//!
//! What a board provides is the [`Board`] trait: the input and output pins, the heartbeat
//! LED, the power-supply and CNC UARTs, the settings flash and its read errors. The tasks are
//! generic over it; `#[embassy_executor::task]` functions cannot be, so each board expands
//! [`board_tasks!`] with its board type, which declares the thin task wrappers around
//! [`io::run`], [`bridge::run`], [`settings::run`], [`progress::heartbeat`] and
//! [`progress::judge`] ([`tasks`]), and the `start_tasks` that puts each in its executor at
//! its priority ([`layout`], the same for every board). A board also brings, outside the
//! trait: its thread executor, its fault handlers (which call
//! [`safe_state::drive_safe_state`] and [`reset::mark_panic`]), and the defmt global logger
//! it links.
//!
//! No HAL code here, and register code only where both chips are the same ([`chip`]): the
//! register-level safe state, from the pin table `plasma_firmware::pins`, and the reset cause.
//! docs/board.md says what each board puts behind the trait and why they differ.
#![no_std]
// MCU only: on the host the crate is empty, so that the workspace builds there.
#![cfg(target_os = "none")]
#![warn(missing_docs)]

pub mod board;
pub mod boot;
pub mod bridge;
pub mod chip;
pub mod clock;
pub mod edges;
pub mod io;
pub mod layout;
pub mod progress;
pub mod reset;
pub mod safe_state;
pub mod settings;
pub mod tasks;
pub mod uart;

pub use board::Board;
