//! A command checked against the manual's rules and the unit's rating before it is queued:
//! nothing the unit would refuse, and nothing off the allow-list, is ever sent.

use heapless::Vec;
use plasma_protocol::hpr::command::id;
use plasma_protocol::hpr::{self, Frame, GasCode, GasFlows, GasPair, Request, StateCode, SystemId};
use plasma_protocol::time::Instant;

use super::super::Core;
use super::super::command::{HprGasFlow, HprValue, LinkCommand, Refusal};
use super::super::event::{CommandOutput, LinkEvent, Ticket};
use super::super::support;
use super::{HprDriver, HprJob, SLOW_ALL, is_cutting};

impl HprDriver {
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
        if !support::accepts(family, command.op()) {
            return Err(unsupported);
        }
        let state = core.status.hpr.state;
        let error = core.status.hpr.error;
        let forbidden = Refusal::StateForbids { state, error };
        let request = match command {
            LinkCommand::HprSetNominalAmps { amps } => {
                check_amps(*amps, self.max_amps())?;
                Request::SetNominalAmps { amps: *amps }
            }
            LinkCommand::HprSetProcess { amps, gases } => {
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
                if !auto_console {
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
                check_corner(*percent)?;
                Request::SetCornerCurrent { percent: *percent }
            }
            LinkCommand::HprClearWarnings => Request::ClearWarnings,
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
            LinkCommand::HprReadErrorLog => Request::ReadErrorLog,
            LinkCommand::HprReadTimers => Request::GetTimerCounter,
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
            // The support table routes no other command to an HPR or MaxPro200.
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
