//! Typed replies to the commands a CNC uses, parsed from frames and emitted (the simulator
//! answers with them).
//!
//! A reply echoes its command's id, so the id alone selects the data format, except 079
//! GET_PS_INFO, whose HPR and MaxPro200 forms differ by their field tags (`PC0044 ...` vs
//! `st0003 ...`). Numbers are written the way the manual's samples show them: most with four
//! digits (`>002000052<`), error log entries with three, timer counters with seven, accept
//! flags and 121's test time without padding. Parsing accepts shorter fields too.

use super::command::id;
use super::diagnostics::{DiagnosticRead, DiagnosticReply};
use super::error_codes::ErrorCode;
use super::field::{DataWriter, Fields};
use super::frame::Frame;
use super::gas::GasCode;
use super::identity::SystemId;
use super::request::Request;
use super::state::StateCode;
use super::values::{GasFlows, GasPair, GasPressures, TorchId, in_range};
use crate::decimal::parse_decimal;
use crate::{Error, Result};

/// Answer of commands whose return value is "1 = accepted, 0 = not accepted".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Acceptance {
    /// `0`: not accepted.
    NotAccepted,
    /// `1`: accepted.
    Accepted,
    /// `2`: MaxPro200 095 and 137: data invalid, or the system is not in state 2 or 3.
    Invalid,
}

impl Acceptance {
    /// Wire value.
    pub const fn code(self) -> u8 {
        match self {
            Acceptance::NotAccepted => 0,
            Acceptance::Accepted => 1,
            Acceptance::Invalid => 2,
        }
    }

    /// From the wire value.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Acceptance::NotAccepted),
            1 => Some(Acceptance::Accepted),
            2 => Some(Acceptance::Invalid),
            _ => None,
        }
    }
}

/// Commands whose reply is an [`Acceptance`].
pub const ACK_COMMANDS: &[u16] = &[
    id::REMOTE_MODE,
    id::GAS_PREFLOW_TEST_START,
    id::GAS_PREFLOW_TEST_STOP,
    id::GAS_CUTFLOW_TEST_START,
    id::GAS_CUTFLOW_TEST_STOP,
    id::SOFTWARE_RESET,
    id::SET_ALL_GAS_FLOWS,
    id::SET_ALL_PARAMETERS,
    id::SET_INLET_GASES,
    id::CLEAR_WARNINGS,
    // 136: `>1360CA<` (disable) is answered `>1361CB<`, so the reply is an accept flag.
    id::SERIAL_RESPONSE_DELAY,
    id::SET_PROCESS,
];

/// 001 VERSION reply: power supply firmware, then gas console firmware, space delimited.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Version<'a> {
    /// Power supply firmware revision (e.g. `A.0`).
    pub power_supply: &'a str,
    /// Gas console firmware revision, when the reply has one.
    pub gas_console: Option<&'a str>,
}

/// 074 GET_IO_STATUS reply: DSP ports A-F, bit 7 first on the wire (`PA00000100` = 0x04).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IoStatus {
    /// Ports A..F; 1 = on.
    pub ports: [u8; 6],
}

const PORT_TAGS: [&[u8]; 6] = [b"PA", b"PB", b"PC", b"PD", b"PE", b"PF"];

/// 079 GET_PS_INFO reply, HPR form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PsInfo {
    /// Pressures, psi (the last four are not measured with a manual gas console).
    pub pressures: GasPressures,
    /// Current setpoint, amps (`CS`).
    pub current_setpoint: u16,
    /// System state (`ST`, table V, HPR column).
    pub state: StateCode,
    /// System error (`ER`, table IV).
    pub error: ErrorCode,
}

/// 079 GET_PS_INFO reply, MaxPro200 form.
///
/// The manual lists the fields and their tags (`st0003`, `er0000`, ...) but prints no sample
/// frame; they are taken to be space delimited like the HPR form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MaxProPsInfo {
    /// System state (`st`, table V, MaxPro200 column).
    pub state: StateCode,
    /// System error (`er`).
    pub error: ErrorCode,
    /// Plasma gas type (`pg`).
    pub plasma_gas: GasCode,
    /// Plasma pressure setpoint, psi (`ps`).
    pub plasma_setpoint: u16,
    /// Shield gas type (`sg`).
    pub shield_gas: GasCode,
    /// Shield pressure setpoint, psi (`ss`).
    pub shield_setpoint: u16,
    /// Current setpoint, amps (`cs`).
    pub current_setpoint: u16,
    /// Display mode (`dm`): 0 current, 1 error/status, 2 coolant flow, 3 test mode.
    pub display_mode: u16,
    /// Display locked (`lm`: 1 locked, 0 unlocked).
    pub locked: bool,
}

/// 125 GET_TIMER_COUNTER reply: seven fixed-width (7-digit) counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TimerCounter {
    /// Arc on time, seconds.
    pub arc_on_seconds: u32,
    /// System on time, minutes.
    pub system_on_minutes: u32,
    /// Total starts (arc transfers).
    pub starts: u32,
    /// Total starting errors (failed to transfer).
    pub start_errors: u32,
    /// Total rampdown errors.
    pub rampdown_errors: u32,
    /// Writes to the current memory block (diagnostics only).
    pub write_counter: u32,
    /// Current memory block (diagnostics only).
    pub memory_block: u32,
}

/// Largest value of a 7-digit counter.
pub const MAX_COUNTER: u32 = 9_999_999;

impl TimerCounter {
    /// The counters in wire order.
    pub const fn to_array(&self) -> [u32; 7] {
        [
            self.arc_on_seconds,
            self.system_on_minutes,
            self.starts,
            self.start_errors,
            self.rampdown_errors,
            self.write_counter,
            self.memory_block,
        ]
    }

