//! The CNC session: the bridge's text protocol and Phoenix serial messaging, sans-IO.
//!
//! Bytes from the CNC port go in ([`Session::handle_rx`]); reply lines, event lines and
//! ACK/NAK bytes come out ([`Session::poll_output`]). The session runs each command against
//! a [`Context`] (the link, the settings, the discrete-I/O snapshot) that the
//! [`Bridge`](crate::bridge::Bridge) lends it for the call. The protocol itself is documented
//! in `docs/cnc-protocol.md`.
//!
//! # Input
//! A byte that opens a Phoenix frame (SOH or STX, [`phoenix::is_frame_start`]) between two
//! inputs goes to the [`Deframer`] of the configured format; everything else to the
//! [`LineAssembler`] (CR, LF or CR LF; at most 128 characters). A text line that a frame
//! start interrupts is dropped with an `ERR`.
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

mod describe;
mod replies;
#[cfg(test)]
pub(crate) mod tests;

use core::fmt::{self, Display, Write};

use heapless::{Deque, String, Vec};
use plasma_protocol::cnc::phoenix::{self, ACK, Deframer, NAK};
use plasma_protocol::cnc::reply::{ReplyWriter, write_error, write_parse_error};
use plasma_protocol::cnc::{
    Amps, Command, ConfigCommand, ConfigKey, ErrorCode, Gas, LineAssembler, LineError,
    MAX_LINE_LEN, Mode, ParseError, Pressure,
};
use plasma_protocol::hpr::{GasCode, GasPair};

use crate::io::{Inputs, Interlock, IoEvent, Outputs};
use crate::link::command::RAW_CAPACITY;
use crate::link::{Family, HprGasFlow, LinkCommand, LinkDownReason, LinkEvent, PsLink, Ticket};
use crate::settings::{Process, SaveError, Settings};
use plasma_protocol::time::{Duration, Instant};

use describe::{
    FaultId, OrDash, SettingsText, Text, fault_text, on_off, settings_failure_word, state_name,
    transaction_word, write_refusal,
};
pub use describe::{ModelName, cnc_mode, family_word, mode_word, unit_mode};
use replies::{cartridge, complete, counters, fault, help, id, limits, status_line};

/// Command lines that can wait behind a command in progress.
pub const QUEUE_CAPACITY: usize = 4;
/// Bytes of output (replies, events, ACK/NAK) held until the driver takes them.
pub const OUTPUT_CAPACITY: usize = 4096;
/// Longest reply or event line, CR LF included.
pub const MAX_REPLY_LEN: usize = 400;
/// Simulator commands held until the driver takes them.
pub const SIM_QUEUE_CAPACITY: usize = 4;
/// A Phoenix frame that stops arriving for this long is abandoned (NAK): the CNC sends a
/// message in one go, and a stray SOH/STX in line noise must not swallow the text lines that
/// follow.
pub const FRAME_IDLE_TIMEOUT: Duration = Duration::from_millis(50);

/// One reply or event line.
pub type ReplyLine = String<MAX_REPLY_LEN>;

type LineText = String<MAX_LINE_LEN>;

/// A command only a simulator can carry out, handed to its driver
/// ([`Bridge::poll_sim_command`](crate::bridge::Bridge::poll_sim_command)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SimCommand {
    /// Drive the CNC's TORCH_ON input on (`true`) or off.
    Torch(bool),
}

/// What the session may use while it handles one input or event.
pub struct Context<'a> {
    /// The time of the call.
    pub now: Instant,
    /// The power-supply link.
    pub link: &'a mut PsLink,
    /// The settings (CONFIG changes them; a confirmed process is kept in them).
    pub settings: &'a mut Settings,
    /// The last discrete-I/O snapshot, if the driver has given one.
    pub io: Option<(Inputs, Outputs)>,
    /// Why the board last reset, if the board said.
    pub boot_report: Option<&'static str>,
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

/// Why an input could not become a command; answered in turn like a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum InputError {
    Parse(ParseError),
    Frame(plasma_protocol::Error),
    Interrupted,
}

