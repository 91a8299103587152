//! The pins through the HAL, placed by the one pin table (`plasma_firmware::pins`): the
//! outputs and the EXTI inputs the I/O task owns, and the heartbeat LED.

use embassy_stm32::Peri;
use embassy_stm32::exti::ExtiInput;
use embassy_stm32::gpio::{AnyPin, Level, Output, Pull, Speed};
use embassy_stm32::mode::Async;
use plasma_firmware::inputs::{self, InputConfig, PinLevels};
use plasma_firmware::io::{self, Input, Outputs};
use plasma_firmware::pins::{self, Pin, Wiring};
use plasma_firmware::safe_state::SAFE_OUTPUTS;

/// The HAL's handle on a pin of the table.
///
/// Sound because every pin handed out here is one the table assigns to exactly one signal
/// (`plasma_firmware::pins`' tests: no two signals, nor a signal and a UART, share a pin), each
/// is taken once (by [`OutputPins::new`], [`input`] or [`led`]), and main.rs takes by name
/// only the UARTs' pins, which it checks against the same table at compile time.
pub fn table_pin(pin: Pin) -> Peri<'static, AnyPin> {
    // SAFETY: see above.
    unsafe { AnyPin::steal(pin.port_pin()) }
}

fn level(high: bool) -> Level {
    if high { Level::High } else { Level::Low }
}

/// The seven outputs, in [`io::Output::ALL`] order (START first).
pub struct OutputPins([Output<'static>; 7]);

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

/// The seven inputs, in [`Input::ALL`] order, each on its own EXTI line.
pub struct InputPins(pub [ExtiInput<'static, Async>; 7]);

impl plasma_tasks::board::InputPins for InputPins {
    fn levels(&self) -> PinLevels {
        Input::ALL
            .iter()
            .zip(&self.0)
            .fold(PinLevels::ALL_LOW, |levels, (&input, pin)| {
                levels.with(input, pin.is_high())
            })
    }

    async fn any_edge(&mut self) {
        let edges = self.0.each_mut().map(|pin| pin.wait_for_any_edge());
        embassy_futures::select::select_array(edges).await;
    }
}

/// `input`'s pin as a GPIO input with the pull that reads inactive on an open wire, ready to
/// become an `ExtiInput` (main.rs pairs it with its typed EXTI channel).
pub fn input(config: &InputConfig, input: Input) -> embassy_stm32::gpio::Input<'static> {
    let pull = match config.get(input).polarity.pull() {
        inputs::Pull::Up => Pull::Up,
        inputs::Pull::Down => Pull::Down,
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
