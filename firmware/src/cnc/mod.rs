//! The CNC session: the bridge's text protocol and Phoenix serial messaging, sans-IO.
//!
//! Bytes from the CNC port go in ([`Session::handle_rx`]); reply lines, event lines and
//! ACK/NAK bytes come out ([`Session::poll_output`]). The session runs each command against
//! a [`Context`] (the link, the settings, the discrete-I/O snapshot) that the
//! [`Bridge`](crate::bridge::Bridge) lends it for the call. The protocol itself is documented
//! in `docs/cnc-protocol.md`.
//!
//! # Input
//! A byte that opens a Phoenix frame (SOH or STX, [`phoenix::is_frame_start`](plasma_protocol::cnc::phoenix::is_frame_start)) between two
//! inputs goes to the [`Deframer`] of the configured format; everything else to the
//! [`LineAssembler`] (CR, LF or CR LF; at most 128 characters). A text line that a frame
//! start interrupts is dropped with an `ERR`. With an unframed format configured (0, 1, 16 or
//! 17, which open with the message itself) the other bytes go to that format's [`Deframer`]
//! instead: every input is then a message, ACKed or NAKed.
//!
//! # One reply per command, in order
//! Every command line (and every framed message) gets exactly one reply line: `OK ...` or
//! `ERR <CODE> <text>`. A command that needs the unit is submitted to the link and its reply
//! waits for the link's `CommandDone`; lines that arrive meanwhile wait in a queue of
//! [`QUEUE_CAPACITY`] and are answered in order. A line that finds the queue full is answered
//! at once with `ERR BUSY`. A framed message is answered with ACK (accepted) or NAK (check
//! byte wrong, framing broken, not a command, queue full) as soon as it is complete; its text
//! reply follows in order.
//!
//! # Events
//! With events on, `!` lines report link, fault, settings and arc changes. They are whole
//! lines in the same output, so they never split a reply line.
//!
//! # Simulator commands
//! `TORCH ON|OFF` drives the TORCH_ON input of a simulated machine. The session never touches
//! an input itself: with [`Session::enable_sim_commands`] it queues a [`SimCommand`] for its
//! driver and answers `OK torch=ON`; on the board (not enabled) it answers
//! `ERR UNSUPPORTED TORCH is a simulator command`.

mod commands;
mod consumables;
mod describe;
mod events;
mod gas_check;
pub mod history;
mod input;
pub mod powermax_port;
mod replies;
#[cfg(test)]
pub(crate) mod rig;
mod table;
pub mod texts;
pub(crate) mod units;

use core::fmt::{self, Display, Write};

use heapless::{Deque, String, Vec};
use plasma_protocol::cnc::phoenix::{ACK, Deframer, NAK};
use plasma_protocol::cnc::reply::{ReplyWriter, write_error};
use plasma_protocol::cnc::{ErrorCode, LineAssembler, MAX_LINE_LEN};

use crate::io::{Inputs, Outputs};
use crate::link::{LinkCommand, MAX_UNITS, PsLink, Refusal, Ticket, Units};
use crate::settings::{SaveError, Settings};
use plasma_protocol::time::{Duration, Instant};

pub(crate) use describe::unit_mode;
use input::Item;
use table::Awaiting;

/// Command lines that can wait behind a command in progress.
pub const QUEUE_CAPACITY: usize = 4;
/// Bytes of output (replies, events, ACK/NAK) held until the driver takes them.
pub const OUTPUT_CAPACITY: usize = 4096;
/// Longest reply or event line, CR LF included: room for `CONFIG`'s list of every key
/// (about 840 bytes with the wiring keys and the consumable limits). A line is built on the
/// stack and copied into the output buffer, so the size costs no static RAM.
pub const MAX_REPLY_LEN: usize = 900;
/// Simulator commands held until the driver takes them.
pub const SIM_QUEUE_CAPACITY: usize = 4;
/// A Phoenix frame that stops arriving for this long is abandoned (NAK): the CNC sends a
/// message in one go, and a stray SOH/STX in line noise must not swallow the text lines that
/// follow.
pub const FRAME_IDLE_TIMEOUT: Duration = Duration::from_millis(50);

