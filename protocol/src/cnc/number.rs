//! Exact fixed-point values: amps in 1/64 A and psi in 1/128 psi, the units the Powermax
//! registers use ("current is amps x 64, pressure is psi x 128"), so a value typed on the CNC
//! reaches the power supply unchanged.

use core::fmt;

/// Why a decimal number was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NumberError {
    /// Not `digits[.digits]`.
    Syntax,
    /// Too large to be anything the protocol accepts.
    TooLarge,
    /// Not a multiple of the step.
    Inexact,
}

/// Parse a non-negative decimal (`45`, `45.5`, `0.015625`) into multiples of
/// `1/denominator`; the value must be an exact multiple.
pub(crate) fn parse_fixed(text: &str, denominator: u32) -> Result<u32, NumberError> {
    let (int, frac) = match text.split_once('.') {
        Some((int, frac)) if !frac.is_empty() => (int, frac),
        Some(_) => return Err(NumberError::Syntax),
        None => (text, ""),
    };
    let is_digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if int.is_empty() || !is_digits(int) || !is_digits(frac) {
        return Err(NumberError::Syntax);
    }
    let int = int.trim_start_matches('0');
    let frac = frac.trim_end_matches('0');
    // Six integer digits are far above any bound; fractions of 1/2^k need at most k digits.
    if int.len() > 6 {
        return Err(NumberError::TooLarge);
    }
    if frac.len() > 9 {
        return Err(NumberError::Inexact);
    }
    let value = |s: &str| s.bytes().fold(0u64, |a, b| a * 10 + u64::from(b - b'0'));
    let scale = 10u64.pow(frac.len() as u32);
    let den = u64::from(denominator);
    let frac_scaled = value(frac) * den;
    if frac_scaled % scale != 0 {
        return Err(NumberError::Inexact);
    }
    let total = value(int) * den + frac_scaled / scale;
    u32::try_from(total).map_err(|_| NumberError::TooLarge)
}

/// Write `raw / 2^shift` as an exact decimal, without trailing zeros.
fn write_binary_fraction(f: &mut fmt::Formatter<'_>, raw: u16, shift: u32) -> fmt::Result {
    let whole = raw >> shift;
    let rest = u32::from(raw) & ((1 << shift) - 1);
    write!(f, "{whole}")?;
    if rest == 0 {
        return Ok(());
    }
    // rest / 2^shift = rest * 5^shift / 10^shift: exactly `shift` decimal digits.
    let mut digits = rest * 5u32.pow(shift);
    let mut width = shift as usize;
    // Drop trailing zeros (digits is never 0 here, so this ends). `is_multiple_of` is newer
    // than the workspace's rust-version.
    #[allow(clippy::manual_is_multiple_of)]
    while digits % 10 == 0 {
        digits /= 10;
        width -= 1;
    }
    write!(f, ".{digits:0width$}")
}

/// A current setpoint in 1/64 A (the Powermax register unit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Amps(u16);

impl Amps {
    /// Lowest current any supported supply accepts (HPR: 5 A).
    pub const MIN: Amps = Amps(5 * 64);
    /// Highest current any supported supply accepts (HPR400: 400 A).
    pub const MAX: Amps = Amps(400 * 64);
    /// The bounds as written in an error reply.
    pub const RANGE_TEXT: &'static str = "5..400";

    /// From the register value (amps x 64).
    pub const fn from_64ths(raw: u16) -> Amps {
        Amps(raw)
    }

    /// Whole amps.
    pub const fn from_whole(amps: u16) -> Option<Amps> {
        match amps.checked_mul(64) {
            Some(raw) => Some(Amps(raw)),
            None => None,
        }
    }

    /// The register value (amps x 64).
    pub const fn as_64ths(self) -> u16 {
        self.0
    }

    /// Whole amps, rounded to nearest (for supplies that take whole amps, such as the HPR).
    pub const fn round_whole(self) -> u16 {
        ((self.0 as u32 + 32) / 64) as u16
    }

    /// Whether the value is whole amps.
    pub const fn is_whole(self) -> bool {
        self.0 & 63 == 0
    }
}

impl fmt::Display for Amps {
    /// The exact value in amps: `45`, `55.5`, `45.015625`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_binary_fraction(f, self.0, 6)
    }
}

/// A gas pressure in 1/128 psi (the Powermax register unit).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Psi(u16);

