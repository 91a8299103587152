//! Matching a received reply to the request it answers.

use super::frame::Frame;
use super::pdu::{Request, Response};
use crate::{Error, Result};

/// Checks that `reply` answers `request` sent to `request_address`, and parses it.
///
/// - The reply's address must be `request_address`, else [`Error::Mismatch`].
/// - Address 0 is a broadcast: units carry it out without answering, so no frame can answer
///   it and this returns [`Error::Mismatch`]. Do not wait for a reply after a broadcast.
/// - The function must be the request's, or its exception form `0x80 | function`, which is
///   returned as `Ok(Response::Exception { .. })`: the unit answered, and refused.
/// - Reads: the data must hold exactly the requested quantity (2 bytes per register,
///   `ceil(quantity / 8)` bytes of coils).
/// - Writes: the echo must repeat the request's address and value, or start and quantity.
/// - Read Device Identification: the reply's access code must be the request's.
///
/// A reply that is not a valid PDU at all gives [`Response::parse`]'s error.
pub fn validate_reply<'a>(
    request: &Request<'_>,
    request_address: u8,
    reply: &Frame<'a>,
) -> Result<Response<'a>> {
    if request_address == 0 || reply.address != request_address {
        return Err(Error::Mismatch);
    }
    let response = Response::parse(reply.pdu)?;
    if answers(request, &response) {
        Ok(response)
    } else {
        Err(Error::Mismatch)
    }
}

