//! Panic and HardFault: outputs to safe state first, a marker that survives the reset
//! (`plasma_tasks::reset`), a log line, reset (SYSRESETREQ, which QEMU models).

use cortex_m_rt::{ExceptionFrame, exception};
use defmt::error;

/// The shared fault path; the semihosting log needs no time to drain.
fn fail(reason: impl FnOnce()) -> ! {
    plasma_tasks::safe_state::fail(reason, || {})
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
