//! `pbtool sim`: the binary, fed through a pipe as a script or a person would.

mod common;

use std::process::Output;

use plasma_sim::Model;

/// Run `pbtool sim ARGS` with `input` on stdin.
fn sim(args: &[&str], input: &str) -> Output {
    pbtool("sim", args, input)
}

/// Run `pbtool SUBCOMMAND ARGS` with `input` on stdin.
fn pbtool(subcommand: &str, args: &[&str], input: &str) -> Output {
    let mut all = vec![subcommand];
    all.extend_from_slice(args);
    common::pbtool_with_input(&all, input)
}

fn stdout_lines(output: &Output) -> Vec<String> {
    String::from_utf8(output.stdout.clone())
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}

#[test]
fn a_piped_script_gets_one_reply_per_command() {
    let output = sim(&["--ps", "sync65", "--fast"], "ID\nSTATUS\n");
    assert!(output.status.success());
    let lines = stdout_lines(&output);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(lines.iter().all(|l| l.starts_with("OK")), "{lines:?}");
    assert_eq!(
        lines[0],
        "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=Powermax65 family=SYNC product=081335 torch=MACHINE lead_ft=25"
    );
    assert!(lines[1].starts_with("OK link=UP model=Powermax65 family=SYNC "));
    assert!(output.stderr.is_empty(), "quiet from a pipe");
}

#[test]
fn virtual_time_is_deterministic() {
    let script = "SET PROCESS CUT 45 AUTO\nTORCH ON\nSTATUS\nTORCH OFF\nCOUNTERS\n";
    let first = sim(&["--ps", "sync85", "--fast", "--seed", "7"], script);
    let second = sim(&["--ps", "sync85", "--fast", "--seed", "7"], script);
    assert_eq!(first.stdout, second.stdout);
    assert_eq!(stdout_lines(&first).len(), 5);
}

#[test]
fn real_time_from_a_pipe_waits_for_the_link_and_exits_at_the_end() {
    let began = std::time::Instant::now();
    let output = sim(&["--ps", "pm65"], "ID\nSTATUS\n\nLIMITS");
    assert!(output.status.success());
    let lines = stdout_lines(&output);
    assert_eq!(lines.len(), 3, "a blank line gets no reply: {lines:?}");
    assert!(
        lines[0].contains(" link=UP ") && lines[0].contains(" family=LEGACY"),
        "{lines:?}"
    );
    assert!(
        lines[2].starts_with("OK modes=CUT,CPA,GOUGE"),
        "the last line without LF counts"
    );
    assert!(began.elapsed() < std::time::Duration::from_secs(5));
}

#[test]
fn a_fault_at_start_shows_in_status() {
    let output = sim(
        &["--ps", "sync65", "--fast", "--fault", "0-50-0"],
        "STATUS\nFAULT\n",
    );
    let lines = stdout_lines(&output);
    assert!(lines[0].contains(" fault=0-50-0 "), "{lines:?}");
    assert!(lines[0].contains(" ready=OFF"), "{lines:?}");
    assert!(lines[1].starts_with("OK fault=0-50-0 action=required text="));
    // The same in decimal, and an HPR error number.
    let lines = stdout_lines(&sim(
        &["--ps", "sync65", "--fast", "--fault", "500"],
        "STATUS\n",
    ));
    assert!(lines[0].contains(" fault=0-50-0 "), "{lines:?}");
    let lines = stdout_lines(&sim(
        &["--ps", "hpr130", "--fast", "--fault", "44"],
        "FAULT\n",
    ));
    assert_eq!(
        lines,
        ["OK fault=044 action=required text=LOW PLASMA GAS PRESSURE"]
    );
}

#[test]
fn bad_arguments_exit_2_and_say_why() {
    let output = sim(&["--ps", "hd4070"], "");
    assert_eq!(output.status.code(), Some(2));
    let err = String::from_utf8(output.stderr).unwrap();
    assert!(err.contains("unknown model \"hd4070\""), "{err}");
    for model in Model::ALL {
        assert!(err.contains(model.name()), "{model} listed: {err}");
    }
    let output = sim(&["--ps", "hpr260", "--fault", "0-50-0"], "");
    assert_eq!(output.status.code(), Some(2));
    let output = sim(&["--ps", "sync65", "--fault", "0-5-0"], "");
    assert_eq!(output.status.code(), Some(2));
    assert!(
        String::from_utf8(output.stderr)
            .unwrap()
            .contains("expected X-YY-Z")
    );
}

