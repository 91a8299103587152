//! A catalogue of every documented Powermax register and coil: its name, how to read its
//! value, and whether a CNC may write it.
//!
//! Used to explain frames to a technician (`pbtool decode`) and to decide which raw Modbus
//! writes the bridge forwards (only to documented writable addresses).

use super::{legacy, sync};

/// How a register's 16-bit value is to be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ValueKind {
    /// Amps x 64.
    Amps,
    /// Psi x 128, where a setting of 0 means automatic pressure.
    Psi,
    /// A decimal-coded fault code (`0-50-0`).
    Fault,
    /// An operating mode number.
    Mode,
    /// High byte and low byte are separate ids (identification, permitted modes).
    BytePair,
    /// Two ASCII characters, first character in the high byte.
    Ascii,
    /// Half of a 32-bit counter, low word first: `high` tells which half.
    Counter32 {
        /// True for the high word.
        high: bool,
    },
    /// A 16-bit count.
    Count,
    /// A 16-bit count of 2-second units.
    TwoSeconds,
    /// A value with no scaling (magic command words, revision).
    Raw,
}

/// Who may write an address.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Access {
    /// Read with function 03/04 (or 01 for coils).
    Read,
    /// Written by the CNC (function 06/0x10, or 05 for coils); may also be read.
    Write,
}

/// One documented register or coil.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RegisterInfo {
    /// First address of the run this entry describes.
    pub first: u16,
    /// Last address of the run (same as `first` for a single register).
    pub last: u16,
    /// Name as a technician would say it.
    pub name: &'static str,
    /// How to read the value.
    pub kind: ValueKind,
    /// Read-only or writable.
    pub access: Access,
}

const fn reg(
    first: u16,
    last: u16,
    name: &'static str,
    kind: ValueKind,
    access: Access,
) -> RegisterInfo {
    RegisterInfo {
        first,
        last,
        name,
        kind,
        access,
    }
}

use Access::{Read, Write};
use ValueKind::*;

