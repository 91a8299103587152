//! Small big-endian readers and a bounds-checked writer shared by the PDU parsers and emitters.

use crate::{Error, Result};

/// Splits `data` into two big-endian words, the body of most fixed-size PDUs.
///
/// Shorter input is [`Error::Truncated`], longer input [`Error::Malformed`].
pub(crate) fn two_words(data: &[u8]) -> Result<(u16, u16)> {
    match *data {
        [a0, a1, b0, b1] => Ok((u16::from_be_bytes([a0, a1]), u16::from_be_bytes([b0, b1]))),
        _ if data.len() < 4 => Err(Error::Truncated),
        _ => Err(Error::Malformed),
    }
}

/// Checks that `data` holds exactly `expected` bytes.
pub(crate) fn exact_len(data: &[u8], expected: usize) -> Result<()> {
    match data.len() {
        n if n < expected => Err(Error::Truncated),
        n if n > expected => Err(Error::Malformed),
        _ => Ok(()),
    }
}

/// `Ok` when `quantity` is in `1..=max`.
pub(crate) fn check_quantity(quantity: u16, max: u16) -> Result<()> {
    if (1..=max).contains(&quantity) {
        Ok(())
    } else {
        Err(Error::Malformed)
    }
}

/// The 16-bit value Write Single Coil carries for `on`.
pub(crate) const fn coil_value(on: bool) -> u16 {
    if on { 0xFF00 } else { 0x0000 }
}

/// Decodes a Write Single Coil value: only 0xFF00 and 0x0000 are allowed.
pub(crate) fn coil_state(value: u16) -> Result<bool> {
    match value {
        0xFF00 => Ok(true),
        0x0000 => Ok(false),
        _ => Err(Error::Malformed),
    }
}

/// Appends bytes to a caller's buffer, failing with [`Error::BufferTooSmall`] instead of
/// panicking when it is full.
pub(crate) struct Writer<'a> {
    out: &'a mut [u8],
    len: usize,
}

impl<'a> Writer<'a> {
    pub(crate) fn new(out: &'a mut [u8]) -> Self {
        Writer { out, len: 0 }
    }

    pub(crate) fn u8(&mut self, byte: u8) -> Result<()> {
        let slot = self.out.get_mut(self.len).ok_or(Error::BufferTooSmall)?;
        *slot = byte;
        self.len += 1;
        Ok(())
    }

    pub(crate) fn u16(&mut self, word: u16) -> Result<()> {
        self.bytes(&word.to_be_bytes())
    }

    pub(crate) fn bytes(&mut self, bytes: &[u8]) -> Result<()> {
        let end = self
            .len
            .checked_add(bytes.len())
            .ok_or(Error::BufferTooSmall)?;
        let slot = self
            .out
            .get_mut(self.len..end)
            .ok_or(Error::BufferTooSmall)?;
        slot.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    /// Bytes written so far.
    pub(crate) fn len(&self) -> usize {
        self.len
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_words_lengths() {
        assert_eq!(two_words(&[0x30, 0x44, 0x00, 0x04]), Ok((0x3044, 4)));
        assert_eq!(two_words(&[0x30, 0x44, 0x00]), Err(Error::Truncated));
        assert_eq!(
            two_words(&[0x30, 0x44, 0x00, 0x04, 0x00]),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn writer_stops_at_the_end() {
        let mut buf = [0u8; 3];
        let mut w = Writer::new(&mut buf);
        assert_eq!(w.u16(0x1234), Ok(()));
        assert_eq!(w.u16(0x5678), Err(Error::BufferTooSmall));
        assert_eq!(w.u8(0x56), Ok(()));
        assert_eq!(w.u8(0x78), Err(Error::BufferTooSmall));
        assert_eq!(w.len(), 3);
        assert_eq!(buf, [0x12, 0x34, 0x56]);
    }

    #[test]
    fn coil_values() {
        assert_eq!(coil_state(coil_value(true)), Ok(true));
        assert_eq!(coil_state(coil_value(false)), Ok(false));
        assert_eq!(coil_state(0x00FF), Err(Error::Malformed));
        assert_eq!(coil_state(0x0001), Err(Error::Malformed));
    }
}
