//! ASCII hex digits, both ways, by table lookup.

/// Upper-case digits; Modbus ASCII senders use upper case.
const DIGITS: &[u8; 16] = b"0123456789ABCDEF";

/// Class of a received character, from [`CLASS`]: 0..=15 are hex digit values.
pub(crate) const COLON: u8 = 0x10;
/// Carriage return.
pub(crate) const CR: u8 = 0x11;
/// Line feed.
pub(crate) const LF: u8 = 0x12;
/// Anything else.
pub(crate) const OTHER: u8 = 0xFF;

/// One lookup per received character: its digit value, or which delimiter it is.
///
/// A table keeps the decoder's hot loop to a load and a compare (see the modbus_decode bench).
pub(crate) static CLASS: [u8; 256] = build_class_table();

/// The class of one received character.
#[inline]
#[allow(clippy::indexing_slicing, reason = "a u8 indexes a 256-entry table")]
pub(crate) fn class(byte: u8) -> u8 {
    CLASS[usize::from(byte)]
}

#[allow(
    clippy::indexing_slicing,
    reason = "compile-time construction: every index is an ASCII code below 256"
)]
const fn build_class_table() -> [u8; 256] {
    let mut table = [OTHER; 256];
    let mut i = 0;
    while i < 10 {
        table[b'0' as usize + i] = i as u8;
        i += 1;
    }
    let mut i = 0;
    while i < 6 {
        table[b'A' as usize + i] = 10 + i as u8;
        table[b'a' as usize + i] = 10 + i as u8;
        i += 1;
    }
    table[b':' as usize] = COLON;
    table[b'\r' as usize] = CR;
    table[b'\n' as usize] = LF;
    table
}

/// The two upper-case characters of `byte`, high nibble first.
#[inline]
#[allow(clippy::indexing_slicing, reason = "a nibble indexes a 16-entry table")]
pub(crate) fn encode_byte(byte: u8) -> [u8; 2] {
    [
        DIGITS[usize::from(byte >> 4)],
        DIGITS[usize::from(byte & 0x0F)],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_byte_round_trips() {
        for b in 0..=255u8 {
            let [h, l] = encode_byte(b);
            assert!(h.is_ascii_hexdigit() && !h.is_ascii_lowercase());
            assert!(l.is_ascii_hexdigit() && !l.is_ascii_lowercase());
            let back = CLASS[usize::from(h)] << 4 | CLASS[usize::from(l)];
            assert_eq!(back, b);
        }
    }

    #[test]
    fn classes() {
        for c in 0..=255u8 {
            let expected = match c {
                b'0'..=b'9' => c - b'0',
                b'A'..=b'F' => c - b'A' + 10,
                b'a'..=b'f' => c - b'a' + 10,
                b':' => COLON,
                b'\r' => CR,
                b'\n' => LF,
                _ => OTHER,
            };
            assert_eq!(CLASS[usize::from(c)], expected, "char {c:#04x}");
        }
    }
}
