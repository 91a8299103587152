//! Panic and HardFault: outputs to safe state first, a marker that survives the reset
//! (`plasma_tasks::reset`), a log line, reset (SYSRESETREQ, which QEMU models). The
//! HardFault vector is the Nucleo's (`plasma_tasks::hard_fault`).

use defmt::error;
use plasma_tasks::Board;

use crate::board::Emulated;

/// The shared fault path.
fn fail(reason: impl FnOnce()) -> ! {
    plasma_tasks::safe_state::fail(reason, Emulated::drain_log)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    // Flash is no concern here: the emulated image always says where and why.
    fail(|| error!("panic: {}", defmt::Display2Format(info)))
}

plasma_tasks::hard_fault_handler!(Emulated);