/// A whole Phoenix frame: the longest message and every framing byte.
const RAW_FRAME_CAPACITY: usize = plasma_protocol::cnc::phoenix::MAX_MESSAGE_LEN + 8;

/// One reply or event line.
pub type ReplyLine = String<MAX_REPLY_LEN>;

type LineText = String<MAX_LINE_LEN>;

/// A command only a simulator can carry out, handed to its driver
/// ([`Bridge::poll_sim_command`](crate::bridge::Bridge::poll_sim_command)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SimCommand {
    /// Drive the CNC's TORCH_ON input of unit `unit` (0 = the first) on or off.
    Torch {
        /// The unit whose input (`@N TORCH ...` names unit N - 1).
        unit: usize,
        /// On (`true`) or off.
        on: bool,
    },
}

/// What the session may use while it handles one input or event.
pub struct Context<'a> {
    /// The time of the call.
    pub now: Instant,
    /// The units' links.
    pub units: &'a mut Units,
    /// The unit the input or event is about (0 = the first; `@N` names unit N - 1).
    pub unit: usize,
    /// The settings (CONFIG changes them; a confirmed process is kept in them).
    pub settings: &'a mut Settings,
    /// Each unit's last discrete-I/O snapshot, if the driver has given one.
    pub ios: &'a [Option<(Inputs, Outputs)>; MAX_UNITS],
    /// Why the board last reset, if the board said.
    pub boot_report: Option<&'static str>,
    /// The history's queue and the wall clock.
    pub history: &'a mut history::HistoryLog,
    /// The consumable set in use.
    pub consumables: &'a mut crate::consumables::Consumables,
}

impl Context<'_> {
    /// The link of the unit this call is about.
    #[inline(never)]
    pub fn link(&self) -> &PsLink {
        self.units.link(self.unit)
    }

    /// Submit `command` to the link of the unit this call is about.
    pub fn submit(&mut self, command: LinkCommand<'_>) -> Result<Ticket, Refusal> {
        self.units.link_mut(self.unit).submit(self.now, command)
    }

    /// That unit's last discrete-I/O snapshot.
    pub fn io(&self) -> Option<(Inputs, Outputs)> {
        self.ios.get(self.unit).copied().flatten()
    }
}

/// Counters of the CNC side.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SessionStats {
    /// Reply lines written (`OK` and `ERR`).
    pub replies: u32,
    /// `ERR` replies among them.
    pub errors: u32,
    /// Event lines written.
    pub events: u32,
    /// Phoenix messages answered with ACK.
    pub acks: u32,
    /// Phoenix messages answered with NAK.
    pub naks: u32,
    /// Lines or bytes dropped because the driver did not take the output in time.
    pub output_dropped: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pending {
    Link {
        ticket: Ticket,
        awaiting: Awaiting,
    },
    Save {
        taken: bool,
    },
    History {
        command: plasma_protocol::cnc::HistoryCommand,
        taken: bool,
    },
    GasCheck(gas_check::GasCheck),
}

/// Output bytes, whole lines at a time.
#[derive(Debug)]
struct Output {
    buf: Vec<u8, OUTPUT_CAPACITY>,
    /// Bytes at the front already handed to the driver.
    taken: usize,
}

impl Output {
    fn room(&self) -> usize {
        OUTPUT_CAPACITY - self.buf.len()
    }

    /// Append all of `bytes` or nothing.
    fn push(&mut self, bytes: &[u8]) -> bool {
        if bytes.len() > self.room() {
            return false;
        }
        self.buf.extend_from_slice(bytes).is_ok()
    }

