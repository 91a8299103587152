//! The reference board's pin map (docs/board.md): where every discrete signal and the heartbeat
//! LED is, and which level is active. This is the one table: the Nucleo's HAL set-up, the
//! register-level safe state of the panic and fault path, the emulated board's GPIO set-up and
//! the QEMU harness all read it, so a signal moved here moves everywhere.
//!
//! ```
//! use plasma_firmware::io::Output;
//! use plasma_firmware::platform::pins::{Port, output};
//!
//! let start = output(Output::Start);
//! assert_eq!((start.pin.port, start.pin.number), (Port::B, 0));
//! assert!(start.level(true), "outputs are active high");
//! ```

use core::fmt;

use crate::io::Polarity;
use crate::io::{Input, Output};
use crate::platform::safe_state::SAFE_OUTPUTS;

/// A GPIO port the board uses. The STM32L476RG and the emulated STM32L475VG have the same
/// ports at the same addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Port {
    /// GPIOA.
    A,
    /// GPIOB.
    B,
    /// GPIOC.
    C,
}

impl Port {
    /// The port's index: A = 0. It is the port's number in SYSCFG_EXTICR and in
    /// embassy-stm32's pin numbering, and its clock-enable bit in RCC_AHB2ENR.
    pub const fn index(self) -> u8 {
        self as u8
    }

    /// The address of the port's register block (RM0351 memory map: AHB2, 0x400 apart).
    pub const fn register_block(self) -> u32 {
        0x4800_0000 + 0x400 * self.index() as u32
    }

    const fn letter(self) -> char {
        match self {
            Port::A => 'A',
            Port::B => 'B',
            Port::C => 'C',
        }
    }
}

/// A pin: port and number (0-15). The number is also the pin's EXTI line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pin {
    /// The port.
    pub port: Port,
    /// The pin number within the port.
    pub number: u8,
}

impl Pin {
    const fn new(port: Port, number: u8) -> Pin {
        Pin { port, number }
    }

    /// This pin's bit in a port register (IDR, ODR).
    pub const fn mask(self) -> u32 {
        1 << self.number
    }

    /// Whether this is pin `number` of `port` (for compile-time checks: `==` is not const).
    pub const fn is(self, port: Port, number: u8) -> bool {
        self.port as u8 == port as u8 && self.number == number
    }

    /// `port index × 16 + number`, the numbering of embassy-stm32's `AnyPin::steal`.
    pub const fn port_pin(self) -> u8 {
        self.port.index() * 16 + self.number
    }
}

impl fmt::Display for Pin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "P{}{}", self.port.letter(), self.number)
    }
}

/// A signal's pin and which of its levels means "on".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Wiring {
    /// Where the signal is.
    pub pin: Pin,
    /// Which pin level is active.
    pub active: Polarity,
}

impl Wiring {
    const fn new(port: Port, number: u8, active: Polarity) -> Wiring {
        Wiring {
            pin: Pin::new(port, number),
            active,
        }
    }

    /// The pin level (`true` = high) for the signal being `on`.
    pub const fn level(self, on: bool) -> bool {
        match self.active {
            Polarity::ActiveHigh => on,
            Polarity::ActiveLow => !on,
        }
    }

    /// Whether the signal is on at pin level `high`.
    pub const fn is_on(self, high: bool) -> bool {
        self.active.is_active(high)
    }
}

/// Inputs are active low: an opto-coupler (or the HPR's open collector) pulls the pin down
/// when the signal is on, a pull-up holds it high otherwise.
const IN: Polarity = Polarity::ActiveLow;
/// Outputs are active high, with an external pull-down so they are off while the pin is still
/// high-impedance after reset.
const OUT: Polarity = Polarity::ActiveHigh;

/// Where each input is. Each is on its own EXTI line (its pin number).
pub const fn input(input: Input) -> Wiring {
    match input {
        Input::TorchOn => Wiring::new(Port::A, 0, IN),
        Input::Motion => Wiring::new(Port::A, 1, IN),
        Input::Hold => Wiring::new(Port::A, 4, IN),
        Input::PierceComplete => Wiring::new(Port::A, 6, IN),
        Input::CornerCurrent => Wiring::new(Port::A, 7, IN),
        Input::NotReady => Wiring::new(Port::A, 8, IN),
        Input::RampdownError => Wiring::new(Port::B, 10, IN),
        // Optional (HPR, MaxPro200): unwired, the pull-up reads it inactive.
        Input::SystemError => Wiring::new(Port::C, 5, IN),
    }
}

