//! From pin levels to the logical input levels [`io::Interlocks`](crate::io::Interlocks) takes:
//! polarity and debounce per input, as settings.
//!
//! The board samples its input pins (on every EXTI edge and at the times
//! [`InputFilter::poll_at`] asks for) and passes the raw levels here; the filter corrects the
//! polarity, lets a new level through once it has held for the input's debounce time, and
//! queues the resulting changes.
//!
//! One rule is not a setting: **TORCH_ON going inactive passes at once**. Debounce exists to
//! keep a bouncing contact or an ignition spike from *firing* the torch; delaying the CNC's
//! release of TORCH_ON would only keep START on longer than asked.
//!
//! ```
//! use plasma_firmware::inputs::{InputConfig, InputFilter, PinLevels};
//! use plasma_firmware::io::Input;
//! use plasma_protocol::time::Instant;
//!
//! let t = Instant::from_micros;
//! // Active-low inputs with pull-ups: every pin high = every input inactive.
//! let mut filter = InputFilter::new(InputConfig::default(), t(0), PinLevels::ALL_HIGH);
//! let pressed = PinLevels::ALL_HIGH.with(Input::TorchOn, false);
//! filter.on_pins(t(1_000), pressed);
//! // TORCH_ON must hold for its debounce time (default 1 ms) before it counts.
//! assert_eq!(filter.poll_at(), Some(t(2_000)));
//! filter.poll(t(2_000));
//! assert_eq!(filter.poll_change(), Some((Input::TorchOn, true)));
//! // Released: at once.
//! filter.on_pins(t(5_000), PinLevels::ALL_HIGH);
//! assert_eq!(filter.poll_change(), Some((Input::TorchOn, false)));
//! ```

use heapless::Deque;

use crate::io::{Input, Inputs};
use plasma_protocol::time::{Duration, Instant};

/// Which pin level means "active".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Polarity {
    /// Pin low = active (the reference board's opto-coupler inputs, HPR open-collector outputs).
    ActiveLow,
    /// Pin high = active (a sourcing 24 V signal through a non-inverting level shifter).
    ActiveHigh,
}

/// The pin's internal pull resistor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pull {
    /// Pull-up.
    Up,
    /// Pull-down.
    Down,
}

impl Polarity {
    /// Whether a pin at `high` means the input is active.
    pub const fn is_active(self, high: bool) -> bool {
        match self {
            Polarity::ActiveLow => !high,
            Polarity::ActiveHigh => high,
        }
    }

    /// The pull that makes an open (broken or unplugged) input read *inactive*.
    pub const fn pull(self) -> Pull {
        match self {
            Polarity::ActiveLow => Pull::Up,
            Polarity::ActiveHigh => Pull::Down,
        }
    }
}

/// Settings of one input pin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InputSetting {
    /// Which level is active.
    pub polarity: Polarity,
    /// How long a new level must hold before it counts (zero: at once).
    pub debounce: Duration,
}

/// Longest debounce accepted; longer values are clamped to it (a slow filter on TORCH_ON
/// would delay the torch noticeably, on the others it would hide short signals).
pub const MAX_DEBOUNCE: Duration = Duration::from_millis(100);

/// Settings of every input, in whole milliseconds (kept as the settings record stores them:
/// the I/O task receives a copy with every settings change).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InputConfig {
    /// One bit per input ([`slot`]): active high.
    active_high: u8,
    /// Debounce per input, ms, in [`Input::ALL`] order.
    debounce_ms: [u8; 7],
}

impl Default for InputConfig {
    fn default() -> Self {
        InputConfig::REFERENCE
    }
}

