//! The Powermax driver (SYNC and legacy): polling, slow data, settings and commands over
//! Modbus ASCII. Family specifics live in [`sync`] and [`legacy`]; [`modbus`] holds the
//! Modbus pieces both use (and auto-detection's device-identification probe).
//!
//! The driver's jobs are split by module: this one schedules (what goes out next: the rest of
//! the active command, the fault register when it is due, the rest of a poll cycle, then
//! polls, commands and other due work in turn),
//! `settings` owns the settings to keep and re-apply, `jobs` carries the active command
//! through its steps, `reply` reads what the unit answers, and `submit` checks a command
//! before it is queued.

mod jobs;
pub(crate) mod legacy;
pub(crate) mod modbus;
mod process;
mod reply;
mod submit;
pub(crate) mod sync;

use heapless::Deque;
use plasma_protocol::powermax::device_id;

use crate::link::config::ProtocolChoice;
use crate::link::core::Core;
use crate::link::event::Ticket;
use crate::link::kept::Reapply;
use crate::link::slow::SlowData;
use crate::link::status::{Family, Model};
use modbus::{BlockPart, BlockPoller, MbRequest};
use plasma_protocol::time::{Duration, Instant};
use sync::SlowItem;

use process::DesiredProcess;

/// Silence after a quick restart (SYNC guide: "wait 2 seconds before you send a new read or
/// write request").
pub(crate) const QUICK_RESTART_BLACKOUT: Duration = Duration::from_secs(2);
/// How often the SYNC cartridge UID is read to notice a cartridge change.
pub(crate) const UID_CHECK_INTERVAL: Duration = Duration::from_secs(1);
/// Wait before re-applying kept settings again after a re-apply failed.
pub(crate) const REAPPLY_BACKOFF: Duration = Duration::from_secs(5);
/// Commands waiting behind the active one.
const QUEUE_CAPACITY: usize = 4;
/// The active fault is read at least this often, from the start of one read of the fault
/// register to the next. The status poll reads it too; between two polls of the default
/// 100 ms schedule one read of the fault register alone (17 + 15 characters, about 20 ms of
/// wire) goes out 60 ms after the poll, which splits the wait so that a fault is known within
/// about 75 ms of its appearing whichever read sees it first (the poll's reply is the longer).
/// A poll interval at or below it needs no such read. The SYNC guide's rule, "at least every
/// 1 s", is far inside.
pub const FAULT_CHECK_INTERVAL: Duration = Duration::from_millis(60);

/// Which register family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Variant {
    /// 0x3xxx.
    Sync,
    /// 0x2xxx.
    Legacy,
}

/// What a Modbus transaction of this driver is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MbPurpose {
    /// Status poll (whole block or part).
    Poll(BlockPart),
    /// A slow-data span.
    Slow(SlowItem),
    /// The SYNC cartridge block (whole or part).
    CartridgeBlock(BlockPart),
    /// The UID read that notices a cartridge change.
    UidCheck,
    /// Read Device Identification again for a unit detection found only by the legacy
    /// register probe (a SYNC unit whose identification replies were lost is told apart).
    Identify,
    /// The current step of the active command.
    Active,
    /// The fault register alone, between status polls.
    FaultCheck,
}

/// A kind of work that takes turns on the line (see [`PowermaxDriver::next_turn`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Turn {
    /// A status poll or a fault check.
    Status,
    /// A command (or a re-apply).
    Command,
    /// Slow data, the cartridge check, identification.
    Other,
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Job {
    Apply(DesiredProcess),
    Exit,
    GasTest(bool),
    ReadPressure,
    QuickRestart,
    Raw(MbRequest),
}

#[derive(Debug, Clone, PartialEq, Eq)]
struct Active {
    /// `None` for a re-apply the link started itself.
    ticket: Option<Ticket>,
    /// The re-apply is the persisted process after start-up: reported like a command
    /// (`reapplied` not set), not tried again when it fails.
    restoring: bool,
    job: Job,
    step: u8,
}

