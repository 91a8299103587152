//! Streaming receiver for Phoenix serial messages.

use super::{CR, EOT, ETX, Format, LF, MAX_MESSAGE_LEN, STX, check_byte};
use crate::{Error, Result};

/// Where the receiver is within a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum State {
    /// Between frames.
    Idle,
    /// Between frames, after bytes that were not a start byte (already reported).
    Garbage,
    /// SOH seen, STX expected (formats 96..=113).
    AfterSoh,
    /// Collecting the message (and its CR LF).
    Message,
    /// ETX seen, EOT expected (formats 96..=113).
    AfterEtx,
    /// Frame complete but for its check byte.
    Check,
    /// Discarding the rest of a refused frame up to its last framing byte.
    Skip,
    /// Discarding the check byte of a refused frame.
    SkipCheck,
}

/// What one byte did.
enum Step {
    Pending,
    Message(usize),
    Refused(Error),
}

/// Receives Phoenix serial messages of one [`Format`] from a byte stream.
///
/// Sans-IO, like smoltcp's sockets: feed bytes as they arrive, one at a time with
/// [`push`](Self::push) or in chunks with [`feed`](Self::feed); the messages and errors are
/// the same however the stream is cut. Each frame yields exactly one outcome:
///
/// - `Ok(message)`: the payload, without framing, CR LF or check byte; answer [`ACK`] to a
///   type-22 message.
/// - `Err(Error::BadChecksum { .. })`, `Err(Error::Overlong)` (more than `N` bytes of
///   message and CR LF), `Err(Error::Malformed)` (a framing byte missing or out of place,
///   or bytes outside any frame, reported once per run), `Err(Error::Truncated)` (a new frame
///   started, or [`idle`](Self::idle) was called, before this one ended): answer [`NAK`] and
///   the CNC sends the message again.
///
/// After an error the receiver skips to the end of the refused frame (or to the next start
/// byte) and goes on.
///
/// Formats 0 and 16 have no byte that ends a message: the message is whatever arrived before
/// the line went idle, so the caller reports idleness (a UART idle-line interrupt) with
/// [`idle`](Self::idle). For the other formats `idle` abandons an incomplete frame.
///
/// ```
/// use plasma_protocol::cnc::phoenix::{Deframer, Format, frame};
///
/// let format = Format::from_value(113)?;
/// let mut wire = [0u8; 32];
/// let n = frame(format, b"SET AMPS 45", &mut wire)?;
///
/// let mut rx: Deframer = Deframer::new(format);
/// let (used, outcome) = rx.feed(&wire[..n]);
/// assert_eq!(used, n);
/// assert_eq!(outcome, Some(Ok(&b"SET AMPS 45"[..])));
/// # Ok::<(), plasma_protocol::Error>(())
/// ```
///
/// [`ACK`]: super::ACK
/// [`NAK`]: super::NAK
#[derive(Debug, Clone)]
pub struct Deframer<const N: usize = MAX_MESSAGE_LEN> {
    format: Format,
    state: State,
    buf: [u8; N],
    len: usize,
}

impl<const N: usize> Deframer<N> {
    /// A receiver for messages sent with `format`.
    pub const fn new(format: Format) -> Self {
        Deframer {
            format,
            state: State::Idle,
            buf: [0; N],
            len: 0,
        }
    }

    /// The format this receiver expects.
    pub const fn format(&self) -> Format {
        self.format
    }

    /// Drop any partial frame.
    pub fn reset(&mut self) {
        self.state = State::Idle;
        self.len = 0;
    }

    /// Whether the receiver is inside a frame (a byte that is not a start byte belongs to it).
    pub fn in_frame(&self) -> bool {
        !matches!(self.state, State::Idle | State::Garbage)
    }

    /// Take one byte; returns the outcome of a frame when this byte completes it.
    pub fn push(&mut self, byte: u8) -> Option<Result<&[u8]>> {
        let step = self.step(byte);
        self.outcome(step)
    }

