//! The HPR / MaxPro200 driver (`>ID data CK<`): polling GET_PS_INFO, the pilot-arc pause,
//! remote settings and the allow-listed commands.
//!
//! Manual rules kept here (section VII/VIII): one command at a time, each reply awaited
//! before the next (the transaction layer), no trailing CR/LF (frames come from the protocol
//! crate as `>...<` only), retries spaced over more than 1 s (the transaction layer), and
//! while the state is pilot arc "stop serial communications" for the length of an
//! HF-ignition burst, then ask GET_STATE only until the pilot arc is over.

//!
//! The driver's jobs are split by module: this one schedules (what goes out next: the
//! pilot-arc GET_STATE, the active command or a re-apply, polls and slow data in turn),
//! [`kept`] keeps the settings to re-apply, `reply` reads what the unit answers, and `submit`
//! checks a command against the manual's rules before it is queued.

mod confirm;
pub(crate) mod kept;
mod reply;
mod submit;

use heapless::{Deque, Vec};
use plasma_protocol::hpr::{self, Request, StateCode, SystemId};

use crate::link::core::Core;
use crate::link::event::{LinkEvent, ProcessFailure, Ticket};
use crate::link::slow::SlowData;
use crate::link::status::Family;
use plasma_protocol::time::{Duration, Instant};

use kept::KEPT_CAPACITY;

/// How long all traffic stops when the state is pilot arc: the manual's HF-ignition burst
/// ("can be active for up to 1 second").
pub(crate) const PILOT_ARC_PAUSE: Duration = Duration::from_secs(1);
/// Longest RAW HPR frame.
pub(crate) const RAW_HPR_CAPACITY: usize = hpr::MAX_FRAME_LEN;
const QUEUE_CAPACITY: usize = 4;

/// What is expected back.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum HprExpect {
    /// A typed request; its reply is parsed for it.
    Typed(Request),
    /// A RAW frame with this id; any reply echoing it (or 500/501) is forwarded.
    Raw(u16),
}

/// What an HPR transaction is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HprPurpose {
    /// GET_PS_INFO.
    Poll,
    /// 134 READ ERROR LOG (slow data).
    SlowErrorLog,
    /// 125 GET_TIMER_COUNTER (slow data).
    SlowTimers,
    /// 122 READ_GAS_SWITCH (slow data, manual gas console).
    SlowGases,
    /// 098 GET_INLET_GASES (slow data, automatic gas console).
    SlowInletGases,
    /// 001 VERSION (once after detection).
    SlowVersion,
    /// 145 READ TORCH ID (once after detection, MaxPro200).
    SlowTorch,
    /// 003 CURRENT_ERROR: the short fault read a poll on a shared line is, between full
    /// GET_PS_INFO polls.
    FaultPoll,
    /// 028 READ_PLASMA_AMPS after an HPR poll that shows the arc on (the MaxPro200 has no
    /// 028).
    PollAmps,
    /// GET_STATE while the pilot arc lasts.
    State,
    /// 004 REMOTE_MODE before the first setting.
    RemoteMode,
    /// The active command.
    Active,
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum HprJob {
    Typed(Request),
    Raw {
        id: u16,
        frame: Vec<u8, RAW_HPR_CAPACITY>,
    },
}

impl HprJob {
    /// Settings need remote mode (004) first.
    fn needs_remote(&self) -> bool {
        matches!(self, HprJob::Typed(request) if kept::sets(request) != 0)
    }
}

const SLOW_ERROR_LOG: u8 = 1;
const SLOW_TIMERS: u8 = 2;
/// A manual gas console's switch positions: 122 READ_GAS_SWITCH ("Manual Gas System" only,
/// line 252).
const SLOW_GASES: u8 = 4;
/// The inlet gases an automatic console uses: 098 GET_INLET_GASES (line 187). A manual
/// console's are its switches (122); a MaxPro200's 079 names them at every poll.
const SLOW_INLET_GASES: u8 = 8;
/// Read once after detection: 001 VERSION (every system, line 140).
const SLOW_VERSION: u8 = 16;
/// Read once after detection: 145 READ TORCH ID ("MaxPro200" only, line 290).
const SLOW_TORCH: u8 = 32;

/// The slow data of `system`, read at detection and at every refresh: an HPR's error log and
/// timers, and its console's gases (122 on a manual console, 098 on an automatic one); a
/// MaxPro200 has none.
fn slow_items(system: &SystemId) -> u8 {
    use hpr::command::id;
    if system.is_maxpro200() {
        0
    } else if hpr::accepts(id::READ_GAS_SWITCH, system) {
        SLOW_ERROR_LOG | SLOW_TIMERS | SLOW_GASES
    } else {
        SLOW_ERROR_LOG | SLOW_TIMERS | SLOW_INLET_GASES
    }
}

