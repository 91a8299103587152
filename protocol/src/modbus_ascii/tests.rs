//! Every Modbus example frame of the two Powermax serial-protocol manuals, decoded field by
//! field and rebuilt byte for byte from typed values.
//!
//! - SYNC: 000_dd931256418ae627.txt, Powermax45/65/85/105 SYNC Serial Communication
//!   Programmer Reference Guide (line numbers below refer to it).
//! - Legacy: 001_0bf4bbd6620a48c8.txt, Powermax65/85 Serial Communication Protocol (807220).
//!
//! The manuals are OCR'd. Each frame's LRC is recomputed here (`lrc_of_seed`) rather than
//! trusted. Four printed frames are damaged; each is tested twice: as printed (rejected) and
//! corrected (accepted), with the correction explained next to it.

use super::*;
use crate::Error;
use crate::errata;

type Bytes = heapless::Vec<u8, 600>;

/// The frame as sent on the wire: the manual's characters followed by CR LF.
fn wire(seed: &str) -> Bytes {
    let mut v = Bytes::from_slice(seed.as_bytes()).unwrap();
    v.extend_from_slice(b"\r\n").unwrap();
    v
}

/// Recomputes the LRC of a printed frame from its hex digits, independently of the decoder,
/// and checks it against the frame's last byte.
fn lrc_of_seed(seed: &str) {
    let digits = seed.strip_prefix(':').unwrap();
    assert_eq!(digits.len() % 2, 0, "{seed}: odd number of digits");
    let mut bytes = heapless::Vec::<u8, 256>::new();
    for i in (0..digits.len()).step_by(2) {
        bytes
            .push(u8::from_str_radix(&digits[i..i + 2], 16).unwrap())
            .unwrap();
    }
    let (&found, body) = bytes.split_last().unwrap();
    let sum = body.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    assert_eq!(
        sum.wrapping_add(found),
        0,
        "{seed}: LRC {found:02X} does not match"
    );
    assert_eq!(lrc(body), found, "{seed}");
}

/// Decodes `text` with a streaming decoder that must use all of it and yield one frame.
fn decode_whole<'d>(decoder: &'d mut Decoder, text: &[u8]) -> Frame<'d> {
    let (used, result) = decoder.feed(text);
    assert_eq!(used, text.len());
    result.expect("frame not ended").expect("frame rejected")
}

/// A request frame of a manual: LRC, every field, and the same characters from typed values.
fn seed_request(seed: &str, address: u8, expected: Request<'_>) {
    lrc_of_seed(seed);
    let text = wire(seed);
    let mut decoder = Decoder::new();
    let frame = decode_whole(&mut decoder, &text);
    assert_eq!(frame.address, address, "{seed}");
    assert_eq!(frame.request(), Ok(expected), "{seed}");

    let mut out = [0u8; MAX_FRAME_CHARS];
    let n = encode_request(address, &expected, &mut out).unwrap();
    assert_eq!(&out[..n], &text[..], "{seed}");
}

/// A reply frame of a manual: LRC, every field, matched to `request`, and rebuilt.
fn seed_reply(seed: &str, address: u8, request: &Request<'_>, expected: Response<'_>) {
    lrc_of_seed(seed);
    let text = wire(seed);
    let mut decoder = Decoder::new();
    let frame = decode_whole(&mut decoder, &text);
    assert_eq!(frame.address, address, "{seed}");
    assert_eq!(
        validate_reply(request, address, &frame),
        Ok(expected),
        "{seed}"
    );

    let mut out = [0u8; MAX_FRAME_CHARS];
    let n = encode_response(address, &expected, &mut out).unwrap();
    assert_eq!(&out[..n], &text[..], "{seed}");
}

/// A damaged frame as printed: the decoder must refuse it.
fn rejected_as_printed(seed: &str, error: Error) {
    let text = wire(seed);
    let mut decoder = Decoder::new();
    let (used, result) = decoder.feed(&text);
    assert_eq!((used, result), (text.len(), Some(Err(error))), "{seed}");
}

