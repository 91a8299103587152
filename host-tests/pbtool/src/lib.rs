//! pbtool, the plasma-bridge technician's tool, as a library: what its commands are made of.
//!
//! - [`decode`]: `pbtool decode`, Modbus ASCII and HPR frames explained in the manuals' terms.
//! - [`sim`]: `pbtool sim`, the bridge's real behaviour against a simulated unit (the scenario
//!   harness of host-tests, in real or virtual time) with the CNC protocol on stdin/stdout.
//! - [`emu`]: `pbtool emu`, the firmware image on the emulated board (the QEMU harness of
//!   host-tests) with its CNC port on stdin/stdout, and `--measure`.
//! - [`monitor`]: `pbtool monitor`, the live dashboard of a bridge over its CNC text protocol.
//! - [`history`]: `pbtool history`, the bridge's event history as a table, JSON or CSV.
//! - [`config`]: `pbtool config`, the board's CNC-port framing set from the PC, both ends in step.
#![warn(missing_docs)]

pub mod config;
pub mod decode;
pub mod emu;
pub mod framer;
pub mod history;
pub mod monitor;
pub mod probe;
pub mod realtime;
pub mod run;
pub mod serial;
pub mod sim;
pub mod sniff;
pub mod unit;
