//! The settings record: the bytes stored under the settings key.
//!
//! ```text
//! offset  size  field
//! 0       1     record format (RECORD_FORMAT): the layout of this envelope
//! 1       1     settings version: which `Persistent` encoding the payload uses
//! 2       4     sequence number, little endian: +1 per save, the higher copy wins
//! 6       n     payload, 0..=MAX_PAYLOAD bytes, written by `Persistent::encode`
//! ```
//!
//! There is no checksum here: sequential-storage already protects every item's length with a
//! CRC-16 and its data with a CRC-32, and skips an item whose data CRC fails (which is what a
//! write torn by a power cut looks like), so the newest *complete* record is the one read.

/// Layout of the envelope. A record with another first byte was not written by this code.
pub const RECORD_FORMAT: u8 = 1;

/// Largest payload a settings encoding may produce.
pub const MAX_PAYLOAD: usize = 256;

/// Envelope bytes before the payload.
pub const HEADER_LEN: usize = 6;

/// Largest record.
pub const MAX_RECORD: usize = HEADER_LEN + MAX_PAYLOAD;

/// A decoded record, borrowing its payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Record<'a> {
    /// The settings version the payload was encoded with.
    pub version: u8,
    /// Save counter: of two copies, the one with the higher sequence is newer.
    pub sequence: u32,
    /// The encoded settings.
    pub payload: &'a [u8],
}

/// Why bytes are not a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecordError {
    /// Shorter than the envelope header.
    Truncated,
    /// The first byte is not [`RECORD_FORMAT`].
    UnknownFormat(u8),
    /// A payload longer than [`MAX_PAYLOAD`] (to encode) or than the buffer (to decode).
    TooLarge,
}

impl<'a> Record<'a> {
    /// Parses a stored record.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, RecordError> {
        match bytes {
            [RECORD_FORMAT, version, s0, s1, s2, s3, payload @ ..] => {
                if payload.len() > MAX_PAYLOAD {
                    return Err(RecordError::TooLarge);
                }
                Ok(Record {
                    version: *version,
                    sequence: u32::from_le_bytes([*s0, *s1, *s2, *s3]),
                    payload,
                })
            }
            [format, ..] if *format != RECORD_FORMAT => Err(RecordError::UnknownFormat(*format)),
            _ => Err(RecordError::Truncated),
        }
    }

    /// Writes the record into `out`, returning its length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, RecordError> {
        if self.payload.len() > MAX_PAYLOAD {
            return Err(RecordError::TooLarge);
        }
        let len = HEADER_LEN + self.payload.len();
        let out = out.get_mut(..len).ok_or(RecordError::TooLarge)?;
        let (header, payload) = out.split_at_mut(HEADER_LEN);
        let [s0, s1, s2, s3] = self.sequence.to_le_bytes();
        header.copy_from_slice(&[RECORD_FORMAT, self.version, s0, s1, s2, s3]);
        payload.copy_from_slice(self.payload);
        Ok(len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emit_then_parse() {
        let mut buf = [0u8; 10];
        let record = Record {
            version: 3,
            sequence: 0x0102_0304,
            payload: &[0xAA, 0x55],
        };
        assert_eq!(record.emit(&mut buf), Ok(8));
        assert_eq!(&buf[..8], &[0x01, 0x03, 0x04, 0x03, 0x02, 0x01, 0xAA, 0x55]);
        assert_eq!(Record::parse(&buf[..8]), Ok(record));
    }

    #[test]
    fn empty_payload_is_a_record() {
        assert_eq!(
            Record::parse(&[0x01, 0x07, 0xFF, 0, 0, 0]),
            Ok(Record {
                version: 7,
                sequence: 255,
                payload: &[]
            })
        );
    }

    #[test]
    fn rejects_what_this_code_did_not_write() {
        assert_eq!(Record::parse(&[]), Err(RecordError::Truncated));
        assert_eq!(Record::parse(&[0x01]), Err(RecordError::Truncated));
        assert_eq!(
            Record::parse(&[0x01, 0x07, 0, 0, 0]),
            Err(RecordError::Truncated)
        );
        assert_eq!(
            Record::parse(&[0x02, 0x01, 0x00]),
            Err(RecordError::UnknownFormat(2))
        );
        assert_eq!(
            Record::parse(&[0xFF; 4]),
            Err(RecordError::UnknownFormat(0xFF))
        );
        let mut long = [0u8; MAX_RECORD + 1];
        long[0] = RECORD_FORMAT;
        assert_eq!(Record::parse(&long), Err(RecordError::TooLarge));
        assert!(Record::parse(&long[..MAX_RECORD]).is_ok());
    }

    #[test]
    fn emit_checks_sizes() {
        let big = [0u8; MAX_PAYLOAD + 1];
        let mut out = [0u8; MAX_RECORD + 8];
        let too_big = Record {
            version: 1,
            sequence: 0,
            payload: &big,
        };
        assert_eq!(too_big.emit(&mut out), Err(RecordError::TooLarge));
        let fits = Record {
            version: 1,
            sequence: 0,
            payload: &big[..4],
        };
        assert_eq!(fits.emit(&mut out[..9]), Err(RecordError::TooLarge));
        assert_eq!(fits.emit(&mut out[..10]), Ok(10));
    }
}