#[test]
fn every_model_is_found_by_the_bridge() {
    for model in Model::ALL {
        let lines = stdout_lines(&sim(&["--ps", model.name(), "--fast"], "ID\n"));
        assert_eq!(lines.len(), 1, "{model}: {lines:?}");
        assert!(lines[0].contains(" link=UP "), "{model}: {lines:?}");
    }
}

#[test]
fn torch_is_a_simulator_command_marked_in_help_and_cuts() {
    let script = "HELP\nSET PROCESS CUT 45 AUTO\nTORCH ON\n\nTORCH OFF\n";
    let output = sim(
        &["--ps", "sync65", "--fast", "--events", "--verbose"],
        script,
    );
    let lines = stdout_lines(&output);
    assert!(lines[0].starts_with("!LINK UP model="), "{lines:?}");
    let help = lines
        .iter()
        .find(|l| l.starts_with("OK commands="))
        .unwrap();
    assert!(
        help.ends_with(" simulator_only=TORCH simulator=YES"),
        "{help}"
    );
    assert!(lines.contains(&"OK torch=ON".to_string()), "{lines:?}");
    assert!(lines.contains(&"OK torch=OFF".to_string()), "{lines:?}");
    let err = String::from_utf8(output.stderr).unwrap();
    assert!(err.contains("START on: torch-on from CNC"), "{err}");
    assert!(err.contains("START off: torch-on released by CNC"), "{err}");
    assert!(
        err.contains("READY on: link up, no fault, supply ready"),
        "{err}"
    );
}

#[test]
fn phoenix_frames_on_stdin_are_acked() {
    let good = "\x01\x02FAULT\r\n\x03\x04\x4A\n";
    let bad = "\x01\x02FAULT\r\n\x03\x04\x4B\n";
    let output = sim(&["--ps", "sync65", "--fast"], &format!("{good}{bad}ID\n"));
    let lines = stdout_lines(&output);
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert_eq!(lines[0], "<ACK>OK fault=none");
    // The NAK, then the session's own `ERR` line for the check byte (its text from there).
    let check_byte = plasma_protocol::Error::BadChecksum {
        expected: 0x4A,
        found: 0x4B,
    };
    let reply = plasma_firmware::texts::frame_error(check_byte);
    assert_eq!(lines[1], format!("<NAK>{}", reply.trim_end()));
    assert!(lines[2].starts_with("OK bridge="));
}

#[test]
fn run_without_a_probe_runs_the_simulator() {
    // `cargo bridge` (the README's run command) is `pbtool run`: with no debug probe attached
    // (or probe-rs not installed, as in CI) it runs the bridge against a simulated SYNC unit.
    let forced = pbtool("run", &["--sim", "--fast"], "ID\n");
    assert!(forced.status.success());
    assert_eq!(
        stdout_lines(&forced),
        [
            "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=Powermax65 family=SYNC product=081335 torch=MACHINE lead_ft=25"
        ]
    );
    let probed = pbtool("run", &["--fast", "--ps", "pm85"], "ID\n");
    let stderr = String::from_utf8_lossy(&probed.stderr);
    if !stderr.contains("flashing the board image") {
        assert!(probed.status.success());
        let lines = stdout_lines(&probed);
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(lines[0].contains("family=LEGACY"), "{lines:?}");
    }
}

