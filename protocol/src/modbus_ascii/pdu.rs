//! Typed Modbus PDUs (function code + data) for the functions Powermax units use.
//!
//! Each type has a `parse` that checks every length, count and limit of the Modbus application
//! protocol and borrows its data from the input, and an `emit` that writes the binary PDU into a
//! caller's buffer and refuses to write what `parse` would refuse.

mod codes;
mod device_id;
mod request;
mod response;
mod wire;

pub use device_id::DeviceObjects;

/// Longest PDU a Modbus ASCII frame can carry: function code + 252 data bytes.
pub const MAX_PDU_LEN: usize = 253;

/// Most registers one read may ask for (Modbus limit for functions 03 and 04).
pub const MAX_READ_REGISTERS: u16 = 125;
/// Most registers one write may carry (Modbus limit for function 0x10).
pub const MAX_WRITE_REGISTERS: u16 = 123;
/// Most coils one read may ask for (Modbus limit for function 01).
pub const MAX_READ_COILS: u16 = 2000;
/// Most data bytes a Read Coils reply may carry: 2000 coils packed 8 to a byte.
pub const MAX_COIL_BYTES: usize = 250;

/// Function codes the bridge uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum FunctionCode {
    /// 0x01 Read Coils.
    ReadCoils = 0x01,
    /// 0x03 Read Holding Registers.
    ReadHoldingRegisters = 0x03,
    /// 0x04 Read Input Registers (SYNC units answer it for holding registers too).
    ReadInputRegisters = 0x04,
    /// 0x05 Write Single Coil.
    WriteSingleCoil = 0x05,
    /// 0x06 Write Single Register.
    WriteSingleRegister = 0x06,
    /// 0x10 Write Multiple Registers.
    WriteMultipleRegisters = 0x10,
    /// 0x2B Encapsulated Interface Transport (MEI type 0x0E: Read Device Identification).
    EncapsulatedInterface = 0x2B,
}

/// Read Device Identification access codes (MEI 0x0E).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum DeviceIdCode {
    /// 0x01: basic identification, stream access (objects 0x00-0x02).
    Basic = 0x01,
    /// 0x02: regular identification, stream access (objects 0x00-0x06).
    Regular = 0x02,
    /// 0x03: extended identification, stream access.
    Extended = 0x03,
    /// 0x04: one specific object.
    Specific = 0x04,
}

/// Standard Modbus exception codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ExceptionCode {
    /// 0x01 Illegal function.
    IllegalFunction,
    /// 0x02 Illegal data address.
    IllegalDataAddress,
    /// 0x03 Illegal data value.
    IllegalDataValue,
    /// 0x04 Server device failure.
    ServerDeviceFailure,
    /// 0x05 Acknowledge.
    Acknowledge,
    /// 0x06 Server device busy.
    ServerDeviceBusy,
    /// 0x08 Memory parity error.
    MemoryParityError,
    /// 0x0A Gateway path unavailable.
    GatewayPathUnavailable,
    /// 0x0B Gateway target device failed to respond.
    GatewayTargetFailed,
    /// Any other code, kept as received.
    Other(u8),
}

/// A run of 16-bit register values, either the caller's words or big-endian bytes of a frame.
///
/// Borrowing keeps decoding zero-copy; both forms compare and iterate the same way.
#[derive(Debug, Clone, Copy)]
pub enum Registers<'a> {
    /// Values given by the caller.
    Words(&'a [u16]),
    /// Values as they sit in a frame: two bytes each, high byte first (length is even).
    BigEndian(&'a [u8]),
}

impl<'a> Registers<'a> {
    /// Number of registers.
    pub fn len(&self) -> usize {
        match self {
            Registers::Words(w) => w.len(),
            Registers::BigEndian(b) => b.len() / 2,
        }
    }

    /// True when there are no registers.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Register `index`, if present.
    pub fn get(&self, index: usize) -> Option<u16> {
        match self {
            Registers::Words(w) => w.get(index).copied(),
            Registers::BigEndian(b) => {
                let hi = *b.get(index * 2)?;
                let lo = *b.get(index * 2 + 1)?;
                Some(u16::from_be_bytes([hi, lo]))
            }
        }
    }

    /// The values in order.
    pub fn iter(&self) -> impl Iterator<Item = u16> + '_ {
        // Two plain slice iterators, one of them empty: cheaper than indexing with `get`.
        let (words, bytes): (&[u16], &[u8]) = match *self {
            Registers::Words(w) => (w, &[]),
            Registers::BigEndian(b) => (&[], b),
        };
        words.iter().copied().chain(
            bytes
                .chunks_exact(2)
                .filter_map(|pair| pair.try_into().ok().map(u16::from_be_bytes)),
        )
    }
}

