//! Legacy Powermax register map (0x2xxx; Powermax65/85/105/125 and 45 XP), also answered by
//! SYNC units for backward compatibility.
//!
//! Sources: the Powermax65/85 Serial Communication Protocol (807220) for the force registers,
//! fault code, limits, arc time and torch-lead coils, and Table 1 of the SYNC guide for
//! 0x204C, the Start/Motion coils 0x0810/0x0811 and the gas-test coil 0x0832.
//!
//! # Remote control ("force registers")
//! The legacy guide: "the CNC needs to write to all three force registers together, once, with
//! correct non-zero values. Afterward, the CNC can write to the force registers one at a time
//! as needed. To return the power supply to manual control, all force registers must be set to
//! zero." The force registers 0x2093, 0x2094 and 0x2096 are not consecutive (0x2095 is not
//! documented), and the guide shows them written with function 06 only (SYNC Table 1 agrees),
//! so [`enter_remote`] gives three single-register writes, mode, current and pressure, to be
//! sent back to back. Pressure must be a real set point for that first write; automatic
//! pressure is selected afterwards with [`set_pressure`]`(Pressure::Auto)`.

use super::fault::FaultCode;
use super::mode::OperatingMode;
use super::plan::{BlockRead, RegisterSpan, need, u32_low_first, word};
use crate::modbus_ascii::{Registers, Request};
use crate::units::{Amps, Pressure, Psi};
use crate::{Error, Result};

// ---------------------------------------------------------------------------------------------
// Register and coil addresses

/// Actual gas pressure, psi x 128 (read; from SYNC Table 1, SYNC equivalent 0x3019).
pub const ACTUAL_PRESSURE: u16 = 0x204C;
/// `cut_mode_force`: 1 normal, 2 CPA, 3 gouge (write, function 06).
pub const MODE_FORCE: u16 = 0x2093;
/// `current_set_force`: A x 64 (write, function 06).
pub const CURRENT_FORCE: u16 = 0x2094;
/// `pressure_set_force`: psi x 128, 0 = automatic gas mode (write, function 06).
pub const PRESSURE_FORCE: u16 = 0x2096;
/// `fault_code`: active fault (read).
pub const FAULT_CODE: u16 = 0x2098;
/// `current_set_min`: minimum current setting, A x 64 (read).
pub const CURRENT_MIN: u16 = 0x2099;
/// `current_set_max`: maximum current setting, A x 64 (read).
pub const CURRENT_MAX: u16 = 0x209A;
/// `pressure_set_min`: minimum pressure setting, psi x 128 (read).
pub const PRESSURE_MIN: u16 = 0x209C;
/// `pressure_set_max`: maximum pressure setting, psi x 128 (read).
pub const PRESSURE_MAX: u16 = 0x209D;
/// `arc_time_low`: arc-on time in seconds, low 16 bits (read with 0x209F).
pub const ARC_TIME_LOW: u16 = 0x209E;
/// `arc_time_high`: arc-on time in seconds, high 16 bits.
pub const ARC_TIME_HIGH: u16 = 0x209F;

/// Coil: torch lead length bit 0 (`torch_index`, read 2 coils from here).
pub const TORCH_LEAD_BIT0_COIL: u16 = 0x0808;
/// Coil: torch lead length bit 1.
pub const TORCH_LEAD_BIT1_COIL: u16 = 0x0809;
/// Coil: Start switch signal status (from SYNC Table 1).
pub const START_SIGNAL_COIL: u16 = 0x0810;
/// Coil: Motion switch signal status (from SYNC Table 1).
pub const MOTION_SIGNAL_COIL: u16 = 0x0811;
/// Coil: gas test, written with function 05 (from SYNC Table 1).
pub const GAS_TEST_COIL: u16 = 0x0832;

// ---------------------------------------------------------------------------------------------
// Read plans

