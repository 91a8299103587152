//! The pins through the HAL: the outputs and the EXTI inputs the I/O task owns. Where each
//! output is, and the register-level safe state, are shared with the emulated board
//! (`../tasks/pin_map.rs`).

use embassy_stm32::exti::ExtiInput;
use embassy_stm32::gpio::{Level, Output, Pull};
use embassy_stm32::mode::Async;
use plasma_firmware::inputs::{self, InputConfig, PinLevels};
use plasma_firmware::io::{Input, Outputs};

/// The seven outputs, owned by the I/O task.
pub struct OutputPins {
    /// PB0.
    pub start: Output<'static>,
    /// PC1.
    pub hold: Output<'static>,
    /// PC0.
    pub pierce_complete: Output<'static>,
    /// PB8.
    pub corner_current: Output<'static>,
    /// PB9.
    pub arc_ok: Output<'static>,
    /// PB6.
    pub ready: Output<'static>,
    /// PC7.
    pub fault: Output<'static>,
}

fn level(on: bool) -> Level {
    if on { Level::High } else { Level::Low }
}

impl OutputPins {
    /// Sets every pin to `outputs` (logical = pin level: all active high). START first: it
    /// is the one whose latency matters.
    pub fn drive(&mut self, outputs: Outputs) {
        self.start.set_level(level(outputs.start));
        self.hold.set_level(level(outputs.hold));
        self.pierce_complete
            .set_level(level(outputs.pierce_complete));
        self.corner_current.set_level(level(outputs.corner_current));
        self.arc_ok.set_level(level(outputs.arc_ok));
        self.ready.set_level(level(outputs.ready));
        self.fault.set_level(level(outputs.fault));
    }
}

/// The seven inputs, in [`Input::ALL`] order, each on its own EXTI line.
pub struct InputPins(pub [ExtiInput<'static, Async>; 7]);

impl InputPins {
    /// Reads every pin now.
    pub fn levels(&self) -> PinLevels {
        Input::ALL
            .iter()
            .zip(&self.0)
            .fold(PinLevels::ALL_LOW, |levels, (&input, pin)| {
                levels.with(input, pin.is_high())
            })
    }

    /// Completes on the next edge of any input (a bounce included: the caller reads levels).
    pub async fn any_edge(&mut self) {
        let edges = self.0.each_mut().map(|pin| pin.wait_for_any_edge());
        embassy_futures::select::select_array(edges).await;
    }
}

/// The HAL pull for an input: the one that reads inactive on an open wire.
pub fn pull(config: &InputConfig, input: Input) -> Pull {
    match config.get(input).polarity.pull() {
        inputs::Pull::Up => Pull::Up,
        inputs::Pull::Down => Pull::Down,
    }
}
