//! The register-level safe state (`plasma_firmware::platform::pins::SAFE_STATE`, from the one pin table):
//! used before any driver exists and from the panic and fault handlers while tasks own the
//! pins. The same on both boards.
//!
//! Also the fail-safe latch (`plasma_firmware::platform::safe_state::FailSafe`): once a stalled task
//! made the outputs safe ([`trip_fail_safe`]), every later output write ([`drive_outputs`]) is
//! refused until the reset.

use plasma_firmware::io::Outputs;
use plasma_firmware::platform::pins::{self, UnitSet};
use plasma_firmware::platform::safe_state::{FailSafe, FaultEntry};

use crate::board::OutputPins;
use crate::chip;
use crate::reset::mark_panic;

static FAIL_SAFE: FailSafe = FailSafe::new();

/// The first entry into [`fail`]; a later one (a fault while it logs) skips the log.
static FAULT_ENTRY: FaultEntry = FaultEntry::new();

/// Every board's fault path (panic, HardFault, NMI): the outputs safe first, the marker the
/// next boot reports (`!BOOT reason=panic`), the board's `log` line, its `drain` (time for the
/// logger to get the line out), then a reset. An NMI or HardFault while the log line is
/// written would enter again, and defmt-rtt panics on re-entry: a second entry resets at once,
/// unlogged (the first already made the outputs safe; the reset leaves every pin
/// high-impedance, held off by its pull-down).
pub fn fail(log: impl FnOnce(), drain: impl FnOnce()) -> ! {
    cortex_m::interrupt::disable();
    if FAULT_ENTRY.first() {
        drive_safe_state();
        mark_panic();
        log();
        drain();
    } else {
        mark_panic();
    }
    cortex_m::peripheral::SCB::sys_reset()
}

/// Drives every output to its safe level with plain register writes.
pub fn drive_safe_state() {
    chip::enable_gpio_clocks(pins::OUTPUT_PORTS);
    for (pin, high) in pins::SAFE_STATE {
        chip::drive_as_output(pin, high);
    }
}

/// Safe state now and for good (until reset): the latch and the pin writes under one critical
/// section, so no output write of a higher-priority task can come between them.
pub fn trip_fail_safe() {
    critical_section::with(|_| {
        FAIL_SAFE.trip();
        drive_safe_state();
    });
}

/// Sets unit `set`'s outputs, unless the fail-safe tripped; whether they were set.
pub fn drive_outputs(pins: &mut impl OutputPins, set: UnitSet, outputs: Outputs) -> bool {
    critical_section::with(|_| FAIL_SAFE.drive_unless_tripped(|| pins.drive(set, outputs)))
}
