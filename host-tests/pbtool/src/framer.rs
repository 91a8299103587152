//! Frames out of a stream of received characters, for logs and the sniffer: a Modbus ASCII
//! frame runs from `:` to LF, an HPR frame from `>` to `<`. Characters outside a frame are
//! kept as noise; a frame cut short by the next start character is reported as incomplete.

use plasma_protocol::time::{Duration, Instant};

use crate::serial::Rx;

/// The longest frame kept (Modbus ASCII allows 513 characters).
const MAX_FRAME: usize = 600;

/// What the stream held.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Piece {
    /// When its first character came.
    pub at: Instant,
    /// Its characters (a flagged character is `?`).
    pub text: String,
    /// Whether it is a whole frame, or noise / an incomplete frame.
    pub complete: bool,
    /// Characters the UART flagged with a parity or framing error.
    pub flagged: u32,
    /// The longest pause between two of its characters.
    pub longest_gap: Duration,
}

/// Splits one direction's characters into [`Piece`]s.
#[derive(Debug, Default)]
pub struct Framer {
    buf: Vec<u8>,
    at: Option<Instant>,
    last: Option<Instant>,
    flagged: u32,
    gap: Duration,
    in_frame: Option<u8>,
}

impl Framer {
    /// One character at `now`; the pieces it completes (at most two: what came before a new
    /// start character, and never more).
    pub fn push(&mut self, now: Instant, rx: Rx, out: &mut Vec<Piece>) {
        let byte = match rx {
            Rx::Byte(b) => b,
            Rx::Error => {
                self.flagged += 1;
                b'?'
            }
        };
        if matches!(rx, Rx::Byte(b':' | b'>')) && !self.buf.is_empty() {
            out.extend(self.take(false));
        }
        if self.buf.is_empty() {
            self.in_frame = match rx {
                Rx::Byte(b':') => Some(b'\n'),
                Rx::Byte(b'>') => Some(b'<'),
                _ => None,
            };
        }
        if let Some(last) = self.last
            && !self.buf.is_empty()
        {
            self.gap = self.gap.max(now.saturating_since(last));
        }
        self.at.get_or_insert(now);
        self.last = Some(now);
        self.buf.push(byte);
        if self.in_frame.is_some_and(|end| end == byte) {
            out.extend(self.take(true));
        } else if self.buf.len() >= MAX_FRAME {
            out.extend(self.take(false));
        }
    }

    /// One character at `now`; the pieces it completes.
    pub fn push_one(&mut self, now: Instant, rx: Rx) -> Vec<Piece> {
        let mut out = Vec::new();
        self.push(now, rx, &mut out);
        out
    }

    /// Whatever is held, as an incomplete piece (the line went quiet).
    pub fn flush(&mut self) -> Option<Piece> {
        self.take(false)
    }

    /// When the last character came, while a piece is held.
    pub fn pending_since(&self) -> Option<Instant> {
        self.last.filter(|_| !self.buf.is_empty())
    }

    fn take(&mut self, complete: bool) -> Option<Piece> {
        if self.buf.is_empty() {
            return None;
        }
        let piece = Piece {
            at: self.at.take().unwrap_or(Instant::ZERO),
            text: String::from_utf8_lossy(&self.buf).into_owned(),
            complete: complete && self.in_frame.is_some(),
            flagged: std::mem::take(&mut self.flagged),
            longest_gap: std::mem::replace(&mut self.gap, Duration::ZERO),
        };
        self.buf.clear();
        self.in_frame = None;
        Some(piece)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn split(chunks: &[(u64, &[u8])]) -> Vec<Piece> {
        let mut framer = Framer::default();
        let mut out = Vec::new();
        for &(ms, bytes) in chunks {
            for &b in bytes {
                framer.push(Instant::from_millis(ms), Rx::Byte(b), &mut out);
            }
        }
        out.extend(framer.flush());
        out
    }

    #[test]
    fn modbus_and_hpr_frames_are_cut_at_their_ends() {
        let pieces = split(&[(0, b":0104300000"), (7, b"01CA\r\n>00090<")]);
        let texts: Vec<_> = pieces
            .iter()
            .map(|p| (p.text.as_str(), p.complete))
            .collect();
        assert_eq!(texts, [(":010430000001CA\r\n", true), (">00090<", true)]);
        assert_eq!(pieces[0].longest_gap, Duration::from_millis(7));
        assert_eq!(pieces[1].at, Instant::from_millis(7));
    }

    #[test]
    fn noise_and_cut_frames_are_kept_apart() {
        let pieces = split(&[(0, b"xx:0104"), (5, b":01\r\n>0")]);
        let texts: Vec<_> = pieces
            .iter()
            .map(|p| (p.text.as_str(), p.complete))
            .collect();
        assert_eq!(
            texts,
            [
                ("xx", false),
                (":0104", false),
                (":01\r\n", true),
                (">0", false)
            ]
        );
    }

    #[test]
    fn flagged_characters_are_counted_in_their_frame() {
        let mut framer = Framer::default();
        let mut out = Vec::new();
        for rx in [Rx::Byte(b'>'), Rx::Error, Rx::Byte(b'<')] {
            framer.push(Instant::ZERO, rx, &mut out);
        }
        assert_eq!(out[0].text, ">?<");
        assert_eq!(out[0].flagged, 1);
    }
}
