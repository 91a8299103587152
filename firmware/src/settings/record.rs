//! The settings record the store keeps: a fixed layout, version 6 (version 5 is its first 63
//! bytes, version 4 its first 54, version 3 its first 46, version 2 its first 45, version 1
//! its first 29, and all still load). Decoding is strict: a wrong length, an unknown code, a value out of
//! range or a reserved bit set gives `None`, and the store falls back to the defaults.

use plasma_protocol::cnc::phoenix::Format;
use plasma_protocol::cnc::{Amps, Mode, Pressure};
use plasma_protocol::serial::{DataBits, Parity, PortConfig, StopBits};
use plasma_protocol::time::Duration;

use super::{CncPort, Process, Settings, ms, wiring};
use crate::consumables::Limits;
use crate::io::{InputConfig, IoConfig, MIN_START_GAP, OutputConfig};
use crate::link::{LineUnit, LinkConfig, MAX_UNITS, NamedUnits, ProtocolChoice};
use crate::storage;

/// Length of the version-1 record (no wiring, no CNC port block).
pub const RECORD_V1_LEN: usize = 29;
/// Length of the version-2 record: version 1, the CNC's wiring, then the CNC port block.
pub const RECORD_V2_LEN: usize = RECORD_V1_LEN + wiring::RECORD_LEN + CNC_BLOCK_LEN;
/// Length of the version-3 record: version 2, then the wiring of the inputs added since.
pub const RECORD_V3_LEN: usize = RECORD_V2_LEN + wiring::TAIL_LEN;
/// Length of the version-4 record: version 3, then the consumable limits.
pub const RECORD_V4_LEN: usize = RECORD_V3_LEN + LIMITS_BLOCK_LEN;
/// Length of the version-5 record: version 4, then the units on the line.
pub const RECORD_V5_LEN: usize = RECORD_V4_LEN + UNITS_BLOCK_LEN;
/// Length of the version-6 record: version 5, then the CNC port's data bits.
pub const RECORD_LEN: usize = RECORD_V5_LEN + 1;
/// Bytes of the units block: their number (0 = AUTO), then kind and address of each.
const UNITS_BLOCK_LEN: usize = 1 + 2 * MAX_UNITS;
/// Bytes of the consumable limits: starts, arc seconds (LE u32 each, 0 = OFF).
const LIMITS_BLOCK_LEN: usize = 8;
/// Bytes of the CNC port block in the record: address, baud (LE u32), parity, stop bits.
const CNC_BLOCK_LEN: usize = 7;

// --- record layout, version 6 (5 is its first 63 bytes, 4 its 54, 3 its 46, 2 its 45, 1 its 29)
// 0 protocol | 1 node address | 2 parity | 3 stop bits | 4-5 response time-out ms (LE)
// 6 retries | 7-8 poll ms | 9-12 slow-data ms | 13 HPR id | 14 failures before down
// 15-16 start gap ms | 17-18 ARC_OK debounce ms | 19-20 transfer time-out ms | 21 flags
// 22 Phoenix format | 23 process present | 24 mode | 25-26 amps raw | 27-28 pressure raw
// 29 active-high inputs (bit per input; bit 7 SYSTEM_ERROR from version 3)
// 30-36 debounce ms of the first seven inputs | 37 inverted outputs
// 38 CNC address | 39-42 CNC baud (LE) | 43 CNC parity | 44 CNC stop bits
// 45 SYSTEM_ERROR debounce ms (version 3)
// 46-49 consumable start limit (LE, 0 = OFF) | 50-53 consumable arc limit s (LE, 0 = OFF) (v4)
// 54 units on the line (0 = AUTO) | 55-62 each unit's kind (1 HPR, 2 MaxPro200, 3 Powermax)
//   and id or node, two bytes per unit, unused pairs 0 (v5)
// 63 CNC data bits (7 or 8) (v6)

