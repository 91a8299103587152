//! Streaming Modbus ASCII decoder with a fixed buffer.

use super::frame::{Frame, MAX_FRAME_BYTES};
use super::hex::{COLON, CR, LF, class};
use crate::{Error, Result};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Discarding everything until a `:`.
    Idle,
    /// Inside a frame, collecting hex digits.
    Hex,
    /// Inside a frame, a CR seen: only LF may follow.
    CarriageReturn,
}

/// Turns received characters into [`Frame`]s, one byte or one chunk at a time.
///
/// No allocation: the decoder holds one binary frame (255 bytes) and converts hex digits as
/// they arrive. Results do not depend on how the input is split into chunks.
///
/// Rules, in the order characters arrive:
/// - Everything before a `:` is ignored (line noise, the tail of a broken frame, echoes).
/// - A `:` inside a frame abandons it: the decoder reports [`Error::Truncated`] for the
///   abandoned frame and starts the new one at that `:` (resynchronisation). Reporting, rather
///   than dropping it silently, lets the link count broken frames.
/// - Digits may be upper or lower case.
/// - LF ends the frame, with or without a CR before it. Powermax units send CR LF; the CR is
///   optional because the end of the frame is unambiguous without it, and some tools send LF.
///   A CR must be followed by LF.
/// - Any other character inside a frame (including a CR not followed by LF) is
///   [`Error::NonHex`]; then the decoder waits for the next `:`.
/// - More than 510 hex digits (a frame longer than [`MAX_FRAME_CHARS`](super::MAX_FRAME_CHARS))
///   is [`Error::Overlong`], reported at the 511th digit; then the decoder waits for the next `:`.
/// - At the end of a frame: an odd number of digits is [`Error::OddLength`], fewer than 3 bytes
///   (address, function, LRC) [`Error::Truncated`], a wrong LRC [`Error::BadChecksum`].
///
/// ```
/// use plasma_protocol::modbus_ascii::Decoder;
///
/// let mut decoder = Decoder::new();
/// // Noise, then a reply split over two reads.
/// let (used, result) = decoder.feed(b"\x00\xff:0104020508");
/// assert_eq!((used, result), (13, None));
/// let (used, result) = decoder.feed(b"EC\r\n:01");
/// let frame = result.unwrap().unwrap();
/// assert_eq!(used, 4); // the caller goes on with the rest, `:01`
/// assert_eq!(frame.address, 0x01);
/// assert_eq!(frame.pdu, [0x04, 0x02, 0x05, 0x08]);
/// ```
#[derive(Debug, Clone)]
pub struct Decoder {
    buf: [u8; MAX_FRAME_BYTES],
    /// Complete bytes in `buf`.
    len: usize,
    /// High nibble waiting for its low nibble, if `half`.
    high: u8,
    half: bool,
    state: State,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder waiting for a `:`.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; MAX_FRAME_BYTES],
            len: 0,
            high: 0,
            half: false,
            state: State::Idle,
        }
    }

    /// Forgets any partial frame and waits for the next `:` (e.g. after a reply time-out).
    pub fn reset(&mut self) {
        self.state = State::Idle;
    }

    /// True when a `:` has been seen and the frame has not ended yet.
    pub fn in_frame(&self) -> bool {
        self.state != State::Idle
    }

    /// Takes one received character; returns a result when it ends a frame or an error.
    pub fn push(&mut self, byte: u8) -> Option<Result<Frame<'_>>> {
        let event = self.step(byte)?;
        Some(self.result(event))
    }

    /// Takes received characters up to the first one that ends a frame or an error.
    ///
    /// Returns how many bytes of `input` were used and that result, if any; the caller feeds
    /// the rest (`&input[used..]`) afterwards. When no result is returned, all of `input`
    /// was used.
    pub fn feed(&mut self, input: &[u8]) -> (usize, Option<Result<Frame<'_>>>) {
        let mut rest = input;
        loop {
            if self.state == State::Hex && !self.half {
                let taken = self.digit_pairs(rest);
                rest = rest.get(taken..).unwrap_or_default();
            }
            let Some((&byte, tail)) = rest.split_first() else {
                return (input.len(), None);
            };
            rest = tail;
            if let Some(event) = self.step(byte) {
                return (input.len() - rest.len(), Some(self.result(event)));
            }
        }
    }

    /// Fast path of [`Decoder::feed`] inside a frame on a byte boundary: converts whole pairs
    /// of hex digits while there is room, and returns how many characters it used. Stops
    /// before anything else, which [`Decoder::step`] then handles, so the outcome is the
    /// same as pushing the characters one by one.
    #[inline(always)]
    fn digit_pairs(&mut self, input: &[u8]) -> usize {
        let free = self.buf.get_mut(self.len..).unwrap_or_default();
        let mut stored = 0;
        for (pair, slot) in input.chunks_exact(2).zip(free) {
            let &[hi, lo] = pair else { break };
            let (hi, lo) = (class(hi), class(lo));
            // Digits are 0..=15; every other class has a bit above the low four.
            if (hi | lo) >= 16 {
                break;
            }
            *slot = hi << 4 | lo;
            stored += 1;
        }
        self.len += stored;
        2 * stored
    }

    /// The state machine. `Some(Ok(n))`: a frame of `n` binary bytes (LRC included) ended.
    #[inline(always)]
    fn step(&mut self, byte: u8) -> Option<Result<usize>> {
        let class = class(byte);
        match self.state {
            State::Idle => {
                if class == COLON {
                    self.start();
                }
                None
            }
            State::Hex if class < 16 => self.digit(class),
            State::Hex => match class {
                CR => {
                    self.state = State::CarriageReturn;
                    None
                }
                LF => Some(self.finish()),
                COLON => self.restart(),
                _ => self.abandon(Error::NonHex),
            },
            State::CarriageReturn => match class {
                LF => Some(self.finish()),
                COLON => self.restart(),
                _ => self.abandon(Error::NonHex),
            },
        }
    }

    fn start(&mut self) {
        self.state = State::Hex;
        self.len = 0;
        self.half = false;
    }

    /// A `:` inside a frame: report the old frame as truncated, begin the new one.
    fn restart(&mut self) -> Option<Result<usize>> {
        self.start();
        Some(Err(Error::Truncated))
    }

    /// Drop the frame and wait for the next `:`.
    fn abandon(&mut self, error: Error) -> Option<Result<usize>> {
        self.state = State::Idle;
        Some(Err(error))
    }

    #[inline(always)]
    fn digit(&mut self, value: u8) -> Option<Result<usize>> {
        if !self.half {
            // A new byte starts: there must be room for it.
            if self.len >= MAX_FRAME_BYTES {
                return self.abandon(Error::Overlong);
            }
            self.high = value;
            self.half = true;
            return None;
        }
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = self.high << 4 | value;
                self.len += 1;
                self.half = false;
                None
            }
            None => self.abandon(Error::Overlong),
        }
    }

    fn finish(&mut self) -> Result<usize> {
        self.state = State::Idle;
        if self.half {
            Err(Error::OddLength)
        } else {
            Ok(self.len)
        }
    }

    /// Turns a finished frame's bytes into a [`Frame`], checking length and LRC.
    fn result(&self, event: Result<usize>) -> Result<Frame<'_>> {
        let len = event?;
        Frame::from_binary(self.buf.get(..len).unwrap_or_default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// All results of feeding `input` one byte at a time, as (address, pdu) or error.
    fn results(input: &[u8]) -> heapless::Vec<Result<(u8, heapless::Vec<u8, 256>)>, 16> {
        let mut decoder = Decoder::new();
        let mut out = heapless::Vec::new();
        for &b in input {
            if let Some(r) = decoder.push(b) {
                let owned = r.map(|f| (f.address, heapless::Vec::from_slice(f.pdu).unwrap()));
                out.push(owned).unwrap();
            }
        }
        out
    }

    fn ok(address: u8, pdu: &[u8]) -> Result<(u8, heapless::Vec<u8, 256>)> {
        Ok((address, heapless::Vec::from_slice(pdu).unwrap()))
    }

    #[test]
    fn one_frame() {
        assert_eq!(
            results(b":0104020508EC\r\n")[..],
            [ok(1, &[0x04, 0x02, 0x05, 0x08])]
        );
    }

    #[test]
    fn lower_case_and_lf_only() {
        assert_eq!(
            results(b":0104020508ec\n")[..],
            [ok(1, &[0x04, 0x02, 0x05, 0x08])]
        );
    }

    #[test]
    fn noise_before_and_between_frames_is_ignored() {
        let input = b"\x00garbage\r\n0104:0104020508EC\r\nxx\n:01010100FD\r\n";
        assert_eq!(
            results(input)[..],
            [ok(1, &[4, 2, 5, 8]), ok(1, &[1, 1, 0])]
        );
    }

    #[test]
    fn colon_inside_a_frame_restarts_and_reports_truncated() {
        let input = b":010402:0104020508EC\r\n";
        assert_eq!(
            results(input)[..],
            [Err(Error::Truncated), ok(1, &[4, 2, 5, 8])]
        );
        // Also right after a CR.
        let input = b":0104\r:0104020508EC\r\n";
        assert_eq!(
            results(input)[..],
            [Err(Error::Truncated), ok(1, &[4, 2, 5, 8])]
        );
        // And for a lone colon.
        assert_eq!(
            results(b"::01010100FD\r\n")[..],
            [Err(Error::Truncated), ok(1, &[1, 1, 0])]
        );
    }

    #[test]
    fn non_hex_discards_until_next_colon() {
        let input = b":0104G20508EC\r\n0104020508EC\r\n:01010100FD\r\n";
        assert_eq!(results(input)[..], [Err(Error::NonHex), ok(1, &[1, 1, 0])]);
        // A space, and a CR not followed by LF.
        assert_eq!(results(b":01 04\r\n")[..], [Err(Error::NonHex)]);
        assert_eq!(results(b":0104\r0\n")[..], [Err(Error::NonHex)]);
        assert_eq!(results(b":0104\r\r\n")[..], [Err(Error::NonHex)]);
    }

    #[test]
    fn end_of_frame_errors() {
        assert_eq!(results(b":0104020508E\r\n")[..], [Err(Error::OddLength)]);
        assert_eq!(results(b":\r\n")[..], [Err(Error::Truncated)]);
        assert_eq!(results(b":01FF\r\n")[..], [Err(Error::Truncated)]);
        assert_eq!(results(b":0104FB\r\n")[..], [ok(1, &[4])]);
        assert_eq!(
            results(b":0104020508ED\r\n")[..],
            [Err(Error::BadChecksum {
                expected: 0xEC,
                found: 0xED
            })]
        );
    }

    #[test]
    fn overlong_at_511th_digit_then_waits_for_colon() {
        // 255 bytes (510 digits) is the longest frame: address 01, function 04, byte count
        // 0xFA, 250 data bytes, 1 pad byte... use a valid-LRC frame of exactly 255 bytes.
        let mut bytes = [0u8; MAX_FRAME_BYTES];
        bytes[0] = 0x01;
        bytes[1] = 0x04;
        let lrc = crate::modbus_ascii::lrc(&bytes[..MAX_FRAME_BYTES - 1]);
        bytes[MAX_FRAME_BYTES - 1] = lrc;
        let mut text = [0u8; 1 + 2 * MAX_FRAME_BYTES + 2 + 2];
        text[0] = b':';
        for (i, b) in bytes.iter().enumerate() {
            text[1 + 2 * i..3 + 2 * i].copy_from_slice(&crate::modbus_ascii::hex::encode_byte(*b));
        }
        let end = 1 + 2 * MAX_FRAME_BYTES;
        text[end..end + 2].copy_from_slice(b"\r\n");
        // Exactly 513 characters: accepted.
        let r = results(&text[..end + 2]);
        assert_eq!(r.len(), 1);
        assert!(matches!(&r[0], Ok((1, pdu)) if pdu.len() == MAX_FRAME_BYTES - 2));

        // One more digit pair: Overlong at the 511th digit, the rest is discarded.
        text[end..end + 2].copy_from_slice(b"00");
        text[end + 2..end + 4].copy_from_slice(b"\r\n");
        assert_eq!(results(&text)[..], [Err(Error::Overlong)]);

        let mut decoder = Decoder::new();
        let (used, r) = decoder.feed(&text);
        assert_eq!((used, r), (end + 1, Some(Err(Error::Overlong))));
        assert!(!decoder.in_frame());
        let (used, r) = decoder.feed(b"0\r\n:01010100FD\r\n");
        assert_eq!(used, 16);
        assert_eq!(
            r,
            Some(Ok(Frame {
                address: 1,
                pdu: &[1, 1, 0]
            }))
        );
    }

    #[test]
    fn feed_stops_at_each_result() {
        let input = b":01010100FD\r\n:0104020508ED\r\n:01010103FA\r\n";
        let mut decoder = Decoder::new();
        let (used, r) = decoder.feed(input);
        assert_eq!(
            (used, r),
            (
                13,
                Some(Ok(Frame {
                    address: 1,
                    pdu: &[1, 1, 0]
                }))
            )
        );
        let (used2, r) = decoder.feed(&input[used..]);
        assert_eq!(
            (used2, r),
            (
                15,
                Some(Err(Error::BadChecksum {
                    expected: 0xEC,
                    found: 0xED
                }))
            )
        );
        let (used3, r) = decoder.feed(&input[used + used2..]);
        assert_eq!(
            (used3, r),
            (
                13,
                Some(Ok(Frame {
                    address: 1,
                    pdu: &[1, 1, 3]
                }))
            )
        );
        assert_eq!(decoder.feed(&[]), (0, None));
    }

    #[test]
    fn reset_drops_a_partial_frame() {
        let mut decoder = Decoder::new();
        assert_eq!(decoder.feed(b":010401"), (7, None));
        assert!(decoder.in_frame());
        decoder.reset();
        assert!(!decoder.in_frame());
        assert_eq!(decoder.feed(b"00FD\r\n"), (6, None));
    }
}