    /// Take bytes from `input` until a frame completes or `input` runs out.
    ///
    /// Returns how many bytes were used and the outcome of the frame they completed, if any;
    /// feed the rest of `input` again after handling it.
    pub fn feed(&mut self, input: &[u8]) -> (usize, Option<Result<&[u8]>>) {
        for (i, &byte) in input.iter().enumerate() {
            let step = self.step(byte);
            if !matches!(step, Step::Pending) {
                return (i + 1, self.outcome(step));
            }
        }
        (input.len(), None)
    }

    /// The line has gone idle: ends the message of formats 0 and 16; for the other formats
    /// abandons an incomplete frame with [`Error::Truncated`]. (An empty format-0 message
    /// sends no byte, so there is nothing to receive.)
    pub fn idle(&mut self) -> Option<Result<&[u8]>> {
        let terminated = self.format.start_byte().is_some() || self.format.cr_lf();
        let step = match self.state {
            State::Idle | State::Garbage => Step::Pending,
            State::Skip | State::SkipCheck => {
                self.state = State::Idle;
                Step::Pending
            }
            State::Message if !terminated => {
                self.state = State::Idle;
                self.finish_unterminated()
            }
            _ => {
                self.state = State::Idle;
                Step::Refused(Error::Truncated)
            }
        };
        self.outcome(step)
    }

    fn outcome(&self, step: Step) -> Option<Result<&[u8]>> {
        match step {
            Step::Pending => None,
            Step::Message(len) => Some(Ok(self.buf.get(..len).unwrap_or_default())),
            Step::Refused(error) => Some(Err(error)),
        }
    }

    /// The byte after which nothing but the check byte follows.
    fn last_marker(&self) -> Option<u8> {
        if self.format.soh_eot() {
            Some(EOT)
        } else if self.format.stx_etx() {
            Some(ETX)
        } else if self.format.cr_lf() {
            Some(LF)
        } else {
            None
        }
    }

    /// The byte that ends the message part (and its CR LF).
    fn message_end(&self) -> Option<u8> {
        if self.format.stx_etx() {
            Some(ETX)
        } else {
            self.last_marker()
        }
    }

    /// Begin a new frame on its start byte.
    fn begin(&mut self) {
        self.len = 0;
        self.state = if self.format.soh_eot() && self.format.stx_etx() {
            State::AfterSoh
        } else {
            State::Message
        };
    }

    /// After a refused frame: skip what is left of it.
    fn refuse(&mut self, error: Error) -> Step {
        self.state = State::Skip;
        Step::Refused(error)
    }

    fn step(&mut self, byte: u8) -> Step {
        let start = self.format.start_byte();
        // A start byte anywhere but in the check byte position opens a new frame.
        if start == Some(byte) && !matches!(self.state, State::Check | State::SkipCheck) {
            let interrupted = matches!(
                self.state,
                State::AfterSoh | State::Message | State::AfterEtx
            );
            self.begin();
            return if interrupted {
                Step::Refused(Error::Truncated)
            } else {
                Step::Pending
            };
        }
        match self.state {
            State::Idle | State::Garbage => {
                if start.is_some() {
                    let first = self.state == State::Idle;
                    self.state = State::Garbage;
                    if first {
                        Step::Refused(Error::Malformed)
                    } else {
                        Step::Pending
                    }
                } else {
                    // No start byte: the first byte of the message opens the frame.
                    self.begin();
                    self.message_byte(byte)
                }
            }
            State::AfterSoh => {
                if byte == STX {
                    self.state = State::Message;
                    Step::Pending
                } else {
                    self.refuse(Error::Malformed)
                }
            }
            State::Message => self.message_byte(byte),
            State::AfterEtx => {
                if byte == EOT {
                    self.frame_end()
                } else {
                    self.refuse(Error::Malformed)
                }
            }
            State::Check => {
                self.state = State::Idle;
                let message = self.buf.get(..self.len).unwrap_or_default();
                let expected = check_byte(message);
                if byte == expected {
                    Step::Message(self.len)
                } else {
                    Step::Refused(Error::BadChecksum {
                        expected,
                        found: byte,
                    })
                }
            }
            State::Skip => {
                if Some(byte) == self.last_marker() {
                    self.state = if self.format.check_byte() {
                        State::SkipCheck
                    } else {
                        State::Idle
                    };
                }
                Step::Pending
            }
            State::SkipCheck => {
                self.state = State::Idle;
                Step::Pending
            }
        }
    }

