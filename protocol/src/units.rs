//! Exact fixed-point current (1/64 A) and gas pressure (1/128 psi), shared by the Powermax
//! registers and the CNC commands so a value typed on the CNC reaches the supply unchanged.
//!
//! Both Powermax manuals describe these registers as "16-bit, fixed-point binary with 1-bit sign
//! at MSB and 6-bit (current) / 7-bit (pressure) decimal at LSB": the raw word is a
//! two's-complement `i16` holding units x 64 or units x 128. Every raw value therefore has a
//! finite decimal expansion (1/64 = 0.015625, 1/128 = 0.0078125), which
//! [`Display`](core::fmt::Display) prints exactly, without floats.
//!
//! Text goes back through [`FromStr`] with one documented rule: the decimal value is converted
//! to the NEAREST raw step, and a value exactly half-way between two steps rounds away from zero
//! (`"0.0078125"` A is half of 1/64 A and becomes raw 1). [`Amps::parse_exact`] and
//! [`Psi::parse_exact`] refuse text that is not a whole number of steps instead.
//!
//! Both map their refusals to the crate [`Error`]: [`Error::Malformed`] for bad syntax, a value
//! outside the 16-bit range or (exact parsing) a value between two steps, [`Error::Overlong`] for
//! more than 30 significant fraction digits. Callers that must say which of these it was (the
//! CNC replies do) use [`Amps::from_decimal`] / [`Psi::from_decimal`], which return a
//! [`ParseError`].
//!
//! ```
//! use plasma_protocol::units::{Amps, ParseError, Rounding};
//! assert_eq!(Amps::from_decimal("45.25", Rounding::Exact), Ok(Amps::from_raw(2896)));
//! assert_eq!(Amps::from_decimal("45.1", Rounding::Exact), Err(ParseError::Inexact));
//! assert_eq!(Amps::from_decimal("45.1", Rounding::Nearest), Ok(Amps::from_raw(2886)));
//! assert_eq!(Amps::from_decimal("512", Rounding::Nearest), Err(ParseError::OutOfRange));
//! assert_eq!(Amps::from_decimal("4S", Rounding::Nearest), Err(ParseError::Syntax));
//! ```

use core::cmp::Ordering;
use core::fmt;
use core::str::FromStr;

use crate::{Error, Result};

/// Significant fraction digits accepted when parsing (far beyond the 7 an exact value needs).
const MAX_FRACTION_DIGITS: usize = 30;

/// Why decimal text was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParseError {
    /// Not `[-]digits[.digits]`.
    Syntax,
    /// Outside the signed 16-bit raw range (after rounding).
    OutOfRange,
    /// Between two steps, with [`Rounding::Exact`].
    Inexact,
    /// More than 30 significant fraction digits.
    TooManyDigits,
}

impl From<ParseError> for Error {
    fn from(error: ParseError) -> Error {
        match error {
            ParseError::TooManyDigits => Error::Overlong,
            ParseError::Syntax | ParseError::OutOfRange | ParseError::Inexact => Error::Malformed,
        }
    }
}

/// What to do with a decimal value that falls between two raw steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rounding {
    /// Take the nearest step; half-way rounds away from zero.
    Nearest,
    /// Refuse it ([`ParseError::Inexact`]).
    Exact,
}

/// Writes `raw / 2^bits` as an exact decimal without trailing zeros.
fn write_fixed(f: &mut fmt::Formatter<'_>, raw: u16, bits: u32) -> fmt::Result {
    let value = i32::from(raw as i16);
    let magnitude = value.unsigned_abs();
    let whole = magnitude >> bits;
    let steps = magnitude & ((1 << bits) - 1);
    if value < 0 {
        f.write_str("-")?;
    }
    write!(f, "{whole}")?;
    if steps != 0 {
        // steps / 2^bits == steps * 5^bits / 10^bits: exactly `bits` decimal digits.
        let mut digits = steps * 5u32.pow(bits);
        let mut width = bits as usize;
        while digits.is_multiple_of(10) {
            digits /= 10;
            width -= 1;
        }
        write!(f, ".{digits:0width$}")?;
    }
    Ok(())
}