impl InputConfig {
    /// The reference board: every input active low. TORCH_ON 1 ms (against contact bounce
    /// and ignition spikes, small beside a PhotoMOS's 0.2-2 ms turn-on); MOTION none, because
    /// the interlocks debounce it themselves for ARC_OK; the other signals 5 ms.
    pub const REFERENCE: InputConfig = InputConfig {
        active_high: 0,
        // Input::ALL order: TORCH_ON, HOLD, PIERCE_COMPLETE, CORNER_CURRENT, MOTION,
        // NOT_READY, RAMPDOWN_ERROR.
        debounce_ms: [1, 5, 5, 5, 0, 5, 5],
    };

    /// The settings of one input.
    pub const fn get(&self, input: Input) -> InputSetting {
        InputSetting {
            polarity: if self.active_high & (1 << slot(input)) != 0 {
                Polarity::ActiveHigh
            } else {
                Polarity::ActiveLow
            },
            debounce: Duration::from_millis(pick(&self.debounce_ms, input) as u64),
        }
    }

    /// Change the polarity of one input.
    pub fn set_polarity(&mut self, input: Input, polarity: Polarity) {
        let bit = 1 << slot(input);
        match polarity {
            Polarity::ActiveHigh => self.active_high |= bit,
            Polarity::ActiveLow => self.active_high &= !bit,
        }
    }

    /// Change the debounce time of one input (whole milliseconds, clamped to
    /// [`MAX_DEBOUNCE`]).
    pub fn set_debounce(&mut self, input: Input, debounce: Duration) {
        let ms = debounce.min(MAX_DEBOUNCE).as_millis();
        *pick_mut(&mut self.debounce_ms, input) = u8::try_from(ms).unwrap_or(u8::MAX);
    }

    /// The stored form: the active-high bits (one per input, [`Input::ALL`] order) and the
    /// debounce times in ms.
    pub const fn to_stored(&self) -> (u8, [u8; 7]) {
        (self.active_high, self.debounce_ms)
    }

    /// From the stored form; `None` if a bit names no input or a time is above
    /// [`MAX_DEBOUNCE`].
    pub fn from_stored(active_high: u8, debounce_ms: [u8; 7]) -> Option<Self> {
        let max = MAX_DEBOUNCE.as_millis();
        (active_high < 1 << 7 && debounce_ms.iter().all(|&ms| u64::from(ms) <= max)).then_some(
            InputConfig {
                active_high,
                debounce_ms,
            },
        )
    }
}

/// Bit (and position) of an input, in [`Input::ALL`] order.
const fn slot(input: Input) -> usize {
    match input {
        Input::TorchOn => 0,
        Input::Hold => 1,
        Input::PierceComplete => 2,
        Input::CornerCurrent => 3,
        Input::Motion => 4,
        Input::NotReady => 5,
        Input::RampdownError => 6,
    }
}

/// `input`'s element of a per-input array (in [`Input::ALL`] order), without indexing.
const fn pick<T: Copy>(items: &[T; 7], input: Input) -> T {
    let [a, b, c, d, e, f, g] = items;
    *match input {
        Input::TorchOn => a,
        Input::Hold => b,
        Input::PierceComplete => c,
        Input::CornerCurrent => d,
        Input::Motion => e,
        Input::NotReady => f,
        Input::RampdownError => g,
    }
}

/// `input`'s element of a per-input array, to change it.
fn pick_mut<T>(items: &mut [T; 7], input: Input) -> &mut T {
    let [a, b, c, d, e, f, g] = items;
    match input {
        Input::TorchOn => a,
        Input::Hold => b,
        Input::PierceComplete => c,
        Input::CornerCurrent => d,
        Input::Motion => e,
        Input::NotReady => f,
        Input::RampdownError => g,
    }
}

/// Raw pin levels of the seven inputs (`true` = pin high), as the board reads them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PinLevels(u8);

impl PinLevels {
    /// Every pin low.
    pub const ALL_LOW: PinLevels = PinLevels(0);
    /// Every pin high (the idle level of pulled-up, active-low inputs).
    pub const ALL_HIGH: PinLevels = PinLevels(0x7f);

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

/// One input's filter state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Channel {
    accepted: bool,
    /// A different level seen, and since when.
    pending: Option<(bool, Instant)>,
}

