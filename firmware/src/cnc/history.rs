//! The event history as the session sees it: [`HistoryLog`] (the drafts queued for the
//! background writer, and the wall clock), `HISTORY [N|CLEAR]` and `CLOCK [time]`.
//!
//! Reading or erasing the flash is slow and async: `HISTORY` waits, like `CONFIG SAVE`, for
//! its driver to take the request ([`Session::take_history_request`]) and hand back the
//! answer ([`Session::history_finished`]). Recording never waits: a draft goes into the
//! bounded [`Pending`] queue, and when that is full it is dropped and counted.

use core::fmt;

use plasma_protocol::cnc::clock::WallClock;
use plasma_protocol::cnc::reply::ReplyWriter;
use plasma_protocol::cnc::{Amps, ErrorCode, HistoryCommand};

use plasma_protocol::time::Instant;

use super::describe::{FaultId, family_word, interlock_word, steps_of, steps_word};

use super::{
    Context, Pending as Waiting, ReplyLine, Session, err_line, line, ok_line, tag_unit, texts,
};
use crate::io::{Interlock, IoEvent};
use crate::link::model_code::{model_code, model_name};
use crate::link::{LinkEvent, Units};
use crate::settings::Process;
use crate::storage::history::{
    ChangedBy, Draft, Entry, Event, HistoryAnswer, HistoryPage, Pending, Stamp, Unit,
};

/// Drafts waiting for the background writer: a fault storm fills it, it never grows.
pub const HISTORY_QUEUE: usize = 8;

/// What the bridge keeps for the history between the flash writes: the drafts not yet
/// written, and the wall clock.
#[derive(Debug, Default)]
pub struct HistoryLog {
    pending: Pending<HISTORY_QUEUE>,
    /// Unix seconds at this boot's start, once the CNC has set the clock.
    clock_at_boot: Option<u32>,
    /// The link was lost this boot: its next start is "back", not the first found.
    link_lost: bool,
    /// The current before the process change under way (the link's view changes with the
    /// write, before the change is confirmed).
    amps_before: Option<Amps>,
}

impl HistoryLog {
    /// Queues `event` (never waits; see [`Pending::push`]).
    pub fn note(&mut self, now: Instant, unit: Unit, event: Event) {
        let stamp = self.stamp(now, unit);
        self.pending.push(Draft { stamp, event });
    }

    /// The stamp of something that happens `now`.
    pub fn stamp(&self, now: Instant, unit: Unit) -> Stamp {
        Stamp {
            // Wraps after 49 days, as the entry's field does.
            uptime_ms: now.as_millis() as u32,
            clock_at_boot: self.clock_at_boot,
            unit,
        }
    }

    /// The oldest draft, for the writer.
    pub fn take(&mut self) -> Option<Draft> {
        self.pending.take()
    }

    /// Whether drafts wait for the writer.
    pub fn has_drafts(&self) -> bool {
        !self.pending.is_empty()
    }

    /// The wall clock now, if set.
    fn clock(&self, now: Instant) -> Option<WallClock> {
        self.clock_at_boot
            .map(|at| WallClock::from_unix_seconds(at.saturating_add(uptime_secs(now))))
    }
}

/// Whole seconds since boot.
fn uptime_secs(now: Instant) -> u32 {
    // `div_rem_u16`: a 64-bit division would link the runtime's (docs/developers.md).
    let (secs, _) = plasma_protocol::time::div_rem_u16(now.as_millis(), 1000);
    u32::try_from(secs).unwrap_or(u32::MAX)
}

/// The unit an entry is about: the family and model of unit `unit` (its index) on the line.
pub fn unit_on(units: &Units, unit: usize) -> Unit {
    let status = units.link(unit).status();
    Unit {
        family: status.family,
        model: model_code(status),
        // Below MAX_UNITS: the index of a unit the bridge drives.
        line_index: unit as u8,
    }
}

fn by_word(by: ChangedBy) -> &'static str {
    match by {
        ChangedBy::Text => "TEXT",
        ChangedBy::Phoenix => "PHOENIX",
        ChangedBy::ModbusCnc => "MODBUS",
    }
}

