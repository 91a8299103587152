//! `pbtool probe` on a pty cable: it finds a SYNC, a legacy Powermax and an HPR served by
//! `pbtool unit`, reads them without writing anything, and reports none on a silent line.

mod common;

use common::{Cable, Pbtool};
use serde_json::Value;

/// Probes `pbtool unit UNIT_ARGS`; the JSON report and the unit's log.
fn probe(unit_args: &[&str]) -> (Value, String) {
    probe_with(unit_args, &[])
}

/// Probes `pbtool unit UNIT_ARGS` with `pbtool probe PROBE_ARGS`.
fn probe_with(unit_args: &[&str], probe_args: &[&str]) -> (Value, String) {
    let cable = Cable::new();
    let mut args = vec!["unit", "--port", &cable.b, "--log"];
    args.extend_from_slice(unit_args);
    let unit = Pbtool::spawn(&args);
    let mut args = vec!["probe", "--port", &cable.a, "--json"];
    args.extend_from_slice(probe_args);
    let mut probe = Pbtool::spawn(&args);
    probe.close_stdin();
    let line = probe.expect("the JSON report", |l| l.starts_with('{'));
    assert!(probe.wait().success(), "{}", probe.transcript());
    let report: Value = serde_json::from_str(&line).expect("one JSON object");
    // The unit logs each request before it answers, and the probe has had every answer: the
    // log is complete once the unit has ended and its stderr has been read to the end.
    (report, unit.kill())
}

fn reply_text(report: &Value, what: &str) -> String {
    report["readings"]
        .as_array()
        .expect("readings")
        .iter()
        .find(|r| r["what"] == what)
        .unwrap_or_else(|| panic!("no reading {what}: {report}"))["reply"]["text"]
        .to_string()
}

fn assert_read_only(log: &str) {
    assert!(log.contains("REQUEST"), "{log}");
    for write in ["Write", "REMOTE_MODE", "SET_"] {
        assert!(!log.contains(write), "the probe sent {write}:\n{log}");
    }
}

#[test]
fn a_sync_unit_is_found_and_read() {
    let (report, log) = probe(&["--ps", "sync65", "--fault", "0-50-0"]);
    assert_eq!(report["family"], "SYNC", "{report}");
    assert_eq!(report["framing"], "19200 8E1");
    assert!(
        report["identity"].to_string().contains("081335"),
        "{report}"
    );
    let fault = reply_text(&report, "active fault");
    assert!(
        fault.contains("0-50-0") && fault.contains("action required"),
        "{fault}"
    );
    assert!(reply_text(&report, "permitted maximum current").contains("65 A"));
    assert_read_only(&log);
}

#[test]
fn a_unit_at_another_node_address_is_found_there() {
    let (report, log) = probe_with(&["--ps", "sync85", "--address", "7"], &["--address", "7"]);
    assert_eq!(report["family"], "SYNC", "{report}");
    assert_eq!(report["identity"]["address"], 7, "{report}");
    assert!(log.contains("node 7"), "{log}");
}

#[test]
fn a_legacy_powermax_is_found_and_read() {
    let (report, log) = probe(&["--ps", "pm65"]);
    assert_eq!(report["family"], "LEGACY", "{report}");
    let readings = report["readings"].as_array().expect("readings");
    assert!(readings.iter().all(|r| !r["reply"].is_null()), "{report}");
    assert_read_only(&log);
}

#[test]
fn an_hpr_is_found_and_read() {
    let (report, log) = probe(&["--ps", "hpr260", "--fault", "80"]);
    assert_eq!(report["family"], "HPR", "{report}");
    assert_eq!(report["framing"], "19200 8N1");
    assert!(
        reply_text(&report, "GET_STATE").contains("state"),
        "{report}"
    );
    assert!(
        reply_text(&report, "CURRENT_ERROR").contains("080"),
        "{report}"
    );
    assert!(
        reply_text(&report, "GET_TIMER_COUNTER").contains("starts"),
        "{report}"
    );
    assert_read_only(&log);
}

#[test]
fn a_silent_line_has_no_unit() {
    let cable = Cable::new();
    let mut probe = Pbtool::spawn(&["probe", "--port", &cable.a, "--seconds", "2"]);
    probe.close_stdin();
    let line = probe.expect_prefix("no unit answered");
    assert!(line.contains(&cable.a), "{line}");
    assert_eq!(probe.wait().code(), Some(1), "{}", probe.transcript());
}
