//! The pins through the HAL, placed by the one pin table (`plasma_firmware::platform::pins`): the
//! outputs and the EXTI inputs the I/O task owns, and the heartbeat LED.

use embassy_stm32::Peri;
use embassy_stm32::gpio::{AnyPin, Level, Output, Pull, Speed};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use plasma_firmware::io::{self, Input, InputConfig, Outputs, PinLevels};
use plasma_firmware::platform::pins::{self, Pin, Wiring};
use plasma_firmware::platform::safe_state::SAFE_OUTPUTS;

/// The HAL's handle on a pin of the table.
///
/// Sound because every pin handed out here is one the table assigns to exactly one signal
/// (`plasma_firmware::platform::pins`' tests: no two signals, nor a signal and a UART, share a pin), each
/// is taken once (by [`OutputPins::new`], [`InputPins::new`] or [`led`]), and main.rs takes by name
/// only the UARTs' pins, which it checks against the same table at compile time.
pub fn table_pin(pin: Pin) -> Peri<'static, AnyPin> {
    // SAFETY: see above.
    unsafe { AnyPin::steal(pin.port_pin()) }
}

fn level(high: bool) -> Level {
    if high { Level::High } else { Level::Low }
}

/// The eight outputs, in [`io::Output::ALL`] order (START first).
pub struct OutputPins([Output<'static>; 8]);

impl OutputPins {
    /// Takes the outputs over at their safe level, the level `drive_safe_state` gave them.
    pub fn new() -> Self {
        OutputPins(io::Output::ALL.map(|o| {
            let wiring = pins::output(o);
            let safe = wiring.level(SAFE_OUTPUTS.is_on(o));
            Output::new(table_pin(wiring.pin), level(safe), Speed::Low)
        }))
    }
}

impl plasma_tasks::board::OutputPins for OutputPins {
    fn drive(&mut self, outputs: Outputs) {
        let all = self.0.iter_mut().zip(io::Output::ALL).zip(pins::OUTPUTS);
        for ((pin, o), wiring) in all {
            pin.set_level(level(wiring.level(outputs.get(o))));
        }
    }
}

/// The eight inputs, in [`Input::ALL`] order, each on its own EXTI line.
pub struct InputPins([embassy_stm32::gpio::Input<'static>; 8]);

impl InputPins {
    /// Every input with the pull that reads inactive when open, its EXTI line armed for good
    /// (`plasma_tasks::edges`: embassy-stm32 0.6.0's `ExtiInput` re-arms per wait and loses
    /// an edge between a level read and the next wait), and the EXTI interrupts on at the
    /// highest priority: their handlers below only note the edge for the I/O task.
    pub fn new(config: &InputConfig) -> Self {
        let pins = Input::ALL.map(|i| input(config, i));
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
    fn levels(&self) -> PinLevels {
        Input::ALL
            .iter()
            .zip(&self.0)
            .fold(PinLevels::ALL_LOW, |levels, (&input, pin)| {
                levels.with(input, pin.is_high())
            })
    }
}

/// The EXTI interrupts of the input lines (0, 1, 4, 5-9, 10-15); lines 2 and 3 have none.
const EXTI_IRQS: [interrupt::Interrupt; 5] = [
    interrupt::EXTI0,
    interrupt::EXTI1,
    interrupt::EXTI4,
    interrupt::EXTI9_5,
    interrupt::EXTI15_10,
];

// Every input's line must raise one of the interrupts handled here.
const _: () = {
    let mut i = 0;
    while i < Input::ALL.len() {
        let line = pins::input(Input::ALL[i]).pin.number;
        assert!(
            line != 2 && line != 3,
            "an input's EXTI line has no handler in pins.rs"
        );
        i += 1;
    }
};

#[interrupt]
unsafe fn EXTI0() {
    plasma_tasks::edges::on_interrupt();
}

#[interrupt]
unsafe fn EXTI1() {
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

/// `input`'s pin as a GPIO input with the pull that reads inactive on an open wire.
fn input(config: &InputConfig, input: Input) -> embassy_stm32::gpio::Input<'static> {
    let pull = match config.get(input).polarity.pull() {
        io::Pull::Up => Pull::Up,
        io::Pull::Down => Pull::Down,
    };
    embassy_stm32::gpio::Input::new(table_pin(pins::input(input).pin), pull)
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
