//! The settings flash: the end of the MCU's flash (region from memory.x), through the HAL's
//! async driver.

use core::ops::Range;
use core::sync::atomic::Ordering;

use plasma_tasks::settings::Store;

use crate::board::Nucleo;
use crate::fault::SETTINGS_ECC_ERRORS;

/// Start of flash in the address map.
pub const FLASH_BASE: u32 = 0x0800_0000;
/// Start of bank 2.
pub const FLASH_BANK2: u32 = 0x0808_0000;

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

/// The store over the settings region; build.rs checks the region against the page size.
pub fn open(flash: <Nucleo as plasma_tasks::Board>::SettingsFlash) -> Option<Store<Nucleo>> {
    plasma_tasks::settings::open::<Nucleo>(flash, settings_region())
}

/// Double ECC errors the NMI handler skipped in the settings region since the last call.
pub fn flash_errors_seen() -> u32 {
    SETTINGS_ECC_ERRORS.swap(0, Ordering::Relaxed)
}
