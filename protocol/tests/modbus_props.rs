//! Property tests of the Modbus ASCII layer: round trips, chunking, no panics.

use plasma_protocol::Error;
use plasma_protocol::modbus_ascii::{
    Decoder, DeviceIdCode, DeviceIdentification, ExceptionCode, Frame, MAX_FRAME_CHARS,
    MAX_PDU_LEN, Registers, Request, Response, decode, encode, encode_request, encode_response,
    validate_reply,
};
use proptest::prelude::*;

/// A request with owned data, so a strategy can produce it.
#[derive(Debug, Clone)]
enum OwnedRequest {
    ReadCoils(u16, u16),
    ReadHolding(u16, u16),
    ReadInput(u16, u16),
    WriteCoil(u16, bool),
    WriteRegister(u16, u16),
    WriteRegisters(u16, Vec<u16>),
    DeviceId(DeviceIdCode, u8),
}

impl OwnedRequest {
    fn get(&self) -> Request<'_> {
        match *self {
            OwnedRequest::ReadCoils(start, quantity) => Request::ReadCoils { start, quantity },
            OwnedRequest::ReadHolding(start, quantity) => {
                Request::ReadHoldingRegisters { start, quantity }
            }
            OwnedRequest::ReadInput(start, quantity) => {
                Request::ReadInputRegisters { start, quantity }
            }
            OwnedRequest::WriteCoil(address, on) => Request::WriteSingleCoil { address, on },
            OwnedRequest::WriteRegister(address, value) => {
                Request::WriteSingleRegister { address, value }
            }
            OwnedRequest::WriteRegisters(start, ref values) => Request::WriteMultipleRegisters {
                start,
                values: Registers::Words(values),
            },
            OwnedRequest::DeviceId(code, object_id) => {
                Request::ReadDeviceIdentification { code, object_id }
            }
        }
    }
}

fn device_id_code() -> impl Strategy<Value = DeviceIdCode> {
    prop_oneof![
        Just(DeviceIdCode::Basic),
        Just(DeviceIdCode::Regular),
        Just(DeviceIdCode::Extended),
        Just(DeviceIdCode::Specific),
    ]
}

fn request() -> impl Strategy<Value = OwnedRequest> {
    prop_oneof![
        (any::<u16>(), 1..=2000u16).prop_map(|(s, q)| OwnedRequest::ReadCoils(s, q)),
        (any::<u16>(), 1..=125u16).prop_map(|(s, q)| OwnedRequest::ReadHolding(s, q)),
        (any::<u16>(), 1..=125u16).prop_map(|(s, q)| OwnedRequest::ReadInput(s, q)),
        (any::<u16>(), any::<bool>()).prop_map(|(a, on)| OwnedRequest::WriteCoil(a, on)),
        (any::<u16>(), any::<u16>()).prop_map(|(a, v)| OwnedRequest::WriteRegister(a, v)),
        (any::<u16>(), prop::collection::vec(any::<u16>(), 1..=123))
            .prop_map(|(s, v)| OwnedRequest::WriteRegisters(s, v)),
        (device_id_code(), any::<u8>()).prop_map(|(c, o)| OwnedRequest::DeviceId(c, o)),
    ]
}

/// A reply with owned data.
#[derive(Debug, Clone)]
enum OwnedResponse {
    ReadCoils(Vec<u8>),
    ReadHolding(Vec<u16>),
    ReadInput(Vec<u16>),
    WriteCoil(u16, bool),
    WriteRegister(u16, u16),
    WriteRegisters(u16, u16),
    /// code, conformity, more follows, next object, objects
    DeviceId(DeviceIdCode, u8, bool, u8, Vec<(u8, Vec<u8>)>),
    Exception(u8, u8),
}

