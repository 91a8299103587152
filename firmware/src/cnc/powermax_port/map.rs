//! The register map the bridge serves as a Powermax: what each register reads, per family of
//! the unit behind the bridge, from what the link holds (never a request to the unit).
//!
//! - Legacy map (0x2093-0x209F, 0x204C) for every family.
//! - SYNC map (0x3000-0x301A, 0x3028-0x304D, 0x3080-0x3082) only while a SYNC unit is behind:
//!   identification, settings, counters, and the installed cartridge (UID, part number, rating,
//!   counters, fault log, name) as the link last read them.
//! - Gaps inside a served block (0x2095, 0x2097, 0x209B, 0x303D-0x303F) read 0, as the legacy
//!   unit's own 13-register block read does; an address outside every served block is
//!   exception 02.

use plasma_protocol::hpr::{MAX_MAXPRO_AMPS, MIN_AMPS, SystemId};
use plasma_protocol::powermax::{FaultCode, legacy, sync};

use super::group::Forced;
use crate::link::{ActiveFault, Family, Model, UnitStatus};

/// Legacy registers served: the force / fault / limits / arc-time block, and actual pressure.
const LEGACY_BLOCK: (u16, u16) = (legacy::MODE_FORCE, legacy::ARC_TIME_HIGH);
/// SYNC registers served while a SYNC unit is behind.
const SYNC_BLOCKS: [(u16, u16); 3] = [
    (sync::IDENTIFICATION, sync::ACTIVE_FAULT),
    (sync::PS_STARTS_LOW, sync::CARTRIDGE_NAME_END),
    (sync::REMOTE_MODE, sync::REMOTE_PRESSURE),
];

/// The Powermax fault an HPR or MaxPro200 error reads as in 0x2098 / 0x301A: its error number
/// itself (never 0 for an error, so an HPR error never reads as "no fault").
pub(super) fn hpr_error_as_fault(number: u16) -> FaultCode {
    FaultCode(number)
}

/// What the register map reads from.
pub(super) struct View<'a> {
    /// The link's latest picture of the unit.
    pub status: &'a UnitStatus,
    /// The force registers as the CNC wrote them (or the process the bridge keeps).
    pub forced: Forced,
    /// A setting the last settings change asked for that the unit refused (0-11-x).
    pub refused: Option<FaultCode>,
}

/// True when `address` is a register the bridge serves for `family`.
pub(super) fn served(address: u16, family: Family) -> bool {
    let within = |(first, last): (u16, u16)| (first..=last).contains(&address);
    within(LEGACY_BLOCK)
        || address == legacy::ACTUAL_PRESSURE
        || (family == Family::PowermaxSync && SYNC_BLOCKS.into_iter().any(within))
}

