//! The pins through the HAL, placed by the one pin table (`plasma_firmware::platform::pins`): the
//! outputs and the EXTI inputs the I/O task owns, and the heartbeat LED.

use embassy_stm32::Peri;
use embassy_stm32::gpio::{AnyPin, Level, Output, Pull, Speed};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use plasma_firmware::io::{self, Input, InputConfig, Outputs, PinLevels};
use plasma_firmware::platform::pins::{self, Pin, UNIT_SETS, UnitSet, Wiring};
use plasma_firmware::platform::safe_state::SAFE_OUTPUTS;

/// The HAL's handle on a pin of the table.
///
/// Sound because every pin handed out here is one the table assigns to exactly one signal
/// (`plasma_firmware::platform::pins` checks at build time that no two signals, nor a signal
/// and a UART, share a pin), each is taken once (by [`OutputPins::new`], [`InputPins::new`]:
/// a board-wide input once, in the first set, or [`led`]), and main.rs takes by name only the
/// UARTs' pins, which it checks against the same table at compile time.
pub fn table_pin(pin: Pin) -> Peri<'static, AnyPin> {
    // SAFETY: see above.
    unsafe { AnyPin::steal(pin.port_pin()) }
}

fn level(high: bool) -> Level {
    if high { Level::High } else { Level::Low }
}

/// Every unit set's eight outputs, each set's in [`io::Output::ALL`] order (START first).
pub struct OutputPins([[Output<'static>; 8]; UNIT_SETS]);

impl OutputPins {
    /// Takes the outputs over at their safe level, the level `drive_safe_state` gave them.
    pub fn new() -> Self {
        OutputPins(UnitSet::ALL.map(|set| {
            io::Output::ALL.map(|o| {
                let wiring = set.output(o);
                let safe = wiring.level(SAFE_OUTPUTS.is_on(o));
                Output::new(table_pin(wiring.pin), level(safe), Speed::Low)
            })
        }))
    }
}

impl plasma_tasks::board::OutputPins for OutputPins {
    fn drive(&mut self, set: UnitSet, outputs: Outputs) {
        let Some(pins) = self.0.get_mut(set.index()) else {
            return;
        };
        let all = pins.iter_mut().zip(io::Output::ALL).zip(set.outputs());
        for ((pin, o), wiring) in all {
            pin.set_level(level(wiring.level(outputs.get(o))));
        }
    }
}

/// Every unit set's eight inputs, each set's in [`Input::ALL`] order; `None` for a board-wide
/// input beyond the first set (the first set's pin serves every unit).
pub struct InputPins([[Option<embassy_stm32::gpio::Input<'static>>; 8]; UNIT_SETS]);

impl InputPins {
    /// Every input with the pull that reads inactive when open, its EXTI line armed for good
    /// (`plasma_tasks::edges`: embassy-stm32 0.6.0's `ExtiInput` re-arms per wait and loses
    /// an edge between a level read and the next wait), and the EXTI interrupts on at the
    /// highest priority: their handlers below only note the edge for the I/O task.
    pub fn new(config: &InputConfig) -> Self {
        let pins = UnitSet::ALL.map(|set| {
            Input::ALL.map(|i| {
                let own = set.index() == 0 || !pins::is_board_wide(i);
                own.then(|| input(config, set, i))
            })
        });
        plasma_tasks::edges::arm_inputs();
        for irq in EXTI_IRQS {
            irq.set_priority(Priority::P0);
            // SAFETY: the handlers below touch only the EXTI pending register and an atomic
            // latch; no priority-based critical section exists in this image.
            unsafe { irq.enable() };
        }
        InputPins(pins)
    }
}

impl plasma_tasks::board::InputPins for InputPins {
    fn levels(&self, set: UnitSet) -> PinLevels {
        let [first, ..] = &self.0;
        let own = self.0.get(set.index()).unwrap_or(first);
        Input::ALL.iter().zip(own).zip(first).fold(
            PinLevels::ALL_LOW,
            |levels, ((&input, pin), first_sets)| {
                let high = pin
                    .as_ref()
                    .or(first_sets.as_ref())
                    .is_some_and(|p| p.is_high());
                levels.with(input, high)
            },
        )
    }
}

/// The EXTI interrupts of the input lines: every line has one (0 to 4 each their own, 5-9 and
/// 10-15 shared), and the table decides which lines are armed (`pins::EDGE_INPUTS`).
const EXTI_IRQS: [interrupt::Interrupt; 7] = [
    interrupt::EXTI0,
    interrupt::EXTI1,
    interrupt::EXTI2,
    interrupt::EXTI3,
    interrupt::EXTI4,
    interrupt::EXTI9_5,
    interrupt::EXTI15_10,
];

#[interrupt]
unsafe fn EXTI0() {
    plasma_tasks::edges::on_interrupt();
}

#[interrupt]
unsafe fn EXTI1() {
    plasma_tasks::edges::on_interrupt();
}

#[interrupt]
unsafe fn EXTI2() {
    plasma_tasks::edges::on_interrupt();
}

#[interrupt]
unsafe fn EXTI3() {
    plasma_tasks::edges::on_interrupt();
}

#[interrupt]
unsafe fn EXTI4() {
    plasma_tasks::edges::on_interrupt();
}

#[interrupt]
unsafe fn EXTI9_5() {
    plasma_tasks::edges::on_interrupt();
}

#[interrupt]
unsafe fn EXTI15_10() {
    plasma_tasks::edges::on_interrupt();
}

/// Unit `set`'s `input` pin as a GPIO input with the pull that reads inactive on an open wire.
fn input(config: &InputConfig, set: UnitSet, input: Input) -> embassy_stm32::gpio::Input<'static> {
    let pull = match config.get(input).polarity.pull() {
        io::Pull::Up => Pull::Up,
        io::Pull::Down => Pull::Down,
    };
    embassy_stm32::gpio::Input::new(table_pin(set.input(input).pin), pull)
}

/// The heartbeat LED, off.
pub struct Led(Output<'static>);

/// Takes the heartbeat LED's pin.
pub fn led() -> Led {
    let wiring: Wiring = pins::HEARTBEAT_LED;
    Led(Output::new(
        table_pin(wiring.pin),
        level(wiring.level(false)),
        Speed::Low,
    ))
}

impl plasma_tasks::board::Led for Led {
    fn toggle(&mut self) {
        self.0.toggle();
    }
}