const FLAG_ARC_OK_REQUIRES_START: u8 = 1 << 0;
const FLAG_DROP_START_ON_TRANSFER_TIMEOUT: u8 = 1 << 1;
const FLAG_REFUSE_START_ON_FAULT: u8 = 1 << 2;
const FLAG_LINK_REQUIRED: u8 = 1 << 3;
const FLAG_EVENTS: u8 = 1 << 4;
/// Set when the ready interlock is off: a record saved before the interlock existed has the
/// bit clear and loads with it on, the default.
const FLAG_READY_NOT_REQUIRED: u8 = 1 << 5;
const FLAG_REAPPLY_AFTER_POWER_CYCLE: u8 = 1 << 6;
const FLAGS_KNOWN: u8 = 0x7F;

const PROTOCOLS: [ProtocolChoice; 4] = [
    ProtocolChoice::Auto,
    ProtocolChoice::Sync,
    ProtocolChoice::Legacy,
    ProtocolChoice::Hpr,
];
const PARITIES: [Parity; 3] = [Parity::None, Parity::Even, Parity::Odd];

fn index_of<T: PartialEq>(items: &[T], item: &T) -> u8 {
    items.iter().position(|i| i == item).unwrap_or(0) as u8
}

fn u16_ms(d: Duration) -> [u8; 2] {
    u16::try_from(d.as_millis())
        .unwrap_or(u16::MAX)
        .to_le_bytes()
}

fn data_bits_from(number: u8) -> Option<DataBits> {
    [DataBits::Seven, DataBits::Eight]
        .into_iter()
        .find(|bits| bits.number() == number)
}

fn stop_bits_from(number: u8) -> Option<StopBits> {
    match number {
        1 => Some(StopBits::One),
        2 => Some(StopBits::Two),
        _ => None,
    }
}

impl CncPort {
    fn encode(&self) -> [u8; CNC_BLOCK_LEN] {
        let b = self.framing.baud.to_le_bytes();
        [
            self.address,
            b[0],
            b[1],
            b[2],
            b[3],
            index_of(&PARITIES, &self.framing.parity),
            self.framing.stop_bits.number(),
        ]
    }

    fn decode(r: &[u8]) -> Option<CncPort> {
        let &[address, b0, b1, b2, b3, parity, stop] = r else {
            return None;
        };
        let port = CncPort {
            address,
            // Data bits are in a later block (version 6); before, always 8.
            framing: PortConfig::new(
                u32::from_le_bytes([b0, b1, b2, b3]),
                *PARITIES.get(usize::from(parity))?,
                stop_bits_from(stop)?,
            ),
        };
        port.is_valid().then_some(port)
    }
}

impl storage::Persistent for Settings {
    const VERSION: u8 = 6;