/// `--flash FILE` keeps the board's flash between runs: restarting is a power cycle, the
/// saved settings and the history are still there.
#[test]
fn the_flash_file_survives_a_restart_as_a_power_cycle() {
    let dir = std::env::temp_dir().join(format!("pbtool-flash-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bridge.flash");
    let flash = file.to_str().unwrap();
    let args = [
        "--ps", "sync65", "--fast", "--fault", "0-50-0", "--flash", flash,
    ];
    let first = sim(&args, "CONFIG arc_ok_debounce_ms 7\nCONFIG SAVE\nHISTORY\n");
    assert!(first.status.success(), "{first:?}");
    let lines = stdout_lines(&first);
    assert_eq!(lines[..2], ["OK arc_ok_debounce_ms=7", "OK config=saved"]);
    assert!(
        lines[2].contains(" boot=0 ") && lines[2].contains(" event=FAULT code=0-50-0"),
        "{lines:?}"
    );

    let second = sim(
        &["--ps", "sync65", "--fast", "--flash", flash],
        "CONFIG arc_ok_debounce_ms\nHISTORY 16\n",
    );
    assert!(second.status.success(), "{second:?}");
    let lines = stdout_lines(&second);
    assert_eq!(lines[0], "OK arc_ok_debounce_ms=7", "{lines:?}");
    let reset = lines
        .iter()
        .position(|l| l.ends_with(" event=RESET cause=power-on"))
        .expect("the restart is a reset");
    assert!(lines[reset].contains(" boot=1 "), "{lines:?}");
    // Older than the reset: the first run's fault, of boot 0.
    assert!(
        lines[reset + 1..]
            .iter()
            .any(|l| l.contains(" boot=0 ") && l.contains(" event=FAULT code=0-50-0")),
        "{lines:?}"
    );
    assert!(
        lines.last().unwrap().starts_with("OK history="),
        "{lines:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `pbtool run --flash FILE` is the bridge on this PC with its flash in a file (the simulator,
/// even where a board or QEMU is there: they keep their own), in real time with the PC's
/// wall clock set at start. Set, quit, restart: the settings and the history are read back.
#[test]
fn run_keeps_its_flash_in_a_file_and_sets_its_clock() {
    let dir = std::env::temp_dir().join(format!("pbtool-run-flash-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bridge.flash");
    let flash = file.to_str().unwrap();
    let first = pbtool(
        "run",
        &["--ps", "sync65", "--fault", "0-50-0", "--flash", flash],
        "CONFIG arc_ok_debounce_ms 7\nCONFIG SAVE\nCLOCK\n",
    );
    assert!(first.status.success(), "{first:?}");
    let stderr = String::from_utf8_lossy(&first.stderr);
    assert!(stderr.contains("running the simulator"), "{stderr}");
    let lines = stdout_lines(&first);
    assert_eq!(lines[..2], ["OK arc_ok_debounce_ms=7", "OK config=saved"]);
    // The clock was set from the PC's: this year's, not `unset`.
    assert!(lines[2].starts_with("OK clock=20"), "{lines:?}");

    let second = pbtool(
        "run",
        &["--ps", "sync65", "--flash", flash],
        "CONFIG arc_ok_debounce_ms\nHISTORY 16\n",
    );
    assert!(second.status.success(), "{second:?}");
    let lines = stdout_lines(&second);
    assert_eq!(lines[0], "OK arc_ok_debounce_ms=7", "{lines:?}");
    let reset = lines
        .iter()
        .position(|l| l.ends_with(" event=RESET cause=power-on"))
        .expect("the restart is a reset");
    // This boot's clock is set: its reset has a time.
    assert!(
        lines[reset].contains(" boot=1 ") && !lines[reset].contains(" clock=- "),
        "{lines:?}"
    );
    assert!(
        lines[reset + 1..]
            .iter()
            .any(|l| l.contains(" boot=0 ") && l.contains(" event=FAULT code=0-50-0")),
        "{lines:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn several_ps_share_one_simulated_line_and_at_n_addresses_each() {
    // HPR ids 0 and 1 on one line: `CONFIG units` names them, `@2` is the second.
    let output = sim(
        &["--ps", "hpr260", "--ps", "hpr130", "--fast"],
        "CONFIG units\nID\n@2 ID\n@3 ID\n",
    );
    assert!(output.status.success());
    let lines = stdout_lines(&output);
    assert_eq!(lines.len(), 4, "{lines:?}");
    assert_eq!(lines[0], "OK units=HPR:0,HPR:1");
    assert!(lines[1].contains(" model=HPR260 "), "{lines:?}");
    assert!(!lines[1].contains("unit="), "{lines:?}");
    assert!(lines[2].contains(" model=HPR130 "), "{lines:?}");
    assert!(lines[2].split(' ').any(|w| w == "unit=2"), "{lines:?}");
    assert!(lines[3].starts_with("ERR RANGE "), "{lines:?}");

    // Powermax units take nodes 1, 2...; `TORCH ON` and `@2 TORCH ON` drive each unit's
    // TORCH_ON, and only its START follows.
    let script = "CONFIG units\n@2 TORCH ON\n\n@2 TORCH OFF\nTORCH ON\n\nTORCH OFF\n";
    let output = sim(
        &["--ps", "sync65", "--ps", "pm85", "--fast", "--verbose"],
        script,
    );
    assert!(output.status.success());
    let lines = stdout_lines(&output);
    assert_eq!(lines[0], "OK units=POWERMAX:1,POWERMAX:2", "{lines:?}");
    assert!(
        lines.contains(&"OK torch=ON unit=2".to_string()),
        "{lines:?}"
    );
    assert!(lines.contains(&"OK torch=ON".to_string()), "{lines:?}");
    let err = String::from_utf8(output.stderr).unwrap();
    assert!(err.contains("2 simulated units on one line: @1 "), "{err}");
    for unit in ["@1", "@2"] {
        let starts = err
            .lines()
            .filter(|l| l.starts_with(&format!("[io {unit}]")) && l.contains("START on:"))
            .count();
        assert_eq!(
            starts, 1,
            "{unit}'s START once, for its own TORCH_ON: {err}"
        );
    }
}

#[test]
fn units_that_cannot_share_a_line_are_refused_with_the_reason() {
    let output = sim(&["--ps", "hpr260", "--ps", "sync65", "--fast"], "");
    assert_eq!(output.status.code(), Some(2));
    let err = String::from_utf8(output.stderr).unwrap();
    assert!(err.contains("cannot share a line"), "{err}");
    let output = sim(&["--ps", "maxpro200", "--ps", "hpr260", "--fast"], "");
    assert_eq!(output.status.code(), Some(2));
    let err = String::from_utf8(output.stderr).unwrap();
    assert!(err.contains("WAKE/SLEEP"), "{err}");
    // The emulated board refuses them in the same words, before QEMU starts.
    for ps in [["hpr260", "sync65"], ["maxpro200", "hpr260"]] {
        let args = ["--ps", ps[0], "--ps", ps[1]];
        let refusal = |output: Output, command: &str| {
            assert_eq!(output.status.code(), Some(2));
            let err = String::from_utf8(output.stderr).unwrap();
            let prefix = format!("pbtool {command}: ");
            let Some(reason) = err.strip_prefix(&prefix) else {
                panic!("{err}");
            };
            reason.to_string()
        };
        let from_sim = refusal(sim(&[&args[..], &["--fast"]].concat(), ""), "sim");
        let from_emu = refusal(pbtool("emu", &args, ""), "emu");
        assert_eq!(from_emu, from_sim);
    }
    // Its measurements are one unit's, and it says so.
    let output = pbtool(
        "emu",
        &["--measure", "--ps", "hpr260", "--ps", "hpr130"],
        "",
    );
    assert_eq!(output.status.code(), Some(2));
    let err = String::from_utf8(output.stderr).unwrap();
    assert!(
        err.starts_with("pbtool emu --measure: one --ps only"),
        "{err}"
    );
}

#[test]
fn run_on_the_simulator_takes_several_ps_as_sim_does() {
    let output = pbtool(
        "run",
        &["--sim", "--fast", "--ps", "hpr260", "--ps", "hpr400"],
        "@2 ID\n",
    );
    assert!(output.status.success());
    let lines = stdout_lines(&output);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(lines[0].contains(" model=HPR400 "), "{lines:?}");
    assert!(lines[0].split(' ').any(|w| w == "unit=2"), "{lines:?}");
}
