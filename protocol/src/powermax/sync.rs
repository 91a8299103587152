//! Powermax SYNC register map (0x3000-0x3180): addresses, requests and decoders.
//!
//! Every read uses function 04, which SYNC units answer for holding registers too. Settings are
//! written with function 0x10 only: mode, current and pressure together in one request (three
//! separate writes would pass through states the unit reports as 0-11-n faults).

use super::cartridge::{CartridgeCounters, CartridgeUid, PartNumber};
use super::fault::FaultCode;
use super::ident::{SyncModel, TorchType};
use super::mode::OperatingMode;
use super::plan::{BlockRead, RegisterSpan, need, u32_low_first, word};
use crate::modbus_ascii::{Registers, Request};
use crate::units::{Amps, Pressure, Psi};
use crate::{Error, Result};

// ---------------------------------------------------------------------------------------------
// Register addresses (function 04 unless noted)

/// Torch and power-supply identification: high byte torch id (Table 3), low byte SYNC id
/// (Table 4).
pub const IDENTIFICATION: u16 = 0x3000;
/// Permitted operating modes for the installed cartridge: high byte "mode high", low byte
/// "mode low".
pub const PERMITTED_MODES: u16 = 0x3001;
/// Permitted minimum output current (A x 64). Legacy equivalent 0x2099.
pub const PERMITTED_MIN_CURRENT: u16 = 0x3002;
/// Permitted maximum output current (A x 64). Legacy equivalent 0x209A.
pub const PERMITTED_MAX_CURRENT: u16 = 0x3003;
/// Permitted minimum gas pressure (psi x 128). Legacy equivalent 0x209C.
pub const PERMITTED_MIN_PRESSURE: u16 = 0x3004;
/// Permitted maximum gas pressure (psi x 128). Legacy equivalent 0x209D.
pub const PERMITTED_MAX_PRESSURE: u16 = 0x3005;
/// Operating mode setting (high byte 0x00, low byte mode).
pub const MODE_SETTING: u16 = 0x3010;
/// Output current setting (A x 64).
pub const CURRENT_SETTING: u16 = 0x3011;
/// Gas pressure setting (psi x 128).
pub const PRESSURE_SETTING: u16 = 0x3012;
/// Actual output current (A x 64).
pub const ACTUAL_CURRENT: u16 = 0x3018;
/// Actual gas pressure output at the valve (psi x 128). Legacy equivalent 0x204C.
pub const ACTUAL_PRESSURE: u16 = 0x3019;
/// Active fault code (0 = none). Legacy equivalent 0x2098.
pub const ACTIVE_FAULT: u16 = 0x301A;
/// Power-supply total torch starts, low word (bytes 1 and 0).
pub const PS_STARTS_LOW: u16 = 0x3028;
/// Power-supply total torch starts, high word (bytes 3 and 2).
pub const PS_STARTS_HIGH: u16 = 0x3029;
/// Power-supply cumulative pilot arc time in seconds, low word. Legacy 0x209E.
pub const PS_PILOT_ARC_TIME_LOW: u16 = 0x302A;
/// Power-supply cumulative pilot arc time in seconds, high word. Legacy 0x209F.
pub const PS_PILOT_ARC_TIME_HIGH: u16 = 0x302B;
/// Power-supply total arc transfers, low word.
pub const PS_TRANSFERS_LOW: u16 = 0x302C;
/// Power-supply total arc transfers, high word.
pub const PS_TRANSFERS_HIGH: u16 = 0x302D;
/// Power-supply cumulative arc transfer time in seconds, low word.
pub const PS_TRANSFER_TIME_LOW: u16 = 0x302E;
/// Power-supply cumulative arc transfer time in seconds, high word.
pub const PS_TRANSFER_TIME_HIGH: u16 = 0x302F;
/// Cartridge UID, bytes 0-1; the UID runs through 0x3037 (16 ASCII characters).
pub const CARTRIDGE_UID: u16 = 0x3030;
/// Cartridge UID, bytes 14-15 (register `CARTRIDGE_UID + n` holds bytes `2n` and `2n + 1`).
pub const CARTRIDGE_UID_END: u16 = 0x3037;
/// Cartridge part number, bytes 0-1; runs through 0x303A (6 ASCII characters, Table 5).
pub const CARTRIDGE_PART_NUMBER: u16 = 0x3038;
/// Cartridge part number, bytes 4-5 (0x3039 holds bytes 2-3).
pub const CARTRIDGE_PART_NUMBER_END: u16 = 0x303A;
/// Cartridge part number revision level.
pub const CARTRIDGE_REVISION: u16 = 0x303B;
/// Nominal (rated) current of the installed cartridge, amperes.
pub const CARTRIDGE_NOMINAL_CURRENT: u16 = 0x303C;
/// Cartridge total pilot arc starts.
pub const CARTRIDGE_STARTS: u16 = 0x3040;
/// Cartridge cumulative pilot arc time, seconds.
pub const CARTRIDGE_PILOT_ARC_TIME: u16 = 0x3041;
/// Cartridge total arc transfers.
pub const CARTRIDGE_TRANSFERS: u16 = 0x3042;
/// Cartridge cumulative arc transfer time, 2 seconds per count.
pub const CARTRIDGE_TRANSFER_TIME: u16 = 0x3043;
/// Cartridge fault log 0 (newest).
pub const FAULT_LOG_0: u16 = 0x3044;
/// Cartridge fault log 1.
pub const FAULT_LOG_1: u16 = 0x3045;
/// Cartridge fault log 2.
pub const FAULT_LOG_2: u16 = 0x3046;
/// Cartridge fault log 3 (oldest).
pub const FAULT_LOG_3: u16 = 0x3047;
/// Cartridge name, bytes 0-1; runs through 0x304D (12 bytes, Table 7).
pub const CARTRIDGE_NAME: u16 = 0x3048;
/// Cartridge name, bytes 10-11 (register `CARTRIDGE_NAME + n` holds bytes `2n` and `2n + 1`).
pub const CARTRIDGE_NAME_END: u16 = 0x304D;
/// Remote operating mode setting (write, function 0x10). Legacy equivalent 0x2093.
pub const REMOTE_MODE: u16 = 0x3080;
/// Remote output current setting, A x 64 (write). Legacy equivalent 0x2094.
pub const REMOTE_CURRENT: u16 = 0x3081;
/// Remote gas pressure setting, psi x 128, 0 = automatic (write). Legacy equivalent 0x2096.
pub const REMOTE_PRESSURE: u16 = 0x3082;
/// Special quick restart command (write [`QUICK_RESTART_COMMAND_VALUE`]).
pub const QUICK_RESTART_COMMAND: u16 = 0x308E;
/// Special quick restart approval (write [`QUICK_RESTART_APPROVAL_VALUE`]).
pub const QUICK_RESTART_APPROVAL: u16 = 0x308F;
/// Value that requests the quick restart.
pub const QUICK_RESTART_COMMAND_VALUE: u16 = 0x0404;
/// Value that approves the quick restart.
pub const QUICK_RESTART_APPROVAL_VALUE: u16 = 0x0618;