/// The wall-clock time of `entry`: from its boot's clock, or, for an entry of the running
/// boot written before the clock was set, from the clock set since.
fn entry_clock(entry: &Entry, page: &HistoryPage, clock_at_boot: Option<u32>) -> Option<WallClock> {
    let at_boot = entry
        .clock_at_boot
        .or(clock_at_boot.filter(|_| entry.boot == page.boot))?;
    Some(WallClock::from_unix_seconds(
        at_boot.saturating_add(entry.uptime_ms / 1000),
    ))
}

/// One `HISTORY` line (see docs/cnc-protocol.md).
fn write_entry(l: &mut ReplyLine, entry: &Entry, clock: Option<WallClock>) -> fmt::Result {
    let mut w = ReplyWriter::data(l, "HISTORY")?;
    w.field("seq", entry.sequence)?;
    w.field("boot", entry.boot)?;
    w.field("uptime_ms", entry.uptime_ms)?;
    match clock {
        Some(clock) => w.field("clock", clock)?,
        None => w.field("clock", "-")?,
    }
    match entry.unit.family {
        Some(family) => w.field("family", family_word(family))?,
        None => w.field("family", "-")?,
    }
    w.field("model", model_name(entry.unit.model).unwrap_or("-"))?;
    match entry.event {
        Event::FaultAppeared { fault, steps } => {
            w.field("event", "FAULT")?;
            w.field("code", FaultId(fault))?;
            w.field("action", steps_word(steps))?;
        }
        Event::FaultCleared { fault } => {
            w.field("event", "FAULT_CLEARED")?;
            w.field("code", FaultId(fault))?;
        }
        Event::LinkLost => w.field("event", "LINK_LOST")?,
        Event::LinkBack => w.field("event", "LINK_BACK")?,
        Event::UnitPowerCycled => w.field("event", "UNIT_POWER_CYCLED")?,
        Event::BridgeReset { cause } => {
            w.field("event", "RESET")?;
            w.field("cause", cause.as_str())?;
        }
        Event::StartRefused { interlock } => {
            w.field("event", "START_REFUSED")?;
            w.field("reason", interlock_word(interlock))?;
        }
        Event::ProcessChanged { from, to, by } => {
            w.field("event", "PROCESS")?;
            w.field("from_amps", Amps::from_raw(from))?;
            w.field("to_amps", Amps::from_raw(to))?;
            w.field("by", by_word(by))?;
        }
        Event::GasCheck {
            passed,
            measured,
            permitted_min,
            permitted_max,
        } => {
            w.field("event", "GAS_CHECK")?;
            w.field("result", if passed { "PASS" } else { "FAIL" })?;
            w.field("psi", measured)?;
            w.field("min_psi", permitted_min)?;
            w.field("max_psi", permitted_max)?;
        }
        Event::ConsumableChanged => w.field("event", "CONSUMABLES_CHANGED")?,
        Event::EntriesDropped { count } => {
            w.field("event", "DROPPED")?;
            w.field("count", count)?;
        }
        Event::Cleared => w.field("event", "CLEARED")?,
    }
    w.finish().map(|_| ())
}

/// What of a link event goes into the history.
pub(super) fn note_link_event(ctx: &mut Context<'_>, event: &LinkEvent) {
    let event = match *event {
        LinkEvent::LinkUp { .. } if ctx.history.link_lost => Event::LinkBack,
        LinkEvent::LinkDown { .. } => {
            ctx.history.link_lost = true;
            Event::LinkLost
        }
        LinkEvent::FaultRaised { code, .. } => Event::FaultAppeared {
            fault: code,
            steps: steps_of(code),
        },
        LinkEvent::FaultCleared { code } => Event::FaultCleared { fault: code },
        LinkEvent::UnitPowerCycled { .. } => Event::UnitPowerCycled,
        _ => return,
    };
    note(ctx, event);
}

/// What of a discrete-I/O event goes into the history: START refused, and why.
pub(super) fn note_io_event(ctx: &mut Context<'_>, event: IoEvent) {
    let interlock = match event {
        IoEvent::StartRefused { reason } => reason,
        IoEvent::StuckTorchOnAtPowerUp => Interlock::TorchOnAtPowerUp,
        _ => return,
    };
    note(ctx, Event::StartRefused { interlock });
}

