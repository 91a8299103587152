//! Decoding and validating the manuals' Modbus reply frames: this crate against rmodbus.
//!
//! Both sides do the same work per frame: hex to binary, LRC check, address and function
//! check against the request, and copying register values out into a fixed vector.
//! `cargo bench -p plasma-protocol --bench modbus_decode -- --quick`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use plasma_protocol::modbus_ascii::{
    Decoder, DeviceIdCode, Registers, Request, Response, validate_reply,
};
use rmodbus::ModbusProto;
use rmodbus::client::ModbusRequest;

/// A reply frame of the manuals with the request it answers.
struct Case {
    name: &'static str,
    reply: &'static [u8],
    request: Request<'static>,
}

const CASES: [Case; 5] = [
    Case {
        // SYNC guide, fault log (OCR corrected: one `0` removed, see src/modbus_ascii/tests.rs).
        name: "fault_log_4_regs",
        reply: b":010408007900790000000001\r\n",
        request: Request::ReadInputRegisters {
            start: 0x3044,
            quantity: 4,
        },
    },
    Case {
        name: "settings_3_regs",
        reply: b":01040600011A40260074\r\n",
        request: Request::ReadInputRegisters {
            start: 0x3010,
            quantity: 3,
        },
    },
    Case {
        name: "counters_8_regs",
        reply: b":010410D1B6000010EB0000D0750000D5AE00069B\r\n",
        request: Request::ReadInputRegisters {
            start: 0x3028,
            quantity: 8,
        },
    },
    Case {
        name: "remote_mode_write_echo",
        reply: b":0110308000033C\r\n",
        request: Request::WriteMultipleRegisters {
            start: 0x3080,
            values: Registers::Words(&[1, 0x0FC0, 0]),
        },
    },
    Case {
        name: "device_id",
        reply: b":012B0E0481000101010630383133333504\r\n",
        request: Request::ReadDeviceIdentification {
            code: DeviceIdCode::Specific,
            object_id: 1,
        },
    },
];

type Words = heapless::Vec<u16, 125>;

/// This crate: stream decoder, reply validation, values copied out.
fn plasma(decoder: &mut Decoder, case: &Case, out: &mut Words) -> usize {
    out.clear();
    let (_, result) = decoder.feed(black_box(case.reply));
    let frame = result.expect("frame ends").expect("frame valid");
    match validate_reply(&case.request, 0x01, &frame).expect("reply matches") {
        Response::ReadInputRegisters { values } | Response::ReadHoldingRegisters { values } => {
            for v in values.iter() {
                let _ = out.push(v);
            }
            out.len()
        }
        Response::ReadDeviceIdentification(id) => id.object(0x01).map_or(0, <[u8]>::len),
        _ => 1,
    }
}

/// The rmodbus request matching `case`, or `None` where rmodbus lacks the function.
fn rmodbus_request(case: &Case) -> Option<ModbusRequest> {
    let mut request = ModbusRequest::new(0x01, ModbusProto::Ascii);
    let mut frame: heapless::Vec<u8, 256> = heapless::Vec::new();
    match case.request {
        Request::ReadInputRegisters { start, quantity } => request
            .generate_get_inputs(start, quantity, &mut frame)
            .ok()?,
        Request::WriteMultipleRegisters { start, values } => {
            let words: Words = values.iter().collect();
            request
                .generate_set_holdings_bulk(start, &words, &mut frame)
                .ok()?
        }
        // rmodbus has no Read Device Identification (0x2B/0x0E).
        _ => return None,
    }
    Some(request)
}

/// rmodbus: ASCII to binary into a frame buffer, then its response parser.
fn rmodbus(request: &ModbusRequest, case: &Case, buf: &mut [u8; 256], out: &mut Words) -> usize {
    out.clear();
    let reply = black_box(case.reply);
    let n = rmodbus::parse_ascii_frame(reply, reply.len(), buf, 0).expect("frame valid");
    let frame = &buf[..usize::from(n)];
    if matches!(case.request, Request::WriteMultipleRegisters { .. }) {
        request.parse_ok(frame).expect("reply matches");
        1
    } else {
        request.parse_u16(frame, out).expect("reply matches");
        out.len()
    }
}

fn decode_replies(c: &mut Criterion) {
    for case in &CASES {
        let mut group = c.benchmark_group(case.name);
        let mut decoder = Decoder::new();
        let mut out = Words::new();
        group.bench_function("plasma", |b| {
            b.iter(|| plasma(&mut decoder, case, &mut out))
        });

        if let Some(request) = rmodbus_request(case) {
            let mut buf = [0u8; 256];
            // Same result from both, before timing anything.
            let mut theirs = Words::new();
            let ours = plasma(&mut decoder, case, &mut out);
            assert_eq!(rmodbus(&request, case, &mut buf, &mut theirs), ours);
            assert_eq!(theirs, out);
            group.bench_function("rmodbus", |b| {
                b.iter(|| rmodbus(&request, case, &mut buf, &mut out))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, decode_replies);
criterion_main!(benches);