static STATUS_PARTS: [RegisterSpan; 2] = [
    RegisterSpan::new(FAULT_CODE, 3),
    RegisterSpan::new(PRESSURE_MIN, 4),
];
/// 0x2098-0x209F: fault, limits and arc time. Crosses the undocumented 0x209B; the fallback
/// reads 0x2098-0x209A and 0x209C-0x209F.
pub const STATUS_BLOCK: BlockRead = BlockRead::new(RegisterSpan::new(FAULT_CODE, 8), &STATUS_PARTS);

static FULL_PARTS: [RegisterSpan; 4] = [
    RegisterSpan::new(MODE_FORCE, 2),
    RegisterSpan::new(PRESSURE_FORCE, 1),
    RegisterSpan::new(FAULT_CODE, 3),
    RegisterSpan::new(PRESSURE_MIN, 4),
];
/// 0x2093-0x209F: the force registers read back, then [`STATUS_BLOCK`]. Crosses the
/// undocumented 0x2095, 0x2097 and 0x209B. The guide documents the force registers as written
/// only; reading them back is what the fallback's first two parts try, and a unit may refuse
/// them too (then use [`STATUS_BLOCK`]).
pub const FULL_BLOCK: BlockRead = BlockRead::new(RegisterSpan::new(MODE_FORCE, 13), &FULL_PARTS);

/// Offset of 0x2098 in [`FULL_BLOCK`].
const STATUS_OFFSET: usize = 5;

// ---------------------------------------------------------------------------------------------
// Requests

/// Read the active fault, 0x2098 (`:010420980001420D0A`).
pub const fn read_fault() -> Request<'static> {
    RegisterSpan::new(FAULT_CODE, 1).read()
}

/// Read the minimum current, 0x2099 (`:010420990001410D0A`).
pub const fn read_current_min() -> Request<'static> {
    RegisterSpan::new(CURRENT_MIN, 1).read()
}

/// Read the maximum current, 0x209A (`:0104209A0001400D0A`).
pub const fn read_current_max() -> Request<'static> {
    RegisterSpan::new(CURRENT_MAX, 1).read()
}

/// Read the minimum pressure, 0x209C (`:0104209C00013E0D0A`).
pub const fn read_pressure_min() -> Request<'static> {
    RegisterSpan::new(PRESSURE_MIN, 1).read()
}

/// Read the maximum pressure, 0x209D (`:0104209D00013D0D0A`).
pub const fn read_pressure_max() -> Request<'static> {
    RegisterSpan::new(PRESSURE_MAX, 1).read()
}

/// Read the arc time, 0x209E-0x209F (`:0104209E00023B0D0A`).
pub const fn read_arc_time() -> Request<'static> {
    RegisterSpan::new(ARC_TIME_LOW, 2).read()
}

/// Read the actual gas pressure, 0x204C.
pub const fn read_actual_pressure() -> Request<'static> {
    RegisterSpan::new(ACTUAL_PRESSURE, 1).read()
}

/// Read 0x2098-0x209F in one request (see [`STATUS_BLOCK`] for the fallback).
pub const fn read_status_block() -> Request<'static> {
    STATUS_BLOCK.read()
}

/// Read 0x2093-0x209F in one request (see [`FULL_BLOCK`]).
pub const fn read_full_block() -> Request<'static> {
    FULL_BLOCK.read()
}

/// Read the two torch-lead coils 0x0808-0x0809 (`:010108080002EC`); decode with
/// [`LeadLength::from_legacy_coils`](super::LeadLength::from_legacy_coils).
pub const fn read_torch_lead() -> Request<'static> {
    Request::ReadCoils {
        start: TORCH_LEAD_BIT0_COIL,
        quantity: 2,
    }
}

/// Read the Start and Motion coils 0x0810-0x0811; decode with
/// [`Signals::decode`](super::Signals::decode).
pub const fn read_signals() -> Request<'static> {
    Request::ReadCoils {
        start: START_SIGNAL_COIL,
        quantity: 2,
    }
}

/// Start (`true`) or stop (`false`) a gas test (coil 0x0832).
pub const fn gas_test(on: bool) -> Request<'static> {
    Request::WriteSingleCoil {
        address: GAS_TEST_COIL,
        on,
    }
}

