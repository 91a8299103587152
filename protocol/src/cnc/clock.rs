//! Wall-clock time as the CNC writes it (`CLOCK 2026-11-26T07:30:00`, UTC, no zone): a count
//! of unix seconds, parsed from and written as that one form.
//!
//! The days are counted with the proleptic Gregorian calendar (the civil-from-days method:
//! years of 365 days, a leap day every 4 years except centuries not divisible by 400),
//! from 1970-01-01 up to 2106-02-07, where 32-bit unix seconds end.
//!
//! ```
//! use plasma_protocol::cnc::clock::WallClock;
//!
//! let t = WallClock::parse("2026-11-26T07:30:00").unwrap();
//! assert_eq!(t.unix_seconds(), 1_795_678_200);
//! assert_eq!(format!("{t}"), "2026-11-26T07:30:00");
//! assert!(WallClock::parse("2026-02-29T00:00:00").is_none());
//! ```

use core::fmt;

/// The form `CLOCK` takes and `HISTORY` writes, for error replies.
pub const CLOCK_FORM: &str = "YYYY-MM-DDTHH:MM:SS";

/// A UTC time to the second, 1970-01-01T00:00:00 to 2106-02-07T06:28:15.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WallClock(u32);

const SECONDS_PER_DAY: u32 = 86_400;

fn is_leap(year: u32) -> bool {
    year.is_multiple_of(4) && (!year.is_multiple_of(100) || year.is_multiple_of(400))
}

fn days_in_month(year: u32, month: u32) -> u32 {
    match month {
        2 if is_leap(year) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Days from 1970-01-01 to the first of `month` in `year` (both valid, year >= 1970).
fn days_before(year: u32, month: u32) -> u32 {
    let years = (1970..year).map(|y| if is_leap(y) { 366 } else { 365 });
    let months = (1..month).map(|m| days_in_month(year, m));
    years.chain(months).sum()
}

/// A fixed-width decimal field of `text` at `at`.
fn field(text: &[u8], at: usize, width: usize) -> Option<u32> {
    let digits = text.get(at..at + width)?;
    digits.iter().try_fold(0u32, |value, &b| {
        b.is_ascii_digit().then(|| value * 10 + u32::from(b - b'0'))
    })
}

impl WallClock {
    /// The time `seconds` after 1970-01-01T00:00:00 UTC.
    pub const fn from_unix_seconds(seconds: u32) -> Self {
        WallClock(seconds)
    }

    /// Seconds since 1970-01-01T00:00:00 UTC.
    pub const fn unix_seconds(self) -> u32 {
        self.0
    }

    /// `YYYY-MM-DDTHH:MM:SS` (exactly that form), or `None` if it is not a valid time in range.
    pub fn parse(text: &str) -> Option<Self> {
        let b = text.as_bytes();
        let separators = [(4, b'-'), (7, b'-'), (10, b'T'), (13, b':'), (16, b':')];
        if b.len() != CLOCK_FORM.len() || separators.iter().any(|&(i, c)| b.get(i) != Some(&c)) {
            return None;
        }
        let (year, month, day) = (field(b, 0, 4)?, field(b, 5, 2)?, field(b, 8, 2)?);
        let (hour, minute, second) = (field(b, 11, 2)?, field(b, 14, 2)?, field(b, 17, 2)?);
        let valid = (1970..=2106).contains(&year)
            && (1..=12).contains(&month)
            && (1..=days_in_month(year, month)).contains(&day)
            && hour < 24
            && minute < 60
            && second < 60;
        if !valid {
            return None;
        }
        let days = u64::from(days_before(year, month) + day - 1);
        let seconds =
            days * u64::from(SECONDS_PER_DAY) + u64::from(hour * 3600 + minute * 60 + second);
        u32::try_from(seconds).ok().map(WallClock)
    }

    /// `(year, month, day, hour, minute, second)`.
    fn parts(self) -> (u32, u32, u32, u32, u32, u32) {
        let mut days = self.0 / SECONDS_PER_DAY;
        let time = self.0 % SECONDS_PER_DAY;
        let mut year = 1970;
        loop {
            let length = if is_leap(year) { 366 } else { 365 };
            if days < length {
                break;
            }
            days -= length;
            year += 1;
        }
        let mut month = 1;
        while days >= days_in_month(year, month) {
            days -= days_in_month(year, month);
            month += 1;
        }
        (
            year,
            month,
            days + 1,
            time / 3600,
            time / 60 % 60,
            time % 60,
        )
    }
}

impl fmt::Display for WallClock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (year, month, day, hour, minute, second) = self.parts();
        write!(
            f,
            "{year:04}-{month:02}-{day:02}T{hour:02}:{minute:02}:{second:02}"
        )
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use super::*;

    #[test]
    fn known_instants() {
        // Unix seconds of these instants as every POSIX `date -u -d ... +%s` gives them.
        let cases = [
            ("1970-01-01T00:00:00", 0),
            ("2000-02-29T23:59:59", 951_868_799),
            ("2026-11-26T07:30:00", 1_795_678_200),
            ("2038-01-19T03:14:08", 2_147_483_648),
            ("2106-02-07T06:28:15", u32::MAX),
        ];
        for (text, seconds) in cases {
            let t = WallClock::parse(text).unwrap();
            assert_eq!(t.unix_seconds(), seconds, "{text}");
            assert_eq!(t.to_string(), text);
        }
    }

    #[test]
    fn every_day_of_four_centuries_round_trips() {
        let mut seconds = 0u32;
        while let Some(next) = seconds.checked_add(SECONDS_PER_DAY + 3_661) {
            let t = WallClock::from_unix_seconds(seconds);
            assert_eq!(WallClock::parse(&t.to_string()), Some(t));
            seconds = next;
        }
    }

    #[test]
    fn refuses_what_is_not_a_time() {
        for text in [
            "",
            "2026-11-26",
            "2026-11-26 07:30:00",
            "2026-11-26T07:30:00Z",
            "2026-13-01T00:00:00",
            "2026-00-01T00:00:00",
            "2026-02-29T00:00:00",
            "2026-04-31T00:00:00",
            "2026-11-26T24:00:00",
            "2026-11-26T07:60:00",
            "1969-12-31T23:59:59",
            "2106-02-07T06:28:16",
            "2026-1-126T07:30:00",
            "+026-11-26T07:30:00",
        ] {
            assert_eq!(WallClock::parse(text), None, "{text}");
        }
    }
}
