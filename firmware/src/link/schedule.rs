//! Scheduling and transaction bookkeeping.
//!
//! Owns the one transaction in flight: which request goes out next (a detection probe or
//! the family driver's choice), its time-outs and retries, and what its end means for the
//! link. Only silence counts toward link-down; damaged replies count toward the
//! [`UNANSWERED_FACTOR`] limit only, and an answer of any kind (even an exception) shows the
//! unit is there.

use heapless::Vec;
use plasma_protocol::time::Instant;

use crate::link::detect::{DetectExpect, DetectStep};
use crate::link::hpr::{HprExpect, HprPurpose};
use crate::link::powermax::MbPurpose;
use crate::link::powermax::modbus::MbRequest;
use crate::link::transaction::{
    Outcome, Outgoing, RetrySpacing, SLEEP_QUIET, TX_CAPACITY, Transaction, TransactionError,
};
use crate::link::{Phase, PsLink};

/// A unit that answers, but only with damaged replies, is declared down after this many
/// times [`LinkConfig::failures_before_down`](crate::link::LinkConfig::failures_before_down) failed
/// transactions in a row (a line too noisy to carry a single valid reply is no link, but a
/// damaged reply is no silence either).
pub(crate) const UNANSWERED_FACTOR: u8 = 4;

/// What a transaction is for: the probe or driver purpose, and what its reply must answer.
#[derive(Debug, Clone)]
pub(super) enum Tag {
    Detect(DetectStep, DetectExpect),
    Modbus(MbPurpose, MbRequest),
    Hpr(HprPurpose, HprExpect),
}

impl PsLink {
    /// Start the next transaction, if anything is due.
    pub(super) fn start_next(&mut self, now: Instant) {
        let next = match self.phase {
            Phase::Detecting(_) => self
                .next_probe(now)
                .map(|probe| probe.map_tag(|(step, expect)| Tag::Detect(step, expect))),
            Phase::Powermax(_) => self.next_powermax_request(now),
            Phase::Hpr(_) => self.next_hpr_request(now),
        };
        let Some(next) = next else {
            return;
        };
        self.txn = if next.no_reply {
            Transaction::without_reply(next.tag, &next.frame, now, SLEEP_QUIET).ok()
        } else {
            let timeout = self.core.config.response_timeout;
            Transaction::new(
                next.tag,
                &next.frame,
                now,
                timeout,
                next.retries,
                next.spacing,
            )
            .ok()
        };
    }

    /// The Powermax driver's next request, encoded for the configured node.
    fn next_powermax_request(&mut self, now: Instant) -> Option<Outgoing<Tag>> {
        let Phase::Powermax(driver) = &mut self.phase else {
            return None;
        };
        let (purpose, request, retries) = driver.next_request(now, &mut self.core)?;
        let config = self.core.config;
        let mut buf = [0u8; TX_CAPACITY];
        let frame = request
            .encode(config.node_address, &mut buf)
            .ok()
            .and_then(|len| buf.get(..len))
            .and_then(|b| Vec::from_slice(b).ok())?;
        Some(Outgoing {
            tag: Tag::Modbus(purpose, request),
            frame,
            retries: retries.unwrap_or(config.retries),
            spacing: RetrySpacing::Immediate,
            no_reply: false,
        })
    }

    /// The HPR driver's next request; its retries ride through an HF-ignition blackout.
    fn next_hpr_request(&mut self, now: Instant) -> Option<Outgoing<Tag>> {
        let Phase::Hpr(driver) = &mut self.phase else {
            return None;
        };
        let (purpose, expect, frame) = driver.next_request(now, &mut self.core)?;
        let frame = Vec::from_slice(&frame).ok()?;
        Some(Outgoing {
            tag: Tag::Hpr(purpose, expect),
            frame,
            retries: self.core.config.retries,
            spacing: RetrySpacing::RideThroughBlackout,
            no_reply: false,
        })
    }

    /// The frame handed out last has left the wire (its last stop bit) at `at`: its reply
    /// time-out starts there (`Transaction::transmitted`). The board's runner reports it after
    /// the UART's flush; the host harness from its line model.
    pub fn handle_transmitted(&mut self, at: Instant) {
        if let Some(txn) = self.txn.as_mut() {
            txn.transmitted(at);
        }
    }

