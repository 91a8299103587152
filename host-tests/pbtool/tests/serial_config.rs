//! `pbtool config` on a pty cable against the bridge of `pbtool sim --cnc-port`: it finds the
//! board, switches the CNC port's framing one setting at a time with both ends following, and
//! saves it; with nothing on the line it says where to look. (A pty carries every framing, so
//! the board's own `CONFIG` reply is what tells its framing here.)

mod common;

use common::{Cable, CncEnd, Pbtool, pbtool_with_input};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `pbtool sim --cnc-port` on the cable's b end, once it has opened the port.
fn bridge_on(cable: &Cable) -> Pbtool {
    let sim = Pbtool::spawn(&["sim", "--ps", "sync65", "--cnc-port", &cable.b]);
    sim.expect_stderr("CNC protocol on");
    sim
}

#[test]
fn config_switches_the_cnc_port_to_pmx485s_framing_in_order_and_saves_it() {
    let cable = Cable::new();
    let sim = bridge_on(&cable);
    let out = pbtool_with_input(
        &[
            "config",
            "--port",
            &cable.a,
            "--cnc-framing",
            "19200:8E1",
            "--save",
        ],
        "",
    );
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}{stderr}{}", sim.transcript());
    assert!(
        stdout.contains("runs 19200 8E1 (was 115200 8N1); saved"),
        "{stdout}"
    );
    let baud = stderr.find("CONFIG cnc_baud 19200: both ends now 19200 8N1");
    let parity = stderr.find("CONFIG cnc_parity EVEN: both ends now 19200 8E1");
    assert!(
        baud.is_some() && parity.is_some() && baud < parity,
        "{stderr}"
    );

    let config = CncEnd::open(&cable.a).command("CONFIG").unwrap_or_default();
    assert!(
        config.contains("cnc_baud=19200 cnc_parity=EVEN cnc_stop_bits=1"),
        "{config}"
    );

    // Run again: nothing to change.
    let again = pbtool_with_input(
        &["config", "--port", &cable.a, "--cnc-framing", "19200:8E1"],
        "",
    );
    assert!(again.status.success(), "{}", text(&again.stderr));
    assert!(
        text(&again.stdout).contains("runs 19200 8E1 (already); not saved"),
        "{}",
        text(&again.stdout)
    );
}

/// A Phoenix messaging port at 4800 baud, 7 data bits, even parity (Phoenix manual,
/// 003_610fea73110d789e.txt lines 7012 and 7043: 1200 to 115200 baud, 7 or 8 data bits). A pty
/// carries bytes whatever its settings, so this shows the plumbing: both ends take 7 data bits
/// step by step, and the bridge still answers at the new framing.
#[test]
fn config_switches_the_cnc_port_to_a_phoenix_ports_seven_data_bits() {
    let cable = Cable::new();
    let sim = bridge_on(&cable);
    let out = pbtool_with_input(
        &["config", "--port", &cable.a, "--cnc-framing", "4800:7E1"],
        "",
    );
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "{stdout}{stderr}{}", sim.transcript());
    assert!(
        stdout.contains("runs 4800 7E1 (was 115200 8N1)"),
        "{stdout}"
    );
    assert!(
        stderr.contains("CONFIG cnc_data_bits 7: both ends now 4800 7N1"),
        "{stderr}"
    );
    let config = CncEnd::open(&cable.a).command("CONFIG").unwrap_or_default();
    assert!(
        config.contains("cnc_baud=4800 cnc_parity=EVEN cnc_stop_bits=1 cnc_data_bits=7"),
        "{config}"
    );
}

#[test]
fn config_with_no_bridge_on_the_line_tries_every_framing_and_says_where_to_look() {
    let cable = Cable::new();
    let out = pbtool_with_input(
        &["config", "--port", &cable.a, "--cnc-framing", "19200:8E1"],
        "",
    );
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no answer at 19200 8E1"), "{stderr}");
    assert!(stderr.contains("no answer at 9600 8O2"), "{stderr}");
    assert!(stderr.contains("no answer at 1200 7E1"), "{stderr}");
    assert!(
        stderr.contains("no bridge answered ID at any framing"),
        "{stderr}"
    );
}
