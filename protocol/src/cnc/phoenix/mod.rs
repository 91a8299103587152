//! Phoenix serial messaging, as a Hypertherm Phoenix (V9.5) CNC sends it.
//!
//! A part program line such as `(>22,113<SET AMPS 45)` makes the CNC send `SET AMPS 45`
//! through a messaging port, wrapped according to the *format value* (here 113 = CR LF,
//! check byte, STX/ETX and SOH/EOT). Message type 22 then waits for [`ACK`] from the external
//! device, and a [`NAK`] makes the CNC send the message again.
//!
//! - [`Format`]: the sixteen format values and the bytes each adds, [`frame`] to wrap a payload,
//!   [`check_byte`] for the XOR check byte.
//! - [`Deframer`]: a streaming, fixed-buffer receiver that yields the payload of each message
//!   or the reason it was refused, so that the bridge can answer [`ACK`] or [`NAK`].
//! - [`decode_escapes`] / [`encode_escapes`]: the two-character codes (`&A`, `!A`, `$A`, `&&`,
//!   `&h`, ...) a part program uses to write bytes it cannot hold.
//! - [`ProgramMessage`]: the `>2x,format,delay,port<text` command as written in a part program.
//!
//! # Telling a framed message from a text line
//! Text command lines never contain control bytes: they are printable ASCII ended by CR, LF or
//! CR LF. A framed message always starts with SOH (format 64 and up) or STX (32..=49), bytes a
//! text line cannot start with. So a receiver that is between two inputs routes a SOH/STX byte
//! to a [`Deframer`] and everything else to a
//! [`LineAssembler`](crate::cnc::line::LineAssembler), see [`is_frame_start`]. Formats without
//! SOH/STX cannot be told apart that way: format 1 (CR LF) looks like a text line, and formats
//! 0, 16 and 17 like any bytes, so a receiver takes them only when told to expect them (the
//! bridge's `phoenix_format`), and then reads every input that does not open with SOH/STX as
//! a message of that format.
//!
//! # Which message to ACK
//! The message type (20, 21, 22) is in the part program, not on the wire: a type-22 message
//! is framed like the others and the CNC then waits for [`ACK`]. So a receiver ACKs every
//! message its [`Deframer`] takes, in any of the sixteen formats (types 20 and 21 do not wait
//! for it), format 1 included, where a message is a CR LF line: a port expecting format 1
//! reads its lines as messages, not as text commands.
//!
//! # Byte order, where the manual is silent
//! The manual fixes that CR LF comes right after the message, inside ETX, and that ETX
//! precedes the check byte. It does not say where SOH/EOT go relative to STX/ETX and the check
//! byte. This module puts SOH/EOT outermost and the check byte last:
//!
//! `[SOH] [STX] message [CR LF] [ETX] [EOT] [BCC]`
//!
//! Keeping the check byte last (as the manual does for ETX) means it is always read by
//! position, so a check byte that happens to equal EOT or LF cannot end a frame early.

mod deframe;
mod escape;
mod program;

pub use deframe::Deframer;
pub use escape::{decode_escapes, encode_escapes, unescape_pair};
pub use program::{MessageType, ProgramMessage};

use crate::{Error, Result};

/// Start of Header: first byte of formats 64..=113.
pub const SOH: u8 = 0x01;
/// Start of Text: first byte (after SOH) of formats 32..=49 and 96..=113.
pub const STX: u8 = 0x02;
/// End of Text: follows the message and its optional CR LF.
pub const ETX: u8 = 0x03;
/// End of Transmission: closes formats 64..=113.
pub const EOT: u8 = 0x04;
/// Acknowledge: the external device accepted a type-22 message.
pub const ACK: u8 = 0x06;
/// Negative acknowledge: the CNC sends the type-22 message again.
pub const NAK: u8 = 0x15;
/// Carriage return, appended with LF by format bit 1.
pub const CR: u8 = 0x0D;
/// Line feed.
pub const LF: u8 = 0x0A;