/// True when `response` is a reply to `request`, by function and contents.
fn answers(request: &Request<'_>, response: &Response<'_>) -> bool {
    match (*request, *response) {
        (_, Response::Exception { function, .. }) => function == request.function().to_u8(),
        (Request::ReadCoils { quantity, .. }, Response::ReadCoils { bits }) => {
            bits.len() == usize::from(quantity).div_ceil(8)
        }
        (
            Request::ReadHoldingRegisters { quantity, .. },
            Response::ReadHoldingRegisters { values },
        )
        | (Request::ReadInputRegisters { quantity, .. }, Response::ReadInputRegisters { values }) => {
            values.len() == usize::from(quantity)
        }
        (
            Request::WriteSingleCoil { address, on },
            Response::WriteSingleCoil {
                address: echo_address,
                on: echo_on,
            },
        ) => address == echo_address && on == echo_on,
        (
            Request::WriteSingleRegister { address, value },
            Response::WriteSingleRegister {
                address: echo_address,
                value: echo_value,
            },
        ) => address == echo_address && value == echo_value,
        (
            Request::WriteMultipleRegisters { start, values },
            Response::WriteMultipleRegisters {
                start: echo_start,
                quantity,
            },
        ) => start == echo_start && values.len() == usize::from(quantity),
        (
            Request::ReadDeviceIdentification { code, .. },
            Response::ReadDeviceIdentification(id),
        ) => id.code == code,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modbus_ascii::{DeviceIdCode, ExceptionCode, Registers};

    const READ_FAULTS: Request<'static> = Request::ReadInputRegisters {
        start: 0x3044,
        quantity: 4,
    };

    fn frame(address: u8, pdu: &[u8]) -> Frame<'_> {
        Frame { address, pdu }
    }

    #[test]
    fn matching_read() {
        let pdu = [0x04, 0x08, 0x00, 0x79, 0x00, 0x79, 0, 0, 0, 0];
        let r = validate_reply(&READ_FAULTS, 1, &frame(1, &pdu)).unwrap();
        let Response::ReadInputRegisters { values } = r else {
            panic!("{r:?}")
        };
        assert!(values.iter().eq([0x79, 0x79, 0, 0]));
    }

    #[test]
    fn address_and_broadcast() {
        let pdu = [0x04, 0x08, 0x00, 0x79, 0x00, 0x79, 0, 0, 0, 0];
        assert_eq!(
            validate_reply(&READ_FAULTS, 2, &frame(1, &pdu)),
            Err(Error::Mismatch)
        );
        assert_eq!(
            validate_reply(&READ_FAULTS, 0, &frame(0, &pdu)),
            Err(Error::Mismatch)
        );
    }

    #[test]
    fn quantity_must_match() {
        let pdu = [0x04, 0x06, 0x00, 0x79, 0x00, 0x79, 0, 0];
        assert_eq!(
            validate_reply(&READ_FAULTS, 1, &frame(1, &pdu)),
            Err(Error::Mismatch)
        );
        let holding = Request::ReadHoldingRegisters {
            start: 0x3044,
            quantity: 4,
        };
        let pdu = [0x04, 0x08, 0x00, 0x79, 0x00, 0x79, 0, 0, 0, 0];
        // Right size, wrong function.
        assert_eq!(
            validate_reply(&holding, 1, &frame(1, &pdu)),
            Err(Error::Mismatch)
        );
    }

    #[test]
    fn coil_byte_count_is_rounded_up() {
        for (quantity, bytes) in [
            (1u16, 1usize),
            (8, 1),
            (9, 2),
            (16, 2),
            (17, 3),
            (2000, 250),
        ] {
            let request = Request::ReadCoils {
                start: 0x3100,
                quantity,
            };
            let mut pdu = [0u8; 252];
            pdu[0] = 0x01;
            pdu[1] = bytes as u8;
            assert!(validate_reply(&request, 1, &frame(1, &pdu[..2 + bytes])).is_ok());
            let wrong = if bytes < 250 { bytes + 1 } else { bytes - 1 };
            pdu[1] = wrong as u8;
            assert_eq!(
                validate_reply(&request, 1, &frame(1, &pdu[..2 + wrong])),
                Err(Error::Mismatch)
            );
        }
    }

    #[test]
    fn exceptions_are_ok_when_they_answer() {
        let pdu = [0x84, 0x02];
        assert_eq!(
            validate_reply(&READ_FAULTS, 1, &frame(1, &pdu)),
            Ok(Response::Exception {
                function: 0x04,
                code: ExceptionCode::IllegalDataAddress
            })
        );
        let pdu = [0x83, 0x02];
        assert_eq!(
            validate_reply(&READ_FAULTS, 1, &frame(1, &pdu)),
            Err(Error::Mismatch)
        );
    }

    #[test]
    fn write_echoes() {
        let coil = Request::WriteSingleCoil {
            address: 0x3180,
            on: true,
        };
        assert!(validate_reply(&coil, 1, &frame(1, &[0x05, 0x31, 0x80, 0xFF, 0x00])).is_ok());
        let off = frame(1, &[0x05, 0x31, 0x80, 0x00, 0x00]);
        assert_eq!(validate_reply(&coil, 1, &off), Err(Error::Mismatch));
        let other = frame(1, &[0x05, 0x31, 0x81, 0xFF, 0x00]);
        assert_eq!(validate_reply(&coil, 1, &other), Err(Error::Mismatch));

        let reg = Request::WriteSingleRegister {
            address: 0x2094,
            value: 0x1040,
        };
        assert!(validate_reply(&reg, 1, &frame(1, &[0x06, 0x20, 0x94, 0x10, 0x40])).is_ok());
        let wrong_value = frame(1, &[0x06, 0x20, 0x94, 0x10, 0x41]);
        assert_eq!(validate_reply(&reg, 1, &wrong_value), Err(Error::Mismatch));
        let wrong_address = frame(1, &[0x06, 0x20, 0x95, 0x10, 0x40]);
        assert_eq!(
            validate_reply(&reg, 1, &wrong_address),
            Err(Error::Mismatch)
        );

        let multi = Request::WriteMultipleRegisters {
            start: 0x3080,
            values: Registers::Words(&[1, 0x0FC0, 0]),
        };
        assert!(validate_reply(&multi, 1, &frame(1, &[0x10, 0x30, 0x80, 0x00, 0x03])).is_ok());
        let short = frame(1, &[0x10, 0x30, 0x80, 0x00, 0x02]);
        assert_eq!(validate_reply(&multi, 1, &short), Err(Error::Mismatch));
        let moved = frame(1, &[0x10, 0x30, 0x81, 0x00, 0x03]);
        assert_eq!(validate_reply(&multi, 1, &moved), Err(Error::Mismatch));
    }

    #[test]
    fn device_id_code() {
        let request = Request::ReadDeviceIdentification {
            code: DeviceIdCode::Specific,
            object_id: 1,
        };
        let pdu = [0x2B, 0x0E, 0x04, 0x81, 0x00, 0x01, 0x01, 0x01, 0x01, b'0'];
        assert!(validate_reply(&request, 1, &frame(1, &pdu)).is_ok());
        let basic = Request::ReadDeviceIdentification {
            code: DeviceIdCode::Basic,
            object_id: 0,
        };
        assert_eq!(
            validate_reply(&basic, 1, &frame(1, &pdu)),
            Err(Error::Mismatch)
        );
    }

    #[test]
    fn invalid_pdus_keep_their_error() {
        assert_eq!(
            validate_reply(&READ_FAULTS, 1, &frame(1, &[0x04, 0x08])),
            Err(Error::Truncated)
        );
        assert_eq!(
            validate_reply(&READ_FAULTS, 1, &frame(1, &[0x07])),
            Err(Error::Unsupported)
        );
    }
}
