//! `pbtool unit` with several units on one port: two HPRs on a pty cable, a client that
//! talks to each by SLEEP (086) and WAKE (085), and what it hears when it forgets the SLEEP
//! (both units answering at once); Powermax units at node addresses in order; and a set of
//! units that cannot share a line, refused.

mod common;

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use common::{Cable, LONG, Pbtool, pbtool_with_input};
use serialport::SerialPort;

/// The CNC's end of an HPR line: frames out, whatever comes back read up to a frame's end.
struct HprClient {
    port: Box<dyn SerialPort>,
    heard: Vec<u8>,
}

impl HprClient {
    /// Opens `device` at the HPR's 19200 8N1.
    fn open(device: &str) -> HprClient {
        let port = serialport::new(device, 19_200)
            .timeout(Duration::from_millis(100))
            .open()
            .expect("the client's end opens");
        HprClient {
            port,
            heard: Vec::new(),
        }
    }

    /// Sends command `id` with `data`.
    fn send(&mut self, id: u16, data: &str) {
        self.port
            .write_all(frame(id, data).as_bytes())
            .expect("written");
    }

    /// Everything heard up to and including `frame`, which it waits for (panics with what was
    /// heard when it has not come within [`LONG`]).
    fn until(&mut self, frame: &str) -> String {
        self.within(frame, LONG).unwrap_or_else(|| {
            panic!(
                "no {frame:?}; heard {:?}",
                String::from_utf8_lossy(&self.heard)
            )
        })
    }

    /// Everything heard up to and including `frame` if it comes within `timeout`; else
    /// nothing is taken.
    fn within(&mut self, frame: &str, timeout: Duration) -> Option<String> {
        let deadline = Instant::now() + timeout;
        let mut buf = [0u8; 256];
        loop {
            let text = String::from_utf8_lossy(&self.heard).into_owned();
            if let Some(at) = text.find(frame) {
                let end = at + frame.len();
                self.heard.drain(..end);
                return Some(text[..end].to_string());
            }
            if Instant::now() >= deadline {
                return None;
            }
            match self.port.read(&mut buf) {
                Ok(n) => self.heard.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) => panic!("the client's port failed: {e}"),
            }
        }
    }

    /// Sends a command and returns the next reply frame, which must be `expected`: nothing
    /// else may come before it.
    fn ask(&mut self, id: u16, data: &str, expected: &str) {
        self.send(id, data);
        let heard = self.until(expected);
        assert_eq!(heard, expected);
    }
}

/// `>` id data checksum `<` (HPR manual lines 123-130), the checksum the low byte of the sum
/// of the id and data characters in hex (the manual's samples: `>00090<`, `>0850CD<`).
fn frame(id: u16, data: &str) -> String {
    let text = format!("{id:03}{data}");
    let sum = text.bytes().fold(0u8, |acc, b| acc.wrapping_add(b));
    format!(">{text}{sum:02X}<")
}

fn hello(amps: u16) -> String {
    frame(0, &format!("HYPERFORMANCE{amps}AUTO"))
}

/// `pbtool unit --ps hpr260 --ps hpr400` on one end of a cable, a client on the other.
fn two_hprs(cable: &Cable) -> (Pbtool, HprClient) {
    let unit = Pbtool::spawn(&[
        "unit", "--ps", "hpr260", "--ps", "hpr400", "--port", &cable.b, "--log",
    ]);
    // The port is open and set once it says what it serves.
    let banner = unit.expect_stderr(" on one line");
    assert!(
        banner.contains("@1 hpr260 (id 0), @2 hpr400 (id 1)"),
        "{banner}"
    );
    (unit, HprClient::open(&cable.a))
}

// HPR manual (002_72b43a5685974c77.txt) lines 107-109: id 0 powers up talking; SLEEP (086)
// puts every system to sleep, WAKE (085) with an id wakes that one; lines 172-173: WAKE is
// echoed, SLEEP has no response.
#[test]
fn a_client_talks_to_two_hprs_in_turn_by_sleep_and_wake() {
    let cable = Cable::new();
    let (unit, mut client) = two_hprs(&cable);
    client.ask(0, "", &hello(260));
    client.send(86, "");
    client.ask(85, "1", &frame(85, "1"));
    client.ask(0, "", &hello(400));
    client.send(86, "");
    client.ask(85, "0", ">0850CD<");
    client.ask(0, "", &hello(260));
    let log = unit.kill();
    assert!(log.contains("tx @2 >0851CE<"), "{log}");
    assert!(!log.contains("collision"), "{log}");
}

