//! The simulators' byte edge for Modbus ASCII: frame assembly, LRC, and the PDU <-> typed
//! [`Request`] / [`Response`] conversion.
//!
//! Kept deliberately thin: the unit models only ever see typed requests and build owned
//! [`Reply`] values, so this file is the only place that knows about characters.

use plasma_protocol::modbus_ascii::{
    DeviceIdCode, ExceptionCode, Registers, Request, Response, pdu::DeviceIdentification,
};

/// Longest frame body (between `:` and CR LF) a unit buffers: address, function, 252 data
/// bytes and the LRC, as hex.
const MAX_FRAME_CHARS: usize = 2 * (1 + 1 + 252 + 1);

/// Collects characters into frames: `:` starts one (dropping any partial frame), CR LF ends it.
#[derive(Debug, Default)]
pub(crate) struct Assembler {
    body: Vec<u8>,
    in_frame: bool,
    saw_cr: bool,
}

impl Assembler {
    /// Feeds one character; returns the hex body of a frame that just ended.
    pub(crate) fn push(&mut self, byte: u8) -> Option<Vec<u8>> {
        match byte {
            b':' => {
                self.body.clear();
                self.in_frame = true;
                self.saw_cr = false;
                None
            }
            _ if !self.in_frame => None,
            b'\r' => {
                self.saw_cr = true;
                None
            }
            b'\n' if self.saw_cr => {
                self.in_frame = false;
                Some(std::mem::take(&mut self.body))
            }
            _ if self.saw_cr || self.body.len() >= MAX_FRAME_CHARS => {
                self.reset();
                None
            }
            _ => {
                self.body.push(byte);
                None
            }
        }
    }

    /// A character arrived with a parity or framing error: the frame in progress is void.
    pub(crate) fn reset(&mut self) {
        self.body.clear();
        self.in_frame = false;
        self.saw_cr = false;
    }
}

fn hex_value(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'A'..=b'F' => Some(c - b'A' + 10),
        b'a'..=b'f' => Some(c - b'a' + 10),
        _ => None,
    }
}

/// LRC of Modbus ASCII: two's complement of the byte sum.
pub(crate) fn lrc(bytes: &[u8]) -> u8 {
    bytes
        .iter()
        .fold(0u8, |acc, &b| acc.wrapping_add(b))
        .wrapping_neg()
}

/// Hex body -> (address, PDU), if the characters are hex pairs and the LRC is right.
pub(crate) fn decode(body: &[u8]) -> Option<(u8, Vec<u8>)> {
    if !body.len().is_multiple_of(2) || body.len() < 6 {
        return None;
    }
    let bytes: Option<Vec<u8>> = body
        .chunks(2)
        .map(|p| Some(hex_value(p[0])? << 4 | hex_value(p[1])?))
        .collect();
    let bytes = bytes?;
    let (frame, check) = bytes.split_at(bytes.len() - 1);
    if lrc(frame) != check[0] {
        return None;
    }
    Some((frame[0], frame[1..].to_vec()))
}

/// (address, PDU) -> the characters of a frame, `:` to CR LF.
pub(crate) fn encode(address: u8, pdu: &[u8]) -> Vec<u8> {
    let mut frame = Vec::with_capacity(pdu.len() + 2);
    frame.push(address);
    frame.extend_from_slice(pdu);
    frame.push(lrc(&frame));
    let mut out = Vec::with_capacity(frame.len() * 2 + 3);
    out.push(b':');
    for b in frame {
        out.extend_from_slice(format!("{b:02X}").as_bytes());
    }
    out.extend_from_slice(b"\r\n");
    out
}

/// Why a PDU is not a request the unit can act on, as the exception it answers with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Refused {
    pub function: u8,
    pub code: ExceptionCode,
}

fn be(pdu: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes([*pdu.get(at)?, *pdu.get(at + 1)?]))
}

/// PDU -> typed request.
pub(crate) fn parse_request(pdu: &[u8]) -> Result<Request<'_>, Refused> {
    let function = *pdu.first().ok_or(Refused {
        function: 0,
        code: ExceptionCode::IllegalFunction,
    })?;
    let bad_value = Refused {
        function,
        code: ExceptionCode::IllegalDataValue,
    };
    let pair = || -> Result<(u16, u16), Refused> {
        if pdu.len() != 5 {
            return Err(bad_value);
        }
        Ok((be(pdu, 1).ok_or(bad_value)?, be(pdu, 3).ok_or(bad_value)?))
    };
    match function {
        0x01 => pair().map(|(start, quantity)| Request::ReadCoils { start, quantity }),
        0x03 => pair().map(|(start, quantity)| Request::ReadHoldingRegisters { start, quantity }),
        0x04 => pair().map(|(start, quantity)| Request::ReadInputRegisters { start, quantity }),
        0x05 => match pair()? {
            (address, 0xFF00) => Ok(Request::WriteSingleCoil { address, on: true }),
            (address, 0x0000) => Ok(Request::WriteSingleCoil { address, on: false }),
            _ => Err(bad_value),
        },
        0x06 => pair().map(|(address, value)| Request::WriteSingleRegister { address, value }),
        0x10 => {
            let start = be(pdu, 1).ok_or(bad_value)?;
            let quantity = be(pdu, 3).ok_or(bad_value)?;
            let count = *pdu.get(5).ok_or(bad_value)? as usize;
            let data = pdu.get(6..).ok_or(bad_value)?;
            if quantity == 0 || count != 2 * quantity as usize || data.len() != count {
                return Err(bad_value);
            }
            Ok(Request::WriteMultipleRegisters {
                start,
                values: Registers::BigEndian(data),
            })
        }
        0x2B => {
            if pdu.get(1) != Some(&0x0E) {
                return Err(Refused {
                    function,
                    code: ExceptionCode::IllegalFunction,
                });
            }
            if pdu.len() != 4 {
                return Err(bad_value);
            }
            let code = match pdu[2] {
                0x01 => DeviceIdCode::Basic,
                0x02 => DeviceIdCode::Regular,
                0x03 => DeviceIdCode::Extended,
                0x04 => DeviceIdCode::Specific,
                _ => return Err(bad_value),
            };
            Ok(Request::ReadDeviceIdentification {
                code,
                object_id: pdu[3],
            })
        }
        _ => Err(Refused {
            function,
            code: ExceptionCode::IllegalFunction,
        }),
    }
}

