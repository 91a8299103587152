//! The one level filter of the discrete I/O: a new level counts once it has held for a set
//! time. [`InputFilter`](super::input_filter::InputFilter) runs one per input pin (the wiring's debounce),
//! [`Interlocks`](super::Interlocks) one on MOTION (ARC_OK's debounce).
//!
//! The hold time is passed to every call that needs it, not kept: it is a setting, and the
//! settings are its one source (a new hold applies at once; a pending level keeps the time it
//! was first seen).

use plasma_protocol::time::{Duration, Instant};

/// Debounced view of one input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Debouncer {
    raw: bool,
    raw_since: Instant,
    stable: bool,
}

impl Debouncer {
    /// Starts inactive; a `raw` level that is already active debounces from `now`.
    pub(crate) fn new(now: Instant, raw: bool) -> Self {
        Debouncer {
            raw,
            raw_since: now,
            stable: false,
        }
    }

    /// Already stable at `level`, nothing pending (a level taken without debounce).
    pub(crate) const fn settled(level: bool) -> Self {
        Debouncer {
            raw: level,
            raw_since: Instant::ZERO,
            stable: level,
        }
    }

    /// Record a new raw level (repeats of the same level are ignored: they are not edges).
    pub(crate) fn on_level(&mut self, now: Instant, raw: bool) {
        if raw != self.raw {
            self.raw = raw;
            self.raw_since = now;
        }
    }

    /// Take `level` as the stable level at once, dropping a pending one.
    pub(crate) fn accept(&mut self, level: bool) {
        *self = Self::settled(level);
    }

    /// Advance to `now`; returns the new stable level if it changed.
    pub(crate) fn poll(&mut self, now: Instant, hold: Duration) -> Option<bool> {
        if self.raw != self.stable && now >= self.raw_since + hold {
            self.stable = self.raw;
            return Some(self.stable);
        }
        None
    }

    /// The debounced level.
    pub(crate) fn stable(&self) -> bool {
        self.stable
    }

    /// When the pending raw level will become stable, if one is pending.
    pub(crate) fn settles_at(&self, hold: Duration) -> Option<Instant> {
        (self.raw != self.stable).then(|| self.raw_since + hold)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: fn(u64) -> Instant = Instant::from_millis;
    const HOLD: Duration = Duration::from_millis(2);

    #[test]
    fn level_must_hold_for_the_whole_time() {
        let mut d = Debouncer::new(MS(0), false);
        d.on_level(MS(10), true);
        assert_eq!(d.settles_at(HOLD), Some(MS(12)));
        assert_eq!(d.poll(Instant::from_micros(11_999), HOLD), None);
        assert_eq!(d.poll(MS(12), HOLD), Some(true));
        assert!(d.stable());
        assert_eq!(d.settles_at(HOLD), None);
    }

    #[test]
    fn a_bounce_restarts_the_wait() {
        let mut d = Debouncer::new(MS(0), false);
        d.on_level(MS(10), true);
        d.on_level(MS(11), false);
        assert_eq!(d.poll(MS(12), HOLD), None);
        d.on_level(Instant::from_micros(11_500), true);
        assert_eq!(d.poll(Instant::from_micros(13_499), HOLD), None);
        assert_eq!(d.poll(Instant::from_micros(13_500), HOLD), Some(true));
    }

    #[test]
    fn active_at_start_debounces_from_start() {
        let mut d = Debouncer::new(MS(5), true);
        assert!(!d.stable());
        assert_eq!(d.poll(MS(7), HOLD), Some(true));
    }
}
