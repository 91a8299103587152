//! Longitudinal redundancy check of Modbus ASCII frames.

/// LRC of `bytes`: the two's complement of their 8-bit sum.
///
/// It is computed over the binary bytes (address, function, data), never over the ASCII
/// characters. Adding the LRC to that sum gives zero, which is how a receiver may check it.
///
/// ```
/// use plasma_protocol::modbus_ascii::lrc;
/// // The worked example of the SYNC guide: `:01043044000483`.
/// assert_eq!(lrc(&[0x01, 0x04, 0x30, 0x44, 0x00, 0x04]), 0x83);
/// ```
pub fn lrc(bytes: &[u8]) -> u8 {
    bytes
        .iter()
        .fold(0u8, |sum, &b| sum.wrapping_add(b))
        .wrapping_neg()
}

#[cfg(test)]
mod tests {
    use super::lrc;

    #[test]
    fn sync_guide_worked_example() {
        // 0x01 + 0x04 + 0x30 + 0x44 + 0x00 + 0x04 = 0x7D; 0xFF - 0x7D + 1 = 0x83.
        assert_eq!(lrc(&[0x01, 0x04, 0x30, 0x44, 0x00, 0x04]), 0x83);
    }

    #[test]
    fn legacy_manual_worked_example() {
        // `:010108080001ED`: 0x01 + 0x01 + 0x08 + 0x08 + 0x00 + 0x01 = 0x13; 0xFF - 0x13 + 1 = 0xED.
        assert_eq!(lrc(&[0x01, 0x01, 0x08, 0x08, 0x00, 0x01]), 0xED);
    }

    #[test]
    fn sum_over_ff_keeps_the_low_byte() {
        // 0xFF + 0x02 = 0x101: the manual's rule "subtract the last two digits from FF" then +1.
        assert_eq!(lrc(&[0xFF, 0x02]), 0xFF);
        // Fault log reply: 01 + 04 + 08 + 79 + 79 = 0xFF -> 0x01.
        assert_eq!(
            lrc(&[0x01, 0x04, 0x08, 0x00, 0x79, 0x00, 0x79, 0, 0, 0, 0]),
            0x01
        );
    }

    #[test]
    fn empty_and_zero_sum() {
        assert_eq!(lrc(&[]), 0x00);
        assert_eq!(lrc(&[0x80, 0x80]), 0x00);
    }

    #[test]
    fn message_plus_lrc_sums_to_zero() {
        let msg = [
            0x01, 0x10, 0x30, 0x80, 0x00, 0x03, 0x06, 0x00, 0x01, 0x0F, 0xC0, 0x00, 0x00,
        ];
        let sum = msg.iter().fold(lrc(&msg), |s: u8, &b| s.wrapping_add(b));
        assert_eq!(sum, 0);
        assert_eq!(lrc(&msg), 0x66);
    }
}