fn read_input(start: u16, quantity: u16) -> Request<'static> {
    Request::ReadInputRegisters { start, quantity }
}

fn input_values(words: &[u16]) -> Response<'_> {
    Response::ReadInputRegisters {
        values: Registers::Words(words),
    }
}

// ---------------------------------------------------------------------------------------------
// SYNC programmer's guide (000)
// ---------------------------------------------------------------------------------------------

/// Line 336 (LRC worked example, "the LRC is 83") and line 1574: the four newest faults.
#[test]
fn sync_fault_log_request() {
    seed_request(":01043044000483", 0x01, read_input(0x3044, 4));
}

/// Line 1589: the fault log reply, printed `:0104080079007900000000001` (25 digits).
///
/// The table under it lists byte count 08, values 0079 0079 0000 0000 and LRC 01, which is
/// `...0079` + `00000000` + `01`: nine `0`s before the final `1`. The print has ten, one `0`
/// too many. 01+04+08+79+79 = 0xFF, so the LRC 01 confirms the corrected frame (and the
/// byte count 08 its length).
#[test]
fn sync_fault_log_reply() {
    rejected_as_printed(errata::SYNC_FAULT_LOG_REPLY.printed, Error::OddLength);
    seed_reply(
        errata::SYNC_FAULT_LOG_REPLY.meant,
        0x01,
        &read_input(0x3044, 4),
        input_values(&[0x0079, 0x0079, 0x0000, 0x0000]),
    );
}

/// Lines 572 and 587: Read Device Identification, one specific object (01, product code).
#[test]
fn sync_device_identification() {
    let request = Request::ReadDeviceIdentification {
        code: DeviceIdCode::Specific,
        object_id: 0x01,
    };
    seed_request(":012B0E0401C1", 0x01, request);

    let seed = ":012B0E0481000101010630383133333504";
    lrc_of_seed(seed);
    let text = wire(seed);
    let mut decoder = Decoder::new();
    let frame = decode_whole(&mut decoder, &text);
    let Ok(Response::ReadDeviceIdentification(id)) = validate_reply(&request, 0x01, &frame) else {
        panic!("not a device identification reply");
    };
    // 04 81 00 01 01 | 01 06 "081335"
    assert_eq!(id.code, DeviceIdCode::Specific);
    assert_eq!(id.conformity, 0x81);
    assert!(!id.more_follows);
    assert_eq!(id.next_object_id, 0x01);
    assert_eq!(id.object_count, 1);
    let mut objects = id.objects();
    // 303831333335 = "081335" = Powermax65/85/105 SYNC (Table 2).
    assert_eq!(objects.next(), Some((0x01, &b"081335"[..])));
    assert_eq!(objects.next(), None);

    // Rebuilt by a simulator from the object list.
    let mut pdu = [0u8; MAX_PDU_LEN];
    let n = DeviceIdentification::emit_objects(
        DeviceIdCode::Specific,
        0x81,
        false,
        0x01,
        &[(0x01, b"081335")],
        &mut pdu,
    )
    .unwrap();
    let mut out = [0u8; MAX_FRAME_CHARS];
    let m = encode(0x01, &pdu[..n], &mut out).unwrap();
    assert_eq!(&out[..m], &text[..]);
    // And from the parsed value.
    let m = encode_response(0x01, &Response::ReadDeviceIdentification(id), &mut out).unwrap();
    assert_eq!(&out[..m], &text[..]);
}

/// Lines 641 and 655: torch and power supply identification (0x3000): 0x0508.
#[test]
fn sync_torch_and_supply_id() {
    seed_request(":010430000001CA", 0x01, read_input(0x3000, 1));
    seed_reply(
        ":0104020508EC",
        0x01,
        &read_input(0x3000, 1),
        input_values(&[0x0508]),
    );
}