    fn encode(&self, out: &mut [u8]) -> usize {
        let mut r = [0u8; RECORD_LEN];
        let link = &self.link;
        let io = &self.io;
        r[0] = index_of(&PROTOCOLS, &link.protocol);
        r[1] = link.node_address;
        r[2] = index_of(&PARITIES, &link.modbus_parity);
        r[3] = link.modbus_stop_bits.number();
        r[4..6].copy_from_slice(&u16_ms(link.response_timeout));
        r[6] = link.retries;
        r[7..9].copy_from_slice(&u16_ms(link.poll_interval));
        r[9..13].copy_from_slice(&ms(link.slow_data_interval).to_le_bytes());
        r[13] = link.hpr_id;
        r[14] = link.failures_before_down;
        r[15..17].copy_from_slice(&u16_ms(io.start_gap));
        r[17..19].copy_from_slice(&u16_ms(io.arc_ok_debounce));
        r[19..21].copy_from_slice(&u16_ms(io.transfer_timeout));
        let flag = |on: bool, bit: u8| if on { bit } else { 0 };
        r[21] = flag(io.arc_ok_requires_start, FLAG_ARC_OK_REQUIRES_START)
            | flag(
                io.drop_start_on_transfer_timeout,
                FLAG_DROP_START_ON_TRANSFER_TIMEOUT,
            )
            | flag(io.refuse_start_on_fault, FLAG_REFUSE_START_ON_FAULT)
            | flag(io.link_required, FLAG_LINK_REQUIRED)
            | flag(self.events, FLAG_EVENTS)
            | flag(!io.ready_required, FLAG_READY_NOT_REQUIRED)
            | flag(
                link.reapply_after_power_cycle,
                FLAG_REAPPLY_AFTER_POWER_CYCLE,
            );
        r[22] = self.phoenix_format.value();
        if let Some(process) = self.process {
            r[23] = 1;
            r[24] = index_of(&Mode::ALL, &process.mode);
            r[25..27].copy_from_slice(&process.amps.raw().to_le_bytes());
            r[27..29].copy_from_slice(&process.pressure.raw().to_le_bytes());
        }
        let (wiring_bytes, wiring_tail) = wiring::encode(io);
        let (wiring_slot, rest) = r[RECORD_V1_LEN..].split_at_mut(wiring::RECORD_LEN);
        let (cnc, rest) = rest.split_at_mut(CNC_BLOCK_LEN);
        let (tail, rest) = rest.split_at_mut(wiring::TAIL_LEN);
        let (limits, rest) = rest.split_at_mut(LIMITS_BLOCK_LEN);
        let (units, data_bits) = rest.split_at_mut(UNITS_BLOCK_LEN);
        wiring_slot.copy_from_slice(&wiring_bytes);
        cnc.copy_from_slice(&self.cnc.encode());
        tail.copy_from_slice(&wiring_tail);
        limits.copy_from_slice(&encode_limits(self.consumable_limits));
        units.copy_from_slice(&encode_units(&self.units));
        data_bits.copy_from_slice(&[self.cnc.framing.data_bits.number()]);
        storage::write_payload(out, &r)
    }

    fn decode(payload: &[u8]) -> Option<Self> {
        let (v5, &[data_bits]) = payload.split_at_checked(RECORD_V5_LEN)? else {
            return None;
        };
        let mut settings = decode_v5(v5)?;
        settings.cnc.framing.data_bits = data_bits_from(data_bits)?;
        settings.is_valid().then_some(settings)
    }

    /// Version 1 had neither the wiring nor the CNC port block: both keep their defaults.
    /// Version 2 had no SYSTEM_ERROR input: it keeps the reference board's wiring.
    /// Version 3 had no consumable limits: they are OFF.
    /// Version 4 had one unit only: `units` is AUTO.
    /// Version 5 had 8 data bits on the CNC port, always.
    fn migrate(version: u8, payload: &[u8]) -> Option<Self> {
        match version {
            1 => decode_v1(payload),
            2 => decode_v2(payload, wiring::decode_v2),
            3 => decode_v3(payload),
            4 => decode_v4(payload),
            5 => decode_v5(payload),
            _ => None,
        }
    }
}

/// The version-5 record (also the first part of version 6).
fn decode_v5(payload: &[u8]) -> Option<Settings> {
    let (v4, units) = payload.split_at_checked(RECORD_V4_LEN)?;
    let v4 = decode_v4(v4)?;
    let settings = Settings {
        units: decode_units(v4.link, units.try_into().ok()?)?,
        ..v4
    };
    settings.is_valid().then_some(settings)
}

/// The version-4 record (also the first part of version 5).
fn decode_v4(payload: &[u8]) -> Option<Settings> {
    let (v3, limits) = payload.split_at_checked(RECORD_V3_LEN)?;
    Some(Settings {
        consumable_limits: decode_limits(limits.try_into().ok()?)?,
        ..decode_v3(v3)?
    })
}

fn encode_units(units: &NamedUnits) -> [u8; UNITS_BLOCK_LEN] {
    let mut block = [0u8; UNITS_BLOCK_LEN];
    let (count, pairs) = block.split_at_mut(1);
    count.copy_from_slice(&[units.as_slice().len() as u8]);
    for (pair, unit) in pairs.chunks_exact_mut(2).zip(units.as_slice()) {
        pair.copy_from_slice(&match *unit {
            LineUnit::Hpr { id } => [1, id],
            LineUnit::MaxPro200 => [2, 0],
            LineUnit::Powermax { node } => [3, node],
        });
    }
    block
}