/// Driver state for one detected Powermax.
#[derive(Debug, Clone)]
pub(crate) struct PowermaxDriver {
    variant: Variant,
    poll: BlockPoller,
    poll_started: Instant,
    next_poll_at: Instant,
    cartridge: BlockPoller,
    slow: SlowData,
    next_uid_check_at: Instant,
    queue: Deque<(Ticket, Job), QUEUE_CAPACITY>,
    active: Option<Active>,
    reapply_pending: bool,
    reapply_not_before: Instant,
    /// The unit answered again with settings kept: its first poll tells a power cycle from a
    /// lost link before they are re-applied (see `kept`).
    returned: bool,
    blackout_until: Option<Instant>,
    /// The unit refused device identification (an exception): it is not asked again.
    identify_refused: bool,
    /// The kinds of work, the one served longest ago first.
    turns: [Turn; 3],
    /// When the fault register is due to be read again.
    fault_check_at: Instant,
    /// The last request read the fault register (see `next_request` on a shared line).
    fault_read_last: bool,
    /// The unit refused a read of the fault register alone: the polls alone read it.
    fault_read_refused: bool,
    now: Instant,
}

impl PowermaxDriver {
    /// A driver for a unit just detected; slow data is read first, and kept settings are
    /// re-applied once the first poll shows the link was lost, not the unit switched off.
    pub(crate) fn new(variant: Variant, now: Instant, core: &Core) -> Self {
        let plan = match variant {
            Variant::Sync => sync::POLL_PLAN,
            Variant::Legacy => legacy::POLL_PLAN,
        };
        PowermaxDriver {
            variant,
            poll: BlockPoller::new(plan),
            poll_started: now,
            next_poll_at: now,
            cartridge: BlockPoller::new(plasma_protocol::powermax::sync::CARTRIDGE_BLOCK),
            slow: SlowData::new(
                match variant {
                    Variant::Sync => SlowItem::ALL_ITEMS,
                    Variant::Legacy => SlowItem::LEGACY_ITEMS,
                },
                now,
                core.config.slow_data_interval,
            ),
            next_uid_check_at: now + UID_CHECK_INTERVAL,
            queue: Deque::new(),
            active: None,
            reapply_pending: matches!(core.kept.powermax_due(), Some(Reapply::Restore(_))),
            reapply_not_before: now,
            returned: matches!(core.kept.powermax_due(), Some(Reapply::Kept(_))),
            blackout_until: None,
            identify_refused: false,
            turns: [Turn::Status, Turn::Command, Turn::Other],
            fault_check_at: now,
            fault_read_last: false,
            fault_read_refused: false,
            now,
        }
    }

    /// The family this driver speaks.
    pub(crate) fn family(&self) -> Family {
        match self.variant {
            Variant::Sync => Family::PowermaxSync,
            Variant::Legacy => Family::PowermaxLegacy,
        }
    }

    /// True when the active command is a RAW forward (its reply bytes are kept).
    pub(crate) fn active_is_raw(&self) -> bool {
        matches!(
            self.active,
            Some(Active {
                job: Job::Raw(_),
                ..
            })
        )
    }

    /// True while the quick-restart silence lasts.
    fn in_blackout(&self, now: Instant) -> bool {
        self.blackout_until.is_some_and(|until| now < until)
    }

    /// Earliest time the driver wants to send something. It mirrors
    /// [`PowermaxDriver::next_request`]: a time not after the last call is only returned when
    /// that call will send something, so a caller sleeping until then never spins.
    pub(crate) fn wake_at(&self, core: &Core) -> Option<Instant> {
        if let Some(until) = self.blackout_until.filter(|&u| self.now < u) {
            return Some(until);
        }
        let busy = self.poll.in_cycle()
            || self.active.is_some()
            || !self.queue.is_empty()
            || self.slow.pending() != 0;
        if busy {
            return Some(self.now);
        }
        let mut at = self.next_poll_at.min(self.slow.wake_at());
        if !self.fault_read_refused {
            at = at.min(self.fault_check_at);
        }
        // The UID check needs a cartridge read first (slow data, retried on its own).
        if self.variant == Variant::Sync && core.status.cartridge.is_some() {
            at = at.min(self.next_uid_check_at);
        }
        // A re-apply waits for the limits (slow data, retried on its own).
        if self.reapply_pending && core.status.limits.is_some() {
            at = at.min(self.reapply_not_before.max(self.now));
        }
        Some(at)
    }