/// Registers of Powermax SYNC units (SYNC guide register map, 0x3000-0x308F).
pub const SYNC_REGISTERS: &[RegisterInfo] = &[
    reg(
        sync::IDENTIFICATION,
        sync::IDENTIFICATION,
        "torch and power supply id",
        BytePair,
        Read,
    ),
    reg(
        sync::PERMITTED_MODES,
        sync::PERMITTED_MODES,
        "permitted operating modes",
        BytePair,
        Read,
    ),
    reg(
        sync::PERMITTED_MIN_CURRENT,
        sync::PERMITTED_MIN_CURRENT,
        "permitted minimum current",
        Amps,
        Read,
    ),
    reg(
        sync::PERMITTED_MAX_CURRENT,
        sync::PERMITTED_MAX_CURRENT,
        "permitted maximum current",
        Amps,
        Read,
    ),
    reg(
        sync::PERMITTED_MIN_PRESSURE,
        sync::PERMITTED_MIN_PRESSURE,
        "permitted minimum pressure",
        Psi,
        Read,
    ),
    reg(
        sync::PERMITTED_MAX_PRESSURE,
        sync::PERMITTED_MAX_PRESSURE,
        "permitted maximum pressure",
        Psi,
        Read,
    ),
    reg(
        sync::MODE_SETTING,
        sync::MODE_SETTING,
        "operating mode setting",
        Mode,
        Read,
    ),
    reg(
        sync::CURRENT_SETTING,
        sync::CURRENT_SETTING,
        "current setting",
        Amps,
        Read,
    ),
    reg(
        sync::PRESSURE_SETTING,
        sync::PRESSURE_SETTING,
        "pressure setting",
        Psi,
        Read,
    ),
    reg(
        sync::ACTUAL_CURRENT,
        sync::ACTUAL_CURRENT,
        "actual output current",
        Amps,
        Read,
    ),
    reg(
        sync::ACTUAL_PRESSURE,
        sync::ACTUAL_PRESSURE,
        "actual gas pressure",
        Psi,
        Read,
    ),
    reg(
        sync::ACTIVE_FAULT,
        sync::ACTIVE_FAULT,
        "active fault",
        Fault,
        Read,
    ),
    reg(
        sync::PS_STARTS_LOW,
        sync::PS_STARTS_LOW,
        "total starts (low word)",
        Counter32 { high: false },
        Read,
    ),
    reg(
        sync::PS_STARTS_HIGH,
        sync::PS_STARTS_HIGH,
        "total starts (high word)",
        Counter32 { high: true },
        Read,
    ),
    reg(
        sync::PS_PILOT_ARC_TIME_LOW,
        sync::PS_PILOT_ARC_TIME_LOW,
        "pilot arc seconds (low word)",
        Counter32 { high: false },
        Read,
    ),
    reg(
        sync::PS_PILOT_ARC_TIME_HIGH,
        sync::PS_PILOT_ARC_TIME_HIGH,
        "pilot arc seconds (high word)",
        Counter32 { high: true },
        Read,
    ),
    reg(
        sync::PS_TRANSFERS_LOW,
        sync::PS_TRANSFERS_LOW,
        "arc transfers (low word)",
        Counter32 { high: false },
        Read,
    ),
    reg(
        sync::PS_TRANSFERS_HIGH,
        sync::PS_TRANSFERS_HIGH,
        "arc transfers (high word)",
        Counter32 { high: true },
        Read,
    ),
    reg(
        sync::PS_TRANSFER_TIME_LOW,
        sync::PS_TRANSFER_TIME_LOW,
        "arc transfer seconds (low word)",
        Counter32 { high: false },
        Read,
    ),
    reg(
        sync::PS_TRANSFER_TIME_HIGH,
        sync::PS_TRANSFER_TIME_HIGH,
        "arc transfer seconds (high word)",
        Counter32 { high: true },
        Read,
    ),
    reg(
        sync::CARTRIDGE_UID,
        sync::CARTRIDGE_UID_END,
        "cartridge UID",
        Raw,
        Read,
    ),
    reg(
        sync::CARTRIDGE_PART_NUMBER,
        sync::CARTRIDGE_PART_NUMBER_END,
        "cartridge part number",
        Ascii,
        Read,
    ),
    reg(
        sync::CARTRIDGE_REVISION,
        sync::CARTRIDGE_REVISION,
        "cartridge revision",
        Raw,
        Read,
    ),
    reg(
        sync::CARTRIDGE_NOMINAL_CURRENT,
        sync::CARTRIDGE_NOMINAL_CURRENT,
        "cartridge nominal current",
        Amps,
        Read,
    ),
    reg(
        sync::CARTRIDGE_STARTS,
        sync::CARTRIDGE_STARTS,
        "cartridge starts",
        Count,
        Read,
    ),
    reg(
        sync::CARTRIDGE_PILOT_ARC_TIME,
        sync::CARTRIDGE_PILOT_ARC_TIME,
        "cartridge pilot arc seconds",
        Count,
        Read,
    ),
    reg(
        sync::CARTRIDGE_TRANSFERS,
        sync::CARTRIDGE_TRANSFERS,
        "cartridge arc transfers",
        Count,
        Read,
    ),
    reg(
        sync::CARTRIDGE_TRANSFER_TIME,
        sync::CARTRIDGE_TRANSFER_TIME,
        "cartridge arc transfer time",
        TwoSeconds,
        Read,
    ),
    reg(
        sync::FAULT_LOG_0,
        sync::FAULT_LOG_3,
        "fault log (newest first)",
        Fault,
        Read,
    ),
    reg(
        sync::CARTRIDGE_NAME,
        sync::CARTRIDGE_NAME_END,
        "cartridge name",
        Ascii,
        Read,
    ),
    reg(
        sync::REMOTE_MODE,
        sync::REMOTE_MODE,
        "remote operating mode",
        Mode,
        Write,
    ),
    reg(
        sync::REMOTE_CURRENT,
        sync::REMOTE_CURRENT,
        "remote current",
        Amps,
        Write,
    ),
    reg(
        sync::REMOTE_PRESSURE,
        sync::REMOTE_PRESSURE,
        "remote pressure",
        Psi,
        Write,
    ),
    reg(
        sync::QUICK_RESTART_COMMAND,
        sync::QUICK_RESTART_COMMAND,
        "quick restart command",
        Raw,
        Write,
    ),
    reg(
        sync::QUICK_RESTART_APPROVAL,
        sync::QUICK_RESTART_APPROVAL,
        "quick restart approval",
        Raw,
        Write,
    ),
];

/// Coils of Powermax SYNC units.
pub const SYNC_COILS: &[RegisterInfo] = &[
    reg(
        sync::START_SIGNAL_COIL,
        sync::START_SIGNAL_COIL,
        "start signal",
        Raw,
        Read,
    ),
    reg(
        sync::MOTION_SIGNAL_COIL,
        sync::MOTION_SIGNAL_COIL,
        "motion signal",
        Raw,
        Read,
    ),
    reg(
        sync::GAS_TEST_COIL,
        sync::GAS_TEST_COIL,
        "gas test",
        Raw,
        Write,
    ),
];

