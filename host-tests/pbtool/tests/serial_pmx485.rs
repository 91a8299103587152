//! LinuxCNC's pmx485 (the Powermax component QtPlasmaC uses), unchanged, as the master of
//! `pbtool unit` over a pty cable: a legacy Powermax65 and a SYNC unit through its legacy
//! registers. pmx485 writes mode, current and pressure, reads the limits, the settings back,
//! the fault and the arc time; it reports `status` TRUE only when every reply was exact and
//! in time. The repository's `.ci/pmx485-check` runs it in a HAL session; LinuxCNC's uspace
//! build is installed by `.ci/install-linuxcnc` (CI runs it; these tests run it once when
//! LinuxCNC is missing, as the emulated board's tests install QEMU).
//!
//! Then pmx485 drives the BRIDGE: its CNC port answers as a Powermax (`pbtool sim
//! --cnc-port` and `pbtool run --ps-port --cnc-port`) for a SYNC, a legacy and an HPR unit
//! behind it, a fault on the unit reaching pmx485's fault pin, the unit's link lost and seen
//! as pmx485's `status` FALSE, and the text protocol answering on the same port afterwards.
//! And the firmware itself: the emulated board's CNC UART on a pty (`pbtool emu --cnc-port`),
//! with a SYNC unit (and a fault) and a MaxPro200 behind it, and with pmx485 polling before
//! the board has booted.
//!
//! One HAL session per machine: `.ci/pmx485-check` queues its runs on a lock.

mod common;

use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use common::{Cable, CncEnd, Pbtool};

/// The repository's `.ci` directory (host-tests/pbtool -> the workspace).
fn ci_script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../.ci")
        .join(name)
}

/// Installs LinuxCNC with `.ci/install-linuxcnc` once per test process (it returns at once
/// when LinuxCNC is there); panics with what to install when that fails.
fn ensure_linuxcnc() {
    static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();
    let installed = INSTALLED.get_or_init(|| {
        let script = ci_script("install-linuxcnc");
        let output = Command::new("bash")
            .arg(&script)
            .stdin(Stdio::null())
            .output()
            .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
        if output.status.success() {
            return Ok(());
        }
        Err(format!(
            "{}{}",
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr)
        ))
    });
    if let Err(why) = installed {
        panic!(
            "these tests run LinuxCNC's pmx485, which is not installed, and              .ci/install-linuxcnc could not install it:\n{why}"
        );
    }
}

/// `.ci/pmx485-check` run on `port` with `args`: its status and its output.
fn pmx485_on(port: &str, args: &[&str]) -> (Output, String) {
    ensure_linuxcnc();
    let output = Command::new("bash")
        .arg(ci_script("pmx485-check"))
        .arg(port)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("bash runs .ci/pmx485-check");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    assert_ne!(
        output.status.code(),
        Some(2),
        "pmx485 could not be set up:\n{text}"
    );
    (output, text)
}

/// What QtPlasmaC asks for. `--wait` is a bound: the pins are read as soon as every
/// expectation holds, so a loaded machine only makes a passing run slower.
const AS_QTPLASMAC: [&str; 8] = ["--mode", "1", "--amps", "45", "--psi", "0", "--wait", "60"];

/// pmx485 against `pbtool unit UNIT_ARGS`; its output, having checked it passed.
fn pmx485_drives(unit_args: &[&str], expect: &[&str]) -> String {
    let cable = Cable::new();
    let mut args = vec!["unit", "--port", &cable.b, "--log"];
    args.extend_from_slice(unit_args);
    let unit = Pbtool::spawn(&args);
    let mut script_args = AS_QTPLASMAC.to_vec();
    script_args.extend_from_slice(expect);
    let (output, text) = pmx485_on(&cable.a, &script_args);
    assert!(
        output.status.success(),
        "pmx485 against pbtool {}:\n{text}\n{}",
        args.join(" "),
        unit.transcript()
    );
    text
}

