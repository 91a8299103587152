//! The emulated board's pins as QEMU sees them. Where each signal is and which level is active
//! come from the firmware's one pin table (`plasma_firmware::platform::pins`, docs/board.md); this module
//! adds only what is QEMU's: the ports' QOM paths and the data registers the harness reads.

use plasma_firmware::io::{Input, Output};
use plasma_firmware::platform::pins::{self, input, output};
pub use plasma_firmware::platform::pins::{Pin, Port, UNIT_SETS, UnitSet};

/// What the harness needs of a GPIO port under QEMU.
pub trait QemuPort {
    /// The port's QOM path, as qtest's `set_irq_in` and `irq_intercept_out` name it.
    fn qom_path(self) -> &'static str;
    /// Address of the port's output data register (ODR, offset 0x14).
    fn odr_address(self) -> u64;
    /// Address of the port's input data register (IDR, offset 0x10).
    fn idr_address(self) -> u64;
}

impl QemuPort for Port {
    fn qom_path(self) -> &'static str {
        match self {
            Port::A => "/machine/soc/gpioa",
            Port::B => "/machine/soc/gpiob",
            Port::C => "/machine/soc/gpioc",
        }
    }

    fn odr_address(self) -> u64 {
        u64::from(self.register_block()) + 0x14
    }

    fn idr_address(self) -> u64 {
        u64::from(self.register_block()) + 0x10
    }
}

/// Unit `unit`'s set of the pin table (0 = the first unit).
///
/// # Panics
/// For a unit the board has no set for: the test asked for pins that do not exist.
pub fn unit_set(unit: usize) -> UnitSet {
    UnitSet::new(unit)
        .unwrap_or_else(|| panic!("the board carries {UNIT_SETS} unit sets, not unit {unit}'s"))
}

/// The pin of unit `unit`'s discrete input (a board-wide input's one pin for every unit).
pub fn unit_input_pin(unit: usize, signal: Input) -> Pin {
    unit_set(unit).input(signal).pin
}

/// The pin of unit `unit`'s discrete output.
pub fn unit_output_pin(unit: usize, signal: Output) -> Pin {
    unit_set(unit).output(signal).pin
}

/// The level to drive on unit `unit`'s `signal` pin for it to be `active`.
pub fn unit_input_level(unit: usize, signal: Input, active: bool) -> bool {
    unit_set(unit).input(signal).level(active)
}

/// Whether unit `unit`'s `signal` is active at pin level `high`.
pub fn unit_output_active(unit: usize, signal: Output, high: bool) -> bool {
    unit_set(unit).output(signal).is_on(high)
}

/// The pin of a discrete input.
pub const fn input_pin(signal: Input) -> Pin {
    input(signal).pin
}

/// The pin of a discrete output.
pub const fn output_pin(signal: Output) -> Pin {
    output(signal).pin
}

/// The level to drive on `signal`'s pin for it to be `active`.
pub const fn input_level(signal: Input, active: bool) -> bool {
    input(signal).level(active)
}

/// Whether `signal` is active at pin level `high`.
pub const fn output_active(signal: Output, high: bool) -> bool {
    output(signal).is_on(high)
}

/// The port whose output edges the harness streams with qtest's `irq_intercept_out`: every
/// unit's START, ARC_OK and READY, and the first unit's PS_CORNER_CURRENT. Intercepting
/// detaches the port from EXTI, so it must hold no input whose edge a test waits for: every
/// unit's TORCH_ON and MOTION are on GPIOA and GPIOC, which are never intercepted.
pub const WATCHED_PORT: Port = Port::B;

/// Every unit's inputs on the watched port (their EXTI is detached while it is watched: the
/// firmware reads their levels at its next wake, within 50 ms).
pub fn watched_port_inputs() -> impl Iterator<Item = (UnitSet, Input)> {
    UnitSet::ALL.into_iter().flat_map(|set| {
        Input::ALL
            .into_iter()
            .filter(move |&i| set.input(i).pin.port == WATCHED_PORT)
            .map(move |i| (set, i))
    })
}

/// A failure the test images make on request (the emulated board's `test-hooks`, see
/// [`super::image`]): each has its pin in the firmware's pin table, pulled low to ask.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TestHook {
    /// Thread mode spins for good: the watchdog's case.
    Stall,
    /// A panic in a task.
    Panic,
    /// A HardFault (an undefined instruction) in a task.
    HardFault,
    /// A task recurses until the stack runs off the bottom of SRAM2.
    StackOverflow,
}

impl TestHook {
    /// Every hook.
    pub const ALL: [TestHook; 4] = [
        TestHook::Stall,
        TestHook::Panic,
        TestHook::HardFault,
        TestHook::StackOverflow,
    ];

    /// The pin that asks for it.
    pub const fn pin(self) -> Pin {
        match self {
            TestHook::Stall => pins::TEST_STALL,
            TestHook::Panic => pins::TEST_PANIC,
            TestHook::HardFault => pins::TEST_HARD_FAULT,
            TestHook::StackOverflow => pins::TEST_STACK_OVERFLOW,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_registers_are_the_ports() {
        assert_eq!(Port::B.odr_address(), 0x4800_0414);
        assert_eq!(Port::C.odr_address(), 0x4800_0814);
        assert_eq!(Port::A.idr_address(), 0x4800_0010);
        assert_eq!(Port::B.qom_path(), "/machine/soc/gpiob");
    }

    #[test]
    fn levels_follow_the_table() {
        // Inputs active low, outputs active high (docs/board.md).
        assert!(!input_level(Input::TorchOn, true));
        assert!(input_level(Input::TorchOn, false));
        assert!(output_active(Output::Start, true));
    }

    #[test]
    fn the_watched_port_holds_every_units_start_and_arc_ok_and_no_torch_input() {
        for unit in 0..UNIT_SETS {
            assert_eq!(unit_output_pin(unit, Output::Start).port, WATCHED_PORT);
            assert_eq!(unit_output_pin(unit, Output::ArcOk).port, WATCHED_PORT);
            assert_ne!(unit_input_pin(unit, Input::TorchOn).port, WATCHED_PORT);
            assert_ne!(unit_input_pin(unit, Input::Motion).port, WATCHED_PORT);
        }
        assert!(
            watched_port_inputs().all(|(_, i)| matches!(i, Input::RampdownError | Input::NotReady)),
            "only supply status inputs, read by level"
        );
        assert_eq!(unit_output_pin(1, Output::Start).to_string(), "PB1");
        assert!(!unit_input_level(1, Input::TorchOn, true));
        assert!(unit_output_active(1, Output::Start, true));
    }

    #[test]
    fn every_test_hook_has_its_own_pin_off_the_watched_port() {
        // Intercepting the watched port detaches its pins from EXTI: a hook there never fires.
        let hook_pins = TestHook::ALL.map(TestHook::pin);
        assert_eq!(hook_pins, pins::TEST_HOOKS);
        assert!(hook_pins.iter().all(|p| p.port != WATCHED_PORT));
    }
}