    /// From the counters in wire order.
    pub const fn from_array(v: [u32; 7]) -> Self {
        let [a, b, c, d, e, f, g] = v;
        TimerCounter {
            arc_on_seconds: a,
            system_on_minutes: b,
            starts: c,
            start_errors: d,
            rampdown_errors: e,
            write_counter: f,
            memory_block: g,
        }
    }
}

/// A reply from the supply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reply<'a> {
    /// 000: which system this is.
    Hello(SystemId),
    /// 001: firmware versions.
    Version(Version<'a>),
    /// 002: state code (table V).
    State(StateCode),
    /// 003: current error code (table IV).
    CurrentError(ErrorCode),
    /// Accept flag of one of [`ACK_COMMANDS`].
    Ack {
        /// Command answered.
        command: u16,
        /// Its answer.
        result: Acceptance,
    },
    /// 028: actual current, amps.
    PlasmaAmps(u16),
    /// 058: current setpoint actually set, amps.
    NominalAmps(u16),
    /// 070: corner current achieved, percent.
    CornerCurrentSet(u16),
    /// 072: control voltage in tenths of a volt (1200 = 120.0 V).
    ControlVoltage(u16),
    /// 074: DSP port status.
    IoStatus(IoStatus),
    /// 079, HPR form.
    PsInfo(PsInfo),
    /// 079, MaxPro200 form.
    MaxProPsInfo(MaxProPsInfo),
    /// 085: the woken system echoes its id.
    Wake(u8),
    /// 094: measured pressures, psi.
    GasPressures(GasPressures),
    /// 097: corner current, percent.
    CornerCurrent(u16),
    /// 098: inlet gases the software uses.
    InletGases(GasPair),
    /// 099: pressure setpoints, psi.
    GasFlows(GasFlows),
    /// 121: test duration in seconds; 0 = not accepted.
    LeakCheck(u16),
    /// 122: gas selector switch positions.
    GasSwitch(GasPair),
    /// 125: timers and counters.
    TimerCounter(TimerCounter),
    /// 134: the last four errors, most recent first.
    ErrorLog([ErrorCode; 4]),
    /// 138: ready for a start signal.
    ReadyForStart(bool),
    /// 143: the reply digit. The only sample asks for mode 1 and gets `1`; the manual does
    /// not say whether it is an echo of the mode or an accept flag, so it is kept as is.
    SetTestMode(u8),
    /// 145: torch id.
    TorchId(TorchId),
    /// 100, 117, 132, 133, 141, 142: a diagnostic read (host tools only, feature
    /// `diagnostics`, except 141).
    Diagnostic(DiagnosticReply),
    /// 500: the command had a bad checksum.
    BadChecksum,
    /// 501: the command id is unknown.
    UnknownCommand,
}

fn tagged_field(f: &mut Fields<'_>, tag: &[u8]) -> Result<u16> {
    f.tagged(tag, 4)
}

fn parse_gas_pair(f: &mut Fields<'_>) -> Result<GasPair> {
    Ok(GasPair {
        plasma: GasCode(f.number(4, 0, 9999)?),
        shield: GasCode(f.number(4, 0, 9999)?),
    })
}

fn parse_io(f: &mut Fields<'_>) -> Result<IoStatus> {
    let mut io = IoStatus::default();
    for (port, tag) in io.ports.iter_mut().zip(PORT_TAGS) {
        let bits = f.next_field()?.strip_prefix(tag).ok_or(Error::Malformed)?;
        if bits.len() != 8 {
            return Err(Error::Malformed);
        }
        *port = bits.iter().try_fold(0u8, |acc, &b| match b {
            b'0' => Ok(acc << 1),
            b'1' => Ok(acc << 1 | 1),
            _ => Err(Error::Malformed),
        })?;
    }
    Ok(io)
}

fn parse_version(data: &[u8]) -> Result<Version<'_>> {
    let text = core::str::from_utf8(data).map_err(|_| Error::Malformed)?;
    // One space between the two revisions; none, a leading, trailing or doubled one is not
    // this reply. (Bytes, not `str::split`: one loop instead of core's generic splitter.)
    let (power_supply, gas_console) = match data.iter().position(|&b| b == b' ') {
        None => (text, None),
        Some(space) => {
            let power_supply = text.get(..space).ok_or(Error::Malformed)?;
            let gas_console = text.get(space + 1..).ok_or(Error::Malformed)?;
            if gas_console.is_empty() || gas_console.bytes().any(|b| b == b' ') {
                return Err(Error::Malformed);
            }
            (power_supply, Some(gas_console))
        }
    };
    if power_supply.is_empty() {
        return Err(Error::Malformed);
    }
    Ok(Version {
        power_supply,
        gas_console,
    })
}

/// The 4-digit fields with `tags`, in order: one loop rather than one inlined parse per field.
fn tagged_fields<const N: usize>(f: &mut Fields<'_>, tags: [&[u8; 2]; N]) -> Result<[u16; N]> {
    let mut values = [0u16; N];
    for (value, tag) in values.iter_mut().zip(tags) {
        *value = tagged_field(f, tag)?;
    }
    Ok(values)
}

fn parse_hpr_ps_info(f: &mut Fields<'_>) -> Result<PsInfo> {
    let [pc, pp, sc, sp, cs, st, er, cg1, cg2, mv1, mv2] = tagged_fields(
        f,
        [
            b"PC", b"PP", b"SC", b"SP", b"CS", b"ST", b"ER", b"CG", b"CG", b"MV", b"MV",
        ],
    )?;
    Ok(PsInfo {
        pressures: gas_pressures([pc, pp, sc, sp, cg1, cg2, mv1, mv2]),
        current_setpoint: cs,
        state: StateCode(st),
        error: ErrorCode(er),
    })
}

