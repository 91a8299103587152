//! The CNC as a Modbus ASCII master on the bridge's CNC port (docs/cnc-protocol.md section 9).
//!
//! Random CNC bytes practically never carry a valid LRC, so these steps build requests whose
//! frames the protocol crate's encoder writes, with addresses taken from the protocol's
//! register tables (mostly the legacy map and the SYNC map, nudged onto the gaps and edges
//! around them) and values biased towards what a master writes: zero, mode numbers, amps x 64
//! and psi x 128, and the limits the bridge holds. [`Pmx485`] is LinuxCNC's sequence, so the
//! write combiner is reached the way a real master reaches it.

use libfuzzer_sys::arbitrary::{self, Arbitrary};

use plasma_firmware::link::UnitStatus;
use plasma_protocol::hpr::{MAX_MAXPRO_AMPS, MIN_AMPS};
use plasma_protocol::modbus_ascii::{DeviceIdCode, FunctionCode, MAX_PDU_LEN, Registers, Request};
use plasma_protocol::powermax::registers::{
    LEGACY_COILS, LEGACY_REGISTERS, RegisterInfo, SYNC_COILS, SYNC_REGISTERS,
};
use plasma_protocol::powermax::{Amps, OperatingMode, Psi, legacy, sync};

use crate::pick;

/// The force registers of both maps, the ones the combiner gathers.
const FORCE_REGISTERS: [u16; 6] = [
    legacy::MODE_FORCE,
    legacy::CURRENT_FORCE,
    legacy::PRESSURE_FORCE,
    sync::REMOTE_MODE,
    sync::REMOTE_CURRENT,
    sync::REMOTE_PRESSURE,
];
const ID_CODES: [DeviceIdCode; 4] = [
    DeviceIdCode::Basic,
    DeviceIdCode::Regular,
    DeviceIdCode::Extended,
    DeviceIdCode::Specific,
];
/// Registers a 0x10 request carries at most here: the bridge takes three, more is an address
/// outside its map; the Modbus limit itself is the decoder targets' business.
const MAX_WRITE_VALUES: usize = 8;
/// Reads pmx485 makes after its writes, at most.
const MAX_PMX485_READS: usize = 4;

/// Whom a request is for.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Node {
    /// The bridge's `cnc_address`.
    Bridge,
    /// Node 0: carried out, never answered.
    Broadcast,
    /// Any node (now and then the bridge's own, or 0).
    Other(u8),
}

impl Node {
    pub fn address(self, cnc_address: u8) -> u8 {
        match self {
            Node::Bridge => cnc_address,
            Node::Broadcast => 0,
            Node::Other(address) => address,
        }
    }
}

/// A register address, mostly one the protocol documents.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Register {
    /// A force register of either map.
    Force(u8),
    /// An address of `LEGACY_REGISTERS`, moved by `nudge % 3` (-2..=2: the gaps and edges).
    Legacy { entry: u8, offset: u8, nudge: i8 },
    /// An address of `SYNC_REGISTERS`, moved the same way.
    Sync { entry: u8, offset: u8, nudge: i8 },
    /// Anywhere.
    Any(u16),
}

impl Register {
    fn address(self) -> u16 {
        match self {
            Register::Force(i) => pick(&FORCE_REGISTERS, i),
            Register::Legacy {
                entry,
                offset,
                nudge,
            } => in_table(LEGACY_REGISTERS, entry, offset, nudge),
            Register::Sync {
                entry,
                offset,
                nudge,
            } => in_table(SYNC_REGISTERS, entry, offset, nudge),
            Register::Any(address) => address,
        }
    }
}

/// A coil address: the documented ones (no coil is served; a write must never reach START).
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Coil {
    Legacy(u8),
    Sync(u8),
    Any(u16),
}

impl Coil {
    fn address(self) -> u16 {
        match self {
            Coil::Legacy(i) => in_table(LEGACY_COILS, i, 0, 0),
            Coil::Sync(i) => in_table(SYNC_COILS, i, 0, 0),
            Coil::Any(address) => address,
        }
    }
}

