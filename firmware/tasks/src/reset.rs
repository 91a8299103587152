//! Why the MCU started, for the boot report (`ID ... reset=`, `!BOOT reason=`): RCC_CSR's reset
//! flags and a panic marker that survives the reset. The same on both chips; each board's
//! fault handlers set the marker before they reset.

use core::mem::MaybeUninit;

use plasma_firmware::platform::safe_state::{BootReport, PANIC_MARKER};

use crate::chip;

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
    boot_report_from(chip::reset_flags())
}

/// As [`boot_report`], with `csr` standing in for RCC_CSR: for a board whose RCC does not
/// record the cause (the emulated board: QEMU's RCC shows power-on after every reset).
pub fn boot_report_from(csr: u32) -> BootReport {
    let report = BootReport::read(csr, take_panic_marker());
    chip::clear_reset_flags();
    report
}

/// Marks the coming reset as caused by a fault. Call with interrupts off.
pub fn mark_panic() {
    // SAFETY: as in take_panic_marker; the caller has interrupts off.
    unsafe { marker_word().write_volatile(PANIC_MARKER) };
}