/// Coil: Start switch signal status (function 01). Legacy equivalent 0x0810.
pub const START_SIGNAL_COIL: u16 = 0x3100;
/// Coil: Motion switch signal status (function 01). Legacy equivalent 0x0811.
pub const MOTION_SIGNAL_COIL: u16 = 0x3101;
/// Coil: gas test, ON starts and OFF stops it (function 05). Legacy equivalent 0x0832.
pub const GAS_TEST_COIL: u16 = 0x3180;

// ---------------------------------------------------------------------------------------------
// Read plans

/// 0x3000: identification.
pub const IDENTIFICATION_SPAN: RegisterSpan = RegisterSpan::new(IDENTIFICATION, 1);
/// 0x3001-0x3005: permitted settings.
pub const PERMITTED_SETTINGS_SPAN: RegisterSpan = RegisterSpan::new(PERMITTED_MODES, 5);
/// 0x3010-0x3012: settings.
pub const SETTINGS_SPAN: RegisterSpan = RegisterSpan::new(MODE_SETTING, 3);
/// 0x3018-0x301A: actual current, actual pressure and active fault.
pub const OUTPUTS_AND_FAULT_SPAN: RegisterSpan = RegisterSpan::new(ACTUAL_CURRENT, 3);
/// 0x3018-0x3019: actual outputs only (the guide's example read).
pub const ACTUAL_OUTPUTS_SPAN: RegisterSpan = RegisterSpan::new(ACTUAL_CURRENT, 2);
/// 0x301A: active fault only.
pub const ACTIVE_FAULT_SPAN: RegisterSpan = RegisterSpan::new(ACTIVE_FAULT, 1);
/// 0x3028-0x302F: power-supply counters.
pub const PS_COUNTERS_SPAN: RegisterSpan = RegisterSpan::new(PS_STARTS_LOW, 8);
/// 0x3030-0x3037: cartridge UID.
pub const CARTRIDGE_UID_SPAN: RegisterSpan =
    RegisterSpan::new(CARTRIDGE_UID, CARTRIDGE_UID_END - CARTRIDGE_UID + 1);
/// 0x3038-0x303A: cartridge part number.
pub const CARTRIDGE_PART_NUMBER_SPAN: RegisterSpan = RegisterSpan::new(
    CARTRIDGE_PART_NUMBER,
    CARTRIDGE_PART_NUMBER_END - CARTRIDGE_PART_NUMBER + 1,
);
/// 0x3030-0x303C: UID, part number, revision and nominal current.
pub const CARTRIDGE_ID_SPAN: RegisterSpan = RegisterSpan::new(CARTRIDGE_UID, 13);
/// 0x3040-0x3043: cartridge counters.
pub const CARTRIDGE_COUNTERS_SPAN: RegisterSpan = RegisterSpan::new(CARTRIDGE_STARTS, 4);
/// 0x3044-0x3047: fault log.
pub const FAULT_LOG_SPAN: RegisterSpan = RegisterSpan::new(FAULT_LOG_0, 4);
/// 0x3048-0x304D: cartridge name.
pub const CARTRIDGE_NAME_SPAN: RegisterSpan =
    RegisterSpan::new(CARTRIDGE_NAME, CARTRIDGE_NAME_END - CARTRIDGE_NAME + 1);