    fn message_byte(&mut self, byte: u8) -> Step {
        if Some(byte) == self.message_end() {
            return self.message_end_seen();
        }
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
                Step::Pending
            }
            None => self.refuse(Error::Overlong),
        }
    }

    /// ETX, EOT or LF ended the message part: strip and check its CR LF.
    fn message_end_seen(&mut self) -> Step {
        let terminator_is_lf = self.message_end() == Some(LF);
        if self.format.cr_lf() {
            // Framed formats keep CR LF in the buffer; the line formats keep only the CR.
            let tail: &[u8] = if terminator_is_lf { &[CR] } else { &[CR, LF] };
            let message = self.buf.get(..self.len).unwrap_or_default();
            if !message.ends_with(tail) {
                // Rest of this frame: EOT (after ETX) and the check byte still to come.
                self.state = if self.format.soh_eot() && self.format.stx_etx() {
                    State::Skip
                } else if self.format.check_byte() {
                    State::SkipCheck
                } else {
                    State::Idle
                };
                return Step::Refused(Error::Malformed);
            }
            self.len -= tail.len();
        }
        if self.format.soh_eot() && self.format.stx_etx() {
            self.state = State::AfterEtx;
            Step::Pending
        } else {
            self.frame_end()
        }
    }

    /// The last framing byte arrived.
    fn frame_end(&mut self) -> Step {
        if self.format.check_byte() {
            self.state = State::Check;
            Step::Pending
        } else {
            self.state = State::Idle;
            Step::Message(self.len)
        }
    }

    /// Formats 0 and 16 at idle: the message is everything received (less the check byte).
    fn finish_unterminated(&mut self) -> Step {
        if !self.format.check_byte() {
            return Step::Message(self.len);
        }
        let Some(len) = self.len.checked_sub(1) else {
            return Step::Refused(Error::Truncated);
        };
        let found = self.buf.get(len).copied().unwrap_or_default();
        let expected = check_byte(self.buf.get(..len).unwrap_or_default());
        self.len = len;
        if found == expected {
            Step::Message(len)
        } else {
            Step::Refused(Error::BadChecksum { expected, found })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{SOH, frame};
    use super::*;

    type Rx = Deframer<32>;

    fn fmt(v: u8) -> Format {
        Format::from_value(v).unwrap()
    }

    /// Every outcome from feeding `input` in one go.
    fn outcomes(rx: &mut Rx, mut input: &[u8]) -> heapless::Vec<Result<heapless::Vec<u8, 32>>, 16> {
        let mut all = heapless::Vec::new();
        while !input.is_empty() {
            let (used, out) = rx.feed(input);
            input = &input[used..];
            if let Some(out) = out {
                all.push(out.map(|m| heapless::Vec::from_slice(m).unwrap()))
                    .unwrap();
            }
        }
        all
    }

    fn ok(m: &[u8]) -> Result<heapless::Vec<u8, 32>> {
        Ok(heapless::Vec::from_slice(m).unwrap())
    }

    #[test]
    fn format_113_fixture() {
        // SOH STX "AB" CR LF ETX EOT BCC, BCC = 0x41 ^ 0x42 = 0x03.
        let wire = [SOH, STX, b'A', b'B', CR, LF, ETX, EOT, 0x03];
        let mut rx = Rx::new(fmt(113));
        assert_eq!(&outcomes(&mut rx, &wire)[..], &[ok(b"AB")]);
        let mut out = [0u8; 16];
        assert_eq!(frame(fmt(113), b"AB", &mut out), Ok(wire.len()));
        assert_eq!(&out[..wire.len()], &wire);
    }

    #[test]
    fn bad_check_byte_is_reported_and_next_frame_received() {
        let wire = [STX, b'A', b'B', ETX, 0x04, STX, b'C', ETX, b'C'];
        let mut rx = Rx::new(fmt(48));
        assert_eq!(
            &outcomes(&mut rx, &wire)[..],
            &[
                Err(Error::BadChecksum {
                    expected: 0x03,
                    found: 0x04
                }),
                ok(b"C")
            ]
        );
    }

    #[test]
    fn check_byte_equal_to_a_framing_byte_is_read_by_position() {
        // A message whose check byte is EOT (0x04): "@D" = 0x40 ^ 0x44 = 0x04.
        let mut out = [0u8; 16];
        let n = frame(fmt(80), b"@D", &mut out).unwrap();
        assert_eq!(&out[..n], &[SOH, b'@', b'D', EOT, EOT]);
        let mut rx = Rx::new(fmt(80));
        assert_eq!(&outcomes(&mut rx, &out[..n])[..], &[ok(b"@D")]);
        // Line format 17 with a check byte equal to LF: "@J" = 0x40 ^ 0x4A = 0x0A.
        let n = frame(fmt(17), b"@J", &mut out).unwrap();
        assert_eq!(&out[..n], b"@J\r\n\n");
        let mut rx = Rx::new(fmt(17));
        assert_eq!(&outcomes(&mut rx, &out[..n])[..], &[ok(b"@J")]);
    }

    #[test]
    fn overlong_frame_is_reported_once_and_skipped() {
        let mut wire: heapless::Vec<u8, 64> = heapless::Vec::new();
        wire.push(STX).unwrap();
        wire.extend_from_slice(&[b'x'; 40]).unwrap();
        wire.extend_from_slice(&[ETX, STX, b'o', b'k', ETX])
            .unwrap();
        let mut rx = Rx::new(fmt(32));
        assert_eq!(
            &outcomes(&mut rx, &wire)[..],
            &[Err(Error::Overlong), ok(b"ok")]
        );
        // Exactly N bytes fit.
        let mut rx = Rx::new(fmt(0));
        assert_eq!(&outcomes(&mut rx, &[b'y'; 32])[..], &[]);
        assert_eq!(rx.idle(), Some(Ok(&[b'y'; 32][..])));
    }

    #[test]
    fn garbage_between_frames_is_reported_once() {
        let mut rx = Rx::new(fmt(32));
        assert_eq!(
            &outcomes(&mut rx, b"noise\r\n\x02hi\x03")[..],
            &[Err(Error::Malformed), ok(b"hi")]
        );
    }

    #[test]
    fn missing_cr_lf_and_missing_eot_are_malformed() {
        let mut rx = Rx::new(fmt(33));
        assert_eq!(
            &outcomes(&mut rx, b"\x02hi\x03\x02hi\r\n\x03")[..],
            &[Err(Error::Malformed), ok(b"hi")]
        );
        // 97 = SOH STX .. CR LF ETX EOT: a byte other than EOT after ETX.
        let mut rx = Rx::new(fmt(97));
        assert_eq!(
            &outcomes(&mut rx, b"\x01\x02hi\r\n\x03X\x04\x01\x02ok\r\n\x03\x04")[..],
            &[Err(Error::Malformed), ok(b"ok")]
        );
        // SOH not followed by STX.
        let mut rx = Rx::new(fmt(96));
        assert_eq!(
            &outcomes(&mut rx, b"\x01hi\x03\x04\x01\x02ok\x03\x04")[..],
            &[Err(Error::Malformed), ok(b"ok")]
        );
    }

    #[test]
    fn a_new_start_byte_truncates_the_frame_in_progress() {
        let mut rx = Rx::new(fmt(64));
        assert_eq!(
            &outcomes(&mut rx, b"\x01lost\x01found\x04")[..],
            &[Err(Error::Truncated), ok(b"found")]
        );
    }

    #[test]
    fn line_formats() {
        let mut rx = Rx::new(fmt(1));
        assert_eq!(
            &outcomes(&mut rx, b"SET AMPS 45\r\nbad\nok\r\n")[..],
            &[ok(b"SET AMPS 45"), Err(Error::Malformed), ok(b"ok")]
        );
        // 17: "AB" CR LF 0x03; a wrong check byte.
        let mut rx = Rx::new(fmt(17));
        assert_eq!(
            &outcomes(&mut rx, b"AB\r\n\x03AB\r\n\x00")[..],
            &[
                ok(b"AB"),
                Err(Error::BadChecksum {
                    expected: 3,
                    found: 0
                })
            ]
        );
    }

    #[test]
    fn unterminated_formats_end_at_idle() {
        let mut rx = Rx::new(fmt(16));
        assert_eq!(rx.idle(), None);
        assert_eq!(rx.feed(b"AB\x03"), (3, None));
        assert_eq!(rx.idle(), Some(Ok(&b"AB"[..])));
        assert_eq!(rx.feed(b"AB\x07"), (3, None));
        assert_eq!(
            rx.idle(),
            Some(Err(Error::BadChecksum {
                expected: 3,
                found: 7
            }))
        );
        // An incomplete framed message is abandoned at idle.
        let mut rx = Rx::new(fmt(32));
        assert_eq!(rx.feed(b"\x02AB"), (3, None));
        assert!(rx.in_frame());
        assert_eq!(rx.idle(), Some(Err(Error::Truncated)));
        assert!(!rx.in_frame());
    }

    /// Phoenix manual (003_610fea73110d789e.txt) lines 7204-7217: format 0 adds nothing, 1
    /// appends CR (0x0D) LF (0x0A), 16 appends the XOR check byte, 17 both; line 7279: a
    /// type-22 message waits for ACK (0x06). The wire carries no message type, so each
    /// message a receiver takes in its configured format is one to ACK (types 20 and 21 do
    /// not wait for it): here every format yields the payload of `(>22,<f><FAULT)`.
    #[test]
    fn formats_0_1_16_17_as_the_manual_lists_them() {
        // "FAULT": F^A^U^L^T = 0x4A.
        let cases: [(u8, &[u8]); 4] = [
            (0, b"FAULT"),
            (1, b"FAULT\r\n"),
            (16, b"FAULT\x4A"),
            (17, b"FAULT\r\n\x4A"),
        ];
        for (value, wire) in cases {
            let format = fmt(value);
            let mut out = [0u8; 16];
            let n = super::super::frame(format, b"FAULT", &mut out).unwrap();
            assert_eq!(&out[..n], wire, "format {value}");
            let mut rx = Rx::new(format);
            let (used, outcome) = rx.feed(wire);
            assert_eq!(used, wire.len(), "format {value}");
            let copy =
                |r: Result<&[u8]>| r.map(|m| heapless::Vec::<u8, 32>::from_slice(m).unwrap());
            let got = match outcome {
                Some(r) => Some(copy(r)),
                // 0 and 16 have no end byte: the message ends when the line goes quiet.
                None => rx.idle().map(copy),
            };
            assert_eq!(got, Some(ok(b"FAULT")), "format {value}");
        }
    }

    #[test]
    fn push_and_feed_agree() {
        let wire = b"\x01\x02AB\r\n\x03\x04\x03";
        let mut rx = Rx::new(fmt(113));
        for &b in &wire[..wire.len() - 1] {
            assert_eq!(rx.push(b), None);
        }
        assert_eq!(rx.push(0x03), Some(Ok(&b"AB"[..])));
    }
}
