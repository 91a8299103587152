//! An independent check of the START safety rules, for tests and simulations.
//!
//! Written from the rules, not from [`Interlocks`](super::Interlocks), and fed only what it
//! observes itself: the input edges as they arrive at the board ([`SafetyMonitor::input`]),
//! the START output pin and the blackout the link reports ([`SafetyMonitor::check`]). It
//! never reads the interlocks' own view of the inputs: a machine that lost or misread a
//! TORCH_ON edge would agree with itself. Feed it every edge the board is given, and a
//! sample after every step of whatever drives START.
//!
//! "Observed" means TORCH_ON as the CNC means it, not the raw pin level: a pin level means
//! nothing without the table's wiring. The monitor is fed the pin read with the active level
//! set at that moment, and when the operator changes TORCH_ON's level or debounce it is told
//! the new meaning ([`SafetyMonitor::torch_on_redefined`]), an observed command like an edge,
//! never the interlocks' view. A change then counts like power-up: a TORCH_ON active under the
//! new setting must be seen inactive before START.
//!
//! The unit's readiness comes the same way: its NOT_READY signal as an input edge, the link's
//! report of the unit's state ([`SafetyMonitor::link_reports`], like the blackout), and the
//! operator's `CONFIG interlock_ready` ([`SafetyMonitor::ready_interlock`]); the rule is in
//! force from power-up, as the default is.

use core::fmt;

use heapless::Vec;

use plasma_protocol::time::{Duration, Instant};

use super::signals::Input;

/// The manuals' least delay between Start signals. Deliberately its own constant rather than
/// the controller's setting, so a wrong setting is caught.
const START_GAP: Duration = Duration::from_millis(50);

/// How long NOT_READY may be active at the pin before a START rising anyway is a violation:
/// the longest debounce a setting may give an input, so a START that rose while the filter
/// still waited is not one. Its own constant, like [`START_GAP`].
const NOT_READY_GRACE: Duration = Duration::from_millis(100);

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
    /// START on while a TORCH_ON active at power-up (or when its wiring setting changed) has
    /// not yet been seen inactive.
    StartFromTorchOnAtPowerUp,
    /// START rose while the unit said it was not ready for a start (its NOT_READY signal, or
    /// the link's report of its state) and the ready interlock was on.
    StartWhileNotReady,
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
            ViolationKind::StartWhileNotReady => f.write_str("START while the unit is not ready"),
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

/// Watches the TORCH_ON edges and sampled START levels for broken safety rules.
#[derive(Debug, Clone)]
pub struct SafetyMonitor {
    sampled: bool,
    /// TORCH_ON at the board's pin, from the edges fed.
    torch_on: bool,
    start: bool,
    last_start_fall: Option<Instant>,
    torch_stuck_since_power_up: bool,
    /// `CONFIG interlock_ready` as the operator last set it.
    ready_interlock: bool,
    /// NOT_READY at the pin, from the edges fed.
    not_ready_signal: bool,
    /// The first sample that saw NOT_READY active, while it stays active.
    not_ready_since: Option<Instant>,
    /// The link is up and reports the unit's state as not ready.
    link_says_not_ready: bool,
    violations: Vec<Violation, KEPT>,
    count: u32,
}

impl SafetyMonitor {
    /// A monitor watching from power-up, with TORCH_ON's level at the board's pin then; its
    /// first sample is taken as the reset.
    pub const fn new(torch_on_at_power_up: bool) -> Self {
        SafetyMonitor {
            sampled: false,
            torch_on: torch_on_at_power_up,
            start: false,
            last_start_fall: None,
            torch_stuck_since_power_up: torch_on_at_power_up,
            ready_interlock: true,
            not_ready_signal: false,
            not_ready_since: None,
            link_says_not_ready: false,
            violations: Vec::new(),
            count: 0,
        }
    }

