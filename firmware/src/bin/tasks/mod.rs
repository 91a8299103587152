//! The tasks of the board image, shared by both boards: the Nucleo-L476RG image
//! (`plasma-bridge`) and the emulated STM32L475VG under QEMU (`plasma-bridge-emu`).
//!
//! They hold no HAL code, and register code only where both chips are the same: the output
//! pin map with its safe state ([`pin_map`]) and the reset cause ([`reset`]). Everything board-specific comes from the
//! including binary's `board` module, which must provide:
//!
//! - `InputPins` (`levels()`, `any_edge()`), `OutputPins` (`drive()`), `Led` (`toggle()`);
//! - `PsUart` (a [`plasma_firmware::runner::ConfigurablePort`]) and `CncUart` with
//!   `CNC_TX_BUFFER`, their error types `defmt::Format`;
//! - `SettingsFlash` (an async `NorFlash`) and `flash_errors_seen()`;
//! - `pac`: the chip's register access crate (stm32-metapac).
//!
//! docs/board.md says what each board puts behind these names and why they differ.

pub mod bridge;
pub mod clock;
pub mod io;
pub mod pin_map;
pub mod progress;
pub mod reset;
pub mod settings;