/// Write the mode force register (`:01062093xxxxcc`).
pub const fn set_mode(mode: OperatingMode) -> Request<'static> {
    Request::WriteSingleRegister {
        address: MODE_FORCE,
        value: mode.to_legacy(),
    }
}

/// Write the current force register (`:01062094xxxxcc`).
pub const fn set_current(current: Amps) -> Request<'static> {
    Request::WriteSingleRegister {
        address: CURRENT_FORCE,
        value: current.raw(),
    }
}

/// Write the pressure force register (`:01062096xxxxcc`); [`Pressure::Auto`] writes 0.
pub const fn set_pressure(pressure: Pressure) -> Request<'static> {
    Request::WriteSingleRegister {
        address: PRESSURE_FORCE,
        value: pressure.raw(),
    }
}

/// The three writes that enter remote control, in the order to send them: mode (0x2093),
/// current (0x2094), pressure (0x2096). See the module docs.
///
/// [`Error::Malformed`] unless current and pressure are above zero: the guide asks for
/// "correct non-zero values" in all three.
pub fn enter_remote(
    mode: OperatingMode,
    current: Amps,
    pressure: Psi,
) -> Result<[Request<'static>; 3]> {
    if !current.is_positive() || !pressure.is_positive() {
        return Err(Error::Malformed);
    }
    Ok([
        set_mode(mode),
        set_current(current),
        set_pressure(Pressure::Set(pressure)),
    ])
}

/// The three writes that return to manual control: zero in every force register.
pub const fn exit_remote() -> [Request<'static>; 3] {
    [
        Request::WriteSingleRegister {
            address: MODE_FORCE,
            value: 0,
        },
        Request::WriteSingleRegister {
            address: CURRENT_FORCE,
            value: 0,
        },
        Request::WriteSingleRegister {
            address: PRESSURE_FORCE,
            value: 0,
        },
    ]
}

// ---------------------------------------------------------------------------------------------
// Decoders (same rules as the SYNC ones: extra registers ignored, missing ones Truncated)

/// Decodes a one-register fault read (0x2098).
pub fn decode_fault(registers: Registers<'_>) -> Result<FaultCode> {
    word(&registers, 0).map(FaultCode)
}

/// Decodes a one-register current read (0x2099, 0x209A).
pub fn decode_current(registers: Registers<'_>) -> Result<Amps> {
    word(&registers, 0).map(Amps::from_raw)
}

/// Decodes a one-register pressure read (0x209C, 0x209D, 0x204C).
pub fn decode_pressure(registers: Registers<'_>) -> Result<Psi> {
    word(&registers, 0).map(Psi::from_raw)
}

/// Decodes the arc time read (0x209E low word, 0x209F high word), in seconds.
pub fn decode_arc_time(registers: Registers<'_>) -> Result<u32> {
    u32_low_first(&registers, 0)
}

/// 0x2098-0x209F.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LegacyStatus {
    /// Active fault.
    pub fault: FaultCode,
    /// Minimum current setting.
    pub min_current: Amps,
    /// Maximum current setting.
    pub max_current: Amps,
    /// Minimum pressure setting.
    pub min_pressure: Psi,
    /// Maximum pressure setting.
    pub max_pressure: Psi,
    /// Arc-on time, seconds.
    pub arc_seconds: u32,
}

impl LegacyStatus {
    /// Decodes the 8 registers of [`STATUS_BLOCK`]; 0x209B is not looked at.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, STATUS_BLOCK.len())?;
        Ok(LegacyStatus {
            fault: FaultCode(word(&registers, 0)?),
            min_current: Amps::from_raw(word(&registers, 1)?),
            max_current: Amps::from_raw(word(&registers, 2)?),
            min_pressure: Psi::from_raw(word(&registers, 4)?),
            max_pressure: Psi::from_raw(word(&registers, 5)?),
            arc_seconds: u32_low_first(&registers, 6)?,
        })
    }
}