/// On a line shared with other units, one poll in this many is the full 079 GET_PS_INFO
/// (manual line 168; 52 ms of wire: 7 characters out, about 90 back); the others are the
/// short fault read 003 CURRENT_ERROR (line 142; 18 characters, `>00393<` and `>00301165B<`).
/// Eight, not four: the four-unit fault latency in the bus benchmark (docs/developers.md).
/// The arbiter lets one long attempt (a full poll or a slow-data read) out per round of
/// turns, so several units' full polls never add up in one round.
pub(crate) const SHARED_LINE_FULL_POLL_EVERY: u8 = 8;

/// What does not change while the unit is on the line, read once after detection where the
/// manual's "System" column names the system: firmware (001) and torch (145).
fn once_items(system: &SystemId) -> u8 {
    use hpr::command::id;
    let mut items = 0;
    if hpr::accepts(id::VERSION, system) {
        items |= SLOW_VERSION;
    }
    if hpr::accepts(id::READ_TORCH_ID, system) {
        items |= SLOW_TORCH;
    }
    items
}

/// Wait before re-applying kept settings again after a re-apply failed.
pub(crate) const REAPPLY_BACKOFF: Duration = Duration::from_secs(5);

/// The command being carried out.
#[derive(Debug, Clone, PartialEq, Eq)]
struct ActiveJob {
    /// `None` for a re-apply the link started itself.
    ticket: Option<Ticket>,
    job: HprJob,
    /// Sent again once after the unit did not take it (remote mode entered again first).
    retried: bool,
    /// The reads back of the setting done so far (`confirm`): 0 while the setting itself is
    /// out, then the index + 1 of the read that is out.
    reads_done: u8,
}

impl ActiveJob {
    fn new(ticket: Option<Ticket>, job: HprJob) -> Self {
        ActiveJob {
            ticket,
            job,
            retried: false,
            reads_done: 0,
        }
    }
}

/// Driver state for one detected HPR or MaxPro200.
#[derive(Debug, Clone)]
pub(crate) struct HprDriver {
    system: SystemId,
    next_poll_at: Instant,
    pause_until: Option<Instant>,
    slow: SlowData,
    queue: Deque<(Ticket, HprJob), QUEUE_CAPACITY>,
    active: Option<ActiveJob>,
    /// Kept settings still to re-apply in this re-apply run.
    reapply: Deque<Request, KEPT_CAPACITY>,
    /// Kept settings must be re-applied (from `reapply_not_before`, in state 2 or 3).
    reapply_pending: bool,
    reapply_not_before: Instant,
    /// The unit answered again with settings kept: its first poll tells a power cycle from a
    /// lost link before they are re-applied (see `kept`).
    returned: bool,
    /// The last transaction started was a poll (the next turn goes to due slow data).
    polled_last: bool,
    /// The poll's 028 READ_PLASMA_AMPS is still to send (HPR with the arc on only).
    amps_due: bool,
    /// Polls that may still be the short fault read before the next full one (on a shared
    /// line only: see [`SHARED_LINE_FULL_POLL_EVERY`]).
    fault_reads_left: u8,
    now: Instant,
}

/// True for the states in which the HF ignition may fire (HPR 5 PILOT ARC; MaxPro200
/// 6 IGNITE and 7 PILOT ARC).
fn is_pilot_arc(maxpro: bool, state: StateCode) -> bool {
    if maxpro {
        matches!(state.0, 6 | 7)
    } else {
        state.0 == 5
    }
}

/// True for the HPR states with the main arc on (6 TRANSFER to 10 FINAL RAMPDOWN), when the
/// output current is worth reading; in the others there is no main arc.
fn is_arc_on(state: StateCode) -> bool {
    (6..=10).contains(&state.0)
}

/// True for the states a unit is in right after power-up (HPR 0; MaxPro200 0 power up and
/// 1 initial checks).
fn is_power_up(maxpro: bool, state: StateCode) -> bool {
    if maxpro {
        matches!(state.0, 0 | 1)
    } else {
        state.0 == 0
    }
}

/// True while cutting (states 4-10 on both families: preflow to rampdown), when the manual
/// forbids gas changes, gas tests and resets.
fn is_cutting(state: Option<StateCode>) -> bool {
    state.is_some_and(|s| (4..=10).contains(&s.0))
}

