//! Writing reply and event lines, allocation-free, into any [`core::fmt::Write`] (a
//! `heapless::String<N>`, a UART buffer adapter, ...).
//!
//! - `OK key=value key=value` answers a command that succeeded;
//! - `ERR <CODE> <text>` answers one that did not (see [`ErrorCode`]);
//! - `!<event> key=value ...` is an unsolicited event (only after `EVENTS ON`).
//!
//! Every line ends with CR LF. Values are written so that they cannot break the line format:
//! spaces become `_`, and control or non-ASCII characters become `?`; free text (after `ERR`)
//! keeps its spaces.

use core::fmt::{self, Display, Write};

use super::error::{ErrorCode, ParseError};

/// What ends every reply and event line.
pub const LINE_END: &str = "\r\n";

// The writing itself goes through `dyn Write` / `dyn Display`: one copy of each routine serves
// every value type and output, where generics would stamp out one per use (flash on the board).

/// Passes text through, replacing what could split or corrupt a line.
struct Sanitize<'w> {
    out: &'w mut dyn Write,
    keep_spaces: bool,
}

impl Write for Sanitize<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        for c in s.chars() {
            let c = match c {
                ' ' if self.keep_spaces => ' ',
                ' ' | '\t' => '_',
                c if c.is_ascii_graphic() => c,
                _ => '?',
            };
            self.out.write_char(c)?;
        }
        Ok(())
    }
}

fn sanitized(out: &mut dyn Write, keep_spaces: bool, value: &dyn Display) -> fmt::Result {
    write!(Sanitize { out, keep_spaces }, "{value}")
}

fn write_field(out: &mut dyn Write, key: &str, value: &dyn Display) -> fmt::Result {
    out.write_char(' ')?;
    sanitized(out, false, &key)?;
    out.write_char('=')?;
    sanitized(out, false, value)
}

fn write_error_line(out: &mut dyn Write, code: ErrorCode, text: &dyn Display) -> fmt::Result {
    write!(out, "ERR {code} ")?;
    sanitized(out, true, text)?;
    out.write_str(LINE_END)
}

/// Builds one `OK ...` or `!event ...` line.
///
/// ```
/// use core::fmt::Write;
/// use plasma_protocol::cnc::reply::ReplyWriter;
///
/// let mut line = heapless::String::<64>::new();
/// let mut reply = ReplyWriter::ok(&mut line)?;
/// reply.field("amps", 55.5)?;
/// reply.field("mode", "CUT")?;
/// reply.finish()?;
/// assert_eq!(line, "OK amps=55.5 mode=CUT\r\n");
/// # Ok::<(), core::fmt::Error>(())
/// ```
pub struct ReplyWriter<W: Write> {
    out: W,
}

impl<W: Write> ReplyWriter<W> {
    /// Start an `OK` line.
    pub fn ok(mut out: W) -> Result<Self, fmt::Error> {
        out.write_str("OK")?;
        Ok(ReplyWriter { out })
    }

    /// Start an event line: `!` followed by the event name.
    pub fn event(mut out: W, name: &str) -> Result<Self, fmt::Error> {
        out.write_char('!')?;
        sanitized(&mut out, false, &name)?;
        Ok(ReplyWriter { out })
    }

    /// Start a data line of a multi-line reply: `name` followed by fields (the lines
    /// `HISTORY` writes before its closing `OK`).
    pub fn data(mut out: W, name: &str) -> Result<Self, fmt::Error> {
        sanitized(&mut out, false, &name)?;
        Ok(ReplyWriter { out })
    }

    /// Append ` key=value`.
    pub fn field(&mut self, key: &str, value: impl Display) -> fmt::Result {
        write_field(&mut self.out, key, &value)
    }

    /// Append ` word` (a value without a key, e.g. a command name in the `HELP` list).
    pub fn word(&mut self, word: impl Display) -> fmt::Result {
        self.out.write_char(' ')?;
        sanitized(&mut self.out, false, &word)
    }

    /// End the line with CR LF and give the writer back.
    pub fn finish(mut self) -> Result<W, fmt::Error> {
        self.out.write_str(LINE_END)?;
        Ok(self.out)
    }
}

/// Write `ERR <CODE> <text>` and CR LF.
pub fn write_error<W: Write>(out: &mut W, code: ErrorCode, text: impl Display) -> fmt::Result {
    write_error_line(out, code, &text)
}

/// Write the `ERR` line for a line that did not parse.
pub fn write_parse_error<W: Write>(out: &mut W, error: &ParseError) -> fmt::Result {
    write_error(out, error.code(), error)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::Amps;

    #[test]
    fn ok_lines() {
        let mut line = heapless::String::<64>::new();
        ReplyWriter::ok(&mut line).unwrap().finish().unwrap();
        assert_eq!(line, "OK\r\n");
        line.clear();
        let mut r = ReplyWriter::ok(&mut line).unwrap();
        r.field("amps", Amps::from_raw(3552)).unwrap();
        r.field("state", "ready").unwrap();
        r.finish().unwrap();
        assert_eq!(line, "OK amps=55.5 state=ready\r\n");
    }

    #[test]
    fn values_cannot_break_the_line() {
        let mut line = heapless::String::<64>::new();
        let mut r = ReplyWriter::event(&mut line, "fault code").unwrap();
        r.field("text", "Gas pressure\r\nOK").unwrap();
        r.field("bad key", "\u{e9}").unwrap();
        r.word("x y").unwrap();
        r.finish().unwrap();
        assert_eq!(line, "!fault_code text=Gas_pressure??OK bad_key=? x_y\r\n");
    }

    #[test]
    fn error_lines() {
        let mut line = heapless::String::<64>::new();
        write_parse_error(&mut line, &ParseError::MissingArgument { what: "amps" }).unwrap();
        assert_eq!(line, "ERR SYNTAX missing amps\r\n");
        line.clear();
        write_error(&mut line, ErrorCode::Link, "no reply\n").unwrap();
        assert_eq!(line, "ERR LINK no reply?\r\n");
        // Too small a buffer is an error, not a panic.
        let mut tiny = heapless::String::<4>::new();
        assert!(write_error(&mut tiny, ErrorCode::Range, "x").is_err());
    }
}
