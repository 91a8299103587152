//! The register-level safe state (`plasma_firmware::pins::SAFE_STATE`, from the one pin table):
//! used before any driver exists and from the panic and fault handlers while tasks own the
//! pins. The same on both boards.

use plasma_firmware::pins;

use crate::chip;

/// Drives every output to its safe level with plain register writes.
pub fn drive_safe_state() {
    chip::enable_gpio_clocks(pins::OUTPUT_PORTS);
    for (pin, high) in pins::SAFE_STATE {
        chip::drive_as_output(pin, high);
    }
}