/// Strict: an unknown kind, a used pair past the count, or units that cannot share a line
/// give `None`.
fn decode_units(link: LinkConfig, block: &[u8; UNITS_BLOCK_LEN]) -> Option<NamedUnits> {
    let (&count, pairs) = block.split_first()?;
    let count = usize::from(count);
    let mut units = [LineUnit::MaxPro200; MAX_UNITS];
    for (index, pair) in pairs.chunks_exact(2).enumerate() {
        let &[kind, address] = pair else {
            return None;
        };
        let unit = match (index < count, kind) {
            (false, 0) if address == 0 => continue,
            (true, 1) => LineUnit::Hpr { id: address },
            (true, 2) if address == 0 => LineUnit::MaxPro200,
            (true, 3) => LineUnit::Powermax { node: address },
            _ => return None,
        };
        *units.get_mut(index)? = unit;
    }
    NamedUnits::new(link, units.get(..count)?).ok()
}

fn encode_limits(limits: Limits) -> [u8; LIMITS_BLOCK_LEN] {
    let mut block = [0u8; LIMITS_BLOCK_LEN];
    let (starts, arc) = block.split_at_mut(4);
    starts.copy_from_slice(&limits.starts.unwrap_or(0).to_le_bytes());
    arc.copy_from_slice(&limits.arc_seconds.unwrap_or(0).to_le_bytes());
    block
}

/// A limit of 0 is OFF; one above [`Limits::MAX`] was not written by this code: `None`.
fn decode_limits(block: &[u8; LIMITS_BLOCK_LEN]) -> Option<Limits> {
    let [a0, a1, a2, a3, b0, b1, b2, b3] = *block;
    let limit = |v: u32| match v {
        0 => Some(None),
        1..=Limits::MAX => Some(Some(v)),
        _ => None,
    };
    Some(Limits {
        starts: limit(u32::from_le_bytes([a0, a1, a2, a3]))?,
        arc_seconds: limit(u32::from_le_bytes([b0, b1, b2, b3]))?,
    })
}

/// The version-3 record (also the first part of version 4).
fn decode_v3(payload: &[u8]) -> Option<Settings> {
    let (v2, tail) = payload.split_at_checked(RECORD_V2_LEN)?;
    decode_v2(v2, |wiring_bytes| {
        wiring::decode(wiring_bytes, tail.try_into().ok()?)
    })
}

/// The version-2 record (also the first part of version 3), its wiring read by `wiring`.
fn decode_v2(
    payload: &[u8],
    wiring: impl FnOnce(&[u8; wiring::RECORD_LEN]) -> Option<(InputConfig, OutputConfig)>,
) -> Option<Settings> {
    let (v1, rest) = payload.split_at_checked(RECORD_V1_LEN)?;
    let (wiring_bytes, cnc) = rest.split_at_checked(wiring::RECORD_LEN)?;
    let (inputs, outputs) = wiring(wiring_bytes.try_into().ok()?)?;
    let mut settings = Settings {
        cnc: CncPort::decode(cnc)?,
        ..decode_v1(v1)?
    };
    settings.io.inputs = inputs;
    settings.io.outputs = outputs;
    settings.is_valid().then_some(settings)
}

