//! Panic and HardFault: outputs to safe state first, a marker that survives the reset
//! (`plasma_tasks::reset`), a log line, reset (SYSRESETREQ, which QEMU models).

use cortex_m_rt::{ExceptionFrame, exception};
use defmt::error;

use plasma_tasks::reset::mark_panic;
use plasma_tasks::safe_state::drive_safe_state;

fn fail(reason: impl FnOnce()) -> ! {
    cortex_m::interrupt::disable();
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