/// Room for one change of every input several times over.
const CHANGE_QUEUE: usize = 16;

/// Polarity correction and debounce for the seven inputs, sans-IO.
#[derive(Debug, Clone)]
pub struct InputFilter {
    config: InputConfig,
    channels: [Channel; 7],
    changes: Deque<(Input, bool), CHANGE_QUEUE>,
    lost_changes: u32,
}

impl InputFilter {
    /// The filter at power-up: the pins' levels now are taken as they are, without debounce,
    /// so the interlocks see what is already active (a TORCH_ON held through reset).
    pub fn new(config: InputConfig, now: Instant, pins: PinLevels) -> Self {
        let _ = now;
        let mut channels = [Channel {
            accepted: false,
            pending: None,
        }; 7];
        for input in Input::ALL {
            pick_mut(&mut channels, input).accepted =
                config.get(input).polarity.is_active(pins.is_high(input));
        }
        InputFilter {
            config,
            channels,
            changes: Deque::new(),
            lost_changes: 0,
        }
    }

    /// The logical levels accepted so far.
    pub fn inputs(&self) -> Inputs {
        let mut inputs = Inputs::NONE;
        for input in Input::ALL {
            inputs.set(input, pick(&self.channels, input).accepted);
        }
        inputs
    }

    /// The settings in use.
    pub fn config(&self) -> &InputConfig {
        &self.config
    }

    /// New settings while running. An input whose setting is unchanged keeps its state (a
    /// level half-way through its debounce stays pending); an input whose setting changed
    /// takes its level under the new setting from `pins` at once, as at power-up, and a
    /// change of its level is queued. The caller decides what a re-taken TORCH_ON may do
    /// ([`DiscreteIo`](crate::discrete::DiscreteIo) treats it like power-up).
    pub fn set_config(&mut self, config: InputConfig, pins: PinLevels) {
        for input in Input::ALL {
            let setting = config.get(input);
            if setting == self.config.get(input) {
                continue;
            }
            let active = setting.polarity.is_active(pins.is_high(input));
            let channel = pick_mut(&mut self.channels, input);
            channel.pending = None;
            if channel.accepted != active {
                channel.accepted = active;
                self.push(input, active);
            }
        }
        self.config = config;
    }

    /// The pins were read at `now`. Levels that need no debounce are accepted at once.
    pub fn on_pins(&mut self, now: Instant, pins: PinLevels) {
        for input in Input::ALL {
            let setting = self.config.get(input);
            let active = setting.polarity.is_active(pins.is_high(input));
            let channel = pick_mut(&mut self.channels, input);
            if active == channel.accepted {
                // Back to the accepted level before the debounce time: a bounce.
                channel.pending = None;
            } else if setting.debounce == Duration::ZERO || (input == Input::TorchOn && !active) {
                channel.accepted = active;
                channel.pending = None;
                self.push(input, active);
            } else if channel.pending.is_none_or(|(level, _)| level != active) {
                channel.pending = Some((active, now));
            }
        }
        self.poll(now);
    }

    /// Let time pass: accept levels that have held for their debounce time.
    pub fn poll(&mut self, now: Instant) {
        for input in Input::ALL {
            let debounce = self.config.get(input).debounce;
            let channel = pick_mut(&mut self.channels, input);
            if let Some((level, since)) = channel.pending
                && now >= since + debounce
            {
                channel.accepted = level;
                channel.pending = None;
                self.push(input, level);
            }
        }
    }

    /// When a pending level will be accepted, if one is pending.
    pub fn poll_at(&self) -> Option<Instant> {
        Input::ALL
            .iter()
            .filter_map(|&input| {
                let (_, since) = pick(&self.channels, input).pending?;
                Some(since + self.config.get(input).debounce)
            })
            .min()
    }

