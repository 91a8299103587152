//! Reply PDUs: parse (what the bridge receives) and emit (what a simulated unit answers).

use super::request::{register_count, write_registers};
use super::wire::{Writer, check_quantity, coil_state, coil_value, exact_len, two_words};
use super::{
    DeviceIdentification, ExceptionCode, FunctionCode, MAX_COIL_BYTES, MAX_READ_REGISTERS,
    MAX_WRITE_REGISTERS, Registers, Response,
};
use crate::{Error, Result};

/// Bit that turns a function code into its exception reply.
const EXCEPTION_BIT: u8 = 0x80;

impl<'a> Response<'a> {
    /// Parses a binary reply PDU (function code + data), including exception replies
    /// (`0x80 | function`, one exception code byte).
    ///
    /// Checks what a reply carries on its own: byte counts against the data that follows,
    /// register byte counts even and at most 250, a coil echo of 0xFF00 or 0x0000, the
    /// device identification object list. Whether it answers a given request is
    /// [`validate_reply`](crate::modbus_ascii::validate_reply)'s job.
    pub fn parse(pdu: &'a [u8]) -> Result<Response<'a>> {
        let (&function, data) = pdu.split_first().ok_or(Error::Truncated)?;
        if function & EXCEPTION_BIT != 0 {
            exact_len(data, 1)?;
            let code = data.first().copied().ok_or(Error::Truncated)?;
            return Ok(Response::Exception {
                function: function & !EXCEPTION_BIT,
                code: ExceptionCode::from_u8(code),
            });
        }
        let function = FunctionCode::from_u8(function).ok_or(Error::Unsupported)?;
        match function {
            FunctionCode::ReadCoils => {
                let bits = counted_bytes(data)?;
                if bits.len() > MAX_COIL_BYTES {
                    return Err(Error::Malformed);
                }
                Ok(Response::ReadCoils { bits })
            }
            FunctionCode::ReadHoldingRegisters => Ok(Response::ReadHoldingRegisters {
                values: counted_registers(data)?,
            }),
            FunctionCode::ReadInputRegisters => Ok(Response::ReadInputRegisters {
                values: counted_registers(data)?,
            }),
            FunctionCode::WriteSingleCoil => {
                let (address, value) = two_words(data)?;
                Ok(Response::WriteSingleCoil {
                    address,
                    on: coil_state(value)?,
                })
            }
            FunctionCode::WriteSingleRegister => {
                let (address, value) = two_words(data)?;
                Ok(Response::WriteSingleRegister { address, value })
            }
            FunctionCode::WriteMultipleRegisters => {
                let (start, quantity) = two_words(data)?;
                check_quantity(quantity, MAX_WRITE_REGISTERS)?;
                Ok(Response::WriteMultipleRegisters { start, quantity })
            }
            FunctionCode::EncapsulatedInterface => Ok(Response::ReadDeviceIdentification(
                DeviceIdentification::parse(data)?,
            )),
        }
    }

    /// The function byte this reply is sent with (`0x80 | function` for an exception).
    pub fn function_byte(&self) -> u8 {
        match self {
            Response::ReadCoils { .. } => FunctionCode::ReadCoils.to_u8(),
            Response::ReadHoldingRegisters { .. } => FunctionCode::ReadHoldingRegisters.to_u8(),
            Response::ReadInputRegisters { .. } => FunctionCode::ReadInputRegisters.to_u8(),
            Response::WriteSingleCoil { .. } => FunctionCode::WriteSingleCoil.to_u8(),
            Response::WriteSingleRegister { .. } => FunctionCode::WriteSingleRegister.to_u8(),
            Response::WriteMultipleRegisters { .. } => FunctionCode::WriteMultipleRegisters.to_u8(),
            Response::ReadDeviceIdentification(_) => FunctionCode::EncapsulatedInterface.to_u8(),
            Response::Exception { function, .. } => function | EXCEPTION_BIT,
        }
    }

    /// Writes the binary PDU into `out` and returns its length.
    ///
    /// Refuses ([`Error::Malformed`]) what [`Response::parse`] would refuse (empty or oversized
    /// data, odd register bytes, an inconsistent object list); [`Error::BufferTooSmall`] when
    /// `out` is short.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize> {
        if let Response::ReadDeviceIdentification(id) = self {
            return id.emit(out);
        }
        let mut w = Writer::new(out);
        w.u8(self.function_byte())?;
        match *self {
            Response::ReadCoils { bits } => {
                if bits.is_empty() || bits.len() > MAX_COIL_BYTES {
                    return Err(Error::Malformed);
                }
                w.u8(bits.len() as u8)?;
                w.bytes(bits)?;
            }
            Response::ReadHoldingRegisters { values } | Response::ReadInputRegisters { values } => {
                let quantity = register_count(&values)?;
                check_quantity(quantity, MAX_READ_REGISTERS)?;
                // At most 125 registers, so 250 bytes: fits in the byte-count field.
                w.u8((quantity * 2) as u8)?;
                write_registers(&mut w, &values)?;
            }
            Response::WriteSingleCoil { address, on } => {
                w.u16(address)?;
                w.u16(coil_value(on))?;
            }
            Response::WriteSingleRegister { address, value } => {
                w.u16(address)?;
                w.u16(value)?;
            }
            Response::WriteMultipleRegisters { start, quantity } => {
                check_quantity(quantity, MAX_WRITE_REGISTERS)?;
                w.u16(start)?;
                w.u16(quantity)?;
            }
            Response::Exception { code, .. } => w.u8(code.to_u8())?,
            // Emitted above, before the function byte.
            Response::ReadDeviceIdentification(_) => {}
        }
        Ok(w.len())
    }
}

