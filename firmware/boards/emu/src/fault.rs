//! Panic and HardFault: outputs to safe state first, a marker that survives the reset
//! (`plasma_tasks::reset`), a log line, reset (SYSRESETREQ, which QEMU models).

use cortex_m_rt::{ExceptionFrame, exception};
use defmt::error;

use plasma_firmware::safe_state::FaultEntry;
use plasma_tasks::reset::mark_panic;
use plasma_tasks::safe_state::drive_safe_state;

/// The first entry into [`fail`]; a later one (a fault while it logs) skips the log.
static ENTRY: FaultEntry = FaultEntry::new();

/// Safe state, marker, log, reset; a second entry (a fault while the log line is written)
/// resets at once, unlogged, as on the Nucleo.
fn fail(reason: impl FnOnce()) -> ! {
    cortex_m::interrupt::disable();
    if !ENTRY.first() {
        // The reset leaves every pin high-impedance, held off by its pull-down.
        mark_panic();
        cortex_m::peripheral::SCB::sys_reset()
    }
    drive_safe_state();
    mark_panic();
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