/// The longest message the CNC sends: 300 characters per command string, including the
/// `>..<` command characters (so the payload itself is always shorter).
pub const MAX_MESSAGE_LEN: usize = 300;

/// A Phoenix "Optional Format Value": which bytes the CNC adds around a message.
///
/// The value is the sum of independent options, as listed in the manual's "Optional Format
/// Character Assignments":
///
/// | bit | option | bytes |
/// |---|---|---|
/// | 1 | [`Format::CR_LF`] | CR LF appended to the message |
/// | 16 | [`Format::CHECK_BYTE`] | XOR check byte of the message, last |
/// | 32 | [`Format::STX_ETX`] | STX before, ETX after the message and its CR LF |
/// | 64 | [`Format::SOH_EOT`] | SOH first, EOT after everything but the check byte |
///
/// Supported values: 0, 1, 16, 17, 32, 33, 48, 49, 64, 65, 80, 81, 96, 97, 112, 113.
/// (The OCR'd V9.5 table lost the "1" in front of "Append a Carriage Return ... and a Line
/// Feed"; the list of supported values and the sums 17, 33, ... restore it.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Format(u8);

impl Format {
    /// Option bit: append CR LF.
    pub const CR_LF: u8 = 1;
    /// Option bit: append the XOR check byte.
    pub const CHECK_BYTE: u8 = 16;
    /// Option bit: enclose in STX .. ETX.
    pub const STX_ETX: u8 = 32;
    /// Option bit: enclose in SOH .. EOT.
    pub const SOH_EOT: u8 = 64;

    const ALL_BITS: u8 = Self::CR_LF | Self::CHECK_BYTE | Self::STX_ETX | Self::SOH_EOT;

    /// Format 0: the message alone.
    pub const PLAIN: Format = Format(0);

    /// Every supported format, in increasing value.
    pub const ALL: [Format; 16] = [
        Format(0),
        Format(1),
        Format(16),
        Format(17),
        Format(32),
        Format(33),
        Format(48),
        Format(49),
        Format(64),
        Format(65),
        Format(80),
        Format(81),
        Format(96),
        Format(97),
        Format(112),
        Format(113),
    ];

    /// The format for a value written in a part program; [`Error::Malformed`] for a value
    /// that is not one of the sixteen supported sums.
    pub const fn from_value(value: u8) -> Result<Format> {
        if value & !Self::ALL_BITS == 0 {
            Ok(Format(value))
        } else {
            Err(Error::Malformed)
        }
    }

    /// The value as written in a part program.
    pub const fn value(self) -> u8 {
        self.0
    }

    /// CR LF follows the message.
    pub const fn cr_lf(self) -> bool {
        self.0 & Self::CR_LF != 0
    }

    /// An XOR check byte closes the frame.
    pub const fn check_byte(self) -> bool {
        self.0 & Self::CHECK_BYTE != 0
    }

    /// The message (and its CR LF) is enclosed in STX .. ETX.
    pub const fn stx_etx(self) -> bool {
        self.0 & Self::STX_ETX != 0
    }

    /// The frame is enclosed in SOH .. EOT.
    pub const fn soh_eot(self) -> bool {
        self.0 & Self::SOH_EOT != 0
    }

    /// The byte that opens a frame: SOH, else STX, else none (the frame starts with the
    /// message itself).
    pub const fn start_byte(self) -> Option<u8> {
        if self.soh_eot() {
            Some(SOH)
        } else if self.stx_etx() {
            Some(STX)
        } else {
            None
        }
    }

    /// How many bytes the format adds to a message.
    pub const fn overhead(self) -> usize {
        2 * self.cr_lf() as usize
            + self.check_byte() as usize
            + 2 * self.stx_etx() as usize
            + 2 * self.soh_eot() as usize
    }