    /// The next accepted change, oldest first: `(input, active)`.
    pub fn poll_change(&mut self) -> Option<(Input, bool)> {
        self.changes.pop_front()
    }

    /// Changes dropped because nobody drained them (the levels themselves are never lost:
    /// see [`inputs`](Self::inputs)).
    pub fn lost_changes(&self) -> u32 {
        self.lost_changes
    }

    fn push(&mut self, input: Input, active: bool) {
        if self.changes.is_full() {
            self.changes.pop_front();
            self.lost_changes = self.lost_changes.saturating_add(1);
        }
        // Cannot fail: room was made above.
        let _ = self.changes.push_back((input, active));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn us(v: u64) -> Instant {
        Instant::from_micros(v)
    }

    fn drain(filter: &mut InputFilter) -> Vec<(Input, bool)> {
        core::iter::from_fn(|| filter.poll_change()).collect()
    }

    #[test]
    fn polarity_maps_levels_and_pulls() {
        assert!(Polarity::ActiveLow.is_active(false));
        assert!(!Polarity::ActiveLow.is_active(true));
        assert!(Polarity::ActiveHigh.is_active(true));
        assert!(!Polarity::ActiveHigh.is_active(false));
        // An open input must read inactive: the pull goes to the inactive level.
        for polarity in [Polarity::ActiveLow, Polarity::ActiveHigh] {
            let open_reads_high = polarity.pull() == Pull::Up;
            assert!(!polarity.is_active(open_reads_high), "{polarity:?}");
        }
    }

    #[test]
    fn defaults_match_the_reference_board() {
        let config = InputConfig::default();
        for input in Input::ALL {
            assert_eq!(config.get(input).polarity, Polarity::ActiveLow, "{input}");
        }
        assert_eq!(
            config.get(Input::TorchOn).debounce,
            Duration::from_millis(1)
        );
        assert_eq!(config.get(Input::Motion).debounce, Duration::ZERO);
        assert_eq!(
            config.get(Input::NotReady).debounce,
            Duration::from_millis(5)
        );
    }

    #[test]
    fn debounce_is_clamped() {
        let mut config = InputConfig::default();
        config.set_debounce(Input::Hold, Duration::from_secs(10));
        assert_eq!(config.get(Input::Hold).debounce, MAX_DEBOUNCE);
    }

    #[test]
    fn power_up_levels_are_taken_without_debounce() {
        let pins = PinLevels::ALL_HIGH.with(Input::TorchOn, false);
        let filter = InputFilter::new(InputConfig::default(), us(0), pins);
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
        let mut filter = InputFilter::new(config, us(0), idle);
        assert_eq!(filter.inputs(), Inputs::NONE);
        filter.on_pins(us(10), idle.with(Input::Hold, true));
        assert_eq!(drain(&mut filter), [(Input::Hold, true)]);
    }

    #[test]
    fn a_bounce_restarts_the_debounce() {
        let mut filter = InputFilter::new(InputConfig::default(), us(0), PinLevels::ALL_HIGH);
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
        let mut filter = InputFilter::new(config, us(0), PinLevels::ALL_HIGH);
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
            debounce_us in prop::collection::vec(0u64..3_000, 7),
            steps in prop::collection::vec((0u64..2_000, any::<u8>(), any::<bool>()), 0..80),
        ) {
            let mut config = InputConfig::default();
            for (input, &d) in Input::ALL.iter().zip(&debounce_us) {
                config.set_debounce(*input, Duration::from_micros(d));
            }
            let mut filter = InputFilter::new(config, us(0), PinLevels::ALL_HIGH);
            let mut replay = filter.inputs();
            let mut now = 0;
            for (step, bits, poll_only) in steps {
                now += step;
                if poll_only {
                    filter.poll(us(now));
                } else {
                    filter.on_pins(us(now), PinLevels(bits & 0x7f));
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