fn parse_maxpro_ps_info(f: &mut Fields<'_>) -> Result<MaxProPsInfo> {
    let [st, er, pg, ps, sg, ss, cs, dm, lm] = tagged_fields(
        f,
        [
            b"st", b"er", b"pg", b"ps", b"sg", b"ss", b"cs", b"dm", b"lm",
        ],
    )?;
    Ok(MaxProPsInfo {
        state: StateCode(st),
        error: ErrorCode(er),
        plasma_gas: GasCode(pg),
        plasma_setpoint: ps,
        shield_gas: GasCode(sg),
        shield_setpoint: ss,
        current_setpoint: cs,
        display_mode: dm,
        locked: match lm {
            0 => false,
            1 => true,
            _ => return Err(Error::Malformed),
        },
    })
}

fn parse_pressures(f: &mut Fields<'_>) -> Result<GasPressures> {
    tagged_fields(f, [b"PC", b"PP", b"SC", b"SP", b"CG", b"CG", b"MV", b"MV"]).map(gas_pressures)
}

/// The pressures in wire order (`PC PP SC SP CG CG MV MV`).
fn gas_pressures([pc, pp, sc, sp, cg1, cg2, mv1, mv2]: [u16; 8]) -> GasPressures {
    GasPressures {
        plasma_cutflow: pc,
        plasma_preflow: pp,
        shield_cutflow: sc,
        shield_preflow: sp,
        cut_gas_1: cg1,
        cut_gas_2: cg2,
        n2_mix_inlet: mv1,
        gas2_mix_inlet: mv2,
    }
}

fn write_pressures(w: &mut DataWriter, p: &GasPressures) -> Result<()> {
    w.tagged(b"PC", p.plasma_cutflow.into(), 4)?;
    w.tagged(b"PP", p.plasma_preflow.into(), 4)?;
    w.tagged(b"SC", p.shield_cutflow.into(), 4)?;
    w.tagged(b"SP", p.shield_preflow.into(), 4)?;
    w.tagged(b"CG", p.cut_gas_1.into(), 4)?;
    w.tagged(b"CG", p.cut_gas_2.into(), 4)?;
    w.tagged(b"MV", p.n2_mix_inlet.into(), 4)?;
    w.tagged(b"MV", p.gas2_mix_inlet.into(), 4)
}

/// A 4-digit number field.
fn four(w: &mut DataWriter, v: u16) -> Result<()> {
    w.field(v.into(), 4, 4)
}

impl<'a> Reply<'a> {
    /// Id of the reply frame (the command's id, or 500/501).
    pub const fn id(&self) -> u16 {
        match self {
            Reply::Hello(_) => id::HELLO,
            Reply::Version(_) => id::VERSION,
            Reply::State(_) => id::GET_STATE,
            Reply::CurrentError(_) => id::CURRENT_ERROR,
            Reply::Ack { command, .. } => *command,
            Reply::PlasmaAmps(_) => id::READ_PLASMA_AMPS,
            Reply::NominalAmps(_) => id::SET_NOMINAL_AMPS,
            Reply::CornerCurrentSet(_) => id::SET_CORNER_CURRENT,
            Reply::ControlVoltage(_) => id::GET_CONTROL_VOLTAGE,
            Reply::IoStatus(_) => id::GET_IO_STATUS,
            Reply::PsInfo(_) | Reply::MaxProPsInfo(_) => id::GET_PS_INFO,
            Reply::Wake(_) => id::WAKE,
            Reply::GasPressures(_) => id::READ_GAS_PRESSURES,
            Reply::CornerCurrent(_) => id::READ_CORNER_CURRENT,
            Reply::InletGases(_) => id::GET_INLET_GASES,
            Reply::GasFlows(_) => id::GET_GAS_FLOWS,
            Reply::LeakCheck(_) => id::LEAK_CHECK_MODE,
            Reply::GasSwitch(_) => id::READ_GAS_SWITCH,
            Reply::TimerCounter(_) => id::GET_TIMER_COUNTER,
            Reply::Diagnostic(d) => d.id(),
            Reply::ErrorLog(_) => id::READ_ERROR_LOG,
            Reply::ReadyForStart(_) => id::IS_SYSTEM_READY_FOR_START,
            Reply::SetTestMode(_) => id::SET_TEST_MODE,
            Reply::TorchId(_) => id::READ_TORCH_ID,
            Reply::BadChecksum => id::BAD_CHECKSUM,
            Reply::UnknownCommand => id::UNKNOWN_COMMAND,
        }
    }

