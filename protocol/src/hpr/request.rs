//! Typed requests for the commands a CNC uses, emitted into a caller buffer and parsed back
//! (the simulator parses what the bridge sends).
//!
//! Data is written as the manual's samples show it: amps, percent, gas codes and modes
//! without padding (`>05813031<`, `>0961 626<`), HPR pressure setpoints with two digits
//! (`>07855 45 35 25 50 50AB<`, `... 35 25 00 0084<`), MaxPro200 pressure setpoints with
//! four (`"0050"`). Parsing accepts any padding. Values outside the manual's ranges are
//! refused both ways with [`Error::Malformed`], so the bridge cannot send them.

use super::command::id;
use super::diagnostics::DiagnosticRead;
use super::field::{DataWriter, Fields, field_count};
use super::frame::Frame;
use super::gas::GasCode;
use super::values::{
    GasFlows, GasPair, HprParameters, LeakCheckMode, MAX_FLOW_PSI, MaxProParameters,
    MaxProPressures, TestMode, in_range,
};
use crate::{Error, Result};

/// Lowest current setpoint of 058/095/137 (amps).
pub const MIN_AMPS: u16 = 5;
/// Highest current setpoint of 058/095 on any HPR (HPR400).
pub const MAX_HPR_AMPS: u16 = 400;
/// Highest current setpoint on a MaxPro200.
pub const MAX_MAXPRO_AMPS: u16 = 200;
/// Corner current range of 070/095 (percent).
pub const CORNER_PERCENT: core::ops::RangeInclusive<u8> = 50..=100;
/// Highest multi-drop system id (dipswitches; 4-7 are reserved).
pub const MAX_SYSTEM_ID: u8 = 3;

/// A command the bridge sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Request {
    /// 000 HELLO: identify the system.
    Hello,
    /// 001 VERSION: firmware versions.
    Version,
    /// 002 GET_STATE.
    GetState,
    /// 003 CURRENT_ERROR.
    CurrentError,
    /// 004 REMOTE_MODE: switch to remote control.
    RemoteMode,
    /// 028 READ_PLASMA_AMPS: actual current.
    ReadPlasmaAmps,
    /// 058 SET_NOMINAL_AMPS, 5-400 A (HPR and MaxPro200).
    SetNominalAmps {
        /// Current setpoint, amps.
        amps: u16,
    },
    /// 064 GAS_PREFLOW_TEST_START.
    GasPreflowTestStart,
    /// 065 GAS_PREFLOW_TEST_STOP.
    GasPreflowTestStop,
    /// 066 GAS_CUTFLOW_TEST_START.
    GasCutflowTestStart,
    /// 067 GAS_CUTFLOW_TEST_STOP.
    GasCutflowTestStop,
    /// 068 SOFTWARE_RESET: clear errors.
    SoftwareReset,
    /// 070 SET_CORNER_CURRENT, 50-100 % of cutting current.
    SetCornerCurrent {
        /// Percent.
        percent: u8,
    },
    /// 072 GET_CONTROL_VOLTAGE.
    GetControlVoltage,
    /// 074 GET_IO_STATUS.
    GetIoStatus,
    /// 078 SET_ALL_GAS_FLOWS, HPR form (six setpoints).
    SetAllGasFlows(GasFlows),
    /// 078 SET_ALL_GAS_FLOWS, MaxPro200 form (two setpoints).
    SetAllGasFlowsMaxPro200(MaxProPressures),
    /// 079 GET_PS_INFO.
    GetPsInfo,
    /// 085 WAKE: enable the transmitter of system 0-3 on a multi-drop line.
    Wake {
        /// Dipswitch system id.
        system_id: u8,
    },
    /// 086 SLEEP: every system on the line disconnects its transmitter. No reply.
    Sleep,
    /// 087 BROADCAST MODE: every system listens, none replies. No reply.
    BroadcastMode,
    /// 094 READ_GAS_PRESSURES.
    ReadGasPressures,
    /// 095 SET_ALL_PARAMETERS, HPR form (ten values).
    SetAllParameters(HprParameters),
    /// 095 SET_ALL_PARAMETERS, MaxPro200 form (five values).
    SetAllParametersMaxPro200(MaxProParameters),
    /// 096 SET_INLET_GASES.
    SetInletGases(GasPair),
    /// 097 READ_CORNER_CURRENT.
    ReadCornerCurrent,
    /// 098 GET_INLET_GASES.
    GetInletGases,
    /// 099 GET_GAS_FLOWS.
    GetGasFlows,
    /// 121 LEAK_CHECK_MODE.
    LeakCheckMode(LeakCheckMode),
    /// 122 READ_GAS_SWITCH.
    ReadGasSwitch,
    /// 125 GET_TIMER_COUNTER.
    GetTimerCounter,
    /// 131 CLEAR WARNINGS: clear error codes below 43.
    ClearWarnings,
    /// 134 READ ERROR LOG.
    ReadErrorLog,
    /// 136 SERIAL RESPONSE DELAY: add about 1 ms before every reply.
    SerialResponseDelay {
        /// Enable (1) or disable (0) the delay.
        enabled: bool,
    },
    /// 137 SET PROCESS (MaxPro200): current and gases; the supply sets the pressures.
    SetProcess {
        /// Current setpoint, 5-200 A.
        amps: u16,
        /// Plasma and shield gases.
        gases: GasPair,
    },
    /// 138 IS SYSTEM READY FOR START (MaxPro200).
    IsSystemReadyForStart,
    /// 143 SET TEST MODE (MaxPro200).
    SetTestMode(TestMode),
    /// 145 READ TORCH ID (MaxPro200).
    ReadTorchId,
    /// 100, 117, 132, 133, 141, 142: a diagnostic read (host tools only, feature
    /// `diagnostics`, except 141: the bridge reads a MaxPro200's measured pressures).
    ReadDiagnostic(DiagnosticRead),
}