/// Lines 701 and 716: cartridge part number, "428936".
#[test]
fn sync_cartridge_part_number() {
    seed_request(":01043038000390", 0x01, read_input(0x3038, 3));
    seed_reply(
        ":010406343238393336B5",
        0x01,
        &read_input(0x3038, 3),
        input_values(&[0x3432, 0x3839, 0x3336]),
    );
}

/// Lines 761 and 774: permitted settings 0x3001-0x3005.
#[test]
fn sync_permitted_settings() {
    seed_request(":010430010005C5", 0x01, read_input(0x3001, 5));
    seed_reply(
        ":01040A020107800B401D002700D8",
        0x01,
        &read_input(0x3001, 5),
        input_values(&[0x0201, 0x0780, 0x0B40, 0x1D00, 0x2700]),
    );
}

/// Lines 833 and 851: enter remote mode, cut at 63 A (0x0FC0), automatic pressure.
#[test]
fn sync_remote_mode_63_amps() {
    let request = Request::WriteMultipleRegisters {
        start: 0x3080,
        values: Registers::Words(&[1, 0x0FC0, 0]),
    };
    seed_request(":0110308000030600010FC0000066", 0x01, request);
    seed_reply(
        ":0110308000033C",
        0x01,
        &request,
        Response::WriteMultipleRegisters {
            start: 0x3080,
            quantity: 3,
        },
    );
}

/// Lines 900 and 915: active fault 0x01F4 = 500 = 0-50-0.
#[test]
fn sync_active_fault() {
    seed_request(":0104301A0001B0", 0x01, read_input(0x301A, 1));
    seed_reply(
        ":01040201F404",
        0x01,
        &read_input(0x301A, 1),
        input_values(&[0x01F4]),
    );
}

/// Lines 1038-1077: gas test coil 0x3180 on and off; the replies echo the requests.
#[test]
fn sync_gas_test_coil() {
    for (seed, on) in [(":01053180FF004A", true), (":01053180000049", false)] {
        let request = Request::WriteSingleCoil {
            address: 0x3180,
            on,
        };
        seed_request(seed, 0x01, request);
        seed_reply(
            seed,
            0x01,
            &request,
            Response::WriteSingleCoil {
                address: 0x3180,
                on,
            },
        );
    }
}

/// Lines 1114 and 1130: special quick restart (0x0404, 0x0618 to 0x308E).
#[test]
fn sync_quick_restart() {
    let request = Request::WriteMultipleRegisters {
        start: 0x308E,
        values: Registers::Words(&[0x0404, 0x0618]),
    };
    seed_request(":0110308E0002040404061805", 0x01, request);
    seed_reply(
        ":0110308E00022F",
        0x01,
        &request,
        Response::WriteMultipleRegisters {
            start: 0x308E,
            quantity: 2,
        },
    );
}

/// Lines 1154 and 1173: exit remote mode, printed `:01103080000306000000000000036` (29 digits).
///
/// The table under it lists byte count 06, three values 0000 and LRC 36; the print has
/// thirteen zeros where the six data bytes need twelve. 01+10+30+80+00+03+06 = 0xCA, LRC
/// 0x36 confirms the corrected frame.
#[test]
fn sync_exit_remote_mode() {
    rejected_as_printed(errata::SYNC_EXIT_REMOTE_MODE.printed, Error::OddLength);
    let request = Request::WriteMultipleRegisters {
        start: 0x3080,
        values: Registers::Words(&[0, 0, 0]),
    };
    seed_request(errata::SYNC_EXIT_REMOTE_MODE.meant, 0x01, request);
    seed_reply(
        ":0110308000033C",
        0x01,
        &request,
        Response::WriteMultipleRegisters {
            start: 0x3080,
            quantity: 3,
        },
    );
}