/// Where each output is.
pub const fn output(output: Output) -> Wiring {
    match output {
        Output::Start => Wiring::new(Port::B, 0, OUT),
        Output::Hold => Wiring::new(Port::C, 1, OUT),
        Output::PierceComplete => Wiring::new(Port::C, 0, OUT),
        Output::CornerCurrent => Wiring::new(Port::B, 8, OUT),
        Output::ArcOk => Wiring::new(Port::B, 9, OUT),
        Output::Ready => Wiring::new(Port::B, 6, OUT),
        Output::Fault => Wiring::new(Port::C, 7, OUT),
        // Optional (HPR): unwired, nothing follows it.
        Output::RemotePower => Wiring::new(Port::C, 8, OUT),
    }
}

/// How many units' discrete sets the board carries: unit 0's is [`input`] and [`output`];
/// the Nucleo's free pins allow one more (docs/board.md, "Several units").
pub const UNIT_SETS: usize = 2;

/// Whether `input` is the board's, read by every unit's I/O, rather than each unit's own: the
/// CNC's HOLD, PIERCE_COMPLETE and CORNER_CURRENT follow the machine's motion, which the torches
/// of one gantry share (HOLD is how a CNC makes several torches ignite together). Each unit
/// still has its own PS_HOLD, PS_PIERCE_COMPLETE and PS_CORNER_CURRENT outputs: each supply
/// has its own isolated inputs.
pub const fn is_board_wide(input: Input) -> bool {
    matches!(
        input,
        Input::Hold | Input::PierceComplete | Input::CornerCurrent
    )
}

/// One unit's discrete set: the index of a set the board carries (below [`UNIT_SETS`]), so
/// every pin it names exists. Unit 0 (the first unit, `@1` on the CNC port) is the set of
/// [`input`] and [`output`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UnitSet(u8);

impl UnitSet {
    /// Every set, unit 0 first.
    pub const ALL: [UnitSet; UNIT_SETS] = [UnitSet(0), UnitSet(1)];

    /// Unit `unit`'s set (0 = the first unit), if the board carries one.
    pub const fn new(unit: usize) -> Option<UnitSet> {
        if unit < UNIT_SETS {
            Some(UnitSet(unit as u8))
        } else {
            None
        }
    }

    /// The unit's index (0 = the first unit).
    pub const fn index(self) -> usize {
        self.0 as usize
    }

    /// Where this unit's `input` is (a board-wide input's pin is unit 0's).
    pub const fn input(self, input: Input) -> Wiring {
        match (self.0, input) {
            (0, _) => self::input(input),
            (_, Input::TorchOn) => Wiring::new(Port::C, 2, IN),
            (_, Input::Motion) => Wiring::new(Port::C, 3, IN),
            (_, Input::NotReady) => Wiring::new(Port::B, 14, IN),
            (_, Input::RampdownError) => Wiring::new(Port::B, 15, IN),
            (_, Input::SystemError) => Wiring::new(Port::C, 4, IN),
            (_, Input::Hold | Input::PierceComplete | Input::CornerCurrent) => self::input(input),
        }
    }

    /// Where this unit's `output` is.
    pub const fn output(self, output: Output) -> Wiring {
        match (self.0, output) {
            (0, _) => self::output(output),
            (_, Output::Start) => Wiring::new(Port::B, 1, OUT),
            (_, Output::Hold) => Wiring::new(Port::C, 6, OUT),
            (_, Output::PierceComplete) => Wiring::new(Port::C, 10, OUT),
            (_, Output::CornerCurrent) => Wiring::new(Port::B, 2, OUT),
            (_, Output::ArcOk) => Wiring::new(Port::B, 5, OUT),
            (_, Output::Ready) => Wiring::new(Port::B, 7, OUT),
            (_, Output::Fault) => Wiring::new(Port::B, 11, OUT),
            (_, Output::RemotePower) => Wiring::new(Port::B, 12, OUT),
        }
    }

