//! Unsigned decimal integers in text fields (HPR data fields and ids, Phoenix program fields):
//! the one digit-run parser those formats share. Fixed-point amps and psi are in
//! [`units`](crate::units).

use crate::{Error, Result};

/// Decimal digits only (no sign, no point, no spaces), 1..=`max_digits` of them and never more
/// than 9, so the value always fits a `u32`.
pub(crate) fn parse_decimal(text: &[u8], max_digits: usize) -> Result<u32> {
    if text.is_empty() || text.len() > max_digits || text.len() > 9 {
        return Err(Error::Malformed);
    }
    text.iter().try_fold(0u32, |acc, &b| {
        if b.is_ascii_digit() {
            Ok(acc * 10 + u32::from(b - b'0'))
        } else {
            Err(Error::Malformed)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn digits_only_and_bounded() {
        assert_eq!(parse_decimal(b"0044", 4), Ok(44));
        assert_eq!(parse_decimal(b"7", 3), Ok(7));
        assert_eq!(parse_decimal(b"999999999", 20), Ok(999_999_999));
        assert_eq!(parse_decimal(b"1000000000", 20), Err(Error::Malformed));
        assert_eq!(parse_decimal(b"", 4), Err(Error::Malformed));
        assert_eq!(parse_decimal(b"12345", 4), Err(Error::Malformed));
        for bad in [&b"1a"[..], b"-1", b"+1", b"1.0", b" 1", b"1 "] {
            assert_eq!(parse_decimal(bad, 4), Err(Error::Malformed));
        }
    }
}
