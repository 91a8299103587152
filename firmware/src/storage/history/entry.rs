//! One history entry: a typed view and its encoding (version [`ENTRY_VERSION`]).
//!
//! ```text
//! offset  size  field
//! 0       1     entry version (ENTRY_VERSION)
//! 1       4     sequence number, little endian: +1 per entry, never reused
//! 5       4     boot count, little endian
//! 9       4     time since boot, milliseconds, little endian (wraps after 49 days)
//! 13      1     1 if the wall clock was set (the next field counts), else 0
//! 14      4     wall clock: unix seconds at boot, little endian
//! 18      1     unit: bits 0-3 its family code (0 unknown, 1 SYNC, 2 legacy Powermax,
//!               3 HPR, 4 MaxPro200), bits 4-7 its place on the line minus one (0-3: `@1`
//!               to `@4`); entries from before the place was kept have 0 there (unit 1)
//! 19      1     unit model code (the caller's small code; 0 unknown)
//! 20      1     event kind
//! 21      0..8  event fields (per kind, see `Event::emit_fields`)
//! ```
//!
//! sequential-storage guards every item with CRCs, so there is no checksum here; a decode
//! error means a version or kind this firmware does not know, and the reader skips and
//! counts it.

use plasma_protocol::hpr::ErrorCode;
use plasma_protocol::powermax::{FaultCode, StepsRequired};
use plasma_protocol::units::Psi;

use crate::io::Interlock;
use crate::link::{ActiveFault, Family, MAX_UNITS};
use crate::platform::safe_state::ResetCause;

/// The encoding version this firmware writes and reads.
///
/// Still 1 after the unit's place moved into byte 18's high nibble: every entry written
/// before has 0 there and reads as the first unit, which it was; a new version would make
/// an older firmware skip every entry, where now it rejects (skips and counts) only those
/// about units 2-4.
pub const ENTRY_VERSION: u8 = 1;

/// Bytes before the event fields.
const HEADER_LEN: usize = 21;

/// Largest encoded entry.
pub const MAX_ENTRY: usize = HEADER_LEN + 8;

/// Why bytes are not an entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EntryError {
    /// Shorter than its kind needs, or the output buffer is too small.
    Truncated,
    /// Written by a firmware with another encoding version.
    UnknownVersion(u8),
    /// An event kind (or a code inside it) this firmware does not know.
    UnknownKind(u8),
}

/// Who changed the process.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChangedBy {
    /// The text CNC protocol.
    Text,
    /// A Phoenix CNC.
    Phoenix,
    /// A Modbus CNC.
    ModbusCnc,
}

/// What happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// The unit reported a fault.
    FaultAppeared {
        /// The fault, as the unit reported it.
        fault: ActiveFault,
        /// Whether the operator must act to clear it.
        steps: StepsRequired,
    },
    /// The unit's fault went away.
    FaultCleared {
        /// The fault that cleared.
        fault: ActiveFault,
    },
    /// The link to the unit was lost.
    LinkLost,
    /// The link to the unit is back.
    LinkBack,
    /// The unit was switched off and on (seen on the link).
    UnitPowerCycled,
    /// The bridge itself reset.
    BridgeReset {
        /// Why.
        cause: ResetCause,
    },
    /// START was refused.
    StartRefused {
        /// The interlock that refused it.
        interlock: Interlock,
    },
    /// The cutting process changed.
    ProcessChanged {
        /// The process before.
        from: u16,
        /// The process after.
        to: u16,
        /// Who changed it.
        by: ChangedBy,
    },
    /// A gas check ran.
    GasCheck {
        /// Whether the measured pressure was in the permitted range.
        passed: bool,
        /// The pressure measured while the gas flowed.
        measured: Psi,
        /// The lowest permitted pressure.
        permitted_min: Psi,
        /// The highest permitted pressure.
        permitted_max: Psi,
    },
    /// The consumables were changed.
    ConsumableChanged,
    /// Entries lost because the RAM queue was full (a fault storm).
    EntriesDropped {
        /// How many.
        count: u32,
    },
    /// The history was cleared; this is its first entry since.
    Cleared,
}

/// The unit an entry is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Unit {
    /// Its protocol family, if known.
    pub family: Option<Family>,
    /// A small model code chosen by the caller (0: unknown).
    pub model: u8,
    /// Its place on the line counted from 0 (`@1` is 0); board-wide events keep 0.
    pub line_index: u8,
}