    /// Whether `byte` may not appear in a message sent with this format, because the
    /// receiver would take it for part of the framing (a start byte that restarts the
    /// frame, or the byte that ends it).
    pub const fn is_reserved(self, byte: u8) -> bool {
        if self.soh_eot() && (byte == SOH || byte == EOT) {
            return true;
        }
        if self.stx_etx() && (byte == STX || byte == ETX) {
            return true;
        }
        // Without SOH/STX a CR LF format ends at the first LF.
        !self.soh_eot() && !self.stx_etx() && self.cr_lf() && byte == LF
    }
}

impl TryFrom<u8> for Format {
    type Error = Error;
    fn try_from(value: u8) -> Result<Format> {
        Format::from_value(value)
    }
}

/// The "Exclusive OR" check byte (BCC) of a message.
///
/// It covers the message bytes only (as transmitted, after the two-character codes are
/// turned into single bytes), never SOH, STX, ETX, EOT, CR or LF added by the format.
pub fn check_byte(message: &[u8]) -> u8 {
    message.iter().fold(0, |acc, b| acc ^ b)
}

/// Whether `byte` opens a framed Phoenix message (SOH or STX): a text line never starts with
/// either, so a receiver between two inputs can route on this byte alone.
pub const fn is_frame_start(byte: u8) -> bool {
    byte == SOH || byte == STX
}

/// Wrap `message` according to `format` into `out`; returns the frame length.
///
/// Layout: `[SOH] [STX] message [CR LF] [ETX] [EOT] [BCC]`.
///
/// Errors: [`Error::BufferTooSmall`] when `out` cannot hold the frame, [`Error::Malformed`]
/// when the message holds a byte the format reserves (see [`Format::is_reserved`]): such a
/// frame could not be received as sent.
pub fn frame(format: Format, message: &[u8], out: &mut [u8]) -> Result<usize> {
    if message.iter().any(|&b| format.is_reserved(b)) {
        return Err(Error::Malformed);
    }
    let len = message
        .len()
        .checked_add(format.overhead())
        .ok_or(Error::BufferTooSmall)?;
    let out = out.get_mut(..len).ok_or(Error::BufferTooSmall)?;
    let mut w = Cursor { out, at: 0 };
    if format.soh_eot() {
        w.put(&[SOH])?;
    }
    if format.stx_etx() {
        w.put(&[STX])?;
    }
    w.put(message)?;
    if format.cr_lf() {
        w.put(&[CR, LF])?;
    }
    if format.stx_etx() {
        w.put(&[ETX])?;
    }
    if format.soh_eot() {
        w.put(&[EOT])?;
    }
    if format.check_byte() {
        w.put(&[check_byte(message)])?;
    }
    Ok(w.at)
}

/// Bounded writer over a caller buffer.
struct Cursor<'a> {
    out: &'a mut [u8],
    at: usize,
}