impl PartialEq for Registers<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}
impl Eq for Registers<'_> {}

/// A request PDU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request<'a> {
    /// 0x01: read `quantity` coils from `start`.
    ReadCoils {
        /// First coil address.
        start: u16,
        /// Number of coils (1..=2000).
        quantity: u16,
    },
    /// 0x03: read `quantity` holding registers from `start`.
    ReadHoldingRegisters {
        /// First register address.
        start: u16,
        /// Number of registers (1..=125).
        quantity: u16,
    },
    /// 0x04: read `quantity` input registers from `start`.
    ReadInputRegisters {
        /// First register address.
        start: u16,
        /// Number of registers (1..=125).
        quantity: u16,
    },
    /// 0x05: force one coil on (0xFF00) or off (0x0000).
    WriteSingleCoil {
        /// Coil address.
        address: u16,
        /// New state.
        on: bool,
    },
    /// 0x06: write one register.
    WriteSingleRegister {
        /// Register address.
        address: u16,
        /// New value.
        value: u16,
    },
    /// 0x10: write consecutive registers from `start`.
    WriteMultipleRegisters {
        /// First register address.
        start: u16,
        /// Values (1..=123).
        values: Registers<'a>,
    },
    /// 0x2B / 0x0E: Read Device Identification.
    ReadDeviceIdentification {
        /// Access code.
        code: DeviceIdCode,
        /// First object to read.
        object_id: u8,
    },
}

/// A reply PDU, borrowing its data from the received frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Response<'a> {
    /// 0x01: coil states packed LSB first, as many bytes as the reply's byte count.
    ReadCoils {
        /// Packed coil bits.
        bits: &'a [u8],
    },
    /// 0x03: register values.
    ReadHoldingRegisters {
        /// Values in address order.
        values: Registers<'a>,
    },
    /// 0x04: register values.
    ReadInputRegisters {
        /// Values in address order.
        values: Registers<'a>,
    },
    /// 0x05: echo of the request.
    WriteSingleCoil {
        /// Coil address.
        address: u16,
        /// State written.
        on: bool,
    },
    /// 0x06: echo of the request.
    WriteSingleRegister {
        /// Register address.
        address: u16,
        /// Value written.
        value: u16,
    },
    /// 0x10: echo of start and quantity.
    WriteMultipleRegisters {
        /// First register address.
        start: u16,
        /// Number of registers written.
        quantity: u16,
    },
    /// 0x2B / 0x0E reply.
    ReadDeviceIdentification(DeviceIdentification<'a>),
    /// `0x80 | function` exception reply.
    Exception {
        /// The function code of the request (without the 0x80 bit).
        function: u8,
        /// Why the unit refused.
        code: ExceptionCode,
    },
}

/// Read Device Identification reply: header fields and the raw object list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceIdentification<'a> {
    /// Access code echoed from the request.
    pub code: DeviceIdCode,
    /// Conformity level byte.
    pub conformity: u8,
    /// True (0xFF) when more objects follow in another transaction.
    pub more_follows: bool,
    /// Object id to ask for next when `more_follows`.
    pub next_object_id: u8,
    /// Number of objects in `objects`.
    pub object_count: u8,
    /// Object list as received: (id, length, value bytes)...; validated by the parser.
    pub objects: &'a [u8],
}
