//! What the link and the interlocks report: the reply of the command in progress, and `!`
//! event lines while events are on.

use core::fmt::{self, Write};

use plasma_protocol::cnc::reply::ReplyWriter;

use super::describe::{
    ActionWord, FaultId, ModelName, OrDash, ProcessText, Uid, family_word, fault_text,
    interlock_word, on_off, process_failure_word, state_name, transaction_word,
};
use super::replies::complete;
use super::texts::RefusalText;
use super::{Context, Pending, ReplyLine, Session};
use crate::io::{Interlock, IoEvent};
use crate::link::{Family, LinkDownReason, LinkEvent, UnitStatus};

impl Session {
    /// A link event: the reply of the command in progress, and/or an event line.
    pub fn on_link_event(&mut self, ctx: &mut Context<'_>, event: &LinkEvent) {
        super::history::note_link_event(ctx, event);
        super::consumables::note_link_event(ctx, event);
        self.powermax.on_link_event(ctx, event);
        self.gas_check_link_event(ctx, event);
        if let LinkEvent::CommandDone { ticket, result } = event {
            if let Some(Pending::Link {
                ticket: t,
                awaiting,
            }) = self.pending
                && t == *ticket
                && ctx.unit == self.answering
            {
                self.pending = None;
                Session::keep_outcome(ctx, awaiting, result, self.origin);
                let reply = complete(ctx, awaiting, result);
                self.send(reply);
                self.pump(ctx);
            }
            return;
        }
        // The kept process is forgotten: so is its persisted copy (`CONFIG SAVE` stores none;
        // only the first unit's process is persisted).
        if let LinkEvent::UnitPowerCycled { reapply: false } = event
            && ctx.unit == 0
        {
            ctx.settings.process = None;
        }
        let status = ctx.link().status();
        self.event(ctx, |l| write_link_event(l, event, status));
    }

    /// A settings change made through the Powermax registers was refused before it was
    /// sent: `!SETTINGS failed reason=refused fault=0-11-X` (the fault 0x2098 reads as).
    pub(super) fn settings_refused_event(
        &mut self,
        ctx: &Context<'_>,
        fault: plasma_protocol::powermax::FaultCode,
    ) {
        self.event(ctx, |l| {
            let mut w = ReplyWriter::event(l, "SETTINGS")?;
            w.word("failed")?;
            w.field("reason", "refused")?;
            w.field("fault", FaultId(crate::link::ActiveFault::Powermax(fault)))?;
            w.finish().map(|_| ())
        });
    }

    /// A discrete-I/O event: an event line.
    pub fn on_io_event(&mut self, ctx: &mut Context<'_>, event: IoEvent) {
        super::history::note_io_event(ctx, event);
        super::consumables::note_io_event(ctx, event);
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
            IoEvent::SystemError => l.write_str("!SYSTEM ERROR\r\n"),
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
}

/// The event line of a link event other than `CommandDone` (which has none).
fn write_link_event(l: &mut ReplyLine, event: &LinkEvent, status: &UnitStatus) -> fmt::Result {
    let family = status.family;
    match *event {
        LinkEvent::LinkUp { family, .. } => {
            let mut w = ReplyWriter::event(l, "LINK")?;
            w.word("UP")?;
            w.field("model", ModelName(status))?;
            w.word(family_word(family))?;
            w.finish().map(|_| ())
        }
        LinkEvent::LinkDown { reason } => write_link_down(l, reason),
        // As `FAULT` answers it; `text=` is the last field and runs to the end of the line.
        LinkEvent::FaultRaised { code, .. } => write!(
            l,
            "!FAULT {} action={} text={}\r\n",
            FaultId(code),
            ActionWord(code),
            fault_text(code, family)
        ),
        LinkEvent::FaultCleared { code } => {
            let mut w = ReplyWriter::event(l, "FAULT")?;
            w.word("CLEARED")?;
            w.field("code", FaultId(code))?;
            w.finish().map(|_| ())
        }
        LinkEvent::ProcessApplied {
            settings,
            reapplied,
        } => {
            write!(l, "!SETTINGS applied {}", ProcessText(&settings, family))?;
            if reapplied {
                l.write_str(" reapplied=YES")?;
            }
            l.write_str("\r\n")
        }
        LinkEvent::ProcessFailed { reason } => {
            let mut w = ReplyWriter::event(l, "SETTINGS")?;
            w.word("failed")?;
            w.field("reason", process_failure_word(&reason))?;
            w.finish().map(|_| ())
        }
        // The persisted process, refused before sending.
        LinkEvent::RestoreRefused { refusal } => {
            let mut w = ReplyWriter::event(l, "SETTINGS")?;
            w.word("failed")?;
            w.field("reason", "refused")?;
            w.field("why", RefusalText(&refusal))?;
            w.finish().map(|_| ())
        }
        LinkEvent::CartridgeChanged { uid } => {
            let mut w = ReplyWriter::event(l, "CARTRIDGE")?;
            w.word("changed")?;
            w.field("uid", Uid(&uid))?;
            w.finish().map(|_| ())
        }
        LinkEvent::StateChanged { from, to } => write_state_changed(l, from, to, family),
        LinkEvent::UnitPowerCycled { reapply } => {
            let mut w = ReplyWriter::event(l, "UNIT")?;
            w.word("POWER_CYCLED")?;
            w.field("reapply", on_off(reapply))?;
            w.finish().map(|_| ())
        }
        LinkEvent::RemoteModeChanged { remote } => {
            let mut w = ReplyWriter::event(l, "REMOTE")?;
            w.word(on_off(remote))?;
            w.finish().map(|_| ())
        }
        // Answered as the reply of its command (see `on_link_event`); no event line.
        LinkEvent::CommandDone { .. } => Err(fmt::Error),
    }
}

fn write_link_down(l: &mut ReplyLine, reason: LinkDownReason) -> fmt::Result {
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
}

fn write_state_changed(
    l: &mut ReplyLine,
    from: Option<plasma_protocol::hpr::StateCode>,
    to: plasma_protocol::hpr::StateCode,
    family: Option<Family>,
) -> fmt::Result {
    let mut w = ReplyWriter::event(l, "STATE")?;
    w.word(to.0)?;
    w.field("name", state_name(to, family))?;
    w.field("from", OrDash(from.map(|s| s.0)))?;
    w.finish().map(|_| ())
}

#[cfg(test)]
mod tests;
