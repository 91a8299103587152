//! How a setting the unit only acknowledges is confirmed. 095 SET_ALL_PARAMETERS and 078
//! SET_ALL_GAS_FLOWS answer "1 = accepted" and nothing else (HPR manual lines 165, 180), where
//! 058 and 070 answer with the value set. So after the acknowledgement the link reads the values
//! back with the manual's read commands, one after the other, and the setting counts (and is
//! kept) only when every read shows what was sent:
//! - HPR 078: 099 GET_GAS_FLOWS, the six set points (line 192; "Auto Gas System", like 078).
//! - HPR 095: 099 for the set points, 097 READ_CORNER_CURRENT (line 186), 098
//!   GET_INLET_GASES for the plasma gas and 079 GET_PS_INFO for the current set point. Not the
//!   shield gas: for some marking processes "the system may override the shield gas type code"
//!   (098, line 187).
//! - MaxPro200 095 and 078: 079 GET_PS_INFO, whose MaxPro200 form carries the gases, both
//!   pressure set points and the current set point (line 168).

use plasma_protocol::hpr::{Reply, Request};

/// The reads that confirm `request`, in the order they are sent (none: the reply to the
/// setting itself says whether it took).
pub(super) fn reads(request: &Request) -> &'static [Request] {
    match request {
        Request::SetAllGasFlows(_) => &[Request::GetGasFlows],
        Request::SetAllParameters(_) => &[
            Request::GetGasFlows,
            Request::ReadCornerCurrent,
            Request::GetInletGases,
            Request::GetPsInfo,
        ],
        Request::SetAllParametersMaxPro200(_) | Request::SetAllGasFlowsMaxPro200(_) => {
            &[Request::GetPsInfo]
        }
        _ => &[],
    }
}

/// Whether `reply`, the answer to one of [`reads`]`(request)`, shows what `request` set.
pub(super) fn shows(request: &Request, reply: Option<&Reply<'_>>) -> bool {
    match (request, reply) {
        (Request::SetAllGasFlows(set), Some(Reply::GasFlows(read))) => read == set,
        (Request::SetAllParameters(set), Some(reply)) => match reply {
            Reply::GasFlows(read) => *read == set.flows,
            Reply::CornerCurrent(read) => *read == u16::from(set.corner_percent),
            Reply::InletGases(read) => read.plasma == set.gases.plasma,
            Reply::PsInfo(read) => read.current_setpoint == set.amps,
            _ => false,
        },
        (Request::SetAllParametersMaxPro200(set), Some(Reply::MaxProPsInfo(read))) => {
            read.current_setpoint == set.amps
                && read.plasma_gas == set.gases.plasma
                && read.shield_gas == set.gases.shield
                && read.plasma_setpoint == set.pressures.plasma
                && read.shield_setpoint == set.pressures.shield
        }
        (Request::SetAllGasFlowsMaxPro200(set), Some(Reply::MaxProPsInfo(read))) => {
            read.plasma_setpoint == set.plasma && read.shield_setpoint == set.shield
        }
        _ => false,
    }
}
