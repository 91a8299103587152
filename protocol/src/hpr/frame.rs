//! Framing: `>` + 3-digit command id + data + 2 hex digits of checksum + `<`.
//!
//! The checksum is the low byte of the sum of the id and data characters (manual section
//! III.e: `>00090<` is `0x30 + 0x30 + 0x30 = 0x90`). Nothing follows `<`: the manual's
//! application note says extra characters such as CR/LF can lock up older control boards,
//! so [`Frame::emit`] never writes them.

use crate::decimal::parse_decimal;
use crate::{Error, Result};

/// Start-of-message character.
pub const START: u8 = b'>';
/// End-of-message character.
pub const END: u8 = b'<';
/// Shortest frame: `>` + id + checksum + `<` with no data.
pub const MIN_FRAME_LEN: usize = 1 + 3 + 2 + 1;
/// Longest frame this crate accepts or writes, delimiters included.
///
/// The longest frame in the manual is the MaxPro200 reply to 100 GET_CONTROL_DATA (twelve
/// 8-character fields: 114 bytes; the HPR form is 112); the manual says that reply was split
/// into 141/142 "to reduce the length", so the supplies do not send longer ones. 128 leaves
/// about 10 % margin and is small enough for a fixed decoder buffer.
pub const MAX_FRAME_LEN: usize = 128;
/// Longest data field that fits in [`MAX_FRAME_LEN`].
pub const MAX_DATA_LEN: usize = MAX_FRAME_LEN - MIN_FRAME_LEN;
/// Highest command id three decimal digits can carry.
pub const MAX_ID: u16 = 999;

/// Checksum of a frame: low byte of the sum of the three id digits and the data bytes.
///
/// `id` must be at most [`MAX_ID`]; larger ids are reduced modulo 1000 like the digits
/// [`Frame::emit`] would refuse to write.
pub fn checksum(id: u16, data: &[u8]) -> u8 {
    let digits = id_digits(id);
    digits
        .iter()
        .chain(data)
        .fold(0u8, |sum, &b| sum.wrapping_add(b))
}

/// One frame, borrowed from the bytes it was parsed from or that the caller will emit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame<'a> {
    /// Command id, 0..=999 (replies echo the id of the command, or 500/501 for errors).
    pub id: u16,
    /// Data characters between the id and the checksum (ASCII, may be empty).
    pub data: &'a [u8],
}

impl<'a> Frame<'a> {
    /// A frame with this id and data (checked when emitted).
    pub const fn new(id: u16, data: &'a [u8]) -> Self {
        Frame { id, data }
    }

    /// Parse exactly one frame: `bytes` starts with `>` and ends with `<`.
    ///
    /// Errors: [`Error::Truncated`] if a delimiter is missing or the frame is shorter than
    /// [`MIN_FRAME_LEN`]; [`Error::Overlong`] beyond [`MAX_FRAME_LEN`]; [`Error::Malformed`]
    /// for a non-digit id or data that is not printable ASCII (or holds `>`/`<`);
    /// [`Error::NonHex`] for a non-hex checksum; [`Error::BadChecksum`] on a mismatch.
    pub fn parse(bytes: &'a [u8]) -> Result<Frame<'a>> {
        if bytes.len() > MAX_FRAME_LEN {
            return Err(Error::Overlong);
        }
        let inner = match bytes {
            [START, inner @ .., END] if bytes.len() >= MIN_FRAME_LEN => inner,
            _ => return Err(Error::Truncated),
        };
        let (id_digits, rest) = inner.split_at_checked(3).ok_or(Error::Truncated)?;
        let (data, ck) = rest
            .split_at_checked(rest.len().checked_sub(2).ok_or(Error::Truncated)?)
            .ok_or(Error::Truncated)?;
        let id = parse_id(id_digits)?;
        let found = parse_hex_byte(ck)?;
        let expected = checksum(id, data);
        if found != expected {
            return Err(Error::BadChecksum { expected, found });
        }
        if !data.iter().all(|&b| is_data_byte(b)) {
            return Err(Error::Malformed);
        }
        Ok(Frame { id, data })
    }

    /// Number of bytes [`emit`](Self::emit) writes.
    pub const fn len(&self) -> usize {
        MIN_FRAME_LEN + self.data.len()
    }

    /// Always false: a frame has at least its id and checksum.
    pub const fn is_empty(&self) -> bool {
        false
    }

    /// Write the frame into `out`; returns the number of bytes written. No CR/LF follows.
    ///
    /// Errors: [`Error::Malformed`] for an id above 999 or data that is not printable ASCII
    /// (or holds `>`/`<`); [`Error::Overlong`] beyond [`MAX_FRAME_LEN`];
    /// [`Error::BufferTooSmall`] if `out` cannot hold it.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize> {
        if self.id > MAX_ID || !self.data.iter().all(|&b| is_data_byte(b)) {
            return Err(Error::Malformed);
        }
        let len = self.len();
        if len > MAX_FRAME_LEN {
            return Err(Error::Overlong);
        }
        let out = out.get_mut(..len).ok_or(Error::BufferTooSmall)?;
        let ck = checksum(self.id, self.data);
        let (head, rest) = out.split_at_mut(4);
        let (body, tail) = rest.split_at_mut(self.data.len());
        let [start, d0, d1, d2] = head else {
            return Err(Error::BufferTooSmall);
        };
        let [c0, c1, end] = tail else {
            return Err(Error::BufferTooSmall);
        };
        *start = START;
        [*d0, *d1, *d2] = id_digits(self.id);
        body.copy_from_slice(self.data);
        *c0 = hex_digit(ck >> 4);
        *c1 = hex_digit(ck & 0x0F);
        *end = END;
        Ok(len)
    }
}