impl OwnedResponse {
    /// The binary PDU, through the typed emitters.
    fn emit(&self, out: &mut [u8]) -> usize {
        let typed = match *self {
            OwnedResponse::ReadCoils(ref bits) => Response::ReadCoils { bits },
            OwnedResponse::ReadHolding(ref v) => Response::ReadHoldingRegisters {
                values: Registers::Words(v),
            },
            OwnedResponse::ReadInput(ref v) => Response::ReadInputRegisters {
                values: Registers::Words(v),
            },
            OwnedResponse::WriteCoil(address, on) => Response::WriteSingleCoil { address, on },
            OwnedResponse::WriteRegister(address, value) => {
                Response::WriteSingleRegister { address, value }
            }
            OwnedResponse::WriteRegisters(start, quantity) => {
                Response::WriteMultipleRegisters { start, quantity }
            }
            OwnedResponse::Exception(function, code) => Response::Exception {
                function,
                code: ExceptionCode::from_u8(code),
            },
            OwnedResponse::DeviceId(code, conformity, more, next, ref objects) => {
                let list: Vec<(u8, &[u8])> =
                    objects.iter().map(|(id, v)| (*id, v.as_slice())).collect();
                return DeviceIdentification::emit_objects(
                    code, conformity, more, next, &list, out,
                )
                .unwrap();
            }
        };
        typed.emit(out).unwrap()
    }

    /// Checks a parsed reply against this one, field by field.
    fn check(&self, parsed: &Response<'_>) {
        match (self, parsed) {
            (OwnedResponse::ReadCoils(bits), Response::ReadCoils { bits: got }) => {
                assert_eq!(bits.as_slice(), *got)
            }
            (OwnedResponse::ReadHolding(v), Response::ReadHoldingRegisters { values })
            | (OwnedResponse::ReadInput(v), Response::ReadInputRegisters { values }) => {
                assert!(values.iter().eq(v.iter().copied()))
            }
            (OwnedResponse::WriteCoil(a, on), &Response::WriteSingleCoil { address, on: o }) => {
                assert_eq!((*a, *on), (address, o))
            }
            (
                OwnedResponse::WriteRegister(a, v),
                &Response::WriteSingleRegister { address, value },
            ) => assert_eq!((*a, *v), (address, value)),
            (
                OwnedResponse::WriteRegisters(s, q),
                &Response::WriteMultipleRegisters { start, quantity },
            ) => assert_eq!((*s, *q), (start, quantity)),
            (OwnedResponse::Exception(f, c), &Response::Exception { function, code }) => {
                assert_eq!((*f, *c), (function, code.to_u8()))
            }
            (
                OwnedResponse::DeviceId(code, conformity, more, next, objects),
                Response::ReadDeviceIdentification(id),
            ) => {
                assert_eq!(id.code, *code);
                assert_eq!(id.conformity, *conformity);
                assert_eq!(id.more_follows, *more);
                assert_eq!(id.next_object_id, *next);
                assert_eq!(usize::from(id.object_count), objects.len());
                assert!(
                    id.objects()
                        .eq(objects.iter().map(|(i, v)| (*i, v.as_slice())))
                );
            }
            (want, got) => panic!("expected {want:?}, parsed {got:?}"),
        }
    }
}

fn device_objects() -> impl Strategy<Value = Vec<(u8, Vec<u8>)>> {
    // Keep the PDU within 253 bytes: 7 header bytes + 2 per object + values.
    prop::collection::vec(
        (any::<u8>(), prop::collection::vec(any::<u8>(), 0..40)),
        0..6,
    )
    .prop_filter("PDU too long", |objects| {
        7 + objects.iter().map(|(_, v)| 2 + v.len()).sum::<usize>() <= MAX_PDU_LEN
    })
}

fn response() -> impl Strategy<Value = OwnedResponse> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 1..=250).prop_map(OwnedResponse::ReadCoils),
        prop::collection::vec(any::<u16>(), 1..=125).prop_map(OwnedResponse::ReadHolding),
        prop::collection::vec(any::<u16>(), 1..=125).prop_map(OwnedResponse::ReadInput),
        (any::<u16>(), any::<bool>()).prop_map(|(a, on)| OwnedResponse::WriteCoil(a, on)),
        (any::<u16>(), any::<u16>()).prop_map(|(a, v)| OwnedResponse::WriteRegister(a, v)),
        (any::<u16>(), 1..=123u16).prop_map(|(s, q)| OwnedResponse::WriteRegisters(s, q)),
        (
            device_id_code(),
            any::<u8>(),
            any::<bool>(),
            any::<u8>(),
            device_objects()
        )
            .prop_map(|(c, f, m, n, o)| OwnedResponse::DeviceId(c, f, m, n, o)),
        (0..0x80u8, any::<u8>()).prop_map(|(f, c)| OwnedResponse::Exception(f, c)),
    ]
}