fn gas(code: GasCode) -> Result<u32> {
    in_range(u32::from(code.0), 0, u32::from(GasCode::MAX))
}

fn parse_gas(fields: &mut Fields<'_>) -> Result<GasCode> {
    fields.number(2, 0, u32::from(GasCode::MAX)).map(GasCode)
}

fn parse_gases(fields: &mut Fields<'_>) -> Result<GasPair> {
    Ok(GasPair {
        plasma: parse_gas(fields)?,
        shield: parse_gas(fields)?,
    })
}

fn write_gases(w: &mut DataWriter, g: &GasPair) -> Result<()> {
    w.field(gas(g.plasma)?, 1, 2)?;
    w.field(gas(g.shield)?, 1, 2)
}

fn write_hpr_flows(w: &mut DataWriter, f: &GasFlows) -> Result<()> {
    f.to_array().iter().enumerate().try_for_each(|(i, &v)| {
        let v = in_range(u32::from(v), 0, u32::from(GasFlows::limit(i)))?;
        w.field(v, 2, 3)
    })
}

fn parse_hpr_flows(fields: &mut Fields<'_>) -> Result<GasFlows> {
    let mut v = [0u16; 6];
    for (i, slot) in v.iter_mut().enumerate() {
        *slot = fields.number(3, 0, u32::from(GasFlows::limit(i)))?;
    }
    Ok(GasFlows::from_array(v))
}

fn write_maxpro_pressures(w: &mut DataWriter, p: &MaxProPressures) -> Result<()> {
    w.field(
        in_range(u32::from(p.plasma), 0, u32::from(MAX_FLOW_PSI))?,
        4,
        4,
    )?;
    w.field(
        in_range(u32::from(p.shield), 0, u32::from(MAX_FLOW_PSI))?,
        4,
        4,
    )
}

fn parse_maxpro_pressures(fields: &mut Fields<'_>) -> Result<MaxProPressures> {
    Ok(MaxProPressures {
        plasma: fields.number(4, 0, u32::from(MAX_FLOW_PSI))?,
        shield: fields.number(4, 0, u32::from(MAX_FLOW_PSI))?,
    })
}