impl View<'_> {
    /// The value of a served register (0 for a gap or a value the link does not hold yet).
    pub(super) fn read(&self, address: u16) -> u16 {
        let status = self.status;
        let limits = status.limits;
        let settings = status.settings;
        let lo = |v: u32| (v & 0xFFFF) as u16;
        let hi = |v: u32| (v >> 16) as u16;
        match address {
            legacy::MODE_FORCE | sync::REMOTE_MODE => self.forced.mode,
            legacy::CURRENT_FORCE | sync::REMOTE_CURRENT => self.forced.current,
            legacy::PRESSURE_FORCE | sync::REMOTE_PRESSURE => self.forced.pressure,
            legacy::FAULT_CODE | sync::ACTIVE_FAULT => self.fault().0,
            legacy::CURRENT_MIN | sync::PERMITTED_MIN_CURRENT => self.current_limits().0,
            legacy::CURRENT_MAX | sync::PERMITTED_MAX_CURRENT => self.current_limits().1,
            legacy::PRESSURE_MIN | sync::PERMITTED_MIN_PRESSURE => {
                limits.map_or(0, |l| l.min_pressure.raw())
            }
            legacy::PRESSURE_MAX | sync::PERMITTED_MAX_PRESSURE => {
                limits.map_or(0, |l| l.max_pressure.raw())
            }
            legacy::ARC_TIME_LOW => lo(self.arc_seconds()),
            legacy::ARC_TIME_HIGH => hi(self.arc_seconds()),
            legacy::ACTUAL_PRESSURE | sync::ACTUAL_PRESSURE => {
                status.actual_pressure.map_or(0, |p| p.raw())
            }
            sync::PERMITTED_MODES => limits
                .and_then(|l| l.modes)
                .map_or(0, |m| u16::from_be_bytes([m.high, m.low])),
            sync::MODE_SETTING => settings.and_then(|s| s.mode).map_or(0, |m| m.to_sync()),
            sync::CURRENT_SETTING => settings.map_or(0, |s| s.current.raw()),
            sync::PRESSURE_SETTING => settings.map_or(0, |s| s.pressure.raw()),
            sync::ACTUAL_CURRENT => status.actual_current.map_or(0, |a| a.raw()),
            sync::PS_STARTS_LOW..=sync::PS_TRANSFER_TIME_HIGH => {
                let Some(c) = status.ps_counters else {
                    return 0;
                };
                let offset = address - sync::PS_STARTS_LOW;
                let value = [
                    c.starts,
                    c.pilot_arc_seconds,
                    c.transfers,
                    c.transfer_seconds,
                ]
                .get(usize::from(offset / 2))
                .copied()
                .unwrap_or(0);
                if offset.is_multiple_of(2) {
                    lo(value)
                } else {
                    hi(value)
                }
            }
            sync::IDENTIFICATION => status.identification.map_or(0, |i| i.raw),
            sync::CARTRIDGE_UID..=sync::FAULT_LOG_3 => self.cartridge(address),
            sync::CARTRIDGE_NAME..=sync::CARTRIDGE_NAME_END => status
                .cartridge_name
                .map_or(0, |n| text_word(&n.0, address - sync::CARTRIDGE_NAME)),
            _ => 0,
        }
    }

    /// 0x3030-0x3047: the installed cartridge as the link last read it (0 until it has).
    /// Out of line: inlined into `read` it cost 60 B more flash.
    #[inline(never)]
    fn cartridge(&self, address: u16) -> u16 {
        let status = self.status;
        if (sync::FAULT_LOG_0..=sync::FAULT_LOG_3).contains(&address) {
            let entry = usize::from(address - sync::FAULT_LOG_0);
            return status
                .fault_log
                .and_then(|log| log.0.get(entry).copied())
                .map_or(0, |code| code.0);
        }
        let Some(c) = status.cartridge else {
            return 0;
        };
        match address {
            sync::CARTRIDGE_UID..=sync::CARTRIDGE_UID_END => {
                text_word(&c.uid.0, address - sync::CARTRIDGE_UID)
            }
            sync::CARTRIDGE_PART_NUMBER..=sync::CARTRIDGE_PART_NUMBER_END => {
                text_word(&c.part_number.0, address - sync::CARTRIDGE_PART_NUMBER)
            }
            sync::CARTRIDGE_REVISION => c.revision,
            sync::CARTRIDGE_NOMINAL_CURRENT => c.nominal_current_raw,
            sync::CARTRIDGE_STARTS => c.counters.starts,
            sync::CARTRIDGE_PILOT_ARC_TIME => c.counters.pilot_arc_seconds,
            sync::CARTRIDGE_TRANSFERS => c.counters.transfers,
            sync::CARTRIDGE_TRANSFER_TIME => c.counters.transfer_time_counts,
            _ => 0,
        }
    }

    /// 0x2098: the unit's fault (an HPR error as its number); else a refused setting; else 0.
    fn fault(&self) -> FaultCode {
        match self.status.active_fault {
            Some(ActiveFault::Powermax(code)) => code,
            Some(ActiveFault::Hpr(code)) => hpr_error_as_fault(code.0),
            None => self.refused.unwrap_or(FaultCode::NONE),
        }
    }

    /// Current limits, amps x 64: the unit's (Powermax), or 5 A to the rating (HPR, MaxPro200).
    fn current_limits(&self) -> (u16, u16) {
        if let Some(l) = self.status.limits {
            return (l.min_current.raw(), l.max_current.raw());
        }
        let max = match self.status.model {
            Some(Model::Hpr(SystemId::Hpr { rating, .. })) => rating.max_amps(),
            Some(Model::Hpr(SystemId::MaxPro200)) => MAX_MAXPRO_AMPS,
            _ => return (0, 0),
        };
        let x64 = |amps: u16| amps.saturating_mul(64);
        (x64(MIN_AMPS), x64(max))
    }

    /// Arc time in seconds: legacy 0x209E-F; SYNC: the pilot arc time (0x302A-B), the register
    /// the manual gives 0x209E-F as the old address of; HPR/MaxPro200: the arc-on timer (125).
    fn arc_seconds(&self) -> u32 {
        let status = self.status;
        match status.family {
            Some(Family::PowermaxSync) => status.ps_counters.map_or(0, |c| c.pilot_arc_seconds),
            Some(Family::Hpr | Family::MaxPro200) => {
                status.hpr.timers.map_or(0, |t| t.arc_on_seconds)
            }
            _ => status.arc_seconds.unwrap_or(0),
        }
    }
}