/// Uppercase hex digit of the low nibble of `n`.
const fn hex_digit(n: u8) -> u8 {
    let n = n & 0x0F;
    if n < 10 { b'0' + n } else { b'A' + n - 10 }
}

/// Bytes allowed in the data field: printable ASCII except the two delimiters.
///
/// The manual's data is digits, letters, `.` and spaces; refusing control bytes keeps HF
/// noise that happens to match a checksum from passing as data.
pub(crate) const fn is_data_byte(b: u8) -> bool {
    matches!(b, 0x20..=0x7E) && b != START && b != END
}

fn id_digits(id: u16) -> [u8; 3] {
    let id = id % 1000;
    // Each digit is < 10, so the casts cannot truncate.
    [
        b'0' + (id / 100) as u8,
        b'0' + (id / 10 % 10) as u8,
        b'0' + (id % 10) as u8,
    ]
}

fn parse_id(digits: &[u8]) -> Result<u16> {
    let id = parse_decimal(digits, 3)?;
    u16::try_from(id).map_err(|_| Error::Malformed)
}

fn hex_value(b: u8) -> Result<u8> {
    match b {
        b'0'..=b'9' => Ok(b - b'0'),
        b'A'..=b'F' => Ok(b - b'A' + 10),
        // The manual only shows uppercase; lowercase costs nothing to accept.
        b'a'..=b'f' => Ok(b - b'a' + 10),
        _ => Err(Error::NonHex),
    }
}

fn parse_hex_byte(ck: &[u8]) -> Result<u8> {
    match ck {
        [hi, lo] => Ok(hex_value(*hi)? << 4 | hex_value(*lo)?),
        _ => Err(Error::Truncated),
    }
}