impl Request {
    /// Command id this request is sent with.
    pub const fn id(&self) -> u16 {
        match self {
            Request::Hello => id::HELLO,
            Request::Version => id::VERSION,
            Request::GetState => id::GET_STATE,
            Request::CurrentError => id::CURRENT_ERROR,
            Request::RemoteMode => id::REMOTE_MODE,
            Request::ReadPlasmaAmps => id::READ_PLASMA_AMPS,
            Request::SetNominalAmps { .. } => id::SET_NOMINAL_AMPS,
            Request::GasPreflowTestStart => id::GAS_PREFLOW_TEST_START,
            Request::GasPreflowTestStop => id::GAS_PREFLOW_TEST_STOP,
            Request::GasCutflowTestStart => id::GAS_CUTFLOW_TEST_START,
            Request::GasCutflowTestStop => id::GAS_CUTFLOW_TEST_STOP,
            Request::SoftwareReset => id::SOFTWARE_RESET,
            Request::SetCornerCurrent { .. } => id::SET_CORNER_CURRENT,
            Request::GetControlVoltage => id::GET_CONTROL_VOLTAGE,
            Request::GetIoStatus => id::GET_IO_STATUS,
            Request::SetAllGasFlows(_) | Request::SetAllGasFlowsMaxPro200(_) => {
                id::SET_ALL_GAS_FLOWS
            }
            Request::GetPsInfo => id::GET_PS_INFO,
            Request::Wake { .. } => id::WAKE,
            Request::Sleep => id::SLEEP,
            Request::BroadcastMode => id::BROADCAST_MODE,
            Request::ReadGasPressures => id::READ_GAS_PRESSURES,
            Request::SetAllParameters(_) | Request::SetAllParametersMaxPro200(_) => {
                id::SET_ALL_PARAMETERS
            }
            Request::SetInletGases(_) => id::SET_INLET_GASES,
            Request::ReadCornerCurrent => id::READ_CORNER_CURRENT,
            Request::GetInletGases => id::GET_INLET_GASES,
            Request::GetGasFlows => id::GET_GAS_FLOWS,
            Request::LeakCheckMode(_) => id::LEAK_CHECK_MODE,
            Request::ReadGasSwitch => id::READ_GAS_SWITCH,
            Request::GetTimerCounter => id::GET_TIMER_COUNTER,
            Request::ClearWarnings => id::CLEAR_WARNINGS,
            Request::ReadErrorLog => id::READ_ERROR_LOG,
            Request::SerialResponseDelay { .. } => id::SERIAL_RESPONSE_DELAY,
            Request::SetProcess { .. } => id::SET_PROCESS,
            Request::IsSystemReadyForStart => id::IS_SYSTEM_READY_FOR_START,
            Request::SetTestMode(_) => id::SET_TEST_MODE,
            Request::ReadTorchId => id::READ_TORCH_ID,
            Request::ReadDiagnostic(read) => read.id(),
        }
    }

    /// False for 086 SLEEP and 087 BROADCAST MODE, which no system answers.
    pub const fn expects_reply(&self) -> bool {
        !matches!(self, Request::Sleep | Request::BroadcastMode)
    }