/// Lines 1235 and 1250: settings 0x3010-0x3012: cut, 105 A, 76 psi.
#[test]
fn sync_settings() {
    seed_request(":010430100003B8", 0x01, read_input(0x3010, 3));
    seed_reply(
        ":01040600011A40260074",
        0x01,
        &read_input(0x3010, 3),
        input_values(&[0x0001, 0x1A40, 0x2600]),
    );
}

/// Lines 1290 and 1304: actual output 65 A, 72 psi.
#[test]
fn sync_actual_output() {
    seed_request(":010430180002B1", 0x01, read_input(0x3018, 2));
    seed_reply(
        ":010404104023DDA7",
        0x01,
        &read_input(0x3018, 2),
        input_values(&[0x1040, 0x23DD]),
    );
}

/// Lines 1389 and 1402: supply cut counters, 32-bit low word first.
#[test]
fn sync_supply_counters() {
    seed_request(":0104302800089B", 0x01, read_input(0x3028, 8));
    seed_reply(
        ":010410D1B6000010EB0000D0750000D5AE00069B",
        0x01,
        &read_input(0x3028, 8),
        input_values(&[
            0xD1B6, 0x0000, 0x10EB, 0x0000, 0xD075, 0x0000, 0xD5AE, 0x0006,
        ]),
    );
}

/// Lines 1440 and 1453: cartridge UID "E00401D0036FB25D".
#[test]
fn sync_cartridge_uid() {
    seed_request(":01043030000893", 0x01, read_input(0x3030, 8));
    let words: [u16; 8] = core::array::from_fn(|i| {
        let uid = b"E00401D0036FB25D";
        u16::from_be_bytes([uid[2 * i], uid[2 * i + 1]])
    });
    seed_reply(
        ":0104104530303430314430303336464232354471",
        0x01,
        &read_input(0x3030, 8),
        input_values(&words),
    );
}

/// Lines 1505 and 1518: cartridge counters.
#[test]
fn sync_cartridge_counters() {
    seed_request(":01043040000487", 0x01, read_input(0x3040, 4));
    seed_reply(
        ":01040800D6000900D3098FA9",
        0x01,
        &read_input(0x3040, 4),
        input_values(&[0x00D6, 0x0009, 0x00D3, 0x098F]),
    );
}

/// Lines 1647 and 1662: cartridge name, printed `:01040C43204D45434800000000000006F`
/// (33 digits).
///
/// The table under it lists byte count 0C, the 12 bytes `43204D454348000000000000`
/// ("C MECH" and six NULs, as in Table 7) and LRC 6F; the print has thirteen zeros where six
/// NUL bytes need twelve. The recomputed LRC 0x6F confirms the corrected frame.
#[test]
fn sync_cartridge_name() {
    rejected_as_printed(errata::SYNC_CARTRIDGE_NAME_REPLY.printed, Error::OddLength);
    seed_request(":0104304800067D", 0x01, read_input(0x3048, 6));
    seed_reply(
        errata::SYNC_CARTRIDGE_NAME_REPLY.meant,
        0x01,
        &read_input(0x3048, 6),
        input_values(&[0x4320, 0x4D45, 0x4348, 0x0000, 0x0000, 0x0000]),
    );
}

/// Lines 1700-1744: Start and Motion coils 0x3100/0x3101.
#[test]
fn sync_start_and_motion_coils() {
    let one = Request::ReadCoils {
        start: 0x3100,
        quantity: 1,
    };
    seed_request(":010131000001CC", 0x01, one);
    seed_reply(
        ":01010100FD",
        0x01,
        &one,
        Response::ReadCoils { bits: &[0x00] },
    );
    let both = Request::ReadCoils {
        start: 0x3100,
        quantity: 2,
    };
    seed_request(":010131000002CB", 0x01, both);
    seed_reply(
        ":01010103FA",
        0x01,
        &both,
        Response::ReadCoils { bits: &[0x03] },
    );
}

// ---------------------------------------------------------------------------------------------
// Legacy Powermax65/85 protocol (001). The manual prints the terminator of requests as the
// characters "0D0A" (meaning CR LF); the frames below stop before it and `wire` adds CR LF.
// ---------------------------------------------------------------------------------------------

