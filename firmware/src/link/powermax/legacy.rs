//! Older Powermax specifics (registers 0x2xxx): poll block with fallbacks, force registers.
//!
//! The legacy guide wants the three force registers written "together, once, with correct
//! non-zero values" and shows only single-register writes (0x2095 between them is not
//! documented, so one 0x10 write over 0x2093-0x2096 would touch it). The link therefore
//! sends mode (0x2093), current (0x2094) and pressure (0x2096) with function 06 back to back
//! with nothing in between; for automatic pressure it writes a permitted set point first
//! (the legacy guide's "non-zero" rule) and then 0. Leaving remote writes 0 to all three.

use plasma_protocol::modbus_ascii::Registers;
use plasma_protocol::powermax::legacy::{
    self, FULL_BLOCK, LegacyFullStatus, LegacyStatus, MODE_FORCE,
};
use plasma_protocol::powermax::{Amps, FaultCode, OperatingMode, Pressure};

use crate::link::powermax::modbus::{BlockPoller, MbRequest};
use crate::link::status::{Limits, PowermaxProcess};

/// The poll: 0x2093-0x209F in one request (force registers read back, fault, limits, arc
/// time), falling back to its documented parts on exception 02; a part the unit refuses
/// too (e.g. the write-only force registers) is left out from then on.
pub(crate) const POLL_PLAN: plasma_protocol::powermax::BlockRead = FULL_BLOCK;

/// Part indexes of [`POLL_PLAN`].
const PART_MODE_CURRENT: usize = 0;
const PART_PRESSURE: usize = 1;
const PART_FAULT_LIMITS: usize = 2;
const PART_PRESSURE_LIMITS_ARC: usize = 3;
/// Offset of 0x2098 in the block.
const STATUS_OFFSET: usize = 5;

/// What one poll tells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PollData {
    /// Force registers as read back, when the unit allows reading them.
    pub settings: Option<PowermaxProcess>,
    /// Active fault.
    pub fault: FaultCode,
    /// Limits.
    pub limits: Limits,
    /// Arc-on time, seconds.
    pub arc_seconds: u32,
}

/// Decode what a poll cycle read.
pub(crate) fn decode_poll(poller: &BlockPoller) -> Option<PollData> {
    let registers = poller.registers();
    if !poller.uses_parts() {
        let full = LegacyFullStatus::decode(registers).ok()?;
        return Some(from_parts(Some(full.settings), full.status));
    }
    if !(poller.part_read(PART_FAULT_LIMITS) && poller.part_read(PART_PRESSURE_LIMITS_ARC)) {
        return None;
    }
    let mut status_words = [0u16; 8];
    for (i, slot) in status_words.iter_mut().enumerate() {
        *slot = registers.get(STATUS_OFFSET + i)?;
    }
    let status = LegacyStatus::decode(Registers::Words(&status_words)).ok()?;
    let settings = if poller.part_read(PART_MODE_CURRENT) && poller.part_read(PART_PRESSURE) {
        LegacyFullStatus::decode(registers).ok().map(|f| f.settings)
    } else {
        None
    };
    Some(from_parts(settings, status))
}

fn from_parts(settings: Option<legacy::LegacyProcess>, status: LegacyStatus) -> PollData {
    PollData {
        settings: settings.map(|s| PowermaxProcess {
            mode: s.mode,
            current: s.current,
            pressure: s.pressure,
        }),
        fault: status.fault,
        limits: Limits {
            modes: None,
            min_current: status.min_current,
            max_current: status.max_current,
            min_pressure: status.min_pressure,
            max_pressure: status.max_pressure,
        },
        arc_seconds: status.arc_seconds,
    }
}

/// The writes that enter remote control, in order (see the module docs).
pub(crate) fn settings_writes(
    mode: OperatingMode,
    current: Amps,
    pressure: Pressure,
    limits: &Limits,
) -> heapless::Vec<MbRequest, 4> {
    let mut writes = heapless::Vec::new();
    let first_pressure = pressure.psi().unwrap_or(limits.min_pressure);
    let _ = writes.push(write(MODE_FORCE, mode.to_legacy()));
    let _ = writes.push(write(legacy::CURRENT_FORCE, current.raw()));
    let _ = writes.push(write(legacy::PRESSURE_FORCE, first_pressure.raw()));
    if pressure == Pressure::Auto {
        let _ = writes.push(write(legacy::PRESSURE_FORCE, 0));
    }
    writes
}

/// Zeros to the three force registers, in order.
pub(crate) fn exit_writes() -> [MbRequest; 3] {
    [
        write(MODE_FORCE, 0),
        write(legacy::CURRENT_FORCE, 0),
        write(legacy::PRESSURE_FORCE, 0),
    ]
}

fn write(address: u16, value: u16) -> MbRequest {
    MbRequest::WriteRegister { address, value }
}

/// Fault read (0x2098): between status polls, and to confirm the unit took the settings (no
/// 0-11-n fault).
pub(crate) fn read_fault() -> MbRequest {
    MbRequest::ReadInput {
        start: legacy::FAULT_CODE,
        quantity: 1,
    }
}

/// The torch-lead coils 0x0808-0x0809 (slow data).
pub(crate) fn read_torch_lead() -> MbRequest {
    MbRequest::ReadCoils {
        start: legacy::TORCH_LEAD_BIT0_COIL,
        quantity: 2,
    }
}

/// Gas test coil 0x0832 (SYNC guide Table 1).
pub(crate) fn gas_test(on: bool) -> MbRequest {
    MbRequest::WriteCoil {
        address: legacy::GAS_TEST_COIL,
        on,
    }
}

/// True for the 0-11-n faults a unit raises for settings it does not permit.
pub(crate) fn is_setting_fault(fault: FaultCode) -> bool {
    (110..=112).contains(&fault.0)
}

#[cfg(test)]
mod tests;