/// The force registers read back (0x2093, 0x2094, 0x2096).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LegacyProcess {
    /// Mode; `None` for 0 (not in remote control) or an unlisted value.
    pub mode: Option<OperatingMode>,
    /// Current.
    pub current: Amps,
    /// Pressure (0 = automatic).
    pub pressure: Pressure,
}

/// 0x2093-0x209F.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LegacyFullStatus {
    /// 0x2093-0x2096.
    pub settings: LegacyProcess,
    /// 0x2098-0x209F.
    pub status: LegacyStatus,
}

impl LegacyFullStatus {
    /// Decodes the 13 registers of [`FULL_BLOCK`]; 0x2095, 0x2097 and 0x209B are not looked at.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, FULL_BLOCK.len())?;
        let mut status = [0u16; 8];
        for (i, slot) in status.iter_mut().enumerate() {
            *slot = word(&registers, STATUS_OFFSET + i)?;
        }
        Ok(LegacyFullStatus {
            settings: LegacyProcess {
                mode: OperatingMode::from_legacy(word(&registers, 0)?),
                current: Amps::from_raw(word(&registers, 1)?),
                pressure: Pressure::from_raw(word(&registers, 3)?),
            },
            status: LegacyStatus::decode(Registers::Words(&status))?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::powermax::{LeadLength, Signals};

    fn read(start: u16, quantity: u16) -> Request<'static> {
        Request::ReadInputRegisters { start, quantity }
    }

    fn write(address: u16, value: u16) -> Request<'static> {
        Request::WriteSingleRegister { address, value }
    }

    #[test]
    fn addresses() {
        let map: [(u16, u16); 16] = [
            (ACTUAL_PRESSURE, 0x204C),
            (MODE_FORCE, 0x2093),
            (CURRENT_FORCE, 0x2094),
            (PRESSURE_FORCE, 0x2096),
            (FAULT_CODE, 0x2098),
            (CURRENT_MIN, 0x2099),
            (CURRENT_MAX, 0x209A),
            (PRESSURE_MIN, 0x209C),
            (PRESSURE_MAX, 0x209D),
            (ARC_TIME_LOW, 0x209E),
            (ARC_TIME_HIGH, 0x209F),
            (TORCH_LEAD_BIT0_COIL, 0x0808),
            (TORCH_LEAD_BIT1_COIL, 0x0809),
            (START_SIGNAL_COIL, 0x0810),
            (MOTION_SIGNAL_COIL, 0x0811),
            (GAS_TEST_COIL, 0x0832),
        ];
        for (got, want) in map {
            assert_eq!(got, want);
        }
    }

    #[test]
    fn mode_force_samples() {
        // :010620930001450D0A normal, :010620930002440D0A CPA, :010620930003430D0A gouge.
        assert_eq!(set_mode(OperatingMode::Cut), write(0x2093, 1));
        assert_eq!(
            set_mode(OperatingMode::ContinuousPilotArc),
            write(0x2093, 2)
        );
        assert_eq!(set_mode(OperatingMode::Gouge), write(0x2093, 3));
    }

    #[test]
    fn current_force_samples() {
        // :010620940A003B 40 A; :010620941040F5 65 A; :010620941540F0 85 A;
        // :010620940DE058 55.5 A. The 45 A sample is printed :0106209400B40FA (a stray 0);
        // corrected, LRC 0xFA verified: :010620940B40FA.
        for (text, raw) in [
            ("40", 0x0A00),
            ("45", 0x0B40),
            ("65", 0x1040),
            ("85", 0x1540),
            ("55.5", 0x0DE0),
        ] {
            let amps: Amps = text.parse().unwrap();
            assert_eq!(set_current(amps), write(0x2094, raw), "{text}");
        }
    }

    #[test]
    fn pressure_force_samples() {
        // :010620961680AD 45 psi; :01062096230020 70 psi; 0 = automatic.
        let psi = |p| Pressure::Set(Psi::from_whole(p).unwrap());
        assert_eq!(set_pressure(psi(45)), write(0x2096, 0x1680));
        assert_eq!(set_pressure(psi(70)), write(0x2096, 0x2300));
        assert_eq!(set_pressure(Pressure::Auto), write(0x2096, 0));
    }