// HPR manual line 109: the SLEEP must come before the next WAKE. Without it, both units are
// awake and both answer.
#[test]
fn a_client_that_forgets_the_sleep_hears_two_units_at_once() {
    let cable = Cable::new();
    let (unit, mut client) = two_hprs(&cable);
    client.ask(85, "1", ">0851CE<");
    client.send(0, "");
    unit.expect_stderr("collision: two units answering at once");
    // Put right (SLEEP, WAKE 1), only unit 2 answers. Its first replies may still meet the
    // tail of unit 1's colliding one, so the master asks until it hears a clean reply; what
    // came before it is the collision.
    let deadline = Instant::now() + LONG;
    let heard = loop {
        assert!(
            Instant::now() < deadline,
            "no clean reply; heard {:?}",
            String::from_utf8_lossy(&client.heard)
        );
        client.send(86, "");
        client.send(85, "1");
        client.send(0, "");
        if let Some(until) = client.within(&hello(400), Duration::from_secs(1)) {
            break until[..until.len() - hello(400).len()].to_string();
        }
    };
    assert!(
        !heard.contains(&hello(260)) && !heard.contains(&hello(400)),
        "{heard:?}"
    );
    client.ask(0, "", &hello(400));
    let log = unit.kill();
    // Each unit sent its whole reply; the port carried them on top of each other.
    assert!(log.contains(&format!("tx @1 {}", hello(260))), "{log}");
    assert!(log.contains(&format!("tx @2 {}", hello(400))), "{log}");
}

// SYNC manual (000_dd931256418ae627.txt) lines 389-391: several Powermax units, each at its own
// node address.
#[test]
fn powermax_units_share_a_port_at_node_addresses_in_order() {
    let cable = Cable::new();
    let unit = Pbtool::spawn(&[
        "unit",
        "--ps",
        "sync65",
        "--ps",
        "pm65",
        "--address",
        "5",
        "--port",
        &cable.b,
    ]);
    let banner = unit.expect_stderr(" on one line");
    assert!(
        banner.contains("@1 sync65 (node 5), @2 pm65 (node 6)"),
        "{banner}"
    );
    let mut client = serialport::new(&cable.a, 19_200)
        .parity(serialport::Parity::Even)
        .timeout(Duration::from_millis(100))
        .open()
        .expect("the client's end opens");
    // Each node's read of holding register 0x2093 is answered by that node alone; node 7 by
    // nobody, so the node 5 reply after it is the next thing heard.
    let mut heard = Vec::new();
    for node in [5u8, 6, 7, 5] {
        client
            .write_all(&modbus_request(node, &[0x03, 0x20, 0x93, 0x00, 0x01]))
            .expect("written");
        if node == 7 {
            continue;
        }
        let deadline = Instant::now() + LONG;
        let mut buf = [0u8; 64];
        while !heard.ends_with(b"\r\n") {
            assert!(
                Instant::now() < deadline,
                "no reply from node {node}: {heard:?}"
            );
            match client.read(&mut buf) {
                Ok(n) => heard.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) => panic!("the client's port failed: {e}"),
            }
        }
        let reply = String::from_utf8_lossy(&heard).into_owned();
        assert!(reply.starts_with(&format!(":{node:02X}03")), "{reply:?}");
        heard.clear();
    }
}

/// A Modbus ASCII request: `:`, address and PDU in hex, LRC (the two's complement of their
/// sum), CR LF.
fn modbus_request(node: u8, pdu: &[u8]) -> Vec<u8> {
    let bytes: Vec<u8> = std::iter::once(node).chain(pdu.iter().copied()).collect();
    let lrc = bytes
        .iter()
        .fold(0u8, |acc, &b| acc.wrapping_add(b))
        .wrapping_neg();
    let hex: String = bytes.iter().map(|b| format!("{b:02X}")).collect();
    format!(":{hex}{lrc:02X}\r\n").into_bytes()
}

#[test]
fn units_that_cannot_share_a_line_are_refused() {
    let cable = Cable::new();
    let refused = |units: &[&str], reason: &str| {
        let mut args = vec!["unit", "--port", &cable.b];
        for model in units {
            args.extend_from_slice(&["--ps", model]);
        }
        let out = pbtool_with_input(&args, "");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(reason), "{stderr}");
    };
    refused(
        &["sync65", "hpr260"],
        "sync65 and hpr260 cannot share a line",
    );
    refused(&["hpr260", "maxpro200"], "no WAKE/SLEEP");
    refused(
        &["sync65", "sync65"],
        "give several units a node address, 1-255",
    );
    refused(&["hpr260"; 5], "at most 4 units");
}