/// A process change is about to be sent: the current it changes from.
pub(super) fn process_change_starts(ctx: &mut Context<'_>) {
    ctx.history.amps_before = ctx
        .settings
        .process
        .map(|p| p.amps)
        .or_else(|| ctx.link().status().settings.map(|s| s.current));
}

/// The process the unit confirmed becomes the one the settings keep; a change is noted.
pub(super) fn keep_process(ctx: &mut Context<'_>, process: Process, by: ChangedBy) {
    let before = ctx.history.amps_before.take();
    ctx.settings.process = Some(process);
    if before != Some(process.amps) {
        let from = before.map_or(0, |a| a.raw());
        let to = process.amps.raw();
        note(ctx, Event::ProcessChanged { from, to, by });
    }
}

/// Queues `event`, now, about the unit this call is about (`ctx.unit`).
pub(super) fn note(ctx: &mut Context<'_>, event: Event) {
    let unit = unit_on(ctx.units, ctx.unit);
    ctx.history.note(ctx.now, unit, event);
}

impl Session {
    /// `HISTORY [N|CLEAR]`: waits for the history's driver.
    pub(super) fn history(&mut self, command: HistoryCommand) -> Option<ReplyLine> {
        self.pending = Some(Waiting::History {
            command,
            taken: false,
        });
        None
    }

    /// `CLOCK [time]`: sets the wall clock (kept as the unix seconds at this boot's start)
    /// and reports it.
    pub(super) fn clock(ctx: &mut Context<'_>, set: Option<WallClock>) -> ReplyLine {
        if let Some(clock) = set {
            ctx.history.clock_at_boot =
                Some(clock.unix_seconds().saturating_sub(uptime_secs(ctx.now)));
        }
        match ctx.history.clock(ctx.now) {
            Some(clock) => ok_line(|w| w.field("clock", clock)),
            None => ok_line(|w| w.field("clock", "unset")),
        }
    }

    /// Once when `HISTORY` waits for its driver: what to read or erase.
    pub fn take_history_request(&mut self) -> Option<HistoryCommand> {
        match &mut self.pending {
            Some(Waiting::History { command, taken }) if !*taken => {
                *taken = true;
                Some(*command)
            }
            _ => None,
        }
    }

