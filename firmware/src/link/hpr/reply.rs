//! What the unit's answers mean: polls and GET_STATE update the status (state changes,
//! the pilot-arc pause, errors, a restart the link did not see), and the reply to the active
//! job decides whether a setting took effect.

use plasma_protocol::hpr::{Acceptance, DiagnosticReply, ErrorCode, Reply, Request, StateCode};
use plasma_protocol::time::Instant;

use super::confirm;
use super::kept::sets;
use super::{
    ActiveJob, HprDriver, HprJob, HprPurpose, PILOT_ARC_PAUSE, REAPPLY_BACKOFF,
    SHARED_LINE_FULL_POLL_EVERY, SLOW_ERROR_LOG, SLOW_GASES, SLOW_INLET_GASES, SLOW_TIMERS,
    SLOW_TORCH, SLOW_VERSION, is_arc_on, is_pilot_arc, is_power_up,
};
use crate::link::core::Core;
use crate::link::event::{CommandFailure, CommandOutput, LinkEvent, ProcessFailure};
use crate::link::status::{ActiveFault, Firmware};
use crate::link::transaction::TransactionError;

/// State 2, GAS PURGE (MaxPro200) / PURGE (HPR): after power-up, before ready.
const PURGE: u16 = 2;

impl HprDriver {
    /// The unit lost its settings or restarted (state back to power-up, or a set point
    /// other than the kept one): it left remote mode on its own, a power cycle (see `kept`);
    /// the kept settings are re-applied (after 004 again) only when configured so.
    fn settings_lost(&mut self, now: Instant, core: &mut Core) {
        core.status.hpr.remote_accepted = false;
        if core.kept.hpr.is_empty() || !self.reapply.is_empty() {
            if core.status.remote {
                core.status.remote = false;
                core.emit(LinkEvent::RemoteModeChanged { remote: false });
            }
            return;
        }
        if core.unit_power_cycled() {
            self.reapply_pending = true;
            self.reapply_not_before = now;
        }
    }

    /// The first poll after the unit answered again with settings kept: powering up,
    /// purging (what it does after power-up) or on another set point, it was switched off
    /// and on; otherwise the link was lost and the kept settings are re-applied.
    fn first_poll_after_return(
        &mut self,
        now: Instant,
        state: StateCode,
        setpoint: u16,
        core: &mut Core,
    ) {
        let restarted = is_power_up(self.maxpro(), state)
            || state.0 == PURGE
            || core.kept.hpr.amps().is_some_and(|kept| kept != setpoint);
        if !restarted || core.unit_power_cycled() {
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
        reason: ProcessFailure,
        core: &mut Core,
    ) {
        match job.ticket {
            Some(ticket) => core.emit(LinkEvent::CommandDone {
                ticket,
                result: Err(failure),
            }),
            None => {
                core.emit(LinkEvent::ProcessFailed { reason });
                self.reapply.clear();
                self.reapply_pending = true;
                self.reapply_not_before = now + REAPPLY_BACKOFF;
            }
        }
    }

    /// A reply arrived for `purpose` (already checked to answer the request; error replies
    /// 500/501 never get here, except for RAW forwards).
    pub(crate) fn on_reply(
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
                // 079 has the set point, not the output current: 028 follows while the arc
                // is on (lines 148, 168); without a main arc the output is 0 A.
                self.amps_due = is_arc_on(info.state);
                if !self.amps_due {
                    core.status.hpr.actual_amps = Some(0);
                }
                self.polled(now, info.state, info.error, info.current_setpoint, core);
            }
            (HprPurpose::Poll, Some(Reply::MaxProPsInfo(info))) => {
                core.status.hpr.maxpro_info = Some(*info);
                self.polled(now, info.state, info.error, info.current_setpoint, core);
            }
            (HprPurpose::FaultPoll, Some(Reply::CurrentError(error))) => {
                self.update_error(*error, core);
            }
            (HprPurpose::PollAmps, Some(Reply::PlasmaAmps(amps))) => {
                core.status.hpr.actual_amps = Some(*amps);
            }
            (HprPurpose::State, Some(Reply::State(state))) => {
                self.next_poll_at = now + core.config.poll_interval;
                self.update_state(now, *state, core);
            }
            (HprPurpose::RemoteMode, Some(Reply::Ack { result, .. })) => {
                self.remote_mode_answered(now, *result, core);
            }
            (HprPurpose::SlowErrorLog, reply) => {
                if let Some(Reply::ErrorLog(log)) = reply {
                    core.status.hpr.error_log = Some(*log);
                }
                self.slow_done(now, SLOW_ERROR_LOG, None, core);
            }
            (HprPurpose::SlowGases, reply) => {
                if let Some(Reply::GasSwitch(gases)) = reply {
                    core.status.hpr.gases = Some(*gases);
                }
                self.slow_done(now, SLOW_GASES, None, core);
            }
            (HprPurpose::SlowInletGases, reply) => {
                if let Some(Reply::InletGases(gases)) = reply {
                    core.status.hpr.inlet_gases = Some(*gases);
                }
                self.slow_done(now, SLOW_INLET_GASES, None, core);
            }
            (HprPurpose::SlowVersion, reply) => {
                if let Some(Reply::Version(version)) = reply {
                    core.status.hpr.firmware = Firmware::new(version);
                }
                self.slow_done(now, SLOW_VERSION, None, core);
            }
            (HprPurpose::SlowTorch, reply) => {
                if let Some(Reply::TorchId(torch)) = reply {
                    core.status.hpr.torch = Some(*torch);
                }
                self.slow_done(now, SLOW_TORCH, None, core);
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

    /// A poll answered: the unit's state, error and current set point.
    fn polled(
        &mut self,
        now: Instant,
        state: StateCode,
        error: ErrorCode,
        setpoint: u16,
        core: &mut Core,
    ) {
        core.status.hpr.nominal_amps = Some(setpoint);
        self.fault_reads_left = SHARED_LINE_FULL_POLL_EVERY - 1;
        self.update_state(now, state, core);
        self.update_error(error, core);
        if core::mem::take(&mut self.returned) {
            self.first_poll_after_return(now, state, setpoint, core);
        } else {
            self.check_setpoint(now, setpoint, core);
        }
    }

    /// 004 REMOTE_MODE answered: remote mode is on, or the job that needed it fails.
    fn remote_mode_answered(&mut self, now: Instant, result: Acceptance, core: &mut Core) {
        if result == Acceptance::Accepted {
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
                ProcessFailure::NotAccepted,
                core,
            );
        }
    }

    /// The reply to the active job arrived. A setting counts as done only when the unit's
    /// answer shows the value asked for (for 095 and 078, which only acknowledge, when the
    /// reads of `confirm` show it too); otherwise it is sent once more after entering remote
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
        let taken = match active.reads_done {
            0 => setting_taken(request, reply, core),
            _ => confirm::shows(&request, reply),
        };
        if taken && usize::from(active.reads_done) < confirm::reads(&request).len() {
            // Acknowledged (or read back) so far: the next read confirms the rest.
            active.reads_done += 1;
            self.active = Some(active);
        } else if taken {
            self.setting_confirmed(active, request, reply, core);
        } else if !active.retried {
            // Perhaps out of remote mode after a restart: 004 again, then once more.
            core.status.hpr.remote_accepted = false;
            active.retried = true;
            active.reads_done = 0;
            self.active = Some(active);
        } else {
            self.job_failed(
                now,
                active,
                CommandFailure::NotAccepted,
                ProcessFailure::NotAccepted,
                core,
            );
        }
    }