/// The version-1 record (also the first part of version 2), the CNC port at its defaults.
fn decode_v1(payload: &[u8]) -> Option<Settings> {
    let r: &[u8; RECORD_V1_LEN] = payload.try_into().ok()?;
    // Offsets are constants inside the fixed-length record.
    let u16_at = |i: usize| {
        r.get(i..i + 2)
            .and_then(|b| b.try_into().ok())
            .map_or(0, u16::from_le_bytes)
    };
    let millis = |i: usize| Duration::from_millis(u64::from(u16_at(i)));
    let flags = r[21];
    if flags & !FLAGS_KNOWN != 0 {
        return None;
    }
    let link = LinkConfig {
        protocol: *PROTOCOLS.get(usize::from(r[0]))?,
        node_address: r[1],
        modbus_parity: *PARITIES.get(usize::from(r[2]))?,
        modbus_stop_bits: stop_bits_from(r[3])?,
        response_timeout: millis(4),
        retries: r[6],
        poll_interval: millis(7),
        slow_data_interval: Duration::from_millis(u64::from(u32::from_le_bytes([
            r[9], r[10], r[11], r[12],
        ]))),
        hpr_id: r[13],
        failures_before_down: r[14],
        reapply_after_power_cycle: flags & FLAG_REAPPLY_AFTER_POWER_CYCLE != 0,
    };
    let io = IoConfig {
        start_gap: millis(15).max(MIN_START_GAP),
        arc_ok_debounce: millis(17),
        arc_ok_requires_start: flags & FLAG_ARC_OK_REQUIRES_START != 0,
        transfer_timeout: millis(19),
        drop_start_on_transfer_timeout: flags & FLAG_DROP_START_ON_TRANSFER_TIMEOUT != 0,
        refuse_start_on_fault: flags & FLAG_REFUSE_START_ON_FAULT != 0,
        link_required: flags & FLAG_LINK_REQUIRED != 0,
        ready_required: flags & FLAG_READY_NOT_REQUIRED == 0,
        // Version 1 has no wiring: the reference board's (version 2 overwrites it).
        ..IoConfig::default()
    };
    let process = match r[23] {
        0 if r[24..].iter().all(|&b| b == 0) => None,
        1 => Some(Process {
            mode: *Mode::ALL.get(usize::from(r[24]))?,
            amps: Amps::from_raw(u16_at(25)),
            pressure: Pressure::from_raw(u16_at(27)),
        }),
        _ => return None,
    };
    let settings = Settings {
        link,
        io,
        events: flags & FLAG_EVENTS != 0,
        phoenix_format: Format::from_value(r[22]).ok()?,
        process,
        cnc: CncPort::DEFAULT,
        consumable_limits: Limits::default(),
        units: NamedUnits::AUTO,
    };
    settings.is_valid().then_some(settings)
}

#[cfg(test)]
mod tests {
    use plasma_protocol::cnc::ConfigKey;

    use super::*;
    use crate::settings::ConfigValue;
    use crate::storage::Persistent as _;

    fn round_trip(settings: &Settings) -> Option<Settings> {
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = settings.encode(&mut out);
        assert_eq!(len, RECORD_LEN);
        Settings::decode(&out[..len])
    }

    #[test]
    fn defaults_are_valid_and_round_trip() {
        let defaults = Settings::default();
        assert!(defaults.is_valid());
        assert_eq!(round_trip(&defaults), Some(defaults));
        assert_eq!(defaults.phoenix_format.value(), 113);
        assert!(!defaults.events);
    }

