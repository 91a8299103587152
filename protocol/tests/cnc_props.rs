//! Property tests of the CNC input side: no panics on any bytes, chunking never changes the
//! outcome, and Phoenix framing round-trips for every format.

use plasma_protocol::Error;
use plasma_protocol::cnc::phoenix::{self, Deframer, Format};
use plasma_protocol::cnc::reply::{ReplyWriter, write_parse_error};
use plasma_protocol::cnc::{Amps, Command, LineAssembler, LineError, MAX_LINE_LEN, Psi};
use proptest::prelude::*;

type LineOutcome = Result<String, LineError>;

/// Feed `input` cut at `cuts` (positions taken modulo the length) and collect every line.
fn lines_chunked(input: &[u8], cuts: &[usize]) -> Vec<LineOutcome> {
    let mut assembler = LineAssembler::new();
    let mut out = Vec::new();
    let mut bounds: Vec<usize> = cuts
        .iter()
        .map(|c| if input.is_empty() { 0 } else { c % input.len() })
        .collect();
    bounds.push(input.len());
    bounds.sort_unstable();
    let mut start = 0;
    for end in bounds {
        let mut chunk = &input[start..end];
        while !chunk.is_empty() {
            let (used, line) = assembler.feed(chunk);
            assert!(used > 0 && used <= chunk.len());
            chunk = &chunk[used..];
            if let Some(line) = line {
                out.push(line.map(str::to_owned));
            }
        }
        start = end;
    }
    out
}

fn lines_bytewise(input: &[u8]) -> Vec<LineOutcome> {
    let mut assembler = LineAssembler::new();
    input
        .iter()
        .filter_map(|&b| assembler.push(b).map(|l| l.map(str::to_owned)))
        .collect()
}

type FrameOutcome = Result<Vec<u8>, Error>;

fn deframe_chunked<const N: usize>(
    format: Format,
    input: &[u8],
    cuts: &[usize],
    idle_at_end: bool,
) -> Vec<FrameOutcome> {
    let mut rx: Deframer<N> = Deframer::new(format);
    let mut out = Vec::new();
    let mut bounds: Vec<usize> = cuts
        .iter()
        .map(|c| if input.is_empty() { 0 } else { c % input.len() })
        .collect();
    bounds.push(input.len());
    bounds.sort_unstable();
    let mut start = 0;
    for end in bounds {
        let mut chunk = &input[start..end];
        while !chunk.is_empty() {
            let (used, outcome) = rx.feed(chunk);
            assert!(used > 0 && used <= chunk.len());
            chunk = &chunk[used..];
            if let Some(outcome) = outcome {
                out.push(outcome.map(<[u8]>::to_vec));
            }
        }
        start = end;
    }
    // (No let-chain: the workspace's rust-version predates them.)
    let at_idle = if idle_at_end { rx.idle() } else { None };
    if let Some(outcome) = at_idle {
        out.push(outcome.map(<[u8]>::to_vec));
    }
    out
}

fn any_format() -> impl Strategy<Value = Format> {
    proptest::sample::select(Format::ALL.to_vec())
}

