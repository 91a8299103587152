//! Fuzz the HPR streaming decoder and the typed parsers behind it.
//!
//! The first input byte picks a chunk size, the rest is the byte stream. Checks: nothing
//! panics; chunked and byte-at-a-time decoding give the same events; every frame the decoder
//! returns re-emits to the same bytes; anything that parses as a request or reply re-emits
//! and parses back to the same value.
#![no_main]

use libfuzzer_sys::fuzz_target;
use plasma_protocol::hpr::{Decoder, Frame, MAX_FRAME_LEN, Reply, Request};

#[derive(Debug, PartialEq)]
enum Event {
    Frame {
        id: u16,
        len: usize,
        bytes: [u8; MAX_FRAME_LEN],
    },
    Error(plasma_protocol::Error),
}

fn check_frame(frame: &Frame<'_>) -> Event {
    let mut bytes = [0u8; MAX_FRAME_LEN];
    let len = frame.emit(&mut bytes).expect("a decoded frame re-emits");
    assert_eq!(Frame::parse(&bytes[..len]), Ok(*frame));
    if let Ok(req) = Request::parse(frame) {
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = req.emit(&mut out).expect("a parsed request re-emits");
        let again = Frame::parse(&out[..n]).expect("emitted request frame parses");
        assert_eq!(Request::parse(&again), Ok(req));
    }
    if let Ok(reply) = Reply::parse(frame) {
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = reply.emit(&mut out).expect("a parsed reply re-emits");
        let again = Frame::parse(&out[..n]).expect("emitted reply frame parses");
        assert_eq!(Reply::parse(&again), Ok(reply));
    }
    Event::Frame {
        id: frame.id,
        len,
        bytes,
    }
}

fn to_event(ev: plasma_protocol::Result<Frame<'_>>) -> Event {
    match ev {
        Ok(frame) => check_frame(&frame),
        Err(e) => Event::Error(e),
    }
}

fuzz_target!(|input: &[u8]| {
    let Some((&chunk, stream)) = input.split_first() else {
        return;
    };
    let chunk = usize::from(chunk).max(1);

    let mut bytewise = Vec::new();
    let mut d = Decoder::new();
    for &b in stream {
        if let Some(ev) = d.push(b) {
            bytewise.push(to_event(ev));
        }
    }

    let mut chunked = Vec::new();
    let mut d = Decoder::new();
    for mut part in stream.chunks(chunk) {
        while !part.is_empty() {
            let (used, ev) = d.feed(part);
            assert!(used >= 1 && used <= part.len());
            if let Some(ev) = ev {
                chunked.push(to_event(ev));
            }
            part = &part[used..];
        }
    }
    assert_eq!(bytewise, chunked);

    // The whole input as one frame must not panic either.
    if let Ok(frame) = Frame::parse(stream) {
        check_frame(&frame);
    }
});