/// An address inside entry `entry` of `table`, `nudge % 3` steps away.
fn in_table(table: &[RegisterInfo], entry: u8, offset: u8, nudge: i8) -> u16 {
    let info = table[usize::from(entry) % table.len()];
    let span = u32::from(info.last - info.first) + 1;
    let inside = info.first + (u32::from(offset) % span) as u16;
    inside.wrapping_add_signed(i16::from(nudge % 3))
}

/// A register value, mostly one a master writes.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Value {
    Zero,
    /// The legacy number of a mode of `OperatingMode::ALL`, or one past the last.
    Mode(u8),
    /// Whole amps x 64 (wrapping past the register, as a master's arithmetic could).
    Amps(u16),
    /// Whole psi x 128.
    Psi(u8),
    /// The current limit the bridge holds (the unit's, else the HPR range), `delta` steps away.
    CurrentLimit {
        max: bool,
        delta: i8,
    },
    /// The pressure limit the bridge holds, `delta` steps away.
    PressureLimit {
        max: bool,
        delta: i8,
    },
    /// 0xFFFF, 0x8000 or 0x7FFF: the sign bit a fixed-point register carries.
    Extreme(u8),
    Any(u16),
}

impl Value {
    fn resolve(self, status: &UnitStatus) -> u16 {
        let limits = status.limits;
        match self {
            Value::Zero => 0,
            Value::Mode(i) => {
                let modes = OperatingMode::ALL.map(OperatingMode::to_legacy);
                let past_last = modes.iter().max().map_or(0, |m| m + 1);
                let i = usize::from(i) % (modes.len() + 1);
                modes.get(i).copied().unwrap_or(past_last)
            }
            Value::Amps(amps) => amps.wrapping_mul(Amps::STEPS_PER_UNIT),
            Value::Psi(psi) => u16::from(psi).wrapping_mul(Psi::STEPS_PER_UNIT),
            Value::CurrentLimit { max, delta } => {
                let limit = match (limits, max) {
                    (Some(l), false) => l.min_current.raw(),
                    (Some(l), true) => l.max_current.raw(),
                    (None, false) => MIN_AMPS.wrapping_mul(Amps::STEPS_PER_UNIT),
                    (None, true) => MAX_MAXPRO_AMPS.wrapping_mul(Amps::STEPS_PER_UNIT),
                };
                limit.wrapping_add_signed(i16::from(delta))
            }
            Value::PressureLimit { max, delta } => {
                let limit = match (limits, max) {
                    (Some(l), false) => l.min_pressure.raw(),
                    (Some(l), true) => l.max_pressure.raw(),
                    (None, _) => 0,
                };
                limit.wrapping_add_signed(i16::from(delta))
            }
            Value::Extreme(i) => pick(&[0xFFFF, 0x8000, 0x7FFF], i),
            Value::Any(value) => value,
        }
    }
}

/// A request PDU from the master.
#[derive(Arbitrary, Debug, Clone)]
pub enum Pdu {
    /// 03 (holding) or 04 (input); any quantity, 0 and over 125 included.
    Read {
        holding: bool,
        start: Register,
        quantity: u8,
    },
    /// 06.
    WriteOne { register: Register, value: Value },
    /// 0x10 (beyond three registers: an address outside the bridge's map).
    WriteMany { start: Register, values: Vec<Value> },
    /// 0x2B / 0x0E.
    Identify { code: u8, object: u8 },
    /// 01 or 05.
    Coil { write: bool, coil: Coil, on: bool },
    /// Any PDU: another function, malformed data.
    Raw(Vec<u8>),
}