/// The reply a well-behaved unit gives to `request`.
fn correct_reply(request: &OwnedRequest) -> OwnedResponse {
    match *request {
        OwnedRequest::ReadCoils(_, q) => {
            OwnedResponse::ReadCoils(vec![0xA5; usize::from(q).div_ceil(8)])
        }
        OwnedRequest::ReadHolding(s, q) => {
            OwnedResponse::ReadHolding((0..q).map(|i| s.wrapping_add(i)).collect())
        }
        OwnedRequest::ReadInput(s, q) => OwnedResponse::ReadInput((0..q).map(|i| s ^ i).collect()),
        OwnedRequest::WriteCoil(a, on) => OwnedResponse::WriteCoil(a, on),
        OwnedRequest::WriteRegister(a, v) => OwnedResponse::WriteRegister(a, v),
        OwnedRequest::WriteRegisters(s, ref v) => OwnedResponse::WriteRegisters(s, v.len() as u16),
        OwnedRequest::DeviceId(code, object_id) => {
            OwnedResponse::DeviceId(code, 0x81, false, 0, vec![(object_id, b"081335".to_vec())])
        }
    }
}

type Outcome = (usize, Result<(u8, Vec<u8>), Error>);

/// Every result of `input`, with the offset of the byte that produced it, one byte at a time.
fn byte_by_byte(input: &[u8]) -> Vec<Outcome> {
    let mut decoder = Decoder::new();
    let mut out = Vec::new();
    for (i, &b) in input.iter().enumerate() {
        if let Some(r) = decoder.push(b) {
            out.push((i, r.map(|f| (f.address, f.pdu.to_vec()))));
        }
    }
    out
}

/// The same with `feed`, cutting `input` at `cuts` (sorted offsets).
fn chunked(input: &[u8], cuts: &[usize]) -> Vec<Outcome> {
    let mut decoder = Decoder::new();
    let mut out = Vec::new();
    let mut start = 0;
    for &end in cuts.iter().chain(core::iter::once(&input.len())) {
        let end = end.clamp(start, input.len());
        let mut pos = start;
        while pos < end {
            let (used, r) = decoder.feed(&input[pos..end]);
            assert!(used >= 1 && used <= end - pos);
            pos += used;
            if let Some(r) = r {
                out.push((pos - 1, r.map(|f| (f.address, f.pdu.to_vec()))));
            } else {
                assert_eq!(pos, end);
            }
        }
        start = end;
    }
    out
}

