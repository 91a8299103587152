//! From pin levels to the logical input levels [`Interlocks`](super::Interlocks) takes:
//! polarity and debounce per input, as settings ([`InputConfig`]).
//!
//! The board samples its input pins (on every EXTI edge and at the times
//! [`InputFilter::poll_at`] asks for) and passes the raw levels here; the filter corrects the
//! polarity, lets a new level through once it has held for the input's debounce time (one
//! [`Debouncer`] per input), and queues the resulting changes.
//!
//! One rule is not a setting: **TORCH_ON going inactive passes at once**. Debounce exists to
//! keep a bouncing contact or an ignition spike from *firing* the torch; delaying the CNC's
//! release of TORCH_ON would only keep START on longer than asked.

use heapless::Deque;

use super::debounce::Debouncer;
use super::input_config::{InputConfig, pick, pick_mut, slot};
use super::signals::{Input, Inputs};
use plasma_protocol::time::{Duration, Instant};

/// Raw pin levels of the eight inputs (`true` = pin high), as the board reads them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PinLevels(u8);

impl PinLevels {
    /// Every pin low.
    pub const ALL_LOW: PinLevels = PinLevels(0);
    /// Every pin high (the idle level of pulled-up, active-low inputs).
    pub const ALL_HIGH: PinLevels = PinLevels(0xff);

    /// These levels with `input`'s pin at `high`.
    pub const fn with(self, input: Input, high: bool) -> Self {
        let bit = 1 << slot(input);
        PinLevels(if high { self.0 | bit } else { self.0 & !bit })
    }

    /// Whether `input`'s pin is high.
    pub const fn is_high(self, input: Input) -> bool {
        self.0 & (1 << slot(input)) != 0
    }
}

/// Room for one change of every input several times over.
const CHANGE_QUEUE: usize = 16;

/// Polarity correction and debounce for the eight inputs, sans-IO.
#[derive(Debug, Clone)]
pub(crate) struct InputFilter {
    config: InputConfig,
    /// One per input, in [`Input::ALL`] order, on the logical (polarity-corrected) level.
    channels: [Debouncer; 8],
    changes: Deque<(Input, bool), CHANGE_QUEUE>,
}

impl InputFilter {
    /// The filter at power-up: the pins' levels now are taken as they are, without debounce,
    /// so the interlocks see what is already active (a TORCH_ON held through reset).
    pub(crate) fn new(config: InputConfig, pins: PinLevels) -> Self {
        InputFilter {
            config,
            channels: Input::ALL.map(|input| {
                Debouncer::settled(config.get(input).polarity.is_active(pins.is_high(input)))
            }),
            changes: Deque::new(),
        }
    }

    /// The logical levels accepted so far.
    pub(crate) fn inputs(&self) -> Inputs {
        let mut inputs = Inputs::NONE;
        for input in Input::ALL {
            inputs.set(input, pick(&self.channels, input).stable());
        }
        inputs
    }

    /// New settings while running. An input whose setting is unchanged keeps its state (a
    /// level half-way through its debounce stays pending); an input whose setting changed
    /// takes its level under the new setting from `pins` at once, as at power-up, and a
    /// change of its level is queued. The caller decides what a re-taken TORCH_ON may do
    /// ([`DiscreteIo`](super::DiscreteIo) treats it like power-up).
    pub(crate) fn set_config(&mut self, config: InputConfig, pins: PinLevels) {
        for input in Input::ALL {
            let setting = config.get(input);
            if setting == self.config.get(input) {
                continue;
            }
            let active = setting.polarity.is_active(pins.is_high(input));
            let channel = pick_mut(&mut self.channels, input);
            let changed = channel.stable() != active;
            channel.accept(active);
            if changed {
                self.push(input, active);
            }
        }
        self.config = config;
    }

    /// The pins were read at `now`. Levels that need no debounce are accepted at once.
    pub(crate) fn on_pins(&mut self, now: Instant, pins: PinLevels) {
        for input in Input::ALL {
            let setting = self.config.get(input);
            let active = setting.polarity.is_active(pins.is_high(input));
            let channel = pick_mut(&mut self.channels, input);
            let at_once =
                setting.debounce == Duration::ZERO || (input == Input::TorchOn && !active);
            if active != channel.stable() && at_once {
                channel.accept(active);
                self.push(input, active);
            } else {
                // A new level starts its wait; back to the stable level is a bounce.
                channel.on_level(now, active);
            }
        }
        self.poll(now);
    }

    /// Let time pass: accept levels that have held for their debounce time.
    pub(crate) fn poll(&mut self, now: Instant) {
        for input in Input::ALL {
            let debounce = self.config.get(input).debounce;
            if let Some(level) = pick_mut(&mut self.channels, input).poll(now, debounce) {
                self.push(input, level);
            }
        }
    }

    /// When a pending level will be accepted, if one is pending.
    pub(crate) fn poll_at(&self) -> Option<Instant> {
        Input::ALL
            .iter()
            .filter_map(|&input| {
                pick(&self.channels, input).settles_at(self.config.get(input).debounce)
            })
            .min()
    }

    /// The next accepted change, oldest first: `(input, active)`.
    pub(crate) fn poll_change(&mut self) -> Option<(Input, bool)> {
        self.changes.pop_front()
    }

