//! A command checked against the manual's rules and the unit's rating before it is queued:
//! nothing the unit would refuse, and nothing off the allow-list, is ever sent.

use heapless::Vec;
use plasma_protocol::hpr::command::id;
use plasma_protocol::hpr::{
    self, Frame, GasCode, GasFlows, GasPair, MAX_FLOW_PSI, MaxProPressures, Request, StateCode,
    TestMode,
};
use plasma_protocol::time::Instant;

use super::{HprDriver, HprJob, is_cutting, slow_items};
use crate::link::command::{HprValue, LinkCommand, Refusal};
use crate::link::core::Core;
use crate::link::event::{CommandOutput, LinkEvent, Ticket};

impl HprDriver {
    /// Validate and queue a command.
    pub(crate) fn submit(
        &mut self,
        now: Instant,
        ticket: Ticket,
        command: &LinkCommand<'_>,
        core: &mut Core,
    ) -> Result<(), Refusal> {
        self.now = now;
        if !command.runs_on(self.family()) {
            return Err(self.unsupported());
        }
        let job = match command {
            LinkCommand::RefreshSlowData => return self.refresh_slow_data(ticket, core),
            LinkCommand::Raw(bytes) => parse_raw(bytes)?,
            command => HprJob::Typed(checked(self.settings_request(command, core)?)?),
        };
        // Nothing the unit's gas console (or the MaxPro200) does not take is sent.
        let id = match &job {
            HprJob::Typed(request) => request.id(),
            HprJob::Raw { id, .. } => *id,
        };
        if !hpr::accepts(id, &self.system) {
            return Err(Refusal::NotOnThisSystem {
                id,
                system: self.system,
            });
        }
        self.queue
            .push_back((ticket, job))
            .map_err(|_| Refusal::QueueFull)
    }

    /// Read the slow data again: the error log and timers (a MaxPro200 has none: done).
    fn refresh_slow_data(&mut self, ticket: Ticket, core: &mut Core) -> Result<(), Refusal> {
        if self.maxpro() {
            core.emit(LinkEvent::CommandDone {
                ticket,
                result: Ok(CommandOutput::Done),
            });
            return Ok(());
        }
        self.slow.request_for(ticket, slow_items(&self.system))
    }

    /// The request a setting command becomes, checked against the unit's rating, the
    /// manual's ranges and the state; other commands go on to [`Self::service_request`].
    fn settings_request(&self, command: &LinkCommand<'_>, core: &Core) -> Result<Request, Refusal> {
        let state = core.status.hpr.state;
        Ok(match command {
            LinkCommand::HprSetNominalAmps { amps } => {
                check_amps(*amps, self.max_amps())?;
                Request::SetNominalAmps { amps: *amps }
            }
            LinkCommand::HprSetInletGases(gases) => {
                check_gases(gases)?;
                if is_cutting(state) {
                    return Err(forbidden(core));
                }
                Request::SetInletGases(*gases)
            }
            // "Only accepted when the system is in state #2 or #3" (line 275).
            LinkCommand::MaxProSetProcess { amps, gases } => {
                check_amps(*amps, self.max_amps())?;
                check_gases(gases)?;
                if !state.is_some_and(|s| matches!(s.0, 2 | 3)) {
                    return Err(forbidden(core));
                }
                Request::SetProcess {
                    amps: *amps,
                    gases: *gases,
                }
            }
            LinkCommand::HprSetCornerCurrent { percent } => {
                check_corner(*percent)?;
                Request::SetCornerCurrent { percent: *percent }
            }
            // "Gas type changes are not allowed when the system is cutting (state 4 - state
            // 10)" (line 180).
            LinkCommand::HprSetAllParameters(p) => {
                check_amps(p.amps, self.max_amps())?;
                check_corner(p.corner_percent)?;
                check_gases(&p.gases)?;
                check_flows(&p.flows)?;
                if is_cutting(state) {
                    return Err(forbidden(core));
                }
                Request::SetAllParameters(*p)
            }
            // The MaxPro200 answers "2 = data invalid or system not in state #2 or #3" (line
            // 180).
            LinkCommand::MaxProSetAllParameters(p) => {
                check_amps(p.amps, self.max_amps())?;
                check_gases(&p.gases)?;
                check_pressures(&p.pressures)?;
                if !state.is_some_and(|s| matches!(s.0, 2 | 3)) {
                    return Err(forbidden(core));
                }
                Request::SetAllParametersMaxPro200(*p)
            }
            // 078 names no state it needs (line 165).
            LinkCommand::HprSetAllGasFlows(flows) => {
                check_flows(flows)?;
                Request::SetAllGasFlows(*flows)
            }
            LinkCommand::MaxProSetAllGasFlows(pressures) => {
                check_pressures(pressures)?;
                Request::SetAllGasFlowsMaxPro200(*pressures)
            }
            command => return self.service_request(command, core),
        })
    }

