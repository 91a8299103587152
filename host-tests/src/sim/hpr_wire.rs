//! The HPR simulator's byte edge: `>` + 3-digit command id + data + 2 hex digits of checksum +
//! `<`, the checksum being the low byte of the sum of the id and data characters.

/// Longest frame body the unit buffers before it gives up on a frame.
const MAX_BODY: usize = 256;

/// What a completed frame turned out to be.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Incoming {
    /// Checksum right: command id (None if not three digits) and data.
    Command { id: Option<u16>, data: String },
    /// Checksum wrong, missing, or a character arrived damaged.
    BadChecksum,
}

/// Collects characters between `>` and `<`.
#[derive(Debug, Default)]
pub(crate) struct Assembler {
    body: Vec<u8>,
    in_frame: bool,
    damaged: bool,
}

impl Assembler {
    /// Feeds one character; returns a frame that just ended.
    pub(crate) fn push(&mut self, byte: u8) -> Option<Incoming> {
        match byte {
            b'>' => {
                self.body.clear();
                self.in_frame = true;
                self.damaged = false;
                None
            }
            _ if !self.in_frame => None,
            b'<' => {
                self.in_frame = false;
                let body = std::mem::take(&mut self.body);
                Some(if self.damaged {
                    Incoming::BadChecksum
                } else {
                    parse(&body)
                })
            }
            _ if self.body.len() >= MAX_BODY => {
                self.in_frame = false;
                self.body.clear();
                None
            }
            _ => {
                self.body.push(byte);
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
        self.body.clear();
        self.in_frame = false;
        self.damaged = false;
    }
}

/// Checksum of id + data characters.
pub(crate) fn checksum(text: &[u8]) -> u8 {
    text.iter().fold(0u8, |acc, &b| acc.wrapping_add(b))
}

fn hex_value(c: u8) -> Option<u8> {
    (c as char).to_digit(16).map(|d| d as u8)
}

fn parse(body: &[u8]) -> Incoming {
    if body.len() < 5 {
        return Incoming::BadChecksum;
    }
    let (text, check) = body.split_at(body.len() - 2);
    let given = match (hex_value(check[0]), hex_value(check[1])) {
        (Some(h), Some(l)) => h << 4 | l,
        _ => return Incoming::BadChecksum,
    };
    if checksum(text) != given {
        return Incoming::BadChecksum;
    }
    let id = std::str::from_utf8(&text[..3])
        .ok()
        .filter(|s| s.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|s| s.parse().ok());
    Incoming::Command {
        id,
        data: String::from_utf8_lossy(&text[3..]).into_owned(),
    }
}

/// A frame with command `id` and `data`.
pub(crate) fn encode(id: u16, data: &str) -> Vec<u8> {
    let text = format!("{id:03}{data}");
    format!(">{text}{:02X}<", checksum(text.as_bytes())).into_bytes()
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