/// A command line (or a refused input) waiting for its turn.
#[derive(Debug, Clone)]
struct Item {
    text: LineText,
    error: Option<InputError>,
}

/// What a command sent to the link waits for, and how to answer when it is done.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    Settings(Process),
    RemoteOff,
    GasTest(bool),
    Restart,
    HprAmps,
    Gases(Gas, Gas),
    Corner,
    Reset,
    ClearWarn,
    Raw,
    FaultLog,
    Counters,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pending {
    Link { ticket: Ticket, op: Op },
    Save { taken: bool },
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
    let _ = write_error(line, ErrorCode::State, "reply longer than the line buffer");
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
    queue: Deque<Item, QUEUE_CAPACITY>,
    pending: Option<Pending>,
    out: Output,
    sim_enabled: bool,
    sim: Deque<SimCommand, SIM_QUEUE_CAPACITY>,
    io_config_changed: bool,
    stats: SessionStats,
    /// When the last CNC byte arrived.
    last_rx: Instant,
}

impl Session {
    /// A session whose Phoenix receiver uses the format in `settings`.
    pub fn new(settings: &Settings) -> Self {
        Session {
            lines: LineAssembler::new(),
            text_partial: false,
            text_discarding: false,
            deframer: Deframer::new(settings.phoenix_format),
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

    /// True while a command waits for the link or for a save.
    pub fn is_busy(&self) -> bool {
        self.pending.is_some()
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
            Err(e) => err_line(ErrorCode::Storage, format_args!("settings not saved: {e}")),
        };
        self.send(reply);
        self.pump(ctx);
    }

    /// Let time pass: a Phoenix frame idle for [`FRAME_IDLE_TIMEOUT`] is abandoned.
    pub fn poll(&mut self, ctx: &mut Context<'_>) {
        if !self.deframer.in_frame() || ctx.now < self.last_rx + FRAME_IDLE_TIMEOUT {
            return;
        }
        if let Some(outcome) = self.deframer.idle() {
            let item = frame_item(outcome);
            self.framed(ctx, item);
        }
    }

    /// When [`Session::poll`] has something to do.
    pub fn poll_at(&self) -> Option<Instant> {
        self.deframer
            .in_frame()
            .then(|| self.last_rx + FRAME_IDLE_TIMEOUT)
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

    fn send(&mut self, line: ReplyLine) {
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

    /// Write an event line if events are on.
    fn event(&mut self, ctx: &Context<'_>, build: impl FnOnce(&mut ReplyLine) -> fmt::Result) {
        if !ctx.settings.events {
            return;
        }
        let mut l = ReplyLine::new();
        if build(&mut l).is_ok() {
            self.push_event(&l);
        }
    }

    /// The part of [`Session::event`] every event shares: one copy in the image instead of
    /// one inlined into each kind of event.
    #[inline(never)]
    fn push_event(&mut self, line: &ReplyLine) {
        self.stats.events = self.stats.events.saturating_add(1);
        self.push(line.as_bytes());
    }

    // --- input --------------------------------------------------------------------------

    fn route(&mut self, ctx: &mut Context<'_>, byte: u8) {
        if self.deframer.in_frame() {
            return self.deframe(ctx, byte);
        }
        if phoenix::is_frame_start(byte) {
            if self.text_partial {
                self.admit(
                    ctx,
                    Item {
                        text: LineText::new(),
                        error: Some(InputError::Interrupted),
                    },
                );
            }
            self.lines.reset();
            self.text_partial = false;
            self.text_discarding = false;
            if self.deframer.format() != ctx.settings.phoenix_format {
                self.deframer = Deframer::new(ctx.settings.phoenix_format);
            }
            return self.deframe(ctx, byte);
        }
        let outcome = self
            .lines
            .push(byte)
            .map(|r| r.map(|text| LineText::try_from(text).unwrap_or_default()));
        match outcome {
            None => {
                if byte == b'\r' || byte == b'\n' {
                    self.text_partial = false;
                    self.text_discarding = false;
                } else if !self.text_discarding && byte != b' ' && byte != b'\t' {
                    self.text_partial = true;
                }
            }
            Some(Ok(text)) => {
                self.text_partial = false;
                self.text_discarding = false;
                self.admit(ctx, Item { text, error: None });
            }
            Some(Err(error)) => {
                self.text_partial = false;
                self.text_discarding = true;
                let error = match error {
                    LineError::TooLong => ParseError::TooLong,
                    LineError::Binary => ParseError::Binary,
                };
                self.admit(
                    ctx,
                    Item {
                        text: LineText::new(),
                        error: Some(InputError::Parse(error)),
                    },
                );
            }
        }
    }

    fn deframe(&mut self, ctx: &mut Context<'_>, byte: u8) {
        let item = match self.deframer.push(byte) {
            None => return,
            Some(outcome) => frame_item(outcome),
        };
        self.framed(ctx, item);
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
            self.send(err_line(
                ErrorCode::Busy,
                format_args!("{QUEUE_CAPACITY} commands are already waiting, line dropped"),
            ));
        }
    }

    fn execute(&mut self, ctx: &mut Context<'_>, item: Item) {
        let reply = match item.error {
            Some(InputError::Parse(error)) => line(|l| write_parse_error(l, &error)),
            Some(InputError::Frame(error)) => frame_error(error),
            Some(InputError::Interrupted) => err_line(
                ErrorCode::Syntax,
                "incomplete line dropped: a Phoenix message (SOH/STX) began before its CR/LF",
            ),
            None => match Command::parse(&item.text) {
                Err(error) => line(|l| write_parse_error(l, &error)),
                Ok(command) => match self.run(ctx, command) {
                    Some(reply) => reply,
                    None => return,
                },
            },
        };
        self.send(reply);
    }

    // --- commands -----------------------------------------------------------------------

    /// Carry out one command: its reply, or `None` when it waits for the link or a save.
    fn run(&mut self, ctx: &mut Context<'_>, command: Command<'_>) -> Option<ReplyLine> {
        let status = ctx.link.status();
        let family = status.family.filter(|_| status.link_up);
        Some(match command {
            Command::Help => help(self.sim_enabled),
            Command::Id => id(ctx),
            Command::Status => status_line(ctx),
            Command::Limits => limits(status, family),
            Command::Fault => fault(status, family),
            Command::FaultLog => match family {
                None => no_link(),
                Some(Family::PowermaxSync) => {
                    return self.submit(ctx, LinkCommand::RefreshSlowData, Op::FaultLog);
                }
                Some(Family::Hpr) => {
                    return self.submit(ctx, LinkCommand::HprReadErrorLog, Op::FaultLog);
                }
                Some(f) => unsupported(format_args!(
                    "FAULTLOG: {} keeps no fault log the bridge can read; FAULT shows the \
                     active fault",
                    describe::family_name(f)
                )),
            },
            Command::Counters => match family {
                Some(Family::PowermaxSync | Family::PowermaxLegacy) => {
                    return self.submit(ctx, LinkCommand::RefreshSlowData, Op::Counters);
                }
                Some(Family::Hpr) => {
                    return self.submit(ctx, LinkCommand::HprReadTimers, Op::Counters);
                }
                // MaxPro200 has no timer read; the link counters are still worth having.
                Some(Family::MaxPro200) | None => counters(ctx.link),
            },
            Command::Cartridge => cartridge(status, family),
            Command::SetMode(mode) => return self.set_powermax(ctx, Some(mode), None, None),
            Command::SetAmps(amps) => match family {
                Some(Family::Hpr | Family::MaxPro200) => return self.set_hpr_amps(ctx, amps),
                _ => return self.set_powermax(ctx, None, Some(amps), None),
            },
            Command::SetPsi(pressure) => {
                return self.set_powermax(ctx, None, None, Some(pressure));
            }
            Command::SetProcess {
                mode,
                amps,
                pressure,
            } => return self.set_powermax(ctx, Some(mode), Some(amps), Some(pressure)),
            Command::RemoteOff => match family {
                None => no_link(),
                Some(f) if f.is_modbus() => {
                    return self.submit(ctx, LinkCommand::ExitRemote, Op::RemoteOff);
                }
                Some(f) => unsupported(format_args!(
                    "REMOTE OFF is a Powermax command; {} stays in remote mode while the \
                     bridge talks to it",
                    describe::family_name(f)
                )),
            },
            Command::GasTest(on) => match family {
                None => no_link(),
                Some(f) if f.is_modbus() => {
                    return self.submit(ctx, LinkCommand::GasTest { on }, Op::GasTest(on));
                }
                Some(_) => {
                    let command = LinkCommand::HprGasTest {
                        flow: HprGasFlow::Preflow,
                        on,
                    };
                    return self.submit(ctx, command, Op::GasTest(on));
                }
            },
            Command::Restart => match family {
                None => no_link(),
                Some(Family::PowermaxSync) => {
                    return self.submit(ctx, LinkCommand::QuickRestart, Op::Restart);
                }
                Some(f) => unsupported(format_args!(
                    "RESTART (quick restart, clears 0-50-0) is a Powermax SYNC function, not \
                     available on {}",
                    describe::family_name(f)
                )),
            },
            Command::Gases { plasma, shield } => match family {
                None => no_link(),
                Some(Family::Hpr | Family::MaxPro200) => {
                    let gases = GasPair {
                        plasma: GasCode(u16::from(plasma.hpr_code())),
                        shield: GasCode(u16::from(shield.hpr_code())),
                    };
                    return self.submit(
                        ctx,
                        LinkCommand::HprSetInletGases(gases),
                        Op::Gases(plasma, shield),
                    );
                }
                Some(f) => unsupported(format_args!(
                    "GASES is an HPR/MaxPro200 command; {} runs on air and sets no gases",
                    describe::family_name(f)
                )),
            },
            Command::Corner(percent) => match family {
                None => no_link(),
                Some(Family::Hpr) => {
                    let command = LinkCommand::HprSetCornerCurrent { percent };
                    return self.submit(ctx, command, Op::Corner);
                }
                Some(f) => unsupported(format_args!(
                    "CORNER is an HPR command (070 corner current), not available on {}",
                    describe::family_name(f)
                )),
            },
            Command::Reset => match family {
                None => no_link(),
                Some(Family::Hpr | Family::MaxPro200) => {
                    return self.submit(ctx, LinkCommand::HprSoftwareReset, Op::Reset);
                }
                Some(f) => unsupported(format_args!(
                    "RESET is an HPR/MaxPro200 command (068 software reset), not available on \
                     {}; a Powermax SYNC clears 0-50-0 with RESTART",
                    describe::family_name(f)
                )),
            },
            Command::ClearWarn => match family {
                None => no_link(),
                Some(Family::Hpr) => {
                    return self.submit(ctx, LinkCommand::HprClearWarnings, Op::ClearWarn);
                }
                Some(f) => unsupported(format_args!(
                    "CLEARWARN is an HPR command (131 clear warnings), not available on {}",
                    describe::family_name(f)
                )),
            },
            Command::Events(on) => {
                ctx.settings.events = on;
                ok_line(|w| w.field("events", on_off(on)))
            }
            Command::Config(config) => return self.config(ctx, config),
            Command::Raw(frame) => {
                if frame.len() > RAW_CAPACITY {
                    return Some(err_line(ErrorCode::TooLong, "frame too long"));
                }
                return self.submit(ctx, LinkCommand::Raw(frame.as_bytes()), Op::Raw);
            }
            Command::Torch(on) => {
                if !self.sim_enabled {
                    unsupported("TORCH is a simulator command")
                } else if self.sim.push_back(SimCommand::Torch(on)).is_err() {
                    err_line(ErrorCode::Busy, "simulator commands are waiting")
                } else {
                    ok_line(|w| w.field("torch", on_off(on)))
                }
            }
        })
    }

    /// Submit `command`; `None` (the reply waits) when the link took it.
    fn submit(
        &mut self,
        ctx: &mut Context<'_>,
        command: LinkCommand<'_>,
        op: Op,
    ) -> Option<ReplyLine> {
        match ctx.link.submit(ctx.now, command) {
            Ok(ticket) => {
                self.pending = Some(Pending::Link { ticket, op });
                None
            }
            Err(refusal) => {
                let family = ctx.link.status().family;
                Some(line(|l| write_refusal(l, &refusal, family, ctx.now)))
            }
        }
    }

    /// SET MODE / AMPS / PSI / PROCESS on a Powermax: missing values come from the process
    /// asked for last (or, failing that, from the unit), and all three go in one write.
    fn set_powermax(
        &mut self,
        ctx: &mut Context<'_>,
        mode: Option<Mode>,
        amps: Option<Amps>,
        pressure: Option<Pressure>,
    ) -> Option<ReplyLine> {
        let status = ctx.link.status();
        let family = match status.family.filter(|_| status.link_up) {
            None => return Some(no_link()),
            Some(f) if f.is_modbus() => f,
            Some(f) => {
                let what = match (mode, amps, pressure) {
                    (Some(_), Some(_), Some(_)) => "SET PROCESS",
                    (Some(_), _, _) => "SET MODE",
                    _ => "SET PSI",
                };
                return Some(unsupported(format_args!(
                    "{what} is a Powermax command; {} takes SET AMPS and GASES",
                    describe::family_name(f)
                )));
            }
        };
        let base = ctx.settings.process.or_else(|| {
            let known = status.desired.or(status.settings)?;
            Some(Process {
                mode: cnc_mode(known.mode?, Some(family)),
                amps: known.current,
                pressure: known.pressure,
            })
        });
        let process = match (mode, amps, pressure, base) {
            (Some(mode), Some(amps), Some(pressure), _) => Process {
                mode,
                amps,
                pressure,
            },
            (_, _, _, Some(base)) => Process {
                mode: mode.unwrap_or(base.mode),
                amps: amps.unwrap_or(base.amps),
                pressure: pressure.unwrap_or(base.pressure),
            },
            (_, _, _, None) => {
                return Some(err_line(
                    ErrorCode::State,
                    "the unit's settings are not known yet: use SET PROCESS <mode> <A> <psi|AUTO>",
                ));
            }
        };
        let command = LinkCommand::ApplySettings {
            mode: unit_mode(process.mode),
            current: process.amps,
            pressure: process.pressure,
        };
        self.submit(ctx, command, Op::Settings(process))
    }

    fn set_hpr_amps(&mut self, ctx: &mut Context<'_>, amps: Amps) -> Option<ReplyLine> {
        let steps = amps.raw();
        if !steps.is_multiple_of(Amps::STEPS_PER_UNIT) {
            return Some(err_line(
                ErrorCode::Range,
                format_args!("amps {amps}: this unit takes whole amps"),
            ));
        }
        let command = LinkCommand::HprSetNominalAmps {
            amps: steps / Amps::STEPS_PER_UNIT,
        };
        self.submit(ctx, command, Op::HprAmps)
    }

    fn config(&mut self, ctx: &mut Context<'_>, config: ConfigCommand<'_>) -> Option<ReplyLine> {
        Some(match config {
            ConfigCommand::Show => {
                let settings = &*ctx.settings;
                ok_line(|w| {
                    for key in ConfigKey::ALL {
                        w.field(key.name(), settings.get(key))?;
                    }
                    Ok(())
                })
            }
            ConfigCommand::Get(key) => {
                let value = ctx.settings.get(key);
                ok_line(|w| w.field(key.name(), value))
            }
            ConfigCommand::Set { key, value } => {
                let before = *ctx.settings;
                if let Err(e) = ctx.settings.set(key, value) {
                    return Some(err_line(e.code(), e));
                }
                let relink = before.link != ctx.settings.link;
                if relink {
                    ctx.link.reconfigure(ctx.now, ctx.settings.link);
                }
                if before.io != ctx.settings.io {
                    self.io_config_changed = true;
                }
                let value = ctx.settings.get(key);
                ok_line(|w| {
                    w.field(key.name(), value)?;
                    if relink {
                        w.field("link", "redetecting")?;
                    }
                    Ok(())
                })
            }
            ConfigCommand::Save => {
                self.pending = Some(Pending::Save { taken: false });
                return None;
            }
        })
    }

    // --- link events --------------------------------------------------------------------

    /// A link event: the reply of the command in progress, and/or an event line.
    pub fn on_link_event(&mut self, ctx: &mut Context<'_>, event: &LinkEvent) {
        if let LinkEvent::CommandDone { ticket, result } = event {
            if let Some(Pending::Link { ticket: t, op }) = self.pending
                && t == *ticket
            {
                self.pending = None;
                let reply = complete(ctx, op, result);
                self.send(reply);
                self.pump(ctx);
            }
            return;
        }
        let status = ctx.link.status();
        let family = status.family;
        match *event {
            LinkEvent::LinkUp { family, .. } => self.event(ctx, |l| {
                let mut w = ReplyWriter::event(l, "LINK")?;
                w.word("UP")?;
                w.field("model", ModelName(status))?;
                w.word(family_word(family))?;
                w.finish().map(|_| ())
            }),
            LinkEvent::LinkDown { reason } => self.event(ctx, |l| {
                let mut w = ReplyWriter::event(l, "LINK")?;
                w.word("DOWN")?;
                match reason {
                    LinkDownReason::ConsecutiveFailures { count, last_error } => {
                        w.field("reason", "no_answer")?;
                        w.field("failures", count)?;
                        w.field("last", transaction_word(last_error))?;
                    }
                    LinkDownReason::Reconfigured => w.field("reason", "reconfigured")?,
                }
                w.finish().map(|_| ())
            }),
            LinkEvent::FaultRaised { code, .. } => self.event(ctx, |l| {
                write!(
                    l,
                    "!FAULT {} {}\r\n",
                    FaultId(code),
                    Text(fault_text(code, family))
                )
            }),
            LinkEvent::FaultCleared { code } => self.event(ctx, |l| {
                let mut w = ReplyWriter::event(l, "FAULT")?;
                w.word("CLEARED")?;
                w.field("code", FaultId(code))?;
                w.finish().map(|_| ())
            }),
            LinkEvent::SettingsApplied {
                settings,
                reapplied,
            } => self.event(ctx, |l| {
                write!(l, "!SETTINGS applied {}", SettingsText(&settings, family))?;
                if reapplied {
                    l.write_str(" reapplied=YES")?;
                }
                l.write_str("\r\n")
            }),
            LinkEvent::SettingsFailed { reason } => self.event(ctx, |l| {
                let mut w = ReplyWriter::event(l, "SETTINGS")?;
                w.word("failed")?;
                w.field("reason", settings_failure_word(&reason))?;
                w.finish().map(|_| ())
            }),
            LinkEvent::CartridgeChanged { uid } => self.event(ctx, |l| {
                let mut w = ReplyWriter::event(l, "CARTRIDGE")?;
                w.word("changed")?;
                w.field("uid", Uid(&uid))?;
                w.finish().map(|_| ())
            }),
            LinkEvent::StateChanged { from, to } => self.event(ctx, |l| {
                let mut w = ReplyWriter::event(l, "STATE")?;
                w.word(to.0)?;
                w.field("name", state_name(to, family))?;
                w.field("from", OrDash(from.map(|s| s.0)))?;
                w.finish().map(|_| ())
            }),
            LinkEvent::RemoteModeChanged { remote } => self.event(ctx, |l| {
                let mut w = ReplyWriter::event(l, "REMOTE")?;
                w.word(on_off(remote))?;
                w.finish().map(|_| ())
            }),
            LinkEvent::CommandDone { .. } => {}
        }
    }

    /// A discrete-I/O event: an event line.
    pub fn on_io_event(&mut self, ctx: &Context<'_>, event: IoEvent) {
        let now = ctx.now;
        self.event(ctx, |l| match event {
            IoEvent::ArcOn => l.write_str("!ARC ON\r\n"),
            IoEvent::ArcOff => l.write_str("!ARC OFF\r\n"),
            IoEvent::TransferTimeout => l.write_str("!TRANSFER TIMEOUT\r\n"),
            IoEvent::StartRefused { reason } => {
                write!(l, "!START REFUSED reason={}\r\n", interlock_word(reason))
            }
            IoEvent::StartDropped { reason } => {
                write!(l, "!START DROPPED reason={}\r\n", interlock_word(reason))
            }
            IoEvent::StartDelayed { until } => write!(
                l,
                "!START DELAYED ms={}\r\n",
                until.saturating_since(now).as_millis_u32()
            ),
            IoEvent::StuckTorchOnAtPowerUp => write!(
                l,
                "!START REFUSED reason={}\r\n",
                interlock_word(Interlock::TorchOnAtPowerUp)
            ),
            IoEvent::RampdownError => l.write_str("!RAMPDOWN ERROR\r\n"),
        });
    }

    /// `!BOOT reason=...`, if events are on (the board calls it once after start-up).
    pub fn boot_event(&mut self, ctx: &Context<'_>, reason: &str) {
        self.event(ctx, |l| {
            let mut w = ReplyWriter::event(l, "BOOT")?;
            w.field("reason", reason)?;
            w.field("version", env!("CARGO_PKG_VERSION"))?;
            w.finish().map(|_| ())
        });
    }

    /// An event line for settings the bridge applied by itself (after power-up), refused
    /// before sending.
    pub fn restore_refused(&mut self, ctx: &Context<'_>, refusal: &crate::link::Refusal) {
        self.event(ctx, |l| {
            let mut w = ReplyWriter::event(l, "SETTINGS")?;
            w.word("failed")?;
            w.field("reason", "refused")?;
            w.field("why", refusal)?;
            w.finish().map(|_| ())
        });
    }
}

/// The item for a deframer outcome.
fn frame_item(outcome: plasma_protocol::Result<&[u8]>) -> Item {
    match outcome {
        Ok(payload) => message_item(payload),
        Err(error) => Item {
            text: LineText::new(),
            error: Some(InputError::Frame(error)),
        },
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
    Item { text, error }
}

fn frame_error(error: plasma_protocol::Error) -> ReplyLine {
    use plasma_protocol::Error as E;
    match error {
        E::BadChecksum { expected, found } => err_line(
            ErrorCode::Syntax,
            format_args!(
                "Phoenix message check byte {found:02X}, expected {expected:02X} (NAK sent)"
            ),
        ),
        E::Overlong => err_line(
            ErrorCode::TooLong,
            format_args!(
                "Phoenix message longer than {} bytes (NAK sent)",
                phoenix::MAX_MESSAGE_LEN
            ),
        ),
        E::Truncated => err_line(
            ErrorCode::Syntax,
            "Phoenix message incomplete: the next one began or the line went quiet (NAK sent)",
        ),
        _ => err_line(
            ErrorCode::Syntax,
            "Phoenix message framing: a framing byte is missing or out of place (NAK sent)",
        ),
    }
}

fn no_link() -> ReplyLine {
    err_line(
        ErrorCode::Link,
        "no power supply connected (the bridge is looking for one)",
    )
}

fn unsupported(text: impl Display) -> ReplyLine {
    err_line(ErrorCode::Unsupported, text)
}

fn interlock_word(interlock: Interlock) -> &'static str {
    match interlock {
        Interlock::TorchOnAtPowerUp => "torch_on_at_power_up",
        Interlock::LinkDown => "link_down",
        Interlock::RestartBlackout => "restart_blackout",
        Interlock::FaultRequiresAction => "fault",
        Interlock::TransferTimeout => "transfer_timeout",
    }
}

/// A cartridge UID as text (`unreadable` when all zero).
struct Uid<'a>(&'a [u8; 16]);

impl Display for Uid<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.iter().all(|&b| b == 0) {
            return f.write_str("unreadable");
        }
        for &b in self.0.iter().take_while(|&&b| b != 0) {
            f.write_char(if b.is_ascii_graphic() { b as char } else { '?' })?;
        }
        Ok(())
    }
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
