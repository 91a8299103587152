//! What the link tells the rest of the bridge, and the answers to its commands.

use heapless::Deque;
use plasma_protocol::hpr::{ErrorCode, StateCode};
use plasma_protocol::powermax::{FaultCode, Psi};

use crate::link::command::Refusal;
use crate::link::diagnostics::Diagnostics;
use crate::link::status::{ActiveFault, Family, Model, PowermaxProcess};
use crate::link::transaction::TransactionError;

/// Identifies one submitted [`LinkCommand`](crate::link::LinkCommand); returned by `submit` and
/// repeated in its [`LinkEvent::CommandDone`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ticket(pub u32);

/// Why the link went down.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkDownReason {
    /// This many transactions in a row failed; the last one with `last_error`.
    ConsecutiveFailures {
        /// Failed transactions in a row.
        count: u8,
        /// How the last one failed.
        last_error: TransactionError,
    },
    /// The configuration was changed by the caller (re-detection follows).
    Reconfigured,
}

/// Why settings could not be applied (also after a power cycle).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ProcessFailure {
    /// The write (or the read-back) failed on the line.
    Transaction(TransactionError),
    /// The unit took the write but reads back other values.
    ReadBackDiffers {
        /// What was written.
        written: PowermaxProcess,
        /// What the unit reports.
        read_back: PowermaxProcess,
    },
    /// The unit reports a 0-11-n fault (setting not permitted) after the write.
    RejectedByUnit {
        /// The fault it shows.
        fault: FaultCode,
    },
    /// The desired settings no longer fit the unit's permitted limits (e.g. after a
    /// cartridge change); they were not sent.
    OutsideLimits,
    /// An HPR / MaxPro200 unit answered "not accepted".
    NotAccepted,
}

/// The successful answer to a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandOutput {
    /// The command was carried out and acknowledged.
    Done,
    /// Settings written and confirmed; the values read back (legacy units: as written and
    /// free of 0-11-n faults).
    Process(PowermaxProcess),
    /// A numeric answer (HPR: amps actually set, corner-current percent achieved).
    Value(u16),
    /// HPR error log, most recent first.
    ErrorLog([ErrorCode; 4]),
    /// A Powermax's actual gas pressure.
    Pressure(Psi),
    /// An HPR's measured cutflow pressures (079) or a MaxPro200's measured pressures (141),
    /// psi.
    HprPressures {
        /// Plasma (`PC`, `plap`).
        plasma: u16,
        /// Shield (`SC`, `shap`).
        shield: u16,
    },
    /// A RAW command's reply: `len` bytes, available from `PsLink::raw_reply` until the next
    /// RAW command completes.
    Raw {
        /// Length of the reply frame.
        len: usize,
    },
}

/// Why a command failed after it was accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CommandFailure {
    /// The request failed on the line (after its retries).
    Transaction(TransactionError),
    /// Settings were not confirmed.
    Process(ProcessFailure),
    /// An HPR unit answered "not accepted" (0) or "invalid" (2).
    NotAccepted,
    /// The link went down before the command completed.
    LinkDown,
}

/// What the link reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkEvent {
    /// A unit was found and answers.
    LinkUp {
        /// Which unit.
        model: Model,
        /// Which protocol family.
        family: Family,
    },
    /// The unit stopped answering; auto-detection runs again.
    LinkDown {
        /// Why.
        reason: LinkDownReason,
    },
    /// A fault (Powermax) or error (HPR) became active.
    FaultRaised {
        /// The fault.
        code: ActiveFault,
        /// True when the manual says someone must act before cutting can go on.
        action_required: bool,
    },
    /// The active fault went away (or was replaced: a `FaultRaised` follows).
    FaultCleared {
        /// The fault that cleared.
        code: ActiveFault,
    },
    /// Settings were written and confirmed (after a command or a re-apply).
    ProcessApplied {
        /// The settings as confirmed.
        settings: PowermaxProcess,
        /// True when this re-applied kept settings after a power cycle or link return.
        reapplied: bool,
    },
    /// Settings could not be applied.
    ProcessFailed {
        /// Why.
        reason: ProcessFailure,
    },
    /// The persisted process ([`PsLink::restore`](crate::link::PsLink::restore)) was refused before
    /// sending (outside the unit's limits); it is dropped.
    RestoreRefused {
        /// Why.
        refusal: Refusal,
    },
    /// A different cartridge is installed (SYNC), new UID attached.
    CartridgeChanged {
        /// The new cartridge's UID (16 ASCII characters; zeros when the unit cannot read it).
        uid: [u8; 16],
    },
    /// The HPR / MaxPro200 state changed.
    StateChanged {
        /// Previous state, if known.
        from: Option<StateCode>,
        /// New state.
        to: StateCode,
    },
    /// The unit answered again without the settings the bridge gave it: it was switched off
    /// and on (see `kept`'s "Power cycle or lost link"), and left remote control.
    UnitPowerCycled {
        /// True when the kept settings are applied again
        /// ([`LinkConfig::reapply_after_power_cycle`](crate::link::LinkConfig)); otherwise they
        /// are forgotten until the CNC sets them again.
        reapply: bool,
    },
    /// The unit entered or left remote control.
    RemoteModeChanged {
        /// True in remote control.
        remote: bool,
    },
    /// A submitted command finished.
    CommandDone {
        /// The command's ticket.
        ticket: Ticket,
        /// What came of it.
        result: Result<CommandOutput, CommandFailure>,
    },
}