/// Bytes that look like the CNC's input: mostly text and terminators, some control bytes.
fn cnc_like_bytes() -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![
        8 => proptest::sample::select(b"SETAMPS psiauto0123456789.modecut\t ".to_vec()),
        2 => proptest::sample::select(b"\r\n".to_vec()),
        1 => proptest::sample::select(vec![0x01, 0x02, 0x03, 0x04, 0x06, 0x15]),
        1 => any::<u8>(),
    ];
    proptest::collection::vec(byte, 0..400)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn line_assembler_chunking_never_changes_the_lines(
        input in prop_oneof![cnc_like_bytes(), proptest::collection::vec(any::<u8>(), 0..400)],
        cuts in proptest::collection::vec(any::<usize>(), 0..8),
    ) {
        let whole = lines_chunked(&input, &[]);
        prop_assert_eq!(&lines_chunked(&input, &cuts), &whole);
        prop_assert_eq!(&lines_bytewise(&input), &whole);
        for line in whole.iter().flatten() {
            prop_assert!(!line.is_empty() && line.len() <= MAX_LINE_LEN);
            prop_assert!(line.bytes().all(|b| b == b'\t' || (0x20..0x7F).contains(&b)));
            prop_assert_eq!(line.trim_matches([' ', '\t']), line.as_str());
            // The parser and the reply writers never panic on what the assembler yields.
            if let Err(error) = Command::parse(line) {
                let mut reply = heapless::String::<160>::new();
                write_parse_error(&mut reply, &error).unwrap();
                prop_assert!(reply.starts_with("ERR ") && reply.ends_with("\r\n"));
                prop_assert_eq!(reply.matches('\n').count(), 1);
            }
        }
    }

    #[test]
    fn parser_never_panics(line in ".{0,200}") {
        let _ = Command::parse(&line);
    }

    #[test]
    fn parser_never_panics_on_command_like_lines(
        words in proptest::collection::vec(
            prop_oneof![
                proptest::sample::select(vec![
                    "SET", "MODE", "AMPS", "PSI", "PROCESS", "AUTO", "CUT", "gouge", "CONFIG",
                    "SAVE", "RAW", "GASES", "O2", "air", "CORNER", "ON", "OFF", "REMOTE",
                    "TORCH", "EVENTS", "GASTEST", "timeout_ms", "STATUS",
                ]).prop_map(str::to_owned),
                "[0-9]{0,8}(\\.[0-9]{0,10})?",
                "[ -~]{0,6}",
            ],
            0..6,
        ),
    ) {
        let line = words.join(" ");
        if let Ok(Command::Raw(frame)) = Command::parse(&line) {
            prop_assert!(!frame.is_empty());
        }
    }

    #[test]
    fn amps_and_psi_round_trip_through_their_text(a in 320u16..=25600, p in 128u16..=19200) {
        let line = format!("SET PROCESS CUT {} {}", Amps::from_raw(a), Psi::from_raw(p));
        match Command::parse(&line) {
            Ok(Command::SetProcess { amps, pressure, .. }) => {
                prop_assert_eq!(amps.raw(), a);
                prop_assert_eq!(pressure.raw(), p);
            }
            other => prop_assert!(false, "{line}: {other:?}"),
        }
    }

    #[test]
    fn reply_fields_stay_on_one_line(key in ".{0,20}", value in ".{0,40}") {
        let mut out = heapless::String::<512>::new();
        let mut reply = ReplyWriter::ok(&mut out).unwrap();
        reply.field(&key, &value).unwrap();
        reply.finish().unwrap();
        prop_assert!(out.ends_with("\r\n"));
        prop_assert_eq!(out.matches(['\r', '\n']).count(), 2);
        prop_assert_eq!(out.matches(' ').count(), 1);
    }

    #[test]
    fn deframer_never_panics_and_chunking_never_changes_the_outcome(
        format in any_format(),
        input in prop_oneof![cnc_like_bytes(), proptest::collection::vec(any::<u8>(), 0..400)],
        cuts in proptest::collection::vec(any::<usize>(), 0..8),
        idle in any::<bool>(),
    ) {
        let whole = deframe_chunked::<32>(format, &input, &[], idle);
        prop_assert_eq!(&deframe_chunked::<32>(format, &input, &cuts, idle), &whole);
        for message in whole.iter().flatten() {
            prop_assert!(message.len() <= 32);
        }
    }

    #[test]
    fn emit_then_deframe_round_trips_for_every_format(
        format in any_format(),
        messages in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..40), 1..4),
        cuts in proptest::collection::vec(any::<usize>(), 0..8),
    ) {
        // Formats 0 and 16 end at idle: one message per burst.
        let unterminated = format.start_byte().is_none() && !format.cr_lf();
        let messages: Vec<Vec<u8>> = messages
            .into_iter()
            .map(|m| m.into_iter().filter(|&b| !format.is_reserved(b)).collect())
            .take(if unterminated { 1 } else { 4 })
            // An empty format-0 message puts nothing on the wire: there is nothing to receive.
            .filter(|m: &Vec<u8>| format != Format::PLAIN || !m.is_empty())
            .collect();
        let mut wire = Vec::new();
        for m in &messages {
            let mut out = [0u8; 64];
            let n = phoenix::frame(format, m, &mut out).unwrap();
            prop_assert_eq!(n, m.len() + format.overhead());
            wire.extend_from_slice(&out[..n]);
        }
        let got = deframe_chunked::<42>(format, &wire, &cuts, unterminated);
        let expected: Vec<FrameOutcome> = messages.into_iter().map(Ok).collect();
        prop_assert_eq!(got, expected);
    }

    #[test]
    fn escapes_round_trip(bytes in proptest::collection::vec(any::<u8>(), 0..100)) {
        let mut text = [0u8; 200];
        let n = phoenix::encode_escapes(&bytes, &mut text).unwrap();
        prop_assert!(text[..n].iter().all(|b| (0x20..0x7F).contains(b)));
        let mut back = [0u8; 100];
        let m = phoenix::decode_escapes(&text[..n], &mut back).unwrap();
        prop_assert_eq!(&back[..m], &bytes[..]);
    }

    #[test]
    fn escape_decoding_never_panics(input in proptest::collection::vec(any::<u8>(), 0..100)) {
        let mut out = [0u8; 100];
        if let Ok(n) = phoenix::decode_escapes(&input, &mut out) {
            prop_assert!(n <= input.len());
        }
        let _ = phoenix::decode_escapes(&input, &mut out[..3]);
        let _ = phoenix::ProgramMessage::parse(core::str::from_utf8(&input).unwrap_or(">20<"));
    }
}
