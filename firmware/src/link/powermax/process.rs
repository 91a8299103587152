//! The settings the CNC asked for: checked against the permitted limits, written and read
//! back, kept, and re-applied when the unit lost them (power cycle, link return, a change at
//! the unit).

use plasma_protocol::modbus_ascii::Response;
use plasma_protocol::powermax::{Amps, FaultCode, OperatingMode, Pressure, Psi};
use plasma_protocol::time::Instant;

use super::{Active, Job, PowermaxDriver, REAPPLY_BACKOFF, Variant};
use crate::link::command::Refusal;
use crate::link::core::Core;
use crate::link::event::{CommandFailure, CommandOutput, LinkEvent, ProcessFailure};
use crate::link::kept::Reapply;
use crate::link::powermax::legacy;
use crate::link::powermax::modbus::{MbRequest, read_values};
use crate::link::powermax::sync;
use crate::link::status::{Limits, PowermaxProcess};
use crate::link::transaction::TransactionError;

/// Settings the CNC asked for, validated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct DesiredProcess {
    pub(super) mode: OperatingMode,
    pub(super) current: Amps,
    pub(super) pressure: Pressure,
    /// Set point written first when `pressure` is automatic on a legacy unit.
    pub(super) legacy_first_pressure: Psi,
}

impl DesiredProcess {
    fn as_process(&self) -> PowermaxProcess {
        PowermaxProcess {
            mode: Some(self.mode),
            current: self.current,
            pressure: self.pressure,
        }
    }

    fn from_process(settings: &PowermaxProcess, limits: &Limits) -> Option<Self> {
        Some(DesiredProcess {
            mode: settings.mode?,
            current: settings.current,
            pressure: settings.pressure,
            legacy_first_pressure: limits.min_pressure,
        })
    }

    /// True when `read` shows these settings (automatic pressure reads back as whatever the
    /// unit chose).
    fn matches(&self, read: &PowermaxProcess) -> bool {
        let pressure_ok = match self.pressure {
            Pressure::Auto => true,
            Pressure::Set(_) => read.pressure == self.pressure,
        };
        read.mode == Some(self.mode) && read.current == self.current && pressure_ok
    }
}

/// Check settings against the permitted limits (nothing is sent when this fails).
pub(super) fn validate_process(
    limits: Option<&Limits>,
    mode: OperatingMode,
    current: Amps,
    pressure: Pressure,
) -> Result<(), Refusal> {
    let limits = limits.ok_or(Refusal::LimitsUnknown)?;
    if let Some(permitted) = limits.modes
        && !permitted.contains(mode)
    {
        return Err(Refusal::ModeNotPermitted { mode, permitted });
    }
    if current < limits.min_current || current > limits.max_current || !current.is_positive() {
        return Err(Refusal::CurrentOutOfRange {
            requested: current,
            min: limits.min_current,
            max: limits.max_current,
        });
    }
    if let Some(psi) = pressure.psi()
        && (psi < limits.min_pressure || psi > limits.max_pressure)
    {
        return Err(Refusal::PressureOutOfRange {
            requested: psi,
            min: limits.min_pressure,
            max: limits.max_pressure,
        });
    }
    Ok(())
}

impl PowermaxDriver {
    pub(super) fn start_reapply(&mut self, now: Instant, core: &mut Core) {
        let (settings, restoring) = match core.kept.powermax_due() {
            Some(Reapply::Kept(settings)) => (settings, false),
            Some(Reapply::Restore(settings)) => (settings, true),
            None => {
                self.reapply_pending = false;
                return;
            }
        };
        // Limits first: they are part of the slow data read at start.
        let Some(limits) = core.status.limits else {
            return;
        };
        self.reapply_pending = false;
        let Some(mode) = settings.mode else {
            return;
        };
        if restoring {
            // One attempt, like a command: refused or started, it is not tried again.
            core.kept.restore_done();
        }
        let checked = validate_process(Some(&limits), mode, settings.current, settings.pressure);
        if let (Err(refusal), true) = (checked, restoring) {
            core.emit(LinkEvent::RestoreRefused { refusal });
            return;
        }
        if checked.is_err() {
            self.reapply_not_before = now + REAPPLY_BACKOFF;
            self.reapply_pending = true;
            core.emit(LinkEvent::ProcessFailed {
                reason: ProcessFailure::OutsideLimits,
            });
            return;
        }
        if let Some(desired) = DesiredProcess::from_process(&settings, &limits) {
            self.active = Some(Active {
                ticket: None,
                restoring,
                job: Job::Apply(desired),
                step: 0,
            });
        }
    }

