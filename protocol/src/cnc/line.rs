//! Splitting the CNC's byte stream into command lines.

/// The longest command line, terminator excluded.
pub const MAX_LINE_LEN: usize = 128;

/// Why a line was dropped. Reported once per line; the session goes on with the next one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LineError {
    /// More than [`MAX_LINE_LEN`] characters before the terminator.
    TooLong,
    /// A byte that is not printable ASCII (nor a tab): binary data, noise or a wrong baud rate.
    Binary,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    Pending,
    Line { start: usize, end: usize },
    Dropped(LineError),
}

/// Assembles command lines from bytes, with a fixed [`MAX_LINE_LEN`]-byte buffer.
///
/// - A line ends at CR, LF or CR LF (one line, not an extra empty one).
/// - Lines are trimmed of spaces and tabs; blank lines are skipped silently.
/// - A line longer than [`MAX_LINE_LEN`] yields [`LineError::TooLong`] as soon as it
///   overflows; a non-printable byte yields [`LineError::Binary`] at once. Either way the rest
///   of that line, up to its terminator, is discarded.
///
/// Sans-IO: [`push`](Self::push) one byte or [`feed`](Self::feed) a chunk; the lines are the
/// same however the stream is cut.
///
/// ```
/// use plasma_protocol::cnc::line::{LineAssembler, LineError};
///
/// let mut lines = LineAssembler::new();
/// let mut input: &[u8] = b"status\r\nset amps 45.5\r\n";
/// let (used, line) = lines.feed(input);
/// assert_eq!(line, Some(Ok("status")));
/// input = &input[used..];
/// let (_, line) = lines.feed(input);
/// assert_eq!(line, Some(Ok("set amps 45.5")));
/// ```
#[derive(Debug, Clone)]
pub struct LineAssembler {
    buf: [u8; MAX_LINE_LEN],
    len: usize,
    discarding: bool,
    after_cr: bool,
}

impl Default for LineAssembler {
    fn default() -> Self {
        Self::new()
    }
}

impl LineAssembler {
    /// An empty assembler.
    pub const fn new() -> Self {
        LineAssembler {
            buf: [0; MAX_LINE_LEN],
            len: 0,
            discarding: false,
            after_cr: false,
        }
    }

    /// Drop any partial line.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// Whether part of a line has been received.
    pub fn is_empty(&self) -> bool {
        self.len == 0 && !self.discarding
    }

    /// Take one byte; returns a line (or why it was dropped) when this byte completes it.
    pub fn push(&mut self, byte: u8) -> Option<Result<&str, LineError>> {
        let step = self.step(byte);
        self.outcome(step)
    }

    /// Take bytes from `input` until a line completes or `input` runs out; returns how many
    /// bytes were used and the outcome, if any. Feed the rest of `input` again afterwards.
    pub fn feed(&mut self, input: &[u8]) -> (usize, Option<Result<&str, LineError>>) {
        for (i, &byte) in input.iter().enumerate() {
            let step = self.step(byte);
            if step != Step::Pending {
                return (i + 1, self.outcome(step));
            }
        }
        (input.len(), None)
    }

    fn outcome(&self, step: Step) -> Option<Result<&str, LineError>> {
        match step {
            Step::Pending => None,
            Step::Line { start, end } => {
                let bytes = self.buf.get(start..end).unwrap_or_default();
                // Only printable ASCII is stored, so this is always valid UTF-8.
                Some(core::str::from_utf8(bytes).map_err(|_| LineError::Binary))
            }
            Step::Dropped(error) => Some(Err(error)),
        }
    }

