//! Property tests of the HPR protocol: emit-then-parse round trips for every typed request
//! and reply, and a decoder that never panics and does not care how input is chunked.

use plasma_protocol::Error;
use plasma_protocol::hpr::{
    ACK_COMMANDS, Acceptance, Decoder, ErrorCode, Frame, GasCode, GasConsole, GasFlows, GasPair,
    GasPressures, HprParameters, HprRating, IoStatus, LeakCheckMode, MAX_DATA_LEN, MAX_FRAME_LEN,
    MaxProParameters, MaxProPressures, MaxProPsInfo, PsInfo, Reply, Request, StateCode, SystemId,
    TestMode, TimerCounter, TorchId, Version,
};
use proptest::prelude::*;

fn gas() -> impl Strategy<Value = GasCode> {
    (0u16..=12).prop_map(GasCode)
}

fn gas_pair() -> impl Strategy<Value = GasPair> {
    (gas(), gas()).prop_map(|(plasma, shield)| GasPair { plasma, shield })
}

fn hpr_flows() -> impl Strategy<Value = GasFlows> {
    (
        prop::array::uniform4(0u16..=99),
        prop::array::uniform2(0u16..=100),
    )
        .prop_map(|(f, m)| GasFlows::from_array([f[0], f[1], f[2], f[3], m[0], m[1]]))
}

fn maxpro_pressures() -> impl Strategy<Value = MaxProPressures> {
    (0u16..=99, 0u16..=99).prop_map(|(plasma, shield)| MaxProPressures { plasma, shield })
}

fn leak_mode() -> impl Strategy<Value = LeakCheckMode> {
    (0u8..=3).prop_map(|c| LeakCheckMode::from_code(c).unwrap())
}

fn test_mode() -> impl Strategy<Value = TestMode> {
    (0u8..=6).prop_map(|c| TestMode::from_code(c).unwrap())
}

fn request() -> impl Strategy<Value = Request> {
    let simple = prop::sample::select(vec![
        Request::Hello,
        Request::Version,
        Request::GetState,
        Request::CurrentError,
        Request::RemoteMode,
        Request::ReadPlasmaAmps,
        Request::GasPreflowTestStart,
        Request::GasPreflowTestStop,
        Request::GasCutflowTestStart,
        Request::GasCutflowTestStop,
        Request::SoftwareReset,
        Request::GetControlVoltage,
        Request::GetIoStatus,
        Request::GetPsInfo,
        Request::Sleep,
        Request::BroadcastMode,
        Request::ReadGasPressures,
        Request::ReadCornerCurrent,
        Request::GetInletGases,
        Request::GetGasFlows,
        Request::ReadGasSwitch,
        Request::GetTimerCounter,
        Request::ClearWarnings,
        Request::ReadErrorLog,
        Request::IsSystemReadyForStart,
        Request::ReadTorchId,
    ]);
    prop_oneof![
        simple,
        (5u16..=400).prop_map(|amps| Request::SetNominalAmps { amps }),
        (50u8..=100).prop_map(|percent| Request::SetCornerCurrent { percent }),
        hpr_flows().prop_map(Request::SetAllGasFlows),
        maxpro_pressures().prop_map(Request::SetAllGasFlowsMaxPro200),
        (0u8..=3).prop_map(|system_id| Request::Wake { system_id }),
        (5u16..=400, 50u8..=100, gas_pair(), hpr_flows()).prop_map(
            |(amps, corner_percent, gases, flows)| {
                Request::SetAllParameters(HprParameters {
                    amps,
                    corner_percent,
                    gases,
                    flows,
                })
            }
        ),
        (0u16..=200, gas_pair(), maxpro_pressures()).prop_map(|(amps, gases, pressures)| {
            Request::SetAllParametersMaxPro200(MaxProParameters {
                amps,
                gases,
                pressures,
            })
        }),
        gas_pair().prop_map(Request::SetInletGases),
        leak_mode().prop_map(Request::LeakCheckMode),
        any::<bool>().prop_map(|enabled| Request::SerialResponseDelay { enabled }),
        (5u16..=200, gas_pair()).prop_map(|(amps, gases)| Request::SetProcess { amps, gases }),
        test_mode().prop_map(Request::SetTestMode),
    ]
}

fn system_id() -> impl Strategy<Value = SystemId> {
    let rating = prop::sample::select(vec![
        HprRating::Hpr130,
        HprRating::Hpr260,
        HprRating::Hpr400,
    ]);
    let console = prop::option::of(prop::sample::select(vec![
        GasConsole::Manual,
        GasConsole::Auto,
        GasConsole::AutoMix,
    ]));
    prop_oneof![
        Just(SystemId::MaxPro200),
        (rating, any::<bool>(), console).prop_map(|(rating, xd, console)| SystemId::Hpr {
            rating,
            xd,
            console
        }),
    ]
}