impl Pdu {
    /// The PDU bytes (`None` when they do not fit a frame).
    pub fn bytes(&self, status: &UnitStatus) -> Option<Vec<u8>> {
        let request = match self {
            Pdu::Read {
                holding,
                start,
                quantity,
            } => {
                let function = if *holding {
                    FunctionCode::ReadHoldingRegisters
                } else {
                    FunctionCode::ReadInputRegisters
                };
                // Written out rather than emitted: `Request::emit` refuses quantities outside
                // the Modbus limits, which the bridge must answer with exception 03.
                let mut pdu = vec![function as u8];
                pdu.extend_from_slice(&start.address().to_be_bytes());
                pdu.extend_from_slice(&u16::from(*quantity).to_be_bytes());
                return Some(pdu);
            }
            Pdu::WriteOne { register, value } => Request::WriteSingleRegister {
                address: register.address(),
                value: value.resolve(status),
            },
            Pdu::WriteMany { start, values } => {
                let bytes: Vec<u8> = values
                    .iter()
                    .take(MAX_WRITE_VALUES)
                    .flat_map(|v| v.resolve(status).to_be_bytes())
                    .collect();
                if bytes.is_empty() {
                    // Quantity 0, which `Request::emit` refuses: exception 03.
                    let mut pdu = vec![FunctionCode::WriteMultipleRegisters as u8];
                    pdu.extend_from_slice(&start.address().to_be_bytes());
                    pdu.extend_from_slice(&[0, 0, 0]);
                    return Some(pdu);
                }
                return emit(&Request::WriteMultipleRegisters {
                    start: start.address(),
                    values: Registers::BigEndian(&bytes),
                });
            }
            Pdu::Identify { code, object } => Request::ReadDeviceIdentification {
                code: pick(&ID_CODES, *code),
                object_id: *object,
            },
            Pdu::Coil { write, coil, on } => {
                let address = coil.address();
                if *write {
                    Request::WriteSingleCoil { address, on: *on }
                } else {
                    Request::ReadCoils {
                        start: address,
                        quantity: 1,
                    }
                }
            }
            Pdu::Raw(bytes) => return (bytes.len() <= MAX_PDU_LEN).then(|| bytes.clone()),
        };
        emit(&request)
    }
}

fn emit(request: &Request<'_>) -> Option<Vec<u8>> {
    let mut out = [0u8; MAX_PDU_LEN];
    let n = request.emit(&mut out).ok()?;
    Some(out[..n].to_vec())
}

/// One request from the CNC.
#[derive(Arbitrary, Debug, Clone)]
pub struct MasterRequest {
    pub node: Node,
    pub pdu: Pdu,
    /// When the board cannot tell where the CNC port's input stands (after random bytes):
    /// let a frame under way lapse and end the line first, so the request is one for sure.
    pub resync: bool,
}

/// LinuxCNC's pmx485: mode, current x 64 and pressure x 128 written with one 06 request each
/// (0x2093, 0x2094, 0x2096, each after the echo of the one before), then reads of its cycle;
/// on disable it writes three zeros.
#[derive(Arbitrary, Debug, Clone)]
pub struct Pmx485 {
    pub mode: Value,
    pub current: Value,
    pub pressure: Value,
    /// Milliseconds before each request (an echo's turn-around; over the combiner's 100 ms a
    /// group completes by itself in the middle).
    pub gaps: [u8; 3],
    pub reads: Vec<Register>,
    /// A TORCH_ON edge (active or not) before the request at this index.
    pub torch_on: Option<(u8, bool)>,
    pub resync: bool,
}

/// One request of a [`Pmx485`] sequence.
pub struct Exchange {
    /// Milliseconds before it.
    pub gap_ms: u8,
    /// A TORCH_ON edge before it.
    pub torch_on: Option<bool>,
    pub pdu: Pdu,
}

impl Pmx485 {
    pub fn exchanges(&self) -> Vec<Exchange> {
        let writes = [
            (legacy::MODE_FORCE, self.mode),
            (legacy::CURRENT_FORCE, self.current),
            (legacy::PRESSURE_FORCE, self.pressure),
        ]
        .into_iter()
        .map(|(address, value)| Pdu::WriteOne {
            register: Register::Any(address),
            value,
        });
        let reads = self
            .reads
            .iter()
            .take(MAX_PMX485_READS)
            .map(|&start| Pdu::Read {
                holding: false,
                start,
                quantity: 1,
            });
        writes
            .chain(reads)
            .enumerate()
            .map(|(i, pdu)| Exchange {
                gap_ms: self.gaps.get(i).copied().unwrap_or(0),
                torch_on: self
                    .torch_on
                    .and_then(|(at, active)| (usize::from(at) == i).then_some(active)),
                pdu,
            })
            .collect()
    }
}