/// Register `index` of a text the unit sends two bytes a register, the first byte high (UID,
/// part number, name: "bytes 0 and 1" in one register).
fn text_word(text: &[u8], index: u16) -> u16 {
    let at = usize::from(index) * 2;
    let byte = |i: usize| text.get(i).copied().unwrap_or(0);
    u16::from_be_bytes([byte(at), byte(at + 1)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::Limits;
    use crate::link::status::HprStatus;
    use plasma_protocol::hpr::{ErrorCode, TimerCounter};
    use plasma_protocol::powermax::sync::PsCounters;
    use plasma_protocol::powermax::{Amps, Psi};

    fn view(status: &UnitStatus) -> View<'_> {
        View {
            status,
            forced: Forced {
                mode: 1,
                current: 2880,
                pressure: 0,
            },
            refused: Some(FaultCode(111)),
        }
    }

    #[test]
    fn legacy_registers_from_a_powermax_status() {
        let status = UnitStatus {
            family: Some(Family::PowermaxLegacy),
            link_up: true,
            limits: Some(Limits {
                modes: None,
                min_current: Amps::from_raw(20 * 64),
                max_current: Amps::from_raw(65 * 64),
                min_pressure: Psi::from_raw(63 * 128),
                max_pressure: Psi::from_raw(78 * 128),
            }),
            arc_seconds: Some(0x0001_0002),
            ..UnitStatus::default()
        };
        let v = view(&status);
        let read = |a| v.read(a);
        assert_eq!(
            [0x2093, 0x2094, 0x2096, 0x2099, 0x209A, 0x209C, 0x209D].map(read),
            [1, 2880, 0, 1280, 4160, 63 * 128, 78 * 128]
        );
        assert_eq!(
            [0x209E, 0x209F].map(read),
            [2, 1],
            "arc time low word first"
        );
        assert_eq!(
            read(0x2098),
            111,
            "a refused setting shows while the unit has no fault"
        );
        assert!(!served(0x3003, Family::PowermaxLegacy));
        assert!(served(0x3003, Family::PowermaxSync));
        assert!(served(0x2095, Family::Hpr), "a gap inside the block");
        assert!(!served(0x20A0, Family::PowermaxSync));
    }

    #[test]
    fn an_hpr_status_reads_as_a_powermax() {
        let status = UnitStatus {
            family: Some(Family::Hpr),
            link_up: true,
            active_fault: Some(ActiveFault::Hpr(ErrorCode(44))),
            hpr: HprStatus {
                timers: Some(TimerCounter {
                    arc_on_seconds: 70_000,
                    system_on_minutes: 0,
                    starts: 0,
                    start_errors: 0,
                    rampdown_errors: 0,
                    write_counter: 0,
                    memory_block: 0,
                }),
                ..HprStatus::default()
            },
            ..UnitStatus::default()
        };
        let v = view(&status);
        assert_eq!(
            v.read(0x2098),
            44,
            "the unit's error wins over a refused setting"
        );
        assert_eq!((v.read(0x209E), v.read(0x209F)), (4464, 1), "70000 s");
    }

    /// SYNC manual (000_dd931256418ae627.txt) lines 480-481: 0x302A/0x302B, cumulative pilot arc
    /// time (bytes 1 and 0, bytes 3 and 2), have the old address 0x209E/0x209F.
    #[test]
    fn a_sync_units_old_arc_time_is_its_pilot_arc_time() {
        let status = UnitStatus {
            family: Some(Family::PowermaxSync),
            link_up: true,
            ps_counters: Some(PsCounters {
                starts: 7,
                pilot_arc_seconds: 0x0002_0003,
                transfers: 5,
                transfer_seconds: 0x0004_0009,
            }),
            ..UnitStatus::default()
        };
        let v = view(&status);
        let read = |a| v.read(a);
        assert_eq!([0x302A, 0x302B].map(read), [3, 2]);
        assert_eq!(
            [0x209E, 0x209F].map(read),
            [0x302A, 0x302B].map(read),
            "the old address reads the SYNC register it names"
        );
        assert_eq!(
            [0x302E, 0x302F].map(read),
            [9, 4],
            "transfer time stays at 0x302E-F"
        );
    }
}