static STATUS_PARTS: [RegisterSpan; 2] = [SETTINGS_SPAN, OUTPUTS_AND_FAULT_SPAN];
/// 0x3010-0x301A in one read: settings, actual outputs and active fault. Crosses the
/// undocumented 0x3013-0x3017; the fallback reads 0x3010-0x3012 and 0x3018-0x301A.
pub const STATUS_BLOCK: BlockRead =
    BlockRead::new(RegisterSpan::new(MODE_SETTING, 11), &STATUS_PARTS);

static CARTRIDGE_PARTS: [RegisterSpan; 2] = [CARTRIDGE_ID_SPAN, CARTRIDGE_COUNTERS_SPAN];
/// 0x3030-0x3043 in one read: UID, part number, revision, nominal current and counters.
/// Crosses the undocumented 0x303D-0x303F; the fallback reads 0x3030-0x303C and 0x3040-0x3043.
pub const CARTRIDGE_BLOCK: BlockRead =
    BlockRead::new(RegisterSpan::new(CARTRIDGE_UID, 20), &CARTRIDGE_PARTS);

// ---------------------------------------------------------------------------------------------
// Requests

/// Read 0x3000 (`:010430000001CA` at node 1).
pub const fn read_identification() -> Request<'static> {
    IDENTIFICATION_SPAN.read()
}

/// Read 0x3001-0x3005 (`:010430010005C5`).
pub const fn read_permitted_settings() -> Request<'static> {
    PERMITTED_SETTINGS_SPAN.read()
}

/// Read 0x3010-0x3012 (`:010430100003B8`).
pub const fn read_settings() -> Request<'static> {
    SETTINGS_SPAN.read()
}

/// Read 0x3018-0x3019 (`:010430180002B1`).
pub const fn read_actual_outputs() -> Request<'static> {
    ACTUAL_OUTPUTS_SPAN.read()
}

/// Read 0x301A (`:0104301A0001B0`).
pub const fn read_active_fault() -> Request<'static> {
    ACTIVE_FAULT_SPAN.read()
}

/// Read 0x3010-0x301A in one request (see [`STATUS_BLOCK`] for the fallback).
pub const fn read_status_block() -> Request<'static> {
    STATUS_BLOCK.read()
}

/// Read 0x3028-0x302F (`:0104302800089B`).
pub const fn read_ps_counters() -> Request<'static> {
    PS_COUNTERS_SPAN.read()
}

/// Read 0x3030-0x3037 (`:01043030000893`).
pub const fn read_cartridge_uid() -> Request<'static> {
    CARTRIDGE_UID_SPAN.read()
}

/// Read 0x3038-0x303A (`:01043038000390`).
pub const fn read_cartridge_part_number() -> Request<'static> {
    CARTRIDGE_PART_NUMBER_SPAN.read()
}

/// Read 0x3040-0x3043 (`:01043040000487`).
pub const fn read_cartridge_counters() -> Request<'static> {
    CARTRIDGE_COUNTERS_SPAN.read()
}

/// Read 0x3030-0x3043 in one request (see [`CARTRIDGE_BLOCK`] for the fallback).
pub const fn read_cartridge() -> Request<'static> {
    CARTRIDGE_BLOCK.read()
}

/// Read 0x3044-0x3047 (`:01043044000483`).
pub const fn read_fault_log() -> Request<'static> {
    FAULT_LOG_SPAN.read()
}

/// Read 0x3048-0x304D (`:0104304800067D`).
pub const fn read_cartridge_name() -> Request<'static> {
    CARTRIDGE_NAME_SPAN.read()
}

/// Read the Start and Motion coils together (`:010131000002CB`); decode with
/// [`Signals::decode`](super::Signals::decode).
pub const fn read_signals() -> Request<'static> {
    Request::ReadCoils {
        start: START_SIGNAL_COIL,
        quantity: 2,
    }
}

/// Start (`true`, `:01053180FF004A`) or stop (`false`, `:01053180000049`) a gas test.
pub const fn gas_test(on: bool) -> Request<'static> {
    Request::WriteSingleCoil {
        address: GAS_TEST_COIL,
        on,
    }
}

static QUICK_RESTART_WORDS: [u16; 2] = [QUICK_RESTART_COMMAND_VALUE, QUICK_RESTART_APPROVAL_VALUE];

/// Quick restart that clears fault 0-50-0 (and only that fault): 0x0404 to 0x308E and 0x0618 to
/// 0x308F in one request (`:0110308E0002040404061805`). Send no request for
/// [`QUICK_RESTART_SILENCE_MS`](super::timing::QUICK_RESTART_SILENCE_MS) afterwards.
pub const fn quick_restart() -> Request<'static> {
    Request::WriteMultipleRegisters {
        start: QUICK_RESTART_COMMAND,
        values: Registers::Words(&QUICK_RESTART_WORDS),
    }
}

/// The three remote-setting words (mode, current, pressure) that put the unit in remote
/// control mode, e.g. `[0x0001, 0x0FC0, 0x0000]` for cut at 63 A with automatic pressure.
///
/// [`Error::Malformed`] when the current is not above zero or a pressure set point is negative:
/// the unit would refuse either with a 0-11-n fault.
pub fn enter_remote(mode: OperatingMode, current: Amps, pressure: Pressure) -> Result<[u16; 3]> {
    if !current.is_positive() {
        return Err(Error::Malformed);
    }
    if pressure.psi().is_some_and(|psi| psi.steps() < 0) {
        return Err(Error::Malformed);
    }
    Ok([mode.to_sync(), current.raw(), pressure.raw()])
}

