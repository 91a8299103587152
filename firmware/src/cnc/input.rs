//! From CNC bytes to commands in turn: text lines and Phoenix messages (framed by SOH/STX, or
//! in an unframed format 0, 1, 16 or 17), ACK/NAK, the queue of lines that wait behind a
//! command in progress.

use plasma_protocol::cnc::phoenix::{self, Deframer, Format};
use plasma_protocol::cnc::reply::write_parse_error;
use plasma_protocol::cnc::{
    AMPS_ARGUMENT, Command, ErrorCode, LineError, MAX_LINE_LEN, ParseError, split_unit,
};

use super::replies::AmpsRange;
use super::texts::{self, frame_error};
use super::{Context, LineText, ReplyLine, Session, err_line, line};
use crate::storage::history::ChangedBy;

/// Why an input could not become a command; answered in turn like a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum InputError {
    Parse(ParseError),
    Frame(plasma_protocol::Error),
    Interrupted,
}

/// A command line (or a refused input) waiting for its turn.
#[derive(Debug, Clone)]
pub(super) struct Item {
    text: LineText,
    error: Option<InputError>,
    /// Came as a Phoenix message (not a text line).
    framed: bool,
}

impl Item {
    fn refused(error: InputError) -> Self {
        Item {
            text: LineText::new(),
            error: Some(error),
            framed: false,
        }
    }
}

impl Session {
    /// One byte from the CNC: to the deframer inside a frame, else to the line assembler.
    pub(super) fn route(&mut self, ctx: &mut Context<'_>, byte: u8) {
        if self.deframer.in_frame() {
            return self.deframe(ctx, byte);
        }
        // A `:` between lines opens a Modbus ASCII request (no text command starts with one);
        // inside a line, even one being discarded, it is text.
        let between_lines = !self.text_partial && !self.text_discarding;
        if self.powermax.in_frame() || (byte == b':' && between_lines) {
            return self.powermax_byte(ctx, byte);
        }
        if phoenix::is_frame_start(byte) {
            self.start_frame(ctx, byte);
            return self.deframe(ctx, byte);
        }
        if ctx.settings.phoenix_format.start_byte().is_none() {
            // Line ends between messages are skipped, as blank lines are: the LF after the
            // CR of the text line that set the format, a CNC's stray CR LF.
            if byte == b'\r' || byte == b'\n' {
                return;
            }
            self.start_unframed(ctx);
            return self.deframe(ctx, byte);
        }
        self.push_text_byte(ctx, byte);
    }

    /// Formats 0, 1, 16 and 17 open with the message itself: with one of them configured,
    /// every input that is neither a Modbus request nor a SOH/STX frame is a message of that
    /// format (format 1: a CR LF line; 0 and 16 end when the line goes quiet), ACKed like a
    /// framed one. Text lines are messages then, not plain lines.
    fn start_unframed(&mut self, ctx: &mut Context<'_>) {
        let configured = ctx.settings.phoenix_format;
        if self.deframer.format() != configured {
            self.deframer = Deframer::new(configured);
        }
        self.raw_frame.clear();
        self.deferred = None;
    }

    /// A frame begins on `start` (SOH or STX): a text line it interrupts is answered with an
    /// `ERR`, and the deframer takes the format recognised on the port, else the configured
    /// one, else the first one that starts with this byte.
    fn start_frame(&mut self, ctx: &mut Context<'_>, start: u8) {
        if self.text_partial {
            self.admit(ctx, Item::refused(InputError::Interrupted));
        }
        self.lines.reset();
        self.text_partial = false;
        self.text_discarding = false;
        let configured = ctx.settings.phoenix_format;
        if configured != self.configured_format {
            self.configured_format = configured;
            self.recognised = None;
        }
        let starts = |f: &Format| f.start_byte() == Some(start);
        let format = self
            .recognised
            .filter(starts)
            .or(Some(configured).filter(starts))
            .or_else(|| candidates(start).next())
            .unwrap_or(configured);
        if self.deframer.format() != format {
            self.deframer = Deframer::new(format);
        }
        self.raw_frame.clear();
        self.deferred = None;
    }