    /// Every output's wiring of this unit, in [`Output::ALL`] order (START first): for loops
    /// that drive a set without a lookup per pin.
    pub fn outputs(self) -> &'static [Wiring; 8] {
        match UNIT_OUTPUTS.get(self.index()) {
            Some(outputs) => outputs,
            None => &OUTPUTS,
        }
    }

    /// Whether this unit's `input` has an EXTI line of its own, whose edges wake the I/O task
    /// (which reads every level at each wake, and at least every 50 ms). A board-wide input
    /// has its line in unit 0's set. Unit 1's SYSTEM_ERROR has none: the sixteen lines are
    /// taken (one port per line: unit 0's eight inputs, unit 1's four, the four test hooks),
    /// and it is the input whose timing matters least (it only holds FAULT on; the
    /// supply's error code comes over the serial link).
    pub const fn wakes_on_edge(self, input: Input) -> bool {
        match (self.0, input) {
            (0, _) => true,
            (_, Input::SystemError) => false,
            (_, input) => !is_board_wide(input),
        }
    }
}

/// The green heartbeat LED (LD2 on the Nucleo, LD1 on the B-L475E-IOT01A: PA5 on both).
pub const HEARTBEAT_LED: Wiring = Wiring::new(Port::A, 5, Polarity::ActiveHigh);

/// The user button (B1 on the Nucleo; the B-L475E-IOT01A's user button is PC13 too), active
/// low. Read once at boot: held at reset, the CNC port starts at its default framing
/// ([`Settings::at_boot`](crate::settings::Settings::at_boot)), the way back to a board whose
/// saved framing is forgotten. After boot only test images read it ([`TEST_STALL`]).
pub const USER_BUTTON: Wiring = Wiring::new(Port::C, 13, Polarity::ActiveLow);

/// The user button again ([`USER_BUTTON`], read at boot only): in test images, after boot,
/// the trigger that stalls thread mode on purpose (the emulated board's `test-hooks`
/// feature, which the QEMU harness turns on to test the fail-safe). Active low, as the button.
pub const TEST_STALL: Pin = USER_BUTTON.pin;

/// Test images only, as [`TEST_STALL`]: pulled low, the firmware panics (the fault path's
/// end-to-end test). PC11 and [`TEST_HARD_FAULT`]'s PC12 are free on both boards (ST morpho
/// CN7-2 and CN7-3 on the Nucleo), on EXTI lines no input uses, and off the port the QEMU
/// harness intercepts (GPIOB: its inputs reach no EXTI there). Active low.
pub const TEST_PANIC: Pin = Pin::new(Port::C, 11);

/// Test images only, as [`TEST_PANIC`]: pulled low, the firmware takes a HardFault.
pub const TEST_HARD_FAULT: Pin = Pin::new(Port::C, 12);

/// Test images only, as [`TEST_PANIC`]: pulled low, the firmware overflows its stack. PC9
/// (ST morpho CN10-1 on the Nucleo) is free, on EXTI line 9, which no input uses.
pub const TEST_STACK_OVERFLOW: Pin = Pin::new(Port::C, 9);

/// The test hooks' pins, for the checks that tie them to the rest of the table.
pub const TEST_HOOKS: [Pin; 4] = [TEST_STALL, TEST_PANIC, TEST_HARD_FAULT, TEST_STACK_OVERFLOW];

/// A UART's pins (alternate function 7 on both).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct UartPins {
    /// Transmit.
    pub tx: Pin,
    /// Receive.
    pub rx: Pin,
    /// The RS-485/422 transceiver's driver enable, driven by the USART itself.
    pub de: Option<Pin>,
}

impl UartPins {
    /// Every pin the UART uses.
    pub fn pins(self) -> impl Iterator<Item = Pin> {
        [self.tx, self.rx].into_iter().chain(self.de)
    }
}

/// The power-supply UART: USART1 on PA9 (TX), PA10 (RX), PA12 (DE).
pub const PS_UART: UartPins = UartPins {
    tx: Pin::new(Port::A, 9),
    rx: Pin::new(Port::A, 10),
    de: Some(Pin::new(Port::A, 12)),
};

/// The CNC UART: USART2 on PA2 (TX), PA3 (RX), the ST-LINK's virtual COM port.
pub const CNC_UART: UartPins = UartPins {
    tx: Pin::new(Port::A, 2),
    rx: Pin::new(Port::A, 3),
    de: None,
};

/// Every output's wiring, in [`Output::ALL`] order (START first): for loops that drive them all
/// without a lookup per pin.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
pub const OUTPUTS: [Wiring; 8] = {
    let mut all = [output(Output::Start); 8];
    let mut i = 0;
    while i < all.len() {
        all[i] = output(Output::ALL[i]);
        i += 1;
    }
    all
};