/// One entry of the history.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Entry {
    /// +1 per entry across boots.
    pub sequence: u32,
    /// Which boot wrote it.
    pub boot: u32,
    /// Milliseconds since that boot.
    pub uptime_ms: u32,
    /// Unix seconds at that boot, if the CNC had set the clock.
    pub clock_at_boot: Option<u32>,
    /// The unit on the line.
    pub unit: Unit,
    /// What happened.
    pub event: Event,
}

/// Byte 18: the family code in the low nibble, the place on the line in the high one.
fn unit_byte(unit: &Unit) -> u8 {
    unit.line_index << 4 | family_code(unit.family)
}

/// The family and the place on the line of byte 18 (an unknown family or a place beyond
/// the fourth unit is an error).
fn unit_from(byte: u8) -> Result<(Option<Family>, u8), EntryError> {
    let line_index = byte >> 4;
    if usize::from(line_index) >= MAX_UNITS {
        return Err(EntryError::UnknownKind(byte));
    }
    Ok((family_from(byte & 0x0F)?, line_index))
}

fn family_code(family: Option<Family>) -> u8 {
    match family {
        None => 0,
        Some(Family::PowermaxSync) => 1,
        Some(Family::PowermaxLegacy) => 2,
        Some(Family::Hpr) => 3,
        Some(Family::MaxPro200) => 4,
    }
}

fn family_from(code: u8) -> Result<Option<Family>, EntryError> {
    Ok(Some(match code {
        0 => return Ok(None),
        1 => Family::PowermaxSync,
        2 => Family::PowermaxLegacy,
        3 => Family::Hpr,
        4 => Family::MaxPro200,
        other => return Err(EntryError::UnknownKind(other)),
    }))
}

const STEPS: [StepsRequired; 3] = [
    StepsRequired::Yes,
    StepsRequired::Recommended,
    StepsRequired::No,
];

const RESET_CAUSES: [ResetCause; 10] = [
    ResetCause::Panic,
    ResetCause::IndependentWatchdog,
    ResetCause::WindowWatchdog,
    ResetCause::LowPower,
    ResetCause::Firewall,
    ResetCause::Software,
    ResetCause::OptionByteLoad,
    ResetCause::PowerOn,
    ResetCause::Pin,
    ResetCause::Unknown,
];

const INTERLOCKS: [Interlock; 7] = [
    Interlock::TorchOnAtPowerUp,
    Interlock::TorchOnAtWiringChange,
    Interlock::LinkDown,
    Interlock::RestartBlackout,
    Interlock::FaultRequiresAction,
    Interlock::TransferTimeout,
    Interlock::NotReady,
];

const CHANGED_BY: [ChangedBy; 3] = [ChangedBy::Text, ChangedBy::Phoenix, ChangedBy::ModbusCnc];

/// The code of `value` in `table` (its index; the tables list every variant).
fn code_of<T: PartialEq>(table: &[T], value: &T) -> u8 {
    table
        .iter()
        .position(|t| t == value)
        .and_then(|i| u8::try_from(i).ok())
        .unwrap_or(u8::MAX)
}

fn from_code<T: Copy>(table: &[T], code: u8) -> Result<T, EntryError> {
    table
        .get(usize::from(code))
        .copied()
        .ok_or(EntryError::UnknownKind(code))
}

fn fault_fields(fault: ActiveFault) -> [u8; 3] {
    let (family, code) = match fault {
        ActiveFault::Powermax(FaultCode(code)) => (0, code),
        ActiveFault::Hpr(ErrorCode(code)) => (1, code),
    };
    let [lo, hi] = code.to_le_bytes();
    [family, lo, hi]
}

fn fault_from(fields: &[u8]) -> Result<ActiveFault, EntryError> {
    match fields {
        [0, lo, hi, ..] => Ok(ActiveFault::Powermax(FaultCode(u16::from_le_bytes([
            *lo, *hi,
        ])))),
        [1, lo, hi, ..] => Ok(ActiveFault::Hpr(ErrorCode(u16::from_le_bytes([*lo, *hi])))),
        [other, _, _, ..] => Err(EntryError::UnknownKind(*other)),
        _ => Err(EntryError::Truncated),
    }
}

fn u16_at(fields: &[u8], at: usize) -> Result<u16, EntryError> {
    let bytes = fields.get(at..at + 2).ok_or(EntryError::Truncated)?;
    Ok(u16::from_le_bytes([bytes[0], bytes[1]]))
}