    /// The driver's answer: the entry lines and the closing `OK` (or `ERR STORAGE`).
    pub fn history_finished(&mut self, ctx: &mut Context<'_>, answer: &HistoryAnswer) {
        let Some(Waiting::History { command, .. }) = self.pending else {
            return;
        };
        self.pending = None;
        let reply = match (answer, command) {
            (Err(_), _) => err_line(ErrorCode::Storage, texts::HISTORY_UNAVAILABLE),
            (Ok(_), HistoryCommand::Clear) => ok_line(|w| w.field("history", "cleared")),
            (Ok(page), HistoryCommand::Newest(_)) => {
                for entry in &page.entries {
                    let clock = entry_clock(entry, page, ctx.history.clock_at_boot);
                    let mut l = line(|l| write_entry(l, entry, clock));
                    tag_unit(&mut l, usize::from(entry.unit.line_index));
                    self.push(l.as_bytes());
                }
                ok_line(|w| {
                    w.field("history", page.entries.len())?;
                    w.field("skipped", page.skipped)
                })
            }
        };
        self.send(reply);
        self.pump(ctx);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::String;
    use std::vec::Vec;

    use crate::cnc::rig::{Rig, is_reply};
    use crate::platform::safe_state::ResetCause;
    use crate::settings::Settings;

    /// `HISTORY ...`'s lines: the entries, then the reply.
    fn history(rig: &mut Rig, line: &str) -> Vec<String> {
        let tokens = rig.send_bytes(std::format!("{line}\r\n").as_bytes(), 1);
        let lines: Vec<String> = tokens.into_iter().filter(|t| !t.starts_with('!')).collect();
        assert!(lines.last().is_some_and(|l| is_reply(l)), "{lines:?}");
        lines
    }

    /// The entries of one SYNC unit: order, `seq`, `boot`, the link's loss and return, the
    /// reset's cause. Every family's codes and models, and the flash across a power cycle of
    /// the board, are the harness's scenario
    /// (`the_history_keeps_faults_across_a_power_cycle_on_every_family`).
    #[test]
    fn faults_the_link_and_a_reset_are_kept_newest_first() {
        let mut rig = Rig::sync65(Settings::default());
        rig.fault(500);
        rig.run(300);
        rig.fault(0);
        rig.run(300);
        rig.unplug(true);
        rig.run(3000);
        rig.unplug(false);
        rig.run(1000);
        assert!(rig.bridge.status().link_up);
        rig.reboot(Settings::default(), ResetCause::IndependentWatchdog);
        rig.run(600);
        let lines = history(&mut rig, "HISTORY 6");
        let events: Vec<&str> = lines
            .iter()
            .map(|l| l.split(" event=").nth(1).unwrap_or(l))
            .collect();
        assert_eq!(
            events,
            [
                "RESET cause=watchdog",
                "LINK_BACK",
                "LINK_LOST",
                "FAULT_CLEARED code=0-50-0",
                "FAULT code=0-50-0 action=required",
                "OK history=5 skipped=0",
            ],
            "{lines:?}"
        );
        assert!(
            lines[1].starts_with("HISTORY seq=3 boot=0 uptime_ms="),
            "{}",
            lines[1]
        );
        assert!(lines[1].contains(" clock=- family=SYNC "), "{}", lines[1]);
        assert!(
            lines[0].starts_with("HISTORY seq=4 boot=1 "),
            "{}",
            lines[0]
        );
        assert_eq!(rig.cmd("HISTORY 1").as_str(), "OK history=1 skipped=0");
    }

    #[test]
    fn the_clock_set_later_dates_this_boots_entries() {
        let mut rig = Rig::sync65(Settings::default());
        assert_eq!(rig.cmd("CLOCK"), "OK clock=unset");
        rig.fault(500);
        rig.run(400);
        let at = rig.now;
        assert_eq!(
            rig.cmd("CLOCK 2026-11-26T07:30:00"),
            "OK clock=2026-11-26T07:30:00"
        );
        rig.run(2000);
        assert_eq!(rig.cmd("CLOCK"), "OK clock=2026-11-26T07:30:02");
        let lines = history(&mut rig, "HISTORY");
        // The fault came about 0.1-0.4 s before the clock was set: the same second or the
        // one before, from the clock of its boot.
        let boot_clock = 1_795_678_200 - at.as_millis() / 1000;
        let fault = &lines[0];
        assert!(fault.contains(" event=FAULT "), "{fault}");
        let uptime: u64 = fault
            .split(" uptime_ms=")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap();
        let expected = plasma_protocol::cnc::clock::WallClock::from_unix_seconds(
            (boot_clock + uptime / 1000) as u32,
        );
        assert!(
            fault.contains(&std::format!(" clock={expected} ")),
            "{fault}"
        );
    }

    #[test]
    fn clear_leaves_one_entry_that_says_so() {
        let mut rig = Rig::sync65(Settings::default());
        rig.fault(500);
        rig.run(300);
        assert_eq!(rig.cmd("HISTORY CLEAR"), "OK history=cleared");
        let lines = history(&mut rig, "HISTORY");
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[0].ends_with(" family=SYNC model=Powermax65 event=CLEARED"),
            "{lines:?}"
        );
        assert_eq!(lines[1], "OK history=1 skipped=0");
    }

    #[test]
    fn a_process_change_says_who_made_it() {
        let mut rig = Rig::sync65(Settings::default());
        assert!(rig.cmd("SET PROCESS CUT 65 AUTO").starts_with("OK"));
        rig.run(300);
        let lines = history(&mut rig, "HISTORY 1");
        assert!(
            lines[0].ends_with(" event=PROCESS from_amps=45 to_amps=65 by=TEXT"),
            "{lines:?}"
        );
    }

    #[test]
    fn start_refused_is_kept_with_its_interlock() {
        let mut rig = Rig::new(Settings::default(), None);
        let mut ctx_event = crate::io::IoEvent::StartRefused {
            reason: crate::io::Interlock::LinkDown,
        };
        rig.bridge.on_io_event(rig.now, ctx_event);
        ctx_event = crate::io::IoEvent::ArcOn;
        rig.bridge.on_io_event(rig.now, ctx_event);
        let lines = history(&mut rig, "HISTORY");
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(
            lines[0].ends_with(" family=- model=- event=START_REFUSED reason=link_down"),
            "{lines:?}"
        );
    }
}