    /// The unit took the setting `request` of `active`: it is kept, and the command (if it
    /// is one) is done.
    fn setting_confirmed(
        &mut self,
        active: ActiveJob,
        request: Request,
        reply: Option<&Reply<'_>>,
        core: &mut Core,
    ) {
        let Some(ticket) = active.ticket else {
            // A re-apply: the request is kept already, and the rest of its run is newer.
            return;
        };
        core.kept.hpr.keep(self.system, request);
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
            // The manual's only 143 sample answers mode 1 with `1` (line 283): an echo of the
            // mode or an accept flag. Either reading of the reply counts as taken.
            (HprJob::Typed(Request::SetTestMode(mode)), Some(Reply::SetTestMode(reply))) => {
                if *reply == mode.code() || *reply == 1 {
                    Ok(CommandOutput::Done)
                } else {
                    Err(CommandFailure::NotAccepted)
                }
            }
            (_, Some(Reply::ErrorLog(log))) => {
                core.status.hpr.error_log = Some(*log);
                Ok(CommandOutput::ErrorLog(*log))
            }
            // The gas check's reading: the freshest 079 the link has, too.
            (_, Some(Reply::PsInfo(info))) => {
                core.status.hpr.ps_info = Some(*info);
                Ok(CommandOutput::HprPressures {
                    plasma: info.pressures.plasma_cutflow,
                    shield: info.pressures.shield_cutflow,
                })
            }
            (_, Some(Reply::Diagnostic(DiagnosticReply::MfgData1(d)))) => {
                Ok(CommandOutput::HprPressures {
                    plasma: d.plasma_pressure,
                    shield: d.shield_pressure,
                })
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
        if core.kept.hpr.amps().is_some_and(|kept| kept != setpoint) {
            self.settings_lost(now, core);
        }
    }

    /// `purpose` failed for good.
    pub(crate) fn on_failed(
        &mut self,
        now: Instant,
        purpose: HprPurpose,
        error: TransactionError,
        core: &mut Core,
    ) {
        self.now = now;
        match purpose {
            HprPurpose::Poll | HprPurpose::FaultPoll | HprPurpose::PollAmps | HprPurpose::State => {
            }
            HprPurpose::SlowErrorLog => self.slow_done(now, SLOW_ERROR_LOG, Some(error), core),
            HprPurpose::SlowTimers => self.slow_done(now, SLOW_TIMERS, Some(error), core),
            HprPurpose::SlowGases => self.slow_done(now, SLOW_GASES, Some(error), core),
            HprPurpose::SlowInletGases => self.slow_done(now, SLOW_INLET_GASES, Some(error), core),
            HprPurpose::SlowVersion => self.slow_done(now, SLOW_VERSION, Some(error), core),
            HprPurpose::SlowTorch => self.slow_done(now, SLOW_TORCH, Some(error), core),
            HprPurpose::RemoteMode | HprPurpose::Active => {
                if let Some(job) = self.active.take() {
                    self.job_failed(
                        now,
                        job,
                        CommandFailure::Transaction(error),
                        ProcessFailure::Transaction(error),
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
}

/// Whether the setting `request` took effect, by the unit's answer `reply` (a nominal
/// current answer also updates the status).
fn setting_taken(request: Request, reply: Option<&Reply<'_>>, core: &mut Core) -> bool {
    match (request, reply) {
        (Request::SetNominalAmps { amps }, Some(Reply::NominalAmps(set))) => {
            core.status.hpr.nominal_amps = Some(*set);
            *set == amps
        }
        (Request::SetCornerCurrent { percent }, Some(Reply::CornerCurrentSet(set))) => {
            *set == u16::from(percent)
        }
        (_, Some(Reply::Ack { result, .. })) => *result == Acceptance::Accepted,
        _ => false,
    }
}
