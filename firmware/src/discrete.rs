//! The discrete I/O as the board runs it: pin levels in, output levels out.
//!
//! [`DiscreteIo`] puts the [`InputFilter`] (polarity, debounce) in front of
//! [`Interlocks`], so the board's high-priority I/O task only samples pins, calls one method
//! and drives the outputs. It is sans-IO like its parts.
//!
//! ```
//! use plasma_firmware::discrete::DiscreteIo;
//! use plasma_firmware::inputs::{InputConfig, PinLevels};
//! use plasma_firmware::io::{Input, IoConfig, SupplyState};
//! use plasma_protocol::time::Instant;
//!
//! let t = Instant::from_millis;
//! let mut io = DiscreteIo::new(IoConfig::default(), InputConfig::default(), t(0), PinLevels::ALL_HIGH);
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

use crate::inputs::{InputConfig, InputFilter, PinLevels};
use crate::io::{Inputs, Interlocks, IoConfig, IoEvent, Outputs, SupplyState, Transition};
use plasma_protocol::time::Instant;

/// Input filter and interlocks.
#[derive(Debug, Clone)]
pub struct DiscreteIo {
    filter: InputFilter,
    interlocks: Interlocks,
}

impl DiscreteIo {
    /// Power-up with the pins as they read now (see [`InputFilter::new`] and
    /// [`Interlocks::new`]: a TORCH_ON already active is ignored until released).
    pub fn new(io: IoConfig, inputs: InputConfig, now: Instant, pins: PinLevels) -> Self {
        let filter = InputFilter::new(inputs, now, pins);
        let interlocks = Interlocks::new(io, now, filter.inputs());
        DiscreteIo { filter, interlocks }
    }

