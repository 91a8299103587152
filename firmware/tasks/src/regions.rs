//! The flash regions' sizes, from memory.x (firmware/tasks/build.rs writes them): for a board
//! that cannot take the regions from the linker symbols at run time, as the emulated board's
//! models of the flash, whose sizes are types.

include!(concat!(env!("OUT_DIR"), "/regions.rs"));
