//! Panic, HardFault and NMI: outputs to safe state first, a marker that survives the reset
//! (`plasma_tasks::reset`, which reads it back at boot), a log line, reset. The HardFault
//! vector is the shared one that survives a stack overflow (`plasma_tasks::hard_fault`).

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m::peripheral::DWT;
use cortex_m_rt::exception;
use defmt::error;
use embassy_stm32::pac;
use plasma_tasks::Board;
use plasma_tasks::chip::rcc_snapshot;

use crate::flash::{FLASH_BANK2, FLASH_BASE, in_storage};

use crate::board::Nucleo;

/// The shared fault path (`plasma_tasks::safe_state::fail`), then [`drain_log`].
fn fail(reason: impl FnOnce()) -> ! {
    plasma_tasks::safe_state::fail(reason, Nucleo::drain_log)
}

/// How long the fault path waits for a probe to drain the RTT buffer: 1/20 s.
const DRAIN_PER_SECOND: u32 = 20;

/// Waits 50 ms for a probe to drain the RTT buffer before the reset (the outputs are already
/// safe), timed by the cycle counter at the SYSCLK the RCC runs, so it is 50 ms on the 4 MHz
/// boot clock as at 80 MHz and well inside the IWDG's second. A clock it cannot tell: no
/// wait (the reset matters more than the line).
pub fn drain_log() {
    let Some(sysclk_hz) = rcc_snapshot().sysclk_hz() else {
        return;
    };
    // SAFETY: the fault path, interrupts off; nothing else uses DCB or DWT.
    let mut core = unsafe { cortex_m::Peripherals::steal() };
    core.DCB.enable_trace();
    core.DWT.enable_cycle_counter();
    let start = DWT::cycle_count();
    while DWT::cycle_count().wrapping_sub(start) < sysclk_hz / DRAIN_PER_SECOND {}
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

plasma_tasks::hard_fault_handler!(Nucleo);

/// Double ECC errors seen in the settings and history regions (a program cut by a power
/// loss can leave one), for the log.
pub static STORAGE_ECC_ERRORS: AtomicU32 = AtomicU32::new(0);

/// The L4 raises an NMI when a flash read hits a double ECC error. In the settings or
/// history region that is the trace of a torn write: clear it and return; the read completes
/// with bad data, which the stores' CRCs reject. Anywhere else the program itself is damaged.
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
        // SYSF_ECC: ADDR_ECC is an offset in system flash (the bootloader), never stored data.
        if !eccr.sysf_ecc() && in_storage(address) {
            STORAGE_ECC_ERRORS.fetch_add(1, Ordering::Relaxed);
            return;
        }
        fail(|| error!("double ECC error in flash at {=u32:#010x}", address))
    }
    fail(|| error!("NMI"))
}
