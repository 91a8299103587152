//! Consumable life as the session sees it: `CONSUMABLES [NEW]`, the `!WARN CONSUMABLE`
//! events, STATUS's `consumables=` field, and what of the link's and the I/O's events the
//! record ([`crate::consumables`]) counts.

use core::fmt::Write as _;

use plasma_protocol::cnc::ConsumablesCommand;
use plasma_protocol::cnc::reply::ReplyWriter;

use plasma_protocol::cnc::ErrorCode;

use super::{Context, ReplyLine, Session, err_line, ok_line, texts};
use crate::consumables::{Source, Usage};
use crate::io::IoEvent;
use crate::link::{ActiveFault, Family, LinkEvent};
use crate::storage::history::Event;

/// A UID of all zeros: the unit could not read the cartridge (SYNC manual
/// 000_dd931256418ae627.txt line 1431), not a cartridge of its own.
const UNREADABLE_UID: [u8; 16] = [0; 16];

/// The counts of the set in use now: a SYNC's cartridge, else the bridge's.
pub(super) fn usage(ctx: &Context<'_>) -> Usage {
    let status = ctx.link().status();
    let cartridge = status
        .cartridge
        .as_ref()
        .filter(|c| status.family == Some(Family::PowermaxSync) && c.uid.0 != UNREADABLE_UID);
    ctx.consumables.usage(ctx.now, cartridge)
}

/// The share of life used, percent, for STATUS (`None`: both limits OFF, or a unit beyond
/// the first, whose consumables the bridge does not follow).
pub(super) fn used_percent(ctx: &Context<'_>) -> Option<u32> {
    if ctx.unit != 0 {
        return None;
    }
    usage(ctx).used_percent(ctx.settings.consumable_limits)
}

/// What of an I/O event the record counts (the first unit's).
pub(super) fn note_io_event(ctx: &mut Context<'_>, event: IoEvent) {
    if ctx.unit != 0 {
        return;
    }
    let c = &mut *ctx.consumables;
    match event {
        IoEvent::ArcOn => c.arc_on(ctx.now),
        IoEvent::ArcOff => c.arc_off(ctx.now),
        IoEvent::TransferTimeout => c.start_without_transfer(),
        IoEvent::RampdownError => c.rampdown_error(),
        _ => {}
    }
}

/// What of a link event the record counts: a 0-32-x fault.
pub(super) fn note_link_event(ctx: &mut Context<'_>, event: &LinkEvent) {
    if ctx.unit != 0 {
        return;
    }
    if let LinkEvent::FaultRaised {
        code: ActiveFault::Powermax(code),
        ..
    } = *event
    {
        ctx.consumables.fault(code);
    }
}

/// Writes a percentage, `OFF` when there is none.
struct Percent(Option<u32>);

impl core::fmt::Display for Percent {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Some(p) => write!(f, "{p}%"),
            None => f.write_str("OFF"),
        }
    }
}

/// A limit, `OFF` when there is none.
struct Limit(Option<u32>);

impl core::fmt::Display for Limit {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Some(n) => write!(f, "{n}"),
            None => f.write_str("OFF"),
        }
    }
}

/// A cartridge UID as its 16 characters (hex digits in the manual's example).
struct Uid([u8; 16]);

impl core::fmt::Display for Uid {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for &b in &self.0 {
            let c = if b.is_ascii_alphanumeric() { b } else { b'?' };
            f.write_char(char::from(c))?;
        }
        Ok(())
    }
}

fn source_word(source: Source) -> &'static str {
    match source {
        Source::Cartridge => "cartridge",
        Source::Bridge => "bridge",
    }
}

impl Session {
    /// `CONSUMABLES`: the set in use; `CONSUMABLES NEW`: a new set (the table refuses it on a
    /// SYNC, whose cartridge names its set).
    pub(super) fn consumables(ctx: &mut Context<'_>, command: ConsumablesCommand) -> ReplyLine {
        if ctx.unit != 0 {
            return err_line(ErrorCode::Unsupported, texts::CONSUMABLES_FIRST_UNIT);
        }
        if command == ConsumablesCommand::New {
            ctx.consumables.new_set(ctx.now, None);
            super::history::note(ctx, Event::ConsumableChanged);
        }
        let usage = usage(ctx);
        let limits = ctx.settings.consumable_limits;
        let set = *ctx.consumables.set();
        ok_line(|w| {
            w.field("source", source_word(usage.source))?;
            w.field("starts", usage.starts)?;
            w.field("arc_s", usage.arc_seconds)?;
            w.field("start_limit", Limit(limits.starts))?;
            w.field("arc_limit_s", Limit(limits.arc_seconds))?;
            w.field("used", Percent(usage.used_percent(limits)))?;
            w.field("wear_faults", set.wear_faults)?;
            let hpr = matches!(
                ctx.link().status().family,
                Some(Family::Hpr | Family::MaxPro200)
            );
            if hpr || set.rampdown_errors > 0 {
                w.field("rampdown_errors", set.rampdown_errors)?;
            }
            if let Some(uid) = set.uid {
                w.field("uid", Uid(uid))?;
            }
            Ok(())
        })
    }