/// Every input's wiring, in [`Input::ALL`] order.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
pub const INPUTS: [Wiring; 8] = {
    let mut all = [input(Input::TorchOn); 8];
    let mut i = 0;
    while i < all.len() {
        all[i] = input(Input::ALL[i]);
        i += 1;
    }
    all
};

/// Every unit set's outputs, each set's in [`Output::ALL`] order ([`UnitSet::outputs`]).
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
const UNIT_OUTPUTS: [[Wiring; 8]; UNIT_SETS] = {
    let mut all = [OUTPUTS; UNIT_SETS];
    let mut i = 0;
    while i < Output::ALL.len() * UNIT_SETS {
        let (set, output) = (i / Output::ALL.len(), i % Output::ALL.len());
        all[set][output] = UnitSet::ALL[set].output(Output::ALL[output]);
        i += 1;
    }
    all
};

/// How many output pins the board drives: every unit's eight.
pub const OUTPUT_PINS: usize = Output::ALL.len() * UNIT_SETS;

/// The pin level of every unit's every output in safe state ([`SAFE_OUTPUTS`]): every unit's
/// START first (the one that matters most, driven before any other), then each other output
/// in [`Output::ALL`] order, unit 0's before unit 1's.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
pub const SAFE_STATE: [(Pin, bool); OUTPUT_PINS] = {
    let mut all = [(OUTPUTS[0].pin, false); OUTPUT_PINS];
    let mut i = 0;
    while i < all.len() {
        let (output, set) = (Output::ALL[i / UNIT_SETS], UnitSet::ALL[i % UNIT_SETS]);
        let wiring = set.output(output);
        all[i] = (wiring.pin, wiring.level(SAFE_OUTPUTS.is_on(output)));
        i += 1;
    }
    all
};

/// The ports that carry an output, one bit per [`Port::index`].
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
pub const OUTPUT_PORTS: u32 = {
    let mut ports = 0;
    let mut i = 0;
    while i < SAFE_STATE.len() {
        ports |= 1 << SAFE_STATE[i].0.port.index();
        i += 1;
    }
    ports
};

/// Every input pin with an EXTI line of its own ([`UnitSet::wakes_on_edge`]): every unit's,
/// unit 0's first, in [`Input::ALL`] order. The boards arm these lines and no others.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
pub const EDGE_INPUTS: [Pin; EDGE_INPUT_COUNT] = {
    let mut all = [INPUTS[0].pin; EDGE_INPUT_COUNT];
    let (mut i, mut n) = (0, 0);
    while i < Input::ALL.len() * UNIT_SETS {
        let (set, input) = (
            UnitSet::ALL[i / Input::ALL.len()],
            Input::ALL[i % Input::ALL.len()],
        );
        if set.wakes_on_edge(input) {
            all[n] = set.input(input).pin;
            n += 1;
        }
        i += 1;
    }
    all
};

/// How many inputs have an EXTI line of their own.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
pub const EDGE_INPUT_COUNT: usize = {
    let (mut i, mut n) = (0, 0);
    while i < Input::ALL.len() * UNIT_SETS {
        let (set, input) = (
            UnitSet::ALL[i / Input::ALL.len()],
            Input::ALL[i % Input::ALL.len()],
        );
        if set.wakes_on_edge(input) {
            n += 1;
        }
        i += 1;
    }
    n
};

/// How many pins the table places: every unit's outputs, every input pin (a board-wide input
/// once), the LED, the test hooks and both UARTs' pins.
const PLACED_PINS: usize = OUTPUT_PINS + 8 + 5 * (UNIT_SETS - 1) + 1 + TEST_HOOKS.len() + 5;