    fn push(&mut self, input: Input, active: bool) {
        // Undrained, the oldest change goes; the levels themselves are never lost (see
        // [`inputs`](Self::inputs)), and DiscreteIo drains after every call.
        if self.changes.is_full() {
            self.changes.pop_front();
        }
        // Cannot fail: room was made above.
        let _ = self.changes.push_back((input, active));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::Polarity;
    use proptest::prelude::*;

    fn us(v: u64) -> Instant {
        Instant::from_micros(v)
    }

    fn drain(filter: &mut InputFilter) -> Vec<(Input, bool)> {
        core::iter::from_fn(|| filter.poll_change()).collect()
    }

    #[test]
    fn a_press_counts_after_its_debounce_and_a_release_at_once() {
        let t = Instant::from_micros;
        // Active-low inputs with pull-ups: every pin high = every input inactive.
        let mut filter = InputFilter::new(InputConfig::default(), PinLevels::ALL_HIGH);
        let pressed = PinLevels::ALL_HIGH.with(Input::TorchOn, false);
        filter.on_pins(t(1_000), pressed);
        // TORCH_ON must hold for its debounce time (default 1 ms) before it counts.
        assert_eq!(filter.poll_at(), Some(t(2_000)));
        filter.poll(t(2_000));
        assert_eq!(filter.poll_change(), Some((Input::TorchOn, true)));
        // Released: at once.
        filter.on_pins(t(5_000), PinLevels::ALL_HIGH);
        assert_eq!(filter.poll_change(), Some((Input::TorchOn, false)));
    }

    #[test]
    fn power_up_levels_are_taken_without_debounce() {
        let pins = PinLevels::ALL_HIGH.with(Input::TorchOn, false);
        let filter = InputFilter::new(InputConfig::default(), pins);
        let inputs = filter.inputs();
        assert!(inputs.torch_on);
        assert!(!inputs.motion);
        assert_eq!(filter.poll_at(), None);
    }

    #[test]
    fn active_high_input_follows_the_pin() {
        let mut config = InputConfig::default();
        config.set_polarity(Input::Hold, Polarity::ActiveHigh);
        config.set_debounce(Input::Hold, Duration::ZERO);
        let idle = PinLevels::ALL_HIGH.with(Input::Hold, false);
        let mut filter = InputFilter::new(config, idle);
        assert_eq!(filter.inputs(), Inputs::NONE);
        filter.on_pins(us(10), idle.with(Input::Hold, true));
        assert_eq!(drain(&mut filter), [(Input::Hold, true)]);
    }

    #[test]
    fn a_bounce_restarts_the_debounce() {
        let mut filter = InputFilter::new(InputConfig::default(), PinLevels::ALL_HIGH);
        let held = PinLevels::ALL_HIGH.with(Input::NotReady, false);
        filter.on_pins(us(1_000), held);
        filter.on_pins(us(3_000), PinLevels::ALL_HIGH); // bounced back
        filter.on_pins(us(4_000), held);
        filter.poll(us(8_999));
        assert!(drain(&mut filter).is_empty());
        assert_eq!(filter.poll_at(), Some(us(9_000)));
        filter.poll(us(9_000));
        assert_eq!(drain(&mut filter), [(Input::NotReady, true)]);
        assert!(filter.inputs().not_ready);
    }

    #[test]
    fn torch_on_release_is_never_delayed() {
        let mut config = InputConfig::default();
        config.set_debounce(Input::TorchOn, Duration::from_millis(20));
        let pressed = PinLevels::ALL_HIGH.with(Input::TorchOn, false);
        let mut filter = InputFilter::new(config, PinLevels::ALL_HIGH);
        filter.on_pins(us(0), pressed);
        filter.poll(us(20_000));
        assert_eq!(drain(&mut filter), [(Input::TorchOn, true)]);
        filter.on_pins(us(20_001), PinLevels::ALL_HIGH);
        assert_eq!(drain(&mut filter), [(Input::TorchOn, false)]);
        // A short press (a spike) never gets through.
        filter.on_pins(us(30_000), pressed);
        filter.on_pins(us(30_500), PinLevels::ALL_HIGH);
        filter.poll(us(60_000));
        assert!(drain(&mut filter).is_empty());
        assert!(!filter.inputs().torch_on);
    }

    proptest! {
        /// Whatever the samples and debounce times: the queued changes replay exactly the
        /// accepted levels, and `poll_at` names the exact instant the next level is accepted.
        #[test]
        fn changes_replay_the_levels(
            debounce_us in prop::collection::vec(0u64..3_000, 8),
            steps in prop::collection::vec((0u64..2_000, any::<u8>(), any::<bool>()), 0..80),
        ) {
            let mut config = InputConfig::default();
            for (input, &d) in Input::ALL.iter().zip(&debounce_us) {
                config.set_debounce(*input, Duration::from_micros(d));
            }
            let mut filter = InputFilter::new(config, PinLevels::ALL_HIGH);
            let mut replay = filter.inputs();
            let mut now = 0;
            for (step, bits, poll_only) in steps {
                now += step;
                if poll_only {
                    filter.poll(us(now));
                } else {
                    filter.on_pins(us(now), PinLevels(bits));
                }
                while let Some((input, active)) = filter.poll_change() {
                    prop_assert_ne!(replay.get(input), active, "a change must change the level");
                    replay.set(input, active);
                }
                prop_assert_eq!(replay, filter.inputs());
                // poll_at is exact: nothing is due before it, something is due at it.
                if let Some(at) = filter.poll_at() {
                    prop_assert!(at > us(now));
                    let mut early = filter.clone();
                    early.poll(Instant::from_micros(at.as_micros() - 1));
                    prop_assert_eq!(early.poll_change(), None);
                    let mut due = filter.clone();
                    due.poll(at);
                    prop_assert!(due.poll_change().is_some());
                }
            }
        }
    }
}