/// `count, bytes[count]`: the body of a read reply. At least one byte must follow.
fn counted_bytes(data: &[u8]) -> Result<&[u8]> {
    let (&count, rest) = data.split_first().ok_or(Error::Truncated)?;
    if count == 0 {
        return Err(Error::Malformed);
    }
    exact_len(rest, usize::from(count))?;
    Ok(rest)
}

/// A register read reply's body: an even byte count of 2..=250 and that many bytes.
fn counted_registers(data: &[u8]) -> Result<Registers<'_>> {
    let bytes = counted_bytes(data)?;
    if bytes.len() % 2 != 0 || bytes.len() > usize::from(MAX_READ_REGISTERS) * 2 {
        return Err(Error::Malformed);
    }
    Ok(Registers::BigEndian(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(pdu: &[u8], expected: Response<'_>) {
        assert_eq!(Response::parse(pdu), Ok(expected));
        let mut out = [0u8; 260];
        let n = expected.emit(&mut out).unwrap();
        assert_eq!(&out[..n], pdu);
    }

    #[test]
    fn every_function() {
        round_trip(&[0x01, 0x01, 0x03], Response::ReadCoils { bits: &[0x03] });
        round_trip(
            &[0x03, 0x02, 0x00, 0x6F],
            Response::ReadHoldingRegisters {
                values: Registers::Words(&[0x006F]),
            },
        );
        round_trip(
            &[0x04, 0x04, 0x10, 0x40, 0x23, 0xDD],
            Response::ReadInputRegisters {
                values: Registers::Words(&[0x1040, 0x23DD]),
            },
        );
        round_trip(
            &[0x05, 0x31, 0x80, 0xFF, 0x00],
            Response::WriteSingleCoil {
                address: 0x3180,
                on: true,
            },
        );
        round_trip(
            &[0x06, 0x20, 0x93, 0x00, 0x01],
            Response::WriteSingleRegister {
                address: 0x2093,
                value: 1,
            },
        );
        round_trip(
            &[0x10, 0x30, 0x80, 0x00, 0x03],
            Response::WriteMultipleRegisters {
                start: 0x3080,
                quantity: 3,
            },
        );
        round_trip(
            &[0x84, 0x02],
            Response::Exception {
                function: 0x04,
                code: ExceptionCode::IllegalDataAddress,
            },
        );
        round_trip(
            &[0x90, 0x03],
            Response::Exception {
                function: 0x10,
                code: ExceptionCode::IllegalDataValue,
            },
        );
    }

    #[test]
    fn exception_lengths() {
        assert_eq!(Response::parse(&[0x84]), Err(Error::Truncated));
        assert_eq!(Response::parse(&[0x84, 0x02, 0x00]), Err(Error::Malformed));
        // An exception to a function this crate does not implement still parses.
        assert_eq!(
            Response::parse(&[0x82, 0x01]),
            Ok(Response::Exception {
                function: 0x02,
                code: ExceptionCode::IllegalFunction
            })
        );
    }

    #[test]
    fn byte_counts() {
        // Count says 4, only 2 follow; count says 2, 3 follow.
        assert_eq!(
            Response::parse(&[0x04, 0x04, 0x00, 0x01]),
            Err(Error::Truncated)
        );
        assert_eq!(
            Response::parse(&[0x04, 0x02, 0x00, 0x01, 0x02]),
            Err(Error::Malformed)
        );
        // Odd and zero register byte counts.
        assert_eq!(Response::parse(&[0x03, 0x01, 0x00]), Err(Error::Malformed));
        assert_eq!(Response::parse(&[0x04, 0x00]), Err(Error::Malformed));
        assert_eq!(Response::parse(&[0x01, 0x00]), Err(Error::Malformed));
        assert_eq!(Response::parse(&[0x04]), Err(Error::Truncated));
        // 252 bytes = 126 registers: more than a read may ask for.
        let mut pdu = [0u8; 254];
        pdu[0] = 0x04;
        pdu[1] = 252;
        assert_eq!(Response::parse(&pdu), Err(Error::Malformed));
        pdu[1] = 250;
        assert!(Response::parse(&pdu[..252]).is_ok());
        pdu[0] = 0x01;
        pdu[1] = 251;
        assert_eq!(Response::parse(&pdu[..253]), Err(Error::Malformed));
    }

    #[test]
    fn echo_checks() {
        assert_eq!(
            Response::parse(&[0x05, 0x31, 0x80, 0x12, 0x34]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Response::parse(&[0x10, 0x30, 0x80, 0x00, 0x00]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Response::parse(&[0x10, 0x30, 0x80, 0x00, 0x7C]),
            Err(Error::Malformed)
        );
        assert_eq!(
            Response::parse(&[0x06, 0x30, 0x80, 0x00]),
            Err(Error::Truncated)
        );
        assert_eq!(Response::parse(&[0x07, 0x00]), Err(Error::Unsupported));
        assert_eq!(Response::parse(&[]), Err(Error::Truncated));
    }

    #[test]
    fn emit_refuses_what_parse_refuses() {
        let mut out = [0u8; 300];
        let no_bits = Response::ReadCoils { bits: &[] };
        assert_eq!(no_bits.emit(&mut out), Err(Error::Malformed));
        let no_regs = Response::ReadInputRegisters {
            values: Registers::Words(&[]),
        };
        assert_eq!(no_regs.emit(&mut out), Err(Error::Malformed));
        let words = [0u16; 126];
        let many = Response::ReadHoldingRegisters {
            values: Registers::Words(&words),
        };
        assert_eq!(many.emit(&mut out), Err(Error::Malformed));
        let odd = Response::ReadHoldingRegisters {
            values: Registers::BigEndian(&[0, 1, 2]),
        };
        assert_eq!(odd.emit(&mut out), Err(Error::Malformed));
        let zero = Response::WriteMultipleRegisters {
            start: 0,
            quantity: 0,
        };
        assert_eq!(zero.emit(&mut out), Err(Error::Malformed));
        let short = Response::WriteSingleRegister {
            address: 0,
            value: 0,
        };
        assert_eq!(short.emit(&mut out[..4]), Err(Error::BufferTooSmall));
    }
}