    /// A byte of a Modbus request: its reply goes out at once, ahead of text replies that
    /// wait for the link (a Powermax master allows 100 ms).
    fn powermax_byte(&mut self, ctx: &mut Context<'_>, byte: u8) {
        use super::powermax_port::Step;
        match self.powermax.push(ctx, byte) {
            Step::Pending => {}
            Step::Reply => {
                let reply = self.powermax.reply();
                if !self.out.push(reply) {
                    self.stats.output_dropped = self.stats.output_dropped.saturating_add(1);
                }
            }
            Step::Refused(fault) => {
                let reply = self.powermax.reply();
                if !self.out.push(reply) {
                    self.stats.output_dropped = self.stats.output_dropped.saturating_add(1);
                }
                self.settings_refused_event(ctx, fault);
            }
        }
    }

    fn push_text_byte(&mut self, ctx: &mut Context<'_>, byte: u8) {
        let outcome = self
            .lines
            .push(byte)
            .map(|r| r.map(|text| LineText::try_from(text).unwrap_or_default()));
        match outcome {
            None => self.note_partial_line(byte),
            Some(Ok(text)) => {
                self.text_partial = false;
                self.text_discarding = false;
                self.admit(
                    ctx,
                    Item {
                        text,
                        error: None,
                        framed: false,
                    },
                );
            }
            Some(Err(error)) => {
                self.text_partial = false;
                self.text_discarding = true;
                let error = match error {
                    LineError::TooLong => ParseError::TooLong,
                    LineError::Binary => ParseError::Binary,
                };
                self.admit(ctx, Item::refused(InputError::Parse(error)));
            }
        }
    }

    /// A byte the assembler kept: whether a line (not only blanks) is under way.
    fn note_partial_line(&mut self, byte: u8) {
        if byte == b'\r' || byte == b'\n' {
            self.text_partial = false;
            self.text_discarding = false;
        } else if !self.text_discarding && byte != b' ' && byte != b'\t' {
            self.text_partial = true;
        }
    }

    fn deframe(&mut self, ctx: &mut Context<'_>, byte: u8) {
        if phoenix::is_frame_start(byte) && !self.deframer.in_frame() {
            self.raw_frame.clear();
        }
        // A frame longer than the buffer is refused as overlong by the deframer anyway.
        let _ = self.raw_frame.push(byte);
        let outcome = self
            .deframer
            .push(byte)
            .map(|outcome| outcome.map(message_item));
        let frame_over = !self.deframer.in_frame();
        let item = match outcome {
            None if self.deferred.is_some() && frame_over => self.recognise_or_refuse(),
            None => return,
            Some(Ok(item)) => item,
            // A start byte broke the frame off: it is refused now, and `byte` begins the next.
            Some(Err(plasma_protocol::Error::Truncated)) => {
                self.raw_frame.clear();
                let _ = self.raw_frame.push(byte);
                self.deferred = None;
                Item::refused(InputError::Frame(plasma_protocol::Error::Truncated))
            }
            Some(Err(error)) => {
                // The expected format does not fit: decide once the whole frame is in.
                self.deferred = Some(error);
                if !frame_over {
                    return;
                }
                self.recognise_or_refuse()
            }
        };
        self.framed(ctx, item);
    }

    /// A Phoenix frame idle for too long is abandoned (NAK), unless it is a whole frame of
    /// another format (one without a check byte, which the deframer was still waiting for).
    pub(super) fn abandon_frame(&mut self, ctx: &mut Context<'_>) {
        let item = match self.deframer.idle() {
            Some(Err(error)) => {
                self.deferred = Some(error);
                self.recognise_or_refuse()
            }
            Some(Ok(payload)) => message_item(payload),
            None if self.deferred.is_some() => self.recognise_or_refuse(),
            None => return,
        };
        self.framed(ctx, item);
    }

    /// The frame failed in the format the deframer expected: the first other format with the
    /// same start byte that takes the whole frame is recognised (and used from now on);
    /// otherwise the frame is refused with the first error.
    fn recognise_or_refuse(&mut self) -> Item {
        let error = self
            .deferred
            .take()
            .unwrap_or(plasma_protocol::Error::Malformed);
        let raw = &self.raw_frame;
        let tried = self.deframer.format();
        let found = raw.first().and_then(|&start| {
            candidates(start)
                .filter(|&f| f != tried)
                .find_map(|f| whole_frame(f, raw).map(|item| (f, item)))
        });
        self.raw_frame.clear();
        match found {
            Some((format, item)) => {
                self.recognised = Some(format);
                self.deframer = Deframer::new(format);
                item
            }
            None => Item::refused(InputError::Frame(error)),
        }
    }

