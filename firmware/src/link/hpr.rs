//! The HPR / MaxPro200 driver (`>ID data CK<`): polling GET_PS_INFO, the pilot-arc pause,
//! remote settings and the allow-listed commands.
//!
//! Manual rules kept here (section VII/VIII): one command at a time, each reply awaited
//! before the next (the transaction layer), no trailing CR/LF (frames come from the protocol
//! crate as `>...<` only), retries spaced over more than 1 s (the transaction layer), and
//! while the state is pilot arc "stop serial communications" for the length of an
//! HF-ignition burst, then ask GET_STATE only until the pilot arc is over.

use heapless::{Deque, Vec};
use plasma_protocol::hpr::command::id;
use plasma_protocol::hpr::{
    self, Acceptance, ErrorCode, Frame, GasCode, GasFlows, GasPair, Reply, Request, StateCode,
    SystemId,
};

use super::Core;
use super::command::{HprGasFlow, HprValue, LinkCommand, Refusal};
use super::event::{CommandFailure, CommandOutput, LinkEvent, SettingsFailure, Ticket};
use super::slow::SlowData;
use super::status::{ActiveFault, Family};
use super::transaction::TransactionError;
use plasma_protocol::time::{Duration, Instant};

/// How long all traffic stops when the state is pilot arc: the manual's HF-ignition burst
/// ("can be active for up to 1 second").
pub const PILOT_ARC_PAUSE: Duration = Duration::from_secs(1);
/// Longest RAW HPR frame.
pub const RAW_HPR_CAPACITY: usize = hpr::MAX_FRAME_LEN;
const QUEUE_CAPACITY: usize = 4;

/// What is expected back.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HprExpect {
    /// A typed request; its reply is parsed for it.
    Typed(Request),
    /// A RAW frame with this id; any reply echoing it (or 500/501) is forwarded.
    Raw(u16),
}

/// What an HPR transaction is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HprPurpose {
    /// GET_PS_INFO.
    Poll,
    /// GET_STATE while the pilot arc lasts.
    State,
    /// 004 REMOTE_MODE before the first setting.
    RemoteMode,
    /// 134 READ ERROR LOG (slow data).
    SlowErrorLog,
    /// 125 GET_TIMER_COUNTER (slow data).
    SlowTimers,
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
    fn needs_remote(&self) -> bool {
        matches!(
            self,
            HprJob::Typed(
                Request::SetNominalAmps { .. }
                    | Request::SetProcess { .. }
                    | Request::SetAllParameters(_)
                    | Request::SetAllParametersMaxPro200(_)
                    | Request::SetInletGases(_)
                    | Request::SetCornerCurrent { .. }
            )
        )
    }
}

const SLOW_ERROR_LOG: u8 = 1;
const SLOW_TIMERS: u8 = 2;
const SLOW_ALL: u8 = SLOW_ERROR_LOG | SLOW_TIMERS;

/// Wait before re-applying kept settings again after a re-apply failed.
pub const REAPPLY_BACKOFF: Duration = Duration::from_secs(5);
/// Kept settings requests (one per kind at most: see [`HprKept::keep`]).
pub const KEPT_CAPACITY: usize = 6;

/// What a settings request sets (bits), to tell which earlier requests a new one replaces.
const SETS_AMPS: u8 = 1;
const SETS_CORNER: u8 = 2;
const SETS_GASES: u8 = 4;
const SETS_FLOWS: u8 = 8;
const SETS_PRESSURES: u8 = 16;

/// What `request` sets; 0 for a request that is no setting.
fn sets(request: &Request) -> u8 {
    match request {
        Request::SetNominalAmps { .. } => SETS_AMPS,
        Request::SetCornerCurrent { .. } => SETS_CORNER,
        Request::SetInletGases(_) => SETS_GASES,
        Request::SetProcess { .. } => SETS_AMPS | SETS_GASES,
        Request::SetAllParameters(_) => SETS_AMPS | SETS_CORNER | SETS_GASES | SETS_FLOWS,
        Request::SetAllParametersMaxPro200(_) => SETS_AMPS | SETS_GASES | SETS_PRESSURES,
        _ => 0,
    }
}

