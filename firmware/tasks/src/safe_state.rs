//! The register-level safe state (`plasma_firmware::pins::SAFE_STATE`, from the one pin table):
//! used before any driver exists and from the panic and fault handlers while tasks own the
//! pins. The same on both boards.
//!
//! Also the fail-safe latch (`plasma_firmware::safe_state::FailSafe`): once a stalled task
//! made the outputs safe ([`trip_fail_safe`]), every later output write ([`drive_outputs`]) is
//! refused until the reset.

use plasma_firmware::io::Outputs;
use plasma_firmware::pins;
use plasma_firmware::safe_state::FailSafe;

use crate::board::OutputPins;
use crate::chip;

static FAIL_SAFE: FailSafe = FailSafe::new();

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

/// Sets the outputs, unless the fail-safe tripped; whether they were set.
pub fn drive_outputs(pins: &mut impl OutputPins, outputs: Outputs) -> bool {
    critical_section::with(|_| FAIL_SAFE.drive_unless_tripped(|| pins.drive(outputs)))
}
