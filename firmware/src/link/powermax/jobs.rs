//! The active command, step by step: the request of each step, and what the answer to the
//! last one means (a command's result, a setting confirmed or refused).

use plasma_protocol::modbus_ascii::Response;
use plasma_protocol::powermax::Psi;
use plasma_protocol::time::Instant;

use super::process::legacy_writes;
use super::{Active, Job, MbPurpose, PowermaxDriver, REAPPLY_BACKOFF, Variant};
use crate::link::core::Core;
use crate::link::event::{CommandFailure, CommandOutput, LinkEvent, ProcessFailure};
use crate::link::powermax::legacy;
use crate::link::powermax::modbus::{MbRequest, read_values};
use crate::link::powermax::sync;
use crate::link::transaction::TransactionError;

impl PowermaxDriver {
    pub(super) fn active_request(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        if self.active.is_none() {
            if let Some((ticket, job)) = self.queue.pop_front() {
                self.active = Some(Active {
                    ticket: Some(ticket),
                    restoring: false,
                    job,
                    step: 0,
                });
            } else if self.reapply_pending && now >= self.reapply_not_before {
                self.start_reapply(now, core);
            }
        }
        let active = self.active.as_ref()?;
        let Some(request) = self.step_request(active) else {
            // A step that cannot be encoded (commands are validated before, so not expected):
            // fail the command rather than leave it in the way.
            if let Some(Active {
                ticket: Some(ticket),
                ..
            }) = self.active.take()
            {
                core.emit(LinkEvent::CommandDone {
                    ticket,
                    result: Err(CommandFailure::Transaction(TransactionError::Malformed)),
                });
            }
            return None;
        };
        // The quick restart is never repeated: the unit may already be restarting.
        let retries = matches!(active.job, Job::QuickRestart).then_some(0);
        Some((MbPurpose::Active, request, retries))
    }

    fn step_request(&self, active: &Active) -> Option<MbRequest> {
        let step = usize::from(active.step);
        match (&active.job, self.variant) {
            (Job::Apply(d), Variant::Sync) => match step {
                0 => sync::settings_words(d.mode, d.current, d.pressure).map(sync::write_settings),
                1 => Some(sync::read_back()),
                _ => None,
            },
            (Job::Apply(d), Variant::Legacy) => {
                let writes = legacy_writes(d);
                match writes.get(step) {
                    Some(write) => Some(write.clone()),
                    None if step == writes.len() => Some(legacy::read_fault()),
                    None => None,
                }
            }
            (Job::Exit, Variant::Sync) => (step == 0).then(sync::exit_remote),
            (Job::Exit, Variant::Legacy) => legacy::exit_writes().get(step).cloned(),
            (Job::GasTest(on), Variant::Sync) => (step == 0).then(|| sync::gas_test(*on)),
            (Job::GasTest(on), Variant::Legacy) => (step == 0).then(|| legacy::gas_test(*on)),
            (Job::ReadPressure, variant) => (step == 0).then(|| MbRequest::ReadInput {
                start: match variant {
                    Variant::Sync => plasma_protocol::powermax::sync::ACTUAL_PRESSURE,
                    Variant::Legacy => plasma_protocol::powermax::legacy::ACTUAL_PRESSURE,
                },
                quantity: 1,
            }),
            (Job::QuickRestart, _) => (step == 0).then(sync::quick_restart).flatten(),
            (Job::Raw(request), _) => (step == 0).then(|| request.clone()),
        }
    }

    pub(super) fn advance_active(
        &mut self,
        now: Instant,
        response: &Response<'_>,
        raw_len: usize,
        core: &mut Core,
    ) {
        let Some(mut active) = self.active.take() else {
            return;
        };
        let outcome: Option<Result<CommandOutput, CommandFailure>> = match &active.job {
            Job::Apply(desired) => {
                let is_final = self.step_request_after(&active).is_none();
                if !is_final {
                    None
                } else {
                    Some(self.confirm_settings(
                        now,
                        desired,
                        response,
                        active.ticket.is_none() && !active.restoring,
                        core,
                    ))
                }
            }
            Job::Exit => {
                let is_final = self.step_request_after(&active).is_none();
                is_final.then(|| self.remote_exited(core))
            }
            Job::GasTest(_) => Some(Ok(CommandOutput::Done)),
            Job::ReadPressure => Some(
                read_values(response)
                    .and_then(|values| values.get(0))
                    .map(|raw| CommandOutput::Pressure(Psi::from_raw(raw)))
                    .ok_or(CommandFailure::Transaction(TransactionError::Malformed)),
            ),
            Job::QuickRestart => {
                self.start_blackout(now, core);
                Some(Ok(CommandOutput::Done))
            }
            Job::Raw(_) => Some(Ok(CommandOutput::Raw { len: raw_len })),
        };
        match outcome {
            None => {
                active.step = active.step.saturating_add(1);
                self.active = Some(active);
            }
            Some(result) => {
                if let Some(ticket) = active.ticket {
                    core.emit(LinkEvent::CommandDone { ticket, result });
                }
            }
        }
    }

    fn step_request_after(&self, active: &Active) -> Option<MbRequest> {
        let next = Active {
            ticket: active.ticket,
            restoring: active.restoring,
            job: active.job.clone(),
            step: active.step.saturating_add(1),
        };
        self.step_request(&next)
    }

    /// The active command's transaction failed for good with `error`.
    pub(super) fn active_failed(&mut self, now: Instant, error: TransactionError, core: &mut Core) {
        let Some(active) = self.active.take() else {
            return;
        };
        let failure = match active.job {
            Job::Apply(_) => {
                let reason = ProcessFailure::Transaction(error);
                core.emit(LinkEvent::ProcessFailed { reason });
                if active.ticket.is_none() && !active.restoring {
                    self.reapply_pending = true;
                    self.reapply_not_before = now + REAPPLY_BACKOFF;
                }
                CommandFailure::Process(reason)
            }
            Job::QuickRestart => {
                // The unit may be restarting without answering: stay quiet anyway.
                self.start_blackout(now, core);
                CommandFailure::Transaction(error)
            }
            _ => CommandFailure::Transaction(error),
        };
        if let Some(ticket) = active.ticket {
            core.emit(LinkEvent::CommandDone {
                ticket,
                result: Err(failure),
            });
        }
    }

    /// The unit left remote control: the kept settings are forgotten.
    fn remote_exited(&mut self, core: &mut Core) -> Result<CommandOutput, CommandFailure> {
        core.kept.forget_powermax();
        self.reapply_pending = false;
        if core.status.remote {
            core.status.remote = false;
            core.emit(LinkEvent::RemoteModeChanged { remote: false });
        }
        Ok(CommandOutput::Done)
    }
}