    /// The next request to send, if any (called only when nothing is in flight).
    /// Returns the purpose, the request and a retry count overriding the configured one.
    pub(crate) fn next_request(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        self.now = now;
        if self.in_blackout(now) {
            return None;
        }
        // The active command's steps go back to back (the legacy force registers are written
        // with nothing in between).
        let active = if self.active.is_some() {
            self.active_request(now, core)
        } else {
            None
        };
        let fault_due = !self.fault_read_refused && now >= self.fault_check_at;
        // On a shared line every turn of this unit comes a round of the others' apart, so the
        // fault read would be due at each: after one, the next turn goes to whatever else is
        // due (slow data, limits first), the fault read only when nothing else is.
        let fault_first = fault_due && !(core.shared_line && self.fault_read_last);
        let next = if active.is_some() {
            active
        } else if fault_first {
            self.fault_check(now)
        } else if self.poll.in_cycle() {
            // A poll cycle split into parts finishes first.
            self.poll_part()
        } else {
            match self.next_turn(now, core) {
                None if fault_due => self.fault_check(now),
                next => next,
            }
        };
        self.fault_read_last = false;
        if let Some((purpose, request, _)) = &next
            && self.sees_fault(*purpose, request)
        {
            self.fault_check_at = now + FAULT_CHECK_INTERVAL;
            self.fault_read_last = true;
        }
        next
    }

    /// True when the answer to `request`, sent for `purpose`, updates the active fault: a
    /// poll or a check that reads the fault register, and the read that ends legacy settings
    /// (not a RAW read, whose answer goes to the CNC only).
    fn sees_fault(&self, purpose: MbPurpose, request: &MbRequest) -> bool {
        let updates = match purpose {
            MbPurpose::Poll(_) | MbPurpose::FaultCheck => true,
            MbPurpose::Active => matches!(
                self.active,
                Some(Active {
                    job: Job::Apply(_),
                    ..
                })
            ),
            _ => false,
        };
        updates && self.reads_fault(request)
    }