    /// Settings differ from the kept ones while the bridge holds remote control: the unit
    /// was power-cycled (or someone took over); re-apply.
    pub(super) fn check_revert(&mut self, now: Instant, read: &PowermaxProcess, core: &mut Core) {
        if self.active.is_some() || self.reapply_pending || !core.status.remote {
            return;
        }
        let Some(desired) = core.kept.powermax() else {
            return;
        };
        let Some(limits) = core.status.limits else {
            return;
        };
        let Some(desired) = DesiredProcess::from_process(&desired, &limits) else {
            return;
        };
        if !desired.matches(read) {
            core.status.remote = false;
            core.emit(LinkEvent::RemoteModeChanged { remote: false });
            self.reapply_pending = true;
            self.reapply_not_before = now;
        }
    }

    /// The last step of an Apply answered: compare and report.
    pub(super) fn confirm_settings(
        &mut self,
        now: Instant,
        desired: &DesiredProcess,
        response: &Response<'_>,
        reapplied: bool,
        core: &mut Core,
    ) -> Result<CommandOutput, CommandFailure> {
        let values = read_values(response);
        let verdict: Result<PowermaxProcess, ProcessFailure> = match self.variant {
            Variant::Sync => match values.and_then(sync::decode_process) {
                Some(read_back) if desired.matches(&read_back) => Ok(read_back),
                Some(read_back) => Err(ProcessFailure::ReadBackDiffers {
                    written: desired.as_process(),
                    read_back,
                }),
                None => Err(ProcessFailure::Transaction(TransactionError::Malformed)),
            },
            Variant::Legacy => match values.and_then(|v| v.get(0)).map(FaultCode) {
                Some(fault) => {
                    self.update_fault(now, fault, core);
                    if legacy::is_setting_fault(fault) {
                        Err(ProcessFailure::RejectedByUnit { fault })
                    } else {
                        Ok(desired.as_process())
                    }
                }
                None => Err(ProcessFailure::Transaction(TransactionError::Malformed)),
            },
        };
        match verdict {
            Ok(read_back) => {
                core.kept.confirmed(desired.as_process());
                core.status.settings = Some(read_back);
                if !core.status.remote {
                    core.status.remote = true;
                    core.emit(LinkEvent::RemoteModeChanged { remote: true });
                }
                core.emit(LinkEvent::ProcessApplied {
                    settings: read_back,
                    reapplied,
                });
                Ok(CommandOutput::Process(read_back))
            }
            Err(reason) => {
                core.emit(LinkEvent::ProcessFailed { reason });
                if reapplied {
                    self.reapply_pending = true;
                    self.reapply_not_before = now + REAPPLY_BACKOFF;
                }
                Err(CommandFailure::Process(reason))
            }
        }
    }
}

pub(super) fn legacy_writes(desired: &DesiredProcess) -> heapless::Vec<MbRequest, 4> {
    let limits = Limits {
        modes: None,
        min_current: desired.current,
        max_current: desired.current,
        min_pressure: desired.legacy_first_pressure,
        max_pressure: desired.legacy_first_pressure,
    };
    legacy::settings_writes(desired.mode, desired.current, desired.pressure, &limits)
}

#[cfg(test)]
mod tests;
