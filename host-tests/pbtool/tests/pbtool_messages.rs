//! What pbtool says when something is missing or wrong: each message names the cause and the
//! remedy in the user's terms (probe-rs not installed, a file that is not a serial port, an
//! address no unit can have, what to check when no unit answers), and a Powermax fault reads
//! as the unit shows it (0-50-0).

mod common;

use std::io::Write;
use std::process::{Command, Stdio};

use common::{Cable, Pbtool, pbtool_with_input};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn run_without_probe_rs_says_it_is_not_installed_and_how_to_install_it() {
    // A PATH with no probe-rs on it, as on a fresh machine.
    let empty = std::env::temp_dir().join(format!("pbtool-no-probe-rs-{}", std::process::id()));
    std::fs::create_dir_all(&empty).expect("a directory");
    let mut run = Command::new(env!("CARGO_BIN_EXE_pbtool"))
        .args(["run", "--fast"])
        .env("PATH", &empty)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("pbtool starts");
    run.stdin
        .take()
        .expect("piped")
        .write_all(b"ID\n")
        .expect("written");
    let out = run.wait_with_output().expect("pbtool ends");
    let _ = std::fs::remove_dir(&empty);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let missing = stderr.find("probe-rs is not installed");
    let fallback = stderr.find("running the bridge against a simulated");
    assert!(missing.is_some() && missing < fallback, "{stderr}");
    assert!(
        stderr.contains("cargo install probe-rs-tools --locked"),
        "{stderr}"
    );
    assert!(!stderr.contains("no debug probe found"), "{stderr}");
    assert!(text(&out.stdout).starts_with("OK bridge="));
}

#[test]
fn a_file_is_not_a_serial_port() {
    for args in [
        &["probe", "--port", "/dev/null"][..],
        &["unit", "--ps", "pm65", "--port", "/dev/null"],
        &[
            "config",
            "--port",
            "/dev/null",
            "--cnc-framing",
            "19200:8E1",
        ],
    ] {
        let out = pbtool_with_input(args, "");
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("/dev/null is not a serial port"),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("typewriter"), "{args:?}: {stderr}");
    }
}

#[test]
fn an_address_no_unit_can_have_is_refused_with_the_ranges_the_docs_give() {
    let out = pbtool_with_input(
        &[
            "unit",
            "--ps",
            "pm65",
            "--port",
            "/dev/null",
            "--address",
            "300",
        ],
        "",
    );
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("a Powermax's node address is 1-247, an HPR's id 0-3"),
        "{stderr}"
    );
    assert!(!stderr.contains("0..=255"), "{stderr}");
}

#[test]
fn a_powermax_fault_raised_on_a_simulated_unit_reads_as_its_display_shows_it() {
    let cable = Cable::new();
    let mut unit = Pbtool::spawn(&["unit", "--ps", "pm65", "--port", &cable.b]);
    unit.expect_stderr("a simulated pm65");
    unit.send("FAULT 0-50-0");
    unit.expect_stderr("fault 0-50-0 raised");
    assert!(!unit.stderr().contains("fault 500"), "{}", unit.stderr());
}

#[test]
fn probe_shows_each_framing_it_tries_and_what_to_check_when_no_unit_answers() {
    let cable = Cable::new();
    let out = pbtool_with_input(&["probe", "--port", &cable.a, "--seconds", "1"], "");
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert_eq!(out.status.code(), Some(1), "{stdout}{stderr}");
    assert!(
        stderr.contains("round 1: Modbus at 19200 8E1, node 1"),
        "{stderr}"
    );
    assert!(
        stderr.contains("round 1: HPR HELLO at 19200 8N1"),
        "{stderr}"
    );
    for hint in ["2W/4W switch", "termination", "--address N", "+ to +"] {
        assert!(stdout.contains(hint), "{hint}: {stdout}");
    }
}
