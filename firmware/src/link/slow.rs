//! Slow-data bookkeeping shared by the Powermax and HPR drivers: which items are still to be
//! read, the retry of items whose read failed on the line (with a doubling wait), the periodic
//! refresh, and the refresh commands waiting for the round to end.
//!
//! Items are bits of a `u8`; each driver gives them meaning (`SlowItem::bit` on Powermax,
//! error log and timers on HPR) and reads them in its own order.

use heapless::Vec;

use crate::link::command::Refusal;
use crate::link::core::Core;
use crate::link::event::{CommandFailure, CommandOutput, LinkEvent, Ticket};
use crate::link::transaction::TransactionError;
use plasma_protocol::time::{Duration, Instant};

/// First wait before a slow-data read that failed on the line is tried again (doubling with
/// each further failure, up to the slow-data interval).
pub(crate) const SLOW_RETRY_FIRST: Duration = Duration::from_millis(200);
/// Refresh commands that can wait for one round.
const TICKET_CAPACITY: usize = 4;

/// Slow-data state of one driver.
#[derive(Debug, Clone)]
pub(crate) struct SlowData {
    /// Items to read now.
    pending: u8,
    /// Items whose read failed on the line, read again from `retry_at`.
    retry: u8,
    retry_at: Instant,
    /// Wait before the next retry of failed items.
    backoff: Duration,
    /// The last failure of this round, reported to the waiting tickets.
    error: Option<TransactionError>,
    /// Refresh commands completed when no item is pending any more.
    tickets: Vec<Ticket, TICKET_CAPACITY>,
    next_refresh_at: Instant,
}

impl SlowData {
    /// `items` to read at once; the first refresh one `interval` after `now`.
    pub(crate) fn new(items: u8, now: Instant, interval: Duration) -> Self {
        SlowData {
            pending: items,
            retry: 0,
            retry_at: now,
            backoff: SLOW_RETRY_FIRST,
            error: None,
            tickets: Vec::new(),
            next_refresh_at: now + interval,
        }
    }

    /// Items to read now (call [`SlowData::take_due_retries`] first).
    pub(crate) fn pending(&self) -> u8 {
        self.pending
    }

    /// Read `items` (again).
    pub(crate) fn request(&mut self, items: u8) {
        self.pending |= items;
    }

    /// Read `items` for a refresh command: `ticket` completes when the round ends.
    pub(crate) fn request_for(&mut self, ticket: Ticket, items: u8) -> Result<(), Refusal> {
        self.tickets.push(ticket).map_err(|_| Refusal::QueueFull)?;
        self.request(items);
        Ok(())
    }

    /// When the next refresh or retry is due (pending items want the line at once: the
    /// caller checks [`SlowData::pending`] first).
    pub(crate) fn wake_at(&self) -> Instant {
        if self.retry != 0 {
            self.next_refresh_at.min(self.retry_at)
        } else {
            self.next_refresh_at
        }
    }

    /// Items whose retry is due become pending.
    pub(crate) fn take_due_retries(&mut self, now: Instant) {
        if self.retry != 0 && now >= self.retry_at {
            self.pending |= self.retry;
            self.retry = 0;
        }
    }

    /// True when the periodic refresh is due; the next one is planned `interval` later.
    pub(crate) fn refresh_due(&mut self, now: Instant, interval: Duration) -> bool {
        if now < self.next_refresh_at {
            return false;
        }
        self.next_refresh_at = now + interval;
        true
    }

    /// `item` is read (`error` = None) or failed for good. A failure on the line is read
    /// again soon: at the first turn after [`SLOW_RETRY_FIRST`], the wait doubling with each
    /// failure up to `interval`. A final answer (an exception, HPR 501) waits for the next
    /// refresh. When no item is pending any more, the waiting refresh commands complete
    /// (with the round's last failure, if any).
    pub(crate) fn finish(
        &mut self,
        now: Instant,
        item: u8,
        error: Option<TransactionError>,
        interval: Duration,
        core: &mut Core,
    ) {
        self.pending &= !item;
        match error {
            Some(e) => {
                if e.is_retryable() {
                    if self.retry == 0 {
                        self.retry_at = now + self.backoff;
                        self.backoff = (self.backoff + self.backoff).min(interval);
                    }
                    self.retry |= item;
                }
                self.error = error;
            }
            None => self.backoff = SLOW_RETRY_FIRST,
        }
        if self.pending == 0 {
            let result = match self.error.take() {
                None => Ok(CommandOutput::Done),
                Some(e) => Err(CommandFailure::Transaction(e)),
            };
            self.complete_tickets(result, core);
        }
    }

    /// The link went down: the waiting refresh commands fail.
    pub(crate) fn fail_all(&mut self, core: &mut Core) {
        self.complete_tickets(Err(CommandFailure::LinkDown), core);
    }