/// The nominal current `request` sets, if it sets one.
fn amps_of(request: &Request) -> Option<u16> {
    match request {
        Request::SetNominalAmps { amps } | Request::SetProcess { amps, .. } => Some(*amps),
        Request::SetAllParameters(p) => Some(p.amps),
        Request::SetAllParametersMaxPro200(p) => Some(p.amps),
        _ => None,
    }
}

/// The HPR / MaxPro200 settings the CNC asked for and the unit confirmed, oldest first. They
/// are kept across link-downs and re-applied (after 004 REMOTE_MODE) when the unit returns or
/// shows that it restarted, like the Powermax settings.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct HprKept {
    requests: Vec<Request, KEPT_CAPACITY>,
    /// The unit that confirmed them (another unit does not get them).
    system: Option<SystemId>,
}

impl HprKept {
    /// The kept requests, in the order they are re-applied.
    pub fn as_slice(&self) -> &[Request] {
        &self.requests
    }

    /// True when nothing is kept.
    pub fn is_empty(&self) -> bool {
        self.requests.is_empty()
    }

    /// The unit that confirmed the kept settings.
    pub fn system(&self) -> Option<SystemId> {
        self.system
    }

    /// Keep `request` (a setting `system` confirmed); earlier requests whose every setting
    /// it sets again are dropped, and so is everything another unit confirmed.
    pub fn keep(&mut self, system: SystemId, request: Request) {
        let new = sets(&request);
        if new == 0 {
            return;
        }
        if self.system != Some(system) {
            self.clear();
            self.system = Some(system);
        }
        self.requests.retain(|old| sets(old) & !new != 0);
        if self.requests.is_full() {
            // Drop the oldest. Rebuilt rather than `Vec::remove`, whose overlapping move is
            // the image's only other use of memmove (1.5 KB of flash), and pushed rather than
            // collected (`collect` carries a capacity panic that cannot happen here).
            let mut newer = Vec::new();
            for request in self.requests.iter().skip(1) {
                let _ = newer.push(*request);
            }
            self.requests = newer;
        }
        let _ = self.requests.push(request);
    }

    /// Forget everything kept.
    pub fn clear(&mut self) {
        self.requests.clear();
        self.system = None;
    }

    /// The nominal current the kept settings give, if they set one.
    pub fn amps(&self) -> Option<u16> {
        self.requests.iter().rev().find_map(amps_of)
    }
}

/// The command being carried out.
#[derive(Debug, Clone, PartialEq, Eq)]
struct ActiveJob {
    /// `None` for a re-apply the link started itself.
    ticket: Option<Ticket>,
    job: HprJob,
    /// Sent again once after the unit did not take it (remote mode entered again first).
    retried: bool,
}

/// Driver state for one detected HPR or MaxPro200.
#[derive(Debug, Clone)]
pub struct HprDriver {
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
    /// The last transaction started was a poll (the next turn goes to due slow data).
    polled_last: bool,
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
    pub fn new(system: SystemId, now: Instant, core: &mut Core) -> Self {
        let maxpro = system == SystemId::MaxPro200;
        if !core.hpr_kept.is_empty() && core.hpr_kept.system() != Some(system) {
            // Another unit is on the line: the kept settings were meant for the one before.
            core.hpr_kept.clear();
            core.emit(LinkEvent::SettingsFailed {
                reason: SettingsFailure::OutsideLimits,
            });
        }
        HprDriver {
            system,
            next_poll_at: now,
            pause_until: None,
            slow: SlowData::new(
                if maxpro { 0 } else { SLOW_ALL },
                now,
                core.config.slow_data_interval,
            ),
            queue: Deque::new(),
            active: None,
            reapply: Deque::new(),
            reapply_pending: !core.hpr_kept.is_empty(),
            reapply_not_before: now,
            polled_last: false,
            now,
        }
    }