    #[test]
    fn every_field_round_trips() {
        let mut s = Settings::default();
        for (key, value) in [
            (ConfigKey::Protocol, "hpr"),
            (ConfigKey::Address, "17"),
            (ConfigKey::Parity, "o"),
            (ConfigKey::StopBits, "2"),
            (ConfigKey::TimeoutMs, "250"),
            (ConfigKey::Retries, "5"),
            (ConfigKey::PollMs, "500"),
            (ConfigKey::InterlockFault, "off"),
            (ConfigKey::InterlockLink, "OFF"),
            (ConfigKey::InterlockReady, "off"),
            (ConfigKey::ArcOkDebounceMs, "10"),
            (ConfigKey::TransferTimeoutMs, "5000"),
            (ConfigKey::TransferTimeoutDropsStart, "off"),
            (ConfigKey::Events, "on"),
            (ConfigKey::HprId, "3"),
            (ConfigKey::PhoenixFormat, "49"),
            (ConfigKey::CncAddress, "7"),
            (ConfigKey::CncBaud, "19200"),
            (ConfigKey::CncParity, "even"),
            (ConfigKey::CncStopBits, "2"),
            (ConfigKey::CncDataBits, "7"),
            (ConfigKey::ConsumableStartLimit, "600"),
            (ConfigKey::ConsumableArcLimitS, "1000000"),
        ] {
            s.set(key, value).unwrap();
        }
        s.process = Some(Process {
            mode: Mode::Expanded,
            amps: Amps::from_raw(45 * 64 + 32),
            pressure: Pressure::Set(plasma_protocol::units::Psi::from_raw(70 * 128)),
        });
        let back = round_trip(&s).unwrap();
        assert_eq!(back, s);
        assert_eq!(back.get(ConfigKey::Parity), ConfigValue::Word("ODD"));
        assert_eq!(back.get(ConfigKey::TimeoutMs), ConfigValue::Number(250));
        assert_eq!(back.link.protocol, ProtocolChoice::Hpr);
        assert!(!back.io.link_required);
        assert!(!back.io.ready_required);
    }

    #[test]
    fn a_record_saved_before_the_ready_interlock_loads_with_it_on() {
        let mut s = Settings::default();
        s.set(ConfigKey::InterlockReady, "OFF").unwrap();
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = s.encode(&mut out);
        assert_eq!(out[21] & FLAG_READY_NOT_REQUIRED, FLAG_READY_NOT_REQUIRED);
        // Older firmware never set the bit: its records take the safe default.
        out[21] &= !FLAG_READY_NOT_REQUIRED;
        let old = Settings::decode(&out[..len]).unwrap();
        assert!(old.io.ready_required);
        assert_eq!(old.get(ConfigKey::InterlockReady), ConfigValue::Word("ON"));
    }

    #[test]
    fn a_version_1_record_loads_with_the_default_cnc_port() {
        let mut s = Settings::default();
        s.set(ConfigKey::HprId, "2").unwrap();
        s.set(ConfigKey::CncBaud, "19200").unwrap();
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = s.encode(&mut out);
        assert_eq!(len, RECORD_LEN);
        let v1 = &out[..RECORD_V1_LEN];
        assert_eq!(Settings::decode(v1), None, "a v1 record is not a v2 one");
        let migrated = Settings::migrate(1, v1).unwrap();
        assert_eq!(migrated.link.hpr_id, 2);
        assert_eq!(migrated.cnc, crate::settings::CncPort::DEFAULT);
        assert_eq!(Settings::migrate(4, v1), None);
    }

    #[test]
    fn a_version_2_record_loads_with_the_reference_system_error_wiring() {
        let mut s = Settings::default();
        s.set(ConfigKey::HprId, "2").unwrap();
        s.set(ConfigKey::RampdownErrorActive, "HIGH").unwrap();
        s.set(ConfigKey::CncBaud, "19200").unwrap();
        s.set(ConfigKey::SystemErrorActive, "HIGH").unwrap();
        s.set(ConfigKey::SystemErrorDebounceMs, "40").unwrap();
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = s.encode(&mut out);
        assert_eq!((len, RECORD_V2_LEN + 1), (RECORD_LEN, RECORD_V3_LEN));
        assert_eq!(out[45], 40);
        // A version-2 record is the first 45 bytes of a version-3 one, SYSTEM_ERROR's
        // active-high bit clear (version 2 never set it).
        let mut v2 = [0u8; RECORD_V2_LEN];
        v2.copy_from_slice(&out[..RECORD_V2_LEN]);
        assert_eq!(Settings::decode(&v2), None, "not a version-3 record");
        assert_eq!(
            Settings::migrate(2, &v2),
            None,
            "bit 7 set: not from version 2"
        );
        v2[29] &= !(1 << 7);
        let migrated = Settings::migrate(2, &v2).unwrap();
        assert_eq!(migrated.link.hpr_id, 2);
        assert_eq!(migrated.cnc.framing.baud, 19200);
        assert_eq!(
            migrated.get(ConfigKey::RampdownErrorActive),
            ConfigValue::Word("HIGH")
        );
        let reference = crate::io::InputConfig::REFERENCE.get(crate::io::Input::SystemError);
        assert_eq!(
            migrated.io.inputs.get(crate::io::Input::SystemError),
            reference
        );
        assert_eq!(
            migrated.get(ConfigKey::SystemErrorActive),
            ConfigValue::Word("LOW")
        );
        assert_eq!(
            migrated.get(ConfigKey::SystemErrorDebounceMs),
            ConfigValue::Number(5)
        );
        assert_eq!(Settings::decode(&out[..len]), Some(s));
    }