    #[test]
    fn remote_procedure() {
        let requests = enter_remote(
            OperatingMode::Cut,
            Amps::from_whole(65).unwrap(),
            Psi::from_whole(70).unwrap(),
        )
        .unwrap();
        assert_eq!(
            requests,
            [
                write(0x2093, 1),
                write(0x2094, 0x1040),
                write(0x2096, 0x2300)
            ]
        );
        let amps = Amps::from_whole(65).unwrap();
        let psi = Psi::from_whole(70).unwrap();
        assert_eq!(
            enter_remote(OperatingMode::Cut, Amps::ZERO, psi),
            Err(Error::Malformed)
        );
        assert_eq!(
            enter_remote(OperatingMode::Cut, amps, Psi::ZERO),
            Err(Error::Malformed)
        );
        assert_eq!(
            enter_remote(OperatingMode::Cut, amps, Psi::from_raw(0xFF00)),
            Err(Error::Malformed)
        );
        assert_eq!(
            exit_remote(),
            [write(0x2093, 0), write(0x2094, 0), write(0x2096, 0)]
        );
    }

    #[test]
    fn read_samples() {
        assert_eq!(read_fault(), read(0x2098, 1)); // :010420980001420D0A
        assert_eq!(read_current_min(), read(0x2099, 1)); // :010420990001410D0A
        assert_eq!(read_current_max(), read(0x209A, 1)); // :0104209A0001400D0A
        assert_eq!(read_pressure_min(), read(0x209C, 1)); // :0104209C00013E0D0A
        assert_eq!(read_pressure_max(), read(0x209D, 1)); // :0104209D00013D0D0A
        assert_eq!(read_arc_time(), read(0x209E, 2)); // :0104209E00023B0D0A
        assert_eq!(read_actual_pressure(), read(0x204C, 1));
        // The torch_index sample is garbled by OCR ("08080002EC0D0"); rebuilt with its LRC
        // verified: :010108080002EC = read 2 coils from 0x0808.
        assert_eq!(
            read_torch_lead(),
            Request::ReadCoils {
                start: 0x0808,
                quantity: 2
            }
        );
        assert_eq!(
            read_signals(),
            Request::ReadCoils {
                start: 0x0810,
                quantity: 2
            }
        );
        assert_eq!(
            gas_test(true),
            Request::WriteSingleCoil {
                address: 0x0832,
                on: true
            }
        );
    }

    #[test]
    fn response_samples() {
        // :010402006F8A -> 0-11-1.
        assert_eq!(
            decode_fault(Registers::BigEndian(&[0x00, 0x6F])),
            Ok(FaultCode(111))
        );
        // :0104020500F4 -> 20 A; :0104021040A9 -> 65 A.
        assert_eq!(
            decode_current(Registers::BigEndian(&[0x05, 0x00])),
            Ok(Amps::from_whole(20).unwrap())
        );
        assert_eq!(
            decode_current(Registers::BigEndian(&[0x10, 0x40])),
            Ok(Amps::from_whole(65).unwrap())
        );
        // :0104021F805A -> 63 psi; :0104022700D2 -> 78 psi.
        assert_eq!(
            decode_pressure(Registers::BigEndian(&[0x1F, 0x80])),
            Ok(Psi::from_whole(63).unwrap())
        );
        assert_eq!(
            decode_pressure(Registers::BigEndian(&[0x27, 0x00])),
            Ok(Psi::from_whole(78).unwrap())
        );
        // Arc time: :01040400010000F6 1 s, :010404003C0000BB 60 s, :0104040E100000D9 3600 s,
        // :0104047E40000534 360000 s.
        for (data, seconds) in [
            ([0x00, 0x01, 0x00, 0x00], 1),
            ([0x00, 0x3C, 0x00, 0x00], 60),
            ([0x0E, 0x10, 0x00, 0x00], 3600),
            ([0x7E, 0x40, 0x00, 0x05], 360_000),
        ] {
            assert_eq!(decode_arc_time(Registers::BigEndian(&data)), Ok(seconds));
        }
        assert_eq!(
            decode_arc_time(Registers::BigEndian(&[0x00, 0x01])),
            Err(Error::Truncated)
        );
        assert_eq!(decode_fault(Registers::Words(&[])), Err(Error::Truncated));
        // Torch lead :01010101FC -> 35-50 ft; Start/Motion coils like SYNC.
        assert_eq!(
            LeadLength::from_legacy_coils(&[0x01]),
            Ok(LeadLength::Upto15m)
        );
        assert_eq!(
            Signals::decode(&[0x02]),
            Ok(Signals {
                start: false,
                motion: true
            })
        );
    }