/// Streaming decoder: push received bytes, get complete frames.
///
/// Bytes outside a frame (HF-ignition noise, stray CR/LF, a lone `<`) are ignored. A `>`
/// always starts a new frame, so a frame damaged by noise costs at most itself: if a frame
/// was in progress it is reported as [`Error::Truncated`] and decoding restarts at the new
/// `>`. A frame longer than [`MAX_FRAME_LEN`] is reported as [`Error::Overlong`] and the
/// rest of it is skipped. The result depends only on the byte sequence, never on how it is
/// split into chunks.
#[derive(Debug, Clone)]
pub struct Decoder {
    buf: [u8; MAX_FRAME_LEN],
    len: usize,
    in_frame: bool,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

/// What one byte did to the decoder, without borrowing its buffer.
enum Step {
    Nothing,
    Complete(usize),
    Failed(Error),
}

impl Decoder {
    /// An idle decoder waiting for `>`.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            in_frame: false,
        }
    }

    /// Forget any partial frame.
    pub fn reset(&mut self) {
        self.len = 0;
        self.in_frame = false;
    }

    /// True while a frame has started (`>` seen) but not ended.
    pub fn in_frame(&self) -> bool {
        self.in_frame
    }

    fn step(&mut self, byte: u8) -> Step {
        if byte == START {
            let interrupted = self.in_frame;
            self.in_frame = true;
            self.len = 0;
            self.store(byte);
            return if interrupted {
                Step::Failed(Error::Truncated)
            } else {
                Step::Nothing
            };
        }
        if !self.in_frame {
            return Step::Nothing;
        }
        if !self.store(byte) {
            self.reset();
            return Step::Failed(Error::Overlong);
        }
        if byte == END {
            self.in_frame = false;
            return Step::Complete(self.len);
        }
        Step::Nothing
    }

    fn store(&mut self, byte: u8) -> bool {
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
                true
            }
            None => false,
        }
    }

    fn finish(&self, step: Step) -> Option<Result<Frame<'_>>> {
        match step {
            Step::Nothing => None,
            Step::Failed(e) => Some(Err(e)),
            Step::Complete(len) => Some(
                self.buf
                    .get(..len)
                    .map_or(Err(Error::Overlong), Frame::parse),
            ),
        }
    }

    /// Push one byte; returns a frame (or why the frame just ended was rejected) when one
    /// completes or fails.
    pub fn push(&mut self, byte: u8) -> Option<Result<Frame<'_>>> {
        let step = self.step(byte);
        self.finish(step)
    }

    /// Push bytes until one of them completes or fails a frame.
    ///
    /// Returns how many bytes of `input` were consumed (all of them when no event occurred)
    /// and the event. Call again with the rest of `input` after handling the event.
    pub fn feed(&mut self, input: &[u8]) -> (usize, Option<Result<Frame<'_>>>) {
        for (i, &byte) in input.iter().enumerate() {
            match self.step(byte) {
                Step::Nothing => {}
                event => return (i + 1, self.finish(event)),
            }
        }
        (input.len(), None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn emit_vec(frame: &Frame<'_>) -> ([u8; MAX_FRAME_LEN], usize) {
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = frame.emit(&mut out).unwrap();
        (out, n)
    }

    #[test]
    fn checksum_section_examples() {
        // Section III.e: HELLO `>00090<`, 0x30 * 3 = 0x90.
        assert_eq!(checksum(0, b""), 0x90);
        // `>107000058<`: 0x31+0x30+0x37+0x30*4 = 0x158, low byte 0x58.
        assert_eq!(checksum(107, b"0000"), 0x58);
        let f = Frame::parse(b">107000058<").unwrap();
        assert_eq!((f.id, f.data), (107, &b"0000"[..]));
        let (out, n) = emit_vec(&f);
        assert_eq!(&out[..n], b">107000058<");
    }

    #[test]
    fn framing_sample() {
        // Section III.b sample: `>0011C2<` (id 001, data "1").
        let f = Frame::parse(b">0011C2<").unwrap();
        assert_eq!((f.id, f.data), (1, &b"1"[..]));
        let (out, n) = emit_vec(&Frame::new(1, b"1"));
        assert_eq!(&out[..n], b">0011C2<");
    }

    #[test]
    fn error_response_samples() {
        // Section III.d: `>00091<` is HELLO with a wrong checksum ("should be 90 not 91").
        assert_eq!(
            Frame::parse(b">00091<"),
            Err(Error::BadChecksum {
                expected: 0x90,
                found: 0x91
            })
        );
        let f = Frame::parse(b">50095<").unwrap();
        assert_eq!((f.id, f.data), (500, &b""[..]));
        // `>999AB<` is a well-formed frame with an id the supply does not know.
        let f = Frame::parse(b">999AB<").unwrap();
        assert_eq!((f.id, f.data), (999, &b""[..]));
        let f = Frame::parse(b">50196<").unwrap();
        assert_eq!((f.id, f.data), (501, &b""[..]));
    }

    #[test]
    fn rejects_bad_frames() {
        assert_eq!(Frame::parse(b""), Err(Error::Truncated));
        assert_eq!(Frame::parse(b">0009<"), Err(Error::Truncated));
        assert_eq!(Frame::parse(b"00090<"), Err(Error::Truncated));
        assert_eq!(Frame::parse(b">00090"), Err(Error::Truncated));
        assert_eq!(Frame::parse(b">00090<\r\n"), Err(Error::Truncated));
        assert_eq!(Frame::parse(b">0A090<"), Err(Error::Malformed));
        assert_eq!(Frame::parse(b">0009G<"), Err(Error::NonHex));
        // Lowercase hex is accepted on input.
        assert!(Frame::parse(b">0641cb<").is_ok());
        let mut long = [b'0'; MAX_FRAME_LEN + 1];
        long[0] = START;
        long[MAX_FRAME_LEN] = END;
        assert_eq!(Frame::parse(&long), Err(Error::Overlong));
        // Control characters in the data are refused even with a matching checksum.
        let ck = checksum(1, b"\r");
        let hex = [hex_digit(ck >> 4), hex_digit(ck)];
        let bad = [b'>', b'0', b'0', b'1', b'\r', hex[0], hex[1], b'<'];
        assert_eq!(Frame::parse(&bad), Err(Error::Malformed));
    }

    #[test]
    fn emit_checks() {
        let mut out = [0u8; 8];
        assert_eq!(Frame::new(1000, b"").emit(&mut out), Err(Error::Malformed));
        assert_eq!(Frame::new(1, b"<").emit(&mut out), Err(Error::Malformed));
        assert_eq!(
            Frame::new(1, b"12").emit(&mut out),
            Err(Error::BufferTooSmall)
        );
        assert_eq!(Frame::new(1, b"1").emit(&mut out), Ok(8));
        assert_eq!(&out, b">0011C2<");
        let data = [b'1'; MAX_DATA_LEN + 1];
        let mut big = [0u8; 256];
        assert_eq!(Frame::new(1, &data).emit(&mut big), Err(Error::Overlong));
        assert_eq!(
            Frame::new(1, &data[..MAX_DATA_LEN]).emit(&mut big),
            Ok(MAX_FRAME_LEN)
        );
        assert!(Frame::parse(&big[..MAX_FRAME_LEN]).is_ok());
    }

    #[test]
    fn decoder_skips_noise_and_resyncs() {
        let mut d = Decoder::new();
        let input = b"\x00\xff<noise\r\n>00292<>002000052<xx>0029>00393<";
        let mut rest = &input[..];
        type Event = Option<Result<(u16, [u8; 8], usize)>>;
        let mut got: [Event; 8] = [None; 8];
        let mut n = 0;
        while !rest.is_empty() {
            let (used, ev) = d.feed(rest);
            if let Some(ev) = ev {
                got[n] = Some(ev.map(|f| {
                    let mut data = [0u8; 8];
                    data[..f.data.len()].copy_from_slice(f.data);
                    (f.id, data, f.data.len())
                }));
                n += 1;
            }
            rest = &rest[used..];
        }
        assert_eq!(n, 4);
        assert_eq!(got[0], Some(Ok((2, [0; 8], 0))));
        assert_eq!(got[1], Some(Ok((2, *b"0000\0\0\0\0", 4))));
        assert_eq!(got[2], Some(Err(Error::Truncated)));
        assert_eq!(got[3], Some(Ok((3, [0; 8], 0))));
    }

    #[test]
    fn decoder_reports_overlong_then_recovers() {
        let mut d = Decoder::new();
        assert!(d.push(START).is_none());
        for _ in 1..MAX_FRAME_LEN {
            assert!(d.push(b'1').is_none());
        }
        assert_eq!(d.push(b'1'), Some(Err(Error::Overlong)));
        // The tail of the overlong frame, including its `<`, is skipped.
        assert!(d.push(END).is_none());
        for &b in &b">0649A"[..] {
            assert!(d.push(b).is_none());
        }
        assert_eq!(d.push(END), Some(Ok(Frame::new(64, b""))));
    }

    #[test]
    fn decoder_accepts_longest_frame() {
        let data = [b'7'; MAX_DATA_LEN];
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = Frame::new(100, &data).emit(&mut out).unwrap();
        assert_eq!(n, MAX_FRAME_LEN);
        let mut d = Decoder::new();
        let (used, ev) = d.feed(&out);
        assert_eq!(used, MAX_FRAME_LEN);
        assert_eq!(ev, Some(Ok(Frame::new(100, &data))));
        assert!(!d.in_frame());
    }

    #[test]
    fn decoder_reports_bad_checksum() {
        let mut d = Decoder::new();
        let (used, ev) = d.feed(b">00091<>00090<");
        assert_eq!(used, 7);
        assert_eq!(
            ev,
            Some(Err(Error::BadChecksum {
                expected: 0x90,
                found: 0x91
            }))
        );
        let (used, ev) = d.feed(b">00090<");
        assert_eq!(used, 7);
        assert_eq!(ev, Some(Ok(Frame::new(0, b""))));
    }
}
