//! Panic and HardFault: outputs to safe state first, a marker that survives the reset, a log
//! line, reset (SYSRESETREQ, which QEMU models). The boot report reads the marker back.

use core::mem::MaybeUninit;

use cortex_m_rt::{ExceptionFrame, exception};
use defmt::error;
use plasma_firmware::safe_state::{BootReport, PANIC_MARKER};
use stm32_metapac::RCC;

use crate::tasks::pin_map::drive_safe_state;

/// A word the reset does not clear (cortex-m-rt's `.uninit`), for the panic marker.
#[unsafe(link_section = ".uninit.PANIC_MARKER")]
static mut PANIC_MARKER_WORD: MaybeUninit<u32> = MaybeUninit::uninit();

fn marker_word() -> *mut u32 {
    (&raw mut PANIC_MARKER_WORD).cast()
}

/// Why the MCU reset, from RCC_CSR and the panic marker; clears both for the next boot.
pub fn boot_report() -> BootReport {
    // SAFETY: a word-aligned static only this module touches, before the executors start.
    let marker = unsafe {
        let value = marker_word().read_volatile();
        marker_word().write_volatile(0);
        value
    };
    let report = BootReport::read(RCC.csr().read().0, marker);
    RCC.csr().modify(|w| w.set_rmvf(true));
    report
}

fn fail(reason: impl FnOnce()) -> ! {
    cortex_m::interrupt::disable();
    drive_safe_state();
    // SAFETY: as in boot_report; interrupts are off.
    unsafe { marker_word().write_volatile(PANIC_MARKER) };
    reason();
    cortex_m::peripheral::SCB::sys_reset()
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    // Flash is no concern here: the emulated image always says where and why.
    fail(|| error!("panic: {}", defmt::Display2Format(info)))
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    let pc = frame.pc();
    fail(|| error!("hard fault at pc {=u32:#010x}", pc))
}