/// Zeros in all three remote registers: leave remote control mode.
pub const EXIT_REMOTE_WORDS: [u16; 3] = [0; 3];

/// Write `words` (from [`enter_remote`] or [`EXIT_REMOTE_WORDS`]) to 0x3080-0x3082 in one
/// request.
pub const fn write_remote(words: &[u16; 3]) -> Request<'_> {
    Request::WriteMultipleRegisters {
        start: REMOTE_MODE,
        values: Registers::Words(words),
    }
}

/// Leave remote control mode: zeros to 0x3080-0x3082 in one request.
pub const fn exit_remote() -> Request<'static> {
    write_remote(&EXIT_REMOTE_WORDS)
}

// ---------------------------------------------------------------------------------------------
// Decoders. Each takes the registers of its read, first register first; extra registers after
// the ones it needs are ignored, missing ones are `Error::Truncated`.

/// 0x3000: torch and power supply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Identification {
    /// The register as read.
    pub raw: u16,
    /// High byte via Table 3; `None` for an id the table does not list.
    pub torch: Option<TorchType>,
    /// Low byte via Table 4; `None` for an id the table does not list.
    pub model: Option<SyncModel>,
}

impl Identification {
    /// Decodes 1 register.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        let raw = word(&registers, 0)?;
        let [torch_id, model_id] = raw.to_be_bytes();
        Ok(Identification {
            raw,
            torch: TorchType::from_id(torch_id),
            model: SyncModel::from_id(model_id),
        })
    }
}

/// 0x3001: the two permitted modes ("mode high" and "mode low" bytes). With one permitted mode
/// both bytes hold it; the guide's example 0x0201 permits cut and expanded metal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PermittedModes {
    /// High byte.
    pub high: u8,
    /// Low byte.
    pub low: u8,
}

impl PermittedModes {
    /// True when either byte names `mode`.
    pub const fn contains(self, mode: OperatingMode) -> bool {
        let value = mode.to_sync();
        self.high as u16 == value || self.low as u16 == value
    }

    /// Mode of the low byte.
    pub const fn low_mode(self) -> Option<OperatingMode> {
        OperatingMode::from_sync(self.low as u16)
    }

    /// Mode of the high byte.
    pub const fn high_mode(self) -> Option<OperatingMode> {
        OperatingMode::from_sync(self.high as u16)
    }
}

/// 0x3001-0x3005: what the installed cartridge permits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PermittedSettings {
    /// Permitted modes.
    pub modes: PermittedModes,
    /// Minimum current.
    pub min_current: Amps,
    /// Maximum current.
    pub max_current: Amps,
    /// Minimum pressure.
    pub min_pressure: Psi,
    /// Maximum pressure.
    pub max_pressure: Psi,
}

impl PermittedSettings {
    /// Decodes 5 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, 5)?;
        let [high, low] = word(&registers, 0)?.to_be_bytes();
        Ok(PermittedSettings {
            modes: PermittedModes { high, low },
            min_current: Amps::from_raw(word(&registers, 1)?),
            max_current: Amps::from_raw(word(&registers, 2)?),
            min_pressure: Psi::from_raw(word(&registers, 3)?),
            max_pressure: Psi::from_raw(word(&registers, 4)?),
        })
    }

    /// True when remote settings would be accepted without a 0-11-n fault: the mode is
    /// permitted, the current within limits, and the pressure automatic or within limits.
    pub fn allows(&self, mode: OperatingMode, current: Amps, pressure: Pressure) -> bool {
        let pressure_ok = match pressure.psi() {
            None => true,
            Some(psi) => self.min_pressure <= psi && psi <= self.max_pressure,
        };
        self.modes.contains(mode)
            && self.min_current <= current
            && current <= self.max_current
            && pressure_ok
    }
}

/// 0x3010-0x3012: the settings in use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Process {
    /// Mode; `None` when the register holds a value the guide does not list.
    pub mode: Option<OperatingMode>,
    /// Current setting.
    pub current: Amps,
    /// Pressure setting (0 reads as automatic).
    pub pressure: Pressure,
}

impl Process {
    /// Decodes 3 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, 3)?;
        Ok(Process {
            mode: OperatingMode::from_sync(word(&registers, 0)?),
            current: Amps::from_raw(word(&registers, 1)?),
            pressure: Pressure::from_raw(word(&registers, 2)?),
        })
    }
}

/// 0x3018-0x3019: actual output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ActualOutputs {
    /// Output current.
    pub current: Amps,
    /// Gas pressure at the valve.
    pub pressure: Psi,
}

impl ActualOutputs {
    /// Decodes 2 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, 2)?;
        Ok(ActualOutputs {
            current: Amps::from_raw(word(&registers, 0)?),
            pressure: Psi::from_raw(word(&registers, 1)?),
        })
    }
}

/// Decodes the active fault (0x301A, 1 register).
pub fn decode_active_fault(registers: Registers<'_>) -> Result<FaultCode> {
    word(&registers, 0).map(FaultCode)
}

