//! `pbtool run --ps-port` (the firmware's bridge in real time) against `pbtool unit` over a
//! pty cable: a SYNC, a legacy Powermax and an HPR. ID, setting the process, STATUS, a fault
//! appearing and clearing, the unit going silent and coming back; and a port that goes away.

mod common;

use std::io::Write;

use common::{Cable, Pbtool};

struct Family {
    model: &'static str,
    found: &'static str,
    set: &'static str,
    set_reply: &'static str,
    fault: &'static str,
    fault_event: &'static str,
}

fn session(family: &Family) {
    let cable = Cable::new();
    let mut unit = Pbtool::spawn(&["unit", "--ps", family.model, "--port", &cable.b]);
    let mut run = Pbtool::spawn(&["run", "--ps-port", &cable.a, "--events"]);

    run.send("ID");
    let id = run.expect_prefix("OK bridge=");
    assert!(id.contains(" link=UP "), "{id}\n{}", run.transcript());
    assert!(id.contains(family.found), "{id}");

    run.send(family.set);
    run.expect_prefix(family.set_reply);
    run.send("STATUS");
    let status = run.expect_prefix("OK link=");
    assert!(
        status.contains(" amps=45 "),
        "{status}\n{}",
        run.transcript()
    );

    unit.send(&format!("FAULT {}", family.fault));
    run.expect_prefix(family.fault_event);
    run.send("STATUS");
    let status = run.expect_prefix("OK link=");
    assert!(!status.contains(" fault=none "), "{status}");
    unit.send("CLEAR");
    run.expect_prefix("!FAULT CLEARED");

    unit.send("SILENT");
    run.expect_prefix("!LINK DOWN reason=no_answer");
    run.send("STATUS");
    let status = run.expect_prefix("OK link=");
    assert!(status.starts_with("OK link=DOWN"), "{status}");
    unit.send("ANSWER");
    run.expect_prefix("!LINK UP");
    run.send("STATUS");
    let status = run.expect_prefix("OK link=");
    assert!(status.starts_with("OK link=UP"), "{status}");

    run.close_stdin();
    let exit = run.wait();
    assert!(exit.success(), "{exit}\n{}", run.transcript());
    unit.expect_stderr("fault cleared");
}

#[test]
fn the_bridge_runs_a_sync_unit_on_a_serial_line() {
    session(&Family {
        model: "sync65",
        found: "family=SYNC",
        set: "SET PROCESS CUT 45 AUTO",
        set_reply: "OK mode=CUT amps=45",
        fault: "0-50-0",
        fault_event: "!FAULT 0-50-0",
    });
}

#[test]
fn the_bridge_runs_a_legacy_powermax_on_a_serial_line() {
    session(&Family {
        model: "pm65",
        found: "family=LEGACY",
        set: "SET PROCESS CUT 45 AUTO",
        set_reply: "OK mode=CUT amps=45",
        fault: "0-50-0",
        fault_event: "!FAULT 0-50-0",
    });
}

#[test]
fn the_bridge_runs_an_hpr_on_a_serial_line() {
    session(&Family {
        model: "hpr260",
        found: "family=HPR",
        set: "SET AMPS 45",
        set_reply: "OK amps=45",
        fault: "80",
        fault_event: "!FAULT 080",
    });
}

#[test]
fn a_port_that_goes_away_ends_the_run_with_a_clear_error() {
    let mut cable = Cable::new();
    let _unit = Pbtool::spawn(&["unit", "--ps", "sync65", "--port", &cable.b]);
    let mut run = Pbtool::spawn(&["run", "--ps-port", &cable.a]);
    run.send("ID");
    run.expect_prefix("OK bridge=");
    cable.unplug();
    let exit = run.wait();
    assert_eq!(exit.code(), Some(2), "{}", run.transcript());
    assert!(run.stderr().contains("went away"), "{}", run.transcript());
}

