//! From CNC bytes to commands: Phoenix frames and ACK/NAK, bad input, the queue, and
//! properties over random input, end to end on the rig.

extern crate std;

use std::string::String;
use std::vec::Vec;

use proptest::prelude::*;

use crate::settings::Settings;
use plasma_protocol::time::Duration;

use crate::cnc::rig::*;
use crate::cnc::texts::{self};
use plasma_protocol::cnc::{ErrorCode, ParseError};

// ---------------------------------------------------------------------------------------
// Phoenix serial messaging

#[test]
fn phoenix_messages_are_acked_or_naked_then_answered() {
    let mut rig = Rig::sync65(Settings::default());
    let fault = framed(113, b"FAULT");
    assert_eq!(
        *fault.last().unwrap(),
        0x4A,
        "the manual's example check byte"
    );
    // The ACK byte on its own, then the reply line (the rig checks every line ends CR LF).
    let tokens = rig.send_bytes(&fault, 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    // A wrong check byte: NAK, and the line says why.
    let mut bad = framed(113, b"FAULT");
    *bad.last_mut().unwrap() ^= 0x01;
    let tokens = rig.send_bytes(&bad, 1);
    assert_eq!(tokens, [NAK_TOKEN, frame_err(0x4A, 0x4B).as_str()]);
    // Intact but not a command: NAK too.
    let tokens = rig.send_bytes(&framed(113, b"FLY"), 1);
    assert_eq!(
        tokens,
        [NAK_TOKEN, parse_err(ParseError::UnknownCommand).as_str()]
    );
    // A command that waits for the unit: ACK at once, before any time passes or any frame
    // goes to the unit; the reply only after the read-back.
    let sent = rig.ps().sent.len();
    let tokens = rig.send_bytes(&framed(113, b"SET PROCESS CUT 45 AUTO"), 0);
    assert_eq!(tokens, [ACK_TOKEN]);
    assert_eq!(rig.ps().sent.len(), sent, "acked before the unit is asked");
    let acked_at = rig.now;
    let tokens = rig.send_bytes(b"", 1);
    assert_eq!(tokens, ["OK mode=CUT amps=45 psi=AUTO"]);
    assert!(
        rig.now > acked_at,
        "the reply follows after the unit answered"
    );
    assert!(rig.ps().sent.len() > sent, "the unit was asked");
    // Text lines still work around frames.
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    // Another format, set by CONFIG.
    assert_eq!(rig.cmd("CONFIG phoenix_format 48"), "OK phoenix_format=48");
    let tokens = rig.send_bytes(&framed(48, b"FAULT"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    // Message type 22 as the part program writes it: `>22,33<FAULT` (STX, CR LF, ETX).
    assert_eq!(rig.cmd("CONFIG phoenix_format 33"), "OK phoenix_format=33");
    let tokens = rig.send_bytes(b"\x02FAULT\r\n\x03", 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    // A frame broken off by the next one.
    let tokens = rig.send_bytes(b"\x02FAU\x02FAULT\r\n\x03", 2);
    assert_eq!(
        tokens,
        [
            NAK_TOKEN,
            err(ErrorCode::Syntax, texts::PHOENIX_TRUNCATED).as_str(),
            ACK_TOKEN,
            "OK fault=none"
        ]
    );
    assert_eq!(rig.bridge.session_stats().acks, 5);
    assert_eq!(rig.bridge.session_stats().naks, 3);
}

/// Phoenix manual (003_610fea73110d789e.txt) lines 7204-7217: format 0 adds nothing, 1
/// appends CR (0x0D) LF (0x0A), 16 the "Exclusive OR" check byte, 17 both (CR LF, then the
/// check byte, line 7196: it never covers CR LF); lines 7124-7130: a type-22 message waits for
/// ACK (0x06) and NAK (0x15) makes the CNC send it again. The bytes below are `FAULT` as each
/// format sends it ("FAULT": F^A^U^L^T = 0x4A); the ESSI example at line 7102,
/// `>20,1,1,0<Message`, is format 1: "Message" CR LF.
#[test]
fn unframed_phoenix_formats_0_1_16_17_are_acked_then_answered() {
    let cases: [(u8, &[u8]); 4] = [
        (0, b"FAULT"),
        (1, b"FAULT\r\n"),
        (16, b"FAULT\x4A"),
        (17, b"FAULT\r\n\x4A"),
    ];
    for (format, wire) in cases {
        let mut rig = Rig::sync65(Settings::default());
        let key = std::format!("CONFIG phoenix_format {format}");
        assert_eq!(rig.cmd(&key), std::format!("OK phoenix_format={format}"));
        assert_eq!(framed(format, b"FAULT"), wire, "format {format}");
        let tokens = rig.send_bytes(wire, 1);
        assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"], "format {format}");
        // The same message with a wrong check byte (or without its CR): NAK and why.
        let damaged: &[u8] = match format {
            0 => b"FLY",
            1 => b"FAULT\n",
            16 => b"FAULT\x4B",
            _ => b"FAULT\r\n\x4B",
        };
        let tokens = rig.send_bytes(damaged, 1);
        assert_eq!(tokens[0], NAK_TOKEN, "format {format}: {tokens:?}");
        // A framed message is still told by its SOH and taken.
        let tokens = rig.send_bytes(&framed(113, b"FAULT"), 1);
        assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"], "format {format}");
        // And the port's own format again after it.
        let tokens = rig.send_bytes(wire, 1);
        assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"], "format {format}");
        assert_eq!(rig.bridge.session_stats().acks, 3, "format {format}");
        assert_eq!(rig.bridge.session_stats().naks, 1, "format {format}");
    }
}

#[test]
fn format_1_takes_a_command_as_a_message_and_a_program_can_switch_back() {
    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(rig.cmd("CONFIG phoenix_format 1"), "OK phoenix_format=1");
    // `>22,1<SET PROCESS CUT 45 AUTO`: ACK at once, the reply after the unit's read-back.
    let tokens = rig.send_bytes(b"SET PROCESS CUT 45 AUTO\r\n", 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK mode=CUT amps=45 psi=AUTO"]);
    let tokens = rig.send_bytes(b"CONFIG phoenix_format 113\r\n", 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK phoenix_format=113"]);
    // Plain text lines again: no ACK.
    let tokens = rig.send_bytes(b"FAULT\r\n", 1);
    assert_eq!(tokens, ["OK fault=none"]);
}

// ---------------------------------------------------------------------------------------
// bad input

#[test]
fn overlong_lines_binary_garbage_and_half_lines_get_an_error_and_the_session_goes_on() {
    let mut rig = Rig::sync65(Settings::default());
    let mut long = std::vec![b'A'; 200];
    long.extend_from_slice(b"\r\nFAULT\r\n");
    let tokens = rig.send_bytes(&long, 2);
    assert_eq!(
        tokens,
        [parse_err(ParseError::TooLong).as_str(), "OK fault=none"]
    );
    let tokens = rig.send_bytes(b"\x80\xff\x00junk\x1b[A\r\nFAULT\n", 2);
    assert_eq!(
        tokens,
        [parse_err(ParseError::Binary).as_str(), "OK fault=none"]
    );
    // A half line followed by a Phoenix frame.
    let mut half = b"SET AMP".to_vec();
    half.extend_from_slice(&framed(113, b"FAULT"));
    let tokens = rig.send_bytes(&half, 2);
    assert_eq!(
        tokens,
        [
            err(ErrorCode::Syntax, texts::LINE_INTERRUPTED).as_str(),
            ACK_TOKEN,
            "OK fault=none"
        ]
    );
    // A half line waits for the rest, however long, and goes on in the next chunk as one line.
    assert!(rig.send_bytes(b"FAU", 0).is_empty());
    let waiting = rig.received.len();
    rig.run(500);
    assert_eq!(
        rig.received.len(),
        waiting,
        "{:?}",
        &rig.received[waiting..]
    );
    assert_eq!(rig.send_bytes(b"LT\r", 1), ["OK fault=none"]);
    // LF after CR is part of the same line end; blank lines get no reply.
    assert_eq!(
        rig.send_bytes(b"\n\r\n  \t\r\nFAULT\n", 1),
        ["OK fault=none"]
    );
    // A burst of noise without SOH/STX: each line it makes gets one ERR, nothing else.
    let garbage: Vec<u8> = (0..2_000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .filter(|b| *b != 0x01 && *b != 0x02)
        .collect();
    let start = rig.received.len();
    rig.send_bytes(&garbage, 0);
    rig.send_bytes(b"\r\n", 0);
    rig.run(2_000);
    let replies: Vec<&Token> = rig.received[start..]
        .iter()
        .filter(|t| is_reply(t))
        .collect();
    assert!(!replies.is_empty());
    assert!(replies.iter().all(|l| l.starts_with("ERR ")), "{replies:?}");
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
}

#[test]
fn lines_wait_while_a_command_is_in_progress_and_a_full_queue_says_busy() {
    let mut rig = Rig::sync65(Settings::default());
    let tokens = rig.send_bytes(
        b"SET PROCESS CUT 45 AUTO\r\nFAULT\r\nLIMITS\r\nFLY\r\nEVENTS OFF\r\nFAULT\r\n",
        6,
    );
    assert_eq!(
        tokens,
        [
            err(ErrorCode::Busy, texts::QUEUE_FULL).as_str(),
            "OK mode=CUT amps=45 psi=AUTO",
            "OK fault=none",
            "OK modes=CUT,EXPANDED amps=20..65 psi=58..78 scope=cartridge",
            parse_err(ParseError::UnknownCommand).as_str(),
            "OK events=OFF",
        ]
    );
}

// ---------------------------------------------------------------------------------------
// properties

/// Words commands are made of, so that random lines are often real commands.
const WORDS: [&str; 22] = [
    "HELP",
    "ID",
    "STATUS",
    "LIMITS",
    "FAULT",
    "SET",
    "MODE",
    "AMPS",
    "PSI",
    "PROCESS",
    "CUT",
    "45",
    "AUTO",
    "EVENTS",
    "ON",
    "OFF",
    "CONFIG",
    "SAVE",
    "timeout_ms",
    "RAW",
    "TORCH",
    "GASES",
];

fn line_content() -> impl Strategy<Value = Vec<u8>> {
    let word = prop_oneof![
        proptest::sample::select(&WORDS[..]).prop_map(|w| w.as_bytes().to_vec()),
        // Anything but the line ends and the Phoenix start bytes.
        proptest::collection::vec(
            any::<u8>().prop_filter("no CR, LF, SOH, STX", |b| {
                !matches!(*b, b'\r' | b'\n' | 0x01 | 0x02)
            }),
            0..40
        ),
    ];
    proptest::collection::vec(word, 0..8).prop_map(|words| words.join(&b' '))
}

const TERMINATORS: [&[u8]; 3] = [b"\r\n", b"\n", b"\r"];

fn terminator() -> impl Strategy<Value = &'static [u8]> {
    proptest::sample::select(&TERMINATORS[..])
}

/// Feed `bytes` in chunks of `chunk`, serving saves and collecting output after each.
fn feed(rig: &mut Rig, bytes: &[u8], chunk: usize) {
    for part in bytes.chunks(chunk.max(1)) {
        rig.bridge.handle_cnc_rx(rig.now, part);
        rig.now = rig.now + Duration::from_millis(1);
        rig.run(2);
    }
    rig.run(100);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn every_complete_line_gets_exactly_one_reply(
        lines in proptest::collection::vec((line_content(), terminator()), 1..12),
        chunk in 1usize..48,
    ) {
        let mut rig = Rig::new(Settings::default(), None);
        let mut bytes = Vec::new();
        let mut expected = 0;
        for (content, end) in &lines {
            if content.iter().any(|b| *b != b' ' && *b != b'\t') {
                expected += 1;
            }
            bytes.extend_from_slice(content);
            bytes.extend_from_slice(end);
        }
        feed(&mut rig, &bytes, chunk);
        let replies = rig.received.iter().filter(|t| is_reply(t)).count();
        prop_assert_eq!(replies, expected, "{:?}", rig.received);
    }

    #[test]
    fn random_bytes_never_panic_and_output_stays_well_formed(
        bytes in proptest::collection::vec(any::<u8>(), 0..600),
        chunk in 1usize..64,
    ) {
        let mut rig = Rig::sync65(Settings::default());
        let before = rig.received.len();
        feed(&mut rig, &bytes, chunk);
        // `collect` checked every line ends with CR LF and holds printable ASCII only.
        for token in &rig.received[before..] {
            prop_assert!(
                is_reply(token) || token.starts_with('!') || token == ACK_TOKEN
                    || token == NAK_TOKEN,
                "{:?}",
                token
            );
        }
        // The session still answers.
        // End whatever half line the noise left (its reply, if any, is an ERR).
        rig.send_bytes(b"\r\n", 0);
        let reply = rig.cmd("FAULT");
        prop_assert_eq!(reply.as_str(), "OK fault=none");
    }
}

#[test]
fn phoenix_framing_is_recognised_without_setting_phoenix_format() {
    let mut rig = Rig::sync65(Settings::default());
    // Default 113; the CNC sends 112 (no CR LF), 97 (no check byte), then 33 (STX only).
    for format in [112, 97, 97, 33, 33, 113] {
        let tokens = rig.send_bytes(&framed(format, b"FAULT"), 1);
        assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"], "format {format}");
    }
    // A frame no format takes is still refused.
    let mut bad = framed(113, b"FAULT");
    *bad.last_mut().unwrap() ^= 0x01;
    let tokens = rig.send_bytes(&bad, 1);
    assert_eq!(tokens[0], NAK_TOKEN, "{tokens:?}");
    // Once recognised, a format is used at once: no wait for a check byte that never comes.
    rig.send_bytes(&framed(97, b"FAULT"), 1);
    let start = rig.now;
    let tokens = rig.send_bytes(&framed(97, b"FAULT"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    assert_eq!(rig.now, start, "answered without waiting");
    // The key stays an override: set, it is the format expected first again.
    assert_eq!(
        rig.cmd("CONFIG phoenix_format 113"),
        "OK phoenix_format=113"
    );
    let tokens = rig.send_bytes(&framed(113, b"FAULT"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    let after = rig.received.len();
    rig.run(200);
    assert_eq!(
        rig.received[after..],
        [] as [String; 0],
        "nothing left over"
    );
}

// ---------------------------------------------------------------------------------------
// `@N`: several units on one line

fn two_hprs() -> Rig {
    let settings = Settings {
        events: true,
        ..Settings::default()
    };
    let mut rig = Rig::on_line(settings, "HPR:0,HPR:1", &["hpr260", "hpr130"]);
    assert!(rig.bridge.status_of(0).link_up && rig.bridge.status_of(1).link_up);
    rig.received.clear();
    rig
}

#[test]
fn a_line_without_at_n_is_for_the_first_unit_and_at_n_names_another() {
    let mut rig = two_hprs();
    // Each unit's firmware is read after its first polls, once a round of turns.
    rig.run(1000);
    // As docs/cnc-protocol.md section 10 shows them.
    let first = rig.cmd("ID");
    assert_eq!(
        first,
        "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=HPR260 family=HPR \
         firmware=A.0 gas_firmware=A.2"
    );
    let second = rig.cmd("@2 ID");
    assert_eq!(
        second,
        "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=HPR130 family=HPR \
         firmware=A.0 gas_firmware=A.2 unit=2"
    );
    assert_eq!(rig.cmd("@1 ID"), first, "@1 is the line without a prefix");
    // Refused lines of unit 2 say so too, after the code: an ERR text runs to the end.
    assert_eq!(
        rig.cmd("@2 FROB"),
        "ERR SYNTAX unit=2 unknown command (HELP lists the commands)"
    );
}

#[test]
fn a_unit_the_bridge_does_not_drive_is_refused_precisely() {
    let mut rig = two_hprs();
    assert_eq!(
        rig.cmd("@3 ID"),
        std::format!("ERR RANGE {}", texts::NoSuchUnit { unit: 2, count: 2 })
    );
    assert_eq!(
        rig.cmd("@3 ID"),
        "ERR RANGE unit 3: the bridge drives 2 units (CONFIG units)"
    );
    assert_eq!(rig.cmd("@5 ID"), "ERR RANGE unit out of range 1..4");
    assert_eq!(rig.cmd("@x ID"), "ERR SYNTAX unit: not a number");
    // One unit (the default): only @1.
    let mut one = Rig::sync65(Settings::default());
    assert_eq!(
        one.cmd("@2 STATUS"),
        "ERR RANGE unit 2: the bridge drives 1 unit (CONFIG units)"
    );
    assert_eq!(one.cmd("@1 FAULT"), "OK fault=none");
}

#[test]
fn each_units_fault_is_its_own_and_its_events_carry_the_unit() {
    let mut rig = two_hprs();
    let now = rig.now;
    rig.line().unit_mut(1).unwrap().inject_fault(now, 44);
    rig.run(1500);
    let events: Vec<&String> = rig
        .received
        .iter()
        .filter(|t| t.starts_with("!FAULT"))
        .collect();
    assert_eq!(events.len(), 1, "{:?}", rig.received);
    // Before the free-text field, which runs to the end of the line.
    assert_eq!(
        events[0],
        "!FAULT 044 action=required unit=2 text=LOW PLASMA GAS PRESSURE"
    );
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    assert_eq!(
        rig.cmd("@2 FAULT"),
        "OK fault=044 action=required unit=2 text=LOW PLASMA GAS PRESSURE"
    );
}

#[test]
fn a_setting_goes_to_the_unit_named_and_stays_there() {
    let mut rig = two_hprs();
    let reply = rig.cmd("@2 SET AMPS 80");
    assert!(reply.starts_with("OK "), "{reply}");
    assert!(reply.ends_with(" unit=2"), "{reply}");
    let second = rig.cmd("@2 STATUS");
    let first = rig.cmd("STATUS");
    assert!(second.contains(" amps=80"), "{second}");
    assert!(!first.contains(" amps=80"), "{first}");
    // The first unit's process is the one the settings persist.
    assert_eq!(rig.bridge.settings().process, None);
}

#[test]
fn what_is_the_whole_bridges_or_the_first_units_refuses_at_n() {
    let mut rig = two_hprs();
    assert_eq!(
        rig.cmd("@2 POWER ON"),
        std::format!("ERR UNSUPPORTED unit=2 {}", texts::POWER_EVERY_UNIT)
    );
    assert_eq!(
        rig.cmd("@2 CONSUMABLES"),
        std::format!("ERR UNSUPPORTED unit=2 {}", texts::CONSUMABLES_FIRST_UNIT)
    );
    assert!(rig.cmd("CONSUMABLES").starts_with("OK source=bridge "));
}

#[test]
fn units_lists_every_unit_with_its_state() {
    let mut rig = two_hprs();
    let now = rig.now;
    rig.line().unit_mut(1).unwrap().inject_fault(now, 44);
    rig.line().set_connected(0, false);
    rig.run(6000);
    assert!(!rig.bridge.status_of(0).link_up);
    rig.received.clear();
    let tokens = rig.send_bytes(b"UNITS\r\n", 1);
    assert_eq!(
        tokens,
        [
            "UNIT n=1 address=HPR:0 link=DOWN family=- model=- fault=-",
            "UNIT n=2 address=HPR:1 link=UP family=HPR model=HPR130 fault=044",
            "OK units=2",
        ]
    );
    // One unit, auto-detected.
    let mut one = Rig::sync65(Settings::default());
    let tokens = one.send_bytes(b"UNITS\r\n", 1);
    assert_eq!(
        tokens,
        [
            "UNIT n=1 address=AUTO link=UP family=SYNC model=Powermax65 fault=none",
            "OK units=1",
        ]
    );
}

/// The examples of docs/cnc-protocol.md section 10, line for line.
#[test]
fn the_several_units_examples_of_the_protocol_page() {
    let mut one = Rig::sync65(Settings::default());
    assert_eq!(
        one.cmd("CONFIG units HPR:0,POWERMAX:1"),
        "ERR REFUSED units: unit 2 cannot share the line: a Powermax speaks Modbus ASCII, an HPR \
         or MaxPro200 its own protocol"
    );
    assert_eq!(
        one.cmd("CONFIG units MAXPRO200,HPR:1"),
        "ERR REFUSED units: a MaxPro200 cannot share a line: it has no SLEEP/WAKE, so it \
         answers every request"
    );
    assert_eq!(
        one.cmd("CONFIG units HPR:0,HPR:1"),
        "OK units=HPR:0,HPR:1 link=redetecting"
    );
    assert_eq!(one.bridge.unit_count(), 2);
    let mut rig = two_hprs();
    assert_eq!(rig.cmd("@2 SET AMPS 80"), "OK amps=80 unit=2");
    let now = rig.now;
    rig.line().unit_mut(1).unwrap().inject_fault(now, 44);
    rig.run(1500);
    let fault: Vec<&String> = rig
        .received
        .iter()
        .filter(|t| t.starts_with("!FAULT"))
        .collect();
    assert_eq!(
        fault,
        ["!FAULT 044 action=required unit=2 text=LOW PLASMA GAS PRESSURE"]
    );
}
