//! The simulators' byte edge for Modbus ASCII, through the protocol crate's framing
//! ([`Decoder`], [`encode`](modbus_ascii::encode)) and PDU codecs ([`Request::parse`],
//! [`Response::emit`]).
//!
//! Kept deliberately thin: the unit models only ever see typed requests and build owned
//! [`Reply`] values, so this file is the only place that knows about characters.

use plasma_protocol::Error;
use plasma_protocol::modbus_ascii::{
    self, Decoder, DeviceIdCode, DeviceIdentification, ExceptionCode, MAX_FRAME_CHARS, MAX_PDU_LEN,
    Registers, Request, Response,
};

/// Collects characters into frames (LRC checked); frames that fail are dropped silently, as
/// a Modbus unit does.
#[derive(Debug, Default)]
pub(crate) struct Assembler {
    decoder: Decoder,
}

impl Assembler {
    /// Feeds one character; returns (address, PDU) of a good frame that just ended.
    pub(crate) fn push(&mut self, byte: u8) -> Option<(u8, Vec<u8>)> {
        match self.decoder.push(byte)? {
            Ok(frame) => Some((frame.address, frame.pdu.to_vec())),
            Err(_) => None,
        }
    }

    /// A character arrived with a parity or framing error: the frame in progress is void.
    pub(crate) fn reset(&mut self) {
        self.decoder.reset();
    }
}

/// Characters of one whole frame (`:` ... CR LF) -> (address, PDU), if it checks out.
#[cfg(test)]
pub(crate) fn decode(frame: &[u8]) -> Option<(u8, Vec<u8>)> {
    let mut buf = [0u8; MAX_PDU_LEN];
    modbus_ascii::decode(frame, &mut buf)
        .ok()
        .map(|f| (f.address, f.pdu.to_vec()))
}

/// (address, PDU) -> the characters of a frame, `:` to CR LF.
pub(crate) fn encode(address: u8, pdu: &[u8]) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME_CHARS];
    match modbus_ascii::encode(address, pdu, &mut out) {
        Ok(n) => out[..n].to_vec(),
        Err(e) => panic!("simulator reply {pdu:02X?} cannot be framed: {e:?}"),
    }
}

/// Why a PDU is not a request the unit can act on, as the exception it answers with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Refused {
    pub function: u8,
    pub code: ExceptionCode,
}

/// PDU -> typed request, or the exception a unit answers: 01 for a function (or MEI type) it
/// does not implement, 03 for bad lengths, quantities or values.
pub(crate) fn parse_request(pdu: &[u8]) -> Result<Request<'_>, Refused> {
    let function = pdu.first().copied().unwrap_or(0);
    Request::parse(pdu).map_err(|e| Refused {
        function,
        code: match e {
            Error::Unsupported => ExceptionCode::IllegalFunction,
            _ => ExceptionCode::IllegalDataValue,
        },
    })
}

fn emit(response: &Response<'_>) -> Vec<u8> {
    let mut out = [0u8; MAX_PDU_LEN];
    match response.emit(&mut out) {
        Ok(n) => out[..n].to_vec(),
        Err(e) => panic!("simulator reply {response:?} cannot be emitted: {e:?}"),
    }
}

/// What a unit answers, owned so a model can build it; [`Reply::to_pdu`] emits it through the
/// protocol crate's typed [`Response`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Reply {
    /// Function 03.
    HoldingRegisters(Vec<u16>),
    /// Function 04.
    InputRegisters(Vec<u16>),
    /// Function 01: packed coil bits.
    Coils(Vec<u8>),
    /// Function 05 echo.
    WriteSingleCoil {
        /// Coil address.
        address: u16,
        /// State written.
        on: bool,
    },
    /// Function 06 echo.
    WriteSingleRegister {
        /// Register address.
        address: u16,
        /// Value written.
        value: u16,
    },
    /// Function 0x10 echo.
    WriteMultipleRegisters {
        /// First register.
        start: u16,
        /// Number of registers.
        quantity: u16,
    },
    /// 0x2B / 0x0E.
    DeviceIdentification {
        /// Access code echoed.
        code: DeviceIdCode,
        /// Conformity level.
        conformity: u8,
        /// Next object id field.
        next_object_id: u8,
        /// (object id, value) pairs.
        objects: Vec<(u8, Vec<u8>)>,
    },
    /// Exception reply.
    Exception {
        /// Function of the request.
        function: u8,
        /// Exception code.
        code: ExceptionCode,
    },
}

