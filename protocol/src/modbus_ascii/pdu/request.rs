//! Request PDUs: parse (what a simulated unit receives) and emit (what the bridge sends).

use super::wire::{Writer, check_quantity, coil_state, coil_value, exact_len, two_words};
use super::{
    DeviceIdCode, FunctionCode, MAX_READ_COILS, MAX_READ_REGISTERS, MAX_WRITE_REGISTERS, Registers,
    Request,
};
use crate::{Error, Result};

/// MEI type of Read Device Identification inside function 0x2B.
pub(crate) const MEI_READ_DEVICE_ID: u8 = 0x0E;

impl<'a> Request<'a> {
    /// Parses a binary request PDU (function code + data).
    ///
    /// Quantities must be within the Modbus limits (1..=2000 coils, 1..=125 registers read,
    /// 1..=123 registers written), byte counts must agree with them and a coil value must be
    /// 0xFF00 or 0x0000. Too few bytes is [`Error::Truncated`], extra bytes or a value out of
    /// range [`Error::Malformed`], a function this crate does not implement
    /// [`Error::Unsupported`].
    pub fn parse(pdu: &'a [u8]) -> Result<Request<'a>> {
        let (&function, data) = pdu.split_first().ok_or(Error::Truncated)?;
        let function = FunctionCode::from_u8(function).ok_or(Error::Unsupported)?;
        match function {
            FunctionCode::ReadCoils => {
                let (start, quantity) = two_words(data)?;
                check_quantity(quantity, MAX_READ_COILS)?;
                Ok(Request::ReadCoils { start, quantity })
            }
            FunctionCode::ReadHoldingRegisters => {
                let (start, quantity) = two_words(data)?;
                check_quantity(quantity, MAX_READ_REGISTERS)?;
                Ok(Request::ReadHoldingRegisters { start, quantity })
            }
            FunctionCode::ReadInputRegisters => {
                let (start, quantity) = two_words(data)?;
                check_quantity(quantity, MAX_READ_REGISTERS)?;
                Ok(Request::ReadInputRegisters { start, quantity })
            }
            FunctionCode::WriteSingleCoil => {
                let (address, value) = two_words(data)?;
                let on = coil_state(value)?;
                Ok(Request::WriteSingleCoil { address, on })
            }
            FunctionCode::WriteSingleRegister => {
                let (address, value) = two_words(data)?;
                Ok(Request::WriteSingleRegister { address, value })
            }
            FunctionCode::WriteMultipleRegisters => {
                let [s0, s1, q0, q1, byte_count, ref values @ ..] = *data else {
                    return Err(Error::Truncated);
                };
                let quantity = u16::from_be_bytes([q0, q1]);
                check_quantity(quantity, MAX_WRITE_REGISTERS)?;
                if usize::from(byte_count) != usize::from(quantity) * 2 {
                    return Err(Error::Malformed);
                }
                exact_len(values, usize::from(byte_count))?;
                Ok(Request::WriteMultipleRegisters {
                    start: u16::from_be_bytes([s0, s1]),
                    values: Registers::BigEndian(values),
                })
            }
            FunctionCode::EncapsulatedInterface => {
                // Other MEI types (e.g. 0x0D, CANopen) exist but no Powermax uses them.
                if data.first() != Some(&MEI_READ_DEVICE_ID) {
                    return Err(if data.is_empty() {
                        Error::Truncated
                    } else {
                        Error::Unsupported
                    });
                }
                let [_, code, object_id] = *data else {
                    return Err(if data.len() < 3 {
                        Error::Truncated
                    } else {
                        Error::Malformed
                    });
                };
                let code = DeviceIdCode::from_u8(code).ok_or(Error::Malformed)?;
                Ok(Request::ReadDeviceIdentification { code, object_id })
            }
        }
    }

    /// The function code this request is sent with.
    pub fn function(&self) -> FunctionCode {
        match self {
            Request::ReadCoils { .. } => FunctionCode::ReadCoils,
            Request::ReadHoldingRegisters { .. } => FunctionCode::ReadHoldingRegisters,
            Request::ReadInputRegisters { .. } => FunctionCode::ReadInputRegisters,
            Request::WriteSingleCoil { .. } => FunctionCode::WriteSingleCoil,
            Request::WriteSingleRegister { .. } => FunctionCode::WriteSingleRegister,
            Request::WriteMultipleRegisters { .. } => FunctionCode::WriteMultipleRegisters,
            Request::ReadDeviceIdentification { .. } => FunctionCode::EncapsulatedInterface,
        }
    }

    /// Writes the binary PDU into `out` and returns its length.
    ///
    /// Refuses ([`Error::Malformed`]) what [`Request::parse`] would refuse, so the bridge cannot
    /// send a request outside the Modbus limits; [`Error::BufferTooSmall`] when `out` is short.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize> {
        let mut w = Writer::new(out);
        w.u8(self.function().to_u8())?;
        match *self {
            Request::ReadCoils { start, quantity } => {
                check_quantity(quantity, MAX_READ_COILS)?;
                w.u16(start)?;
                w.u16(quantity)?;
            }
            Request::ReadHoldingRegisters { start, quantity }
            | Request::ReadInputRegisters { start, quantity } => {
                check_quantity(quantity, MAX_READ_REGISTERS)?;
                w.u16(start)?;
                w.u16(quantity)?;
            }
            Request::WriteSingleCoil { address, on } => {
                w.u16(address)?;
                w.u16(coil_value(on))?;
            }
            Request::WriteSingleRegister { address, value } => {
                w.u16(address)?;
                w.u16(value)?;
            }
            Request::WriteMultipleRegisters { start, values } => {
                let quantity = register_count(&values)?;
                check_quantity(quantity, MAX_WRITE_REGISTERS)?;
                w.u16(start)?;
                w.u16(quantity)?;
                // At most 123 registers, so 246 bytes: fits in the byte-count field.
                w.u8((quantity * 2) as u8)?;
                write_registers(&mut w, &values)?;
            }
            Request::ReadDeviceIdentification { code, object_id } => {
                w.u8(MEI_READ_DEVICE_ID)?;
                w.u8(code.to_u8())?;
                w.u8(object_id)?;
            }
        }
        Ok(w.len())
    }
}

