//! `pbtool emu` (`cargo emu`) and `pbtool run` without a probe: the firmware on the emulated
//! board with the CNC port on stdin/stdout, as a person (or a script) uses it.

mod common;

use std::process::Output;

use common::pbtool_with_input as pbtool;

fn lines(output: &Output) -> Vec<String> {
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn emu_gives_the_cnc_console_of_the_emulated_board() {
    let output = pbtool(
        &["emu", "--ps", "sync65", "--events", "--log"],
        "ID\nTORCH ON\nSTATUS\nTORCH OFF\nSTATUS\nHELP\n",
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let lines = lines(&output);
    let replies: Vec<&String> = lines.iter().filter(|l| !l.starts_with('!')).collect();
    assert_eq!(replies.len(), 6, "{lines:#?}\n{stderr}");
    // --events: on before the link came up, as its help says.
    assert!(
        lines.iter().any(|l| l.starts_with("!LINK UP ")),
        "{lines:#?}"
    );
    assert!(
        replies[0].starts_with("OK bridge=plasma-bridge version=0.1.0 reset=power-on"),
        "{lines:#?}"
    );
    assert!(replies[0].contains(" link=UP "), "{lines:#?}");
    assert_eq!(replies[1], "OK torch=ON");
    assert!(replies[2].starts_with("OK link=UP "), "{lines:#?}");
    assert_eq!(replies[3], "OK torch=OFF");
    assert!(replies[4].starts_with("OK link=UP "), "{lines:#?}");
    // The board is no simulator, and TORCH worked: pbtool says whose TORCH it is.
    assert!(replies[5].ends_with(" simulator=NO"), "{lines:#?}");
    assert!(
        stderr.contains("TORCH ON|OFF also work here: pbtool, not the board"),
        "{stderr}"
    );
    // (STATUS shows the bridge's last view of the outputs, which a loaded host may deliver
    // a little after the pin changed: the firmware's log says what START did.)
    // --log: the firmware's own log on stderr, decoded.
    assert!(
        stderr.contains("INFO  plasma-bridge 0.1.0 on the emulated STM32L475VG"),
        "{stderr}"
    );
    // "torch-on from CNC", or "torch-on held through the gap between starts" when TORCH ON
    // came within the first 50 ms of guest time (the start gap counts from the boot).
    let on = stderr.find("START on: torch-on ").expect("START on logged");
    let off = stderr
        .find("START off: torch-on released")
        .expect("START off logged");
    assert!(on < off, "{stderr}");
}

#[test]
fn run_without_a_probe_boots_the_emulated_board() {
    let output = pbtool(&["run", "--ps", "pm85"], "ID\n");
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
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(lines[0].contains("family=LEGACY"), "{lines:?}");
    assert!(lines[0].contains("reset=power-on"), "{lines:?}");
}