/// 0x3010-0x301A: everything the supervisor polls.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StatusBlock {
    /// 0x3010-0x3012.
    pub settings: Process,
    /// 0x3018-0x3019.
    pub actual: ActualOutputs,
    /// 0x301A.
    pub fault: FaultCode,
}

impl StatusBlock {
    /// Decodes the 11 registers of [`STATUS_BLOCK`]; 0x3013-0x3017 are not looked at.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, STATUS_BLOCK.len())?;
        Ok(StatusBlock {
            settings: Process::decode(registers)?,
            actual: ActualOutputs {
                current: Amps::from_raw(word(&registers, 8)?),
                pressure: Psi::from_raw(word(&registers, 9)?),
            },
            fault: FaultCode(word(&registers, 10)?),
        })
    }
}

/// 0x3028-0x302F: lifetime counters of the power supply (32 bits each, low word first).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PsCounters {
    /// Torch starts.
    pub starts: u32,
    /// Cumulative pilot arc time, seconds.
    pub pilot_arc_seconds: u32,
    /// Arc transfers.
    pub transfers: u32,
    /// Cumulative arc transfer time, seconds.
    pub transfer_seconds: u32,
}

impl PsCounters {
    /// Decodes 8 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, 8)?;
        Ok(PsCounters {
            starts: u32_low_first(&registers, 0)?,
            pilot_arc_seconds: u32_low_first(&registers, 2)?,
            transfers: u32_low_first(&registers, 4)?,
            transfer_seconds: u32_low_first(&registers, 6)?,
        })
    }
}

/// 0x3030-0x3043: the installed cartridge.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cartridge {
    /// 0x3030-0x3037.
    pub uid: CartridgeUid,
    /// 0x3038-0x303A.
    pub part_number: PartNumber,
    /// 0x303B, as read: the guide names the register but not its encoding.
    pub revision: u16,
    /// 0x303C, as read: see [`Cartridge::nominal_current`].
    pub nominal_current_raw: u16,
    /// 0x3040-0x3043.
    pub counters: CartridgeCounters,
}

impl Cartridge {
    /// Decodes the 20 registers of [`CARTRIDGE_BLOCK`]; 0x303D-0x303F are not looked at.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, CARTRIDGE_BLOCK.len())?;
        let counters: [u16; 4] = [
            word(&registers, 16)?,
            word(&registers, 17)?,
            word(&registers, 18)?,
            word(&registers, 19)?,
        ];
        Ok(Cartridge {
            uid: CartridgeUid::decode(registers)?,
            part_number: PartNumber(super::plan::bytes(&registers, 8)?),
            revision: word(&registers, 11)?,
            nominal_current_raw: word(&registers, 12)?,
            counters: CartridgeCounters::decode(Registers::Words(&counters))?,
        })
    }

    /// The nominal current. The guide gives the unit (amperes) but not the scaling; this reads
    /// it as A x 64 like every other current register of the map.
    pub const fn nominal_current(&self) -> Amps {
        Amps::from_raw(self.nominal_current_raw)
    }
}

/// 0x3044-0x3047: the four most recent faults of the cartridge, newest first; 0 = no entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultLog(pub [FaultCode; 4]);