impl Reply {
    /// Exception reply to `function`.
    pub fn exception(function: u8, code: ExceptionCode) -> Reply {
        Reply::Exception { function, code }
    }

    /// The PDU bytes of this reply.
    pub fn to_pdu(&self) -> Vec<u8> {
        match self {
            Reply::HoldingRegisters(v) => emit(&Response::ReadHoldingRegisters {
                values: Registers::Words(v),
            }),
            Reply::InputRegisters(v) => emit(&Response::ReadInputRegisters {
                values: Registers::Words(v),
            }),
            Reply::Coils(bits) => emit(&Response::ReadCoils { bits }),
            Reply::WriteSingleCoil { address, on } => emit(&Response::WriteSingleCoil {
                address: *address,
                on: *on,
            }),
            Reply::WriteSingleRegister { address, value } => emit(&Response::WriteSingleRegister {
                address: *address,
                value: *value,
            }),
            Reply::WriteMultipleRegisters { start, quantity } => {
                emit(&Response::WriteMultipleRegisters {
                    start: *start,
                    quantity: *quantity,
                })
            }
            Reply::DeviceIdentification {
                code,
                conformity,
                next_object_id,
                objects,
            } => {
                let objects: Vec<(u8, &[u8])> =
                    objects.iter().map(|(id, v)| (*id, v.as_slice())).collect();
                let mut out = [0u8; MAX_PDU_LEN];
                match DeviceIdentification::emit_objects(
                    *code,
                    *conformity,
                    false,
                    *next_object_id,
                    &objects,
                    &mut out,
                ) {
                    Ok(n) => out[..n].to_vec(),
                    Err(e) => panic!("device identification cannot be emitted: {e:?}"),
                }
            }
            Reply::Exception { function, code } => emit(&Response::Exception {
                function: *function,
                code: *code,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(text: &str) -> Option<(u8, Vec<u8>)> {
        let mut a = Assembler::default();
        text.bytes().filter_map(|b| a.push(b)).last()
    }

    #[test]
    fn manual_request_decodes_to_a_typed_read() {
        // SYNC guide p. 11: read the 4-entry cartridge fault log.
        let (address, pdu) = frame(":01043044000483\r\n").unwrap();
        assert_eq!(address, 1);
        assert_eq!(
            parse_request(&pdu),
            Ok(Request::ReadInputRegisters {
                start: 0x3044,
                quantity: 4
            })
        );
    }

    #[test]
    fn a_wrong_lrc_is_not_a_frame() {
        assert_eq!(frame(":01043044000484\r\n"), None);
    }

    #[test]
    fn a_colon_restarts_the_frame() {
        assert_eq!(
            frame(":0104:010430000001CA\r\n").unwrap().1,
            [4, 0x30, 0, 0, 1]
        );
    }

    #[test]
    fn replies_encode_like_the_manual() {
        // SYNC guide p. 24: 0x3000 = 0x0508.
        let pdu = Reply::InputRegisters(vec![0x0508]).to_pdu();
        assert_eq!(encode(1, &pdu), b":0104020508EC\r\n");
        // SYNC guide p. 31: remote-mode write echo.
        let pdu = Reply::WriteMultipleRegisters {
            start: 0x3080,
            quantity: 3,
        }
        .to_pdu();
        assert_eq!(encode(1, &pdu), b":0110308000033C\r\n");
        assert_eq!(decode(b":0110308000033C\r\n"), Some((1, pdu)));
    }

    #[test]
    fn unknown_functions_are_illegal_and_bad_quantities_illegal_values() {
        assert_eq!(
            parse_request(&[0x17, 0, 0, 0, 1]),
            Err(Refused {
                function: 0x17,
                code: ExceptionCode::IllegalFunction
            })
        );
        assert_eq!(
            parse_request(&[0x04, 0x30, 0, 0, 0]),
            Err(Refused {
                function: 0x04,
                code: ExceptionCode::IllegalDataValue
            })
        );
        assert_eq!(
            parse_request(&[0x2B, 0x0D, 4, 1]),
            Err(Refused {
                function: 0x2B,
                code: ExceptionCode::IllegalFunction
            })
        );
    }
}
