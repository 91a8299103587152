//! The HPR simulator's byte edge: `>` + 3-digit command id + data + 2 hex digits of checksum +
//! `<`. Parsing and emitting go through [`plasma_protocol::hpr::Frame`]; this file only keeps
//! the raw characters of a frame so the unit can tell a bad checksum (500) from an unknown
//! command (501) the way the manual describes.

use plasma_protocol::Error;
use plasma_protocol::hpr::{Frame, MAX_FRAME_LEN};

/// What a completed frame turned out to be.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Incoming {
    /// Checksum right: command id (None if not three digits) and data.
    Command { id: Option<u16>, data: String },
    /// Checksum wrong, missing, or a character arrived damaged.
    BadChecksum,
}

/// Collects the characters of a frame, `>` to `<`.
#[derive(Debug, Default)]
pub(crate) struct Assembler {
    raw: Vec<u8>,
    in_frame: bool,
    damaged: bool,
}

impl Assembler {
    /// Feeds one character; returns a frame that just ended.
    pub(crate) fn push(&mut self, byte: u8) -> Option<Incoming> {
        match byte {
            b'>' => {
                self.raw.clear();
                self.raw.push(byte);
                self.in_frame = true;
                self.damaged = false;
                None
            }
            _ if !self.in_frame => None,
            _ if self.raw.len() >= MAX_FRAME_LEN => {
                // Longer than any frame: the unit gives up on it silently.
                self.reset();
                None
            }
            b'<' => {
                self.raw.push(byte);
                self.in_frame = false;
                let raw = std::mem::take(&mut self.raw);
                Some(if self.damaged {
                    Incoming::BadChecksum
                } else {
                    classify(&raw)
                })
            }
            _ => {
                self.raw.push(byte);
                None
            }
        }
    }

    /// A character arrived with a UART error: the frame in progress cannot check out.
    pub(crate) fn damage(&mut self) {
        if self.in_frame {
            self.damaged = true;
        }
    }

    /// Forgets any partial frame.
    pub(crate) fn reset(&mut self) {
        self.raw.clear();
        self.in_frame = false;
        self.damaged = false;
    }
}

/// Sum of the characters between the delimiters minus the checksum, against the checksum.
fn checksum_matches(raw: &[u8]) -> bool {
    let Some(inner) = raw.get(1..raw.len().saturating_sub(1)) else {
        return false;
    };
    let Some((text, ck)) = inner.split_at_checked(inner.len().saturating_sub(2)) else {
        return false;
    };
    let sum = text.iter().fold(0u8, |acc, &b| acc.wrapping_add(b));
    std::str::from_utf8(ck)
        .ok()
        .and_then(|s| u8::from_str_radix(s, 16).ok())
        .is_some_and(|given| ck.len() == 2 && given == sum)
}

fn classify(raw: &[u8]) -> Incoming {
    match Frame::parse(raw) {
        Ok(frame) => Incoming::Command {
            id: Some(frame.id),
            data: String::from_utf8_lossy(frame.data).into_owned(),
        },
        // A non-digit id with a right checksum is a command the unit does not know.
        Err(Error::Malformed)
            if checksum_matches(raw)
                && !raw
                    .get(1..4)
                    .is_some_and(|d| d.iter().all(u8::is_ascii_digit)) =>
        {
            Incoming::Command {
                id: None,
                data: String::new(),
            }
        }
        Err(_) => Incoming::BadChecksum,
    }
}

/// A frame with command `id` and `data` (printable ASCII, short enough: the simulator's own
/// replies always are).
pub(crate) fn encode(id: u16, data: &str) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    match Frame::new(id, data.as_bytes()).emit(&mut buf) {
        Ok(n) => buf[..n].to_vec(),
        Err(e) => panic!("simulator reply {id:03} {data:?} cannot be framed: {e:?}"),
    }
}

/// Checksum of id + data characters as text, for tests that build expected frames.
#[cfg(test)]
pub(crate) fn checksum(text: &[u8]) -> u8 {
    text.iter().fold(0u8, |acc, &b| acc.wrapping_add(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed(text: &str) -> Option<Incoming> {
        let mut a = Assembler::default();
        text.bytes().filter_map(|b| a.push(b)).last()
    }

    #[test]
    fn manual_frames_parse_and_encode() {
        assert_eq!(
            feed(">00090<"),
            Some(Incoming::Command {
                id: Some(0),
                data: String::new()
            })
        );
        assert_eq!(encode(0, ""), b">00090<");
        assert_eq!(encode(58, "0130"), b">058013061<");
        assert_eq!(encode(500, ""), b">50095<");
        assert_eq!(
            feed(">095100 75 1 6 55 45 35 25 00 0084<"),
            Some(Incoming::Command {
                id: Some(95),
                data: "100 75 1 6 55 45 35 25 00 00".into()
            })
        );
    }

    #[test]
    fn bad_frames() {
        // The guide's bad-checksum example.
        assert_eq!(feed(">00091<"), Some(Incoming::BadChecksum));
        assert_eq!(feed(">0<"), Some(Incoming::BadChecksum));
        assert_eq!(
            feed(">999AB<"),
            Some(Incoming::Command {
                id: Some(999),
                data: String::new()
            })
        );
        // Letters for an id, checksum right: an unknown command, not a bad checksum.
        let ck = checksum(b"AB0");
        assert_eq!(
            feed(&format!(">AB0{ck:02X}<")),
            Some(Incoming::Command {
                id: None,
                data: String::new()
            })
        );
        // A lower-case checksum is still a checksum.
        assert_eq!(
            feed(">0850cd<"),
            Some(Incoming::Command {
                id: Some(85),
                data: "0".into()
            })
        );
        // A '>' restarts the frame.
        assert_eq!(
            feed(">12>00090<"),
            Some(Incoming::Command {
                id: Some(0),
                data: String::new()
            })
        );
    }
}