/// Ask `ID` on the bridge's CNC port until its reply satisfies `wanted` (the link comes up
/// or goes down in real time); the last reply.
fn wait_for_id(cnc_port: &str, wanted: impl Fn(&str) -> bool) -> String {
    let mut cnc = CncEnd::open(cnc_port);
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        // Asked again when unanswered: an emulated board drops what came while it booted.
        let id = cnc
            .command_within("ID", Duration::from_secs(2))
            .unwrap_or_default();
        if wanted(&id) || Instant::now() > deadline {
            return id;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// pmx485 against `pbtool COMMAND --cnc-port DEV --cnc-framing 19200:8E1 UNIT` (pmx485's
/// framing; `emu`, and `run` with no board attached, set the emulated board to it with
/// CONFIG), once its link is up; the pbtool process (still running) and the script's output,
/// having checked it passed.
fn pmx485_drives_pbtool(
    cable: &Cable,
    command: &str,
    unit: &[&str],
    expect: &[&str],
) -> (Pbtool, String) {
    let mut args = vec![
        command,
        "--cnc-port",
        &cable.b,
        "--cnc-framing",
        "19200:8E1",
    ];
    args.extend_from_slice(unit);
    let pbtool = Pbtool::spawn(&args);
    let id = wait_for_id(&cable.a, |id| id.contains(" link=UP "));
    assert!(id.contains(" link=UP "), "{id}\n{}", pbtool.transcript());
    let mut script_args = AS_QTPLASMAC.to_vec();
    script_args.extend_from_slice(expect);
    let (output, text) = pmx485_on(&cable.a, &script_args);
    assert!(
        output.status.success(),
        "pmx485 against pbtool {}:\n{text}\n{}",
        args.join(" "),
        pbtool.transcript()
    );
    (pbtool, text)
}

/// pmx485 against the bridge of `pbtool sim --ps MODEL` on its CNC port; the script's output,
/// having checked it passed and that the text protocol answers afterwards.
fn pmx485_drives_the_bridge(sim_args: &[&str], expect: &[&str]) -> String {
    let cable = Cable::new();
    let (_sim, text) = pmx485_drives_pbtool(&cable, "sim", sim_args, expect);
    // The text protocol still answers on the same port after the Modbus traffic.
    let id = wait_for_id(&cable.a, |id| id.starts_with("OK bridge="));
    assert!(id.contains(" link=UP "), "{id}");
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

#[test]
fn linuxcnc_pmx485_drives_the_bridge_with_a_sync_unit_behind_it() {
    let text = pmx485_drives_the_bridge(&["--ps", "sync65"], &["--expect-limits", "20:65:58:78"]);
    assert!(text.contains("status        TRUE"), "{text}");
}

#[test]
fn linuxcnc_pmx485_sees_a_legacy_units_fault_through_the_bridge() {
    let text = pmx485_drives_the_bridge(
        &["--ps", "pm65", "--fault", "0-50-0"],
        &["--expect-limits", "20:65:63:78", "--expect-fault", "500"],
    );
    assert!(text.contains("fault         500"), "{text}");
}

#[test]
fn linuxcnc_pmx485_drives_an_hpr_through_the_bridge() {
    // An HPR260: 5-260 A from its rating, pressure automatic (limits 0), mode normal.
    pmx485_drives_the_bridge(&["--ps", "hpr260"], &["--expect-limits", "5:260:0:0"]);
}

#[test]
fn linuxcnc_pmx485_sees_the_units_link_lost_as_a_communication_error() {
    let ps = Cable::new();
    let cnc = Cable::new();
    let mut unit = Pbtool::spawn(&["unit", "--ps", "pm65", "--port", &ps.b]);
    let run = Pbtool::spawn(&[
        "run",
        "--ps-port",
        &ps.a,
        "--cnc-port",
        &cnc.b,
        "--cnc-framing",
        "19200:8E1",
    ]);
    let id = wait_for_id(&cnc.a, |id| id.contains(" link=UP "));
    assert!(id.contains(" link=UP "), "{id}\n{}", run.transcript());
    unit.send("SILENT");
    let id = wait_for_id(&cnc.a, |id| id.contains(" link=DOWN "));
    assert!(id.contains(" link=DOWN "), "{id}\n{}", run.transcript());
    // The expectations never hold here: pmx485 runs for 8 s (the bound), then its pins are read.
    let mut args = AS_QTPLASMAC;
    args[7] = "8";
    let (output, text) = pmx485_on(&cnc.a, &args);
    assert!(!output.status.success(), "{text}");
    assert!(text.contains("status        FALSE"), "{text}");
    // The text protocol still answers, and says why.
    let id = wait_for_id(&cnc.a, |id| id.starts_with("OK bridge="));
    assert!(id.contains(" link=DOWN "), "{id}");
}

#[test]
fn linuxcnc_pmx485_drives_a_maxpro200_through_the_emulated_board() {
    // `pbtool run --cnc-port` without a board: the emulated board's CNC port on the device.
    // 5-200 A from the unit; mode normal and pressure automatic, as for an HPR.
    let cable = Cable::new();
    let (run, text) = pmx485_drives_pbtool(
        &cable,
        "run",
        &["--ps", "maxpro200"],
        &["--expect-limits", "5:200:0:0"],
    );
    assert!(text.contains("current       45"), "{text}");
    run.expect_stderr("running the firmware on the emulated board against a simulated maxpro200");
}

#[test]
fn linuxcnc_pmx485_drives_the_emulated_board() {
    let cable = Cable::new();
    let (emu, text) = pmx485_drives_pbtool(
        &cable,
        "emu",
        &["--ps", "sync65", "--fault", "0-50-0"],
        &["--expect-limits", "20:65:58:78", "--expect-fault", "500"],
    );
    assert!(text.contains("current       45"), "{text}");

    // The text protocol answers on the same port after the Modbus traffic, and the board's
    // UART follows CONFIG at once: the reply comes at 19200, then the CNC's 19200 8E1 line
    // no longer reaches it.
    let mut cnc = CncEnd::open(&cable.a);
    let id = cnc.command("ID").unwrap_or_default();
    assert!(id.starts_with("OK bridge="), "{id}\n{}", emu.transcript());
    assert_eq!(
        cnc.command("CONFIG cnc_baud 9600").as_deref(),
        Some("OK cnc_baud=9600"),
        "{}",
        emu.transcript()
    );
    assert_eq!(cnc.command_within("ID", Duration::from_secs(2)), None);
    emu.expect_stderr("the board's CNC UART now runs 9600 8E1, the CNC's line 19200 8E1");
}

#[test]
fn linuxcnc_pmx485_polling_before_the_emulated_board_boots_connects_once_it_is_up() {
    // pmx485 starts first and polls an empty line while QEMU boots; what it sent meanwhile
    // must not be answered late (every reply would then be one behind, and pmx485 never
    // catches up). pmx485 retries for ever: the script reads its pins once every expectation
    // holds, within a bound generous enough for the board's build and boot on a loaded
    // machine, instead of a fixed run.
    let cable = Cable::with_taps(1);
    let port = cable.a.clone();
    let pmx485 = std::thread::spawn(move || {
        let mut args = AS_QTPLASMAC.to_vec();
        args[7] = "600";
        args.extend_from_slice(&["--expect-limits", "20:65:58:78"]);
        pmx485_on(&port, &args)
    });
    // Its requests on the line: pmx485 is polling. The tap is read until the cable goes
    // (a tap nobody reads fills up and holds the whole cable).
    let mut tap = serialport::new(&cable.taps[0], 19_200)
        .timeout(Duration::from_millis(100))
        .open()
        .expect("the tap opens");
    let (polling, heard) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut seen = Vec::new();
        let mut buf = [0u8; 256];
        loop {
            match tap.read(&mut buf) {
                Ok(n) => seen.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(_) => return,
            }
            if String::from_utf8_lossy(&seen).contains(":01") {
                let _ = polling.send(());
                seen.clear();
            }
        }
    });
    assert!(
        heard.recv_timeout(Duration::from_secs(300)).is_ok(),
        "pmx485 never polled"
    );
    let emu = Pbtool::spawn(&[
        "emu",
        "--cnc-port",
        &cable.b,
        "--cnc-framing",
        "19200:8E1",
        "--ps",
        "sync65",
    ]);
    let (output, text) = pmx485.join().expect("the pmx485 run ends");
    assert!(output.status.success(), "{text}\n{}", emu.transcript());
    assert!(text.contains("status        TRUE"), "{text}");
    // Said before the board's port was relayed, so before pmx485 could see its link up (the
    // board's build and boot can take longer than any fixed wait on a loaded machine).
    assert!(
        emu.stderr()
            .contains("characters the CNC sent while the board was booting"),
        "{}",
        emu.transcript()
    );
}
