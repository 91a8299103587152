//! The message command as written in a part program: `>20+Format+Delay+Port<Message`.

use super::{Format, MAX_MESSAGE_LEN, decode_escapes};
use crate::decimal::parse_decimal;
use crate::{Error, Result};

/// The message command types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MessageType {
    /// `>20`: the program waits until the message is sent, then the optional delay.
    Delay,
    /// `>21`: sent while the program goes on; no delay, no acknowledge.
    NoDelay,
    /// `>22`: the program waits for ACK; NAK makes the CNC send it again; the optional
    /// value is the time-out.
    Acknowledge,
}

impl MessageType {
    /// The number written after `>`.
    pub const fn code(self) -> u8 {
        match self {
            MessageType::Delay => 20,
            MessageType::NoDelay => 21,
            MessageType::Acknowledge => 22,
        }
    }

    /// Whether the CNC waits for ACK / NAK after this message.
    pub const fn needs_ack(self) -> bool {
        matches!(self, MessageType::Acknowledge)
    }
}

/// One `>2x[,format[,delay[,port]]]<text` command from a part program (without the
/// comment characters around it: `(`..`)` in WORD ADDRESS programs, `3`..`4` in ESSI).
///
/// ```
/// use plasma_protocol::cnc::phoenix::{MessageType, ProgramMessage};
///
/// // The manual's example.
/// let m = ProgramMessage::parse(">20,1,1,0<Message")?;
/// assert_eq!(m.kind, MessageType::Delay);
/// assert_eq!(m.format.value(), 1);
/// assert_eq!(m.delay_centis, Some(100));
/// assert_eq!(m.port, 0);
/// assert_eq!(m.text, "Message");
/// # Ok::<(), plasma_protocol::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ProgramMessage<'a> {
    /// `>20`, `>21` or `>22`.
    pub kind: MessageType,
    /// Format value; 0 when omitted.
    pub format: Format,
    /// Delay (type 20) or time-out (type 22) in 1/100 s, 0..=99999 ("3.2 format",
    /// 0.00 to 999.99 s); `None` when omitted (type 22 then uses the Ports screen value).
    pub delay_centis: Option<u32>,
    /// 0 = messaging port 1 (the default), 1 = port 2.
    pub port: u8,
    /// The message text, with its two-character codes (see [`ProgramMessage::decode_text`]).
    pub text: &'a str,
}

/// Field delimiters the manual allows between the command fields.
fn is_delimiter(c: char) -> bool {
    matches!(c, '+' | '-' | ',' | ' ')
}

impl<'a> ProgramMessage<'a> {
    /// Parse a command; [`Error::Malformed`] for a bad field, [`Error::Overlong`] over the
    /// manual's 300 characters (command characters included), [`Error::Truncated`] without
    /// the closing `<`.
    pub fn parse(command: &'a str) -> Result<Self> {
        if command.len() > MAX_MESSAGE_LEN {
            return Err(Error::Overlong);
        }
        let rest = command.strip_prefix('>').ok_or(Error::Malformed)?;
        let (fields, text) = rest.split_once('<').ok_or(Error::Truncated)?;
        let mut fields = fields.split(is_delimiter).filter(|f| !f.is_empty());
        let kind = match fields.next() {
            Some("20") => MessageType::Delay,
            Some("21") => MessageType::NoDelay,
            Some("22") => MessageType::Acknowledge,
            _ => return Err(Error::Malformed),
        };
        let format = match fields.next() {
            Some(f) => Format::from_value(parse_small(f, 255)? as u8)?,
            None => Format::PLAIN,
        };
        let delay_centis = fields.next().map(parse_seconds).transpose()?;
        if kind == MessageType::NoDelay && delay_centis.is_some_and(|d| d != 0) {
            // "No delay is supported for Message Type 21."
            return Err(Error::Malformed);
        }
        let port = match fields.next() {
            Some(p) => parse_small(p, 1)? as u8,
            None => 0,
        };
        if fields.next().is_some() {
            return Err(Error::Malformed);
        }
        Ok(ProgramMessage {
            kind,
            format,
            delay_centis,
            port,
            text,
        })
    }

    /// The bytes the CNC sends for [`text`](Self::text) (two-character codes resolved).
    pub fn decode_text(&self, out: &mut [u8]) -> Result<usize> {
        decode_escapes(self.text.as_bytes(), out)
    }
}