    /// New settings; returns whether anything changed.
    ///
    /// New interlock settings alone apply live ([`Interlocks::set_config`]: a stricter setting
    /// at once, a looser one from the next TORCH_ON). New input settings (polarity, debounce)
    /// change what the pins *mean*, so the logic starts over as at power-up with the pins as
    /// they read now: START goes off, and a TORCH_ON that reads active under the new settings
    /// must be released before it fires the torch. The supply state is kept.
    pub fn reconfigure(
        &mut self,
        now: Instant,
        io: IoConfig,
        inputs: InputConfig,
        pins: PinLevels,
    ) -> bool {
        if *self.filter.config() != inputs {
            let supply = self.interlocks.supply();
            *self = DiscreteIo::new(io, inputs, now, pins);
            self.interlocks.on_supply(now, supply);
            return true;
        }
        if *self.interlocks.config() != io {
            self.interlocks.set_config(now, io);
            return true;
        }
        false
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

    /// The output levels to drive.
    pub fn outputs(&self) -> Outputs {
        self.interlocks.outputs()
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
    pub fn config(&self) -> (IoConfig, InputConfig) {
        (*self.interlocks.config(), *self.filter.config())
    }

    fn forward(&mut self, now: Instant) {
        while let Some((input, active)) = self.filter.poll_change() {
            self.interlocks.on_input(now, input, active);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inputs::Polarity;
    use crate::io::{Input, Interlock, Output, Reason};
    use plasma_protocol::time::Duration;

    fn ms(v: u64) -> Instant {
        Instant::from_millis(v)
    }

    const TORCH: PinLevels = PinLevels::ALL_HIGH.with(Input::TorchOn, false);

    fn healthy() -> DiscreteIo {
        let mut io = DiscreteIo::new(
            IoConfig::default(),
            InputConfig::default(),
            ms(0),
            PinLevels::ALL_HIGH,
        );
        io.on_supply(ms(0), SupplyState::HEALTHY);
        io
    }

    #[test]
    fn start_follows_the_debounced_pin_and_drops_at_once() {
        let mut io = healthy();
        io.on_pins(ms(100), TORCH);
        assert!(!io.outputs().start);
        assert_eq!(io.poll_at(), Some(ms(101)));
        io.poll(ms(101));
        assert!(io.outputs().start);
        let last = core::iter::from_fn(|| io.poll_transition()).last().unwrap();
        assert_eq!((last.output, last.reason), (Output::Start, Reason::TorchOn));
        io.on_pins(ms(150), PinLevels::ALL_HIGH);
        assert!(!io.outputs().start);
    }

    #[test]
    fn torch_on_held_at_power_up_does_not_fire() {
        let mut io = DiscreteIo::new(IoConfig::default(), InputConfig::default(), ms(0), TORCH);
        io.on_supply(ms(1), SupplyState::HEALTHY);
        io.poll(ms(500));
        assert!(!io.outputs().start);
        assert_eq!(
            io.interlocks().start_locked_by(),
            Some(Interlock::TorchOnAtPowerUp)
        );
    }

    #[test]
    fn reconfigure_drops_start_and_needs_a_new_torch_on() {
        let mut io = healthy();
        io.on_pins(ms(100), TORCH);
        io.poll(ms(101));
        assert!(io.outputs().start);

        let mut inputs = InputConfig::default();
        inputs.set_debounce(Input::TorchOn, Duration::from_millis(3));
        assert!(io.reconfigure(ms(200), IoConfig::default(), inputs, TORCH));
        assert!(!io.outputs().start);
        // The supply state survived: READY is back on at once.
        assert!(io.outputs().ready);
        io.poll(ms(1_000));
        assert!(
            !io.outputs().start,
            "a held TORCH_ON must not fire after a change"
        );
        io.on_pins(ms(1_100), PinLevels::ALL_HIGH);
        io.on_pins(ms(1_200), TORCH);
        io.poll(ms(1_203));
        assert!(io.outputs().start);
        assert_eq!(
            io.config().1.get(Input::TorchOn).debounce,
            Duration::from_millis(3)
        );
    }

    #[test]
    fn interlock_settings_apply_live() {
        let discrete_only = IoConfig {
            link_required: false,
            ..IoConfig::default()
        };
        let mut io = DiscreteIo::new(
            discrete_only,
            InputConfig::default(),
            ms(0),
            PinLevels::ALL_HIGH,
        );
        io.on_pins(ms(100), TORCH);
        io.poll(ms(101));
        assert!(io.outputs().start, "no link needed");

        // Looser: START stays on.
        let longer_gap = IoConfig {
            start_gap: Duration::from_millis(200),
            ..discrete_only
        };
        assert!(io.reconfigure(ms(150), longer_gap, InputConfig::default(), TORCH));
        assert!(io.outputs().start);
        // Stricter: the link is required now and down, START drops in the same call.
        assert!(io.reconfigure(ms(160), IoConfig::default(), InputConfig::default(), TORCH));
        assert!(!io.outputs().start);
        assert_eq!(io.interlocks().start_locked_by(), Some(Interlock::LinkDown));
    }

    #[test]
    fn same_settings_change_nothing() {
        let mut io = healthy();
        io.on_pins(ms(100), TORCH);
        io.poll(ms(101));
        assert!(!io.reconfigure(ms(200), IoConfig::default(), InputConfig::default(), TORCH));
        assert!(io.outputs().start);
    }

    #[test]
    fn inverted_polarity_input_reaches_the_interlocks() {
        let mut inputs = InputConfig::default();
        inputs.set_polarity(Input::Hold, Polarity::ActiveHigh);
        let idle = PinLevels::ALL_HIGH.with(Input::Hold, false);
        let mut io = DiscreteIo::new(IoConfig::default(), inputs, ms(0), idle);
        assert!(!io.outputs().hold);
        io.on_pins(ms(10), PinLevels::ALL_HIGH);
        io.poll(ms(15));
        assert!(io.inputs().hold);
        assert!(io.outputs().hold);
    }
}
