//! Powermax SYNC specifics (registers 0x3xxx): what the driver polls, reads slowly, writes.

use heapless::Vec;
use plasma_protocol::modbus_ascii::Registers;
use plasma_protocol::powermax::sync::{
    self, CARTRIDGE_NAME_SPAN, FAULT_LOG_SPAN, IDENTIFICATION_SPAN, PERMITTED_SETTINGS_SPAN,
    PS_COUNTERS_SPAN, PermittedSettings, SETTINGS_SPAN, StatusBlock,
};
use plasma_protocol::powermax::{Amps, FaultCode, Pressure, Psi, RegisterSpan};

use crate::link::powermax::modbus::MbRequest;
use crate::link::status::{Limits, PowermaxProcess};

/// The poll: 0x3010-0x301A in one function-04 request (fallback: 0x3010-0x3012 and
/// 0x3018-0x301A).
pub(crate) const POLL_PLAN: plasma_protocol::powermax::BlockRead = sync::STATUS_BLOCK;

/// What one poll tells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PollData {
    /// Settings as the unit reports them.
    pub settings: PowermaxProcess,
    /// Actual output current.
    pub actual_current: Amps,
    /// Actual gas pressure.
    pub actual_pressure: Psi,
    /// Active fault.
    pub fault: FaultCode,
}

/// Decode a complete poll block.
pub(crate) fn decode_poll(registers: Registers<'_>) -> Option<PollData> {
    let block = StatusBlock::decode(registers).ok()?;
    Some(PollData {
        settings: PowermaxProcess {
            mode: block.settings.mode,
            current: block.settings.current,
            pressure: block.settings.pressure,
        },
        actual_current: block.actual.current,
        actual_pressure: block.actual.pressure,
        fault: block.fault,
    })
}

/// A read request for a span (function 04).
pub(crate) fn read(span: RegisterSpan) -> MbRequest {
    MbRequest::ReadInput {
        start: span.start,
        quantity: span.quantity,
    }
}

/// Slow-data items, in the order they are read (limits first: settings commands need them):
/// a SYNC unit's registers, and a legacy unit's torch-lead coils.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SlowItem {
    /// 0x3001-0x3005.
    Permitted,
    /// 0x3000.
    Identification,
    /// 0x3028-0x302F.
    PsCounters,
    /// 0x3030-0x3043 (block with fallback).
    Cartridge,
    /// 0x3044-0x3047.
    FaultLog,
    /// 0x3048-0x304D.
    CartridgeName,
    /// Legacy: the torch-lead coils 0x0808-0x0809 (a SYNC unit has its lead in 0x3000).
    TorchLead,
}

impl SlowItem {
    /// Every item, in reading order.
    pub(crate) const ALL: [SlowItem; 7] = [
        SlowItem::Permitted,
        SlowItem::Identification,
        SlowItem::PsCounters,
        SlowItem::Cartridge,
        SlowItem::FaultLog,
        SlowItem::CartridgeName,
        SlowItem::TorchLead,
    ];

    /// Bit in a pending-set.
    pub(crate) const fn bit(self) -> u8 {
        match self {
            SlowItem::Permitted => 1,
            SlowItem::Identification => 2,
            SlowItem::PsCounters => 4,
            SlowItem::Cartridge => 8,
            SlowItem::FaultLog => 16,
            SlowItem::CartridgeName => 32,
            SlowItem::TorchLead => 64,
        }
    }

    /// Items that depend on the installed cartridge.
    pub(crate) const CARTRIDGE_ITEMS: u8 = SlowItem::Permitted.bit()
        | SlowItem::Cartridge.bit()
        | SlowItem::FaultLog.bit()
        | SlowItem::CartridgeName.bit();

    /// Every item of a SYNC unit.
    pub(crate) const ALL_ITEMS: u8 = 0x3F;

    /// Every item of a legacy unit (the poll reads its registers).
    pub(crate) const LEGACY_ITEMS: u8 = SlowItem::TorchLead.bit();

    /// The single-span register read for this item (the cartridge block is read by its
    /// poller, the torch lead is coils).
    pub(crate) fn span(self) -> Option<RegisterSpan> {
        match self {
            SlowItem::Permitted => Some(PERMITTED_SETTINGS_SPAN),
            SlowItem::Identification => Some(IDENTIFICATION_SPAN),
            SlowItem::PsCounters => Some(PS_COUNTERS_SPAN),
            SlowItem::Cartridge | SlowItem::TorchLead => None,
            SlowItem::FaultLog => Some(FAULT_LOG_SPAN),
            SlowItem::CartridgeName => Some(CARTRIDGE_NAME_SPAN),
        }
    }
}

/// Permitted settings as link limits.
pub(crate) fn limits(registers: Registers<'_>) -> Option<Limits> {
    let p = PermittedSettings::decode(registers).ok()?;
    Some(Limits {
        modes: Some(p.modes),
        min_current: p.min_current,
        max_current: p.max_current,
        min_pressure: p.min_pressure,
        max_pressure: p.max_pressure,
    })
}

/// The one request that writes mode, current and pressure (0x3080-0x3082, function 0x10).
pub(crate) fn write_settings(words: [u16; 3]) -> MbRequest {
    MbRequest::WriteRegisters {
        start: sync::REMOTE_MODE,
        values: Vec::from_array(words),
    }
}

/// The words for `settings`; `None` when the protocol crate refuses them.
pub(crate) fn settings_words(
    mode: plasma_protocol::powermax::OperatingMode,
    current: Amps,
    pressure: Pressure,
) -> Option<[u16; 3]> {
    sync::enter_remote(mode, current, pressure).ok()
}

/// Read the settings back (0x3010-0x3012).
pub(crate) fn read_back() -> MbRequest {
    read(SETTINGS_SPAN)
}

/// Decode a settings read-back.
pub(crate) fn decode_process(registers: Registers<'_>) -> Option<PowermaxProcess> {
    let s = sync::Process::decode(registers).ok()?;
    Some(PowermaxProcess {
        mode: s.mode,
        current: s.current,
        pressure: s.pressure,
    })
}

/// Quick restart (0x308E-0x308F).
pub(crate) fn quick_restart() -> Option<MbRequest> {
    MbRequest::from_request(&sync::quick_restart())
}

/// Gas test coil 0x3180.
pub(crate) fn gas_test(on: bool) -> MbRequest {
    MbRequest::WriteCoil {
        address: sync::GAS_TEST_COIL,
        on,
    }
}

/// Zeros to 0x3080-0x3082 in one request.
pub(crate) fn exit_remote() -> MbRequest {
    write_settings(sync::EXIT_REMOTE_WORDS)
}

/// The active fault alone (0x301A), read between status polls.
pub(crate) fn read_fault() -> MbRequest {
    read(sync::ACTIVE_FAULT_SPAN)
}

/// UID read used to notice a cartridge change (0x3030-0x3037).
pub(crate) fn read_uid() -> MbRequest {
    read(sync::CARTRIDGE_UID_SPAN)
}
