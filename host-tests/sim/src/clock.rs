//! Small helpers for virtual time: the earliest deadline (the protocol crate's), and time
//! accumulators that report whole seconds the way the power supplies' counters do.

use plasma_protocol::time::Duration;

pub use plasma_protocol::time::earliest;

/// Microsecond-exact running total of some duration (arc time, pilot time...).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Accumulator {
    micros: u64,
}

impl Accumulator {
    /// Starts from `seconds`.
    pub fn from_secs(seconds: u64) -> Accumulator {
        Accumulator {
            micros: seconds.saturating_mul(1_000_000),
        }
    }

    /// Adds `d`.
    pub fn add(&mut self, d: Duration) {
        self.micros = self.micros.saturating_add(d.as_micros());
    }

    /// Microseconds so far.
    pub fn as_micros(&self) -> u64 {
        self.micros
    }

    /// Whole seconds so far.
    pub fn secs(&self) -> u64 {
        self.micros / 1_000_000
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_are_counted_whole() {
        let mut a = Accumulator::from_secs(2);
        a.add(Duration::from_millis(999));
        assert_eq!(a.secs(), 2);
        a.add(Duration::from_millis(1));
        assert_eq!(a.secs(), 3);
    }
}
