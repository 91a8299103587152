//! `pbtool sniff` on the taps of a pty cable while `pbtool run` talks to `pbtool unit`: a
//! 4-wire line (one port per direction) and a 2-wire bus (one port for both).

mod common;

use common::{Cable, Pbtool};

/// A short session on `cable`, then, once the sniffer's output shows what `heard` looks for,
/// the cable unplugged: the sniffer's whole output.
fn sniff_a_session(
    cable: &mut Cable,
    model: &str,
    sniff_args: &[&str],
    heard: impl Fn(&str) -> bool,
) -> (Pbtool, String) {
    let mut args = vec!["sniff"];
    for tap in &cable.taps {
        args.extend(["--port", tap.as_str()]);
    }
    args.extend_from_slice(sniff_args);
    let mut sniff = Pbtool::spawn(&args);
    // Listening before the first frame passes.
    let deadline = std::time::Instant::now() + common::LONG;
    while !sniff.stderr().contains("listening on") {
        assert!(
            std::time::Instant::now() < deadline,
            "{}",
            sniff.transcript()
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let _unit = Pbtool::spawn(&["unit", "--ps", model, "--port", &cable.b]);
    let mut run = Pbtool::spawn(&["run", "--ps-port", &cable.a]);
    run.send("STATUS");
    run.expect_prefix("OK link=UP");
    run.close_stdin();
    assert!(run.wait().success(), "{}", run.transcript());
    // The last reply has passed the tap, but the sniffer may not have printed it yet: wait
    // for what the test looks for, then unplug (the sniffer stops when its ports go away).
    let deadline = std::time::Instant::now() + common::LONG;
    while !heard(&sniff.transcript()) {
        assert!(
            std::time::Instant::now() < deadline,
            "{}",
            sniff.transcript()
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    cable.unplug();
    let exit = sniff.wait();
    assert_eq!(exit.code(), Some(2), "{}", sniff.transcript());
    let transcript = sniff.transcript();
    (sniff, transcript)
}

#[test]
fn a_4_wire_line_is_decoded_in_both_directions_with_replies_paired() {
    let mut cable = Cable::with_taps(2);
    // Some reply paired, not the first: during detection the bridge sends its next request
    // as soon as a reply is in, and two ports' frames of the same millisecond are ordered by
    // when each port's reader ran, which a loaded machine delays (seen: reply #1 printed
    // after request #2). The polls after detection leave room between exchanges.
    let (_, out) = sniff_a_session(&mut cable, "sync65", &[], |out| {
        out.contains("Read Device Identification, REPLY")
            && out.contains("product code 081335")
            && out.contains("reply to #")
    });
    let request_tap = format!("  {}  :", cable.taps[0]);
    let reply_tap = format!("  {}  :", cable.taps[1]);
    assert!(out.contains(&request_tap), "{out}");
    assert!(out.contains(&reply_tap), "{out}");
    assert!(out.contains("Read Device Identification, REQUEST"), "{out}");
    assert!(out.contains("Read Device Identification, REPLY"), "{out}");
    assert!(
        out.contains("Powermax65/85/105 SYNC (product code 081335)"),
        "{out}"
    );
    assert!(out.contains("reply to #"), "{out}");
    assert!(!out.contains("bad checksum"), "{out}");
}

#[test]
fn a_2_wire_bus_is_decoded_as_json_objects() {
    let mut cable = Cable::with_taps(1);
    let (sniff, _) = sniff_a_session(
        &mut cable,
        "hpr260",
        &["--json", "--framing", "8N1"],
        |out| out.contains(">000HYPERFORMANCE") && out.contains("got no reply"),
    );
    let frames: Vec<serde_json::Value> = sniff
        .transcript()
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    let kinds: Vec<&str> = frames
        .iter()
        .filter_map(|f| f["decoded"]["kind"].as_str())
        .collect();
    assert!(
        kinds.contains(&"request") && kinds.contains(&"reply"),
        "{frames:?}"
    );
    let hello_reply = frames
        .iter()
        .find(|f| {
            f["text"]
                .as_str()
                .is_some_and(|t| t.starts_with(">000HYPERFORMANCE"))
        })
        .expect("the HELLO reply was heard");
    let request = &frames[hello_reply["reply_to"].as_u64().expect("paired") as usize - 1];
    assert!(
        request["text"].as_str().unwrap().starts_with(">000"),
        "{request}"
    );
    assert_eq!(hello_reply["decoded"]["protocol"], "hpr");
    // Detection asked in Modbus first: those requests went unanswered, and say so.
    assert!(
        frames
            .iter()
            .any(|f| f["flags"].to_string().contains("got no reply")),
        "{frames:?}"
    );
}
