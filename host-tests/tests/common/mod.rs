//! Helpers shared by the CNC-side scenario and property tests.
#![allow(dead_code, reason = "each test crate uses a different subset")]

pub mod emu;

use host_tests::harness::{BridgeEndpoint, World, WorldOptions};
use plasma_firmware::settings::Settings;
use plasma_protocol::time::Duration;
use plasma_sim::Model;

/// The bridge (default settings, simulator commands on) against `model`, run until the link
/// is up and the unit's limits (Powermax) or state (HPR) are known.
pub fn bridge_world(model: Model) -> World<BridgeEndpoint> {
    bridge_world_with(model, Settings::default())
}

/// As [`bridge_world`], with `settings`.
pub fn bridge_world_with(model: Model, settings: Settings) -> World<BridgeEndpoint> {
    let mut world = World::with_bridge(model, WorldOptions::default(), settings);
    settle(&mut world);
    world
}

/// Run until the link is up and the first status cycle is read.
pub fn settle(world: &mut World<BridgeEndpoint>) {
    world
        .run_until(
            |w| {
                let s = w.bridge().status();
                s.link_up && (s.limits.is_some() || s.hpr.state.is_some())
            },
            Duration::from_secs(5),
        )
        .unwrap_or_else(|t| panic!("link not up: {t}\n{}", world.trace().tail(10)));
    world.run_for(Duration::from_millis(300));
}

/// An HPR / MaxPro200 world, run until the unit is ready for a start (state 3).
pub fn ready_hpr(model: Model) -> World<BridgeEndpoint> {
    let mut world = bridge_world(model);
    world
        .run_until(|w| w.bridge().status().ready, Duration::from_secs(10))
        .expect("the unit becomes ready");
    world
}

/// The value of `key=` in a reply line (up to the next space).
pub fn field<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split(' ')
        .find_map(|word| word.strip_prefix(key)?.strip_prefix('='))
}

/// A Modbus ASCII frame `:` + `body` + LRC (computed here, two's complement of the byte sum).
pub fn modbus(body: &str) -> String {
    let bytes: Vec<u8> = (0..body.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&body[i..i + 2], 16).unwrap())
        .collect();
    let lrc = bytes
        .iter()
        .fold(0u8, |a, &b| a.wrapping_add(b))
        .wrapping_neg();
    format!(":{body}{lrc:02X}")
}

/// An HPR frame `>` + `body` + checksum (byte sum modulo 256) + `<`.
pub fn hpr(body: &str) -> String {
    let sum = body.bytes().fold(0u8, |a, b| a.wrapping_add(b));
    format!(">{body}{sum:02X}<")
}

/// A Phoenix message in format 113: SOH STX message CR LF ETX EOT, then the XOR of the
/// message bytes (built here byte by byte, independently of the bridge's framer).
pub fn phoenix_113(message: &str, check: Option<u8>) -> Vec<u8> {
    let bcc = message.bytes().fold(0u8, |a, b| a ^ b);
    let mut frame = vec![0x01, 0x02];
    frame.extend_from_slice(message.as_bytes());
    frame.extend_from_slice(b"\r\n\x03\x04");
    frame.push(check.unwrap_or(bcc));
    frame
}

/// True when `line` is a well-formed CNC output line: `OK`, `OK ...`, `ERR <CODE> ...` with
/// a known code, or an event `!WORD...`; printable ASCII only.
pub fn well_formed(line: &str) -> bool {
    const CODES: [&str; 11] = [
        "SYNTAX",
        "RANGE",
        "TOOLONG",
        "BINARY",
        "STATE",
        "LINK",
        "UNSUPPORTED",
        "BUSY",
        "REFUSED",
        "STORAGE",
        "DENIED",
    ];
    let printable = line.bytes().all(|b| (0x20..0x7f).contains(&b));
    let shape = if line == "OK" || line.starts_with("OK ") {
        true
    } else if let Some(rest) = line.strip_prefix("ERR ") {
        let code = rest.split(' ').next().unwrap_or("");
        CODES.contains(&code) && rest.len() > code.len() + 1
    } else if let Some(rest) = line.strip_prefix('!') {
        rest.starts_with(|c: char| c.is_ascii_uppercase())
    } else {
        false
    };
    printable && shape
}