/// Decimal integer 0..=max.
fn parse_small(field: &str, max: u32) -> Result<u32> {
    let value = parse_decimal(field.as_bytes(), 3)?;
    if value > max {
        return Err(Error::Malformed);
    }
    Ok(value)
}

/// Seconds in "3.2 format": up to three integer and two decimal digits.
fn parse_seconds(field: &str) -> Result<u32> {
    let (int, frac) = field.split_once('.').unwrap_or((field, ""));
    let digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if int.is_empty() || int.len() > 3 || frac.len() > 2 || !digits(int) || !digits(frac) {
        return Err(Error::Malformed);
    }
    if field.contains('.') && frac.is_empty() {
        return Err(Error::Malformed);
    }
    let seconds = int.bytes().fold(0u32, |a, b| a * 10 + u32::from(b - b'0'));
    let mut centis = frac.bytes().fold(0u32, |a, b| a * 10 + u32::from(b - b'0'));
    if frac.len() == 1 {
        centis *= 10;
    }
    Ok(seconds * 100 + centis)
}

#[cfg(test)]
mod tests {
    use super::super::frame;
    use super::*;

    #[test]
    fn manual_essi_and_eia_examples() {
        // ESSI: `3` opens and `4` closes a comment; EIA: `(` .. `)`.
        for program in ["3>20,1,1,0<Message4", "(>20,1,1,0<Message)"] {
            let inner = &program[1..program.len() - 1];
            let m = ProgramMessage::parse(inner).unwrap();
            assert_eq!(m.kind, MessageType::Delay);
            assert_eq!(
                (m.format.value(), m.delay_centis, m.port),
                (1, Some(100), 0)
            );
            assert_eq!(m.text, "Message");
            let mut text = [0u8; 16];
            let n = m.decode_text(&mut text).unwrap();
            let mut wire = [0u8; 32];
            let len = frame(m.format, &text[..n], &mut wire).unwrap();
            assert_eq!(&wire[..len], b"Message\r\n");
        }
    }

    #[test]
    fn delimiters_and_optional_fields() {
        let m = ProgramMessage::parse(">22+113+2.5+1<SET AMPS 45").unwrap();
        assert_eq!(m.kind, MessageType::Acknowledge);
        assert!(m.kind.needs_ack());
        assert_eq!(
            (m.format.value(), m.delay_centis, m.port),
            (113, Some(250), 1)
        );
        assert_eq!(m.text, "SET AMPS 45");
        let m = ProgramMessage::parse(">21 33<x").unwrap();
        assert_eq!((m.format.value(), m.delay_centis, m.port), (33, None, 0));
        let m = ProgramMessage::parse(">22<").unwrap();
        assert_eq!((m.format, m.text), (Format::PLAIN, ""));
        assert_eq!(
            ProgramMessage::parse(">20-0-999.99<a")
                .unwrap()
                .delay_centis,
            Some(99999)
        );
    }

    #[test]
    fn bad_commands_are_refused() {
        assert_eq!(ProgramMessage::parse(">23<x"), Err(Error::Malformed));
        assert_eq!(ProgramMessage::parse(">20,2<x"), Err(Error::Malformed));
        assert_eq!(ProgramMessage::parse(">20,1,1000<x"), Err(Error::Malformed));
        assert_eq!(
            ProgramMessage::parse(">20,1,1.234<x"),
            Err(Error::Malformed)
        );
        assert_eq!(ProgramMessage::parse(">20,1,1,2<x"), Err(Error::Malformed));
        assert_eq!(
            ProgramMessage::parse(">20,1,1,0,0<x"),
            Err(Error::Malformed)
        );
        assert_eq!(ProgramMessage::parse(">21,0,5<x"), Err(Error::Malformed));
        assert_eq!(ProgramMessage::parse(">20,1"), Err(Error::Truncated));
        assert_eq!(ProgramMessage::parse("20<x"), Err(Error::Malformed));
        let mut long = heapless::String::<320>::new();
        long.push_str(">20<").unwrap();
        for _ in 0..297 {
            long.push('x').unwrap();
        }
        assert_eq!(ProgramMessage::parse(&long), Err(Error::Overlong));
        assert!(ProgramMessage::parse(&long[..300]).is_ok());
    }
}