impl LinkEvent {
    /// Events the bridge must not lose (safety and command completion). Others may be
    /// dropped, oldest first, when the queue is full.
    pub const fn is_critical(&self) -> bool {
        matches!(
            self,
            LinkEvent::LinkUp { .. }
                | LinkEvent::LinkDown { .. }
                | LinkEvent::FaultRaised { .. }
                | LinkEvent::FaultCleared { .. }
                | LinkEvent::ProcessFailed { .. }
                | LinkEvent::RestoreRefused { .. }
                | LinkEvent::CommandDone { .. }
        )
    }
}

/// Capacity of the event queue.
pub(crate) const EVENT_CAPACITY: usize = 16;

/// Bounded event queue. When full, the oldest non-critical event makes room (or, if every
/// queued event is critical, the oldest one); each drop is counted in the diagnostics.
#[derive(Debug, Default)]
pub(crate) struct EventQueue {
    events: Deque<LinkEvent, EVENT_CAPACITY>,
}

impl EventQueue {
    /// An empty queue.
    pub(crate) const fn new() -> Self {
        EventQueue {
            events: Deque::new(),
        }
    }

    /// Queue `event`, making room if needed.
    pub(crate) fn push(&mut self, event: LinkEvent, diagnostics: &mut Diagnostics) {
        if self.events.is_full() {
            self.drop_one();
            diagnostics.record_event_dropped();
        }
        // Cannot fail: room was made above.
        let _ = self.events.push_back(event);
    }

    fn drop_one(&mut self) {
        let len = self.events.len();
        let victim = self
            .events
            .iter()
            .position(|e| !e.is_critical())
            .unwrap_or(0);
        // Rotate the victim to the front, drop it, and restore the order of the rest.
        for _ in 0..victim {
            if let Some(e) = self.events.pop_front() {
                let _ = self.events.push_back(e);
            }
        }
        self.events.pop_front();
        for _ in 0..len.saturating_sub(1).saturating_sub(victim) {
            if let Some(e) = self.events.pop_front() {
                let _ = self.events.push_back(e);
            }
        }
    }

    /// Oldest event.
    pub(crate) fn pop(&mut self) -> Option<LinkEvent> {
        self.events.pop_front()
    }

    /// True when no event is queued.
    pub(crate) fn is_empty(&self) -> bool {
        self.events.is_empty()
    }

    /// Number of queued events.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.events.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_queue_drops_the_oldest_non_critical_event_and_counts_it() {
        let mut d = Diagnostics::default();
        let mut q = EventQueue::new();
        q.push(
            LinkEvent::CommandDone {
                ticket: Ticket(0),
                result: Ok(CommandOutput::Done),
            },
            &mut d,
        );
        q.push(LinkEvent::RemoteModeChanged { remote: true }, &mut d);
        for i in 1..(EVENT_CAPACITY as u32 - 1) {
            q.push(
                LinkEvent::CommandDone {
                    ticket: Ticket(i),
                    result: Ok(CommandOutput::Done),
                },
                &mut d,
            );
        }
        assert_eq!(q.len(), EVENT_CAPACITY);
        q.push(
            LinkEvent::CommandDone {
                ticket: Ticket(99),
                result: Ok(CommandOutput::Done),
            },
            &mut d,
        );
        assert_eq!(d.events_dropped, 1);
        let mut tickets = heapless::Vec::<u32, EVENT_CAPACITY>::new();
        while let Some(e) = q.pop() {
            match e {
                LinkEvent::CommandDone { ticket, .. } => tickets.push(ticket.0).unwrap(),
                other => panic!("non-critical event kept: {other:?}"),
            }
        }
        let mut expected: heapless::Vec<u32, EVENT_CAPACITY> =
            (0..(EVENT_CAPACITY as u32 - 1)).collect();
        expected.push(99).unwrap();
        assert_eq!(tickets, expected, "order is kept");
    }

    #[test]
    fn when_all_are_critical_the_oldest_goes() {
        let mut d = Diagnostics::default();
        let mut q = EventQueue::new();
        for i in 0..=(EVENT_CAPACITY as u32) {
            q.push(
                LinkEvent::CommandDone {
                    ticket: Ticket(i),
                    result: Ok(CommandOutput::Done),
                },
                &mut d,
            );
        }
        assert_eq!(d.events_dropped, 1);
        assert!(matches!(
            q.pop(),
            Some(LinkEvent::CommandDone {
                ticket: Ticket(1),
                ..
            })
        ));
    }
}
