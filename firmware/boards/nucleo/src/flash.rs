//! The settings and history flash: the end of the MCU's flash (regions from memory.x),
//! through the HAL's one async driver, with the data cache off while it programs or erases
//! (errata ES0250). The settings task and the history task each get a partition of it
//! (embassy-embedded-hal's, behind an async mutex): one operation at a time, each within its
//! own region.

use core::ops::Range;
use core::sync::atomic::Ordering;

use embassy_embedded_hal::flash::partition::Partition;
use embassy_stm32::flash::{Async, Error, Flash};
use embassy_stm32::pac;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::mutex::Mutex;
use embedded_storage_async::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use plasma_tasks::{history, settings};
use static_cell::StaticCell;

use crate::board::Nucleo;
use crate::fault::STORAGE_ECC_ERRORS;

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

/// The history region from memory.x, as offsets from the start of flash.
pub fn history_region() -> Range<u32> {
    unsafe extern "C" {
        static __history_start: u8;
        static __history_end: u8;
    }
    // As above: addresses only.
    let start = (&raw const __history_start) as u32;
    let end = (&raw const __history_end) as u32;
    start - FLASH_BASE..end - FLASH_BASE
}

/// Whether `address` (in the address map) is in the settings or the history region.
pub fn in_storage(address: u32) -> bool {
    [settings_region(), history_region()]
        .iter()
        .any(|region| (region.start + FLASH_BASE..region.end + FLASH_BASE).contains(&address))
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
pub struct GuardedFlash(Flash<'static, Async>);

/// The one flash, shared by the settings and history partitions.
type SharedFlash = Mutex<CriticalSectionRawMutex, GuardedFlash>;

/// A region of the flash: offsets from the region's start.
pub type Region = Partition<'static, CriticalSectionRawMutex, GuardedFlash>;

static FLASH: StaticCell<SharedFlash> = StaticCell::new();

fn data_cache_off() {
    pac::FLASH.acr().modify(|w| w.set_dcen(false));
}

/// After the operation: flush what the cache may hold from during it, then switch it on.
fn data_cache_reset_and_on() {
    pac::FLASH.acr().modify(|w| w.set_dcrst(true));
    pac::FLASH.acr().modify(|w| w.set_dcrst(false));
    pac::FLASH.acr().modify(|w| w.set_dcen(true));
}

impl ErrorType for GuardedFlash {
    type Error = Error;
}

impl ReadNorFlash for GuardedFlash {
    const READ_SIZE: usize = <Flash<'static, Async> as ReadNorFlash>::READ_SIZE;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Error> {
        ReadNorFlash::read(&mut self.0, offset, bytes).await
    }

    fn capacity(&self) -> usize {
        ReadNorFlash::capacity(&self.0)
    }
}

impl NorFlash for GuardedFlash {
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

/// The settings store and the history over their regions; build.rs checks the regions
/// against the page size. Both `None` (logged) while the banks are swapped (option bit BFB2
/// booted bank 2, SYSCFG_MEMRMP FB_MODE): the regions' addresses would then be in the other
/// bank from the one the flash controller erases, and every write would fail its read-back
/// (docs/board.md). Call once.
pub fn open(
    flash: Flash<'static, Async>,
) -> (
    Option<settings::Store<Nucleo>>,
    Option<history::Store<Nucleo>>,
) {
    plasma_tasks::chip::enable_syscfg_clock();
    if pac::SYSCFG.memrmp().read().fb_mode() {
        defmt::error!("flash banks swapped (BFB2 set): settings and history will not be kept");
        return (None, None);
    }
    let shared: &'static SharedFlash = FLASH.init(Mutex::new(GuardedFlash(flash)));
    let settings = partition(shared, settings_region())
        .and_then(|(region, size)| settings::open::<Nucleo>(region, 0..size));
    let history = partition(shared, history_region())
        .and_then(|(region, size)| history::open::<Nucleo>(region, 0..size));
    (settings, history)
}

/// The partition over `region` and its size, or `None` (logged) for a region that is not
/// whole pages (which `Partition::new` would panic on; build.rs already refuses it).
fn partition(shared: &'static SharedFlash, region: Range<u32>) -> Option<(Region, u32)> {
    let page = GuardedFlash::ERASE_SIZE as u32;
    let size = region.end.checked_sub(region.start)?;
    if !region.start.is_multiple_of(page) || !size.is_multiple_of(page) {
        defmt::error!("flash region {=u32:#x}: not whole pages", region.start);
        return None;
    }
    Some((Partition::new(shared, region.start, size), size))
}

/// Double ECC errors the NMI handler skipped in the settings and history regions since the
/// last call.
pub fn flash_errors_seen() -> u32 {
    STORAGE_ECC_ERRORS.swap(0, Ordering::Relaxed)
}
