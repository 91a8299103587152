//! The state every part of the link shares: the configuration, what is known about the unit,
//! the counters, the settings to re-apply and the event queue. The family drivers and
//! detection reach it as `&mut Core`; [`PsLink`](crate::link::PsLink) shows it read-only.

use crate::link::config::LinkConfig;
use crate::link::diagnostics::Diagnostics;
use crate::link::event::{CommandFailure, EventQueue, LinkEvent, Ticket};
use crate::link::kept::Kept;
use crate::link::status::{ActiveFault, UnitStatus};

/// State shared by the link and its family drivers.
#[derive(Debug)]
pub(crate) struct Core {
    /// The (validated) configuration.
    pub(crate) config: LinkConfig,
    /// What is known about the unit.
    pub(crate) status: UnitStatus,
    /// Counters.
    pub(crate) diagnostics: Diagnostics,
    /// What is re-applied, for every family (see [`kept`](crate::link::kept)).
    pub(crate) kept: Kept,
    /// The unit shares its line with others (set by the line's arbiter): an HPR's polls are
    /// mostly the short fault read (see `hpr::SHARED_LINE_FULL_POLL_EVERY`).
    pub(crate) shared_line: bool,
    /// On a shared line, the arbiter allows a long attempt in this turn (a full poll or slow
    /// data: no unit's went out in the last round); always true for a unit alone.
    pub(crate) long_allowed: bool,
    /// On a shared line, the unit's START is on (the bridge drives it): its state is polled
    /// in full every turn, so its pilot arc is seen and the line falls quiet for it.
    pub(crate) start_on: bool,
    events: EventQueue,
}

impl Core {
    /// The state of a link that knows nothing yet, configured with `config`.
    pub(crate) fn new(config: LinkConfig) -> Self {
        Core {
            config,
            status: UnitStatus::default(),
            diagnostics: Diagnostics::default(),
            kept: Kept::default(),
            shared_line: false,
            long_allowed: true,
            start_on: false,
            events: EventQueue::new(),
        }
    }

    /// Queue an event.
    pub(crate) fn emit(&mut self, event: LinkEvent) {
        self.events.push(event, &mut self.diagnostics);
    }

    /// The unit answered again without the settings the bridge gave it (see
    /// [`kept`](crate::link::kept), "Power cycle or lost link"): it is no longer in remote
    /// control, the CNC is told, and the kept settings are forgotten unless the configuration
    /// says to re-apply them. Returns true when they are to be re-applied.
    pub(crate) fn unit_power_cycled(&mut self) -> bool {
        if self.status.remote {
            self.status.remote = false;
            self.emit(LinkEvent::RemoteModeChanged { remote: false });
        }
        let reapply = self.config.reapply_after_power_cycle;
        self.emit(LinkEvent::UnitPowerCycled { reapply });
        if !reapply {
            self.kept.forget_powermax();
            self.kept.hpr.clear();
        }
        reapply
    }

    /// The oldest queued event, taken.
    pub(crate) fn pop_event(&mut self) -> Option<LinkEvent> {
        self.events.pop()
    }

    /// True while events are queued.
    pub(crate) fn has_events(&self) -> bool {
        !self.events.is_empty()
    }

    /// The link went down: the active command (`active`, when there is one) and every queued
    /// one fail.
    pub(crate) fn fail_commands<J, const N: usize>(
        &mut self,
        active: Option<Ticket>,
        queue: &mut heapless::Deque<(Ticket, J), N>,
    ) {
        let queued = core::iter::from_fn(|| queue.pop_front().map(|(ticket, _)| ticket));
        for ticket in active.into_iter().chain(queued) {
            self.emit(LinkEvent::CommandDone {
                ticket,
                result: Err(CommandFailure::LinkDown),
            });
        }
    }

    /// The unit's active fault is now `new`: a change is reported (the old fault cleared,
    /// the new one raised). False when nothing changed.
    pub(crate) fn set_active_fault(&mut self, new: Option<ActiveFault>) -> bool {
        if self.status.active_fault == new {
            return false;
        }
        if let Some(old) = self.status.active_fault {
            self.emit(LinkEvent::FaultCleared { code: old });
        }
        if let Some(fault) = new {
            self.emit(LinkEvent::FaultRaised {
                code: fault,
                action_required: fault.action_required(),
            });
        }
        self.status.active_fault = new;
        true
    }
}
