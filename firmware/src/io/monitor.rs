//! An independent check of the START safety rules, for tests and simulations.
//!
//! Written from the rules, not from [`Interlocks`](super::Interlocks): it only sees sampled
//! levels (TORCH_ON, START, the blackout the link reports) and flags any sample that breaks
//! a rule. Feed it after every step of whatever drives START.

use core::fmt;

use heapless::Vec;

use plasma_protocol::time::{Duration, Instant};

/// The manuals' least delay between Start signals. Deliberately its own constant rather than
/// the controller's setting, so a wrong setting is caught.
const START_GAP: Duration = Duration::from_millis(50);

/// How many violations are kept (the count goes on beyond).
const KEPT: usize = 16;

/// A broken safety rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ViolationKind {
    /// START was on at the first sample (it must be off at reset).
    StartOnAtReset,
    /// START on while TORCH_ON is off.
    StartWithoutTorchOn,
    /// START rose less than 50 ms after its previous falling edge.
    StartGapTooShort {
        /// The gap actually seen.
        gap: Duration,
    },
    /// START on before the quick-restart blackout ended.
    StartDuringBlackout,
    /// START on while a TORCH_ON active at power-up has not yet been seen inactive.
    StartFromTorchOnAtPowerUp,
}

impl fmt::Display for ViolationKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ViolationKind::StartOnAtReset => f.write_str("START on at reset"),
            ViolationKind::StartWithoutTorchOn => f.write_str("START on while TORCH_ON off"),
            ViolationKind::StartGapTooShort { gap } => {
                write!(f, "START again after only {} us", gap.as_micros())
            }
            ViolationKind::StartDuringBlackout => f.write_str("START during restart blackout"),
            ViolationKind::StartFromTorchOnAtPowerUp => {
                f.write_str("START from a TORCH_ON stuck since power-up")
            }
        }
    }
}

/// A broken rule and when it was seen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Violation {
    /// The sample's time.
    pub at: Instant,
    /// What was wrong.
    pub kind: ViolationKind,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} us: {}", self.at.as_micros(), self.kind)
    }
}

/// Watches sampled TORCH_ON / START levels for broken safety rules.
#[derive(Debug, Clone, Default)]
pub struct SafetyMonitor {
    sampled: bool,
    start: bool,
    last_start_fall: Option<Instant>,
    torch_stuck_since_power_up: bool,
    violations: Vec<Violation, KEPT>,
    count: u32,
}

impl SafetyMonitor {
    /// A monitor that has seen nothing yet; its first sample is taken as power-up.
    pub const fn new() -> Self {
        SafetyMonitor {
            sampled: false,
            start: false,
            last_start_fall: None,
            torch_stuck_since_power_up: false,
            violations: Vec::new(),
            count: 0,
        }
    }

    /// One sample: the levels after a step at `now`, and the blackout the link reports.
    pub fn check(
        &mut self,
        now: Instant,
        torch_on: bool,
        start: bool,
        blackout_until: Option<Instant>,
    ) {
        if !self.sampled {
            self.sampled = true;
            self.torch_stuck_since_power_up = torch_on;
            if start {
                self.record(now, ViolationKind::StartOnAtReset);
            }
        }
        if !torch_on {
            self.torch_stuck_since_power_up = false;
        }

        let rose = start && !self.start;
        let fell = !start && self.start;
        self.start = start;
        if fell {
            self.last_start_fall = Some(now);
        }

        if rose && let Some(fall) = self.last_start_fall {
            let gap = now.saturating_since(fall);
            if gap < START_GAP {
                self.record(now, ViolationKind::StartGapTooShort { gap });
            }
        }
        if start && !torch_on {
            self.record(now, ViolationKind::StartWithoutTorchOn);
        }
        if start && blackout_until.is_some_and(|until| now < until) {
            self.record(now, ViolationKind::StartDuringBlackout);
        }
        if start && self.torch_stuck_since_power_up {
            self.record(now, ViolationKind::StartFromTorchOnAtPowerUp);
        }
    }

    /// The first violations seen (at most 16 are kept; see [`count`](Self::count)).
    pub fn violations(&self) -> &[Violation] {
        &self.violations
    }

    /// How many violations were seen in all.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// No rule broken so far.
    pub fn is_clean(&self) -> bool {
        self.count == 0
    }

    fn record(&mut self, at: Instant, kind: ViolationKind) {
        self.count = self.count.saturating_add(1);
        // Keep the first ones: the first violation is the one that explains the rest.
        let _ = self.violations.push(Violation { at, kind });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(v: u64) -> Instant {
        Instant::from_millis(v)
    }

    fn kinds(m: &SafetyMonitor) -> std::vec::Vec<ViolationKind> {
        m.violations().iter().map(|v| v.kind).collect()
    }

    #[test]
    fn a_correct_trace_is_clean() {
        let mut m = SafetyMonitor::new();
        m.check(ms(0), false, false, None);
        m.check(ms(10), true, true, None);
        m.check(ms(20), false, false, None);
        m.check(ms(70), true, true, None); // exactly 50 ms after the fall: allowed
        m.check(ms(100), true, true, Some(ms(100))); // blackout ended at 100 ms
        assert!(m.is_clean(), "{:?}", m.violations());
    }

    #[test]
    fn start_on_at_reset_is_caught() {
        let mut m = SafetyMonitor::new();
        m.check(ms(0), true, true, None);
        assert_eq!(
            kinds(&m),
            [
                ViolationKind::StartOnAtReset,
                ViolationKind::StartFromTorchOnAtPowerUp
            ]
        );
    }

    #[test]
    fn start_without_torch_on_is_caught() {
        let mut m = SafetyMonitor::new();
        m.check(ms(0), false, false, None);
        m.check(ms(5), true, true, None);
        m.check(ms(6), false, true, None);
        assert_eq!(kinds(&m), [ViolationKind::StartWithoutTorchOn]);
        assert_eq!(m.violations()[0].at, ms(6));
    }

    #[test]
    fn a_short_gap_is_caught() {
        let mut m = SafetyMonitor::new();
        m.check(ms(0), false, false, None);
        m.check(ms(100), true, true, None);
        m.check(ms(200), false, false, None);
        m.check(Instant::from_micros(249_999), true, true, None);
        assert_eq!(
            kinds(&m),
            [ViolationKind::StartGapTooShort {
                gap: Duration::from_micros(49_999)
            }]
        );
    }

    #[test]
    fn start_during_blackout_is_caught() {
        let mut m = SafetyMonitor::new();
        m.check(ms(0), false, false, Some(ms(2000)));
        m.check(ms(1999), true, true, Some(ms(2000)));
        assert_eq!(kinds(&m), [ViolationKind::StartDuringBlackout]);
    }

    #[test]
    fn start_from_a_stuck_torch_on_is_caught_until_it_was_released() {
        let mut m = SafetyMonitor::new();
        m.check(ms(0), true, false, None);
        m.check(ms(100), true, true, None);
        assert_eq!(kinds(&m), [ViolationKind::StartFromTorchOnAtPowerUp]);
        // Released, then pressed again: now it is a real request.
        m.check(ms(200), false, false, None);
        m.check(ms(300), true, true, None);
        assert_eq!(m.count(), 1);
    }

    #[test]
    fn counts_beyond_what_it_keeps() {
        let mut m = SafetyMonitor::new();
        m.check(ms(0), false, false, None);
        for t in 1..=20 {
            m.check(ms(t), false, true, None);
        }
        assert_eq!(m.count(), 20);
        assert_eq!(m.violations().len(), KEPT);
        assert_eq!(m.violations()[0].at, ms(1));
    }
}
