//! A level filter: the output takes the input's level once it has held for a set time.

use plasma_protocol::time::{Duration, Instant};

/// Debounced view of one input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Debouncer {
    hold: Duration,
    raw: bool,
    raw_since: Instant,
    stable: bool,
}

impl Debouncer {
    /// Starts inactive; a `raw` level that is already active debounces from `now`.
    pub(crate) fn new(hold: Duration, now: Instant, raw: bool) -> Self {
        Debouncer {
            hold,
            raw,
            raw_since: now,
            stable: false,
        }
    }

    /// Record a new raw level (repeats of the same level are ignored: they are not edges).
    pub(crate) fn on_level(&mut self, now: Instant, raw: bool) {
        if raw != self.raw {
            self.raw = raw;
            self.raw_since = now;
        }
    }

    /// Advance to `now`; returns the new stable level if it changed.
    pub(crate) fn poll(&mut self, now: Instant) -> Option<bool> {
        if self.raw != self.stable && now >= self.raw_since + self.hold {
            self.stable = self.raw;
            return Some(self.stable);
        }
        None
    }

    /// Use a new hold time from now on (a pending level keeps the time it was first seen).
    pub(crate) fn set_hold(&mut self, hold: Duration) {
        self.hold = hold;
    }

    /// The debounced level.
    pub(crate) fn stable(&self) -> bool {
        self.stable
    }

    /// When the pending raw level will become stable, if one is pending.
    pub(crate) fn settles_at(&self) -> Option<Instant> {
        (self.raw != self.stable).then(|| self.raw_since + self.hold)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: fn(u64) -> Instant = Instant::from_millis;

    #[test]
    fn level_must_hold_for_the_whole_time() {
        let mut d = Debouncer::new(Duration::from_millis(2), MS(0), false);
        d.on_level(MS(10), true);
        assert_eq!(d.settles_at(), Some(MS(12)));
        assert_eq!(d.poll(Instant::from_micros(11_999)), None);
        assert_eq!(d.poll(MS(12)), Some(true));
        assert!(d.stable());
        assert_eq!(d.settles_at(), None);
    }

    #[test]
    fn a_bounce_restarts_the_wait() {
        let mut d = Debouncer::new(Duration::from_millis(2), MS(0), false);
        d.on_level(MS(10), true);
        d.on_level(MS(11), false);
        assert_eq!(d.poll(MS(12)), None);
        d.on_level(Instant::from_micros(11_500), true);
        assert_eq!(d.poll(Instant::from_micros(13_499)), None);
        assert_eq!(d.poll(Instant::from_micros(13_500)), Some(true));
    }

    #[test]
    fn active_at_start_debounces_from_start() {
        let mut d = Debouncer::new(Duration::from_millis(2), MS(5), true);
        assert!(!d.stable());
        assert_eq!(d.poll(MS(7)), Some(true));
    }
}
