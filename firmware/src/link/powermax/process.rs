//! The settings the CNC asked for: checked against the permitted limits, written and read
//! back, kept, and re-applied when the link returns (after the unit's own power cycle only
//! when configured, see `kept`).

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

    /// True when `read` shows these settings.
    fn matches(&self, read: &PowermaxProcess) -> bool {
        shows(&self.as_process(), read)
    }
}

/// True when the settings `read` show `kept` (automatic pressure reads back as whatever the
/// unit chose).
fn shows(kept: &PowermaxProcess, read: &PowermaxProcess) -> bool {
    let pressure_ok = match kept.pressure {
        Pressure::Auto => true,
        Pressure::Set(_) => read.pressure == kept.pressure,
    };
    kept.mode.is_some() && read.mode == kept.mode && read.current == kept.current && pressure_ok
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

    /// A poll read the unit's settings (`None`: a legacy unit that does not let its force
    /// registers be read). After the link returned, and while the bridge holds remote
    /// control, they are compared with the kept ones (see `kept`, "Power cycle or lost
    /// link"): the kept ones after a return, the link was lost, and they are re-applied;
    /// others, the unit was switched off and on.
    pub(super) fn check_revert(
        &mut self,
        now: Instant,
        read: Option<&PowermaxProcess>,
        core: &mut Core,
    ) {
        if self.active.is_some() || self.reapply_pending {
            return;
        }
        let returned = core::mem::take(&mut self.returned);
        let Some(kept) = core.kept.powermax() else {
            return;
        };
        // Unreadable settings cannot tell: as after a lost link.
        let kept_shown = read.is_none_or(|read| shows(&kept, read));
        let reapply = if kept_shown {
            returned
        } else if returned || core.status.remote {
            core.unit_power_cycled()
        } else {
            false
        };
        if reapply {
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
                // What the unit shows now is what the CNC set: nothing left to tell apart.
                self.returned = false;
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
