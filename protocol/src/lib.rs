//! Wire formats spoken by the plasma-bridge.
//!
//! Bytes in, typed values out, and back. No I/O, no clock, no allocation and no panics on
//! any input: every decoder returns an [`Error`] for input it cannot accept.
//!
//! - [`modbus_ascii`]: Modbus ASCII framing (LRC, encoder, streaming decoder) and the PDUs the
//!   Powermax units use.
//! - [`powermax`]: register and coil map of legacy Powermax (0x2xxx) and Powermax SYNC (0x3xxx)
//!   units (values in [`units`]) and the fault/model/cartridge tables.
//! - [`hpr`]: the `>ID data CK<` protocol of HyPerformance HPR and MaxPro200 units.
//! - [`units`]: exact fixed-point amps (1/64 A), psi (1/128 psi) and pressure settings, shared
//!   by the Powermax registers and the CNC commands.
//! - [`errata`]: the manuals' sample frames printed with a typo, and what each meant.
//! - [`cnc`]: what the CNC sends: Phoenix serial-messaging framing and the text commands.
//! - [`serial`]: a UART's framing (baud, parity, stop bits) and how long a character takes.
//! - [`time`]: instants and durations as values (the caller's clock, never read here).
//!
//! `serial` and `time` sit here, at the bottom of the crate graph, because both the bridge
//! (firmware) and the simulated units (plasma-sim) need them and neither may depend on the
//! other: a character's time at a framing and the manuals' timing rules are facts of the wire.
//! This crate still reads no clock: the caller passes `now`.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// No panics on any input: these are errors outside tests.
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::unreachable,
        clippy::indexing_slicing
    )
)]

mod decimal;
mod error;
mod text_table;
pub use error::{Error, Result};
pub use text_table::{Pieces, Text};

pub mod cnc;
pub mod errata;
pub mod hpr;
pub mod modbus_ascii;
pub mod powermax;
pub mod serial;
pub mod time;
pub mod units;