    /// An input edge as it arrives at the board (TORCH_ON and NOT_READY bear on the rules).
    /// Feed it before the sample of the step that delivers it.
    pub fn input(&mut self, input: Input, active: bool) {
        match input {
            Input::TorchOn => {
                self.torch_on = active;
                if !active {
                    self.torch_stuck_since_power_up = false;
                }
            }
            Input::NotReady => {
                self.not_ready_signal = active;
                if !active {
                    self.not_ready_since = None;
                }
            }
            _ => {}
        }
    }

    /// The link's report of the unit: whether the link is up and the unit's own state allows a
    /// start ([`SupplyState`](super::SupplyState)'s `link_up` and `unit_ready`). With the link
    /// down its state is unknown and the rule does not judge it.
    pub fn link_reports(&mut self, link_up: bool, unit_ready: bool) {
        self.link_says_not_ready = link_up && !unit_ready;
    }

    /// The operator set `CONFIG interlock_ready` (on at power-up, the default).
    pub fn ready_interlock(&mut self, on: bool) {
        self.ready_interlock = on;
    }

    /// TORCH_ON's meaning at the pin changed: the operator set its active level or debounce
    /// (`CONFIG torch_on_active`, `torch_on_debounce_ms`). The monitor judges TORCH_ON as the
    /// CNC means it, and after such a change that is the pin read with the new level:
    /// `active`. An operator's command is observed like an edge, not taken from the
    /// interlocks. Like power-up, a TORCH_ON active now must be seen inactive before any START
    /// ([`ViolationKind::StartFromTorchOnAtPowerUp`]).
    pub fn torch_on_redefined(&mut self, active: bool) {
        self.torch_on = active;
        self.torch_stuck_since_power_up = active;
    }