    fn step(&mut self, byte: u8) -> Step {
        let after_cr = core::mem::replace(&mut self.after_cr, false);
        if byte == b'\r' || byte == b'\n' {
            if byte == b'\n' && after_cr {
                // The LF of a CR LF pair: the line already ended at the CR.
                return Step::Pending;
            }
            self.after_cr = byte == b'\r';
            let len = core::mem::take(&mut self.len);
            if core::mem::take(&mut self.discarding) {
                return Step::Pending;
            }
            let line = self.buf.get(..len).unwrap_or_default();
            let is_blank = |b: &u8| *b == b' ' || *b == b'\t';
            let start = line.iter().position(|b| !is_blank(b));
            let end = line.iter().rposition(|b| !is_blank(b));
            return match (start, end) {
                (Some(start), Some(end)) => Step::Line {
                    start,
                    end: end + 1,
                },
                _ => Step::Pending,
            };
        }
        if self.discarding {
            return Step::Pending;
        }
        if !(byte == b'\t' || (0x20..0x7F).contains(&byte)) {
            self.discarding = true;
            self.len = 0;
            return Step::Dropped(LineError::Binary);
        }
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
                Step::Pending
            }
            None => {
                self.discarding = true;
                self.len = 0;
                Step::Dropped(LineError::TooLong)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Outcome = Result<heapless::String<MAX_LINE_LEN>, LineError>;

    fn all(input: &[u8]) -> heapless::Vec<Outcome, 16> {
        let mut lines = LineAssembler::new();
        let mut out = heapless::Vec::new();
        let mut rest = input;
        while !rest.is_empty() {
            let (used, line) = lines.feed(rest);
            rest = &rest[used..];
            if let Some(line) = line {
                out.push(line.map(|l| heapless::String::try_from(l).unwrap()))
                    .unwrap();
            }
        }
        out
    }

    fn ok(s: &str) -> Outcome {
        Ok(heapless::String::try_from(s).unwrap())
    }

    #[test]
    fn terminators() {
        assert_eq!(&all(b"a\rb\nc\r\nd")[..], &[ok("a"), ok("b"), ok("c")]);
        // CR LF is one terminator; LF CR is two (the second ends a blank line, skipped).
        assert_eq!(&all(b"a\r\n\r\nb\n\rc\r")[..], &[ok("a"), ok("b"), ok("c")]);
        // A CR split from its LF across chunks is still one terminator.
        let mut lines = LineAssembler::new();
        assert_eq!(lines.feed(b"x\r"), (2, Some(Ok("x"))));
        assert_eq!(lines.feed(b"\ny\n"), (3, Some(Ok("y"))));
    }

    #[test]
    fn trimming_and_blank_lines() {
        assert_eq!(&all(b"  \t\r\n \tID  \r\n")[..], &[ok("ID")]);
    }

    #[test]
    fn too_long_is_reported_once_then_the_line_is_discarded() {
        let mut input = [b'a'; 200];
        input[199] = b'\n';
        let mut with_next: heapless::Vec<u8, 256> = heapless::Vec::from_slice(&input).unwrap();
        with_next.extend_from_slice(b"ID\n").unwrap();
        assert_eq!(&all(&with_next)[..], &[Err(LineError::TooLong), ok("ID")]);
        // Exactly 128 characters fit.
        let mut exact = [b'b'; 129];
        exact[128] = b'\r';
        let lines = all(&exact);
        assert_eq!(lines.len(), 1);
        assert_eq!(lines[0].as_ref().map(|l| l.len()), Ok(128));
    }

    #[test]
    fn binary_is_reported_once_per_line() {
        assert_eq!(
            &all(b"ST\x00\xffATUS\r\nID\r\n\x02\x03\n")[..],
            &[Err(LineError::Binary), ok("ID"), Err(LineError::Binary)]
        );
        assert_eq!(&all(b"\x7f\n")[..], &[Err(LineError::Binary)]);
    }

    #[test]
    fn push_matches_feed() {
        let mut lines = LineAssembler::new();
        assert!(lines.is_empty());
        for &b in b"HELP" {
            assert_eq!(lines.push(b), None);
        }
        assert!(!lines.is_empty());
        assert_eq!(lines.push(b'\n'), Some(Ok("HELP")));
        lines.push(b'x');
        lines.reset();
        assert!(lines.is_empty());
    }
}