    /// The fault register is due: the poll reads it when its next read covers it (a poll due
    /// now starts first), otherwise the fault register is read alone. It goes before the
    /// turns and counts as the status's turn.
    fn fault_check(&mut self, now: Instant) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        self.served(Turn::Status);
        if !self.poll.in_cycle() && now >= self.next_poll_at {
            self.start_poll(now);
        }
        if let Some((request, part)) = self.poll.request()
            && self.reads_fault(&request)
        {
            return Some((MbPurpose::Poll(part), request, None));
        }
        let request = match self.variant {
            Variant::Sync => sync::read_fault(),
            Variant::Legacy => legacy::read_fault(),
        };
        Some((MbPurpose::FaultCheck, request, None))
    }

    /// True when `request` reads the register holding the active fault.
    fn reads_fault(&self, request: &MbRequest) -> bool {
        let fault = match self.variant {
            Variant::Sync => plasma_protocol::powermax::sync::ACTIVE_FAULT,
            Variant::Legacy => plasma_protocol::powermax::legacy::FAULT_CODE,
        };
        matches!(*request, MbRequest::ReadInput { start, quantity }
            if start <= fault && fault - start < quantity)
    }

    /// Round robin: of the kinds of work that are due (a poll, a new command, slow data or
    /// the cartridge check), the one served longest ago goes, so each waits for at most one
    /// turn of each other kind (and the fault checks): neither a short poll interval nor a
    /// stream of commands starves the rest.
    fn next_turn(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        for turn in self.turns {
            let next = match turn {
                Turn::Status if now >= self.next_poll_at => {
                    self.start_poll(now);
                    self.poll_part()
                }
                Turn::Status => None,
                Turn::Command => self.active_request(now, core),
                Turn::Other => self.other_request(now, core),
            };
            if next.is_some() {
                self.served(turn);
                return next;
            }
        }
        None
    }

    /// `turn` was served: it goes to the back of the line.
    fn served(&mut self, turn: Turn) {
        let [first, second, third] = self.turns;
        self.turns = if turn == first {
            [second, third, first]
        } else if turn == second {
            [first, third, second]
        } else {
            self.turns
        };
    }

    fn start_poll(&mut self, now: Instant) {
        self.poll.start();
        self.poll_started = now;
    }

    fn poll_part(&self) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        self.poll
            .request()
            .map(|(request, part)| (MbPurpose::Poll(part), request, None))
    }

    /// Slow data, the cartridge check, the slow-data refresh: whatever is due.
    fn other_request(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        self.slow.take_due_retries(now);
        if let Some(request) = self.slow_request() {
            return Some(request);
        }
        if self.variant == Variant::Sync
            && now >= self.next_uid_check_at
            && core.status.cartridge.is_some()
        {
            self.next_uid_check_at = now + UID_CHECK_INTERVAL;
            return Some((MbPurpose::UidCheck, sync::read_uid(), None));
        }
        if self.slow.refresh_due(now, core.config.slow_data_interval) {
            match self.variant {
                Variant::Sync => {
                    self.slow.request(SlowItem::ALL_ITEMS);
                    return self.slow_request();
                }
                Variant::Legacy => {
                    self.slow.request(SlowItem::LEGACY_ITEMS);
                    if self.wants_identify(core) {
                        return MbRequest::from_request(&device_id::read_product_code())
                            .map(|request| (MbPurpose::Identify, request, None));
                    }
                    return self.slow_request();
                }
            }
        }
        None
    }

    /// True while the unit runs as legacy only because the legacy register probe found it:
    /// device identification is asked again at each slow-data refresh (auto-detection only).
    fn wants_identify(&self, core: &Core) -> bool {
        self.variant == Variant::Legacy
            && !self.identify_refused
            && core.config.protocol == ProtocolChoice::Auto
            && core.status.model == Some(Model::PowermaxUnidentified)
    }

    fn slow_request(&mut self) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        let item = SlowItem::ALL
            .into_iter()
            .find(|item| self.slow.pending() & item.bit() != 0)?;
        if item == SlowItem::TorchLead {
            return Some((MbPurpose::Slow(item), legacy::read_torch_lead(), None));
        }
        match item.span() {
            Some(span) => Some((MbPurpose::Slow(item), sync::read(span), None)),
            None => {
                if !self.cartridge.in_cycle() {
                    self.cartridge.start();
                }
                self.cartridge
                    .request()
                    .map(|(request, part)| (MbPurpose::CartridgeBlock(part), request, None))
            }
        }
    }

    fn start_blackout(&mut self, now: Instant, core: &mut Core) {
        let until = now + QUICK_RESTART_BLACKOUT;
        self.blackout_until = Some(until);
        core.status.restart_blackout_until = Some(until);
        self.poll.abort();
        self.next_poll_at = until;
        // The restart may come with another cartridge: read its data again afterwards.
        if self.variant == Variant::Sync {
            self.slow.request(SlowItem::ALL_ITEMS);
        }
    }

    /// The link went down: every pending command fails.
    pub(crate) fn abort(&mut self, core: &mut Core) {
        let active = self.active.take().and_then(|active| active.ticket);
        core.fail_commands(active, &mut self.queue);
        self.slow.fail_all(core);
    }
}

#[cfg(test)]
mod tests;