/// Every pin the table places, each once if the table is right.
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
const PLACED: [Pin; PLACED_PINS] = {
    let mut all = [HEARTBEAT_LED.pin; PLACED_PINS];
    let mut n = 1;
    let mut i = 0;
    while i < SAFE_STATE.len() {
        all[n] = SAFE_STATE[i].0;
        (i, n) = (i + 1, n + 1);
    }
    let mut i = 0;
    while i < Input::ALL.len() * UNIT_SETS {
        let (set, input) = (
            UnitSet::ALL[i / Input::ALL.len()],
            Input::ALL[i % Input::ALL.len()],
        );
        if set.index() == 0 || !is_board_wide(input) {
            all[n] = set.input(input).pin;
            n += 1;
        }
        i += 1;
    }
    let mut i = 0;
    while i < TEST_HOOKS.len() {
        all[n] = TEST_HOOKS[i];
        (i, n) = (i + 1, n + 1);
    }
    let uart = [PS_UART.tx, PS_UART.rx, CNC_UART.tx, CNC_UART.rx];
    let mut i = 0;
    while i < uart.len() {
        all[n] = uart[i];
        (i, n) = (i + 1, n + 1);
    }
    if let Some(de) = PS_UART.de {
        all[n] = de;
        n += 1;
    }
    assert!(n == PLACED_PINS, "PLACED_PINS miscounts the table");
    all
};

/// Whether two of `pins` are the same pin (or, with `lines_only`, on the same EXTI line).
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
const fn any_shared(pins: &[Pin], lines_only: bool) -> bool {
    let mut i = 0;
    while i < pins.len() {
        let mut j = i + 1;
        while j < pins.len() {
            let same_line = pins[i].number == pins[j].number;
            if same_line && (lines_only || pins[i].port as u8 == pins[j].port as u8) {
                return true;
            }
            j += 1;
        }
        i += 1;
    }
    false
}

