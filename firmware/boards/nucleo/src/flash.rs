//! The settings flash: the end of the MCU's flash (region from memory.x), through the HAL's
//! async driver, with the data cache off while it programs or erases (errata ES0250).

use core::ops::Range;
use core::sync::atomic::Ordering;

use embassy_stm32::flash::{Async, Error, Flash};
use embassy_stm32::pac;
use embedded_storage_async::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
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

/// The HAL's flash with the data cache kept out of every program and erase.
///
/// ES0250 (STM32L47x/L48x errata), "Data cache might be corrupted during Flash memory
/// read-while-write operation": the settings live in bank 2 while the code and its constants
/// are read from bank 1, exactly the trigger. embassy-stm32 0.6.0 does not guard against it
/// (fixed upstream after 0.6.0, not released). The workaround the errata gives: data cache
/// off (DCEN = 0) for the operation, then reset it (DCRST pulse) and switch it on again.
///
/// If the operation's future is dropped halfway, the cache stays off: slower constant reads
/// until the next reset, never a corrupt one.
pub struct SettingsFlash(Flash<'static, Async>);

impl SettingsFlash {
    /// Takes the HAL's flash.
    pub fn new(flash: Flash<'static, Async>) -> Self {
        SettingsFlash(flash)
    }
}

fn data_cache_off() {
    pac::FLASH.acr().modify(|w| w.set_dcen(false));
}

/// After the operation: flush what the cache may hold from during it, then switch it on.
fn data_cache_reset_and_on() {
    pac::FLASH.acr().modify(|w| w.set_dcrst(true));
    pac::FLASH.acr().modify(|w| w.set_dcrst(false));
    pac::FLASH.acr().modify(|w| w.set_dcen(true));
}

impl ErrorType for SettingsFlash {
    type Error = Error;
}

impl ReadNorFlash for SettingsFlash {
    const READ_SIZE: usize = <Flash<'static, Async> as ReadNorFlash>::READ_SIZE;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Error> {
        ReadNorFlash::read(&mut self.0, offset, bytes).await
    }

    fn capacity(&self) -> usize {
        ReadNorFlash::capacity(&self.0)
    }
}

impl NorFlash for SettingsFlash {
    const WRITE_SIZE: usize = <Flash<'static, Async> as NorFlash>::WRITE_SIZE;
    const ERASE_SIZE: usize = <Flash<'static, Async> as NorFlash>::ERASE_SIZE;

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Error> {
        data_cache_off();
        let result = NorFlash::write(&mut self.0, offset, bytes).await;
        data_cache_reset_and_on();
        result
    }

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Error> {
        data_cache_off();
        let result = NorFlash::erase(&mut self.0, from, to).await;
        data_cache_reset_and_on();
        result
    }
}

/// The store over the settings region; build.rs checks the region against the page size.
/// `None` (logged) while the banks are swapped (option bit BFB2 booted bank 2, SYSCFG_MEMRMP
/// FB_MODE): the region's addresses would then be in the other bank from the one the flash
/// controller erases, and every save would fail its read-back (docs/board.md).
pub fn open(flash: SettingsFlash) -> Option<Store<Nucleo>> {
    plasma_tasks::chip::enable_syscfg_clock();
    if pac::SYSCFG.memrmp().read().fb_mode() {
        defmt::error!("flash banks swapped (BFB2 set): settings will not be kept");
        return None;
    }
    plasma_tasks::settings::open::<Nucleo>(flash, settings_region())
}

/// Double ECC errors the NMI handler skipped in the settings region since the last call.
pub fn flash_errors_seen() -> u32 {
    SETTINGS_ECC_ERRORS.swap(0, Ordering::Relaxed)
}