impl Cursor<'_> {
    fn put(&mut self, bytes: &[u8]) -> Result<()> {
        let end = self
            .at
            .checked_add(bytes.len())
            .ok_or(Error::BufferTooSmall)?;
        self.out
            .get_mut(self.at..end)
            .ok_or(Error::BufferTooSmall)?
            .copy_from_slice(bytes);
        self.at = end;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn framed(format: u8, message: &[u8]) -> heapless::Vec<u8, 64> {
        let mut out = [0u8; 64];
        let n = frame(Format::from_value(format).unwrap(), message, &mut out).unwrap();
        heapless::Vec::from_slice(&out[..n]).unwrap()
    }

    #[test]
    fn supported_values_are_exactly_the_manuals_list() {
        let listed = [
            0, 1, 16, 17, 32, 33, 48, 49, 64, 65, 80, 81, 96, 97, 112, 113,
        ];
        for v in 0..=255u8 {
            assert_eq!(
                Format::from_value(v).is_ok(),
                listed.contains(&v),
                "value {v}"
            );
        }
        let all: heapless::Vec<u8, 16> = Format::ALL.iter().map(|f| f.value()).collect();
        assert_eq!(&all[..], &listed[..]);
    }

    #[test]
    fn check_byte_is_xor_of_message_only() {
        // "AB": 0x41 ^ 0x42 = 0x03.
        assert_eq!(check_byte(b"AB"), 0x03);
        assert_eq!(check_byte(b""), 0x00);
        // "Message": 4D^65=28, ^73=5B, ^73=28, ^61=49, ^67=2E, ^65=4B.
        assert_eq!(check_byte(b"Message"), 0x4B);
        // The framing bytes never enter the check byte.
        assert_eq!(framed(113, b"Message").last(), Some(&0x4B));
        assert_eq!(framed(17, b"Message").last(), Some(&0x4B));
    }

    #[test]
    fn every_format_lays_out_bytes_in_the_documented_order() {
        let m = b"Message";
        let bcc = 0x4B;
        let cases: [(u8, &[u8], &[u8]); 16] = [
            (0, b"", b""),
            (1, b"", b"\r\n"),
            (16, b"", &[bcc]),
            (17, b"", &[CR, LF, bcc]),
            (32, &[STX], &[ETX]),
            // Manual: "The <ETX> follows the message and the optional <CR><LF> append codes
            // but precedes the Check Byte <BCC>."
            (33, &[STX], &[CR, LF, ETX]),
            (48, &[STX], &[ETX, bcc]),
            (49, &[STX], &[CR, LF, ETX, bcc]),
            (64, &[SOH], &[EOT]),
            (65, &[SOH], &[CR, LF, EOT]),
            (80, &[SOH], &[EOT, bcc]),
            (81, &[SOH], &[CR, LF, EOT, bcc]),
            (96, &[SOH, STX], &[ETX, EOT]),
            (97, &[SOH, STX], &[CR, LF, ETX, EOT]),
            (112, &[SOH, STX], &[ETX, EOT, bcc]),
            (113, &[SOH, STX], &[CR, LF, ETX, EOT, bcc]),
        ];
        for (value, head, tail) in cases {
            let mut expected: heapless::Vec<u8, 64> = heapless::Vec::new();
            expected.extend_from_slice(head).unwrap();
            expected.extend_from_slice(m).unwrap();
            expected.extend_from_slice(tail).unwrap();
            assert_eq!(framed(value, m), expected, "format {value}");
            let f = Format::from_value(value).unwrap();
            assert_eq!(f.overhead(), head.len() + tail.len(), "format {value}");
        }
    }

    #[test]
    fn manual_example_format_1_appends_cr_lf() {
        // ESSI example `>20,1,1,0<Message`: format 1 sends "Message" CR LF.
        assert_eq!(&framed(1, b"Message")[..], b"Message\r\n");
    }

    #[test]
    fn frame_refuses_small_buffers_and_reserved_bytes() {
        let mut out = [0u8; 9];
        let f = Format::from_value(113).unwrap();
        assert_eq!(frame(f, b"AB", &mut out[..8]), Err(Error::BufferTooSmall));
        assert_eq!(frame(f, b"AB", &mut out), Ok(9));
        assert_eq!(frame(f, b"A\x03B", &mut [0; 16]), Err(Error::Malformed));
        assert_eq!(
            frame(Format::from_value(1).unwrap(), b"A\nB", &mut [0; 16]),
            Err(Error::Malformed)
        );
        // A plain format carries any byte.
        assert_eq!(
            frame(Format::PLAIN, b"\x01\x02\x03\x04\n", &mut [0; 8]),
            Ok(5)
        );
    }

    #[test]
    fn ack_nak_values() {
        assert_eq!(ACK, 0x06);
        assert_eq!(NAK, 0x15);
        assert!(is_frame_start(SOH) && is_frame_start(STX) && !is_frame_start(b'S'));
    }
}
