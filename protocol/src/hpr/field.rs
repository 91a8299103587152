//! Text fields inside a frame's data: decimal numbers, space-delimited lists, tagged values.
//!
//! Parsers are strict about characters (digits only, single spaces) and lenient about zero
//! padding: the supplies pad most values to four digits, the manual's requests do not, and a
//! value means the same either way. Writers produce the padding the manual's samples show.

use super::frame::MAX_DATA_LEN;
use crate::decimal::parse_decimal;
use crate::{Error, Result};

/// Builds a data field in a fixed buffer.
pub(crate) struct DataWriter {
    buf: [u8; MAX_DATA_LEN],
    len: usize,
}

impl DataWriter {
    pub(crate) const fn new() -> Self {
        DataWriter {
            buf: [0; MAX_DATA_LEN],
            len: 0,
        }
    }

    pub(crate) fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    pub(crate) fn byte(&mut self, b: u8) -> Result<()> {
        let slot = self.buf.get_mut(self.len).ok_or(Error::Overlong)?;
        *slot = b;
        self.len += 1;
        Ok(())
    }

    pub(crate) fn bytes(&mut self, bs: &[u8]) -> Result<()> {
        bs.iter().try_for_each(|&b| self.byte(b))
    }

    /// Space before every field but the first.
    pub(crate) fn separator(&mut self) -> Result<()> {
        if self.len > 0 {
            self.byte(b' ')
        } else {
            Ok(())
        }
    }

    /// `value` in decimal, zero-padded to at least `min_width` digits and refused
    /// ([`Error::Malformed`]) if it needs more than `max_width`.
    pub(crate) fn decimal(&mut self, value: u32, min_width: usize, max_width: usize) -> Result<()> {
        let mut digits = [0u8; 10];
        let mut n = 0;
        let mut v = value;
        loop {
            let slot = digits.get_mut(n).ok_or(Error::Malformed)?;
            // v % 10 < 10: the cast cannot truncate.
            *slot = b'0' + (v % 10) as u8;
            n += 1;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        if n > max_width {
            return Err(Error::Malformed);
        }
        for _ in n..min_width {
            self.byte(b'0')?;
        }
        digits
            .get(..n)
            .ok_or(Error::Malformed)?
            .iter()
            .rev()
            .try_for_each(|&d| self.byte(d))
    }

    /// A tagged value such as `PC0044`: tag then exactly `width` digits.
    pub(crate) fn tagged(&mut self, tag: &[u8], value: u32, width: usize) -> Result<()> {
        self.separator()?;
        self.bytes(tag)?;
        self.decimal(value, width, width)
    }

    /// A space-separated decimal field.
    pub(crate) fn field(&mut self, value: u32, min_width: usize, max_width: usize) -> Result<()> {
        self.separator()?;
        self.decimal(value, min_width, max_width)
    }
}

/// Parse a decimal and check it against an inclusive range.
pub(crate) fn parse_in<T: TryFrom<u32>>(
    text: &[u8],
    max_digits: usize,
    min: u32,
    max: u32,
) -> Result<T> {
    let v = parse_decimal(text, max_digits)?;
    if v < min || v > max {
        return Err(Error::Malformed);
    }
    T::try_from(v).map_err(|_| Error::Malformed)
}

/// Splits data into space-separated fields; an empty field (double space, leading or
/// trailing space) is an error reported by [`Fields::next_field`].
pub(crate) struct Fields<'a> {
    rest: Option<&'a [u8]>,
}

impl<'a> Fields<'a> {
    pub(crate) fn new(data: &'a [u8]) -> Self {
        Fields { rest: Some(data) }
    }

    pub(crate) fn next_field(&mut self) -> Result<&'a [u8]> {
        let rest = self.rest.ok_or(Error::Malformed)?;
        let (field, tail) = match rest.iter().position(|&b| b == b' ') {
            Some(i) => (rest.get(..i), rest.get(i + 1..)),
            None => (Some(rest), None),
        };
        self.rest = tail;
        match field {
            Some(f) if !f.is_empty() => Ok(f),
            _ => Err(Error::Malformed),
        }
    }

    /// Next field as a number of at most `max_digits` digits within `min..=max`.
    pub(crate) fn number<T: TryFrom<u32>>(
        &mut self,
        max_digits: usize,
        min: u32,
        max: u32,
    ) -> Result<T> {
        parse_in(self.next_field()?, max_digits, min, max)
    }

    /// Next field as `tag` followed by 1..=`max_digits` digits.
    pub(crate) fn tagged<T: TryFrom<u32>>(&mut self, tag: &[u8], max_digits: usize) -> Result<T> {
        let field = self.next_field()?;
        let digits = field.strip_prefix(tag).ok_or(Error::Malformed)?;
        parse_in(digits, max_digits, 0, u32::MAX)
    }

    /// Fields left (0 once the data is used up).
    pub(crate) fn remaining(&self) -> usize {
        self.rest
            .map_or(0, |r| r.iter().filter(|&&b| b == b' ').count() + 1)
    }

    /// Succeeds only if every field was consumed.
    pub(crate) fn end(&self) -> Result<()> {
        if self.rest.is_none() {
            Ok(())
        } else {
            Err(Error::Malformed)
        }
    }
}

/// Count of space-separated fields in `data` (0 for empty data).
pub(crate) fn field_count(data: &[u8]) -> usize {
    if data.is_empty() {
        0
    } else {
        Fields::new(data).remaining()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_padding() {
        let mut w = DataWriter::new();
        w.field(7, 4, 4).unwrap();
        w.field(130, 1, 3).unwrap();
        w.field(0, 2, 3).unwrap();
        assert_eq!(w.as_bytes(), b"0007 130 00");
        assert_eq!(w.field(10000, 4, 4), Err(Error::Malformed));
    }

    #[test]
    fn fields_split_strictly() {
        let mut f = Fields::new(b"1 22  3");
        assert_eq!(f.next_field(), Ok(&b"1"[..]));
        assert_eq!(f.next_field(), Ok(&b"22"[..]));
        assert_eq!(f.next_field(), Err(Error::Malformed));
        let mut f = Fields::new(b"PC0044");
        assert_eq!(f.tagged::<u16>(b"PC", 4), Ok(44));
        assert!(f.end().is_ok());
        assert_eq!(
            Fields::new(b"PP0044").tagged::<u16>(b"PC", 4),
            Err(Error::Malformed)
        );
        assert_eq!(parse_in::<u8>(b"300", 3, 0, 999), Err(Error::Malformed));
        assert_eq!(field_count(b""), 0);
        assert_eq!(field_count(b"1 6"), 2);
    }
}