/// Parses `[-]digits[.digits]` into signed steps of `bits` fraction bits (see the module docs).
///
/// The crate's one decimal parser: the CNC commands use it too (with `bits` 0 for whole numbers).
pub(crate) fn parse_fixed(
    text: &str,
    bits: u32,
    rounding: Rounding,
) -> core::result::Result<i16, ParseError> {
    let (negative, body) = match text.as_bytes().split_first() {
        Some((b'-', rest)) => (true, rest),
        Some(_) => (false, text.as_bytes()),
        None => return Err(ParseError::Syntax),
    };
    let (whole_digits, fraction_digits) = match body.iter().position(|&b| b == b'.') {
        Some(dot) => {
            let (w, f) = body.split_at(dot);
            let f = f.get(1..).unwrap_or(&[]);
            if f.is_empty() {
                return Err(ParseError::Syntax);
            }
            (w, f)
        }
        None => (body, &[][..]),
    };
    if whole_digits.is_empty() || !whole_digits.iter().all(u8::is_ascii_digit) {
        return Err(ParseError::Syntax);
    }
    if !fraction_digits.iter().all(u8::is_ascii_digit) {
        return Err(ParseError::Syntax);
    }
    let mut whole: u32 = 0;
    for &d in whole_digits {
        whole = whole
            .checked_mul(10)
            .and_then(|w| w.checked_add(u32::from(d - b'0')))
            .filter(|&w| w <= 0xFFFF)
            .ok_or(ParseError::OutOfRange)?;
    }
    // Trailing zeros carry no value; only the rest counts toward the digit limit.
    let significant = fraction_digits
        .iter()
        .rposition(|&d| d != b'0')
        .map_or(0, |last| last + 1);
    if significant > MAX_FRACTION_DIGITS {
        return Err(ParseError::TooManyDigits);
    }
    // The fraction times 2^bits, in decimal: each doubling of the digits carries the next bit
    // of the steps out of the first digit, and what stays behind is the remainder. Exact for
    // every digit count, and no wide division (u128 arithmetic costs the board ~1 KB).
    let mut digits = [0u8; MAX_FRACTION_DIGITS];
    for (slot, &d) in digits
        .iter_mut()
        .zip(fraction_digits.iter().take(significant))
    {
        *slot = d - b'0';
    }
    let mut fraction_steps: u64 = 0;
    for _ in 0..bits {
        let mut carry = 0;
        for d in digits.iter_mut().take(significant).rev() {
            let doubled = *d * 2 + carry;
            *d = doubled % 10;
            carry = doubled / 10;
        }
        fraction_steps = (fraction_steps << 1) | u64::from(carry);
    }
    let mut steps = u64::from(whole)
        .checked_shl(bits)
        .filter(|s| s >> bits == u64::from(whole))
        .and_then(|s| s.checked_add(fraction_steps))
        .ok_or(ParseError::OutOfRange)?;
    // The remainder as a decimal fraction: zero, below one half, or at least one half.
    let remainder = digits.first().copied().unwrap_or(0);
    if digits.iter().any(|&d| d != 0) {
        if rounding == Rounding::Exact {
            return Err(ParseError::Inexact);
        }
        if remainder >= 5 {
            steps += 1;
        }
    }
    let limit = if negative { 0x8000 } else { 0x7FFF };
    if steps > limit {
        return Err(ParseError::OutOfRange);
    }
    let signed = if negative {
        (steps as i32).wrapping_neg()
    } else {
        steps as i32
    };
    Ok(signed as i16)
}

/// `numerator / denominator` units as raw steps of `bits` fraction bits, nearest, ties away
/// from zero; `None` if it does not fit the positive range.
fn from_ratio(numerator: u32, denominator: u32, bits: u32) -> Option<u16> {
    let scaled = u64::from(numerator) << bits;
    let denominator = u64::from(denominator);
    let mut steps = scaled / denominator;
    if (scaled % denominator) * 2 >= denominator {
        steps += 1;
    }
    u16::try_from(steps).ok().filter(|&s| s <= 0x7FFF)
}