    fn write_data(&self, w: &mut DataWriter) -> Result<()> {
        match self {
            Request::SetNominalAmps { amps } => {
                let amps = in_range(u32::from(*amps), MIN_AMPS.into(), MAX_HPR_AMPS.into())?;
                w.field(amps, 1, 3)
            }
            Request::SetCornerCurrent { percent } => {
                let p = in_range(u32::from(*percent), 50, 100)?;
                w.field(p, 1, 3)
            }
            Request::SetAllGasFlows(flows) => write_hpr_flows(w, flows),
            Request::SetAllGasFlowsMaxPro200(p) => write_maxpro_pressures(w, p),
            Request::Wake { system_id } => w.field(
                in_range(u32::from(*system_id), 0, MAX_SYSTEM_ID.into())?,
                1,
                1,
            ),
            Request::SetAllParameters(p) => {
                w.field(
                    in_range(u32::from(p.amps), MIN_AMPS.into(), MAX_HPR_AMPS.into())?,
                    1,
                    3,
                )?;
                w.field(in_range(u32::from(p.corner_percent), 50, 100)?, 1, 3)?;
                write_gases(w, &p.gases)?;
                write_hpr_flows(w, &p.flows)
            }
            Request::SetAllParametersMaxPro200(p) => {
                w.field(
                    in_range(u32::from(p.amps), 0, MAX_MAXPRO_AMPS.into())?,
                    1,
                    3,
                )?;
                write_gases(w, &p.gases)?;
                // No sample exists for this form; pressures are written like the HPR form.
                w.field(
                    in_range(u32::from(p.pressures.plasma), 0, MAX_FLOW_PSI.into())?,
                    2,
                    2,
                )?;
                w.field(
                    in_range(u32::from(p.pressures.shield), 0, MAX_FLOW_PSI.into())?,
                    2,
                    2,
                )
            }
            Request::SetInletGases(g) => write_gases(w, g),
            Request::LeakCheckMode(m) => w.field(m.code().into(), 1, 1),
            Request::SerialResponseDelay { enabled } => w.field(u32::from(*enabled), 1, 1),
            Request::SetProcess { amps, gases } => {
                w.field(
                    in_range(u32::from(*amps), MIN_AMPS.into(), MAX_MAXPRO_AMPS.into())?,
                    1,
                    3,
                )?;
                write_gases(w, gases)
            }
            Request::SetTestMode(m) => w.field(m.code().into(), 1, 1),
            _ => Ok(()),
        }
    }