/// Line 122: LRC worked example, `:010108080001ED0D0A` ("the LRC is 0xED"): read coil 0x0808.
#[test]
fn legacy_lrc_example() {
    seed_request(
        ":010108080001ED",
        0x01,
        Request::ReadCoils {
            start: 0x0808,
            quantity: 1,
        },
    );
}

/// Lines 151-156: cut_mode_force (0x2093) normal, CPA, gouge; replies echo the requests.
#[test]
fn legacy_cut_mode_force() {
    for (seed, value) in [
        (":01062093000145", 1),
        (":01062093000244", 2),
        (":01062093000343", 3),
    ] {
        let request = Request::WriteSingleRegister {
            address: 0x2093,
            value,
        };
        seed_request(seed, 0x01, request);
        seed_reply(
            seed,
            0x01,
            &request,
            Response::WriteSingleRegister {
                address: 0x2093,
                value,
            },
        );
    }
}

/// Lines 165-181: current_set_force (0x2094).
///
/// The 45 A sample is printed `:0106209400B40FA0D0A` and `:0106209400B40FA` (15 digits): the
/// text beside it gives 45 A x 64 = 0x0B40, and the print has a stray `0` before `B40`.
/// 01+06+20+94+0B+40 = 0x106, LRC 0xFA confirms the corrected `:010620940B40FA`.
#[test]
fn legacy_current_set_force() {
    rejected_as_printed(":0106209400B40FA", Error::OddLength);
    for (seed, value) in [
        (":010620940A003B", 0x0A00), // 40 A
        (":010620940B40FA", 0x0B40), // 45 A (corrected)
        (":010620941040F5", 0x1040), // 65 A
        (":010620941540F0", 0x1540), // 85 A
        (":010620940DE058", 0x0DE0), // 55.5 A
    ] {
        let request = Request::WriteSingleRegister {
            address: 0x2094,
            value,
        };
        seed_request(seed, 0x01, request);
        seed_reply(
            seed,
            0x01,
            &request,
            Response::WriteSingleRegister {
                address: 0x2094,
                value,
            },
        );
    }
}

/// Lines 193-198: pressure_set_force (0x2096) 45 and 70 psi.
#[test]
fn legacy_pressure_set_force() {
    for (seed, value) in [(":010620961680AD", 0x1680), (":01062096230020", 0x2300)] {
        let request = Request::WriteSingleRegister {
            address: 0x2096,
            value,
        };
        seed_request(seed, 0x01, request);
        seed_reply(
            seed,
            0x01,
            &request,
            Response::WriteSingleRegister {
                address: 0x2096,
                value,
            },
        );
    }
}

/// Lines 200-238: single-register reads and their replies.
#[test]
fn legacy_register_reads() {
    for (request_seed, register, reply_seed, value) in [
        (":010420980001420D0A", 0x2098, ":010402006F8A", 0x006F), // fault_code 0-11-1
        (":010420990001410D0A", 0x2099, ":0104020500F4", 0x0500), // current_set_min 20 A
        (":0104209A0001400D0A", 0x209A, ":0104021040A9", 0x1040), // current_set_max 65 A
        (":0104209C00013E0D0A", 0x209C, ":0104021F805A", 0x1F80), // pressure_set_min 63 psi
        (":0104209D00013D0D0A", 0x209D, ":0104022700D2", 0x2700), // pressure_set_max 78 psi
    ] {
        let request_seed = request_seed.strip_suffix("0D0A").unwrap();
        seed_request(request_seed, 0x01, read_input(register, 1));
        seed_reply(
            reply_seed,
            0x01,
            &read_input(register, 1),
            input_values(&[value]),
        );
    }
}