/// Streams that look like a serial line: valid frames, damaged frames, noise.
fn line_traffic() -> impl Strategy<Value = Vec<u8>> {
    let piece = prop_oneof![
        (any::<u8>(), response()).prop_map(|(address, r)| {
            let mut pdu = [0u8; MAX_PDU_LEN];
            let n = r.emit(&mut pdu);
            let mut text = vec![0u8; MAX_FRAME_CHARS];
            let m = encode(address, &pdu[..n], &mut text).unwrap();
            text.truncate(m);
            text
        }),
        prop::collection::vec(
            prop::sample::select(b"0123456789ABCDEFabcdef::\r\n\r\nxG \x00\xff".to_vec()),
            0..40
        ),
        prop::collection::vec(any::<u8>(), 0..20),
    ];
    prop::collection::vec(piece, 0..8).prop_map(|pieces| pieces.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn request_round_trip(address in any::<u8>(), owned in request()) {
        let request = owned.get();
        let mut text = [0u8; MAX_FRAME_CHARS];
        let n = encode_request(address, &request, &mut text).unwrap();
        prop_assert_eq!(text[0], b':');
        prop_assert_eq!(&text[n - 2..n], b"\r\n");
        prop_assert!(text[1..n - 2].iter().all(|c| c.is_ascii_digit() || c.is_ascii_uppercase()));

        let mut decoder = Decoder::new();
        let (used, result) = decoder.feed(&text[..n]);
        prop_assert_eq!(used, n);
        let frame = result.unwrap().unwrap();
        prop_assert_eq!(frame.address, address);
        prop_assert_eq!(Request::parse(frame.pdu), Ok(request));

        // Lower case decodes to the same frame.
        let lower = text[..n].to_ascii_lowercase();
        let mut buf = [0u8; MAX_PDU_LEN];
        prop_assert_eq!(decode(&lower, &mut buf).map(|f| f.request()), Ok(Ok(request)));
    }

    #[test]
    fn response_round_trip(address in any::<u8>(), owned in response()) {
        let mut pdu = [0u8; MAX_PDU_LEN];
        let n = owned.emit(&mut pdu);
        let parsed = Response::parse(&pdu[..n]).unwrap();
        owned.check(&parsed);

        let mut text = [0u8; MAX_FRAME_CHARS];
        let m = encode_response(address, &parsed, &mut text).unwrap();
        let mut decoder = Decoder::new();
        let (used, result) = decoder.feed(&text[..m]);
        prop_assert_eq!(used, m);
        let frame = result.unwrap().unwrap();
        prop_assert_eq!(frame.address, address);
        prop_assert_eq!(frame.pdu, &pdu[..n]);
        owned.check(&Response::parse(frame.pdu).unwrap());
    }

    #[test]
    fn correct_replies_validate(address in 1..=255u8, owned in request()) {
        let request = owned.get();
        let reply = correct_reply(&owned);
        let mut pdu = [0u8; MAX_PDU_LEN];
        let n = reply.emit(&mut pdu);
        let frame = Frame { address, pdu: &pdu[..n] };
        let response = validate_reply(&request, address, &frame).unwrap();
        reply.check(&response);
        // From another unit, or as a reply to a broadcast: refused.
        let other = Frame { address: address.wrapping_add(1), pdu: &pdu[..n] };
        prop_assert_eq!(validate_reply(&request, address, &other), Err(Error::Mismatch));
        prop_assert_eq!(validate_reply(&request, 0, &frame), Err(Error::Mismatch));
        // The exception form of the same function answers it too.
        let exception = [request.function().to_u8() | 0x80, 0x02];
        let frame = Frame { address, pdu: &exception };
        let refused = validate_reply(&request, address, &frame);
        let expected = Response::Exception {
            function: request.function().to_u8(),
            code: ExceptionCode::IllegalDataAddress,
        };
        prop_assert_eq!(refused, Ok(expected));
    }

    #[test]
    fn decoder_never_panics(input in prop::collection::vec(any::<u8>(), 0..1200)) {
        let mut decoder = Decoder::new();
        let mut rest = &input[..];
        while !rest.is_empty() {
            let (used, result) = decoder.feed(rest);
            if let Some(Ok(frame)) = result {
                let _ = Response::parse(frame.pdu);
                let _ = Request::parse(frame.pdu);
            }
            rest = &rest[used..];
        }
        let mut buf = [0u8; MAX_PDU_LEN];
        let _ = decode(&input, &mut buf);
    }

    #[test]
    fn chunking_never_changes_results(
        input in line_traffic(),
        mut cuts in prop::collection::vec(any::<prop::sample::Index>(), 0..12),
    ) {
        let mut cuts: Vec<usize> = cuts.drain(..).map(|i| i.index(input.len() + 1)).collect();
        cuts.sort_unstable();
        prop_assert_eq!(byte_by_byte(&input), chunked(&input, &cuts));
    }

    #[test]
    fn one_shot_decode_agrees_with_the_decoder(input in line_traffic()) {
        // For input that starts with ':' and whose first result ends the input.
        let Some(start) = input.iter().position(|&c| c == b':') else { return Ok(()); };
        let input = &input[start..];
        let all = byte_by_byte(input);
        if let Some((at, first)) = all.first() {
            let mut buf = [0u8; MAX_PDU_LEN];
            let one = decode(&input[..=*at], &mut buf).map(|f| (f.address, f.pdu.to_vec()));
            prop_assert_eq!(&one, first);
        }
    }

    #[test]
    fn validate_never_panics(
        owned in request(),
        request_address in any::<u8>(),
        address in any::<u8>(),
        pdu in prop::collection::vec(any::<u8>(), 1..=MAX_PDU_LEN),
        function in prop::sample::select(vec![0x01u8, 0x03, 0x04, 0x05, 0x06, 0x10, 0x2B, 0x84]),
    ) {
        let request = owned.get();
        let frame = Frame { address, pdu: &pdu };
        let _ = validate_reply(&request, request_address, &frame);
        // With a plausible function byte, so the parsers go deeper than "unsupported".
        let mut pdu = pdu.clone();
        pdu[0] = function;
        if function == 0x2B && pdu.len() > 1 {
            pdu[1] = 0x0E;
        }
        let frame = Frame { address, pdu: &pdu };
        let _ = validate_reply(&request, request_address, &frame);
    }
}
