use core::fmt;

/// Why a frame or value was rejected.
///
/// One small error type for every wire format in this crate (as smoltcp's `wire::Error`).
/// Variants are distinct so that link diagnostics can count each kind separately.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The frame ended before all of its fields were present.
    Truncated,
    /// A character that must be a hexadecimal digit was not.
    NonHex,
    /// A hex-encoded field had an odd number of characters.
    OddLength,
    /// The checksum (Modbus LRC, HPR sum, Phoenix XOR) did not match.
    BadChecksum {
        /// Checksum computed over the received bytes.
        expected: u8,
        /// Checksum carried by the frame.
        found: u8,
    },
    /// The frame was longer than the protocol allows (or than the decoder's buffer).
    Overlong,
    /// A field holds a value the protocol does not allow (bad byte count, quantity, id, ...).
    Malformed,
    /// A function, command or object this crate does not implement.
    Unsupported,
    /// The caller's output buffer is too small for the encoded frame.
    BufferTooSmall,
    /// A reply that does not answer the request it was matched with.
    Mismatch,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Truncated => f.write_str("frame truncated"),
            Error::NonHex => f.write_str("non-hex character"),
            Error::OddLength => f.write_str("odd number of hex characters"),
            Error::BadChecksum { expected, found } => {
                write!(
                    f,
                    "bad checksum: expected {expected:02X}, found {found:02X}"
                )
            }
            Error::Overlong => f.write_str("frame too long"),
            Error::Malformed => f.write_str("malformed field"),
            Error::Unsupported => f.write_str("unsupported function or command"),
            Error::BufferTooSmall => f.write_str("output buffer too small"),
            Error::Mismatch => f.write_str("reply does not match request"),
        }
    }
}

impl core::error::Error for Error {}

/// Shorthand used throughout the crate.
pub type Result<T> = core::result::Result<T, Error>;