    fn complete_tickets(&mut self, result: Result<CommandOutput, CommandFailure>, core: &mut Core) {
        for &ticket in self.tickets.iter() {
            core.emit(LinkEvent::CommandDone { ticket, result });
        }
        self.tickets.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::config::LinkConfig;

    const INTERVAL: Duration = Duration::from_secs(1);

    fn core() -> Core {
        Core::new(LinkConfig::default())
    }

    fn at(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    #[test]
    fn a_line_failure_is_retried_with_a_doubling_wait_up_to_the_interval() {
        let mut core = core();
        let mut slow = SlowData::new(0b11, at(0), INTERVAL);
        slow.finish(
            at(0),
            0b01,
            Some(TransactionError::Timeout),
            INTERVAL,
            &mut core,
        );
        assert_eq!(slow.pending(), 0b10);
        assert_eq!(slow.wake_at(), at(200));
        // A second failure in the same round does not move the retry.
        slow.finish(
            at(10),
            0b10,
            Some(TransactionError::Timeout),
            INTERVAL,
            &mut core,
        );
        assert_eq!(slow.wake_at(), at(200));
        slow.take_due_retries(at(199));
        assert_eq!(slow.pending(), 0);
        slow.take_due_retries(at(200));
        assert_eq!(slow.pending(), 0b11);
        let mut waits = [0u64; 4];
        let mut now = 200;
        for wait in &mut waits {
            slow.finish(
                at(now),
                0b11,
                Some(TransactionError::Timeout),
                INTERVAL,
                &mut core,
            );
            // (The refresh may come first: `wake_at` shows the earlier of the two.)
            *wait = slow.retry_at.as_millis() - now;
            now += *wait;
            slow.take_due_retries(at(now));
        }
        assert_eq!(waits, [400, 800, 1000, 1000]);
        // A success starts again from the first wait.
        slow.finish(at(now), 0b11, None, INTERVAL, &mut core);
        slow.request(0b01);
        slow.finish(
            at(now),
            0b01,
            Some(TransactionError::Timeout),
            INTERVAL,
            &mut core,
        );
        assert_eq!(slow.retry_at, at(now + 200));
    }

    #[test]
    fn a_final_answer_waits_for_the_refresh() {
        let mut core = core();
        let mut slow = SlowData::new(0b01, at(0), INTERVAL);
        let refused = TransactionError::HprUnknownCommand501;
        slow.finish(at(5), 0b01, Some(refused), INTERVAL, &mut core);
        assert_eq!(slow.wake_at(), at(1000));
        slow.take_due_retries(at(999));
        assert_eq!(slow.pending(), 0);
        assert!(!slow.refresh_due(at(999), INTERVAL));
        assert!(slow.refresh_due(at(1000), INTERVAL));
        assert_eq!(slow.wake_at(), at(2000));
    }

    #[test]
    fn refresh_commands_complete_when_the_round_ends() {
        let mut core = core();
        let mut slow = SlowData::new(0, at(0), INTERVAL);
        slow.request_for(Ticket(1), 0b11).unwrap();
        slow.request_for(Ticket(2), 0b01).unwrap();
        slow.finish(
            at(1),
            0b01,
            Some(TransactionError::Timeout),
            INTERVAL,
            &mut core,
        );
        assert_eq!(core.pop_event(), None);
        slow.finish(at(2), 0b10, None, INTERVAL, &mut core);
        let failed = Err(CommandFailure::Transaction(TransactionError::Timeout));
        for ticket in [Ticket(1), Ticket(2)] {
            let done = LinkEvent::CommandDone {
                ticket,
                result: failed,
            };
            assert_eq!(core.pop_event(), Some(done));
        }
        assert_eq!(core.pop_event(), None);
        // The next round starts without the old error.
        slow.request_for(Ticket(3), 0b10).unwrap();
        slow.finish(at(3), 0b10, None, INTERVAL, &mut core);
        let done = LinkEvent::CommandDone {
            ticket: Ticket(3),
            result: Ok(CommandOutput::Done),
        };
        assert_eq!(core.pop_event(), Some(done));
    }

    #[test]
    fn waiting_commands_fail_on_link_down_and_a_full_list_is_refused() {
        let mut core = core();
        let mut slow = SlowData::new(0, at(0), INTERVAL);
        for n in 0..4 {
            slow.request_for(Ticket(n), 0b01).unwrap();
        }
        assert_eq!(slow.request_for(Ticket(9), 0b10), Err(Refusal::QueueFull));
        // The refused command asked for nothing.
        assert_eq!(slow.pending(), 0b01);
        slow.fail_all(&mut core);
        for n in 0..4 {
            let done = LinkEvent::CommandDone {
                ticket: Ticket(n),
                result: Err(CommandFailure::LinkDown),
            };
            assert_eq!(core.pop_event(), Some(done));
        }
        assert_eq!(core.pop_event(), None);
    }
}
