//! Time as the bridge's state machines see it: a monotonic microsecond count passed in by
//! the caller (the board's embassy-time clock, or a simulator's virtual clock).
//!
//! The logic never reads a clock itself, so every behaviour is deterministic to test.

use core::fmt;
use core::ops::{Add, Sub};

/// A point in time, microseconds since an arbitrary start (power-up on the board).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Instant(u64);

/// A span of time in microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Duration(u64);

impl Instant {
    /// The start of time.
    pub const ZERO: Instant = Instant(0);

    /// From microseconds since start.
    pub const fn from_micros(us: u64) -> Self {
        Instant(us)
    }

    /// From milliseconds since start.
    pub const fn from_millis(ms: u64) -> Self {
        Instant(ms.saturating_mul(1000))
    }

    /// Microseconds since start.
    pub const fn as_micros(self) -> u64 {
        self.0
    }

    /// Milliseconds since start (rounded down).
    pub const fn as_millis(self) -> u64 {
        div_rem_u16(self.0, 1000).0
    }

    /// Time elapsed from `earlier` to `self`, zero if `earlier` is later.
    pub const fn saturating_since(self, earlier: Instant) -> Duration {
        Duration(self.0.saturating_sub(earlier.0))
    }
}

/// The earlier of two optional deadlines (`None`: no deadline).
pub fn earliest(a: Option<Instant>, b: Option<Instant>) -> Option<Instant> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

impl Duration {
    /// No time.
    pub const ZERO: Duration = Duration(0);

    /// From microseconds.
    pub const fn from_micros(us: u64) -> Self {
        Duration(us)
    }

    /// From milliseconds.
    pub const fn from_millis(ms: u64) -> Self {
        Duration(ms.saturating_mul(1000))
    }

    /// From seconds.
    pub const fn from_secs(s: u64) -> Self {
        Duration(s.saturating_mul(1_000_000))
    }

    /// Length in microseconds.
    pub const fn as_micros(self) -> u64 {
        self.0
    }

    /// Length in milliseconds (rounded down).
    pub const fn as_millis(self) -> u64 {
        div_rem_u16(self.0, 1000).0
    }

    /// Length in milliseconds (rounded down), saturating at `u32::MAX` (49.7 days): for the
    /// spans the CNC port shows (a restart's quiet time, a delayed START), which are seconds
    /// long, without 64-bit number formatting in the board image.
    pub const fn as_millis_u32(self) -> u32 {
        let ms = self.as_millis();
        if ms > u32::MAX as u64 {
            u32::MAX
        } else {
            ms as u32
        }
    }
}

impl Add<Duration> for Instant {
    type Output = Instant;
    fn add(self, rhs: Duration) -> Instant {
        Instant(self.0.saturating_add(rhs.0))
    }
}

impl Sub<Duration> for Instant {
    type Output = Instant;
    fn sub(self, rhs: Duration) -> Instant {
        Instant(self.0.saturating_sub(rhs.0))
    }
}

impl Add for Duration {
    type Output = Duration;
    fn add(self, rhs: Duration) -> Duration {
        Duration(self.0.saturating_add(rhs.0))
    }
}

/// `n / d` and `n % d` with 32-bit divisions only, for a divisor that fits 16 bits.
///
/// The MCU (Cortex-M4) divides 32 by 32 bits in one instruction but has no 64-bit divide: a
/// `u64` division calls the compiler's generic routine, about 1 KB of flash. Long division in
/// 16-bit digits keeps every step within 32 bits (remainder < `d` < 2^16): four `udiv`s.
/// Panics when `d` is zero, as `/` does.
pub const fn div_rem_u16(n: u64, d: u16) -> (u64, u16) {
    let d = d as u32;
    let (high, remainder) = div_rem_step(0, (n >> 32) as u32, d);
    let (low, remainder) = div_rem_step(remainder, n as u32, d);
    (((high as u64) << 32) | low as u64, remainder as u16)
}

/// `(carry * 2^32 + n) / d` and its remainder, for `carry < d < 2^16`: two 16-bit digits.
const fn div_rem_step(carry: u32, n: u32, d: u32) -> (u32, u32) {
    let upper = (carry << 16) | (n >> 16);
    let lower = ((upper % d) << 16) | (n & 0xFFFF);
    (((upper / d) << 16) | (lower / d), lower % d)
}

/// A `u64` written in decimal without a 64-bit division (see [`div_rem_u16`]): `u64`'s own
/// `Display` would bring the compiler's 64-bit division routine into the board image. Width,
/// fill and other formatter flags are not applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Decimal(pub u64);

impl fmt::Display for Decimal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Four digits at a time, the most significant first (at most five groups).
        let (rest, last) = div_rem_u16(self.0, 10_000);
        if rest == 0 {
            write!(f, "{last}")
        } else {
            write!(f, "{}{last:04}", Decimal(rest))
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn div_rem_u16_is_the_u64_division(n in any::<u64>(), d in 1u16..) {
            let (q, r) = div_rem_u16(n, d);
            prop_assert_eq!(q, n / u64::from(d));
            prop_assert_eq!(u64::from(r), n % u64::from(d));
        }

        #[test]
        fn decimal_writes_what_u64_display_writes(n in any::<u64>(), digits in 0u32..20) {
            let small = n % 10u64.pow(digits);
            for n in [n, small] {
                prop_assert_eq!(std::format!("{}", Decimal(n)), std::format!("{n}"));
            }
        }
    }

    #[test]
    fn millisecond_conversions() {
        for us in [0, 999, 1000, 1_234_567, u64::MAX] {
            assert_eq!(Instant::from_micros(us).as_millis(), us / 1000);
            assert_eq!(Duration::from_micros(us).as_millis(), us / 1000);
        }
        assert_eq!(div_rem_u16(u64::MAX, 1), (u64::MAX, 0));
        for n in [0, 7, 9_999, 10_000, 10_001, 100_000_000, u64::MAX] {
            assert_eq!(std::format!("{}", Decimal(n)), std::format!("{n}"));
        }
        assert_eq!(div_rem_u16(u64::MAX, u16::MAX), (u64::MAX / 65535, 0));
        assert_eq!(Duration::from_millis(2_000).as_millis_u32(), 2_000);
        let longest = Duration::from_millis(u64::from(u32::MAX));
        assert_eq!(longest.as_millis_u32(), u32::MAX);
        assert_eq!(
            (longest + Duration::from_millis(1)).as_millis_u32(),
            u32::MAX
        );
        assert_eq!(Duration::from_micros(u64::MAX).as_millis_u32(), u32::MAX);
    }

    #[test]
    fn the_earliest_deadline_is_the_earlier_one_that_is_set() {
        let (two, three) = (Instant::from_millis(2), Instant::from_millis(3));
        assert_eq!(earliest(Some(three), Some(two)), Some(two));
        assert_eq!(earliest(Some(two), Some(three)), Some(two));
        assert_eq!(earliest(None, Some(Instant::ZERO)), Some(Instant::ZERO));
        assert_eq!(earliest(Some(three), None), Some(three));
        assert_eq!(earliest(None, None), None);
    }

    #[test]
    fn arithmetic_saturates_instead_of_panicking() {
        assert_eq!(Instant::ZERO - Duration::from_millis(5), Instant::ZERO);
        assert_eq!(
            Instant::from_millis(3).saturating_since(Instant::from_millis(5)),
            Duration::ZERO
        );
        assert_eq!(
            (Instant::from_millis(2) + Duration::from_micros(500)).as_micros(),
            2500
        );
    }
}