fn exception_byte(code: ExceptionCode) -> u8 {
    match code {
        ExceptionCode::IllegalFunction => 0x01,
        ExceptionCode::IllegalDataAddress => 0x02,
        ExceptionCode::IllegalDataValue => 0x03,
        ExceptionCode::ServerDeviceFailure => 0x04,
        ExceptionCode::Acknowledge => 0x05,
        ExceptionCode::ServerDeviceBusy => 0x06,
        ExceptionCode::MemoryParityError => 0x08,
        ExceptionCode::GatewayPathUnavailable => 0x0A,
        ExceptionCode::GatewayTargetFailed => 0x0B,
        ExceptionCode::Other(c) => c,
    }
}

/// Typed response -> PDU bytes.
pub(crate) fn emit_response(response: &Response<'_>) -> Vec<u8> {
    let mut out = Vec::new();
    let registers = |out: &mut Vec<u8>, function: u8, values: &Registers<'_>| {
        out.push(function);
        out.push((values.len() * 2) as u8);
        for v in values.iter() {
            out.extend_from_slice(&v.to_be_bytes());
        }
    };
    match response {
        Response::ReadCoils { bits } => {
            out.push(0x01);
            out.push(bits.len() as u8);
            out.extend_from_slice(bits);
        }
        Response::ReadHoldingRegisters { values } => registers(&mut out, 0x03, values),
        Response::ReadInputRegisters { values } => registers(&mut out, 0x04, values),
        Response::WriteSingleCoil { address, on } => {
            out.push(0x05);
            out.extend_from_slice(&address.to_be_bytes());
            out.extend_from_slice(if *on { &[0xFF, 0x00] } else { &[0x00, 0x00] });
        }
        Response::WriteSingleRegister { address, value } => {
            out.push(0x06);
            out.extend_from_slice(&address.to_be_bytes());
            out.extend_from_slice(&value.to_be_bytes());
        }
        Response::WriteMultipleRegisters { start, quantity } => {
            out.push(0x10);
            out.extend_from_slice(&start.to_be_bytes());
            out.extend_from_slice(&quantity.to_be_bytes());
        }
        Response::ReadDeviceIdentification(id) => {
            out.extend_from_slice(&[0x2B, 0x0E, id.code as u8, id.conformity]);
            out.push(if id.more_follows { 0xFF } else { 0x00 });
            out.push(id.next_object_id);
            out.push(id.object_count);
            out.extend_from_slice(id.objects);
        }
        Response::Exception { function, code } => {
            out.push(function | 0x80);
            out.push(exception_byte(*code));
        }
    }
    out
}

/// What a unit answers, owned so a model can build it; [`Reply::response`] borrows it as the
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
            Reply::HoldingRegisters(v) => emit_response(&Response::ReadHoldingRegisters {
                values: Registers::Words(v),
            }),
            Reply::InputRegisters(v) => emit_response(&Response::ReadInputRegisters {
                values: Registers::Words(v),
            }),
            Reply::Coils(bits) => emit_response(&Response::ReadCoils { bits }),
            Reply::WriteSingleCoil { address, on } => emit_response(&Response::WriteSingleCoil {
                address: *address,
                on: *on,
            }),
            Reply::WriteSingleRegister { address, value } => {
                emit_response(&Response::WriteSingleRegister {
                    address: *address,
                    value: *value,
                })
            }
            Reply::WriteMultipleRegisters { start, quantity } => {
                emit_response(&Response::WriteMultipleRegisters {
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
                let mut raw = Vec::new();
                for (id, value) in objects {
                    raw.push(*id);
                    raw.push(value.len() as u8);
                    raw.extend_from_slice(value);
                }
                emit_response(&Response::ReadDeviceIdentification(DeviceIdentification {
                    code: *code,
                    conformity: *conformity,
                    more_follows: false,
                    next_object_id: *next_object_id,
                    object_count: objects.len() as u8,
                    objects: &raw,
                }))
            }
            Reply::Exception { function, code } => emit_response(&Response::Exception {
                function: *function,
                code: *code,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(text: &str) -> Vec<u8> {
        let mut a = Assembler::default();
        let mut out = None;
        for &b in text.as_bytes() {
            if let Some(f) = a.push(b) {
                out = Some(f);
            }
        }
        out.expect("complete frame")
    }

    #[test]
    fn manual_request_decodes_to_a_typed_read() {
        // SYNC guide p. 11: read the 4-entry cartridge fault log.
        let (address, pdu) = decode(&frame(":01043044000483\r\n")).unwrap();
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
        assert_eq!(decode(&frame(":01043044000484\r\n")), None);
    }

    #[test]
    fn a_colon_restarts_the_frame() {
        assert_eq!(frame(":0104:010430000001CA\r\n"), b"010430000001CA");
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
    }

    #[test]
    fn unknown_functions_are_illegal() {
        assert_eq!(
            parse_request(&[0x17, 0, 0, 0, 1]),
            Err(Refused {
                function: 0x17,
                code: ExceptionCode::IllegalFunction
            })
        );
    }
}
