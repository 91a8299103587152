//! Test harnesses for the plasma-bridge, over the simulated units of `plasma-sim`.
//!
//! - [`harness`]: the scenario harness: the bridge's power-supply side, the line and a
//!   simulator in one deterministic discrete-event [`harness::World`], with the discrete I/O
//!   and the safety monitor checked after every step.
//! - [`emu`]: the firmware image itself on an emulated board (QEMU), with a simulated unit on
//!   its PS port in real time, for end-to-end tests and `pbtool emu`.
//!
//! pbtool (host-tests/pbtool) builds its consoles on both.
#![warn(missing_docs)]

pub mod emu;
pub mod harness;
