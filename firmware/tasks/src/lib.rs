//! The tasks of the board image, shared by every board: the Nucleo-L476RG
//! (`firmware/boards/nucleo`, bin `plasma-bridge`) and the emulated STM32L475VG under QEMU
//! (`firmware/boards/emu`, bin `plasma-bridge-emu`).
//!
//! What a board provides is the [`Board`] trait: the input and output pins, the heartbeat
//! LED, the power-supply and CNC UARTs, the settings and history flash and their read errors. The tasks are
//! generic over it; `#[embassy_executor::task]` functions cannot be, so each board expands
//! [`board_tasks!`] with its board type, which declares the thin task wrappers around
//! [`io::run`], [`bridge::run`], [`settings::run`], [`history::run`], [`progress::heartbeat`] and
//! [`progress::judge`] ([`tasks`]), and the `start_tasks` that puts each in its executor at
//! its priority ([`layout`], the same for every board). A board also brings, outside the
//! trait: its thread executor, its fault handlers (which call
//! [`safe_state::drive_safe_state`] and [`reset::mark_panic`]), and the defmt global logger
//! it links.
//!
//! No HAL code here, and register code only where both chips are the same ([`chip`]): the
//! register-level safe state, from the pin table `plasma_firmware::platform::pins`, and the reset cause.
//! docs/board.md says what each board puts behind the trait and why they differ.
//!
//! MCU only, but for [`clock_tree`] (pure arithmetic, tested on the host): on the host the
//! crate holds nothing else, so that the workspace builds there.
#![cfg_attr(not(test), no_std)]
#![warn(missing_docs)]

#[cfg(target_os = "none")]
pub mod board;
#[cfg(target_os = "none")]
pub mod boot;
#[cfg(target_os = "none")]
pub mod bridge;
#[cfg(target_os = "none")]
pub mod chip;
#[cfg(target_os = "none")]
pub mod clock;
pub mod clock_tree;
#[cfg(target_os = "none")]
pub mod edges;
#[cfg(target_os = "none")]
pub mod hard_fault;
#[cfg(target_os = "none")]
pub mod history;
#[cfg(target_os = "none")]
pub mod io;
#[cfg(target_os = "none")]
pub mod layout;
#[cfg(target_os = "none")]
pub mod log_text;
#[cfg(target_os = "none")]
pub mod progress;
#[cfg(target_os = "none")]
pub mod regions;
#[cfg(target_os = "none")]
pub mod reset;
#[cfg(target_os = "none")]
pub mod safe_state;
#[cfg(target_os = "none")]
pub mod settings;
#[cfg(target_os = "none")]
pub mod tasks;
#[cfg(target_os = "none")]
pub mod uart;

#[cfg(target_os = "none")]
pub use board::Board;