    /// The transaction in flight timed out (an attempt, or the quiet after a request nothing
    /// answers).
    pub(super) fn handle_timeout(&mut self, now: Instant) {
        let Some(txn) = self.txn.as_mut() else {
            return;
        };
        match txn.handle_timeout(now) {
            None => {}
            Some(Outcome::Retrying(error)) => {
                self.core.diagnostics.record_error(error);
                self.core.diagnostics.record_retry();
            }
            Some(Outcome::Failed(error)) => {
                self.core.diagnostics.record_error(error);
                self.transaction_failed(now, error);
            }
            Some(Outcome::Sent) => {
                let tag = self.txn.take().map(|t| t.tag().clone());
                if let Some(Tag::Detect(step, _)) = tag {
                    self.detect_next(now, step);
                }
            }
        }
    }

    /// One attempt failed with `error` (a reply arrived but is unusable).
    pub(super) fn attempt_failed(&mut self, now: Instant, error: TransactionError) {
        self.core.diagnostics.record_error(error);
        let Some(txn) = self.txn.as_mut() else {
            return;
        };
        match txn.attempt_failed(now, error) {
            Outcome::Retrying(_) => self.core.diagnostics.record_retry(),
            Outcome::Failed(error) => self.transaction_failed(now, error),
            Outcome::Sent => {}
        }
    }

    /// The unit refused the request (a Modbus exception, HPR 501): counted, and the
    /// transaction ends when the error is final (no retry is counted).
    pub(super) fn attempt_refused(&mut self, now: Instant, error: TransactionError) {
        self.core.diagnostics.record_error(error);
        if let Some(txn) = self.txn.as_mut()
            && let Outcome::Failed(error) = txn.attempt_failed(now, error)
        {
            self.transaction_failed(now, error);
        }
    }

    /// The transaction in flight failed for good.
    fn transaction_failed(&mut self, now: Instant, error: TransactionError) {
        let Some(txn) = self.txn.take() else {
            return;
        };
        self.core.diagnostics.record_failed();
        let heard_reply = txn.heard_reply();
        let tag = txn.tag().clone();
        self.count_failure(&tag, error, heard_reply);
        match tag {
            Tag::Detect(step, _) => self.probe_failed(now, step, error, heard_reply),
            Tag::Modbus(purpose, _) => {
                if let Phase::Powermax(driver) = &mut self.phase {
                    driver.on_failed(now, purpose, error, &mut self.core);
                }
            }
            Tag::Hpr(purpose, _) => {
                if let Phase::Hpr(driver) = &mut self.phase {
                    driver.on_failed(now, purpose, error, &mut self.core);
                }
            }
        }
        self.check_link_down(now, error);
    }

    /// Count a failed transaction toward link-down: silence toward both limits, damaged
    /// replies toward the unanswered one only; an answer (exception, unknown command) resets
    /// both.
    fn count_failure(&mut self, tag: &Tag, error: TransactionError, heard_reply: bool) {
        if matches!(tag, Tag::Modbus(MbPurpose::Identify, _)) {
            // Optional: a unit without device identification may stay silent to it.
        } else if !error.is_retryable() {
            // The unit answered (exception, unknown command): it is there.
            self.consecutive_failures = 0;
            self.unanswered = 0;
        } else if heard_reply {
            // Damaged replies: the unit is there, the line is noisy. Not silence.
            self.consecutive_failures = 0;
            self.unanswered = self.unanswered.saturating_add(1);
        } else {
            self.consecutive_failures = self.consecutive_failures.saturating_add(1);
            self.unanswered = self.unanswered.saturating_add(1);
        }
    }

    /// Take the link down when either failure count reached its limit.
    fn check_link_down(&mut self, now: Instant, error: TransactionError) {
        let down = self.core.config.failures_before_down;
        if self.consecutive_failures >= down {
            self.link_down(now, self.consecutive_failures, error);
        } else if self.unanswered >= down.saturating_mul(UNANSWERED_FACTOR) {
            self.link_down(now, self.unanswered, error);
        }
    }

    /// The transaction in flight succeeded: its tag, to dispatch the reply.
    pub(super) fn transaction_ok(&mut self) -> Option<Tag> {
        let txn = self.txn.take()?;
        self.core.diagnostics.record_ok();
        self.consecutive_failures = 0;
        self.unanswered = 0;
        Some(txn.tag().clone())
    }
}

#[cfg(test)]
mod tests;