impl FaultLog {
    /// Decodes 4 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, 4)?;
        Ok(FaultLog([
            FaultCode(word(&registers, 0)?),
            FaultCode(word(&registers, 1)?),
            FaultCode(word(&registers, 2)?),
            FaultCode(word(&registers, 3)?),
        ]))
    }

    /// The logged faults, newest first, without empty entries.
    pub fn iter(&self) -> impl Iterator<Item = FaultCode> + '_ {
        self.0.iter().copied().filter(|code| !code.is_none())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::powermax::{CartridgeProcess, LeadLength, Signals, TorchKind};

    fn read(start: u16, quantity: u16) -> Request<'static> {
        Request::ReadInputRegisters { start, quantity }
    }

    #[test]
    fn every_address() {
        let map: [(u16, u16); 55] = [
            (CARTRIDGE_UID_END, 0x3037),
            (CARTRIDGE_PART_NUMBER_END, 0x303A),
            (CARTRIDGE_NAME_END, 0x304D),
            (IDENTIFICATION, 0x3000),
            (PERMITTED_MODES, 0x3001),
            (PERMITTED_MIN_CURRENT, 0x3002),
            (PERMITTED_MAX_CURRENT, 0x3003),
            (PERMITTED_MIN_PRESSURE, 0x3004),
            (PERMITTED_MAX_PRESSURE, 0x3005),
            (MODE_SETTING, 0x3010),
            (CURRENT_SETTING, 0x3011),
            (PRESSURE_SETTING, 0x3012),
            (ACTUAL_CURRENT, 0x3018),
            (ACTUAL_PRESSURE, 0x3019),
            (ACTIVE_FAULT, 0x301A),
            (PS_STARTS_LOW, 0x3028),
            (PS_STARTS_HIGH, 0x3029),
            (PS_PILOT_ARC_TIME_LOW, 0x302A),
            (PS_PILOT_ARC_TIME_HIGH, 0x302B),
            (PS_TRANSFERS_LOW, 0x302C),
            (PS_TRANSFERS_HIGH, 0x302D),
            (PS_TRANSFER_TIME_LOW, 0x302E),
            (PS_TRANSFER_TIME_HIGH, 0x302F),
            (CARTRIDGE_UID, 0x3030),
            (CARTRIDGE_UID_SPAN.last(), 0x3037),
            (CARTRIDGE_PART_NUMBER, 0x3038),
            (CARTRIDGE_PART_NUMBER_SPAN.last(), 0x303A),
            (CARTRIDGE_REVISION, 0x303B),
            (CARTRIDGE_NOMINAL_CURRENT, 0x303C),
            (CARTRIDGE_ID_SPAN.last(), 0x303C),
            (CARTRIDGE_STARTS, 0x3040),
            (CARTRIDGE_PILOT_ARC_TIME, 0x3041),
            (CARTRIDGE_TRANSFERS, 0x3042),
            (CARTRIDGE_TRANSFER_TIME, 0x3043),
            (FAULT_LOG_0, 0x3044),
            (FAULT_LOG_1, 0x3045),
            (FAULT_LOG_2, 0x3046),
            (FAULT_LOG_3, 0x3047),
            (CARTRIDGE_NAME, 0x3048),
            (CARTRIDGE_NAME_SPAN.last(), 0x304D),
            (REMOTE_MODE, 0x3080),
            (REMOTE_CURRENT, 0x3081),
            (REMOTE_PRESSURE, 0x3082),
            (QUICK_RESTART_COMMAND, 0x308E),
            (QUICK_RESTART_APPROVAL, 0x308F),
            (QUICK_RESTART_COMMAND_VALUE, 0x0404),
            (QUICK_RESTART_APPROVAL_VALUE, 0x0618),
            (START_SIGNAL_COIL, 0x3100),
            (MOTION_SIGNAL_COIL, 0x3101),
            (GAS_TEST_COIL, 0x3180),
            (STATUS_BLOCK.block().last(), 0x301A),
            (CARTRIDGE_BLOCK.block().last(), 0x3043),
            (PERMITTED_SETTINGS_SPAN.last(), 0x3005),
            (PS_COUNTERS_SPAN.last(), 0x302F),
            (FAULT_LOG_SPAN.last(), 0x3047),
        ];
        for (got, want) in map {
            assert_eq!(got, want);
        }
    }

    #[test]
    fn manual_requests() {
        // Each frame's LRC was recomputed; the framing itself is tested in modbus_ascii.
        assert_eq!(read_identification(), read(0x3000, 1)); // :010430000001CA
        assert_eq!(read_permitted_settings(), read(0x3001, 5)); // :010430010005C5
        assert_eq!(read_settings(), read(0x3010, 3)); // :010430100003B8
        assert_eq!(read_actual_outputs(), read(0x3018, 2)); // :010430180002B1
        assert_eq!(read_active_fault(), read(0x301A, 1)); // :0104301A0001B0
        assert_eq!(read_ps_counters(), read(0x3028, 8)); // :0104302800089B
        assert_eq!(read_cartridge_uid(), read(0x3030, 8)); // :01043030000893
        assert_eq!(read_cartridge_part_number(), read(0x3038, 3)); // :01043038000390
        assert_eq!(read_cartridge_counters(), read(0x3040, 4)); // :01043040000487
        assert_eq!(read_fault_log(), read(0x3044, 4)); // :01043044000483
        assert_eq!(read_cartridge_name(), read(0x3048, 6)); // :0104304800067D
        // :010131000002CB
        assert_eq!(
            read_signals(),
            Request::ReadCoils {
                start: 0x3100,
                quantity: 2
            }
        );
        // :01053180FF004A and :01053180000049
        assert_eq!(
            gas_test(true),
            Request::WriteSingleCoil {
                address: 0x3180,
                on: true
            }
        );
        assert_eq!(
            gas_test(false),
            Request::WriteSingleCoil {
                address: 0x3180,
                on: false
            }
        );
        // :0110308E0002040404061805
        assert_eq!(
            quick_restart(),
            Request::WriteMultipleRegisters {
                start: 0x308E,
                values: Registers::Words(&[0x0404, 0x0618])
            }
        );
    }

    #[test]
    fn block_reads() {
        assert_eq!(read_status_block(), read(0x3010, 11));
        assert!(STATUS_BLOCK.has_gaps());
        let mut parts = STATUS_BLOCK.part_reads();
        assert_eq!(parts.next(), Some(read(0x3010, 3)));
        assert_eq!(parts.next(), Some(read(0x3018, 3)));
        assert_eq!(parts.next(), None);
        assert_eq!(read_cartridge(), read(0x3030, 20));
        let mut parts = CARTRIDGE_BLOCK.part_reads();
        assert_eq!(parts.next(), Some(read(0x3030, 13)));
        assert_eq!(parts.next(), Some(read(0x3040, 4)));
        assert_eq!(parts.next(), None);
        for plan in [STATUS_BLOCK, CARTRIDGE_BLOCK] {
            for part in plan.parts() {
                assert!(plan.block().contains(part.start));
                assert!(plan.block().contains(part.last()));
            }
        }
    }

    #[test]
    fn remote_mode_63_amps() {
        // :0110308000030600010FC0000066 (LRC 0x66 verified): cut, 63 A, automatic pressure.
        let words = enter_remote(
            OperatingMode::Cut,
            Amps::from_whole(63).unwrap(),
            Pressure::Auto,
        )
        .unwrap();
        assert_eq!(words, [0x0001, 0x0FC0, 0x0000]);
        assert_eq!(
            write_remote(&words),
            Request::WriteMultipleRegisters {
                start: 0x3080,
                values: Registers::BigEndian(&[0x00, 0x01, 0x0F, 0xC0, 0x00, 0x00])
            }
        );
        // Guide examples for the single registers: 65 A = 0x1040, 45 psi = 0x1680.
        let words = enter_remote(
            OperatingMode::Gouge,
            Amps::from_whole(65).unwrap(),
            Pressure::Set(Psi::from_whole(45).unwrap()),
        )
        .unwrap();
        assert_eq!(words, [0x0003, 0x1040, 0x1680]);
        assert_eq!(
            enter_remote(OperatingMode::Cut, Amps::ZERO, Pressure::Auto),
            Err(Error::Malformed)
        );
        assert_eq!(
            enter_remote(OperatingMode::Cut, Amps::from_raw(0xFFC0), Pressure::Auto),
            Err(Error::Malformed)
        );
        assert_eq!(
            enter_remote(
                OperatingMode::Cut,
                Amps::from_whole(45).unwrap(),
                Pressure::Set(Psi::from_raw(0x8000))
            ),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn exit_remote_zeros() {
        // The guide prints :01103080000306000000000000036 (one 0 too many); corrected, LRC
        // 0x36 verified: :0110308000030600000000000036.
        assert_eq!(
            exit_remote(),
            Request::WriteMultipleRegisters {
                start: 0x3080,
                values: Registers::Words(&[0, 0, 0])
            }
        );
    }

    #[test]
    fn identification_example() {
        // :0104020508EC -> 0x0508.
        let id = Identification::decode(Registers::BigEndian(&[0x05, 0x08])).unwrap();
        assert_eq!(id.raw, 0x0508);
        assert_eq!(
            id.torch,
            Some(TorchType {
                kind: TorchKind::Machine,
                lead: LeadLength::Upto15m
            })
        );
        assert_eq!(id.model, Some(SyncModel::Powermax105_Csa200_600));
        let unknown = Identification::decode(Registers::Words(&[0x0714])).unwrap();
        assert_eq!((unknown.torch, unknown.model), (None, None));
        assert_eq!(
            Identification::decode(Registers::Words(&[])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn permitted_settings_example() {
        // :01040A020107800B401D002700D8 -> 0x0201 (expanded metal, cut), 30 A, 45 A, 58 psi,
        // 78 psi.
        let data = [0x02, 0x01, 0x07, 0x80, 0x0B, 0x40, 0x1D, 0x00, 0x27, 0x00];
        let p = PermittedSettings::decode(Registers::BigEndian(&data)).unwrap();
        assert_eq!(p.modes, PermittedModes { high: 2, low: 1 });
        assert_eq!(p.modes.high_mode(), Some(OperatingMode::ContinuousPilotArc));
        assert_eq!(p.modes.low_mode(), Some(OperatingMode::Cut));
        assert!(p.modes.contains(OperatingMode::Cut));
        assert!(p.modes.contains(OperatingMode::ContinuousPilotArc));
        assert!(!p.modes.contains(OperatingMode::Gouge));
        assert_eq!(p.min_current, Amps::from_whole(30).unwrap());
        assert_eq!(p.max_current, Amps::from_whole(45).unwrap());
        assert_eq!(p.min_pressure, Psi::from_whole(58).unwrap());
        assert_eq!(p.max_pressure, Psi::from_whole(78).unwrap());
        let amps = |a| Amps::from_whole(a).unwrap();
        let psi = |p| Pressure::Set(Psi::from_whole(p).unwrap());
        assert!(p.allows(OperatingMode::Cut, amps(45), Pressure::Auto));
        assert!(p.allows(OperatingMode::Cut, amps(30), psi(58)));
        assert!(p.allows(OperatingMode::ContinuousPilotArc, amps(40), psi(78)));
        assert!(!p.allows(OperatingMode::Gouge, amps(40), Pressure::Auto));
        assert!(!p.allows(OperatingMode::Cut, amps(46), Pressure::Auto));
        assert!(!p.allows(OperatingMode::Cut, amps(29), Pressure::Auto));
        assert!(!p.allows(OperatingMode::Cut, amps(40), psi(79)));
        assert!(!p.allows(OperatingMode::Cut, amps(40), psi(57)));
        assert_eq!(
            PermittedSettings::decode(Registers::BigEndian(&data[..8])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn settings_example() {
        // :01040600011A40260074 -> cut, 105 A, 76 psi.
        let s =
            Process::decode(Registers::BigEndian(&[0x00, 0x01, 0x1A, 0x40, 0x26, 0x00])).unwrap();
        assert_eq!(s.mode, Some(OperatingMode::Cut));
        assert_eq!(s.current, Amps::from_whole(105).unwrap());
        assert_eq!(s.pressure, Pressure::Set(Psi::from_whole(76).unwrap()));
        let auto = Process::decode(Registers::Words(&[0, 0, 0])).unwrap();
        assert_eq!(auto.mode, None);
        assert_eq!(auto.pressure, Pressure::Auto);
    }

    #[test]
    fn actual_outputs_and_fault_examples() {
        // :010404104023DDA7 -> 65 A and 0x23DD = 9181/128 psi (the guide rounds to 72).
        let a = ActualOutputs::decode(Registers::BigEndian(&[0x10, 0x40, 0x23, 0xDD])).unwrap();
        assert_eq!(a.current, Amps::from_whole(65).unwrap());
        assert_eq!(a.pressure.raw(), 9181);
        // :01040201F404 -> 0-50-0.
        let f = decode_active_fault(Registers::BigEndian(&[0x01, 0xF4])).unwrap();
        assert_eq!(f, FaultCode(500));
        assert_eq!(
            decode_active_fault(Registers::BigEndian(&[0x01])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn status_block_ignores_gap() {
        let words = [
            0x0001, 0x1A40, 0x2600, 0xDEAD, 0xDEAD, 0xDEAD, 0xDEAD, 0xDEAD, 0x1040, 0x23DD, 0x01F4,
        ];
        let status = StatusBlock::decode(Registers::Words(&words)).unwrap();
        assert_eq!(status.settings.mode, Some(OperatingMode::Cut));
        assert_eq!(status.settings.current, Amps::from_whole(105).unwrap());
        assert_eq!(status.actual.current, Amps::from_whole(65).unwrap());
        assert_eq!(status.actual.pressure, Psi::from_raw(0x23DD));
        assert_eq!(status.fault, FaultCode(500));
        let mut zeroed = words;
        zeroed[3..8].fill(0);
        assert_eq!(StatusBlock::decode(Registers::Words(&zeroed)), Ok(status));
        // Assembled from the fallback parts.
        let mut buf = [0u16; 11];
        STATUS_BLOCK
            .place(0, Registers::Words(&words[..3]), &mut buf)
            .unwrap();
        STATUS_BLOCK
            .place(1, Registers::Words(&words[8..]), &mut buf)
            .unwrap();
        assert_eq!(StatusBlock::decode(Registers::Words(&buf)), Ok(status));
        assert_eq!(
            StatusBlock::decode(Registers::Words(&words[..10])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn ps_counters_example() {
        // :010410D1B6000010EB0000D0750000D5AE00069B (LRC verified).
        let data = [
            0xD1, 0xB6, 0x00, 0x00, 0x10, 0xEB, 0x00, 0x00, 0xD0, 0x75, 0x00, 0x00, 0xD5, 0xAE,
            0x00, 0x06,
        ];
        let c = PsCounters::decode(Registers::BigEndian(&data)).unwrap();
        assert_eq!(c.starts, 53_686);
        assert_eq!(c.pilot_arc_seconds, 4_331);
        assert_eq!(c.transfers, 53_365);
        assert_eq!(c.transfer_seconds, 447_918);
        assert_eq!(
            PsCounters::decode(Registers::BigEndian(&data[..14])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn cartridge_block() {
        let mut words = [0u16; 20];
        // UID "E00401D0036FB25D", part number "428936", revision 3, 105 A, counters from the
        // guide's example, 0xBEEF in the undocumented gap.
        let uid = b"E00401D0036FB25D";
        for (i, pair) in uid.chunks(2).enumerate() {
            words[i] = u16::from_be_bytes([pair[0], pair[1]]);
        }
        words[8..11].copy_from_slice(&[0x3432, 0x3839, 0x3336]);
        words[11] = 3;
        words[12] = 0x1A40;
        words[13..16].fill(0xBEEF);
        words[16..20].copy_from_slice(&[0x00D6, 0x0009, 0x00D3, 0x098F]);
        let c = Cartridge::decode(Registers::Words(&words)).unwrap();
        assert_eq!(c.uid.as_str(), Some("E00401D0036FB25D"));
        assert_eq!(c.part_number.as_str(), Some("428936"));
        assert_eq!(
            c.part_number.cartridge_type().unwrap().process,
            CartridgeProcess::Cut
        );
        assert_eq!(c.revision, 3);
        assert_eq!(c.nominal_current(), Amps::from_whole(105).unwrap());
        assert_eq!(c.counters.starts, 214);
        assert_eq!(c.counters.transfer_seconds(), 4894);
        assert_eq!(
            Cartridge::decode(Registers::Words(&words[..19])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn fault_log_example() {
        // The guide prints :0104080079007900000000001 (one 0 too many); corrected, LRC 0x01
        // verified: :010408007900790000000001 -> 0-12-1, 0-12-1, none, none.
        let data = [0x00, 0x79, 0x00, 0x79, 0, 0, 0, 0];
        let log = FaultLog::decode(Registers::BigEndian(&data)).unwrap();
        assert_eq!(
            log,
            FaultLog([FaultCode(121), FaultCode(121), FaultCode(0), FaultCode(0)])
        );
        assert_eq!(log.iter().count(), 2);
        assert_eq!(
            FaultLog::decode(Registers::BigEndian(&data[..7])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn signals_examples() {
        // :01010103FA -> Start and Motion on.
        assert_eq!(
            Signals::decode(&[0x03]),
            Ok(Signals {
                start: true,
                motion: true
            })
        );
    }
}
