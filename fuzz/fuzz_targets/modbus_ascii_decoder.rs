//! Arbitrary bytes into the Modbus ASCII decoder; every frame it yields is parsed and matched
//! against a few fixed requests, and re-encoded. Nothing may panic, and a decoded frame must
//! survive an encode/decode round trip unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use plasma_protocol::modbus_ascii::{
    Decoder, DeviceIdCode, MAX_FRAME_CHARS, Registers, Request, Response, decode, encode_response,
    validate_reply,
};

/// Requests the bridge really sends (SYNC guide examples).
const REQUESTS: [Request<'static>; 6] = [
    Request::ReadInputRegisters {
        start: 0x3044,
        quantity: 4,
    },
    Request::ReadCoils {
        start: 0x3100,
        quantity: 2,
    },
    Request::WriteSingleCoil {
        address: 0x3180,
        on: true,
    },
    Request::WriteSingleRegister {
        address: 0x2094,
        value: 0x1040,
    },
    Request::WriteMultipleRegisters {
        start: 0x3080,
        values: Registers::Words(&[1, 0x0FC0, 0]),
    },
    Request::ReadDeviceIdentification {
        code: DeviceIdCode::Specific,
        object_id: 0x01,
    },
];

fuzz_target!(|data: &[u8]| {
    let mut decoder = Decoder::new();
    let mut rest = data;
    while !rest.is_empty() {
        let (used, result) = decoder.feed(rest);
        assert!(used >= 1 && used <= rest.len());
        rest = &rest[used..];
        let Some(Ok(frame)) = result else { continue };

        let _ = frame.request();
        for request in &REQUESTS {
            if let Ok(response) = validate_reply(request, frame.address, &frame) {
                check_round_trip(frame.address, &response);
            }
        }
        if let Ok(response) = Response::parse(frame.pdu) {
            check_round_trip(frame.address, &response);
        }
    }
    let mut buf = [0u8; 256];
    let _ = decode(data, &mut buf);
});

/// A reply that parsed must encode and decode back to the same reply.
fn check_round_trip(address: u8, response: &Response<'_>) {
    let mut text = [0u8; MAX_FRAME_CHARS];
    let n = encode_response(address, response, &mut text).expect("parsed reply must encode");
    let mut buf = [0u8; 256];
    let frame = decode(&text[..n], &mut buf).expect("encoded reply must decode");
    assert_eq!(frame.address, address);
    assert_eq!(Response::parse(frame.pdu).as_ref(), Ok(response));
}