/// Registers of legacy Powermax units (0x2xxx, Powermax65/85 protocol and the SYNC guide's
/// legacy column).
pub const LEGACY_REGISTERS: &[RegisterInfo] = &[
    reg(
        legacy::ACTUAL_PRESSURE,
        legacy::ACTUAL_PRESSURE,
        "actual gas pressure",
        Psi,
        Read,
    ),
    reg(
        legacy::MODE_FORCE,
        legacy::MODE_FORCE,
        "cut mode force",
        Mode,
        Write,
    ),
    reg(
        legacy::CURRENT_FORCE,
        legacy::CURRENT_FORCE,
        "current force",
        Amps,
        Write,
    ),
    reg(
        legacy::PRESSURE_FORCE,
        legacy::PRESSURE_FORCE,
        "pressure force",
        Psi,
        Write,
    ),
    reg(
        legacy::FAULT_CODE,
        legacy::FAULT_CODE,
        "fault code",
        Fault,
        Read,
    ),
    reg(
        legacy::CURRENT_MIN,
        legacy::CURRENT_MIN,
        "minimum current",
        Amps,
        Read,
    ),
    reg(
        legacy::CURRENT_MAX,
        legacy::CURRENT_MAX,
        "maximum current",
        Amps,
        Read,
    ),
    reg(
        legacy::PRESSURE_MIN,
        legacy::PRESSURE_MIN,
        "minimum pressure",
        Psi,
        Read,
    ),
    reg(
        legacy::PRESSURE_MAX,
        legacy::PRESSURE_MAX,
        "maximum pressure",
        Psi,
        Read,
    ),
    reg(
        legacy::ARC_TIME_LOW,
        legacy::ARC_TIME_LOW,
        "arc seconds (low word)",
        Counter32 { high: false },
        Read,
    ),
    reg(
        legacy::ARC_TIME_HIGH,
        legacy::ARC_TIME_HIGH,
        "arc seconds (high word)",
        Counter32 { high: true },
        Read,
    ),
];

/// Coils of legacy Powermax units.
pub const LEGACY_COILS: &[RegisterInfo] = &[
    reg(
        legacy::TORCH_LEAD_BIT0_COIL,
        legacy::TORCH_LEAD_BIT1_COIL,
        "torch lead length",
        Raw,
        Read,
    ),
    reg(
        legacy::START_SIGNAL_COIL,
        legacy::START_SIGNAL_COIL,
        "start signal",
        Raw,
        Read,
    ),
    reg(
        legacy::MOTION_SIGNAL_COIL,
        legacy::MOTION_SIGNAL_COIL,
        "motion signal",
        Raw,
        Read,
    ),
    reg(
        legacy::GAS_TEST_COIL,
        legacy::GAS_TEST_COIL,
        "gas test",
        Raw,
        Write,
    ),
];

fn find(table: &'static [RegisterInfo], address: u16) -> Option<&'static RegisterInfo> {
    table.iter().find(|r| (r.first..=r.last).contains(&address))
}

/// The documented register at `address` (either family: their address ranges do not overlap).
pub fn register(address: u16) -> Option<&'static RegisterInfo> {
    find(SYNC_REGISTERS, address).or_else(|| find(LEGACY_REGISTERS, address))
}

/// The documented coil at `address` (either family).
pub fn coil(address: u16) -> Option<&'static RegisterInfo> {
    find(SYNC_COILS, address).or_else(|| find(LEGACY_COILS, address))
}

/// True when every register in `start..start+quantity` is documented and writable.
pub fn registers_writable(start: u16, quantity: u16) -> bool {
    quantity > 0
        && (0..quantity).all(|i| {
            start
                .checked_add(i)
                .and_then(register)
                .is_some_and(|r| r.access == Access::Write)
        })
}

/// True when the coil at `address` is documented and writable.
pub fn coil_writable(address: u16) -> bool {
    coil(address).is_some_and(|c| c.access == Access::Write)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remote_mode_registers_are_writable_and_nothing_else_in_between() {
        assert!(registers_writable(0x3080, 3));
        assert!(!registers_writable(0x3080, 4), "0x3083 is undocumented");
        assert!(registers_writable(0x308E, 2));
        assert!(
            !registers_writable(0x3010, 1),
            "settings read-back is read-only"
        );
        assert!(!registers_writable(0x2095, 1), "0x2095 is undocumented");
        assert!(registers_writable(0x2093, 2));
        assert!(!registers_writable(0x3080, 0));
        assert!(!registers_writable(0xFFFF, 2), "no wrap-around");
    }

    #[test]
    fn lookups_name_every_family() {
        assert_eq!(register(0x301A).map(|r| r.kind), Some(ValueKind::Fault));
        assert_eq!(
            register(0x3046).map(|r| r.name),
            Some("fault log (newest first)")
        );
        assert_eq!(register(0x2098).map(|r| r.name), Some("fault code"));
        assert_eq!(register(0x3013), None);
        assert!(coil_writable(0x3180));
        assert!(coil_writable(0x0832));
        assert!(!coil_writable(0x3100));
        assert_eq!(coil(0x0809).map(|c| c.name), Some("torch lead length"));
    }

    #[test]
    fn tables_have_no_overlapping_runs() {
        for table in [SYNC_REGISTERS, LEGACY_REGISTERS, SYNC_COILS, LEGACY_COILS] {
            for (i, a) in table.iter().enumerate() {
                assert!(a.first <= a.last, "{}", a.name);
                for b in table.iter().skip(i + 1) {
                    assert!(
                        a.last < b.first || b.last < a.first,
                        "{} overlaps {}",
                        a.name,
                        b.name
                    );
                }
            }
        }
    }
}