fn psi4() -> impl Strategy<Value = u16> {
    0u16..=9999
}

fn pressures() -> impl Strategy<Value = GasPressures> {
    prop::array::uniform8(psi4()).prop_map(|p| GasPressures {
        plasma_cutflow: p[0],
        plasma_preflow: p[1],
        shield_cutflow: p[2],
        shield_preflow: p[3],
        cut_gas_1: p[4],
        cut_gas_2: p[5],
        n2_mix_inlet: p[6],
        gas2_mix_inlet: p[7],
    })
}

fn four_digit_pair() -> impl Strategy<Value = GasPair> {
    (psi4(), psi4()).prop_map(|(p, s)| GasPair {
        plasma: GasCode(p),
        shield: GasCode(s),
    })
}

fn reply() -> impl Strategy<Value = Reply<'static>> {
    prop_oneof![
        system_id().prop_map(Reply::Hello),
        psi4().prop_map(|v| Reply::State(StateCode(v))),
        psi4().prop_map(|v| Reply::CurrentError(ErrorCode(v))),
        (prop::sample::select(ACK_COMMANDS.to_vec()), 0u8..=2).prop_map(|(command, c)| {
            Reply::Ack {
                command,
                result: Acceptance::from_code(c).unwrap(),
            }
        }),
        psi4().prop_map(Reply::PlasmaAmps),
        psi4().prop_map(Reply::NominalAmps),
        psi4().prop_map(Reply::CornerCurrentSet),
        psi4().prop_map(Reply::ControlVoltage),
        any::<[u8; 6]>().prop_map(|ports| Reply::IoStatus(IoStatus { ports })),
        (pressures(), psi4(), psi4(), psi4()).prop_map(|(pressures, cs, st, er)| {
            Reply::PsInfo(PsInfo {
                pressures,
                current_setpoint: cs,
                state: StateCode(st),
                error: ErrorCode(er),
            })
        }),
        (prop::array::uniform8(psi4()), any::<bool>()).prop_map(|(v, locked)| {
            Reply::MaxProPsInfo(MaxProPsInfo {
                state: StateCode(v[0]),
                error: ErrorCode(v[1]),
                plasma_gas: GasCode(v[2]),
                plasma_setpoint: v[3],
                shield_gas: GasCode(v[4]),
                shield_setpoint: v[5],
                current_setpoint: v[6],
                display_mode: v[7],
                locked,
            })
        }),
        (0u8..=9).prop_map(Reply::Wake),
        pressures().prop_map(Reply::GasPressures),
        psi4().prop_map(Reply::CornerCurrent),
        four_digit_pair().prop_map(Reply::InletGases),
        prop::array::uniform6(psi4()).prop_map(|v| Reply::GasFlows(GasFlows::from_array(v))),
        psi4().prop_map(Reply::LeakCheck),
        four_digit_pair().prop_map(Reply::GasSwitch),
        prop::array::uniform7(0u32..=9_999_999)
            .prop_map(|v| Reply::TimerCounter(TimerCounter::from_array(v))),
        prop::array::uniform4(0u16..=999).prop_map(|v| Reply::ErrorLog(v.map(ErrorCode))),
        any::<bool>().prop_map(Reply::ReadyForStart),
        (0u8..=9).prop_map(Reply::SetTestMode),
        psi4().prop_map(|v| Reply::TorchId(TorchId(v))),
        Just(Reply::BadChecksum),
        Just(Reply::UnknownCommand),
    ]
}

/// Decode `input` feeding it in the given chunk sizes; returns the events as owned values.
fn decode_chunked(input: &[u8], chunks: &[usize]) -> Vec<Result<(u16, Vec<u8>), Error>> {
    let mut d = Decoder::new();
    let mut events = Vec::new();
    let mut rest = input;
    let mut sizes = chunks.iter().cycle();
    while !rest.is_empty() {
        let size = sizes.next().copied().unwrap_or(1).clamp(1, rest.len());
        let mut chunk = &rest[..size];
        while !chunk.is_empty() {
            let (used, ev) = d.feed(chunk);
            assert!(used >= 1 && used <= chunk.len());
            if let Some(ev) = ev {
                events.push(ev.map(|f| (f.id, f.data.to_vec())));
            }
            chunk = &chunk[used..];
        }
        rest = &rest[size..];
    }
    events
}

