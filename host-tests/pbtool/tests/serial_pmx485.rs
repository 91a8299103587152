//! LinuxCNC's pmx485 (the Powermax component QtPlasmaC uses), unchanged, as the master of
//! `pbtool unit` over a pty cable: a legacy Powermax65 and a SYNC unit through its legacy
//! registers. pmx485 writes mode, current and pressure, reads the limits, the settings back,
//! the fault and the arc time; it reports `status` TRUE only when every reply was exact and
//! in time. The script (../shared/peers/pmx485-vs.sh, beside the checkout) needs LinuxCNC's
//! uspace build: ../shared/peers/install.sh installs it (CI runs it).

mod common;

use std::path::PathBuf;
use std::process::Command;

use common::{Cable, Pbtool};

fn peers() -> PathBuf {
    // host-tests/pbtool -> the checkout -> the shared directory beside it.
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/peers")
}

/// pmx485 against `pbtool unit UNIT_ARGS`; its output, having checked it passed.
fn pmx485_drives(unit_args: &[&str], expect: &[&str]) -> String {
    let script = peers().join("pmx485-vs.sh");
    assert!(
        script.exists(),
        "{} is missing: the shared directory must sit beside the checkout",
        script.display()
    );
    let cable = Cable::new();
    let mut args = vec!["unit", "--port", &cable.b, "--log"];
    args.extend_from_slice(unit_args);
    let unit = Pbtool::spawn(&args);
    let output = Command::new("bash")
        .arg(&script)
        .arg(&cable.a)
        .args(["--mode", "1", "--amps", "45", "--psi", "0", "--wait", "4"])
        .args(expect)
        .output()
        .expect("bash runs the script");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert_ne!(
        output.status.code(),
        Some(2),
        "pmx485 could not be set up (run ../shared/peers/install.sh once):\n{text}"
    );
    assert!(
        output.status.success(),
        "pmx485 against pbtool {}:\n{text}\n{}",
        args.join(" "),
        unit.transcript()
    );
    text
}

#[test]
fn linuxcnc_pmx485_drives_a_legacy_and_a_sync_unit() {
    // The realtime session is one per machine: both runs in one test, one after the other.
    let legacy = pmx485_drives(
        &["--ps", "pm65", "--fault", "0-50-0"],
        &[
            "--expect-limits",
            "20:65:63:78",
            "--expect-fault",
            "500",
            "--expect-arctime",
            "0",
        ],
    );
    assert!(legacy.contains("status        TRUE"), "{legacy}");
    let sync = pmx485_drives(
        &["--ps", "sync65"],
        &["--expect-limits", "20:65:58:78", "--expect-arctime", "0"],
    );
    assert!(sync.contains("current       45"), "{sync}");
}