macro_rules! fixed_point {
    ($(#[$doc:meta])* $name:ident, $bits:expr, $unit:literal) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $name(u16);

        impl $name {
            /// Fraction bits of the raw value.
            pub const FRACTION_BITS: u32 = $bits;
            /// Raw steps per whole unit.
            pub const STEPS_PER_UNIT: u16 = 1 << $bits;
            /// Zero.
            pub const ZERO: Self = Self(0);

            /// Wraps a raw register value.
            pub const fn from_raw(raw: u16) -> Self {
                Self(raw)
            }

            /// The raw register value.
            pub const fn raw(self) -> u16 {
                self.0
            }

            /// The raw value read as the signed steps the manuals describe.
            pub const fn steps(self) -> i16 {
                self.0 as i16
            }

            /// True when the value is above zero (the sign bit is clear and some bit is set).
            pub const fn is_positive(self) -> bool {
                self.steps() > 0
            }

            #[doc = concat!("Whole ", $unit, ", exact; `None` above the 16-bit signed range.")]
            pub const fn from_whole(units: u16) -> Option<Self> {
                if units > (0x7FFF >> $bits) {
                    None
                } else {
                    Some(Self(units << $bits))
                }
            }

            #[doc = concat!("Tenths of ", $unit, ", rounded to the nearest step (ties away from zero).")]
            pub fn from_tenths(tenths: u16) -> Option<Self> {
                from_ratio(u32::from(tenths), 10, $bits).map(Self)
            }

            #[doc = concat!("Hundredths of ", $unit, ", rounded to the nearest step (ties away from zero).")]
            pub fn from_hundredths(hundredths: u16) -> Option<Self> {
                from_ratio(u32::from(hundredths), 100, $bits).map(Self)
            }

            /// Whether the value is a whole number of units (e.g. for supplies that take whole
            /// amps, such as the HPR).
            pub const fn is_whole(self) -> bool {
                self.0 & (Self::STEPS_PER_UNIT - 1) == 0
            }

            #[doc = concat!("Whole ", $unit, ", nearest, half-way away from zero.")]
            pub const fn round_whole(self) -> i16 {
                let steps = self.steps() as i32;
                let half = (Self::STEPS_PER_UNIT / 2) as i32;
                let away = if steps < 0 { steps - half } else { steps + half };
                // Division truncates toward zero, so this rounds half away from zero; the
                // result is within i16 (at most 2^(15 - bits) in magnitude).
                (away / Self::STEPS_PER_UNIT as i32) as i16
            }

            /// Parses decimal text, telling why it was refused (see the module docs).
            pub fn from_decimal(
                text: &str,
                rounding: Rounding,
            ) -> core::result::Result<Self, ParseError> {
                parse_fixed(text, $bits, rounding).map(|steps| Self(steps as u16))
            }

            /// Parses decimal text that must be a whole number of raw steps.
            pub fn parse_exact(text: &str) -> Result<Self> {
                Ok(Self::from_decimal(text, Rounding::Exact)?)
            }
        }

        impl FromStr for $name {
            type Err = Error;

            /// Decimal text to the nearest raw step (ties away from zero); see the module docs.
            fn from_str(text: &str) -> Result<Self> {
                Ok(Self::from_decimal(text, Rounding::Nearest)?)
            }
        }

        impl fmt::Display for $name {
            /// The exact decimal value, without unit and without trailing zeros.
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write_fixed(f, self.0, $bits)
            }
        }

        impl PartialOrd for $name {
            fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
                Some(self.cmp(other))
            }
        }

        impl Ord for $name {
            /// Orders by the signed value, not by the raw bits.
            fn cmp(&self, other: &Self) -> Ordering {
                self.steps().cmp(&other.steps())
            }
        }
    };
}

fixed_point!(
    /// Output current in steps of 1/64 A (the register holds amps x 64).
    ///
    /// ```
    /// use plasma_protocol::units::Amps;
    /// let a: Amps = "55.5".parse().unwrap();
    /// assert_eq!(a.raw(), 3552);
    /// assert_eq!(Amps::from_whole(63).unwrap().raw(), 0x0FC0);
    /// assert_eq!(Amps::from_raw(2896).to_string(), "45.25");
    /// ```
    Amps,
    6,
    "amperes"
);