    #[test]
    fn a_version_3_record_loads_with_the_consumable_limits_off() {
        let mut s = Settings::default();
        s.set(ConfigKey::HprId, "2").unwrap();
        s.set(ConfigKey::ConsumableStartLimit, "800").unwrap();
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = s.encode(&mut out);
        assert_eq!(
            (len, RECORD_V5_LEN, RECORD_V4_LEN, RECORD_V3_LEN),
            (64, 63, 54, 46)
        );
        assert_eq!(out[46..50], 800u32.to_le_bytes());
        let v3 = &out[..RECORD_V3_LEN];
        assert_eq!(Settings::decode(v3), None, "not a version-6 record");
        let migrated = Settings::migrate(3, v3).unwrap();
        assert_eq!(migrated.link.hpr_id, 2);
        assert_eq!(migrated.consumable_limits, Limits::default());
    }

    #[test]
    fn a_version_4_record_loads_with_one_unit_and_the_units_round_trip() {
        let mut s = Settings::default();
        s.set(ConfigKey::ConsumableStartLimit, "800").unwrap();
        s.set(ConfigKey::Units, "HPR:0,HPR:2,HPR:3").unwrap();
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = s.encode(&mut out);
        assert_eq!(out[54..RECORD_V5_LEN], [3, 1, 0, 1, 2, 1, 3, 0, 0]);
        assert_eq!(Settings::decode(&out[..len]), Some(s));
        let v4 = &out[..RECORD_V4_LEN];
        assert_eq!(Settings::decode(v4), None, "not a version-6 record");
        let migrated = Settings::migrate(4, v4).unwrap();
        assert_eq!(migrated.consumable_limits.starts, Some(800));
        assert_eq!(migrated.units, NamedUnits::AUTO);
        // Units that cannot share a line, an unknown kind, a pair past the count: refused.
        for (at, byte) in [(55, 3), (55, 9), (61, 1)] {
            let mut bad = out;
            bad[at] = byte;
            assert_eq!(Settings::decode(&bad[..len]), None, "byte {at} = {byte}");
        }
    }

    #[test]
    fn a_version_5_record_loads_with_8_data_bits_on_the_cnc_port() {
        let mut s = Settings::default();
        s.set(ConfigKey::Units, "HPR:0,HPR:2").unwrap();
        s.set(ConfigKey::CncParity, "EVEN").unwrap();
        s.set(ConfigKey::CncDataBits, "7").unwrap();
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = s.encode(&mut out);
        assert_eq!((len, out[RECORD_V5_LEN]), (RECORD_V5_LEN + 1, 7));
        assert_eq!(Settings::decode(&out[..len]), Some(s));
        let v5 = &out[..RECORD_V5_LEN];
        assert_eq!(Settings::decode(v5), None, "not a version-6 record");
        let migrated = Settings::migrate(5, v5).unwrap();
        assert_eq!(migrated.units, s.units);
        assert_eq!(
            migrated.cnc.framing,
            s.cnc.framing.with_data_bits(DataBits::Eight)
        );
        assert_eq!(migrated.get(ConfigKey::CncDataBits), ConfigValue::Number(8));
        assert_eq!(Settings::migrate(6, v5), None);
    }