    fn maxpro(&self) -> bool {
        self.system == SystemId::MaxPro200
    }

    /// Family of the unit.
    pub fn family(&self) -> Family {
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

    /// True when the active command is a RAW forward.
    pub fn active_is_raw(&self) -> bool {
        matches!(
            self.active,
            Some(ActiveJob {
                job: HprJob::Raw { .. },
                ..
            })
        )
    }

    fn in_pilot_arc(&self, core: &Core) -> bool {
        core.status
            .hpr
            .state
            .is_some_and(|s| is_pilot_arc(self.maxpro(), s))
    }

    /// Earliest time the driver wants to send something.
    pub fn wake_at(&self, core: &Core) -> Option<Instant> {
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
    pub fn next_request(
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
        if let Some(ActiveJob { job, .. }) = &self.active {
            if job.needs_remote() && !core.status.hpr.remote_accepted {
                return typed(HprPurpose::RemoteMode, Request::RemoteMode);
            }
            return match job {
                HprJob::Typed(request) => typed(HprPurpose::Active, *request),
                HprJob::Raw { id, frame } => {
                    Some((HprPurpose::Active, HprExpect::Raw(*id), frame.clone()))
                }
            };
        }
        // Round robin: after a poll, due slow data gets one transaction before the next
        // poll, so a short poll interval cannot starve it.
        let poll_due = now >= self.next_poll_at;
        if poll_due && !self.polled_last {
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
            for request in core.hpr_kept.as_slice() {
                let _ = self.reapply.push_back(*request);
            }
        }
        if let Some(request) = self.reapply.pop_front() {
            self.active = Some(ActiveJob {
                ticket: None,
                job: HprJob::Typed(request),
                retried: false,
            });
            return;
        }
        self.active = self.queue.pop_front().map(|(ticket, job)| ActiveJob {
            ticket: Some(ticket),
            job,
            retried: false,
        });
    }

    /// The unit lost its settings or restarted (state back to power-up, or a set point
    /// other than the kept one): remote mode must be entered again and the kept settings
    /// re-applied.
    fn settings_lost(&mut self, now: Instant, core: &mut Core) {
        core.status.hpr.remote_accepted = false;
        if core.status.remote {
            core.status.remote = false;
            core.emit(LinkEvent::RemoteModeChanged { remote: false });
        }
        if !core.hpr_kept.is_empty() && self.reapply.is_empty() {
            self.reapply_pending = true;
            self.reapply_not_before = now;
        }
    }

    /// A settings job (re-apply or command) did not end well: a command fails with
    /// `failure`; a re-apply reports `reason` and is tried again later.
    fn job_failed(
        &mut self,
        now: Instant,
        job: ActiveJob,
        failure: CommandFailure,
        reason: SettingsFailure,
        core: &mut Core,
    ) {
        match job.ticket {
            Some(ticket) => core.emit(LinkEvent::CommandDone {
                ticket,
                result: Err(failure),
            }),
            None => {
                core.emit(LinkEvent::SettingsFailed { reason });
                self.reapply.clear();
                self.reapply_pending = true;
                self.reapply_not_before = now + REAPPLY_BACKOFF;
            }
        }
    }

    fn start_poll(
        &mut self,
        now: Instant,
        core: &Core,
    ) -> Option<(HprPurpose, HprExpect, Vec<u8, RAW_HPR_CAPACITY>)> {
        self.next_poll_at = now + core.config.poll_interval;
        self.polled_last = true;
        typed(HprPurpose::Poll, Request::GetPsInfo)
    }

    fn slow_request(
        &mut self,
        now: Instant,
        core: &Core,
    ) -> Option<(HprPurpose, HprExpect, Vec<u8, RAW_HPR_CAPACITY>)> {
        if self.slow.refresh_due(now, core.config.slow_data_interval) && !self.maxpro() {
            self.slow.request(SLOW_ALL);
        }
        self.slow.take_due_retries(now);
        let pending = self.slow.pending();
        if pending & SLOW_ERROR_LOG != 0 {
            return typed(HprPurpose::SlowErrorLog, Request::ReadErrorLog);
        }
        if pending & SLOW_TIMERS != 0 {
            return typed(HprPurpose::SlowTimers, Request::GetTimerCounter);
        }
        None
    }

    /// A reply arrived for `purpose` (already checked to answer the request; error replies
    /// 500/501 never get here, except for RAW forwards).
    pub fn on_reply(
        &mut self,
        now: Instant,
        purpose: HprPurpose,
        reply: Option<&Reply<'_>>,
        raw_len: usize,
        core: &mut Core,
    ) {
        self.now = now;
        match (purpose, reply) {
            (HprPurpose::Poll, Some(Reply::PsInfo(info))) => {
                core.status.hpr.ps_info = Some(*info);
                core.status.hpr.nominal_amps = Some(info.current_setpoint);
                self.update_state(now, info.state, core);
                self.update_error(info.error, core);
                self.check_setpoint(now, info.current_setpoint, core);
            }
            (HprPurpose::Poll, Some(Reply::MaxProPsInfo(info))) => {
                core.status.hpr.maxpro_info = Some(*info);
                core.status.hpr.nominal_amps = Some(info.current_setpoint);
                self.update_state(now, info.state, core);
                self.update_error(info.error, core);
                self.check_setpoint(now, info.current_setpoint, core);
            }
            (HprPurpose::State, Some(Reply::State(state))) => {
                self.next_poll_at = now + core.config.poll_interval;
                self.update_state(now, *state, core);
            }
            (HprPurpose::RemoteMode, Some(Reply::Ack { result, .. })) => {
                if *result == Acceptance::Accepted {
                    core.status.hpr.remote_accepted = true;
                    if !core.status.remote {
                        core.status.remote = true;
                        core.emit(LinkEvent::RemoteModeChanged { remote: true });
                    }
                } else if let Some(job) = self.active.take() {
                    self.job_failed(
                        now,
                        job,
                        CommandFailure::NotAccepted,
                        SettingsFailure::NotAccepted,
                        core,
                    );
                }
            }
            (HprPurpose::SlowErrorLog, reply) => {
                if let Some(Reply::ErrorLog(log)) = reply {
                    core.status.hpr.error_log = Some(*log);
                }
                self.slow_done(now, SLOW_ERROR_LOG, None, core);
            }
            (HprPurpose::SlowTimers, reply) => {
                if let Some(Reply::TimerCounter(t)) = reply {
                    core.status.hpr.timers = Some(*t);
                }
                self.slow_done(now, SLOW_TIMERS, None, core);
            }
            (HprPurpose::Active, reply) => {
                let Some(active) = self.active.take() else {
                    return;
                };
                self.finish_job(now, active, reply, raw_len, core);
            }
            _ => {}
        }
    }

    /// The reply to the active job arrived. A setting counts as done only when the unit's
    /// answer shows the value asked for; otherwise it is sent once more after entering remote
    /// mode again (the unit may have restarted and left remote mode), then reported as not
    /// accepted. Never success with another value.
    fn finish_job(
        &mut self,
        now: Instant,
        mut active: ActiveJob,
        reply: Option<&Reply<'_>>,
        raw_len: usize,
        core: &mut Core,
    ) {
        let request = match &active.job {
            HprJob::Typed(request) => Some(*request),
            HprJob::Raw { .. } => None,
        };
        let Some(request) = request.filter(|r| sets(r) != 0) else {
            return Self::finish_other(active, reply, raw_len, core);
        };
        // Whether the setting took effect, by the unit's answer.
        let taken = match (request, reply) {
            (Request::SetNominalAmps { amps }, Some(Reply::NominalAmps(set))) => {
                core.status.hpr.nominal_amps = Some(*set);
                *set == amps
            }
            (Request::SetCornerCurrent { percent }, Some(Reply::CornerCurrentSet(set))) => {
                *set == u16::from(percent)
            }
            (_, Some(Reply::Ack { result, .. })) => *result == Acceptance::Accepted,
            _ => false,
        };
        if taken {
            core.hpr_kept.keep(self.system, request);
            // A re-apply run still to come must not set older values again.
            let new = sets(&request);
            // In order, without `Deque::retain` (its swaps are memmoves, see `keep`).
            for _ in 0..self.reapply.len() {
                if let Some(old) = self.reapply.pop_front()
                    && sets(&old) & !new != 0
                {
                    let _ = self.reapply.push_back(old);
                }
            }
            if let Some(ticket) = active.ticket {
                let output = match reply {
                    Some(Reply::NominalAmps(set)) | Some(Reply::CornerCurrentSet(set)) => {
                        CommandOutput::Value(*set)
                    }
                    _ => CommandOutput::Done,
                };
                core.emit(LinkEvent::CommandDone {
                    ticket,
                    result: Ok(output),
                });
            }
        } else if !active.retried {
            // Perhaps out of remote mode after a restart: 004 again, then once more.
            core.status.hpr.remote_accepted = false;
            active.retried = true;
            self.active = Some(active);
        } else {
            self.job_failed(
                now,
                active,
                CommandFailure::NotAccepted,
                SettingsFailure::NotAccepted,
                core,
            );
        }
    }

    /// The reply to a job that sets nothing (RAW, gas tests, logs...).
    fn finish_other(active: ActiveJob, reply: Option<&Reply<'_>>, raw_len: usize, core: &mut Core) {
        let Some(ticket) = active.ticket else {
            return;
        };
        let result = match (&active.job, reply) {
            (HprJob::Raw { .. }, _) => Ok(CommandOutput::Raw { len: raw_len }),
            (_, Some(Reply::Ack { result, .. })) => {
                if *result == Acceptance::Accepted {
                    Ok(CommandOutput::Done)
                } else {
                    Err(CommandFailure::NotAccepted)
                }
            }
            (_, Some(Reply::ErrorLog(log))) => {
                core.status.hpr.error_log = Some(*log);
                Ok(CommandOutput::ErrorLog(*log))
            }
            (_, Some(Reply::TimerCounter(t))) => {
                core.status.hpr.timers = Some(*t);
                Ok(CommandOutput::Done)
            }
            _ => Ok(CommandOutput::Done),
        };
        core.emit(LinkEvent::CommandDone { ticket, result });
    }

    /// A poll shows the unit's current set point: when kept settings say otherwise (and
    /// no setting is under way), the unit lost them (a power blip too short for a link-down,
    /// or a change at the unit): re-apply.
    fn check_setpoint(&mut self, now: Instant, setpoint: u16, core: &mut Core) {
        let busy = self.active.is_some() || !self.reapply.is_empty() || self.reapply_pending;
        if busy {
            return;
        }
        if core.hpr_kept.amps().is_some_and(|kept| kept != setpoint) {
            self.settings_lost(now, core);
        }
    }

    /// `purpose` failed for good.
    pub fn on_failed(
        &mut self,
        now: Instant,
        purpose: HprPurpose,
        error: TransactionError,
        core: &mut Core,
    ) {
        self.now = now;
        match purpose {
            HprPurpose::Poll | HprPurpose::State => {}
            HprPurpose::SlowErrorLog => self.slow_done(now, SLOW_ERROR_LOG, Some(error), core),
            HprPurpose::SlowTimers => self.slow_done(now, SLOW_TIMERS, Some(error), core),
            HprPurpose::RemoteMode | HprPurpose::Active => {
                if let Some(job) = self.active.take() {
                    self.job_failed(
                        now,
                        job,
                        CommandFailure::Transaction(error),
                        SettingsFailure::Transaction(error),
                        core,
                    );
                }
            }
        }
    }

    fn update_state(&mut self, now: Instant, state: StateCode, core: &mut Core) {
        let previous = core.status.hpr.state;
        if previous != Some(state) {
            core.status.hpr.state = Some(state);
            core.emit(LinkEvent::StateChanged {
                from: previous,
                to: state,
            });
            // Back in a power-up state: the unit restarted (a power blip shorter than a
            // link-down, or a software reset) and forgot remote mode and its settings.
            let maxpro = self.maxpro();
            if is_power_up(maxpro, state) && previous.is_some_and(|p| !is_power_up(maxpro, p)) {
                self.settings_lost(now, core);
            }
            if is_pilot_arc(self.maxpro(), state) {
                let until = now + PILOT_ARC_PAUSE;
                self.pause_until = Some(until);
                self.next_poll_at = until;
            }
        }
    }

    fn update_error(&mut self, error: ErrorCode, core: &mut Core) {
        let new = error.is_error().then_some(ActiveFault::Hpr(error));
        core.status.hpr.error = Some(error);
        core.set_active_fault(new);
    }

    /// A slow-data item is read (`error` = None) or failed for good (see [`SlowData::finish`]).
    fn slow_done(
        &mut self,
        now: Instant,
        bit: u8,
        error: Option<TransactionError>,
        core: &mut Core,
    ) {
        let interval = core.config.slow_data_interval;
        self.slow.finish(now, bit, error, interval, core);
    }

    /// Validate and queue a command.
    pub fn submit(
        &mut self,
        now: Instant,
        ticket: Ticket,
        command: &LinkCommand<'_>,
        core: &mut Core,
    ) -> Result<(), Refusal> {
        self.now = now;
        let family = self.family();
        let maxpro = self.maxpro();
        let unsupported = Refusal::NotSupported { family };
        let state = core.status.hpr.state;
        let error = core.status.hpr.error;
        let forbidden = Refusal::StateForbids { state, error };
        let request = match command {
            LinkCommand::HprSetNominalAmps { amps } => {
                check_amps(*amps, self.max_amps())?;
                Request::SetNominalAmps { amps: *amps }
            }
            LinkCommand::HprSetProcess { amps, gases } => {
                if !maxpro {
                    return Err(unsupported);
                }
                check_amps(*amps, hpr::MAX_MAXPRO_AMPS)?;
                check_gases(gases)?;
                // "only accepted when the system is in state #2 or #3".
                if !state.is_some_and(|s| matches!(s.0, 2 | 3)) {
                    return Err(forbidden);
                }
                Request::SetProcess {
                    amps: *amps,
                    gases: *gases,
                }
            }
            LinkCommand::HprSetAllParameters(parameters) => {
                let auto_console = matches!(
                    self.system,
                    SystemId::Hpr {
                        console: Some(hpr::GasConsole::Auto | hpr::GasConsole::AutoMix) | None,
                        ..
                    }
                );
                if maxpro || !auto_console {
                    return Err(unsupported);
                }
                check_amps(parameters.amps, self.max_amps())?;
                check_corner(parameters.corner_percent)?;
                check_gases(&parameters.gases)?;
                check_flows(&parameters.flows)?;
                if is_cutting(state) {
                    return Err(forbidden);
                }
                Request::SetAllParameters(*parameters)
            }
            LinkCommand::MaxProSetAllParameters(parameters) => {
                if !maxpro {
                    return Err(unsupported);
                }
                check_amps(parameters.amps, hpr::MAX_MAXPRO_AMPS)?;
                check_gases(&parameters.gases)?;
                for psi in [parameters.pressures.plasma, parameters.pressures.shield] {
                    check_range(HprValue::GasParameter, psi, 0, hpr::MAX_FLOW_PSI)?;
                }
                if !state.is_some_and(|s| matches!(s.0, 2 | 3)) {
                    return Err(forbidden);
                }
                Request::SetAllParametersMaxPro200(*parameters)
            }
            LinkCommand::HprSetInletGases(gases) => {
                check_gases(gases)?;
                if is_cutting(state) {
                    return Err(forbidden);
                }
                Request::SetInletGases(*gases)
            }
            LinkCommand::HprSetCornerCurrent { percent } => {
                if maxpro {
                    return Err(unsupported);
                }
                check_corner(*percent)?;
                Request::SetCornerCurrent { percent: *percent }
            }
            LinkCommand::HprClearWarnings => {
                if maxpro {
                    return Err(unsupported);
                }
                Request::ClearWarnings
            }
            LinkCommand::HprSoftwareReset => {
                let allowed = if maxpro {
                    // "only valid when the system is not cutting".
                    state.is_some() && !is_cutting(state)
                } else {
                    // "Only accepted if ... Error code > 79 and State = 14".
                    state == Some(StateCode(14)) && error.is_some_and(|e| e.is_shutdown_error())
                };
                if !allowed {
                    return Err(forbidden);
                }
                Request::SoftwareReset
            }
            LinkCommand::HprGasTest { flow, on } => {
                if maxpro {
                    return Err(unsupported);
                }
                if is_cutting(state) {
                    return Err(forbidden);
                }
                match (flow, on) {
                    (HprGasFlow::Preflow, true) => Request::GasPreflowTestStart,
                    (HprGasFlow::Preflow, false) => Request::GasPreflowTestStop,
                    (HprGasFlow::Cutflow, true) => Request::GasCutflowTestStart,
                    (HprGasFlow::Cutflow, false) => Request::GasCutflowTestStop,
                }
            }
            LinkCommand::HprReadErrorLog => {
                if maxpro {
                    return Err(unsupported);
                }
                Request::ReadErrorLog
            }
            LinkCommand::HprReadTimers => {
                if maxpro {
                    return Err(unsupported);
                }
                Request::GetTimerCounter
            }
            LinkCommand::RefreshSlowData => {
                if maxpro {
                    core.emit(LinkEvent::CommandDone {
                        ticket,
                        result: Ok(CommandOutput::Done),
                    });
                    return Ok(());
                }
                return self.slow.request_for(ticket, SLOW_ALL);
            }
            LinkCommand::Raw(bytes) => {
                let job = parse_raw(bytes)?;
                return self
                    .queue
                    .push_back((ticket, job))
                    .map_err(|_| Refusal::QueueFull);
            }
            _ => return Err(unsupported),
        };
        // Belt and braces: the typed commands above are all on the allow-list.
        if !hpr::is_allowed(request.id()) {
            return Err(Refusal::RawCommandNotAllowed { id: request.id() });
        }
        let mut buf = [0u8; hpr::MAX_FRAME_LEN];
        request.emit(&mut buf).map_err(Refusal::RawMalformed)?;
        self.queue
            .push_back((ticket, HprJob::Typed(request)))
            .map_err(|_| Refusal::QueueFull)
    }

    /// The link went down: every pending command fails.
    pub fn abort(&mut self, core: &mut Core) {
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
pub fn emit(request: &Request) -> Option<Vec<u8, RAW_HPR_CAPACITY>> {
    let mut buf = [0u8; hpr::MAX_FRAME_LEN];
    let len = request.emit(&mut buf).ok()?;
    Vec::from_slice(buf.get(..len)?).ok()
}

fn check_range(value: HprValue, requested: u16, min: u16, max: u16) -> Result<(), Refusal> {
    if (min..=max).contains(&requested) {
        Ok(())
    } else {
        Err(Refusal::HprValueOutOfRange {
            value,
            requested,
            min,
            max,
        })
    }
}

fn check_amps(amps: u16, max: u16) -> Result<(), Refusal> {
    check_range(HprValue::Amps, amps, hpr::MIN_AMPS, max)
}

fn check_corner(percent: u8) -> Result<(), Refusal> {
    check_range(
        HprValue::CornerPercent,
        u16::from(percent),
        u16::from(*hpr::CORNER_PERCENT.start()),
        u16::from(*hpr::CORNER_PERCENT.end()),
    )
}

/// Gas type codes 1..=12 (0 is "No Gas, invalid gas type").
fn check_gases(gases: &GasPair) -> Result<(), Refusal> {
    for gas in [gases.plasma, gases.shield] {
        check_range(HprValue::GasParameter, gas.0, 1, GasCode::MAX)?;
    }
    Ok(())
}

fn check_flows(flows: &GasFlows) -> Result<(), Refusal> {
    for (i, psi) in flows.to_array().into_iter().enumerate() {
        let max = if i < 4 {
            hpr::MAX_FLOW_PSI
        } else {
            hpr::MAX_MIX_PSI
        };
        check_range(HprValue::GasParameter, psi, 0, max)?;
    }
    Ok(())
}

/// Check a RAW HPR frame: valid framing and checksum, an allow-listed id, and not line
/// control the link owns (SLEEP, WAKE, BROADCAST would strand the link).
fn parse_raw(bytes: &[u8]) -> Result<HprJob, Refusal> {
    let frame = Frame::parse(bytes).map_err(Refusal::RawMalformed)?;
    let line_control = matches!(frame.id, id::SLEEP | id::WAKE | id::BROADCAST_MODE);
    if !hpr::is_allowed(frame.id) || line_control {
        return Err(Refusal::RawCommandNotAllowed { id: frame.id });
    }
    let mut buf = [0u8; hpr::MAX_FRAME_LEN];
    let len = frame.emit(&mut buf).map_err(Refusal::RawMalformed)?;
    let frame_bytes = buf
        .get(..len)
        .and_then(|b| Vec::from_slice(b).ok())
        .ok_or(Refusal::RawMalformed(plasma_protocol::Error::Overlong))?;
    Ok(HprJob::Raw {
        id: frame.id,
        frame: frame_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::hpr::HprParameters;

    const SYSTEM: SystemId = SystemId::MaxPro200;

    #[test]
    fn a_kept_setting_replaces_the_earlier_ones_it_sets_again() {
        let mut kept = HprKept::default();
        let gases = GasPair {
            plasma: GasCode(1),
            shield: GasCode(2),
        };
        kept.keep(SYSTEM, Request::SetNominalAmps { amps: 130 });
        kept.keep(SYSTEM, Request::SetCornerCurrent { percent: 70 });
        kept.keep(SYSTEM, Request::SetInletGases(gases));
        kept.keep(SYSTEM, Request::SetNominalAmps { amps: 200 });
        assert_eq!(
            kept.as_slice(),
            [
                Request::SetCornerCurrent { percent: 70 },
                Request::SetInletGases(gases),
                Request::SetNominalAmps { amps: 200 },
            ]
        );
        assert_eq!(kept.amps(), Some(200));
        // All parameters set everything the others set.
        let all = HprParameters {
            amps: 260,
            corner_percent: 80,
            gases,
            flows: GasFlows::default(),
        };
        kept.keep(SYSTEM, Request::SetAllParameters(all));
        assert_eq!(kept.as_slice(), [Request::SetAllParameters(all)]);
        kept.keep(SYSTEM, Request::SetCornerCurrent { percent: 60 });
        assert_eq!(kept.as_slice().len(), 2);
        assert_eq!(kept.amps(), Some(260));
        // Not settings: not kept.
        kept.keep(SYSTEM, Request::ClearWarnings);
        assert_eq!(kept.as_slice().len(), 2);
        // Settings another unit confirmed replace everything.
        let hpr130 = SystemId::Hpr {
            rating: hpr::HprRating::Hpr130,
            console: Some(hpr::GasConsole::Auto),
            xd: false,
        };
        kept.keep(hpr130, Request::SetNominalAmps { amps: 100 });
        assert_eq!(kept.as_slice(), [Request::SetNominalAmps { amps: 100 }]);
        assert_eq!(kept.system(), Some(hpr130));
    }
}
