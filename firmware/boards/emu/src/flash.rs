//! Settings and history "flash" in RAM that survives a reset, as flash survives a power cut.
//! QEMU models no FLASH controller, so the stores run on the library's model of the L4 flash
//! (`plasma_firmware::storage::ram_flash`: 2 KiB pages, double-word programming), the sizes of
//! the Nucleo's regions, each kept in a `.uninit` section the start-up code does not clear
//! (QEMU keeps RAM across a reset and zeroes it only when it starts). So `CONFIG SAVE` and the
//! history last until QEMU exits, and a reset in the middle of a write leaves what the
//! silicon would: the steps done so far, one perhaps torn, none after.
//!
//! Each program and erase takes the L4's time (datasheet: 22 ms a page erase, 82 µs a double
//! word), as an async wait after the step: a save lasts as long as on the Nucleo, and a reset
//! at a random instant during it cuts it somewhere in the middle.

use core::mem::MaybeUninit;

use embassy_time::Timer;
use embedded_storage_async::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
use plasma_firmware::storage::ram_flash::{PAGE_SIZE, RamFlash, RamFlashError, WORD_SIZE};

/// The Nucleo's settings region (memory.x).
pub const SETTINGS_SIZE: usize = plasma_tasks::regions::SETTINGS_BYTES;
/// The Nucleo's history region (memory.x).
pub const HISTORY_SIZE: usize = plasma_tasks::regions::HISTORY_BYTES;

/// Page erase time (STM32L476 datasheet, tERASE typical).
const PAGE_ERASE_US: u64 = 22_000;
/// Double-word program time (tPROG typical).
const WORD_PROGRAM_US: u64 = 82;

/// Marks a kept model that holds flash contents (QEMU zeroes RAM when it starts: not erased
/// flash, so the first boot erases the model).
const KEPT: u32 = 0x464C_5348;

/// A flash model and its [`KEPT`] mark, in RAM the start-up code leaves alone.
type Kept<const SIZE: usize> = MaybeUninit<(u32, RamFlash<SIZE>)>;

#[unsafe(link_section = ".uninit.EMU_SETTINGS_FLASH")]
static mut SETTINGS: Kept<SETTINGS_SIZE> = MaybeUninit::uninit();

#[unsafe(link_section = ".uninit.EMU_HISTORY_FLASH")]
static mut HISTORY: Kept<HISTORY_SIZE> = MaybeUninit::uninit();

/// A flash model that outlives resets.
pub struct KeptFlash<const SIZE: usize>(&'static mut RamFlash<SIZE>);

/// The flash the settings store writes.
pub type SettingsFlash = KeptFlash<SETTINGS_SIZE>;
/// The flash the history is kept in.
pub type HistoryFlash = KeptFlash<HISTORY_SIZE>;

/// The kept settings flash (erased on QEMU's first boot). Call once.
pub fn settings_flash() -> SettingsFlash {
    // SAFETY: called once, at boot, before anything else uses SETTINGS.
    let place = &raw mut SETTINGS;
    KeptFlash::take(unsafe { &mut *place })
}

/// The kept history flash (erased on QEMU's first boot). Call once.
pub fn history_flash() -> HistoryFlash {
    // SAFETY: called once, at boot, before anything else uses HISTORY.
    let place = &raw mut HISTORY;
    KeptFlash::take(unsafe { &mut *place })
}

impl<const SIZE: usize> KeptFlash<SIZE> {
    // Out of line: its erased flash (up to 16 KB, built and copied at the first boot) is in
    // this frame only while it runs, not in the boot task's for its whole life (the stack is
    // 32 KB).
    #[inline(never)]
    fn take(store: &'static mut Kept<SIZE>) -> Self {
        // SAFETY: every bit pattern the previous run can have left is a valid RamFlash (it
        // only ever stores whole valid values: bytes, counters, flags written as 0 or 1), and
        // a store never marked KEPT is overwritten before it is read as one.
        let kept = unsafe { (&raw const (*store.as_ptr()).0).read_volatile() } == KEPT;
        if !kept {
            store.write((KEPT, RamFlash::new()));
        }
        // SAFETY: initialised above or by a previous run.
        let (_, flash) = unsafe { store.assume_init_mut() };
        // A cut scheduled by the previous run (none: only tests schedule them) is over.
        flash.power_cycle();
        KeptFlash(flash)
    }
}

impl<const SIZE: usize> ErrorType for KeptFlash<SIZE> {
    type Error = RamFlashError;
}

impl<const SIZE: usize> ReadNorFlash for KeptFlash<SIZE> {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes).await
    }

    fn capacity(&self) -> usize {
        SIZE
    }
}

impl<const SIZE: usize> NorFlash for KeptFlash<SIZE> {
    const WRITE_SIZE: usize = WORD_SIZE;
    const ERASE_SIZE: usize = PAGE_SIZE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        for page in (from..to).step_by(PAGE_SIZE) {
            self.0.erase(page, page + PAGE_SIZE as u32).await?;
            Timer::after_micros(PAGE_ERASE_US).await;
        }
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        for (i, word) in bytes.chunks(WORD_SIZE).enumerate() {
            self.0.write(offset + (i * WORD_SIZE) as u32, word).await?;
            Timer::after_micros(WORD_PROGRAM_US).await;
        }
        Ok(())
    }
}
