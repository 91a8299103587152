//! The settings store in the MCU's flash (bank 2, region from memory.x).

use core::ops::Range;
use core::sync::atomic::Ordering;

use defmt::{error, warn};
use embassy_stm32::flash::{Async, Flash};
use plasma_firmware::storage::SettingsStore;

use crate::fault::SETTINGS_ECC_ERRORS;

/// Start of flash in the address map.
pub const FLASH_BASE: u32 = 0x0800_0000;
/// Start of bank 2.
pub const FLASH_BANK2: u32 = 0x0808_0000;

/// The store over the on-chip flash.
pub type Store = SettingsStore<Flash<'static, Async>>;

/// The settings region from memory.x, as offsets from the start of flash.
pub fn settings_region() -> Range<u32> {
    unsafe extern "C" {
        static __settings_start: u8;
        static __settings_end: u8;
    }
    // Only the addresses of these linker symbols are used, never their contents.
    let start = (&raw const __settings_start) as u32;
    let end = (&raw const __settings_end) as u32;
    start - FLASH_BASE..end - FLASH_BASE
}

/// The store, or `None` (logged) if the region does not suit it; build.rs checks the region,
/// so that would be a mismatch between memory.x and the flash driver's page size.
pub fn open(flash: Flash<'static, Async>) -> Option<Store> {
    match SettingsStore::new(flash, settings_region()) {
        Ok(store) => Some(store),
        Err(e) => {
            error!(
                "settings region: {=str}; settings will not be kept",
                e.as_str()
            );
            None
        }
    }
}

/// Logs double ECC errors the NMI handler skipped while the store was read.
pub fn report_ecc_errors() {
    let ecc_errors = SETTINGS_ECC_ERRORS.load(Ordering::Relaxed);
    if ecc_errors > 0 {
        warn!(
            "settings: {} double ECC error(s) read (torn writes), skipped",
            ecc_errors
        );
    }
}