impl Psi {
    /// Lowest explicit pressure (0 means automatic on a Powermax: write `AUTO`).
    pub const MIN: Psi = Psi(128);
    /// Highest pressure accepted (above any supported supply's setpoint range).
    pub const MAX: Psi = Psi(150 * 128);
    /// The bounds as written in an error reply.
    pub const RANGE_TEXT: &'static str = "1..150";

    /// From the register value (psi x 128).
    pub const fn from_128ths(raw: u16) -> Psi {
        Psi(raw)
    }

    /// The register value (psi x 128).
    pub const fn as_128ths(self) -> u16 {
        self.0
    }

    /// Whole psi, rounded to nearest.
    pub const fn round_whole(self) -> u16 {
        ((self.0 as u32 + 64) / 128) as u16
    }
}

impl fmt::Display for Psi {
    /// The exact value in psi: `72`, `72.5`, `0.0078125`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write_binary_fraction(f, self.0, 7)
    }
}

/// A pressure setting: explicit, or chosen by the power supply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Pressure {
    /// The supply picks the pressure (register value 0).
    Auto,
    /// An explicit pressure.
    Psi(Psi),
}

impl Pressure {
    /// The Powermax register value: psi x 128, 0 for automatic.
    pub const fn as_128ths(self) -> u16 {
        match self {
            Pressure::Auto => 0,
            Pressure::Psi(psi) => psi.as_128ths(),
        }
    }
}

impl fmt::Display for Pressure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Pressure::Auto => f.write_str("AUTO"),
            Pressure::Psi(psi) => psi.fmt(f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;

    fn show(v: impl fmt::Display) -> heapless::String<32> {
        let mut s = heapless::String::new();
        write!(s, "{v}").unwrap();
        s
    }

    #[test]
    fn decimals_are_exact() {
        assert_eq!(parse_fixed("55.5", 64), Ok(3552));
        assert_eq!(parse_fixed("45", 64), Ok(2880));
        assert_eq!(parse_fixed("045.50", 64), Ok(2912));
        assert_eq!(parse_fixed("0.015625", 64), Ok(1));
        assert_eq!(parse_fixed("0.0078125", 128), Ok(1));
        assert_eq!(parse_fixed("72.25", 128), Ok(9248));
        assert_eq!(parse_fixed("45.1", 64), Err(NumberError::Inexact));
        assert_eq!(parse_fixed("0.0078125", 64), Err(NumberError::Inexact));
        assert_eq!(parse_fixed("1.0000000001", 64), Err(NumberError::Inexact));
        assert_eq!(parse_fixed("1.50000000000000", 64), Ok(96));
        assert_eq!(parse_fixed("99999999", 64), Err(NumberError::TooLarge));
        assert_eq!(parse_fixed("0000000000045", 64), Ok(2880));
        for bad in [
            "", ".", ".5", "5.", "-5", "+5", "4 5", "1e3", "4.5.1", "0x10", "٣",
        ] {
            assert_eq!(parse_fixed(bad, 64), Err(NumberError::Syntax), "{bad}");
        }
    }

    #[test]
    fn display_is_exact() {
        assert_eq!(show(Amps::from_64ths(3552)), "55.5");
        assert_eq!(show(Amps::from_64ths(2880)), "45");
        assert_eq!(show(Amps::from_64ths(2881)), "45.015625");
        assert_eq!(show(Psi::from_128ths(9248)), "72.25");
        assert_eq!(show(Psi::from_128ths(1)), "0.0078125");
        assert_eq!(show(Pressure::Auto), "AUTO");
        assert_eq!(show(Amps::MAX), "400");
        assert_eq!(show(Amps::from_64ths(u16::MAX)), "1023.984375");
    }

    #[test]
    fn conversions() {
        assert_eq!(Amps::from_whole(45).map(Amps::as_64ths), Some(2880));
        assert_eq!(Amps::from_whole(1024), None);
        assert_eq!(Amps::from_64ths(3552).round_whole(), 56);
        assert!(!Amps::from_64ths(3552).is_whole());
        assert_eq!(Pressure::Auto.as_128ths(), 0);
        assert_eq!(Pressure::Psi(Psi::from_128ths(9216)).as_128ths(), 9216);
        assert_eq!(Psi::from_128ths(9216).round_whole(), 72);
        assert_eq!(Amps::from_64ths(u16::MAX).round_whole(), 1024);
        assert_eq!(Psi::from_128ths(u16::MAX).round_whole(), 512);
    }
}