impl HprDriver {
    /// A driver for a unit that answered HELLO with `system`.
    pub(crate) fn new(system: SystemId, now: Instant, core: &mut Core) -> Self {
        // Only a Powermax keeps a process: the persisted one is not for this unit.
        core.kept.restore_done();
        if !core.kept.hpr.is_empty() && core.kept.hpr.system() != Some(system) {
            // Another unit is on the line: the kept settings were meant for the one before.
            core.kept.hpr.clear();
            core.emit(LinkEvent::ProcessFailed {
                reason: ProcessFailure::OutsideLimits,
            });
        }
        HprDriver {
            system,
            next_poll_at: now,
            pause_until: None,
            slow: SlowData::new(
                slow_items(&system) | once_items(&system),
                now,
                core.config.slow_data_interval,
            ),
            queue: Deque::new(),
            active: None,
            reapply: Deque::new(),
            reapply_pending: false,
            reapply_not_before: now,
            returned: !core.kept.hpr.is_empty(),
            polled_last: false,
            amps_due: false,
            fault_reads_left: 0,
            now,
        }
    }

    fn maxpro(&self) -> bool {
        self.system == SystemId::MaxPro200
    }

    /// Family of the unit.
    pub(crate) fn family(&self) -> Family {
        if self.maxpro() {
            Family::MaxPro200
        } else {
            Family::Hpr
        }
    }

    fn max_amps(&self) -> u16 {
        match self.system {
            SystemId::Hpr { rating, .. } => rating.max_amps(),
            SystemId::MaxPro200 => hpr::MAX_MAXPRO_AMPS,
        }
    }

    fn in_pilot_arc(&self, core: &Core) -> bool {
        core.status
            .hpr
            .state
            .is_some_and(|s| is_pilot_arc(self.maxpro(), s))
    }

    /// The last transaction started was a poll.
    pub(crate) fn polled_last(&self) -> bool {
        self.polled_last
    }

    /// The end of the pilot-arc pause under way, if any: the HF ignition's quiet.
    pub(crate) fn quiet_until(&self, now: Instant) -> Option<Instant> {
        self.pause_until.filter(|&until| now < until)
    }

    /// Earliest time the driver wants to send something.
    pub(crate) fn wake_at(&self, core: &Core) -> Option<Instant> {
        if let Some(until) = self.pause_until.filter(|&u| self.now < u) {
            return Some(until);
        }
        if self.in_pilot_arc(core) {
            return Some(self.next_poll_at);
        }
        if self.active.is_some()
            || !self.queue.is_empty()
            || !self.reapply.is_empty()
            || self.slow.pending() != 0
        {
            return Some(self.now);
        }
        let mut at = self.next_poll_at.min(self.slow.wake_at());
        if self.reapply_pending && self.reapply_allowed(core) {
            at = at.min(self.reapply_not_before.max(self.now));
        }
        Some(at)
    }

