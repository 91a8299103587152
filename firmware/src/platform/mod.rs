//! What runs the bridge on a platform: the async loops around the sans-IO bridge and the
//! board-facing policy, each free of any HAL (the boards' tasks supply ports, clock and
//! registers; the tests here supply fakes and a virtual clock).
//!
//! - [`runner`]: [`PsEndpoint`], what a driver of the power-supply port drives (the
//!   [`Bridge`](crate::bridge::Bridge), or a bare [`PsLink`](crate::link::PsLink)), and
//!   [`PsPort`](runner::PsPort), that port over any `embedded-io-async` UART and [`Clock`].
//! - [`supervisor`]: the bridge task's loop: both ports, the exchange with the I/O task, the
//!   settings saves.
//! - [`watchdog`]: when the hardware watchdog may be fed (every task made progress).
//! - [`safe_state`]: the panic and reset policy, and the reset cause at boot.
//! - [`pins`]: the board's pin map, the one table every board layer and the QEMU harness read.
//!
//! Not named `board`: that is the board crates (firmware/boards/) and `plasma_tasks::board`;
//! this folder is the platform-independent part they build on.

pub mod pins;
pub mod runner;
pub mod safe_state;
pub mod supervisor;
pub mod watchdog;

pub use runner::{Clock, PsEndpoint};
