//! The discrete I/O as the board runs it: pin levels in, output levels out.
//!
//! [`DiscreteIo`] puts the input filter (polarity, debounce: [`InputConfig`](super::InputConfig)) in front of
//! [`Interlocks`], so the board's high-priority I/O task only samples pins, calls one method
//! and drives the outputs. It is sans-IO like its parts.
//!
//! ```
//! use plasma_firmware::io::{DiscreteIo, Input, IoConfig, PinLevels, SupplyState};
//! use plasma_protocol::time::Instant;
//!
//! let t = Instant::from_millis;
//! let mut io = DiscreteIo::new(IoConfig::default(), t(0), PinLevels::ALL_HIGH);
//! io.on_supply(t(1), SupplyState::HEALTHY);
//! // The CNC pulls TORCH_ON low; after its 1 ms debounce START comes on.
//! io.on_pins(t(100), PinLevels::ALL_HIGH.with(Input::TorchOn, false));
//! assert!(!io.outputs().start);
//! io.poll(io.poll_at().unwrap());
//! assert!(io.outputs().start);
//! // Released: START drops in the same call.
//! io.on_pins(t(200), PinLevels::ALL_HIGH);
//! assert!(!io.outputs().start);
//! ```

use super::config::IoConfig;
use super::input_filter::{InputFilter, PinLevels};
use super::interlocks::Interlocks;
use super::reason::{IoEvent, Transition};
use super::signals::{Input, Inputs, Outputs, SupplyState};
use plasma_protocol::time::Instant;

/// Input filter and interlocks.
#[derive(Debug, Clone)]
pub struct DiscreteIo {
    filter: InputFilter,
    interlocks: Interlocks,
}

impl DiscreteIo {
    /// Power-up with the pins as they read now (see
    /// [`Interlocks::new`]: a TORCH_ON already active is ignored until released).
    pub fn new(config: IoConfig, now: Instant, pins: PinLevels) -> Self {
        let filter = InputFilter::new(config.inputs, pins);
        let interlocks = Interlocks::new(config, now, filter.inputs());
        DiscreteIo { filter, interlocks }
    }

    /// New settings while running; returns whether anything changed.
    ///
    /// The interlocks' rules apply live ([`Interlocks::set_config`]: a stricter setting at
    /// once, a looser one from the next TORCH_ON). An input whose active level or debounce
    /// changed takes its level from `pins` at once, as at power-up; for
    /// TORCH_ON that is the power-up rule ([`Interlocks::rearm_torch_on`]): a START that is on
    /// drops, and a TORCH_ON that reads active under the new setting must be seen inactive
    /// before it fires the torch. So no change, at any moment of a press, produces a START.
    /// Output levels apply from the next [`table_outputs`](Self::table_outputs).
    pub fn reconfigure(&mut self, now: Instant, config: IoConfig, pins: PinLevels) -> bool {
        let old = *self.interlocks.config();
        if old == config {
            return false;
        }
        if old.inputs != config.inputs {
            self.filter.set_config(config.inputs, pins);
            let torch_on = |c: &IoConfig| c.inputs.get(Input::TorchOn);
            if torch_on(&old) != torch_on(&config) {
                self.interlocks
                    .rearm_torch_on(now, self.filter.inputs().torch_on);
            }
        }
        self.interlocks.set_config(now, config);
        self.forward(now);
        true
    }

    /// The input pins were read at `now`.
    pub fn on_pins(&mut self, now: Instant, pins: PinLevels) {
        self.filter.on_pins(now, pins);
        self.forward(now);
    }

    /// The link's view of the supply changed.
    pub fn on_supply(&mut self, now: Instant, supply: SupplyState) {
        self.interlocks.on_supply(now, supply);
    }

    /// Let time pass (debounce, gap between starts, transfer time-out, blackout end).
    pub fn poll(&mut self, now: Instant) {
        self.filter.poll(now);
        self.forward(now);
        self.interlocks.poll(now);
    }

    /// The next instant [`poll`](Self::poll) has something to do.
    pub fn poll_at(&self) -> Option<Instant> {
        match (self.filter.poll_at(), self.interlocks.poll_at()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// The logical output levels (`true` = on).
    pub fn outputs(&self) -> Outputs {
        self.interlocks.outputs()
    }

    /// The levels to hand a board that drives its pins from the pin table
    /// ([`pins::output`](crate::platform::pins::output)): [`outputs`](Self::outputs) with the inverted
    /// ones flipped ([`OutputConfig::for_table`](super::OutputConfig::for_table)).
    pub fn table_outputs(&self) -> Outputs {
        self.interlocks.config().outputs.for_table(self.outputs())
    }

    /// The logical input levels (after polarity and debounce).
    pub fn inputs(&self) -> Inputs {
        self.interlocks.inputs()
    }

    /// The next logged output change.
    pub fn poll_transition(&mut self) -> Option<Transition> {
        self.interlocks.poll_transition()
    }

    /// The next event.
    pub fn poll_event(&mut self) -> Option<IoEvent> {
        self.interlocks.poll_event()
    }

    /// The interlocks, for status queries.
    pub fn interlocks(&self) -> &Interlocks {
        &self.interlocks
    }

    /// The settings in use.
    pub fn config(&self) -> &IoConfig {
        self.interlocks.config()
    }

    fn forward(&mut self, now: Instant) {
        while let Some((input, active)) = self.filter.poll_change() {
            self.interlocks.on_input(now, input, active);
        }
    }
}

#[cfg(test)]
mod tests;
