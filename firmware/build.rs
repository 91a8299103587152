//! For the MCU build, turns on the library's own `defmt` feature.
//!
//! The board images always log with defmt, and the library's types then log natively
//! (`defmt::Format`) instead of through `core::fmt`, which is larger and slower. Cargo cannot
//! turn on a package's own feature per target, so the MCU build sets the cfg here; the
//! dependencies' defmt features are on in Cargo.toml's MCU-only table.

use std::env;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("none")
        && env::var_os("CARGO_FEATURE_DEFMT").is_none()
    {
        println!("cargo:rustc-cfg=feature=\"defmt\"");
    }
}