    /// Follows the set in use: another SYNC cartridge starts a new record (and a history
    /// entry; the first one the bridge sees only a record); a warning due goes out as
    /// `!WARN CONSUMABLE`.
    pub(super) fn follow_consumables(&mut self, ctx: &mut Context<'_>) {
        let status = ctx.link().status();
        if status.family == Some(Family::PowermaxSync)
            && let Some(cartridge) = status.cartridge
            && cartridge.uid.0 != UNREADABLE_UID
        {
            let counters = cartridge.counters;
            let replaced = ctx.consumables.cartridge_seen(ctx.now, cartridge.uid.0);
            ctx.consumables
                .cartridge_counts(u32::from(counters.starts), counters.transfer_seconds());
            if replaced {
                super::history::note(ctx, Event::ConsumableChanged);
            }
        }
        let usage = usage(ctx);
        let limits = ctx.settings.consumable_limits;
        let Some(warning) = ctx.consumables.warning_due(&usage, limits) else {
            return;
        };
        self.event(ctx, |l| {
            let mut w = ReplyWriter::event(l, "WARN")?;
            w.word("CONSUMABLE")?;
            w.field("used", Percent(Some(warning.used_percent)))?;
            w.field("threshold", Percent(Some(warning.threshold)))?;
            w.field("source", source_word(usage.source))?;
            w.field("starts", usage.starts)?;
            w.field("arc_s", usage.arc_seconds)?;
            w.finish().map(|_| ())
        });
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::String;

    use crate::cnc::rig::{Rig, events_on};
    use crate::io::IoEvent;
    use crate::platform::safe_state::ResetCause;

    fn cut(rig: &mut Rig, arc_ms: u64) {
        rig.bridge.on_io_event(rig.now, IoEvent::ArcOn);
        rig.run(arc_ms);
        rig.bridge.on_io_event(rig.now, IoEvent::ArcOff);
        rig.run(200);
    }

    fn warnings(rig: &Rig) -> std::vec::Vec<&String> {
        rig.received
            .iter()
            .filter(|l| l.starts_with("!WARN CONSUMABLE"))
            .collect()
    }

    #[test]
    fn an_hpr_counts_its_cuts_warns_once_each_and_keeps_the_set_across_a_reset() {
        let mut rig = Rig::hpr("HPR260XD");
        rig.bridge.on_io_event(rig.now, IoEvent::RampdownError);
        assert_eq!(
            rig.cmd("CONSUMABLES"),
            "OK source=bridge starts=0 arc_s=0 start_limit=OFF arc_limit_s=OFF used=OFF \
             wear_faults=0 rampdown_errors=1"
        );
        assert_eq!(rig.cmd("EVENTS ON"), "OK events=ON");
        assert!(rig.cmd("CONFIG consumable_start_limit 10").ends_with("=10"));
        for _ in 0..8 {
            cut(&mut rig, 1500);
        }
        assert!(warnings(&rig).is_empty());
        assert!(rig.cmd("STATUS").contains(" consumables=80%"));
        cut(&mut rig, 1500);
        cut(&mut rig, 1500);
        cut(&mut rig, 1500);
        assert_eq!(
            warnings(&rig),
            [
                // Given as the start that reaches the share begins: its arc is not counted yet.
                "!WARN CONSUMABLE used=90% threshold=90% source=bridge starts=9 arc_s=12",
                "!WARN CONSUMABLE used=100% threshold=100% source=bridge starts=10 arc_s=13"
            ]
        );
        let saved = rig
            .saved_consumables
            .expect("the warnings were saved at once");
        assert!(saved.warned_100);
        // After a reset with what was saved: no warning again, the counts go on.
        let settings = *rig.bridge.settings();
        rig.reboot(settings, ResetCause::PowerOn);
        rig.received.clear();
        cut(&mut rig, 1500);
        assert!(warnings(&rig).is_empty(), "{:?}", rig.received);
        assert!(
            rig.cmd("CONSUMABLES")
                .starts_with("OK source=bridge starts=11 ")
        );
        // A new set: from zero, history entry, and warned again when worn.
        let reply = rig.cmd("CONSUMABLES NEW");
        assert!(
            reply.starts_with("OK source=bridge starts=0 arc_s=0 "),
            "{reply}"
        );
        assert!(reply.contains(" used=0% "), "{reply}");
        let tokens = rig.send_bytes(b"HISTORY 1\r\n", 1);
        assert!(
            tokens[0].contains(" family=HPR ") && tokens[0].ends_with(" event=CONSUMABLES_CHANGED"),
            "{tokens:?}"
        );
    }

    #[test]
    fn a_sync_shows_its_cartridge_and_refuses_new() {
        let mut rig = Rig::sync65(events_on());
        rig.run(600);
        let reply = rig.cmd("CONSUMABLES");
        assert!(reply.starts_with("OK source=cartridge starts="), "{reply}");
        assert!(reply.ends_with(" uid=E00401D0036FB25D"), "{reply}");
        let refused = rig.cmd("CONSUMABLES NEW");
        assert_eq!(
            refused,
            "ERR UNSUPPORTED CONSUMABLES NEW is not taken on a Powermax SYNC: its cartridge \
             keeps its own counts and another cartridge starts a new record by itself"
        );
    }
}
