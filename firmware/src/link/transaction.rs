//! One request in flight: its encoded frame, its deadline, its attempts and its retry timing.
//!
//! A [`Transaction`] knows nothing about the protocol: the family driver encodes the request,
//! validates replies and tells the transaction how an attempt ended. The transaction decides
//! when the next attempt may go out and when to give up.
//!
//! # Retry spacing
//!
//! Modbus units answer within milliseconds and have no ignition noise to wait out, so a
//! Modbus retry goes out as soon as the failed attempt is over ([`RetrySpacing::Immediate`]).
//!
//! HPR and MaxPro200 units fire a high-frequency ignition that "can be active for up to
//! 1 second and can corrupt serial communications"; the manual asks for retries spaced so
//! that a 1 s interruption is survived. With [`RetrySpacing::RideThroughBlackout`] the
//! attempts follow a fixed schedule measured from the first transmission, so that the last
//! attempt is sent at least [`BLACKOUT_SPAN`] (1.25 s) after the first, whatever made the
//! earlier attempts fail (time-out, or an early corrupted reply):
//!
//! - with `r` retries and response time-out `T`, attempt `k` (0-based) is sent at
//!   `S_k = k*T + d_1 + ... + d_k` after the first;
//! - the waits share the budget `G = 1250 ms - r*T` (zero if negative) in doubling
//!   proportions, `d_j = ceil(G * 2^(j-1) / (2^r - 1))`, so an early retry catches a short
//!   glitch quickly while the last one lands clear of a full blackout;
//! - defaults (`r = 2`, `T = 100 ms`): `G = 1050 ms`, `d_1 = 350 ms`, `d_2 = 700 ms`; attempts
//!   at 0, 450 ms and 1250 ms. A blackout starting just as the first attempt goes out ends at
//!   1000 ms, 250 ms before the last attempt.

use heapless::Vec;
use plasma_protocol::modbus_ascii::ExceptionCode;

use plasma_protocol::time::{Duration, Instant, div_rem_u16};

/// Longest frame a transaction can hold: a Modbus ASCII frame is at most
/// 1 + 2 + 2 + 2x252 + 2 + 2 = 513 characters; HPR frames are far shorter.
pub const TX_CAPACITY: usize = 520;

/// Time from the first to the last attempt that [`RetrySpacing::RideThroughBlackout`]
/// guarantees: the manual's 1 s HF-ignition blackout plus a 0.25 s margin.
pub(crate) const BLACKOUT_SPAN: Duration = Duration::from_millis(1250);

/// Quiet time after HPR SLEEP (086), which no unit answers.
pub(crate) const SLEEP_QUIET: Duration = Duration::from_millis(20);

/// A request ready to become the transaction in flight, tagged with what it is for.
pub(crate) struct Outgoing<T> {
    pub(crate) tag: T,
    pub(crate) frame: Vec<u8, TX_CAPACITY>,
    pub(crate) retries: u8,
    pub(crate) spacing: RetrySpacing,
    /// Nothing answers it (HPR SLEEP): the line stays quiet for [`SLEEP_QUIET`] instead.
    pub(crate) no_reply: bool,
}

impl<T> Outgoing<T> {
    /// The same request with its tag turned into another by `f`.
    pub(crate) fn map_tag<U>(self, f: impl FnOnce(T) -> U) -> Outgoing<U> {
        Outgoing {
            tag: f(self.tag),
            frame: self.frame,
            retries: self.retries,
            spacing: self.spacing,
            no_reply: self.no_reply,
        }
    }
}

/// How a transaction (one request, all its attempts) failed, or why one attempt failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TransactionError {
    /// No complete reply before the response time-out.
    Timeout,
    /// A reply arrived with a wrong Modbus LRC or HPR checksum.
    BadChecksum,
    /// The Modbus unit answered with an exception.
    Exception(ExceptionCode),
    /// A well-formed reply that does not answer the request (address, function, count, echo,
    /// HPR id).
    Mismatch,
    /// HPR error reply 500: the unit saw a bad checksum in our request.
    HprBadChecksum500,
    /// HPR error reply 501: the unit does not know the command.
    HprUnknownCommand501,
    /// A reply whose framing or fields cannot be parsed.
    Malformed,
}

impl TransactionError {
    /// Whether another attempt can help: the request or the reply was lost or damaged.
    /// An exception or an unknown-command reply is the unit's definite answer.
    pub(crate) const fn is_retryable(&self) -> bool {
        !matches!(
            self,
            TransactionError::Exception(_) | TransactionError::HprUnknownCommand501
        )
    }
}

