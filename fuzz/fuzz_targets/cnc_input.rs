//! Fuzz everything the CNC can send: Phoenix frames of any format, text lines, the command
//! parser on both, and the reply writers on every error. Nothing may panic, and feeding in
//! two chunks must give the same outcomes as feeding all at once.
#![no_main]

use libfuzzer_sys::fuzz_target;
use plasma_protocol::cnc::phoenix::{self, Deframer, Format};
use plasma_protocol::cnc::reply::write_parse_error;
use plasma_protocol::cnc::{Command, LineAssembler};

/// Parse a command and write the reply an error would get.
fn parse_and_reply(text: &str) {
    if let Err(error) = Command::parse(text) {
        let mut reply = heapless::String::<256>::new();
        let _ = write_parse_error(&mut reply, &error);
    }
}

/// Run the deframer over `input` cut at `cut`, recording each outcome's kind and payload hash.
fn deframe(format: Format, input: &[u8], cut: usize) -> heapless::Vec<(bool, usize, u8), 512> {
    let mut rx: Deframer = Deframer::new(format);
    let mut seen = heapless::Vec::new();
    let (a, b) = input.split_at(cut.min(input.len()));
    for mut chunk in [a, b] {
        while !chunk.is_empty() {
            let (used, outcome) = rx.feed(chunk);
            chunk = &chunk[used..];
            match outcome {
                Some(Ok(payload)) => {
                    let _ = seen.push((true, payload.len(), phoenix::check_byte(payload)));
                    parse_and_reply(core::str::from_utf8(payload).unwrap_or(""));
                }
                Some(Err(_)) => {
                    let _ = seen.push((false, 0, 0));
                }
                None => {}
            }
        }
    }
    if let Some(outcome) = rx.idle() {
        let _ = seen.push((outcome.is_ok(), 0, 0));
    }
    seen
}

fn lines(input: &[u8], cut: usize) -> heapless::Vec<(bool, usize), 512> {
    let mut assembler = LineAssembler::new();
    let mut seen = heapless::Vec::new();
    let (a, b) = input.split_at(cut.min(input.len()));
    for mut chunk in [a, b] {
        while !chunk.is_empty() {
            let (used, outcome) = assembler.feed(chunk);
            chunk = &chunk[used..];
            match outcome {
                Some(Ok(line)) => {
                    let _ = seen.push((true, line.len()));
                    parse_and_reply(line);
                }
                Some(Err(_)) => {
                    let _ = seen.push((false, 0));
                }
                None => {}
            }
        }
    }
    seen
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, input)) = data.split_first() else {
        return;
    };
    let format = Format::ALL[usize::from(selector & 0x0F)];
    let cut = usize::from(selector >> 4) * input.len() / 16;

    assert_eq!(deframe(format, input, 0), deframe(format, input, cut));
    assert_eq!(lines(input, 0), lines(input, cut));

    if let Ok(text) = core::str::from_utf8(input) {
        parse_and_reply(text);
        let _ = phoenix::ProgramMessage::parse(text);
    }
    let mut out = [0u8; 512];
    let _ = phoenix::decode_escapes(input, &mut out);
});
