//! Puts the workspace's `memory.x` on the linker search path, for the MCU build only, after
//! checking its settings and history regions.
//!
//! cortex-m-rt's `link.x` does `INCLUDE memory.x`; the linker runs in the board's package
//! directory and would not find the file at the workspace root. Every board links this crate,
//! and cargo passes a dependency's link search path on to the binaries that use it, so both
//! boards link against the one memory.x. Host builds never see it.

use std::{env, fs, path::PathBuf};

fn main() {
    let memory_x = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap()).join("../../memory.x");
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rerun-if-changed=build.rs");

    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    let text = fs::read_to_string(&memory_x)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", memory_x.display()));
    let (settings, history) = check_storage_regions(&text);
    // The regions' sizes for the code (`plasma_tasks::regions`): memory.x stays their one
    // source.
    fs::write(
        out.join("regions.rs"),
        format!(
            "/// The SETTINGS region's size in bytes (memory.x).\n\
             pub const SETTINGS_BYTES: usize = {settings};\n\
             /// The HISTORY region's size in bytes (memory.x).\n\
             pub const HISTORY_BYTES: usize = {history};\n"
        ),
    )
    .unwrap();
    fs::write(out.join("memory.x"), text).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
}

/// The settings store and the history each need whole 2 KiB pages, at least two of them
/// (sequential-storage's minimum), outside the program's FLASH region and apart from each
/// other. A mistake here would erase code or settings at run time, so it fails the build
/// instead. Returns the two sizes (settings, history).
fn check_storage_regions(memory_x: &str) -> (u64, u64) {
    const PAGE: u64 = 2048;
    let flash = region(memory_x, "FLASH");
    let settings = region(memory_x, "SETTINGS");
    let history = region(memory_x, "HISTORY");
    for (name, (origin, length)) in [("SETTINGS", settings), ("HISTORY", history)] {
        assert!(
            origin.is_multiple_of(PAGE) && length.is_multiple_of(PAGE) && length >= 2 * PAGE,
            "memory.x: {name} must be at least two whole 2 KiB pages"
        );
        assert!(
            flash.0 + flash.1 <= origin,
            "memory.x: {name} overlaps FLASH (the program)"
        );
    }
    assert!(
        history.0 + history.1 <= settings.0 || settings.0 + settings.1 <= history.0,
        "memory.x: HISTORY overlaps SETTINGS"
    );
    (settings.1, history.1)
}

/// `(origin, length)` of a MEMORY region line such as `FLASH : ORIGIN = 0x08000000, LENGTH = 512K`.
fn region(memory_x: &str, name: &str) -> (u64, u64) {
    let line = memory_x
        .lines()
        .map(str::trim)
        .find(|l| l.split(':').next().map(str::trim) == Some(name))
        .unwrap_or_else(|| panic!("memory.x: no {name} region"));
    let field = |key: &str| -> u64 {
        let value = line
            .split(',')
            .find_map(|part| part.split_once('=').filter(|(k, _)| k.contains(key)))
            .map(|(_, v)| v.trim())
            .unwrap_or_else(|| panic!("memory.x: {name} has no {key}"));
        parse_number(value).unwrap_or_else(|| panic!("memory.x: bad number {value:?}"))
    };
    (field("ORIGIN"), field("LENGTH"))
}

fn parse_number(text: &str) -> Option<u64> {
    let (digits, scale) = match text.strip_suffix('K') {
        Some(d) => (d, 1024),
        None => match text.strip_suffix('M') {
            Some(d) => (d, 1024 * 1024),
            None => (text, 1),
        },
    };
    let value = match digits
        .strip_prefix("0x")
        .or_else(|| digits.strip_prefix("0X"))
    {
        Some(hex) => u64::from_str_radix(hex, 16).ok()?,
        None => digits.parse().ok()?,
    };
    value.checked_mul(scale)
}
