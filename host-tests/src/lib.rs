//! Simulated power supplies and test harness for the plasma-bridge.
//!
//! - [`line`]: the serial line in virtual time (baud-accurate timing, port-setting mismatches,
//!   seeded fault injection, 2-wire / 4-wire).
//! - [`sim`]: simulated Hypertherm power supplies (Powermax SYNC, legacy Powermax, HPR and
//!   MaxPro200) behind one byte-level interface, [`sim::SimulatedUnit`].
#![warn(missing_docs)]

pub mod decode;
pub mod line;
pub mod sim;