/// When a retry may follow a failed attempt (see the module docs for the arithmetic).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) enum RetrySpacing {
    /// Retry as soon as the failed attempt is over (Modbus).
    Immediate,
    /// Retry on a schedule spanning more than [`BLACKOUT_SPAN`] (HPR).
    RideThroughBlackout,
}

impl RetrySpacing {
    /// Offset from the first transmission at which attempt `attempt` (0-based) may be sent,
    /// given the response time-out and the number of retries configured.
    pub(crate) fn attempt_offset(self, attempt: u8, timeout: Duration, retries: u8) -> Duration {
        match self {
            RetrySpacing::Immediate => Duration::ZERO,
            RetrySpacing::RideThroughBlackout => {
                let retries = u32::from(retries.min(16));
                let attempt = u32::from(attempt).min(retries);
                let timeout_us = timeout.as_micros();
                let waits_us = timeout_us.saturating_mul(u64::from(retries));
                let budget_us = BLACKOUT_SPAN.as_micros().saturating_sub(waits_us);
                // Weights 1, 2, 4, ... sum to 2^r - 1; attempt k has used the first k of them.
                // (At most 16 retries: the total weight fits 16 bits, a cheap division.)
                let total_weight = ((1u32 << retries) - 1).max(1) as u16;
                let used_weight = (1u64 << attempt) - 1;
                let (whole, rest) =
                    div_rem_u16(budget_us.saturating_mul(used_weight), total_weight);
                let gaps_us = whole.saturating_add(u64::from(rest != 0)).min(budget_us);
                Duration::from_micros(
                    timeout_us
                        .saturating_mul(u64::from(attempt))
                        .saturating_add(gaps_us),
                )
            }
        }
    }
}

/// The frame was longer than [`TX_CAPACITY`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct FrameTooLong;

/// What happened to a transaction after a failed attempt or a time-out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) enum Outcome {
    /// Another attempt is scheduled.
    Retrying(TransactionError),
    /// No attempts left (or the error is final): the transaction failed.
    Failed(TransactionError),
    /// A request that expects no reply (HPR SLEEP) has been sent and the line is quiet again.
    Sent,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// The next attempt may be transmitted from `at` on.
    Ready { at: Instant },
    /// An attempt is on the wire; it fails at `deadline`.
    AwaitingReply { deadline: Instant },
}

/// One request with its retries. `T` is the driver's note of what was asked.
#[derive(Debug, Clone)]
pub(crate) struct Transaction<T> {
    tag: T,
    frame: Vec<u8, TX_CAPACITY>,
    timeout: Duration,
    retries: u8,
    spacing: RetrySpacing,
    expects_reply: bool,
    attempts_sent: u8,
    first_sent: Option<Instant>,
    last_sent: Option<Instant>,
    heard_reply: bool,
    phase: Phase,
}

impl<T> Transaction<T> {
    /// A request whose first attempt may go out from `ready_at` on.
    pub(crate) fn new(
        tag: T,
        frame: &[u8],
        ready_at: Instant,
        timeout: Duration,
        retries: u8,
        spacing: RetrySpacing,
    ) -> Result<Self, FrameTooLong> {
        let frame = Vec::from_slice(frame).map_err(|_| FrameTooLong)?;
        Ok(Transaction {
            tag,
            frame,
            timeout,
            retries,
            spacing,
            expects_reply: true,
            attempts_sent: 0,
            first_sent: None,
            last_sent: None,
            heard_reply: false,
            phase: Phase::Ready { at: ready_at },
        })
    }

    /// A request the unit never answers (HPR SLEEP, 086): sent once, then the line is
    /// left quiet for `quiet` before the transaction counts as done.
    pub(crate) fn without_reply(
        tag: T,
        frame: &[u8],
        ready_at: Instant,
        quiet: Duration,
    ) -> Result<Self, FrameTooLong> {
        let mut transaction = Self::new(tag, frame, ready_at, quiet, 0, RetrySpacing::Immediate)?;
        transaction.expects_reply = false;
        Ok(transaction)
    }

    /// The driver's note of what was asked.
    pub(crate) fn tag(&self) -> &T {
        &self.tag
    }

    /// The encoded request.
    pub(crate) fn frame(&self) -> &[u8] {
        &self.frame
    }

    /// Attempts transmitted so far.
    #[cfg(test)]
    pub(crate) fn attempts_sent(&self) -> u8 {
        self.attempts_sent
    }

    /// True when some attempt got a reply, even a damaged or unusable one: the unit is
    /// there (only silence, [`TransactionError::Timeout`], says otherwise).
    pub(crate) fn heard_reply(&self) -> bool {
        self.heard_reply
    }