    fn poll(&mut self) -> Option<&[u8]> {
        let taken = core::mem::take(&mut self.taken);
        let len = self.buf.len();
        let taken = taken.min(len);
        // What arrived since the last poll moves to the front. A forward byte copy (the
        // destination is below the source), not `copy_within`: that is a memmove, and keeping
        // memmove out of the image saves 1.5 KB of flash. Rarely more than one reply moves.
        for from in taken..len {
            if let Some(&byte) = self.buf.get(from)
                && let Some(slot) = self.buf.get_mut(from - taken)
            {
                *slot = byte;
            }
        }
        self.buf.truncate(len - taken);
        if self.buf.is_empty() {
            return None;
        }
        self.taken = self.buf.len();
        Some(&self.buf)
    }
}

/// Build one line with `build`; a line that does not fit becomes an `ERR` that says so.
fn line(build: impl FnOnce(&mut ReplyLine) -> fmt::Result) -> ReplyLine {
    let mut line = ReplyLine::new();
    if build(&mut line).is_err() {
        too_long(&mut line);
    }
    line
}

/// A reply that did not fit becomes an `ERR` that says so (one copy, not one per reply).
#[inline(never)]
fn too_long(line: &mut ReplyLine) {
    line.clear();
    let _ = write_error(line, ErrorCode::State, texts::REPLY_TOO_LONG);
}

/// An `OK` line with the fields `fields` writes.
fn ok_line(fields: impl FnOnce(&mut ReplyWriter<&mut ReplyLine>) -> fmt::Result) -> ReplyLine {
    line(|l| {
        let mut w = ReplyWriter::ok(l)?;
        fields(&mut w)?;
        w.finish().map(|_| ())
    })
}

/// An `ERR` line.
fn err_line(code: ErrorCode, text: impl Display) -> ReplyLine {
    line(|l| write_error(l, code, text))
}

/// The CNC session. See the module docs.
#[derive(Debug)]
pub struct Session {
    lines: LineAssembler,
    /// Part of a text line (not only blanks) has arrived.
    text_partial: bool,
    /// The assembler drops the rest of a refused line up to its terminator.
    text_discarding: bool,
    deframer: Deframer,
    /// The Phoenix framing recognised on the port (see `input::recognise`), used instead of
    /// `phoenix_format` until a frame fails with it or the key changes.
    recognised: Option<plasma_protocol::cnc::phoenix::Format>,
    /// `phoenix_format` when the session last looked: a change drops what was recognised.
    configured_format: plasma_protocol::cnc::phoenix::Format,
    /// The bytes of the Phoenix frame under way, from its start byte.
    raw_frame: Vec<u8, RAW_FRAME_CAPACITY>,
    /// The frame failed in the configured format; its verdict waits for the frame's end.
    deferred: Option<plasma_protocol::Error>,
    queue: Deque<Item, QUEUE_CAPACITY>,
    pending: Option<Pending>,
    out: Output,
    sim_enabled: bool,
    sim: Deque<SimCommand, SIM_QUEUE_CAPACITY>,
    io_config_changed: bool,
    stats: SessionStats,
    /// When the last CNC byte arrived.
    last_rx: Instant,
    /// Modbus ASCII requests: the bridge answering as a Powermax.
    powermax: powermax_port::PowermaxPort,
    /// Who sent the command being carried out (for the history's process changes).
    origin: crate::storage::history::ChangedBy,
    /// A gas check's stop that could not be sent (link lost), and the unit it is for: sent
    /// when that unit's link is back.
    gas_stop_owed: Option<(usize, crate::link::LinkCommand<'static>)>,
    /// The unit of the command being answered (`@N` names unit N - 1; 0 without it): its
    /// reply, and the link events that complete it, are that unit's.
    answering: usize,
}

impl Session {
    /// A session whose Phoenix receiver uses the format in `settings`.
    pub fn new(settings: &Settings) -> Self {
        Session {
            lines: LineAssembler::new(),
            text_partial: false,
            text_discarding: false,
            deframer: Deframer::new(settings.phoenix_format),
            recognised: None,
            configured_format: settings.phoenix_format,
            raw_frame: Vec::new(),
            deferred: None,
            queue: Deque::new(),
            pending: None,
            out: Output {
                buf: Vec::new(),
                taken: 0,
            },
            sim_enabled: false,
            sim: Deque::new(),
            io_config_changed: false,
            stats: SessionStats::default(),
            last_rx: Instant::ZERO,
            powermax: powermax_port::PowermaxPort::default(),
            origin: crate::storage::history::ChangedBy::Text,
            gas_stop_owed: None,
            answering: 0,
        }
    }