/// Number of registers in `values`, refusing a byte form with an odd length (half a register).
pub(crate) fn register_count(values: &Registers<'_>) -> Result<u16> {
    if matches!(values, Registers::BigEndian(bytes) if bytes.len() % 2 != 0) {
        return Err(Error::Malformed);
    }
    u16::try_from(values.len()).map_err(|_| Error::Malformed)
}

/// Writes `values` big-endian, two bytes each.
pub(crate) fn write_registers(w: &mut Writer<'_>, values: &Registers<'_>) -> Result<()> {
    match values {
        Registers::BigEndian(bytes) => w.bytes(bytes),
        Registers::Words(words) => words.iter().try_for_each(|&v| w.u16(v)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(pdu: &[u8], expected: Request<'_>) {
        assert_eq!(Request::parse(pdu), Ok(expected));
        let mut out = [0u8; 260];
        let n = expected.emit(&mut out).unwrap();
        assert_eq!(&out[..n], pdu);
    }

    #[test]
    fn every_function() {
        round_trip(
            &[0x01, 0x31, 0x00, 0x00, 0x02],
            Request::ReadCoils {
                start: 0x3100,
                quantity: 2,
            },
        );
        round_trip(
            &[0x03, 0x20, 0x93, 0x00, 0x03],
            Request::ReadHoldingRegisters {
                start: 0x2093,
                quantity: 3,
            },
        );
        round_trip(
            &[0x04, 0x30, 0x44, 0x00, 0x04],
            Request::ReadInputRegisters {
                start: 0x3044,
                quantity: 4,
            },
        );
        round_trip(
            &[0x05, 0x31, 0x80, 0xFF, 0x00],
            Request::WriteSingleCoil {
                address: 0x3180,
                on: true,
            },
        );
        round_trip(
            &[0x05, 0x31, 0x80, 0x00, 0x00],
            Request::WriteSingleCoil {
                address: 0x3180,
                on: false,
            },
        );
        round_trip(
            &[0x06, 0x20, 0x94, 0x10, 0x40],
            Request::WriteSingleRegister {
                address: 0x2094,
                value: 0x1040,
            },
        );
        round_trip(
            &[0x10, 0x30, 0x8E, 0x00, 0x02, 0x04, 0x04, 0x04, 0x06, 0x18],
            Request::WriteMultipleRegisters {
                start: 0x308E,
                values: Registers::Words(&[0x0404, 0x0618]),
            },
        );
        round_trip(
            &[0x2B, 0x0E, 0x04, 0x01],
            Request::ReadDeviceIdentification {
                code: DeviceIdCode::Specific,
                object_id: 1,
            },
        );
    }

    #[test]
    fn quantity_limits() {
        let read = |f: u8, q: u16| Request::parse(&[f, 0, 0, (q >> 8) as u8, q as u8]).map(|_| ());
        for f in [0x03, 0x04] {
            assert_eq!(read(f, 0), Err(Error::Malformed));
            assert_eq!(read(f, 1), Ok(()));
            assert_eq!(read(f, 125), Ok(()));
            assert_eq!(read(f, 126), Err(Error::Malformed));
        }
        assert_eq!(read(0x01, 0), Err(Error::Malformed));
        assert_eq!(read(0x01, 2000), Ok(()));
        assert_eq!(read(0x01, 2001), Err(Error::Malformed));

        let mut out = [0u8; 8];
        let too_many = Request::ReadInputRegisters {
            start: 0,
            quantity: 126,
        };
        assert_eq!(too_many.emit(&mut out), Err(Error::Malformed));
        let none = Request::ReadCoils {
            start: 0,
            quantity: 0,
        };
        assert_eq!(none.emit(&mut out), Err(Error::Malformed));
    }

    #[test]
    fn write_multiple_limits_and_counts() {
        let mut pdu = [0u8; 6 + 2 * 124];
        pdu[0] = 0x10;
        // 123 registers: the most allowed.
        pdu[4] = 123;
        pdu[5] = 246;
        assert!(Request::parse(&pdu[..6 + 246]).is_ok());
        // 124 registers: too many.
        pdu[4] = 124;
        pdu[5] = 248;
        assert_eq!(Request::parse(&pdu[..6 + 248]), Err(Error::Malformed));
        // Byte count disagreeing with the quantity.
        assert_eq!(
            Request::parse(&[0x10, 0, 0, 0, 1, 3, 0, 0, 0]),
            Err(Error::Malformed)
        );
        // Fewer data bytes than the byte count, and more.
        assert_eq!(
            Request::parse(&[0x10, 0, 0, 0, 1, 2, 0]),
            Err(Error::Truncated)
        );
        assert_eq!(
            Request::parse(&[0x10, 0, 0, 0, 1, 2, 0, 0, 0]),
            Err(Error::Malformed)
        );
        assert_eq!(Request::parse(&[0x10, 0, 0, 0, 1]), Err(Error::Truncated));

        let mut out = [0u8; 300];
        let empty = Request::WriteMultipleRegisters {
            start: 0,
            values: Registers::Words(&[]),
        };
        assert_eq!(empty.emit(&mut out), Err(Error::Malformed));
        let words = [0u16; 124];
        let big = Request::WriteMultipleRegisters {
            start: 0,
            values: Registers::Words(&words),
        };
        assert_eq!(big.emit(&mut out), Err(Error::Malformed));
        let odd = Request::WriteMultipleRegisters {
            start: 0,
            values: Registers::BigEndian(&[1, 2, 3]),
        };
        assert_eq!(odd.emit(&mut out), Err(Error::Malformed));
    }

    #[test]
    fn coil_value_must_be_ff00_or_0000() {
        assert_eq!(
            Request::parse(&[0x05, 0x31, 0x80, 0x00, 0x01]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Request::parse(&[0x05, 0x31, 0x80, 0x00, 0xFF]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Request::parse(&[0x05, 0x31, 0x80, 0xFF, 0xFF]),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn lengths_and_unknown_functions() {
        assert_eq!(Request::parse(&[]), Err(Error::Truncated));
        assert_eq!(
            Request::parse(&[0x04, 0x30, 0x44, 0x00]),
            Err(Error::Truncated)
        );
        assert_eq!(
            Request::parse(&[0x04, 0x30, 0x44, 0x00, 0x04, 0x00]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Request::parse(&[0x02, 0x00, 0x00, 0x00, 0x01]),
            Err(Error::Unsupported)
        );
        assert_eq!(Request::parse(&[0x84, 0x02]), Err(Error::Unsupported));
        assert_eq!(Request::parse(&[0x2B]), Err(Error::Truncated));
        assert_eq!(
            Request::parse(&[0x2B, 0x0D, 0x00, 0x00]),
            Err(Error::Unsupported)
        );
        assert_eq!(Request::parse(&[0x2B, 0x0E, 0x04]), Err(Error::Truncated));
        assert_eq!(
            Request::parse(&[0x2B, 0x0E, 0x04, 0x01, 0x00]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Request::parse(&[0x2B, 0x0E, 0x05, 0x01]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Request::parse(&[0x2B, 0x0E, 0x00, 0x01]),
            Err(Error::Malformed)
        );
    }

    #[test]
    fn emit_needs_room() {
        let req = Request::ReadInputRegisters {
            start: 0x3044,
            quantity: 4,
        };
        let mut out = [0u8; 4];
        assert_eq!(req.emit(&mut out), Err(Error::BufferTooSmall));
        let mut out = [0u8; 5];
        assert_eq!(req.emit(&mut out), Ok(5));
    }
}
