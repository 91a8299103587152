//! Panic, HardFault and NMI: outputs to safe state first, a marker that survives the reset,
//! a log line, reset. And the boot report that reads the marker back.

use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m_rt::{ExceptionFrame, exception};
use defmt::error;
use embassy_stm32::pac;
use plasma_firmware::safe_state::{BootReport, PANIC_MARKER};

use crate::flash::{FLASH_BANK2, FLASH_BASE, settings_region};
use crate::tasks::pin_map::drive_safe_state;

/// A word the reset does not clear (cortex-m-rt's `.uninit`), for the panic marker.
#[unsafe(link_section = ".uninit.PANIC_MARKER")]
static mut PANIC_MARKER_WORD: MaybeUninit<u32> = MaybeUninit::uninit();

fn marker_word() -> *mut u32 {
    (&raw mut PANIC_MARKER_WORD).cast()
}

/// Reads and clears the panic marker. The word may hold power-up garbage: BootReport only
/// believes it together with the software-reset flag.
fn take_panic_marker() -> u32 {
    // SAFETY: a word-aligned static only this module touches, in a single-threaded context
    // (before the executors start); volatile because the compiler cannot know the previous
    // run wrote it.
    unsafe {
        let value = marker_word().read_volatile();
        marker_word().write_volatile(0);
        value
    }
}

/// Why the MCU reset, from RCC_CSR and the panic marker; clears both for the next boot.
pub fn boot_report() -> BootReport {
    let csr = pac::RCC.csr().read().0;
    let report = BootReport::read(csr, take_panic_marker());
    pac::RCC.csr().modify(|w| w.set_rmvf(true));
    report
}

/// Safe state, marker, log, reset.
fn fail(reason: impl FnOnce()) -> ! {
    cortex_m::interrupt::disable();
    drive_safe_state();
    // SAFETY: as in take_panic_marker; interrupts are off.
    unsafe { marker_word().write_volatile(PANIC_MARKER) };
    reason();
    // Give a probe ~50 ms to drain the RTT buffer; the outputs are already safe.
    cortex_m::asm::delay(4_000_000);
    cortex_m::peripheral::SCB::sys_reset()
}

/// The outcome is the same in every build: safe state, marker (`!BOOT reason=panic`), reset.
/// Only the log line differs: the message and location of a panic cost ~5 KB of flash (the
/// file path and line of every panic site and the formatting behind the messages), so the
/// standard image logs the bare fact and a debugging build (`cargo fw --features
/// panic-message`) says where and why.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    #[cfg(feature = "panic-message")]
    fail(|| error!("panic: {}", defmt::Display2Format(info)));
    #[cfg(not(feature = "panic-message"))]
    {
        // Unread, the PanicInfo and everything that builds it are left out of the image.
        let _ = info;
        fail(|| error!("panic (cargo fw --features panic-message logs where and why)"))
    }
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    let pc = frame.pc();
    fail(|| error!("hard fault at pc {=u32:#010x}", pc))
}

/// Double ECC errors seen in the settings region (a program cut by a power loss can leave
/// one), for the log.
pub static SETTINGS_ECC_ERRORS: AtomicU32 = AtomicU32::new(0);

/// The L4 raises an NMI when a flash read hits a double ECC error. In the settings region
/// that is the trace of a torn write: clear it and return; the load completes with bad data,
/// which the store's CRCs reject. Anywhere else the program itself is damaged.
///
/// An NMI can interrupt a critical section, so this handler touches only an atomic and the
/// FLASH registers; the failure path ignores that rule because it resets.
#[exception]
unsafe fn NonMaskableInt() {
    let eccr = pac::FLASH.eccr().read();
    if eccr.eccd() {
        let bank_base = if eccr.bk_ecc() {
            FLASH_BANK2
        } else {
            FLASH_BASE
        };
        let address = bank_base + eccr.addr_ecc();
        // ECCD is write-1-to-clear.
        pac::FLASH.eccr().modify(|w| w.set_eccd(true));
        let settings = settings_region();
        if (settings.start + FLASH_BASE..settings.end + FLASH_BASE).contains(&address) {
            SETTINGS_ECC_ERRORS.fetch_add(1, Ordering::Relaxed);
            return;
        }
        fail(|| error!("double ECC error in flash at {=u32:#010x}", address))
    }
    fail(|| error!("NMI"))
}