fn u32_at(fields: &[u8], at: usize) -> Result<u32, EntryError> {
    let bytes = fields.get(at..at + 4).ok_or(EntryError::Truncated)?;
    Ok(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
}

fn byte_at(fields: &[u8], at: usize) -> Result<u8, EntryError> {
    fields.get(at).copied().ok_or(EntryError::Truncated)
}

impl Event {
    /// Writes the kind and fields into `out` (at least 9 bytes); returns the length.
    fn emit(&self, out: &mut [u8; 9]) -> usize {
        let (kind, len) = match *self {
            Event::FaultAppeared { fault, steps } => {
                out[1..4].copy_from_slice(&fault_fields(fault));
                out[4] = code_of(&STEPS, &steps);
                (1, 4)
            }
            Event::FaultCleared { fault } => {
                out[1..4].copy_from_slice(&fault_fields(fault));
                (2, 3)
            }
            Event::LinkLost => (3, 0),
            Event::LinkBack => (4, 0),
            Event::UnitPowerCycled => (5, 0),
            Event::BridgeReset { cause } => {
                out[1] = code_of(&RESET_CAUSES, &cause);
                (6, 1)
            }
            Event::StartRefused { interlock } => {
                out[1] = code_of(&INTERLOCKS, &interlock);
                (7, 1)
            }
            Event::ProcessChanged { from, to, by } => {
                out[1..3].copy_from_slice(&from.to_le_bytes());
                out[3..5].copy_from_slice(&to.to_le_bytes());
                out[5] = code_of(&CHANGED_BY, &by);
                (8, 5)
            }
            Event::GasCheck {
                passed,
                measured,
                permitted_min,
                permitted_max,
            } => {
                out[1] = u8::from(passed);
                out[2..4].copy_from_slice(&measured.raw().to_le_bytes());
                out[4..6].copy_from_slice(&permitted_min.raw().to_le_bytes());
                out[6..8].copy_from_slice(&permitted_max.raw().to_le_bytes());
                (9, 7)
            }
            Event::ConsumableChanged => (10, 0),
            Event::EntriesDropped { count } => {
                out[1..5].copy_from_slice(&count.to_le_bytes());
                (11, 4)
            }
            Event::Cleared => (12, 0),
        };
        out[0] = kind;
        1 + len
    }

    fn parse(kind: u8, fields: &[u8]) -> Result<Self, EntryError> {
        Ok(match kind {
            1 => Event::FaultAppeared {
                fault: fault_from(fields)?,
                steps: from_code(&STEPS, byte_at(fields, 3)?)?,
            },
            2 => Event::FaultCleared {
                fault: fault_from(fields)?,
            },
            3 => Event::LinkLost,
            4 => Event::LinkBack,
            5 => Event::UnitPowerCycled,
            6 => Event::BridgeReset {
                cause: from_code(&RESET_CAUSES, byte_at(fields, 0)?)?,
            },
            7 => Event::StartRefused {
                interlock: from_code(&INTERLOCKS, byte_at(fields, 0)?)?,
            },
            8 => Event::ProcessChanged {
                from: u16_at(fields, 0)?,
                to: u16_at(fields, 2)?,
                by: from_code(&CHANGED_BY, byte_at(fields, 4)?)?,
            },
            9 => Event::GasCheck {
                passed: byte_at(fields, 0)? != 0,
                measured: Psi::from_raw(u16_at(fields, 1)?),
                permitted_min: Psi::from_raw(u16_at(fields, 3)?),
                permitted_max: Psi::from_raw(u16_at(fields, 5)?),
            },
            10 => Event::ConsumableChanged,
            11 => Event::EntriesDropped {
                count: u32_at(fields, 0)?,
            },
            12 => Event::Cleared,
            other => return Err(EntryError::UnknownKind(other)),
        })
    }
}

impl Entry {
    /// Writes the entry into `out`; returns the length.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, EntryError> {
        let mut event = [0u8; 9];
        let event_len = self.event.emit(&mut event);
        let len = HEADER_LEN - 1 + event_len;
        let out = out.get_mut(..len).ok_or(EntryError::Truncated)?;
        out[0] = ENTRY_VERSION;
        out[1..5].copy_from_slice(&self.sequence.to_le_bytes());
        out[5..9].copy_from_slice(&self.boot.to_le_bytes());
        out[9..13].copy_from_slice(&self.uptime_ms.to_le_bytes());
        out[13] = u8::from(self.clock_at_boot.is_some());
        out[14..18].copy_from_slice(&self.clock_at_boot.unwrap_or(0).to_le_bytes());
        out[18] = unit_byte(&self.unit);
        out[19] = self.unit.model;
        out[20..].copy_from_slice(&event[..event_len]);
        Ok(len)
    }

    /// Reads an entry.
    pub fn parse(bytes: &[u8]) -> Result<Self, EntryError> {
        match bytes.first() {
            Some(&ENTRY_VERSION) => {}
            Some(&other) => return Err(EntryError::UnknownVersion(other)),
            None => return Err(EntryError::Truncated),
        }
        let kind = byte_at(bytes, 20)?;
        let fields = &bytes[HEADER_LEN..];
        let (family, line_index) = unit_from(byte_at(bytes, 18)?)?;
        Ok(Entry {
            sequence: u32_at(bytes, 1)?,
            boot: u32_at(bytes, 5)?,
            uptime_ms: u32_at(bytes, 9)?,
            clock_at_boot: (byte_at(bytes, 13)? != 0)
                .then(|| u32_at(bytes, 14))
                .transpose()?,
            unit: Unit {
                family,
                model: byte_at(bytes, 19)?,
                line_index,
            },
            event: Event::parse(kind, fields)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(event: Event) -> Entry {
        Entry {
            sequence: 0x0102_0304,
            boot: 7,
            uptime_ms: 65_000,
            clock_at_boot: Some(1_795_000_000),
            unit: Unit {
                family: Some(Family::PowermaxSync),
                model: 3,
                line_index: 0,
            },
            event,
        }
    }

    fn every_event() -> [Event; 16] {
        [
            Event::FaultAppeared {
                fault: ActiveFault::Powermax(FaultCode(320)),
                steps: StepsRequired::Yes,
            },
            Event::FaultAppeared {
                fault: ActiveFault::Hpr(ErrorCode(46)),
                steps: StepsRequired::Recommended,
            },
            Event::FaultCleared {
                fault: ActiveFault::Hpr(ErrorCode(46)),
            },
            Event::LinkLost,
            Event::LinkBack,
            Event::UnitPowerCycled,
            Event::BridgeReset {
                cause: ResetCause::IndependentWatchdog,
            },
            Event::BridgeReset {
                cause: ResetCause::Unknown,
            },
            Event::StartRefused {
                interlock: Interlock::TransferTimeout,
            },
            Event::ProcessChanged {
                from: 1,
                to: 513,
                by: ChangedBy::ModbusCnc,
            },
            Event::GasCheck {
                passed: false,
                measured: Psi::from_raw(480),
                permitted_min: Psi::from_raw(550),
                permitted_max: Psi::from_raw(650),
            },
            Event::ConsumableChanged,
            Event::EntriesDropped { count: 70_000 },
            Event::Cleared,
            Event::StartRefused {
                interlock: Interlock::TorchOnAtPowerUp,
            },
            Event::ProcessChanged {
                from: 0,
                to: u16::MAX,
                by: ChangedBy::Text,
            },
        ]
    }

    #[test]
    fn a_fault_entry_has_the_documented_layout() {
        let mut out = [0u8; MAX_ENTRY];
        let len = entry(every_event()[0]).emit(&mut out).unwrap();
        assert_eq!(
            &out[..len],
            &[
                1, // version
                4, 3, 2, 1, // sequence
                7, 0, 0, 0, // boot
                0xE8, 0xFD, 0, 0, // 65 000 ms
                1, 0xC0, 0x86, 0xFD, 0x6A, // clock set, 1 795 000 000
                1, 3, // SYNC, model 3
                1, 0, 0x40, 0x01, 0, // fault appeared: Powermax 320, steps Yes
            ]
        );
    }

    /// Bytes a firmware wrote before byte 18 kept the unit's place: the fault of a SYNC,
    /// model 3, read as the first unit.
    const ENTRY_FROM_BEFORE_THE_PLACE: [u8; 25] = [
        1, 4, 3, 2, 1, 7, 0, 0, 0, 0xE8, 0xFD, 0, 0, 1, 0xC0, 0x86, 0xFD, 0x6A, 1, 3, 1, 0, 0x40,
        0x01, 0,
    ];

    #[test]
    fn an_entry_written_before_the_place_was_kept_reads_as_the_first_unit() {
        let parsed = Entry::parse(&ENTRY_FROM_BEFORE_THE_PLACE).unwrap();
        assert_eq!(parsed, entry(every_event()[0]));
        assert_eq!(parsed.unit.line_index, 0);
    }

    #[test]
    fn the_third_unit_is_kept_in_the_family_bytes_high_nibble() {
        let mut e = entry(Event::FaultCleared {
            fault: ActiveFault::Hpr(ErrorCode(46)),
        });
        e.unit = Unit {
            family: Some(Family::Hpr),
            model: 9,
            line_index: 2,
        };
        let mut out = [0u8; MAX_ENTRY];
        let len = e.emit(&mut out).unwrap();
        assert_eq!(out[18..20], [0x23, 9]); // unit 3, HPR; model 9
        assert_eq!(Entry::parse(&out[..len]), Ok(e));
        for line_index in 0..MAX_UNITS as u8 {
            e.unit.line_index = line_index;
            let len = e.emit(&mut out).unwrap();
            assert_eq!(Entry::parse(&out[..len]), Ok(e));
        }
    }

    #[test]
    fn an_unknown_place_or_family_in_byte_18_is_an_error() {
        let mut out = [0u8; MAX_ENTRY];
        let len = entry(Event::LinkLost).emit(&mut out).unwrap();
        for byte in [0x41, 0xF1, 0x05, 0x3F] {
            out[18] = byte;
            assert_eq!(
                Entry::parse(&out[..len]),
                Err(EntryError::UnknownKind(if byte & 0xF0 >= 0x40 {
                    byte
                } else {
                    byte & 0x0F
                })),
                "{byte:#x}"
            );
        }
        out[18] = 0x31; // unit 4, SYNC
        assert_eq!(Entry::parse(&out[..len]).map(|e| e.unit.line_index), Ok(3));
    }

    #[test]
    fn every_event_round_trips_and_fits() {
        for event in every_event() {
            for clock in [None, Some(0), Some(u32::MAX)] {
                let mut e = entry(event);
                e.clock_at_boot = clock;
                e.unit.family = None;
                let mut out = [0u8; MAX_ENTRY];
                let len = e.emit(&mut out).unwrap();
                assert_eq!(Entry::parse(&out[..len]), Ok(e), "{event:?}");
                // Every shorter prefix is an error, never a different entry.
                for short in 0..len {
                    assert!(Entry::parse(&out[..short]).is_err(), "{event:?} {short}");
                }
            }
        }
    }

    #[test]
    fn unknown_versions_and_kinds_are_errors() {
        let mut out = [0u8; MAX_ENTRY];
        let len = entry(Event::LinkLost).emit(&mut out).unwrap();
        out[0] = 2;
        assert_eq!(
            Entry::parse(&out[..len]),
            Err(EntryError::UnknownVersion(2))
        );
        out[0] = ENTRY_VERSION;
        out[20] = 200;
        assert_eq!(Entry::parse(&out[..len]), Err(EntryError::UnknownKind(200)));
        out[20] = 6; // a reset with an unknown cause
        assert_eq!(
            Entry::parse(&[&out[..len], &[99]].concat()),
            Err(EntryError::UnknownKind(99))
        );
        out[18] = 9;
        assert!(Entry::parse(&out[..len]).is_err());
        assert_eq!(Entry::parse(&[]), Err(EntryError::Truncated));
    }

    /// The code tables list every variant, in a fixed order: a new variant fails to compile
    /// here until it has a code (appended, so stored codes keep their meaning).
    #[test]
    fn the_code_tables_cover_every_variant_in_order() {
        for (code, cause) in RESET_CAUSES.iter().enumerate() {
            let expected = match cause {
                ResetCause::Panic => 0,
                ResetCause::IndependentWatchdog => 1,
                ResetCause::WindowWatchdog => 2,
                ResetCause::LowPower => 3,
                ResetCause::Firewall => 4,
                ResetCause::Software => 5,
                ResetCause::OptionByteLoad => 6,
                ResetCause::PowerOn => 7,
                ResetCause::Pin => 8,
                ResetCause::Unknown => 9,
            };
            assert_eq!(code, expected);
        }
        for (code, interlock) in INTERLOCKS.iter().enumerate() {
            let expected = match interlock {
                Interlock::TorchOnAtPowerUp => 0,
                Interlock::TorchOnAtWiringChange => 1,
                Interlock::LinkDown => 2,
                Interlock::RestartBlackout => 3,
                Interlock::FaultRequiresAction => 4,
                Interlock::TransferTimeout => 5,
                Interlock::NotReady => 6,
            };
            assert_eq!(code, expected);
        }
        for (code, steps) in STEPS.iter().enumerate() {
            let expected = match steps {
                StepsRequired::Yes => 0,
                StepsRequired::Recommended => 1,
                StepsRequired::No => 2,
            };
            assert_eq!(code, expected);
        }
    }

    #[test]
    fn too_small_a_buffer_is_an_error() {
        let mut out = [0u8; 10];
        assert_eq!(
            entry(Event::LinkLost).emit(&mut out),
            Err(EntryError::Truncated)
        );
    }
}