// The table at build time: no pin serves two signals (a board-wide input is one signal read
// by every unit), every pin number exists, and no two edge-waking inputs nor test hooks share
// an EXTI line (SYSCFG routes one port per line).
#[allow(
    clippy::indexing_slicing,
    reason = "evaluated at compile time: an index out of range fails the build"
)]
const _: () = {
    assert!(!any_shared(&PLACED, false), "two signals share a pin");
    let mut i = 0;
    while i < PLACED.len() {
        assert!(PLACED[i].number < 16, "a pin number past 15");
        i += 1;
    }
    let mut lines = [TEST_HOOKS[0]; EDGE_INPUT_COUNT + TEST_HOOKS.len()];
    let mut i = 0;
    while i < lines.len() {
        lines[i] = if i < EDGE_INPUT_COUNT {
            EDGE_INPUTS[i]
        } else {
            TEST_HOOKS[i - EDGE_INPUT_COUNT]
        };
        i += 1;
    }
    assert!(!any_shared(&lines, true), "two edges share an EXTI line");
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::InputConfig;

    /// Every pin the table places, a board-wide input once.
    fn every_pin() -> Vec<Pin> {
        let mut pins: Vec<Pin> = UnitSet::ALL
            .into_iter()
            .flat_map(|set| {
                Input::ALL
                    .into_iter()
                    .filter(move |&i| set.index() == 0 || !is_board_wide(i))
                    .map(move |i| set.input(i).pin)
            })
            .collect();
        for set in UnitSet::ALL {
            pins.extend(Output::ALL.into_iter().map(|o| set.output(o).pin));
        }
        pins.push(HEARTBEAT_LED.pin);
        pins.extend(TEST_HOOKS);
        pins.extend(PS_UART.pins().chain(CNC_UART.pins()));
        pins
    }

    #[test]
    fn no_two_signals_share_a_pin() {
        let mut pins = every_pin();
        let count = pins.len();
        pins.sort();
        pins.dedup();
        assert_eq!(pins.len(), count);
        assert!(every_pin().iter().all(|p| p.number < 16));
        let mut placed = PLACED.to_vec();
        placed.sort();
        assert_eq!(placed, pins, "the build-time check sees every pin");
    }

    #[test]
    fn no_two_inputs_share_an_exti_line() {
        // PA5 and PB5 share EXTI5: SYSCFG routes one port per line. The test hooks' pins are
        // edge-triggered inputs too.
        let mut lines: Vec<u8> = EDGE_INPUTS
            .into_iter()
            .chain(TEST_HOOKS)
            .map(|p| p.number)
            .collect();
        lines.sort();
        lines.dedup();
        assert_eq!(lines.len(), EDGE_INPUT_COUNT + TEST_HOOKS.len());
        // Every unit's TORCH_ON and MOTION wake the I/O task on an edge; only unit 1's
        // SYSTEM_ERROR and the board-wide inputs' second readings have no line of their own.
        for set in UnitSet::ALL {
            for i in [Input::TorchOn, Input::Motion, Input::NotReady] {
                assert!(EDGE_INPUTS.contains(&set.input(i).pin), "{set:?} {i}");
            }
        }
        assert_eq!(EDGE_INPUT_COUNT, 8 + 4);
    }

    #[test]
    fn unit_0s_set_is_the_one_unit_table_and_unit_1_has_its_own_signals() {
        let [first, second] = UnitSet::ALL;
        for i in Input::ALL {
            assert_eq!(first.input(i), input(i), "{i}");
            assert_eq!(second.input(i) == input(i), is_board_wide(i), "{i}");
        }
        for (set, outputs) in UnitSet::ALL.into_iter().zip(UNIT_OUTPUTS) {
            assert_eq!(*set.outputs(), outputs);
            for (o, wiring) in Output::ALL.into_iter().zip(outputs) {
                assert_eq!(wiring, set.output(o), "{set:?} {o}");
            }
        }
        for o in Output::ALL {
            assert_eq!(first.output(o), output(o), "{o}");
            assert_ne!(second.output(o).pin, output(o).pin, "{o}");
            assert_eq!(second.output(o).active, output(o).active, "{o}");
        }
        assert_eq!(UnitSet::new(1), Some(second));
        assert_eq!(UnitSet::new(UNIT_SETS), None);
        assert_eq!(second.index(), 1);
        assert_eq!(second.output(Output::Start).pin.to_string(), "PB1");
        assert_eq!(second.input(Input::TorchOn).pin.to_string(), "PC2");
    }

    #[test]
    fn the_safe_state_drives_every_units_every_output_off() {
        let mut driven = Vec::new();
        for set in UnitSet::ALL {
            for o in Output::ALL {
                let wiring = set.output(o);
                let (_, level) = SAFE_STATE
                    .into_iter()
                    .find(|&(pin, _)| pin == wiring.pin)
                    .unwrap_or_else(|| panic!("{set:?} {o} not in the safe state"));
                assert!(!wiring.is_on(level), "{set:?} {o} on in safe state");
                assert!(
                    OUTPUT_PORTS & 1 << wiring.pin.port.index() != 0,
                    "{o}'s port not clocked"
                );
                driven.push(wiring.pin);
            }
        }
        assert_eq!(driven.len(), SAFE_STATE.len());
        // Every unit's START first: the one that matters most, driven before any other.
        let starts = UnitSet::ALL.map(|set| (set.output(Output::Start).pin, false));
        assert_eq!(SAFE_STATE[..UNIT_SETS], starts);
    }

    #[test]
    fn the_arrays_follow_the_signal_order() {
        for (i, o) in Output::ALL.into_iter().enumerate() {
            assert_eq!(OUTPUTS[i], output(o));
        }
        for (i, input_signal) in Input::ALL.into_iter().enumerate() {
            assert_eq!(INPUTS[i], input(input_signal));
        }
        assert_eq!(OUTPUT_PORTS, 0b110, "outputs on GPIOB and GPIOC");
    }

    #[test]
    fn the_default_input_polarity_is_the_boards() {
        let config = InputConfig::default();
        for i in Input::ALL {
            assert_eq!(config.get(i).polarity, input(i).active, "{i}");
        }
    }

    #[test]
    fn pins_match_the_board_map() {
        assert_eq!(input(Input::TorchOn).pin.to_string(), "PA0");
        assert_eq!(input(Input::RampdownError).pin.to_string(), "PB10");
        assert_eq!(input(Input::SystemError).pin.to_string(), "PC5");
        assert_eq!(output(Output::Start).pin.to_string(), "PB0");
        assert_eq!(output(Output::Fault).pin.to_string(), "PC7");
        assert_eq!(output(Output::RemotePower).pin.to_string(), "PC8");
        assert_eq!(Port::C.register_block(), 0x4800_0800);
        assert_eq!(output(Output::Fault).pin.port_pin(), 2 * 16 + 7);
        assert_eq!(output(Output::ArcOk).pin.mask(), 1 << 9);
        assert!(!input(Input::TorchOn).level(true), "inputs are active low");
        assert!(input(Input::TorchOn).is_on(false));
        assert!(output(Output::Start).pin.is(Port::B, 0));
        assert!(!output(Output::Start).pin.is(Port::A, 0));
        assert_eq!(PS_UART.pins().count() + CNC_UART.pins().count(), 5);
        assert_eq!(USER_BUTTON.pin.to_string(), "PC13");
        assert!(USER_BUTTON.is_on(false), "pressed pulls the pin low");
    }
}
