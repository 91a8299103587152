//! `pbtool emu`: the firmware image on the emulated board of [`host_tests::emu`].
//!
//! - [`console`]: the board's CNC port on stdin/stdout, TORCH ON|OFF on its input pin.
//! - [`cnc_port`]: `--cnc-port DEV`, the board's CNC port on a serial device for CNC software.
//! - [`measure`]: `--measure`, the `emu-probe` figures (instructions from a TORCH_ON edge to
//!   START, idle time) under QEMU's instruction counting.

pub mod cnc_port;
pub mod console;
pub mod measure;