    /// Accept simulator-only commands (`TORCH`): for `pbtool sim` and test harnesses.
    pub fn enable_sim_commands(&mut self) {
        self.sim_enabled = true;
    }

    /// Counters.
    pub fn stats(&self) -> &SessionStats {
        &self.stats
    }

    /// Bytes received from the CNC (any chunking).
    pub fn handle_rx(&mut self, ctx: &mut Context<'_>, bytes: &[u8]) {
        self.poll(ctx);
        self.last_rx = ctx.now;
        for &byte in bytes {
            self.route(ctx, byte);
        }
    }

    /// The next output bytes. They are taken: write them all before calling again.
    pub fn poll_output(&mut self) -> Option<&[u8]> {
        self.out.poll()
    }

    /// The next simulator command for the driver.
    pub fn poll_sim_command(&mut self) -> Option<SimCommand> {
        self.sim.pop_front()
    }

    /// True once after a `CONFIG` change of a discrete-I/O key.
    pub fn take_io_config_change(&mut self) -> bool {
        core::mem::take(&mut self.io_config_changed)
    }

    /// True once when `CONFIG SAVE` waits for the settings to be stored.
    pub fn take_save_request(&mut self) -> bool {
        match &mut self.pending {
            Some(Pending::Save { taken }) if !*taken => {
                *taken = true;
                true
            }
            _ => false,
        }
    }

    /// The store finished: answer `CONFIG SAVE` and go on with waiting lines.
    pub fn save_finished(&mut self, ctx: &mut Context<'_>, result: Result<(), SaveError>) {
        if !matches!(self.pending, Some(Pending::Save { .. })) {
            return;
        }
        self.pending = None;
        let reply = match result {
            Ok(()) => ok_line(|w| w.field("config", "saved")),
            Err(e) => texts::not_saved(e),
        };
        self.send(reply);
        self.pump(ctx);
    }

    /// Let time pass: a Phoenix or Modbus frame idle for [`FRAME_IDLE_TIMEOUT`] is
    /// abandoned; a group of Modbus writes with nothing after it completes.
    pub fn poll(&mut self, ctx: &mut Context<'_>) {
        self.gas_check_poll(ctx);
        let caller = ctx.unit;
        if let Some(fault) = self.powermax.poll(ctx) {
            self.settings_refused_event(ctx, fault);
        }
        ctx.unit = caller;
        self.follow_consumables(ctx);
        if ctx.now < self.last_rx + FRAME_IDLE_TIMEOUT {
            return;
        }
        if self.powermax.in_frame() {
            self.powermax.abandon_frame();
        }
        if self.deframer.in_frame() {
            self.abandon_frame(ctx);
        }
    }

    /// When [`Session::poll`] has something to do.
    pub fn poll_at(&self) -> Option<Instant> {
        let frame = (self.deframer.in_frame() || self.powermax.in_frame())
            .then(|| self.last_rx + FRAME_IDLE_TIMEOUT);
        [frame, self.powermax.poll_at(), self.gas_check_poll_at()]
            .into_iter()
            .flatten()
            .min()
    }

    /// A new discrete-I/O snapshot: a gas check stops when the torch comes on.
    pub fn io_changed(&mut self, ctx: &mut Context<'_>) {
        self.gas_check_poll(ctx);
    }