    /// Parse a reply frame; the id selects the format.
    ///
    /// Errors: [`Error::Unsupported`] for ids without a typed reply (factory commands, 086,
    /// 087) or an unknown HELLO identity; [`Error::Malformed`] for bad data.
    pub fn parse(frame: &Frame<'a>) -> Result<Reply<'a>> {
        let data = frame.data;
        let mut f = Fields::new(data);
        let reply = match frame.id {
            id::HELLO => return SystemId::parse(data).map(Reply::Hello),
            id::VERSION => return parse_version(data).map(Reply::Version),
            id::BAD_CHECKSUM | id::UNKNOWN_COMMAND => {
                if !data.is_empty() {
                    return Err(Error::Malformed);
                }
                return Ok(if frame.id == id::BAD_CHECKSUM {
                    Reply::BadChecksum
                } else {
                    Reply::UnknownCommand
                });
            }
            id::GET_STATE => Reply::State(StateCode(f.number(4, 0, 9999)?)),
            id::CURRENT_ERROR => Reply::CurrentError(ErrorCode(f.number(4, 0, 9999)?)),
            command if ACK_COMMANDS.contains(&command) => {
                let code: u8 = f.number(1, 0, 2)?;
                Reply::Ack {
                    command,
                    result: Acceptance::from_code(code).ok_or(Error::Malformed)?,
                }
            }
            id::READ_PLASMA_AMPS => Reply::PlasmaAmps(f.number(4, 0, 9999)?),
            id::SET_NOMINAL_AMPS => Reply::NominalAmps(f.number(4, 0, 9999)?),
            id::SET_CORNER_CURRENT => Reply::CornerCurrentSet(f.number(4, 0, 9999)?),
            id::GET_CONTROL_VOLTAGE => Reply::ControlVoltage(f.number(4, 0, 9999)?),
            id::GET_IO_STATUS => Reply::IoStatus(parse_io(&mut f)?),
            id::GET_PS_INFO => {
                if data.first().is_some_and(u8::is_ascii_lowercase) {
                    Reply::MaxProPsInfo(parse_maxpro_ps_info(&mut f)?)
                } else {
                    Reply::PsInfo(parse_hpr_ps_info(&mut f)?)
                }
            }
            id::WAKE => Reply::Wake(f.number(1, 0, 9)?),
            id::READ_GAS_PRESSURES => Reply::GasPressures(parse_pressures(&mut f)?),
            id::READ_CORNER_CURRENT => Reply::CornerCurrent(f.number(4, 0, 9999)?),
            id::GET_INLET_GASES => Reply::InletGases(parse_gas_pair(&mut f)?),
            id::GET_GAS_FLOWS => {
                let mut v = [0u16; 6];
                for slot in &mut v {
                    *slot = f.number(4, 0, 9999)?;
                }
                Reply::GasFlows(GasFlows::from_array(v))
            }
            command if DiagnosticRead::from_id(command).is_some() => {
                Reply::Diagnostic(DiagnosticReply::parse(command, data, &mut f)?)
            }
            id::LEAK_CHECK_MODE => Reply::LeakCheck(f.number(4, 0, 9999)?),
            id::READ_GAS_SWITCH => Reply::GasSwitch(parse_gas_pair(&mut f)?),
            id::GET_TIMER_COUNTER => {
                // Every field is "7 numbers followed by a space", so the last one may carry
                // a trailing space; accept it with or without.
                let trimmed = data.strip_suffix(b" ").unwrap_or(data);
                let mut f = Fields::new(trimmed);
                let mut v = [0u32; 7];
                for slot in &mut v {
                    *slot = parse_decimal(f.next_field()?, 7)?;
                }
                f.end()?;
                return Ok(Reply::TimerCounter(TimerCounter::from_array(v)));
            }
            id::READ_ERROR_LOG => {
                let mut log = [ErrorCode::NONE; 4];
                for slot in &mut log {
                    *slot = ErrorCode(f.number(3, 0, 999)?);
                }
                Reply::ErrorLog(log)
            }
            id::IS_SYSTEM_READY_FOR_START => Reply::ReadyForStart(f.number::<u8>(1, 0, 1)? == 1),
            id::SET_TEST_MODE => Reply::SetTestMode(f.number(1, 0, 9)?),
            id::READ_TORCH_ID => Reply::TorchId(TorchId(f.number(4, 0, 9999)?)),
            _ => return Err(Error::Unsupported),
        };
        f.end()?;
        Ok(reply)
    }

    /// Parse `frame` as the answer to `request`.
    ///
    /// 500/501 answer any request. Errors: [`Error::Mismatch`] if the frame's id is not the
    /// request's, or the request gets no reply (086, 087); otherwise as [`parse`](Self::parse).
    pub fn parse_for(request: &Request, frame: &Frame<'a>) -> Result<Reply<'a>> {
        let error_reply = frame.id == id::BAD_CHECKSUM || frame.id == id::UNKNOWN_COMMAND;
        if !error_reply && (frame.id != request.id() || !request.expects_reply()) {
            return Err(Error::Mismatch);
        }
        Reply::parse(frame)
    }

    fn write_data(&self, w: &mut DataWriter) -> Result<()> {
        match self {
            Reply::Hello(system) => system.write(w),
            Reply::Version(v) => {
                let ok = |s: &str| !s.is_empty() && s.bytes().all(|b| b != b' ');
                if !ok(v.power_supply) || !v.gas_console.is_none_or(ok) {
                    return Err(Error::Malformed);
                }
                w.bytes(v.power_supply.as_bytes())?;
                if let Some(g) = v.gas_console {
                    w.byte(b' ')?;
                    w.bytes(g.as_bytes())?;
                }
                Ok(())
            }
            Reply::State(s) => four(w, s.0),
            Reply::CurrentError(e) => four(w, e.0),
            Reply::Ack { command, result } => {
                if !ACK_COMMANDS.contains(command) {
                    return Err(Error::Malformed);
                }
                w.field(result.code().into(), 1, 1)
            }
            Reply::PlasmaAmps(v)
            | Reply::NominalAmps(v)
            | Reply::CornerCurrentSet(v)
            | Reply::ControlVoltage(v)
            | Reply::CornerCurrent(v) => four(w, *v),
            Reply::IoStatus(io) => io.ports.iter().zip(PORT_TAGS).try_for_each(|(&p, tag)| {
                w.separator()?;
                w.bytes(tag)?;
                (0..8)
                    .rev()
                    .try_for_each(|bit| w.byte(if p >> bit & 1 == 1 { b'1' } else { b'0' }))
            }),
            Reply::PsInfo(i) => {
                let p = &i.pressures;
                w.tagged(b"PC", p.plasma_cutflow.into(), 4)?;
                w.tagged(b"PP", p.plasma_preflow.into(), 4)?;
                w.tagged(b"SC", p.shield_cutflow.into(), 4)?;
                w.tagged(b"SP", p.shield_preflow.into(), 4)?;
                w.tagged(b"CS", i.current_setpoint.into(), 4)?;
                w.tagged(b"ST", i.state.0.into(), 4)?;
                w.tagged(b"ER", i.error.0.into(), 4)?;
                w.tagged(b"CG", p.cut_gas_1.into(), 4)?;
                w.tagged(b"CG", p.cut_gas_2.into(), 4)?;
                w.tagged(b"MV", p.n2_mix_inlet.into(), 4)?;
                w.tagged(b"MV", p.gas2_mix_inlet.into(), 4)
            }
            Reply::MaxProPsInfo(i) => {
                w.tagged(b"st", i.state.0.into(), 4)?;
                w.tagged(b"er", i.error.0.into(), 4)?;
                w.tagged(b"pg", i.plasma_gas.0.into(), 4)?;
                w.tagged(b"ps", i.plasma_setpoint.into(), 4)?;
                w.tagged(b"sg", i.shield_gas.0.into(), 4)?;
                w.tagged(b"ss", i.shield_setpoint.into(), 4)?;
                w.tagged(b"cs", i.current_setpoint.into(), 4)?;
                w.tagged(b"dm", i.display_mode.into(), 4)?;
                w.tagged(b"lm", i.locked.into(), 4)
            }
            Reply::Wake(system_id) => w.field((*system_id).into(), 1, 1),
            Reply::GasPressures(p) => write_pressures(w, p),
            Reply::InletGases(g) | Reply::GasSwitch(g) => {
                four(w, g.plasma.0)?;
                four(w, g.shield.0)
            }
            Reply::GasFlows(flows) => flows.to_array().iter().try_for_each(|&v| four(w, v)),
            Reply::LeakCheck(seconds) => w.field((*seconds).into(), 1, 4),
            Reply::TimerCounter(t) => t.to_array().iter().try_for_each(|&v| {
                w.decimal(in_range(v, 0, MAX_COUNTER)?, 7, 7)?;
                w.byte(b' ')
            }),
            Reply::ErrorLog(log) => log.iter().try_for_each(|e| w.field(e.0.into(), 3, 3)),
            Reply::ReadyForStart(ready) => w.field((*ready).into(), 1, 1),
            Reply::SetTestMode(v) => w.field((*v).into(), 1, 1),
            Reply::TorchId(t) => four(w, t.0),
            Reply::Diagnostic(d) => d.write(w),
            Reply::BadChecksum | Reply::UnknownCommand => Ok(()),
        }
    }

    /// Write the reply frame into `out`; returns its length.
    ///
    /// Errors: [`Error::Malformed`] for a value wider than its field, an
    /// [`Ack`](Reply::Ack) for a command not in [`ACK_COMMANDS`], or version text with
    /// spaces; [`Error::BufferTooSmall`] if `out` is too short.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize> {
        let mut w = DataWriter::new();
        self.write_data(&mut w)?;
        Frame::new(self.id(), w.as_bytes()).emit(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::errata;
    #[cfg(feature = "diagnostics")]
    use crate::hpr::diagnostics::{
        ControlData, ControlData3, CoolantCounts, GasConsoleInputs, MaxProControlData, MfgData1,
        MfgData2,
    };
    use crate::hpr::identity::{GasConsole, HprRating};

    /// Parse a seed reply frame, check it equals `expected`, and check that emitting
    /// `expected` gives the seed frame byte for byte.
    #[track_caller]
    fn seed(frame: &[u8], expected: Reply<'_>) {
        let f = Frame::parse(frame).unwrap();
        assert_eq!(Reply::parse(&f), Ok(expected));
        let mut out = [0u8; 128];
        let n = expected.emit(&mut out).unwrap();
        assert_eq!(
            &out[..n],
            frame,
            "{}",
            core::str::from_utf8(&out[..n]).unwrap()
        );
    }

    fn ack(command: u16) -> Reply<'static> {
        Reply::Ack {
            command,
            result: Acceptance::Accepted,
        }
    }

    #[test]
    fn hello_identities() {
        // HPR manual (002_72b43a5685974c77.txt) line 139 prints `>000HYPERPERFORMANCE130MANUALB5<`
        // etc.; the checksums (B5, 30, 1E) only match `HYPERFORMANCE`, so the doubled "PER"
        // is a typo. The frames meant (the errata table's):
        let hpr = |console| {
            Reply::Hello(SystemId::Hpr {
                rating: HprRating::Hpr130,
                xd: false,
                console,
            })
        };
        seed(
            errata::HPR_HELLO_MANUAL_CONSOLE.meant.as_bytes(),
            hpr(Some(GasConsole::Manual)),
        );
        seed(
            errata::HPR_HELLO_AUTO_CONSOLE.meant.as_bytes(),
            hpr(Some(GasConsole::Auto)),
        );
        seed(
            errata::HPR_HELLO_AUTOMIX_CONSOLE.meant.as_bytes(),
            hpr(Some(GasConsole::AutoMix)),
        );
        seed(b">000MaxPro20079<", Reply::Hello(SystemId::MaxPro200));
        // As printed, the frames fail their checksum.
        assert_eq!(
            Frame::parse(errata::HPR_HELLO_MANUAL_CONSOLE.printed.as_bytes()),
            Err(Error::BadChecksum {
                expected: 0x9C,
                found: 0xB5
            })
        );
        // The misspelling is still understood when the checksum matches it.
        let mut out = [0u8; 64];
        let n = Frame::new(0, b"HYPERPERFORMANCE400XD")
            .emit(&mut out)
            .unwrap();
        assert_eq!(
            Reply::parse(&Frame::parse(&out[..n]).unwrap()),
            Ok(Reply::Hello(SystemId::Hpr {
                rating: HprRating::Hpr400,
                xd: true,
                console: None
            }))
        );
        let n = Frame::new(0, b"HD4070").emit(&mut out).unwrap();
        assert_eq!(
            Reply::parse(&Frame::parse(&out[..n]).unwrap()),
            Err(Error::Unsupported)
        );
    }

    #[test]
    fn version() {
        // The manual's `>001A.0 A.25<` ("ps rev A, gas rev A") fails its checksum: "001A.0 A."
        // sums to BF, "001A.0 A.2" to F1; neither reading ends in a checksum of 25, so the
        // frame cannot be corrected with confidence and is rejected.
        assert_eq!(
            Frame::parse(b">001A.0 A.25<"),
            Err(Error::BadChecksum {
                expected: 0xBF,
                found: 0x25
            })
        );
        // A constructed (not manual) reply with the format the manual describes.
        let v = Reply::Version(Version {
            power_supply: "A.0",
            gas_console: Some("A.2"),
        });
        let mut out = [0u8; 64];
        let n = v.emit(&mut out).unwrap();
        assert_eq!(&out[..n], b">001A.0 A.2F1<");
        assert_eq!(Reply::parse(&Frame::parse(&out[..n]).unwrap()), Ok(v));
        let single = Reply::Version(Version {
            power_supply: "1.05",
            gas_console: None,
        });
        let n = single.emit(&mut out).unwrap();
        assert_eq!(Reply::parse(&Frame::parse(&out[..n]).unwrap()), Ok(single));
        let bad = Reply::Version(Version {
            power_supply: "A 0",
            gas_console: None,
        });
        assert_eq!(bad.emit(&mut out), Err(Error::Malformed));
    }

    #[test]
    fn version_text_has_one_or_two_revisions_and_one_space() {
        let both = parse_version(b"A.0 A.2").unwrap();
        assert_eq!((both.power_supply, both.gas_console), ("A.0", Some("A.2")));
        let single = parse_version(b"1.05").unwrap();
        assert_eq!((single.power_supply, single.gas_console), ("1.05", None));
        for bad in [
            &b""[..],
            b" A.2",
            b"A.0 ",
            b"A.0  A.2",
            b"A.0 A.2 B",
            b" ",
            b"A.0 \xFF",
        ] {
            assert_eq!(parse_version(bad), Err(Error::Malformed), "{bad:?}");
        }
    }

    #[test]
    fn seed_simple_replies() {
        seed(b">002000052<", Reply::State(StateCode(0)));
        seed(b">00301165B<", Reply::CurrentError(ErrorCode(116)));
        seed(b">0041C5<", ack(id::REMOTE_MODE));
        seed(b">02801305E<", Reply::PlasmaAmps(130));
        seed(b">058013061<", Reply::NominalAmps(130));
        seed(b">0641CB<", ack(id::GAS_PREFLOW_TEST_START));
        seed(b">0651CC<", ack(id::GAS_PREFLOW_TEST_STOP));
        seed(b">0661CD<", ack(id::GAS_CUTFLOW_TEST_START));
        seed(b">0671CE<", ack(id::GAS_CUTFLOW_TEST_STOP));
        seed(b">0681CF<", ack(id::SOFTWARE_RESET));
        seed(b">070007563<", Reply::CornerCurrentSet(75));
        seed(b">07212005C<", Reply::ControlVoltage(1200));
        seed(b">0781D0<", ack(id::SET_ALL_GAS_FLOWS));
        seed(b">0850CD<", Reply::Wake(0));
        seed(b">0951CF<", ack(id::SET_ALL_PARAMETERS));
        seed(b">0961D0<", ack(id::SET_INLET_GASES));
        seed(b">09700756C<", Reply::CornerCurrent(75));
        seed(
            b">0980001 000648<",
            Reply::InletGases(GasPair {
                plasma: GasCode::OXYGEN,
                shield: GasCode::NITROGEN,
            }),
        );
        seed(
            b">0990055 0045 0035 0025 0050 0050EE<",
            Reply::GasFlows(GasFlows::from_array([55, 45, 35, 25, 50, 50])),
        );
        seed(b">12140F8<", Reply::LeakCheck(40));
        seed(
            b">1220001 00063C<",
            Reply::GasSwitch(GasPair {
                plasma: GasCode::OXYGEN,
                shield: GasCode::NITROGEN,
            }),
        );
        seed(b">1311C6<", ack(id::CLEAR_WARNINGS));
        seed(
            b">134020 020 024 0534A<",
            Reply::ErrorLog([ErrorCode(20), ErrorCode(20), ErrorCode(24), ErrorCode(53)]),
        );
        seed(b">1361CB<", ack(id::SERIAL_RESPONSE_DELAY));
        seed(b">1371CC<", ack(id::SET_PROCESS));
        seed(b">1380CC<", Reply::ReadyForStart(false));
        seed(b">1431C9<", Reply::SetTestMode(1));
        seed(b">14500025C<", Reply::TorchId(TorchId(2)));
        seed(b">50095<", Reply::BadChecksum);
        seed(b">50196<", Reply::UnknownCommand);
    }

    #[test]
    fn seed_io_status() {
        seed(
            b">074PA00000100 PB00000000 PC00010101 PD00100000 PE00010000 PF10000000B7<",
            Reply::IoStatus(IoStatus {
                ports: [0x04, 0x00, 0x15, 0x20, 0x10, 0x80],
            }),
        );
    }

    #[cfg(feature = "diagnostics")]
    #[test]
    fn seed_diagnostic_reads() {
        // HPR manual (002_72b43a5685974c77.txt) line 200: 100 GET_CONTROL_DATA, HPR form.
        seed(
            b">100CAT0482 CBT0021 LVO0118 CFL0009 CTP0481 TTP0481 CAC0001 CBC0014 WLC0005 CAS0000 CBS0534 PWMA0000 PWMB00000B<",
            Reply::Diagnostic(DiagnosticReply::ControlData(ControlData {
                chopper_a_temp: 482,
                chopper_b_temp: 21,
                line_voltage: 118,
                coolant_flow: 9,
                coolant_temp: 481,
                transformer_temp: 481,
                chopper_a_current: 1,
                chopper_b_current: 14,
                work_lead_current: 5,
                chopper_a_setpoint: 0,
                chopper_b_setpoint: 534,
                pwm_chopper_a: 0,
                pwm_chopper_b: 0,
            })),
        );
        // Line 239: 117 READ_GAS_INPUTS_FROM_PS, seven inputs all off.
        seed(
            b">1170000000E9<",
            Reply::Diagnostic(DiagnosticReply::GasConsoleInputs(
                GasConsoleInputs::new(&[false; 7]).unwrap(),
            )),
        );
        // Line 266: 132 READ COOLANT PRESSURE, 80 counts ("83 counts = 225 psi").
        seed(
            b">13280FE<",
            Reply::Diagnostic(DiagnosticReply::CoolantPressure(CoolantCounts(80))),
        );
        // Line 269: 133 GET CONTROL DATA3 (HPR400).
        seed(
            b">133CCT0482 CDT0021 CCC0000 CDC000050<",
            Reply::Diagnostic(DiagnosticReply::ControlData3(ControlData3 {
                chopper_c_temp: 482,
                chopper_d_temp: 21,
                chopper_c_current: 0,
                chopper_d_current: 0,
            })),
        );
    }

    #[cfg(feature = "diagnostics")]
    #[test]
    fn maxpro_control_data_is_141_then_142() {
        // No MaxPro200 sample frame exists for 100, 141 or 142 (lines 200, 289, 290): these
        // are built from the field lists, with the manual's example `flow0100` (1.00 gpm).
        let first = MfgData1 {
            plasma_pressure: 56,
            shield_pressure: 58,
            inlet_pressure: 110,
            coolant_temp: 300,
            chopper_temp: 310,
            channel_a_current: 100,
        };
        let second = MfgData2 {
            channel_b_current: 99,
            transformer_temp: 320,
            inductor_a_temp: 330,
            inductor_b_temp: 340,
            bus_voltage: 400,
            coolant_flow: 100,
        };
        let mut out = [0u8; 160];
        let n = Reply::Diagnostic(DiagnosticReply::MaxProControlData(MaxProControlData {
            first,
            second,
        }))
        .emit(&mut out)
        .unwrap();
        assert_eq!(
            &out[4..n - 3],
            &b"plap0056 shap0058 icrp0110 colt0300 chpt0310 chac0100 \
               chbc0099 xfmr0320 inat0330 inbt0340 busv0400 flow0100"[..]
        );
        assert_eq!(
            Reply::parse(&Frame::parse(&out[..n]).unwrap()),
            Ok(Reply::Diagnostic(DiagnosticReply::MaxProControlData(
                MaxProControlData { first, second }
            )))
        );
        for (reply, data) in [
            (
                Reply::Diagnostic(DiagnosticReply::MfgData1(first)),
                &out[4..57],
            ),
            (
                Reply::Diagnostic(DiagnosticReply::MfgData2(second)),
                &out[58..n - 3],
            ),
        ] {
            let mut half = [0u8; 96];
            let m = reply.emit(&mut half).unwrap();
            assert_eq!(&half[4..m - 3], data);
            assert_eq!(Reply::parse(&Frame::parse(&half[..m]).unwrap()), Ok(reply));
        }
        // A field out of order or a tag of the other form is not this reply.
        let mut buf = [0u8; 160];
        let n = Frame::new(
            141,
            b"shap0058 plap0056 icrp0110 colt0300 chpt0310 chac0100",
        )
        .emit(&mut buf)
        .unwrap();
        assert_eq!(
            Reply::parse(&Frame::parse(&buf[..n]).unwrap()),
            Err(Error::Malformed)
        );
        let n = Frame::new(100, b"CAT0482").emit(&mut buf).unwrap();
        assert_eq!(
            Reply::parse(&Frame::parse(&buf[..n]).unwrap()),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn seed_ps_info_hpr() {
        // Printed across three lines with runs of spaces where the OCR wrapped it; with single
        // spaces between the fields the checksum DE matches (as printed it sums to 9E).
        let frame =
            b">079PC0044 PP0042 SC0034 SP0035 CS0040 ST0003 ER0000 CG0000 CG0000 MV0000 MV0000DE<";
        let info = PsInfo {
            pressures: GasPressures {
                plasma_cutflow: 44,
                plasma_preflow: 42,
                shield_cutflow: 34,
                shield_preflow: 35,
                ..GasPressures::default()
            },
            current_setpoint: 40,
            state: StateCode::READY,
            error: ErrorCode::NONE,
        };
        seed(frame, Reply::PsInfo(info));
    }

    #[test]
    fn ps_info_maxpro() {
        // No MaxPro200 sample frame exists; this one is built from the field list.
        let info = MaxProPsInfo {
            state: StateCode(3),
            error: ErrorCode(0),
            plasma_gas: GasCode::OXYGEN,
            plasma_setpoint: 56,
            shield_gas: GasCode::OXYGEN,
            shield_setpoint: 58,
            current_setpoint: 200,
            display_mode: 1,
            locked: true,
        };
        let mut out = [0u8; 128];
        let n = Reply::MaxProPsInfo(info).emit(&mut out).unwrap();
        assert_eq!(
            &out[4..n - 3],
            b"st0003 er0000 pg0001 ps0056 sg0001 ss0058 cs0200 dm0001 lm0001"
        );
        assert_eq!(
            Reply::parse(&Frame::parse(&out[..n]).unwrap()),
            Ok(Reply::MaxProPsInfo(info))
        );
    }

    #[test]
    fn seed_gas_pressures() {
        seed(
            b">094PC0007 PP0036 SC0016 SP0003 CG0000 CG0000 MV0000 MV00005D<",
            Reply::GasPressures(GasPressures {
                plasma_cutflow: 7,
                plasma_preflow: 36,
                shield_cutflow: 16,
                shield_preflow: 3,
                ..GasPressures::default()
            }),
        );
    }

    #[test]
    fn timer_counter() {
        // The manual prints `>1250000000 0000000 0000000 0000000 0000000 0000000 0000000 58<`.
        // Its data sums to A8 (88 without the trailing space); 58 is reachable only with a
        // digit count that contradicts "7 numbers followed by a space", so the frame cannot be
        // corrected with confidence and is rejected.
        assert_eq!(
            Frame::parse(b">1250000000 0000000 0000000 0000000 0000000 0000000 0000000 58<"),
            Err(Error::BadChecksum {
                expected: 0xA8,
                found: 0x58
            })
        );
        // The same data with its computed checksum (constructed, not from the manual).
        let zero = b">1250000000 0000000 0000000 0000000 0000000 0000000 0000000 A8<";
        seed(zero, Reply::TimerCounter(TimerCounter::default()));
        let t = TimerCounter::from_array([1234567, 1, 22, 333, 4444, 55555, 9_999_999]);
        let mut out = [0u8; 128];
        let n = Reply::TimerCounter(t).emit(&mut out).unwrap();
        assert_eq!(
            &out[4..n - 3],
            b"1234567 0000001 0000022 0000333 0004444 0055555 9999999 "
        );
        assert_eq!(
            Reply::parse(&Frame::parse(&out[..n]).unwrap()),
            Ok(Reply::TimerCounter(t))
        );
        // Without the trailing space it still parses.
        let n2 = Frame::new(125, &out[4..n - 4])
            .emit(&mut [0u8; 128])
            .unwrap();
        assert_eq!(n2, n - 1);
        let bad = TimerCounter::from_array([10_000_000, 0, 0, 0, 0, 0, 0]);
        assert_eq!(
            Reply::TimerCounter(bad).emit(&mut out),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn rejects_bad_reply_data() {
        let mut buf = [0u8; 128];
        let mut parse = |id, data: &[u8]| {
            let n = Frame::new(id, data).emit(&mut buf).unwrap();
            let f = Frame::parse(&buf[..n]).unwrap();
            Reply::parse(&f).map(|_| ())
        };
        assert_eq!(parse(2, b""), Err(Error::Malformed));
        assert_eq!(parse(2, b"00001"), Err(Error::Malformed));
        assert_eq!(parse(2, b"0000 "), Err(Error::Malformed));
        assert_eq!(parse(4, b"3"), Err(Error::Malformed));
        assert_eq!(
            parse(
                74,
                b"PA0000010 PB00000000 PC00010101 PD00100000 PE00010000 PF10000000"
            ),
            Err(Error::Malformed)
        );
        assert_eq!(
            parse(
                74,
                b"PA00000102 PB00000000 PC00010101 PD00100000 PE00010000 PF10000000"
            ),
            Err(Error::Malformed)
        );
        assert_eq!(parse(79, b"PC0044"), Err(Error::Malformed));
        assert_eq!(
            parse(
                94,
                b"PP0007 PC0036 SC0016 SP0003 CG0000 CG0000 MV0000 MV0000"
            ),
            Err(Error::Malformed)
        );
        assert_eq!(parse(134, b"020 020 024"), Err(Error::Malformed));
        assert_eq!(parse(134, b"020 020 024 053 001"), Err(Error::Malformed));
        assert_eq!(parse(500, b"1"), Err(Error::Malformed));
        assert_eq!(parse(86, b""), Err(Error::Unsupported));
        assert_eq!(parse(120, b"1"), Err(Error::Unsupported));
        let mut out = [0u8; 32];
        let bad_ack = Reply::Ack {
            command: id::GET_STATE,
            result: Acceptance::Accepted,
        };
        assert_eq!(bad_ack.emit(&mut out), Err(Error::Malformed));
        assert_eq!(
            Reply::State(StateCode(10_000)).emit(&mut out),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn replies_match_requests() {
        let f = Frame::parse(b">002000052<").unwrap();
        assert_eq!(
            Reply::parse_for(&Request::GetState, &f),
            Ok(Reply::State(StateCode(0)))
        );
        assert_eq!(
            Reply::parse_for(&Request::CurrentError, &f),
            Err(Error::Mismatch)
        );
        let f = Frame::parse(b">50095<").unwrap();
        assert_eq!(
            Reply::parse_for(&Request::GetState, &f),
            Ok(Reply::BadChecksum)
        );
        let f = Frame::parse(b">0869E<").unwrap();
        assert_eq!(Reply::parse_for(&Request::Sleep, &f), Err(Error::Mismatch));
        // MaxPro200 answers 095/137 with 2 when the data is invalid or the state is wrong.
        let mut buf = [0u8; 16];
        let n = Frame::new(137, b"2").emit(&mut buf).unwrap();
        let req = Request::SetProcess {
            amps: 200,
            gases: GasPair {
                plasma: GasCode::AIR,
                shield: GasCode::AIR,
            },
        };
        assert_eq!(
            Reply::parse_for(&req, &Frame::parse(&buf[..n]).unwrap()),
            Ok(Reply::Ack {
                command: id::SET_PROCESS,
                result: Acceptance::Invalid
            })
        );
    }
}
