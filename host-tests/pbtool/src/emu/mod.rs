//! `pbtool emu`: the firmware image on the emulated board of [`host_tests::emu`].
//!
//! - [`console`]: the board's CNC port on stdin/stdout, TORCH ON|OFF on its input pin.
//! - [`measure`]: `--measure`, the `emu-probe` figures (instructions from a TORCH_ON edge to
//!   START, idle time) under QEMU's instruction counting.

pub mod console;
pub mod measure;