/// Lines 245-255: arc time (0x209E low word, 0x209F high word).
#[test]
fn legacy_arc_time() {
    let request = read_input(0x209E, 2);
    seed_request(":0104209E00023B", 0x01, request);
    for (seed, low, high, seconds) in [
        (":01040400010000F6", 0x0001, 0x0000, 1u32),
        (":010404003C0000BB", 0x003C, 0x0000, 60),
        (":0104040E100000D9", 0x0E10, 0x0000, 3600),
        (":0104047E40000534", 0x7E40, 0x0005, 360_000),
    ] {
        seed_reply(seed, 0x01, &request, input_values(&[low, high]));
        assert_eq!(u32::from(high) << 16 | u32::from(low), seconds);
    }
}

/// Lines 257-271: torch_index coils 0x0808/0x0809.
///
/// The request is printed as the fragment `08080002EC0D0` (start and end lost in the OCR).
/// Read Coils of 2 from 0x0808 at address 01 is `:010108080002EC`: 01+01+08+08+00+02 = 0x14,
/// LRC 0xEC, the same digits as the fragment, so it is restored with confidence.
#[test]
fn legacy_torch_index() {
    let request = Request::ReadCoils {
        start: 0x0808,
        quantity: 2,
    };
    seed_request(":010108080002EC", 0x01, request);
    for (seed, bits) in [
        (":01010100FD", 0x00),
        (":01010101FC", 0x01),
        (":01010102FB", 0x02),
    ] {
        seed_reply(seed, 0x01, &request, Response::ReadCoils { bits: &[bits] });
    }
}

// ---------------------------------------------------------------------------------------------
// The same frames through the other entry points.
// ---------------------------------------------------------------------------------------------

/// All the valid seed frames, back to back, in one stream: byte by byte and as one chunk.
#[test]
fn seed_frames_as_one_stream() {
    const FRAMES: [&str; 6] = [
        ":01043044000483",
        ":010408007900790000000001",
        ":012B0E0481000101010630383133333504",
        ":0110308000033C",
        ":01010103FA",
        ":0104047E40000534",
    ];
    let mut stream = heapless::Vec::<u8, 256>::new();
    for f in FRAMES {
        stream.extend_from_slice(&wire(f)).unwrap();
    }
    let mut decoder = Decoder::new();
    let mut rest = &stream[..];
    let mut seen = 0;
    while !rest.is_empty() {
        let (used, result) = decoder.feed(rest);
        if let Some(result) = result {
            let frame = result.unwrap();
            let mut out = [0u8; MAX_FRAME_CHARS];
            let n = frame.encode(&mut out).unwrap();
            assert_eq!(&out[..n], &wire(FRAMES[seen])[..]);
            seen += 1;
        }
        rest = &rest[used..];
    }
    assert_eq!(seen, FRAMES.len());
}

/// The one-shot `decode` agrees with the decoder, with or without CR LF and in lower case.
#[test]
fn one_shot_decode() {
    let mut buf = [0u8; MAX_PDU_LEN];
    let frame = decode(b":0104020508EC\r\n", &mut buf).unwrap();
    assert_eq!((frame.address, frame.pdu), (1, &[4, 2, 5, 8][..]));
    let frame = decode(b":0104020508ec", &mut buf).unwrap();
    assert_eq!((frame.address, frame.pdu), (1, &[4, 2, 5, 8][..]));
    assert_eq!(decode(b"0104020508EC\r\n", &mut buf), Err(Error::Malformed));
    assert_eq!(
        decode(b":0104020508EC\r\n:", &mut buf),
        Err(Error::Malformed)
    );
    assert_eq!(
        decode(b":0104020508ED", &mut buf),
        Err(Error::BadChecksum {
            expected: 0xEC,
            found: 0xED
        })
    );
    assert_eq!(
        decode(b":0104080079007900000000001", &mut buf),
        Err(Error::OddLength)
    );
    assert_eq!(
        decode(b":0104020508EC", &mut buf[..2]),
        Err(Error::BufferTooSmall)
    );
}