fixed_point!(
    /// Gas pressure in steps of 1/128 psi (the register holds psi x 128).
    ///
    /// A raw 0 is a real reading in the actual-pressure registers; in the setting registers it
    /// means "automatic", which [`Pressure`] spells out.
    ///
    /// ```
    /// use plasma_protocol::units::Psi;
    /// assert_eq!(Psi::from_whole(45).unwrap().raw(), 0x1680);
    /// assert_eq!(Psi::from_raw(0x23DD).to_string(), "71.7265625");
    /// ```
    Psi,
    7,
    "psi"
);

/// A gas pressure setting: raw 0 selects automatic pressure, anything else is a set point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pressure {
    /// The power supply chooses the pressure for the mode, torch, lead and cartridge (raw 0).
    Auto,
    /// A set point. `Set(Psi::ZERO)` would be sent as raw 0, i.e. automatic; [`Pressure::from_raw`]
    /// never produces it.
    Set(Psi),
}

impl Pressure {
    /// Reads a setting register: 0 is [`Pressure::Auto`].
    pub const fn from_raw(raw: u16) -> Self {
        if raw == 0 {
            Pressure::Auto
        } else {
            Pressure::Set(Psi::from_raw(raw))
        }
    }

    /// The value to write.
    pub const fn raw(self) -> u16 {
        match self {
            Pressure::Auto => 0,
            Pressure::Set(psi) => psi.raw(),
        }
    }

    /// The set point, if not automatic.
    pub const fn psi(self) -> Option<Psi> {
        match Pressure::from_raw(self.raw()) {
            Pressure::Auto => None,
            Pressure::Set(psi) => Some(psi),
        }
    }
}

impl fmt::Display for Pressure {
    /// `AUTO` (the CNC keyword) or the exact psi value.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match Pressure::from_raw(self.raw()) {
            Pressure::Auto => f.write_str("AUTO"),
            Pressure::Set(psi) => psi.fmt(f),
        }
    }
}

impl FromStr for Pressure {
    type Err = Error;

