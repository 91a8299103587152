//! `pbtool emu` (`cargo emu`) and `pbtool run` without a probe: the firmware on the emulated
//! board with the CNC port on stdin/stdout, as a person (or a script) uses it.

mod common;

use std::process::Output;

use common::{Pbtool, pbtool_with_input as pbtool};

fn lines(output: &Output) -> Vec<String> {
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn emu_gives_the_cnc_console_of_the_emulated_board() {
    // Line by line, each after the condition it depends on: TORCH OFF sent right after TORCH
    // ON can reach the board within the start gap (which counts from the boot), and START
    // then never comes on.
    let mut emu = Pbtool::spawn(&["emu", "--ps", "sync65", "--events", "--log"]);
    emu.send("ID");
    let id = emu.expect_prefix("OK bridge=");
    assert!(
        id.starts_with("OK bridge=plasma-bridge version=0.1.0 reset=power-on"),
        "{id}"
    );
    assert!(id.contains(" link=UP "), "{id}");
    emu.send("TORCH ON");
    emu.expect("OK torch=ON", |l| l == "OK torch=ON");
    // "torch-on from CNC", or "torch-on held through the gap between starts" when TORCH ON
    // came within the first 50 ms of guest time.
    emu.expect_stderr("START on: torch-on ");
    emu.send("STATUS");
    emu.expect_prefix("OK link=UP ");
    emu.send("TORCH OFF");
    emu.expect("OK torch=OFF", |l| l == "OK torch=OFF");
    let stderr = emu.expect_stderr("START off: torch-on released");
    assert!(
        stderr.find("START on: torch-on ") < stderr.find("START off: torch-on released"),
        "{stderr}"
    );
    emu.send("STATUS");
    emu.expect_prefix("OK link=UP ");
    // The board is no simulator, and TORCH worked: pbtool says whose TORCH it is.
    emu.send("HELP");
    emu.expect("HELP's reply", |l| l.ends_with(" simulator=NO"));
    emu.close_stdin();
    assert!(emu.wait().success(), "{}", emu.transcript());
    let transcript = emu.transcript();
    // --events: on before the link came up, as its help says.
    assert!(transcript.contains("\n!LINK UP "), "{transcript}");
    assert!(
        transcript.contains("TORCH ON|OFF also work here: pbtool, not the board"),
        "{transcript}"
    );
    // --log: the firmware's own log on stderr, decoded.
    assert!(
        transcript.contains("INFO  plasma-bridge 0.1.0 on the emulated STM32L475VG"),
        "{transcript}"
    );
}

#[test]
fn emu_drives_two_units_on_one_line_and_at_n_torch_on_starts_unit_n_only() {
    let mut emu = Pbtool::spawn(&["emu", "--ps", "hpr260", "--ps", "hpr130"]);
    // The second unit answers for itself: the board was told both (`CONFIG units`).
    emu.send("@2 ID");
    let id = emu.expect_prefix("OK bridge=");
    assert!(id.split(' ').any(|w| w == "unit=2"), "{id}");
    assert!(id.contains(" model=HPR130 "), "{id}");
    // A TORCH_ON the unit is not ready for stays refused until released: wait for READY
    // (an HPR purges for about 2 s), asking at most 300 times (each a full CNC round trip).
    let mut ready = false;
    for _ in 0..300 {
        emu.send("@2 STATUS");
        let status = emu.expect_prefix("OK link=");
        if status.contains(" link=UP ") && status.contains(" ready=ON") {
            ready = true;
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    assert!(ready, "unit 2 never ready\n{}", emu.transcript());
    emu.send("@2 TORCH ON");
    emu.expect("OK torch=ON unit=2", |l| l == "OK torch=ON unit=2");
    // Unit 2's START is on (the console answers once it followed), unit 1's is not.
    emu.send("@2 STATUS");
    let second = emu.expect_prefix("OK link=");
    assert!(second.contains(" start=ON "), "{second}");
    emu.send("STATUS");
    let first = emu.expect_prefix("OK link=");
    assert!(first.contains(" start=OFF "), "{first}");
    emu.send("@2 TORCH OFF");
    emu.expect("OK torch=OFF unit=2", |l| l == "OK torch=OFF unit=2");
    emu.close_stdin();
    assert!(emu.wait().success(), "{}", emu.transcript());
}

#[test]
fn run_without_a_probe_boots_the_emulated_board() {
    let output = pbtool(&["run", "--ps", "pm85"], "ID\nCLOCK\n");
    let stderr = String::from_utf8_lossy(&output.stderr);
    if stderr.contains("flashing the board image") {
        return; // A board is attached: `run` flashes it.
    }
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("running the firmware on the emulated board"),
        "{stderr}"
    );
    let lines = lines(&output);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(lines[0].contains("family=LEGACY"), "{lines:?}");
    assert!(lines[0].contains("reset=power-on"), "{lines:?}");
    // `run` is the bridge: the board's clock is the PC's from the start.
    assert!(lines[1].starts_with("OK clock=20"), "{lines:?}");
}

#[test]
fn run_without_a_probe_boots_the_emulated_board_for_several_units() {
    let output = pbtool(&["run", "--ps", "hpr260", "--ps", "hpr130"], "@2 ID\n");
    let stderr = String::from_utf8_lossy(&output.stderr);
    if stderr.contains("flashing the board image") {
        return; // A board is attached: `run` flashes it.
    }
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("running the firmware on the emulated board against 2 simulated units"),
        "{stderr}"
    );
    let lines = lines(&output);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(lines[0].contains(" model=HPR130 "), "{lines:?}");
    assert!(lines[0].split(' ').any(|w| w == "unit=2"), "{lines:?}");
}

#[test]
fn history_from_the_emulated_board() {
    let output = pbtool(
        &[
            "history", "--emu", "--ps", "sync65", "--fault", "0-50-0", "--csv",
        ],
        "",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let lines = lines(&output);
    assert_eq!(
        lines[0], "seq,boot,uptime_ms,clock,unit,family,model,event,details",
        "{lines:?}"
    );
    // Newest first: the unit's fault, then the board's reset; both of this boot, whose clock
    // pbtool set.
    let fault = lines
        .iter()
        .position(|l| l.contains(",FAULT,\"code=0-50-0 action=required\""))
        .unwrap_or_else(|| panic!("no fault entry: {lines:?}"));
    // The model as the bridge knew it then: a fault read at power-up comes before the exact
    // size (0x3000), so `Powermax65/85/105` or `Powermax65`.
    assert!(
        lines[fault].contains(",SYNC,Powermax65"),
        "{}",
        lines[fault]
    );
    let reset = lines
        .iter()
        .position(|l| l.ends_with(",RESET,cause=power-on"))
        .unwrap_or_else(|| panic!("no reset entry: {lines:?}"));
    assert!(fault < reset, "{lines:?}");
    assert!(!lines[reset].contains(",-,-,-,RESET"), "a clock: {lines:?}");
}