    /// A framed message is complete: ACK or NAK it at once, answer it in turn.
    fn framed(&mut self, ctx: &mut Context<'_>, item: Item) {
        let accepted = item.error.is_none() && self.has_room();
        self.ack(accepted);
        self.admit(ctx, item);
    }

    fn has_room(&self) -> bool {
        (self.pending.is_none() && self.queue.is_empty()) || !self.queue.is_full()
    }

    /// Answer `item` now, or queue it behind the command in progress.
    fn admit(&mut self, ctx: &mut Context<'_>, item: Item) {
        if self.pending.is_none() && self.queue.is_empty() {
            return self.execute(ctx, item);
        }
        if self.queue.push_back(item).is_err() {
            self.send_untagged(err_line(ErrorCode::Busy, texts::QUEUE_FULL));
        }
    }

    /// Answer one item: its input error, or the command's reply (none yet when it waits).
    pub(super) fn execute(&mut self, ctx: &mut Context<'_>, item: Item) {
        self.origin = if item.framed {
            ChangedBy::Phoenix
        } else {
            ChangedBy::Text
        };
        self.answering = 0;
        ctx.unit = 0;
        let reply = match item.error {
            Some(InputError::Parse(error)) => parse_error(ctx, &error),
            Some(InputError::Frame(error)) => frame_error(error),
            Some(InputError::Interrupted) => err_line(ErrorCode::Syntax, texts::LINE_INTERRUPTED),
            None => match split_unit(&item.text) {
                Err(error) => parse_error(ctx, &error),
                Ok((unit, text)) => {
                    let unit = usize::from(unit) - 1;
                    let count = ctx.units.count();
                    if unit >= count {
                        self.send_untagged(err_line(
                            ErrorCode::Range,
                            texts::NoSuchUnit { unit, count },
                        ));
                        return;
                    }
                    self.answering = unit;
                    ctx.unit = unit;
                    match Command::parse(text) {
                        Err(error) => parse_error(ctx, &error),
                        Ok(command) => match self.run(ctx, command) {
                            Some(reply) => reply,
                            None => return,
                        },
                    }
                }
            },
        };
        self.send(reply);
    }
}

/// The reply to a line that did not parse. A current outside every unit's bounds quotes the
/// range of the unit on the line when the link knows it (what LIMITS shows), not the bounds.
fn parse_error(ctx: &Context<'_>, error: &ParseError) -> ReplyLine {
    let status = ctx.link().status();
    let family = status.family.filter(|_| status.link_up);
    match (error, AmpsRange::of(status, family)) {
        (ParseError::OutOfRange { what, .. }, Some(range)) if *what == AMPS_ARGUMENT => {
            texts::amps_out_of_range(range, family)
        }
        _ => line(|l| write_parse_error(l, error)),
    }
}

/// The framed formats that open with `start`, the most complete first (113: SOH, STX, CR LF,
/// ETX, EOT, check byte).
fn candidates(start: u8) -> impl Iterator<Item = Format> {
    Format::ALL
        .into_iter()
        .rev()
        .filter(move |f| f.start_byte() == Some(start))
}

/// The item for `raw` if it is exactly one whole frame of `format` (idle ends a frame whose
/// format has no check byte).
fn whole_frame(format: Format, raw: &[u8]) -> Option<Item> {
    let mut deframer: Deframer = Deframer::new(format);
    let (used, outcome) = deframer.feed(raw);
    match outcome {
        Some(Ok(payload)) if used == raw.len() => Some(message_item(payload)),
        None => match deframer.idle() {
            Some(Ok(payload)) => Some(message_item(payload)),
            _ => None,
        },
        _ => None,
    }
}

/// The item for a framed message's payload: a command line, or why it is not one.
fn message_item(payload: &[u8]) -> Item {
    let trimmed = payload.trim_ascii();
    let error = if trimmed.len() > MAX_LINE_LEN {
        Some(InputError::Parse(ParseError::TooLong))
    } else if !trimmed
        .iter()
        .all(|&b| b == b'\t' || (0x20..0x7F).contains(&b))
    {
        Some(InputError::Parse(ParseError::Binary))
    } else {
        None
    };
    let text = match error {
        Some(_) => LineText::new(),
        None => core::str::from_utf8(trimmed)
            .ok()
            .and_then(|t| LineText::try_from(t).ok())
            .unwrap_or_default(),
    };
    let error = error.or_else(|| Command::parse(&text).err().map(InputError::Parse));
    Item {
        text,
        error,
        framed: true,
    }
}

#[cfg(test)]
mod tests;