    /// Write the request frame into `out`; returns its length.
    ///
    /// Errors: [`Error::Malformed`] for a value outside the manual's range,
    /// [`Error::BufferTooSmall`] if `out` is too short.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize> {
        let mut w = DataWriter::new();
        self.write_data(&mut w)?;
        Frame::new(self.id(), w.as_bytes()).emit(out)
    }

    /// Parse a request frame (what a supply, or the simulator, receives).
    ///
    /// Errors: [`Error::Unsupported`] for ids this module does not type (including every
    /// factory-only or dangerous command), [`Error::Malformed`] for bad or out-of-range data.
    pub fn parse(frame: &Frame<'_>) -> Result<Request> {
        let data = frame.data;
        let mut f = Fields::new(data);
        let req = match frame.id {
            id::HELLO => Request::Hello,
            id::VERSION => Request::Version,
            id::GET_STATE => Request::GetState,
            id::CURRENT_ERROR => Request::CurrentError,
            id::REMOTE_MODE => Request::RemoteMode,
            id::READ_PLASMA_AMPS => Request::ReadPlasmaAmps,
            id::SET_NOMINAL_AMPS => Request::SetNominalAmps {
                amps: f.number(3, MIN_AMPS.into(), MAX_HPR_AMPS.into())?,
            },
            id::GAS_PREFLOW_TEST_START => Request::GasPreflowTestStart,
            id::GAS_PREFLOW_TEST_STOP => Request::GasPreflowTestStop,
            id::GAS_CUTFLOW_TEST_START => Request::GasCutflowTestStart,
            id::GAS_CUTFLOW_TEST_STOP => Request::GasCutflowTestStop,
            id::SOFTWARE_RESET => Request::SoftwareReset,
            id::SET_CORNER_CURRENT => Request::SetCornerCurrent {
                percent: f.number(3, 50, 100)?,
            },
            id::GET_CONTROL_VOLTAGE => Request::GetControlVoltage,
            id::GET_IO_STATUS => Request::GetIoStatus,
            // The two forms differ in their number of fields: six (HPR) or two (MaxPro200).
            id::SET_ALL_GAS_FLOWS => match field_count(data) {
                6 => Request::SetAllGasFlows(parse_hpr_flows(&mut f)?),
                2 => Request::SetAllGasFlowsMaxPro200(parse_maxpro_pressures(&mut f)?),
                _ => return Err(Error::Malformed),
            },
            id::GET_PS_INFO => Request::GetPsInfo,
            id::WAKE => Request::Wake {
                system_id: f.number(1, 0, MAX_SYSTEM_ID.into())?,
            },
            id::SLEEP => Request::Sleep,
            id::BROADCAST_MODE => Request::BroadcastMode,
            id::READ_GAS_PRESSURES => Request::ReadGasPressures,
            // Ten fields (HPR) or five (MaxPro200).
            id::SET_ALL_PARAMETERS => match field_count(data) {
                10 => Request::SetAllParameters(HprParameters {
                    amps: f.number(3, MIN_AMPS.into(), MAX_HPR_AMPS.into())?,
                    corner_percent: f.number(3, 50, 100)?,
                    gases: parse_gases(&mut f)?,
                    flows: parse_hpr_flows(&mut f)?,
                }),
                5 => Request::SetAllParametersMaxPro200(MaxProParameters {
                    amps: f.number(3, 0, MAX_MAXPRO_AMPS.into())?,
                    gases: parse_gases(&mut f)?,
                    pressures: parse_maxpro_pressures(&mut f)?,
                }),
                _ => return Err(Error::Malformed),
            },
            id::SET_INLET_GASES => Request::SetInletGases(parse_gases(&mut f)?),
            id::READ_CORNER_CURRENT => Request::ReadCornerCurrent,
            id::GET_INLET_GASES => Request::GetInletGases,
            id::GET_GAS_FLOWS => Request::GetGasFlows,
            id::LEAK_CHECK_MODE => {
                let code: u8 = f.number(1, 0, 3)?;
                Request::LeakCheckMode(LeakCheckMode::from_code(code).ok_or(Error::Malformed)?)
            }
            id::READ_GAS_SWITCH => Request::ReadGasSwitch,
            id::GET_TIMER_COUNTER => Request::GetTimerCounter,
            id::CLEAR_WARNINGS => Request::ClearWarnings,
            id::READ_ERROR_LOG => Request::ReadErrorLog,
            id::SERIAL_RESPONSE_DELAY => Request::SerialResponseDelay {
                enabled: f.number::<u8>(1, 0, 1)? == 1,
            },
            id::SET_PROCESS => Request::SetProcess {
                amps: f.number(3, MIN_AMPS.into(), MAX_MAXPRO_AMPS.into())?,
                gases: parse_gases(&mut f)?,
            },
            id::IS_SYSTEM_READY_FOR_START => Request::IsSystemReadyForStart,
            id::SET_TEST_MODE => {
                let code: u8 = f.number(1, 0, 6)?;
                Request::SetTestMode(TestMode::from_code(code).ok_or(Error::Malformed)?)
            }
            id::READ_TORCH_ID => Request::ReadTorchId,
            command => match DiagnosticRead::from_id(command) {
                Some(read) => Request::ReadDiagnostic(read),
                None => return Err(Error::Unsupported),
            },
        };
        if req.has_data() {
            f.end()?;
        } else if !data.is_empty() {
            return Err(Error::Malformed);
        }
        Ok(req)
    }

    const fn has_data(&self) -> bool {
        matches!(
            self,
            Request::SetNominalAmps { .. }
                | Request::SetCornerCurrent { .. }
                | Request::SetAllGasFlows(_)
                | Request::SetAllGasFlowsMaxPro200(_)
                | Request::Wake { .. }
                | Request::SetAllParameters(_)
                | Request::SetAllParametersMaxPro200(_)
                | Request::SetInletGases(_)
                | Request::LeakCheckMode(_)
                | Request::SerialResponseDelay { .. }
                | Request::SetProcess { .. }
                | Request::SetTestMode(_)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parse a seed frame as a request, check it equals `expected`, and check that emitting
    /// `expected` gives the seed frame byte for byte.
    #[track_caller]
    fn seed(frame: &[u8], expected: Request) {
        let f = Frame::parse(frame).unwrap();
        assert_eq!(Request::parse(&f), Ok(expected));
        let mut out = [0u8; 128];
        let n = expected.emit(&mut out).unwrap();
        assert_eq!(
            &out[..n],
            frame,
            "{}",
            core::str::from_utf8(&out[..n]).unwrap()
        );
    }

    #[test]
    fn seed_requests_without_data() {
        seed(b">00090<", Request::Hello);
        seed(b">00191<", Request::Version);
        seed(b">00292<", Request::GetState);
        seed(b">00393<", Request::CurrentError);
        seed(b">00494<", Request::RemoteMode);
        seed(b">0289A<", Request::ReadPlasmaAmps);
        seed(b">0649A<", Request::GasPreflowTestStart);
        seed(b">0659B<", Request::GasPreflowTestStop);
        seed(b">0669C<", Request::GasCutflowTestStart);
        seed(b">0679D<", Request::GasCutflowTestStop);
        seed(b">0689E<", Request::SoftwareReset);
        seed(b">07299<", Request::GetControlVoltage);
        seed(b">0749B<", Request::GetIoStatus);
        seed(b">079A0<", Request::GetPsInfo);
        seed(b">0869E<", Request::Sleep);
        seed(b">0879F<", Request::BroadcastMode);
        seed(b">0949D<", Request::ReadGasPressures);
        seed(b">097A0<", Request::ReadCornerCurrent);
        seed(b">098A1<", Request::GetInletGases);
        seed(b">099A2<", Request::GetGasFlows);
        seed(b">12295<", Request::ReadGasSwitch);
        seed(b">12598<", Request::GetTimerCounter);
        seed(b">13195<", Request::ClearWarnings);
        seed(b">13498<", Request::ReadErrorLog);
        seed(b">1389C<", Request::IsSystemReadyForStart);
        seed(b">1459A<", Request::ReadTorchId);
    }

    #[cfg(feature = "diagnostics")]
    #[test]
    fn seed_diagnostic_reads() {
        use crate::hpr::diagnostics::DiagnosticRead::*;
        // HPR manual (002_72b43a5685974c77.txt) lines 200, 239, 266 and 269.
        seed(b">10091<", Request::ReadDiagnostic(ControlData));
        seed(b">11799<", Request::ReadDiagnostic(GasInputs));
        seed(b">13296<", Request::ReadDiagnostic(CoolantPressure));
        seed(b">13397<", Request::ReadDiagnostic(ControlData3));
        // 141 and 142 have no sample (lines 289-290); the checksum is the sum of the id digits.
        seed(b">14196<", Request::ReadDiagnostic(MfgData1));
        seed(b">14297<", Request::ReadDiagnostic(MfgData2));
        // With data, none of them is a request.
        let f = Frame::parse(b">13280FE<").unwrap();
        assert_eq!(Request::parse(&f), Err(Error::Malformed));
    }

    #[test]
    fn seed_requests_with_data() {
        seed(b">05813031<", Request::SetNominalAmps { amps: 130 });
        seed(b">0707503<", Request::SetCornerCurrent { percent: 75 });
        seed(
            b">07855 45 35 25 50 50AB<",
            Request::SetAllGasFlows(GasFlows::from_array([55, 45, 35, 25, 50, 50])),
        );
        seed(b">0850CD<", Request::Wake { system_id: 0 });
        seed(
            b">095100 75 1 6 55 45 35 25 00 0084<",
            Request::SetAllParameters(HprParameters {
                amps: 100,
                corner_percent: 75,
                gases: GasPair {
                    plasma: GasCode::OXYGEN,
                    shield: GasCode::NITROGEN,
                },
                flows: GasFlows::from_array([55, 45, 35, 25, 0, 0]),
            }),
        );
        // "Set plasma gas = O2 and set shield gas = N2".
        seed(
            b">0961 626<",
            Request::SetInletGases(GasPair {
                plasma: GasCode::OXYGEN,
                shield: GasCode::NITROGEN,
            }),
        );
        seed(
            b">1211C5<",
            Request::LeakCheckMode(LeakCheckMode::InletLeak),
        );
        seed(b">1360CA<", Request::SerialResponseDelay { enabled: false });
        seed(b">1361CB<", Request::SerialResponseDelay { enabled: true });
        seed(
            b">137200 5 5D7<",
            Request::SetProcess {
                amps: 200,
                gases: GasPair {
                    plasma: GasCode::AIR,
                    shield: GasCode::AIR,
                },
            },
        );
        seed(b">1431C9<", Request::SetTestMode(TestMode::TestGas));
    }

    #[test]
    fn maxpro_forms() {
        let mut out = [0u8; 64];
        let r = Request::SetAllGasFlowsMaxPro200(MaxProPressures {
            plasma: 50,
            shield: 58,
        });
        let n = r.emit(&mut out).unwrap();
        assert_eq!(&out[4..n - 3], b"0050 0058");
        assert_eq!(Request::parse(&Frame::parse(&out[..n]).unwrap()), Ok(r));
        let r = Request::SetAllParametersMaxPro200(MaxProParameters {
            amps: 200,
            gases: GasPair {
                plasma: GasCode::AIR,
                shield: GasCode::AIR,
            },
            pressures: MaxProPressures {
                plasma: 56,
                shield: 58,
            },
        });
        let n = r.emit(&mut out).unwrap();
        assert_eq!(&out[4..n - 3], b"200 5 5 56 58");
        assert_eq!(Request::parse(&Frame::parse(&out[..n]).unwrap()), Ok(r));
    }

    #[test]
    fn out_of_range_values_are_refused() {
        let mut out = [0u8; 64];
        for r in [
            Request::SetNominalAmps { amps: 4 },
            Request::SetNominalAmps { amps: 401 },
            Request::SetCornerCurrent { percent: 49 },
            Request::SetCornerCurrent { percent: 101 },
            Request::Wake { system_id: 4 },
            Request::SetAllGasFlows(GasFlows::from_array([100, 0, 0, 0, 0, 0])),
            Request::SetAllGasFlows(GasFlows::from_array([0, 0, 0, 0, 0, 101])),
            Request::SetAllGasFlowsMaxPro200(MaxProPressures {
                plasma: 100,
                shield: 0,
            }),
            Request::SetInletGases(GasPair {
                plasma: GasCode(13),
                shield: GasCode::AIR,
            }),
            Request::SetProcess {
                amps: 201,
                gases: GasPair {
                    plasma: GasCode::AIR,
                    shield: GasCode::AIR,
                },
            },
        ] {
            assert_eq!(r.emit(&mut out), Err(Error::Malformed), "{r:?}");
        }
        let parse = |b: &[u8]| Request::parse(&Frame::parse(b).unwrap());
        // Valid frames (checksums computed) carrying values the manual does not allow.
        let mut buf = [0u8; 64];
        let mut frame = |id, data: &[u8]| {
            let n = Frame::new(id, data).emit(&mut buf).unwrap();
            parse(&buf[..n])
        };
        assert_eq!(frame(58, b"401"), Err(Error::Malformed));
        assert_eq!(frame(58, b""), Err(Error::Malformed));
        assert_eq!(frame(58, b"130 1"), Err(Error::Malformed));
        assert_eq!(frame(85, b"4"), Err(Error::Malformed));
        assert_eq!(frame(78, b"1 2 3"), Err(Error::Malformed));
        assert_eq!(frame(95, b"100 75 1 6"), Err(Error::Malformed));
        assert_eq!(frame(2, b"1"), Err(Error::Malformed));
        assert_eq!(frame(121, b"4"), Err(Error::Malformed));
        assert_eq!(frame(143, b"7"), Err(Error::Malformed));
        assert_eq!(frame(120, b""), Err(Error::Unsupported));
        assert_eq!(frame(999, b""), Err(Error::Unsupported));
        // 500/501 are replies, never requests.
        assert_eq!(frame(500, b""), Err(Error::Unsupported));
    }

    #[test]
    fn multi_drop_sequence() {
        // Section II.e: SLEEP puts every system to sleep, WAKE + id wakes one (ids 0-3).
        let mut out = [0u8; 16];
        let n = Request::Sleep.emit(&mut out).unwrap();
        assert_eq!(&out[..n], b">0869E<");
        let expected: [&[u8]; 4] = [b">0850CD<", b">0851CE<", b">0852CF<", b">0853D0<"];
        for (system_id, frame) in (0..=MAX_SYSTEM_ID).zip(expected) {
            let n = Request::Wake { system_id }.emit(&mut out).unwrap();
            assert_eq!(&out[..n], frame);
        }
        assert_eq!(
            Request::Wake { system_id: 4 }.emit(&mut out),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn sleep_and_broadcast_expect_no_reply() {
        assert!(!Request::Sleep.expects_reply());
        assert!(!Request::BroadcastMode.expects_reply());
        assert!(Request::Wake { system_id: 3 }.expects_reply());
    }
}