    /// Answer waiting lines while no command is in progress.
    pub fn pump(&mut self, ctx: &mut Context<'_>) {
        while self.pending.is_none() {
            let Some(item) = self.queue.pop_front() else {
                break;
            };
            self.execute(ctx, item);
        }
    }

    // --- output -------------------------------------------------------------------------

    fn push(&mut self, bytes: &[u8]) {
        if !self.out.push(bytes) {
            self.stats.output_dropped = self.stats.output_dropped.saturating_add(1);
        }
    }

    /// The reply to the command being answered, `unit=N` added for a unit beyond the first.
    fn send(&mut self, mut line: ReplyLine) {
        tag_unit(&mut line, self.answering);
        self.send_untagged(line);
    }

    /// A reply that is no unit's (a line refused before it was read).
    fn send_untagged(&mut self, line: ReplyLine) {
        self.stats.replies = self.stats.replies.saturating_add(1);
        if line.starts_with("ERR") {
            self.stats.errors = self.stats.errors.saturating_add(1);
        }
        self.push(line.as_bytes());
    }

    fn ack(&mut self, accepted: bool) {
        if accepted {
            self.stats.acks = self.stats.acks.saturating_add(1);
            self.push(&[ACK]);
        } else {
            self.stats.naks = self.stats.naks.saturating_add(1);
            self.push(&[NAK]);
        }
    }

    /// Write an event line if events are on (`unit=N` added for a unit beyond the first).
    fn event(&mut self, ctx: &Context<'_>, build: impl FnOnce(&mut ReplyLine) -> fmt::Result) {
        if !ctx.settings.events {
            return;
        }
        let mut l = ReplyLine::new();
        if build(&mut l).is_ok() {
            self.push_event(l, ctx.unit);
        }
    }

    /// The part of [`Session::event`] every event shares: one copy in the image instead of
    /// one inlined into each kind of event.
    #[inline(never)]
    fn push_event(&mut self, mut line: ReplyLine, unit: usize) {
        tag_unit(&mut line, unit);
        self.stats.events = self.stats.events.saturating_add(1);
        self.push(line.as_bytes());
    }
}

/// `unit=N` in a line about unit `unit` (0-based) beyond the first, where a reader of the
/// line for one unit does not trip on it: after an `ERR` line's code (its text runs to the end
/// of the line), before a free-text `text=` or `reply=` field (which runs to the end), else
/// last. Lines about the first unit stay as they were.
#[inline(never)]
fn tag_unit(line: &mut ReplyLine, unit: usize) {
    if unit == 0 {
        return;
    }
    let body = line.trim_ascii_end();
    let bytes = body.as_bytes();
    // Byte searches, not `str::find`: its substring searcher costs 2 KB of flash.
    let at = if bytes.starts_with(b"ERR ") {
        // After `ERR <CODE>`.
        let spaces = bytes.iter().enumerate().filter(|&(_, &b)| b == b' ');
        spaces.map(|(i, _)| i).nth(1)
    } else {
        [&b" text="[..], b" reply="].iter().find_map(|field| {
            bytes
                .windows(field.len())
                .position(|window| window == *field)
        })
    }
    .unwrap_or(body.len());
    let mut tagged = ReplyLine::new();
    let (head, tail) = body.split_at_checked(at).unwrap_or((body, ""));
    if write!(tagged, "{head} unit={}{tail}\r\n", unit + 1).is_err() {
        too_long(&mut tagged);
    }
    *line = tagged;
}

fn no_link() -> ReplyLine {
    err_line(ErrorCode::Link, texts::NO_LINK)
}

/// A comma-separated list.
struct List<I>(I);

impl<I, T> Display for List<I>
where
    I: Iterator<Item = T> + Clone,
    T: Display,
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        for item in self.0.clone() {
            if !first {
                f.write_char(',')?;
            }
            first = false;
            item.fmt(f)?;
        }
        if first {
            f.write_str("none")?;
        }
        Ok(())
    }
}