fn decode_bytewise(input: &[u8]) -> Vec<Result<(u16, Vec<u8>), Error>> {
    let mut d = Decoder::new();
    input
        .iter()
        .filter_map(|&b| d.push(b).map(|ev| ev.map(|f| (f.id, f.data.to_vec()))))
        .collect()
}

/// Bytes likely to form frames: delimiters, digits, hex, spaces, and a little noise.
fn framey_bytes() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(
        prop_oneof![
            4 => prop::sample::select(b"><0123456789ABCDEF ".to_vec()),
            1 => any::<u8>(),
        ],
        0..600,
    )
}

proptest! {
    #[test]
    fn request_round_trip(req in request()) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = req.emit(&mut buf).unwrap();
        prop_assert!(!buf[..n].ends_with(b"\r\n"));
        let frame = Frame::parse(&buf[..n]).unwrap();
        prop_assert_eq!(frame.id, req.id());
        prop_assert_eq!(Request::parse(&frame), Ok(req));
    }

    #[test]
    fn reply_round_trip(reply in reply()) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = reply.emit(&mut buf).unwrap();
        let frame = Frame::parse(&buf[..n]).unwrap();
        prop_assert_eq!(frame.id, reply.id());
        prop_assert_eq!(Reply::parse(&frame), Ok(reply));
    }

    #[test]
    fn version_round_trip(ps in "[A-Z0-9.]{1,8}", gc in prop::option::of("[A-Z0-9.]{1,8}")) {
        let reply = Reply::Version(Version { power_supply: &ps, gas_console: gc.as_deref() });
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = reply.emit(&mut buf).unwrap();
        let frame = Frame::parse(&buf[..n]).unwrap();
        prop_assert_eq!(Reply::parse(&frame), Ok(reply));
    }

    #[test]
    fn frame_round_trip(id in 0u16..=999, data in prop::collection::vec(0x20u8..=0x7E, 0..=MAX_DATA_LEN)) {
        let data: Vec<u8> = data.into_iter().filter(|&b| b != b'<' && b != b'>').collect();
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = Frame::new(id, &data).emit(&mut buf).unwrap();
        prop_assert_eq!(Frame::parse(&buf[..n]), Ok(Frame::new(id, &data)));
        // The decoder finds it between noise that holds no `>`.
        let mut stream = b"\r\n<\x00\xffnoise".to_vec();
        stream.extend_from_slice(&buf[..n]);
        stream.extend_from_slice(b"<\r\n");
        prop_assert_eq!(decode_bytewise(&stream), vec![Ok((id, data.clone()))]);
    }

    #[test]
    fn parsers_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..200)) {
        if let Ok(frame) = Frame::parse(&bytes) {
            let _ = Request::parse(&frame);
            let _ = Reply::parse(&frame);
        }
    }

    #[test]
    fn typed_parsers_never_panic_on_valid_frames(id in 0u16..=520, data in "[ -;=?-~]{0,60}") {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = Frame::new(id, data.as_bytes()).emit(&mut buf).unwrap();
        let frame = Frame::parse(&buf[..n]).unwrap();
        if let Ok(req) = Request::parse(&frame) {
            // Whatever parses re-emits to something that parses to the same value.
            let mut out = [0u8; MAX_FRAME_LEN];
            let m = req.emit(&mut out).unwrap();
            prop_assert_eq!(Request::parse(&Frame::parse(&out[..m]).unwrap()), Ok(req));
        }
        if let Ok(reply) = Reply::parse(&frame) {
            let mut out = [0u8; MAX_FRAME_LEN];
            let m = reply.emit(&mut out).unwrap();
            prop_assert_eq!(Reply::parse(&Frame::parse(&out[..m]).unwrap()), Ok(reply));
        }
    }

    #[test]
    fn decoder_never_panics_and_ignores_chunking(
        input in prop_oneof![prop::collection::vec(any::<u8>(), 0..600), framey_bytes()],
        chunks in prop::collection::vec(1usize..40, 1..8),
    ) {
        let bytewise = decode_bytewise(&input);
        prop_assert_eq!(decode_chunked(&input, &chunks), bytewise.clone());
        prop_assert_eq!(decode_chunked(&input, &[input.len().max(1)]), bytewise);
    }

    #[test]
    fn decoder_recovers_after_garbage(garbage in prop::collection::vec(any::<u8>(), 0..400), req in request()) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = req.emit(&mut buf).unwrap();
        let mut stream = garbage;
        stream.extend_from_slice(&buf[..n]);
        let events = decode_bytewise(&stream);
        // Whatever the garbage did, the last event is the request frame.
        let last = events.last().cloned();
        let frame = Frame::parse(&buf[..n]).unwrap();
        prop_assert_eq!(last, Some(Ok((frame.id, frame.data.to_vec()))));
    }
}