    #[test]
    fn decode_is_strict() {
        let mut out = [0u8; 72];
        let len = Settings::default().encode(&mut out);
        let good = out;
        assert!(Settings::decode(&good[..len]).is_some());
        assert_eq!(Settings::decode(&good[..len - 1]), None, "short");
        assert_eq!(Settings::decode(&good[..len + 1]), None, "long");
        let corrupt = |i: usize, v: u8| {
            let mut r = good;
            r[i] = v;
            Settings::decode(&r[..len])
        };
        assert_eq!(corrupt(0, 4), None, "unknown protocol");
        assert_eq!(corrupt(1, 0), None, "node address 0");
        assert_eq!(corrupt(2, 3), None, "unknown parity");
        assert_eq!(corrupt(3, 3), None, "three stop bits");
        assert_eq!(corrupt(4, 10), None, "10 ms time-out");
        assert_eq!(corrupt(6, 6), None, "six retries");
        assert_eq!(corrupt(13, 4), None, "HPR id 4");
        assert_eq!(corrupt(14, 0), None, "no failures before down");
        assert_eq!(corrupt(21, 0x80), None, "reserved flag");
        assert_eq!(corrupt(22, 2), None, "no such Phoenix format");
        assert_eq!(corrupt(23, 2), None, "bad process tag");
        assert_eq!(corrupt(24, 1), None, "process bytes without a process");
        assert!(corrupt(29, 0x80).is_some(), "SYSTEM_ERROR active high");
        assert_eq!(corrupt(45, 101), None, "SYSTEM_ERROR debounce above 100 ms");
        assert_eq!(corrupt(30, 101), None, "TORCH_ON debounce above 100 ms");
        assert_eq!(corrupt(37, 1), None, "START inverted");
        assert_eq!(corrupt(38, 0), None, "CNC node address 0 (broadcast)");
        assert_eq!(corrupt(39, 0x81), None, "CNC baud not one of the five");
        assert_eq!(corrupt(43, 3), None, "unknown CNC parity");
        assert_eq!(corrupt(44, 3), None, "three CNC stop bits");
        assert_eq!(corrupt(49, 1), None, "a start limit above 1000000");
        assert_eq!(corrupt(63, 9), None, "nine CNC data bits");
        assert!(corrupt(63, 7).is_some(), "seven CNC data bits");
        let with_process = Settings {
            process: Some(Process {
                mode: Mode::Cut,
                amps: Amps::from_raw(45 * 64),
                pressure: Pressure::Auto,
            }),
            ..Settings::default()
        };
        let len = with_process.encode(&mut out);
        let mut r = out;
        r[24] = 4;
        assert_eq!(Settings::decode(&r[..len]), None, "unknown mode");
        let mut r = out;
        r[25..27].copy_from_slice(&(401u16 * 64).to_le_bytes());
        assert_eq!(Settings::decode(&r[..len]), None, "amps above 400");
    }

    #[test]
    fn a_version_1_record_still_loads_with_the_reference_wiring() {
        let mut s = Settings::default();
        s.set(ConfigKey::TimeoutMs, "250").unwrap();
        s.set(ConfigKey::TorchOnActive, "HIGH").unwrap();
        let mut out = [0u8; RECORD_LEN];
        let len = s.encode(&mut out);
        assert_eq!(len, RECORD_LEN);
        // A version-1 record is the first 29 bytes of a version-2 one.
        let v1 = &out[..RECORD_V1_LEN];
        assert_eq!(Settings::decode(v1), None, "not a version-2 record");
        let migrated = Settings::migrate(1, v1).unwrap();
        assert_eq!(migrated.link, s.link);
        assert_eq!(migrated.io.inputs, crate::io::InputConfig::default());
        assert_eq!(
            migrated.get(ConfigKey::TorchOnActive),
            ConfigValue::Word("LOW")
        );
        assert_eq!(Settings::migrate(4, v1), None);
        // And the wiring round-trips in version 2.
        assert_eq!(Settings::decode(&out[..len]), Some(s));
    }
}