    /// True while an attempt is on the wire and its reply is awaited.
    pub(crate) fn is_awaiting_reply(&self) -> bool {
        self.expects_reply && matches!(self.phase, Phase::AwaitingReply { .. })
    }

    /// True while an attempt is on the wire, whether its reply or only the quiet after it
    /// (a request without reply) is awaited.
    pub(crate) fn is_on_wire(&self) -> bool {
        matches!(self.phase, Phase::AwaitingReply { .. })
    }

    /// The next time this transaction needs attention: the send time or the deadline.
    pub(crate) fn poll_at(&self) -> Instant {
        match self.phase {
            Phase::Ready { at } => at,
            Phase::AwaitingReply { deadline } => deadline,
        }
    }

    /// The frame to transmit now, if an attempt is due.
    pub(crate) fn poll_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        match self.phase {
            Phase::Ready { at } if now >= at => {
                if self.first_sent.is_none() {
                    self.first_sent = Some(now);
                }
                self.attempts_sent = self.attempts_sent.saturating_add(1);
                self.last_sent = Some(now);
                self.phase = Phase::AwaitingReply {
                    deadline: now + self.timeout,
                };
                Some(&self.frame)
            }
            _ => None,
        }
    }

    /// The attempt's last stop bit left the wire at `at`: the reply time-out runs from there,
    /// so the frame's own transmission (10-25 ms of a 100 ms time-out at 19200 baud) does not
    /// eat into it. Never moves the deadline earlier; without this call it runs from the hand
    /// over ([`Transaction::poll_transmit`]).
    pub(crate) fn transmitted(&mut self, at: Instant) {
        if let Phase::AwaitingReply { deadline } = self.phase {
            self.phase = Phase::AwaitingReply {
                deadline: deadline.max(at + self.timeout),
            };
        }
    }

    /// Call when time passes; reports a time-out (and what follows) once the deadline is hit.
    pub(crate) fn handle_timeout(&mut self, now: Instant) -> Option<Outcome> {
        match self.phase {
            Phase::AwaitingReply { deadline } if now >= deadline => {
                if self.expects_reply {
                    Some(self.attempt_failed(now, TransactionError::Timeout))
                } else {
                    Some(Outcome::Sent)
                }
            }
            _ => None,
        }
    }

    /// The current attempt ended with a bad or unusable reply (or an error reply).
    /// Schedules a retry when the error allows it and attempts remain.
    pub(crate) fn attempt_failed(&mut self, now: Instant, error: TransactionError) -> Outcome {
        if error != TransactionError::Timeout {
            self.heard_reply = true;
        }
        let attempts_allowed = u16::from(self.retries) + 1;
        if !error.is_retryable() || u16::from(self.attempts_sent) >= attempts_allowed {
            return Outcome::Failed(error);
        }
        let first = self.first_sent.unwrap_or(now);
        let planned = first
            + self
                .spacing
                .attempt_offset(self.attempts_sent, self.timeout, self.retries);
        self.phase = Phase::Ready {
            at: if planned > now { planned } else { now },
        };
        Outcome::Retrying(error)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T100: Duration = Duration::from_millis(100);

    fn ms(v: u64) -> Instant {
        Instant::from_millis(v)
    }

    #[test]
    fn default_hpr_schedule_is_0_450_1250_ms() {
        let s = RetrySpacing::RideThroughBlackout;
        assert_eq!(s.attempt_offset(0, T100, 2), Duration::ZERO);
        assert_eq!(s.attempt_offset(1, T100, 2), Duration::from_millis(450));
        assert_eq!(s.attempt_offset(2, T100, 2), Duration::from_millis(1250));
    }

    #[test]
    fn hpr_schedule_spans_the_blackout_for_every_valid_setting() {
        for timeout_ms in [60u64, 100, 250, 600, 1000] {
            for retries in 1..=5u8 {
                let timeout = Duration::from_millis(timeout_ms);
                let s = RetrySpacing::RideThroughBlackout;
                let last = s.attempt_offset(retries, timeout, retries);
                assert!(last >= BLACKOUT_SPAN, "T={timeout_ms} r={retries}");
                // Offsets never shrink and each attempt waits at least its time-out.
                for k in 1..=retries {
                    let gap = s.attempt_offset(k, timeout, retries).as_micros()
                        - s.attempt_offset(k - 1, timeout, retries).as_micros();
                    assert!(gap >= timeout.as_micros());
                }
            }
        }
    }

    #[test]
    fn the_time_out_runs_from_the_end_of_transmission() {
        let mut t = Transaction::new((), b"abc", ms(0), T100, 2, RetrySpacing::Immediate).unwrap();
        assert!(t.poll_transmit(ms(0)).is_some());
        // The last stop bit leaves 20 ms later (a long frame at 19200 baud).
        t.transmitted(ms(20));
        assert_eq!(t.poll_at(), ms(120));
        assert_eq!(t.handle_timeout(ms(100)), None, "not from the hand-over");
        assert_eq!(t.handle_timeout(ms(119)), None);
        assert_eq!(
            t.handle_timeout(ms(120)),
            Some(Outcome::Retrying(TransactionError::Timeout))
        );
        // A report from before the hand-over never shortens the wait.
        assert!(t.poll_transmit(ms(120)).is_some());
        t.transmitted(ms(110));
        assert_eq!(t.poll_at(), ms(220));
    }

    #[test]
    fn modbus_timeouts_retry_immediately_then_fail() {
        let mut t = Transaction::new((), b"abc", ms(0), T100, 2, RetrySpacing::Immediate).unwrap();
        assert_eq!(t.poll_transmit(ms(0)), Some(&b"abc"[..]));
        assert_eq!(t.poll_transmit(ms(1)), None, "one attempt at a time");
        assert_eq!(t.poll_at(), ms(100));
        assert_eq!(t.handle_timeout(ms(99)), None);
        assert_eq!(
            t.handle_timeout(ms(100)),
            Some(Outcome::Retrying(TransactionError::Timeout))
        );
        assert!(t.poll_transmit(ms(100)).is_some());
        assert_eq!(
            t.handle_timeout(ms(200)),
            Some(Outcome::Retrying(TransactionError::Timeout))
        );
        assert!(t.poll_transmit(ms(200)).is_some());
        assert_eq!(
            t.handle_timeout(ms(300)),
            Some(Outcome::Failed(TransactionError::Timeout))
        );
        assert_eq!(t.attempts_sent(), 3);
    }

    #[test]
    fn hpr_retries_follow_the_schedule_even_after_early_bad_replies() {
        let mut t = Transaction::new(
            (),
            b">00090<",
            ms(0),
            T100,
            2,
            RetrySpacing::RideThroughBlackout,
        )
        .unwrap();
        assert!(t.poll_transmit(ms(10)).is_some());
        // A corrupted reply arrives after 5 ms: the retry still waits for its slot.
        assert_eq!(
            t.attempt_failed(ms(15), TransactionError::BadChecksum),
            Outcome::Retrying(TransactionError::BadChecksum)
        );
        assert_eq!(t.poll_at(), ms(460));
        assert!(t.poll_transmit(ms(459)).is_none());
        assert!(t.poll_transmit(ms(460)).is_some());
        assert_eq!(
            t.handle_timeout(ms(560)),
            Some(Outcome::Retrying(TransactionError::Timeout))
        );
        assert_eq!(t.poll_at(), ms(1260));
        assert!(t.poll_transmit(ms(1260)).is_some());
        assert_eq!(
            t.handle_timeout(ms(1360)),
            Some(Outcome::Failed(TransactionError::Timeout))
        );
    }

    #[test]
    fn final_answers_are_not_retried() {
        let mut t = Transaction::new((), b"x", ms(0), T100, 2, RetrySpacing::Immediate).unwrap();
        t.poll_transmit(ms(0));
        let exception = TransactionError::Exception(ExceptionCode::IllegalDataAddress);
        assert_eq!(
            t.attempt_failed(ms(5), exception),
            Outcome::Failed(exception)
        );
        let mut t = Transaction::new((), b"x", ms(0), T100, 2, RetrySpacing::Immediate).unwrap();
        t.poll_transmit(ms(0));
        assert_eq!(
            t.attempt_failed(ms(5), TransactionError::HprUnknownCommand501),
            Outcome::Failed(TransactionError::HprUnknownCommand501)
        );
    }

    #[test]
    fn requests_without_reply_complete_after_the_quiet_time() {
        let mut t =
            Transaction::without_reply((), b">0869E<", ms(0), Duration::from_millis(20)).unwrap();
        assert!(t.poll_transmit(ms(0)).is_some());
        assert!(!t.is_awaiting_reply());
        assert_eq!(t.handle_timeout(ms(19)), None);
        assert_eq!(t.handle_timeout(ms(20)), Some(Outcome::Sent));
    }

    #[test]
    fn oversized_frames_are_refused() {
        let big = [b'0'; TX_CAPACITY + 1];
        assert_eq!(
            Transaction::new((), &big, ms(0), T100, 2, RetrySpacing::Immediate).err(),
            Some(FrameTooLong)
        );
    }
}