    /// The request a command that sets nothing becomes (warnings, reset, gas test, logs),
    /// checked against the family and the state.
    fn service_request(&self, command: &LinkCommand<'_>, core: &Core) -> Result<Request, Refusal> {
        let (state, error) = (core.status.hpr.state, core.status.hpr.error);
        Ok(match command {
            LinkCommand::HprClearWarnings => Request::ClearWarnings,
            LinkCommand::HprSoftwareReset => {
                let allowed = if self.maxpro() {
                    // "only valid when the system is not cutting".
                    state.is_some() && !is_cutting(state)
                } else {
                    // "Only accepted if ... Error code > 79 and State = 14".
                    state == Some(StateCode(14)) && error.is_some_and(|e| e.is_shutdown_error())
                };
                if !allowed {
                    return Err(forbidden(core));
                }
                Request::SoftwareReset
            }
            // "Not allowed when cutting" (lines 150-155).
            LinkCommand::HprGasTest { cutflow, on } => {
                if is_cutting(state) {
                    return Err(forbidden(core));
                }
                match (cutflow, on) {
                    (false, true) => Request::GasPreflowTestStart,
                    (false, false) => Request::GasPreflowTestStop,
                    (true, true) => Request::GasCutflowTestStart,
                    (true, false) => Request::GasCutflowTestStop,
                }
            }
            // 143 starts a test "when the system is in state #3 - Ready for Start" (line 283);
            // mode 0 stops the gases, not while cutting.
            LinkCommand::MaxProTestGas { on } => {
                let allowed = if *on {
                    state == Some(StateCode(3))
                } else {
                    state.is_some() && !is_cutting(state)
                };
                if !allowed {
                    return Err(forbidden(core));
                }
                Request::SetTestMode(if *on {
                    TestMode::TestGas
                } else {
                    TestMode::None
                })
            }
            LinkCommand::HprReadGasPressures => Request::GetPsInfo,
            LinkCommand::MaxProReadGasPressures => {
                Request::ReadDiagnostic(hpr::DiagnosticRead::MfgData1)
            }
            LinkCommand::HprReadErrorLog => Request::ReadErrorLog,
            LinkCommand::HprReadTimers => Request::GetTimerCounter,
            // `runs_on` lets no other command through to an HPR or MaxPro200.
            _ => return Err(self.unsupported()),
        })
    }

    fn unsupported(&self) -> Refusal {
        Refusal::NotSupported {
            family: self.family(),
        }
    }
}

/// The unit's state does not allow the command now.
fn forbidden(core: &Core) -> Refusal {
    Refusal::StateForbids {
        state: core.status.hpr.state,
        error: core.status.hpr.error,
    }
}

/// Belt and braces: every typed command is on the allow-list and encodes.
fn checked(request: Request) -> Result<Request, Refusal> {
    if !hpr::is_allowed(request.id()) {
        return Err(Refusal::RawCommandNotAllowed { id: request.id() });
    }
    let mut buf = [0u8; hpr::MAX_FRAME_LEN];
    request.emit(&mut buf).map_err(Refusal::RawMalformed)?;
    Ok(request)
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

/// The HPR's pressure set points: 0-99 psi, the two mix set points 0-100 (lines 165, 180).
fn check_flows(flows: &GasFlows) -> Result<(), Refusal> {
    for (i, psi) in flows.to_array().into_iter().enumerate() {
        check_range(HprValue::GasParameter, psi, 0, GasFlows::limit(i))?;
    }
    Ok(())
}

/// The MaxPro200's pressure set points, 0-99 psi (line 180).
fn check_pressures(pressures: &MaxProPressures) -> Result<(), Refusal> {
    for psi in [pressures.plasma, pressures.shield] {
        check_range(HprValue::GasParameter, psi, 0, MAX_FLOW_PSI)?;
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