    /// One sample: the START pin after a step at `now`, and the blackout the link reports.
    pub fn check(&mut self, now: Instant, start: bool, blackout_until: Option<Instant>) {
        let torch_on = self.torch_on;
        if !self.sampled {
            self.sampled = true;
            if start {
                self.record(now, ViolationKind::StartOnAtReset);
            }
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
        if self.not_ready_signal && self.not_ready_since.is_none() {
            self.not_ready_since = Some(now);
        }
        let signal_says_not_ready = self
            .not_ready_since
            .is_some_and(|since| now.saturating_since(since) >= NOT_READY_GRACE);
        if rose && self.ready_interlock && (self.link_says_not_ready || signal_says_not_ready) {
            self.record(now, ViolationKind::StartWhileNotReady);
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

    /// Feeds TORCH_ON's level as an edge, then samples START (one step of a trace).
    fn step(
        m: &mut SafetyMonitor,
        now: Instant,
        torch_on: bool,
        start: bool,
        blackout_until: Option<Instant>,
    ) {
        m.input(Input::TorchOn, torch_on);
        m.check(now, start, blackout_until);
    }

    fn kinds(m: &SafetyMonitor) -> std::vec::Vec<ViolationKind> {
        m.violations().iter().map(|v| v.kind).collect()
    }

    #[test]
    fn a_correct_trace_is_clean() {
        let mut m = SafetyMonitor::new(false);
        step(&mut m, ms(0), false, false, None);
        step(&mut m, ms(10), true, true, None);
        step(&mut m, ms(20), false, false, None);
        step(&mut m, ms(70), true, true, None); // exactly 50 ms after the fall: allowed
        step(&mut m, ms(100), true, true, Some(ms(100))); // blackout ended at 100 ms
        assert!(m.is_clean(), "{:?}", m.violations());
    }

    #[test]
    fn start_on_at_reset_is_caught() {
        let mut m = SafetyMonitor::new(true);
        step(&mut m, ms(0), true, true, None);
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
        let mut m = SafetyMonitor::new(false);
        step(&mut m, ms(0), false, false, None);
        step(&mut m, ms(5), true, true, None);
        step(&mut m, ms(6), false, true, None);
        assert_eq!(kinds(&m), [ViolationKind::StartWithoutTorchOn]);
        assert_eq!(m.violations()[0].at, ms(6));
    }

    #[test]
    fn a_short_gap_is_caught() {
        let mut m = SafetyMonitor::new(false);
        step(&mut m, ms(0), false, false, None);
        step(&mut m, ms(100), true, true, None);
        step(&mut m, ms(200), false, false, None);
        step(&mut m, Instant::from_micros(249_999), true, true, None);
        assert_eq!(
            kinds(&m),
            [ViolationKind::StartGapTooShort {
                gap: Duration::from_micros(49_999)
            }]
        );
    }

    #[test]
    fn start_during_blackout_is_caught() {
        let mut m = SafetyMonitor::new(false);
        step(&mut m, ms(0), false, false, Some(ms(2000)));
        step(&mut m, ms(1999), true, true, Some(ms(2000)));
        assert_eq!(kinds(&m), [ViolationKind::StartDuringBlackout]);
    }

    #[test]
    fn start_from_a_stuck_torch_on_is_caught_until_it_was_released() {
        let mut m = SafetyMonitor::new(true);
        step(&mut m, ms(0), true, false, None);
        step(&mut m, ms(100), true, true, None);
        assert_eq!(kinds(&m), [ViolationKind::StartFromTorchOnAtPowerUp]);
        // Released, then pressed again: now it is a real request.
        step(&mut m, ms(200), false, false, None);
        step(&mut m, ms(300), true, true, None);
        assert_eq!(m.count(), 1);
    }

    #[test]
    fn start_rising_while_the_unit_is_not_ready_is_caught() {
        let mut m = SafetyMonitor::new(false);
        step(&mut m, ms(0), false, false, None);
        m.link_reports(true, false);
        step(&mut m, ms(100), true, true, None);
        assert_eq!(kinds(&m), [ViolationKind::StartWhileNotReady]);
        // A START already on when the unit leaves its ready state is its cut (PREFLOW).
        step(&mut m, ms(200), false, false, None);
        m.link_reports(true, true);
        step(&mut m, ms(300), true, true, None);
        m.link_reports(true, false);
        step(&mut m, ms(400), true, true, None);
        assert_eq!(m.count(), 1);
        // The link down says nothing about the unit's state.
        step(&mut m, ms(500), false, false, None);
        m.link_reports(false, false);
        step(&mut m, ms(600), true, true, None);
        assert_eq!(m.count(), 1);
        // With the interlock off, the operator allowed it.
        step(&mut m, ms(700), false, false, None);
        m.link_reports(true, false);
        m.ready_interlock(false);
        step(&mut m, ms(800), true, true, None);
        assert_eq!(m.count(), 1);
    }

    #[test]
    fn the_not_ready_signal_counts_once_any_debounce_is_over() {
        let mut m = SafetyMonitor::new(false);
        step(&mut m, ms(0), false, false, None);
        m.input(Input::NotReady, true);
        m.check(ms(10), false, None);
        // Inside the longest debounce the filter may still be waiting.
        step(&mut m, ms(109), true, true, None);
        assert!(m.is_clean());
        step(&mut m, ms(200), false, false, None);
        step(&mut m, ms(250), true, true, None);
        assert_eq!(kinds(&m), [ViolationKind::StartWhileNotReady]);
        // Released: fine again.
        step(&mut m, ms(300), false, false, None);
        m.input(Input::NotReady, false);
        step(&mut m, ms(400), true, true, None);
        assert_eq!(m.count(), 1);
    }

    #[test]
    fn counts_beyond_what_it_keeps() {
        let mut m = SafetyMonitor::new(false);
        step(&mut m, ms(0), false, false, None);
        for t in 1..=20 {
            step(&mut m, ms(t), false, true, None);
        }
        assert_eq!(m.count(), 20);
        assert_eq!(m.violations().len(), KEPT);
        assert_eq!(m.violations()[0].at, ms(1));
    }
}