    /// `auto` (any case) or decimal psi as for [`Psi`]; `"0"` is automatic too.
    fn from_str(text: &str) -> Result<Self> {
        if text.eq_ignore_ascii_case("auto") {
            return Ok(Pressure::Auto);
        }
        text.parse::<Psi>().map(|psi| Pressure::from_raw(psi.raw()))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use core::fmt::Write;
    use heapless::String;
    use std::vec;

    fn text(value: impl fmt::Display) -> String<32> {
        let mut s = String::new();
        write!(s, "{value}").unwrap();
        s
    }

    #[test]
    fn manual_current_examples() {
        // SYNC guide: 63 A x 64 = 4032 = 0x0FC0; 65 A = 0x1040; permitted 30 A = 0x0780,
        // 45 A = 0x0B40; setting 105 A = 0x1A40.
        // Legacy guide: 40 A = 0x0A00, 45 A = 0x0B40, 65 A = 0x1040, 85 A = 0x1540,
        // 55.5 A = 3552 = 0x0DE0, min 20 A = 0x0500.
        for (amps, raw) in [
            (63, 0x0FC0),
            (65, 0x1040),
            (30, 0x0780),
            (45, 0x0B40),
            (105, 0x1A40),
            (40, 0x0A00),
            (85, 0x1540),
            (20, 0x0500),
        ] {
            assert_eq!(Amps::from_whole(amps).unwrap().raw(), raw);
            assert_eq!(text(Amps::from_raw(raw)).as_str(), text(amps).as_str());
        }
        assert_eq!(Amps::from_tenths(555).unwrap().raw(), 0x0DE0);
        assert_eq!("55.5".parse::<Amps>().unwrap().raw(), 3552);
        assert_eq!(text(Amps::from_raw(0x0DE0)).as_str(), "55.5");
    }

    #[test]
    fn manual_pressure_examples() {
        // SYNC: 45 psi = 0x1680, 58 = 0x1D00, 78 = 0x2700, 76 = 0x2600.
        // Legacy: 45 psi = 0x1680, 70 = 0x2300, 63 = 0x1F80, 78 = 0x2700.
        for (psi, raw) in [
            (45, 0x1680),
            (58, 0x1D00),
            (78, 0x2700),
            (76, 0x2600),
            (70, 0x2300),
            (63, 0x1F80),
        ] {
            assert_eq!(Psi::from_whole(psi).unwrap().raw(), raw);
            assert_eq!(text(Psi::from_raw(raw)).as_str(), text(psi).as_str());
        }
        // The SYNC actual-output example: 0x23DD = 9181/128, which the manual rounds to
        // "72 psi"; the exact value is 71.7265625.
        assert_eq!(text(Psi::from_raw(0x23DD)).as_str(), "71.7265625");
        assert_eq!("71.7265625".parse::<Psi>().unwrap().raw(), 0x23DD);
    }

    #[test]
    fn display_is_exact() {
        assert_eq!(text(Amps::from_raw(1)).as_str(), "0.015625");
        assert_eq!(text(Amps::from_raw(2896)).as_str(), "45.25");
        assert_eq!(text(Amps::from_raw(2881)).as_str(), "45.015625");
        assert_eq!(text(Psi::from_raw(9248)).as_str(), "72.25");
        assert_eq!(text(Amps::from_raw(0x7FFF)).as_str(), "511.984375");
        assert_eq!(text(Amps::from_raw(0x8000)).as_str(), "-512");
        assert_eq!(text(Amps::from_raw(0xFFFF)).as_str(), "-0.015625");
        assert_eq!(text(Psi::from_raw(1)).as_str(), "0.0078125");
        assert_eq!(text(Psi::from_raw(0x7FFF)).as_str(), "255.9921875");
        assert_eq!(text(Psi::from_raw(0)).as_str(), "0");
    }

    #[test]
    fn parse_rounds_to_nearest_ties_away() {
        // 0.0078125 A is exactly half a step: away from zero.
        assert_eq!("0.0078125".parse::<Amps>().unwrap().raw(), 1);
        assert_eq!("-0.0078125".parse::<Amps>().unwrap().raw(), 0xFFFF);
        // Just below half a step.
        assert_eq!("0.0078124".parse::<Amps>().unwrap().raw(), 0);
        // 45.3 A = 2899.2 steps -> 2899.
        assert_eq!("45.3".parse::<Amps>().unwrap().raw(), 2899);
        assert_eq!(Amps::from_tenths(453).unwrap().raw(), 2899);
        assert_eq!(Amps::from_hundredths(4525).unwrap().raw(), 2896);
        assert_eq!("55.50000".parse::<Amps>().unwrap().raw(), 3552);
        assert_eq!("007".parse::<Amps>().unwrap().raw(), 7 * 64);
    }

    #[test]
    fn parse_exact_rejects_inexact() {
        assert_eq!(Amps::parse_exact("45.3"), Err(Error::Malformed));
        assert_eq!(Amps::parse_exact("45.25").unwrap().raw(), 2896);
        assert_eq!(Psi::parse_exact("0.0078125").unwrap().raw(), 1);
        assert_eq!(Psi::parse_exact("0.00390625"), Err(Error::Malformed));
    }

    #[test]
    fn parse_rejects_bad_text_and_range() {
        for bad in [
            "", "-", ".5", "5.", "5..0", "+5", "5a", " 5", "5 ", "1e3", "--1",
        ] {
            assert_eq!(bad.parse::<Amps>(), Err(Error::Malformed), "{bad}");
        }
        assert_eq!("512".parse::<Amps>(), Err(Error::Malformed));
        assert_eq!("511.9921875".parse::<Amps>(), Err(Error::Malformed)); // rounds to 512
        assert_eq!("-512".parse::<Amps>().unwrap().raw(), 0x8000);
        assert_eq!("-512.0078125".parse::<Amps>(), Err(Error::Malformed));
        assert_eq!("256".parse::<Psi>(), Err(Error::Malformed));
        assert_eq!("99999999999".parse::<Psi>(), Err(Error::Malformed));
        let long = "1.0000000000000000000000000000001"; // 31 significant fraction digits
        assert_eq!(long.parse::<Amps>(), Err(Error::Overlong));
        let zeros = "1.50000000000000000000000000000000000000000";
        assert_eq!(zeros.parse::<Amps>().unwrap().raw(), 96);
    }

    #[test]
    fn constructors_range() {
        assert_eq!(Amps::from_whole(511).unwrap().raw(), 511 * 64);
        assert_eq!(Amps::from_whole(512), None);
        assert_eq!(Psi::from_whole(255).unwrap().raw(), 255 * 128);
        assert_eq!(Psi::from_whole(256), None);
        assert_eq!(Amps::from_tenths(5120), None);
        assert_eq!(Amps::from_hundredths(u16::MAX), None); // 655.35 A
        assert_eq!(Amps::from_hundredths(51198).unwrap().raw(), 0x7FFF); // 32766.72 steps
    }

    #[test]
    fn ordering_is_signed() {
        assert!(Amps::from_raw(0xFFFF) < Amps::ZERO);
        assert!(Amps::from_whole(45).unwrap() < Amps::from_whole(63).unwrap());
        assert!(!Amps::from_raw(0x8000).is_positive());
        assert!(Amps::from_raw(1).is_positive());
    }

    #[test]
    fn parse_errors_say_why() {
        let exact = |t| Amps::from_decimal(t, Rounding::Exact);
        assert_eq!(exact("55.5"), Ok(Amps::from_raw(3552)));
        assert_eq!(exact("045.50"), Ok(Amps::from_raw(2912)));
        assert_eq!(exact("0.015625"), Ok(Amps::from_raw(1)));
        assert_eq!(exact("0000000000045"), Ok(Amps::from_raw(2880)));
        assert_eq!(exact("1.50000000000000"), Ok(Amps::from_raw(96)));
        assert_eq!(exact("45.1"), Err(ParseError::Inexact));
        assert_eq!(exact("0.0078125"), Err(ParseError::Inexact));
        assert_eq!(exact("1.0000000001"), Err(ParseError::Inexact));
        assert_eq!(exact("99999999"), Err(ParseError::OutOfRange));
        assert_eq!(
            exact("99999999999999999999999"),
            Err(ParseError::OutOfRange)
        );
        assert_eq!(exact("512"), Err(ParseError::OutOfRange));
        assert_eq!(exact("-512.015625"), Err(ParseError::OutOfRange));
        let long = "1.0000000000000000000000000000001"; // 31 significant fraction digits
        assert_eq!(exact(long), Err(ParseError::TooManyDigits));
        for bad in [
            "", ".", "-", ".5", "5.", "+5", "4 5", "1e3", "4.5.1", "0x10", "\u{663}", "--1",
        ] {
            assert_eq!(exact(bad), Err(ParseError::Syntax), "{bad}");
            assert_eq!(
                Psi::from_decimal(bad, Rounding::Nearest),
                Err(ParseError::Syntax)
            );
        }
        assert_eq!(
            Psi::from_decimal("72.25", Rounding::Exact),
            Ok(Psi::from_raw(9248))
        );
        assert_eq!(
            Psi::from_decimal("0.0078125", Rounding::Exact),
            Ok(Psi::from_raw(1))
        );
        assert_eq!(
            Psi::from_decimal("72.001", Rounding::Nearest),
            Ok(Psi::from_raw(9216))
        );
        // The crate error keeps the old mapping.
        assert_eq!(Error::from(ParseError::Syntax), Error::Malformed);
        assert_eq!(Error::from(ParseError::OutOfRange), Error::Malformed);
        assert_eq!(Error::from(ParseError::Inexact), Error::Malformed);
        assert_eq!(Error::from(ParseError::TooManyDigits), Error::Overlong);
    }

    #[test]
    fn whole_units() {
        assert_eq!(Amps::from_raw(3552).round_whole(), 56); // 55.5: half-way, away from zero
        assert_eq!(Amps::from_raw(3551).round_whole(), 55);
        assert!(!Amps::from_raw(3552).is_whole());
        assert!(Amps::from_raw(2880).is_whole());
        assert!(Amps::ZERO.is_whole());
        assert_eq!(Amps::from_raw(0x7FFF).round_whole(), 512);
        assert_eq!(Amps::from_raw(0x8000).round_whole(), -512);
        assert!(Amps::from_raw(0x8000).is_whole());
        assert!(Amps::from_raw(0xFFC0).is_whole()); // -1 A
        assert!(!Amps::from_raw(0xFFFF).is_whole());
        assert_eq!(Amps::from_raw(0xFFFF).round_whole(), 0); // -1/64 A
        assert_eq!(Amps::from_raw(0xFFE0).round_whole(), -1); // -0.5 A
        assert_eq!(Amps::from_raw(0xFFE1).round_whole(), 0); // -0.484375 A
        assert_eq!(Psi::from_raw(9216).round_whole(), 72);
        assert_eq!(Psi::from_raw(9216 + 63).round_whole(), 72);
        assert_eq!(Psi::from_raw(9216 + 64).round_whole(), 73);
        assert_eq!(Psi::from_raw(0x7FFF).round_whole(), 256);
        assert_eq!(Psi::from_raw(0x8000).round_whole(), -256);
        assert!(Psi::from_raw(128).is_whole());
        assert!(!Psi::from_raw(64).is_whole());
    }

    #[test]
    fn pressure_auto() {
        assert_eq!(Pressure::from_raw(0), Pressure::Auto);
        assert_eq!(Pressure::Auto.raw(), 0);
        assert_eq!(Pressure::from_raw(0x1680).psi(), Psi::from_whole(45));
        assert_eq!(Pressure::Set(Psi::ZERO).psi(), None);
        assert_eq!(text(Pressure::Auto).as_str(), "AUTO");
        assert_eq!(text(Pressure::Set(Psi::ZERO)).as_str(), "AUTO");
        assert_eq!(text(Pressure::from_raw(0x2300)).as_str(), "70");
        assert_eq!("AUTO".parse::<Pressure>(), Ok(Pressure::Auto));
        assert_eq!("0".parse::<Pressure>(), Ok(Pressure::Auto));
        assert_eq!("45".parse::<Pressure>(), Ok(Pressure::from_raw(0x1680)));
        assert_eq!("x".parse::<Pressure>(), Err(Error::Malformed));
    }

    /// The arithmetic the parser had before it doubled decimal digits: numerator and
    /// denominator of the fraction in u128.
    fn parse_fixed_u128(
        text: &str,
        bits: u32,
        rounding: Rounding,
    ) -> core::result::Result<i16, ParseError> {
        let (negative, body) = match text.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, text),
        };
        let (whole, fraction) = body.split_once('.').unwrap_or((body, ""));
        let whole: u128 = whole.parse().unwrap();
        if whole > 0xFFFF {
            return Err(ParseError::OutOfRange);
        }
        let fraction = fraction.trim_end_matches('0');
        if fraction.len() > MAX_FRACTION_DIGITS {
            return Err(ParseError::TooManyDigits);
        }
        let numerator: u128 = if fraction.is_empty() {
            0
        } else {
            fraction.parse().unwrap()
        };
        let denominator = 10u128.pow(fraction.len() as u32);
        let scaled = numerator << bits;
        let mut steps = (whole << bits) + scaled / denominator;
        let remainder = scaled % denominator;
        if remainder != 0 {
            if rounding == Rounding::Exact {
                return Err(ParseError::Inexact);
            }
            if remainder * 2 >= denominator {
                steps += 1;
            }
        }
        if steps > if negative { 0x8000 } else { 0x7FFF } {
            return Err(ParseError::OutOfRange);
        }
        Ok(if negative {
            (steps as i32).wrapping_neg()
        } else {
            steps as i32
        } as i16)
    }

    proptest::proptest! {
        #[test]
        fn parse_matches_wide_arithmetic(
            negative in proptest::bool::ANY,
            whole in 0u32..70_000,
            fraction in "[0-9]{0,34}",
            dot in proptest::bool::ANY,
            bits in proptest::sample::select(vec![0u32, 1, 6, 7, 12, 15]),
            exact in proptest::bool::ANY,
        ) {
            let rounding = if exact { Rounding::Exact } else { Rounding::Nearest };
            let mut text = std::format!("{}{whole}", if negative { "-" } else { "" });
            if dot && !fraction.is_empty() {
                text.push('.');
                text.push_str(&fraction);
            }
            proptest::prop_assert_eq!(
                parse_fixed(&text, bits, rounding),
                parse_fixed_u128(&text, bits, rounding),
                "{}", text
            );
        }
    }
}
