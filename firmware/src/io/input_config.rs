//! The CNC's wiring of the inputs, as settings: which pin level is active, and how long a new
//! level must hold before it counts. [`InputFilter`](super::input_filter::InputFilter) applies them.

use super::signals::Input;
use plasma_protocol::time::Duration;

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
    debounce_ms: [u8; 8],
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
        // NOT_READY, RAMPDOWN_ERROR, SYSTEM_ERROR.
        debounce_ms: [1, 5, 5, 5, 0, 5, 5, 5],
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
    pub(crate) const fn to_stored(self) -> (u8, [u8; 8]) {
        (self.active_high, self.debounce_ms)
    }

    /// From the stored form; `None` if a bit names no input or a time is above
    /// [`MAX_DEBOUNCE`].
    pub(crate) fn from_stored(active_high: u8, debounce_ms: [u8; 8]) -> Option<Self> {
        let max = MAX_DEBOUNCE.as_millis();
        // Eight inputs: every bit of `active_high` names one.
        debounce_ms
            .iter()
            .all(|&ms| u64::from(ms) <= max)
            .then_some(InputConfig {
                active_high,
                debounce_ms,
            })
    }
}

/// Bit (and position) of an input, in [`Input::ALL`] order.
pub(super) const fn slot(input: Input) -> usize {
    match input {
        Input::TorchOn => 0,
        Input::Hold => 1,
        Input::PierceComplete => 2,
        Input::CornerCurrent => 3,
        Input::Motion => 4,
        Input::NotReady => 5,
        Input::RampdownError => 6,
        Input::SystemError => 7,
    }
}

/// `input`'s element of a per-input array (in [`Input::ALL`] order), without indexing.
pub(super) const fn pick<T: Copy>(items: &[T; 8], input: Input) -> T {
    let [a, b, c, d, e, f, g, h] = items;
    *match input {
        Input::TorchOn => a,
        Input::Hold => b,
        Input::PierceComplete => c,
        Input::CornerCurrent => d,
        Input::Motion => e,
        Input::NotReady => f,
        Input::RampdownError => g,
        Input::SystemError => h,
    }
}

/// `input`'s element of a per-input array, to change it.
pub(super) fn pick_mut<T>(items: &mut [T; 8], input: Input) -> &mut T {
    let [a, b, c, d, e, f, g, h] = items;
    match input {
        Input::TorchOn => a,
        Input::Hold => b,
        Input::PierceComplete => c,
        Input::CornerCurrent => d,
        Input::Motion => e,
        Input::NotReady => f,
        Input::RampdownError => g,
        Input::SystemError => h,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