    /// The next frame to send, if any, and what it is for.
    pub(crate) fn next_request(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(HprPurpose, HprExpect, Vec<u8, RAW_HPR_CAPACITY>)> {
        self.now = now;
        if self.pause_until.is_some_and(|until| now < until) {
            return None;
        }
        if self.in_pilot_arc(core) {
            // Only GET_STATE until the pilot arc is over.
            if now < self.next_poll_at {
                return None;
            }
            return typed(HprPurpose::State, Request::GetState);
        }
        if self.active.is_none() {
            self.next_job(now, core);
        }
        if let Some(ActiveJob {
            job, reads_done, ..
        }) = &self.active
        {
            if job.needs_remote() && !core.status.hpr.remote_accepted {
                return typed(HprPurpose::RemoteMode, Request::RemoteMode);
            }
            return match job {
                // The setting, then the reads that confirm it.
                HprJob::Typed(request) => {
                    let read = usize::from(*reads_done).checked_sub(1);
                    let out = read.and_then(|i| confirm::reads(request).get(i));
                    typed(HprPurpose::Active, *out.unwrap_or(request))
                }
                HprJob::Raw { id, frame } => {
                    Some((HprPurpose::Active, HprExpect::Raw(*id), frame.clone()))
                }
            };
        }
        if core::mem::take(&mut self.amps_due) {
            return typed(HprPurpose::PollAmps, Request::ReadPlasmaAmps);
        }
        // Round robin: after a poll, due slow data gets one transaction before the next
        // poll, so a short poll interval cannot starve it. On a shared line a due poll goes
        // first: the arbiter lets slow data follow a poll in the same turn, once a round.
        let poll_due = now >= self.next_poll_at;
        if poll_due && (!self.polled_last || core.shared_line) {
            return self.start_poll(now, core);
        }
        if let Some(request) = self.slow_request(now, core) {
            self.polled_last = false;
            return Some(request);
        }
        if poll_due {
            return self.start_poll(now, core);
        }
        None
    }

    /// States in which kept settings are re-applied: 2 (purge) and 3 (idle / ready), the
    /// states in which every settings command is accepted (137 and MaxPro 095 need them).
    fn reapply_allowed(&self, core: &Core) -> bool {
        core.status.hpr.state.is_some_and(|s| matches!(s.0, 2 | 3))
    }

    /// Pick the next job: the rest of a re-apply run (older settings first), a new re-apply
    /// run when due, or the next command.
    fn next_job(&mut self, now: Instant, core: &mut Core) {
        if self.reapply.is_empty()
            && self.reapply_pending
            && now >= self.reapply_not_before
            && self.reapply_allowed(core)
        {
            self.reapply_pending = false;
            for request in core.kept.hpr.as_slice() {
                let _ = self.reapply.push_back(*request);
            }
        }
        if let Some(request) = self.reapply.pop_front() {
            self.active = Some(ActiveJob::new(None, HprJob::Typed(request)));
            return;
        }
        self.active = self
            .queue
            .pop_front()
            .map(|(ticket, job)| ActiveJob::new(Some(ticket), job));
    }
    fn start_poll(
        &mut self,
        now: Instant,
        core: &Core,
    ) -> Option<(HprPurpose, HprExpect, Vec<u8, RAW_HPR_CAPACITY>)> {
        self.next_poll_at = now + core.config.poll_interval;
        self.polled_last = true;
        if self.fault_read_will_do(core) {
            self.fault_reads_left = self.fault_reads_left.saturating_sub(1);
            return typed(HprPurpose::FaultPoll, Request::CurrentError);
        }
        typed(HprPurpose::Poll, Request::GetPsInfo)
    }

    /// Whether this poll may be the short fault read: on a shared line, while START is off
    /// and the unit is not cutting, between full polls or while the line's arbiter holds a
    /// full one back (another unit's long attempt went out this round; a new driver's first
    /// full poll waits for it too, so that units detected together do not fill one round
    /// with full polls). From START on and while cutting (states 4-10) every poll is the
    /// full one: the state drives the pilot-arc pause, which the whole line keeps, and 028.
    fn fault_read_will_do(&self, core: &Core) -> bool {
        let state = core.status.hpr.state;
        core.shared_line
            && !core.start_on
            && !is_cutting(state)
            && (self.fault_reads_left > 0 || !core.long_allowed)
    }

    fn slow_request(
        &mut self,
        now: Instant,
        core: &Core,
    ) -> Option<(HprPurpose, HprExpect, Vec<u8, RAW_HPR_CAPACITY>)> {
        if !core.long_allowed {
            return None;
        }
        if self.slow.refresh_due(now, core.config.slow_data_interval) && !self.maxpro() {
            self.slow.request(slow_items(&self.system));
        }
        self.slow.take_due_retries(now);
        let pending = self.slow.pending();
        if pending & SLOW_VERSION != 0 {
            return typed(HprPurpose::SlowVersion, Request::Version);
        }
        if pending & SLOW_TORCH != 0 {
            return typed(HprPurpose::SlowTorch, Request::ReadTorchId);
        }
        if pending & SLOW_INLET_GASES != 0 {
            return typed(HprPurpose::SlowInletGases, Request::GetInletGases);
        }
        if pending & SLOW_GASES != 0 {
            return typed(HprPurpose::SlowGases, Request::ReadGasSwitch);
        }
        if pending & SLOW_ERROR_LOG != 0 {
            return typed(HprPurpose::SlowErrorLog, Request::ReadErrorLog);
        }
        if pending & SLOW_TIMERS != 0 {
            return typed(HprPurpose::SlowTimers, Request::GetTimerCounter);
        }
        None
    }
    /// The link went down: every pending command fails.
    pub(crate) fn abort(&mut self, core: &mut Core) {
        let active = self.active.take().and_then(|active| active.ticket);
        core.fail_commands(active, &mut self.queue);
        // Kept settings stay (in the core) and are re-applied when the unit is back.
        self.reapply.clear();
        self.slow.fail_all(core);
    }
}

fn typed(
    purpose: HprPurpose,
    request: Request,
) -> Option<(HprPurpose, HprExpect, Vec<u8, RAW_HPR_CAPACITY>)> {
    let frame = emit(&request)?;
    Some((purpose, HprExpect::Typed(request), frame))
}

/// The frame for `request`: `>ID data CK<`, nothing after `<`.
pub(crate) fn emit(request: &Request) -> Option<Vec<u8, RAW_HPR_CAPACITY>> {
    let mut buf = [0u8; hpr::MAX_FRAME_LEN];
    let len = request.emit(&mut buf).ok()?;
    Vec::from_slice(buf.get(..len)?).ok()
}

#[cfg(test)]
mod tests;