#[test]
fn a_missing_or_busy_port_is_an_error_that_says_so() {
    let mut missing = Pbtool::spawn(&["run", "--ps-port", "/dev/pbtool-no-such-port"]);
    assert_eq!(missing.wait().code(), Some(2));
    assert!(
        missing.stderr().contains("does not exist"),
        "{}",
        missing.stderr()
    );

    let cable = Cable::new();
    let unit = Pbtool::spawn(&["unit", "--ps", "sync65", "--port", &cable.b]);
    // Once the unit has the port, a second user is refused.
    let deadline = std::time::Instant::now() + common::LONG;
    while !unit.stderr().contains("pbtool unit: a simulated") {
        assert!(
            std::time::Instant::now() < deadline,
            "{}",
            unit.transcript()
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let mut second = Pbtool::spawn(&["unit", "--ps", "pm65", "--port", &cable.b]);
    assert_eq!(second.wait().code(), Some(2));
    assert!(second.stderr().contains("in use"), "{}", second.stderr());
}

#[test]
fn with_no_unit_on_the_line_the_console_says_so_and_goes_on() {
    let cable = Cable::new();
    let mut run = Pbtool::spawn(&["run", "--ps-port", &cable.a]);
    run.send("ID");
    let id = run.expect_prefix("OK bridge=");
    assert!(!id.contains(" link=UP "), "{id}");
    // The console's message goes to stderr, read by another thread than stdout's reply.
    run.expect_stderr("no power supply answered on the PS port within 15 s");
    run.close_stdin();
    assert!(run.wait().success(), "{}", run.transcript());
}

#[test]
fn at_a_terminal_commands_are_answered_while_detection_runs() {
    // A person typing gets `link=DOWN` at once, as from the board, not 15 s of silence; and
    // Ctrl-D ends the run without waiting for detection.
    let cable = Cable::new();
    let (mut run, mut keyboard) = Pbtool::spawn_on_terminal(&["run", "--ps-port", &cable.a]);
    run.expect_stderr("commands are answered meanwhile");
    keyboard.write_all(b"ID\n").expect("typed");
    let id = run.expect_prefix("OK bridge=");
    assert!(id.contains(" link=DOWN "), "{id}");
    keyboard.write_all(b"\x04").expect("Ctrl-D typed");
    assert!(run.wait().success(), "{}", run.transcript());
    // The settle time-out's message comes only from a console that held the command back.
    assert!(
        !run.stderr().contains("no power supply answered"),
        "{}",
        run.transcript()
    );
}

#[test]
fn an_input_that_ends_before_any_command_ends_the_run_without_waiting_for_detection() {
    let cable = Cable::new();
    let mut run = Pbtool::spawn(&["run", "--ps-port", &cable.a]);
    run.expect_stderr("the first command waits for it");
    run.close_stdin();
    assert!(run.wait().success(), "{}", run.transcript());
    assert!(
        !run.stderr().contains("no power supply answered"),
        "{}",
        run.transcript()
    );
}

/// `run --ps-port DEV --flash FILE`: the settings saved and the history kept in the file;
/// the next run boots from it as from a power cycle. Its clock is the PC's from the start.
#[test]
fn the_bridge_on_a_serial_line_keeps_its_flash_in_a_file() {
    let dir = std::env::temp_dir().join(format!("pbtool-line-flash-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bridge.flash");
    let flash = file.to_str().unwrap();
    let cable = Cable::new();
    let mut unit = Pbtool::spawn(&["unit", "--ps", "sync65", "--port", &cable.b]);

    let mut run = Pbtool::spawn(&["run", "--ps-port", &cable.a, "--flash", flash, "--events"]);
    run.send("CLOCK");
    let clock = run.expect_prefix("OK clock=");
    assert!(clock.starts_with("OK clock=20"), "{clock}");
    run.send("CONFIG arc_ok_debounce_ms 7");
    run.expect_prefix("OK arc_ok_debounce_ms=7");
    run.send("CONFIG SAVE");
    run.expect_prefix("OK config=saved");
    unit.send("FAULT 0-50-0");
    run.expect_prefix("!FAULT 0-50-0");
    run.close_stdin();
    assert!(run.wait().success(), "{}", run.transcript());

    let mut again = Pbtool::spawn(&["run", "--ps-port", &cable.a, "--flash", flash]);
    again.send("CONFIG arc_ok_debounce_ms");
    again.expect_prefix("OK arc_ok_debounce_ms=7");
    again.send("HISTORY 3");
    let reset = again.expect("the restart's reset", |l| {
        l.starts_with("HISTORY ") && l.ends_with(" event=RESET cause=power-on")
    });
    assert!(reset.contains(" boot=1 "), "{reset}");
    // The first run's fault, of boot 0, older than the reset.
    let fault = again.expect("the first run's fault", |l| {
        l.starts_with("HISTORY ") && l.contains(" event=FAULT code=0-50-0")
    });
    assert!(fault.contains(" boot=0 "), "{fault}");
    again.expect_prefix("OK history=");
    again.close_stdin();
    assert!(again.wait().success(), "{}", again.transcript());
    std::fs::remove_dir_all(&dir).unwrap();
}