    #[test]
    fn blocks() {
        assert_eq!(read_status_block(), read(0x2098, 8));
        let mut parts = STATUS_BLOCK.part_reads();
        assert_eq!(parts.next(), Some(read(0x2098, 3)));
        assert_eq!(parts.next(), Some(read(0x209C, 4)));
        assert_eq!(parts.next(), None);
        assert_eq!(read_full_block(), read(0x2093, 13));
        let mut parts = FULL_BLOCK.part_reads();
        assert_eq!(parts.next(), Some(read(0x2093, 2)));
        assert_eq!(parts.next(), Some(read(0x2096, 1)));
        assert_eq!(parts.next(), Some(read(0x2098, 3)));
        assert_eq!(parts.next(), Some(read(0x209C, 4)));
        assert_eq!(parts.next(), None);
        assert_eq!(FULL_BLOCK.block().last(), ARC_TIME_HIGH);
        assert_eq!(
            usize::from(FAULT_CODE - MODE_FORCE),
            STATUS_OFFSET,
            "status offset"
        );
    }

    #[test]
    fn status_decoders() {
        // The sample values of the guide in one block, 0xDEAD in 0x209B.
        let status = [
            0x006F, 0x0500, 0x1040, 0xDEAD, 0x1F80, 0x2700, 0x7E40, 0x0005,
        ];
        let s = LegacyStatus::decode(Registers::Words(&status)).unwrap();
        assert_eq!(s.fault, FaultCode(111));
        assert_eq!(s.min_current, Amps::from_whole(20).unwrap());
        assert_eq!(s.max_current, Amps::from_whole(65).unwrap());
        assert_eq!(s.min_pressure, Psi::from_whole(63).unwrap());
        assert_eq!(s.max_pressure, Psi::from_whole(78).unwrap());
        assert_eq!(s.arc_seconds, 360_000);
        assert_eq!(
            LegacyStatus::decode(Registers::Words(&status[..7])),
            Err(Error::Truncated)
        );

        let mut full = [0xDEADu16; 13];
        full[0] = 2;
        full[1] = 0x0DE0;
        full[3] = 0;
        full[5..].copy_from_slice(&status);
        let f = LegacyFullStatus::decode(Registers::Words(&full)).unwrap();
        assert_eq!(f.settings.mode, Some(OperatingMode::ContinuousPilotArc));
        assert_eq!(f.settings.current, "55.5".parse().unwrap());
        assert_eq!(f.settings.pressure, Pressure::Auto);
        assert_eq!(f.status, s);
        // Assembled from the four fallback parts.
        let mut buf = [0u16; 13];
        FULL_BLOCK
            .place(0, Registers::Words(&full[0..2]), &mut buf)
            .unwrap();
        FULL_BLOCK
            .place(1, Registers::Words(&full[3..4]), &mut buf)
            .unwrap();
        FULL_BLOCK
            .place(2, Registers::Words(&full[5..8]), &mut buf)
            .unwrap();
        FULL_BLOCK
            .place(3, Registers::Words(&full[9..13]), &mut buf)
            .unwrap();
        assert_eq!(LegacyFullStatus::decode(Registers::Words(&buf)), Ok(f));
        assert_eq!(
            LegacyFullStatus::decode(Registers::Words(&full[..12])),
            Err(Error::Truncated)
        );
    }
}
