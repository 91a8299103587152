//! `pbtool monitor`: the screen drawn on ratatui's test backend from reply lines, the real
//! `pbtool sim` child through the monitor's transport, and `--snapshot`.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use pbtool::monitor::state::Command as Ask;
use pbtool::monitor::transport::Source;
use pbtool::monitor::{Dashboard, Session, screen_text};

const S: Duration = Duration::from_secs(1);

// What `pbtool sim --ps sync65 --fault 0-50-0 --events` answers (10:00:00 UTC is the start).
const STATUS_FAULT: &str = "OK link=UP model=Powermax65 family=SYNC remote=OFF mode=CUT amps=65 psi=72 out_amps=0 out_psi=0 fault=0-50-0 start=OFF motion=OFF arc_ok=OFF ready=OFF";
const FAULT: &str = "OK fault=0-50-0 action=required text=The cartridge is off, the torch was disconnected when you set the plasma power supply to ON (I), or the torch was in the yellow lock (X) position during a restart.";
/// 2026-11-26T10:00:00 UTC.
const TEN_O_CLOCK: u64 = 1_795_687_200;

/// A dashboard connected to the simulator, its first replies (events on, the clock set, no
/// CONSUMABLES, the history of a bridge that has just started) in.
fn connected() -> Dashboard {
    let mut dash = Dashboard::new("sim sync65", None, TEN_O_CLOCK);
    dash.connected(Duration::ZERO);
    for line in [
        "OK events=ON",
        "OK clock=2026-11-26T10:00:00",
        "ERR SYNTAX unknown command (HELP lists the commands)",
        "HISTORY seq=1 boot=1 uptime_ms=3 clock=2026-11-26T10:00:00 family=- event=RESET cause=power-on",
        "OK history=1 skipped=0",
    ] {
        dash.apply_line(Duration::ZERO, line);
    }
    dash
}

/// Answers what `dash` asks at `now` as `pbtool sim --ps sync65 --fault 0-50-0` does.
fn answer_with_fault(dash: &mut Dashboard, now: Duration) {
    for command in dash.poll(now) {
        let lines: &[&str] = match command {
            Ask::Status => &[STATUS_FAULT],
            Ask::Fault => &[FAULT],
            Ask::Counters => &["OK link_ok=21 link_failed=0"],
            // The fault is in the history.
            Ask::History => &[
                "HISTORY seq=2 boot=1 uptime_ms=1250 clock=2026-11-26T10:00:01 family=SYNC model=Powermax65 event=FAULT code=0-50-0 action=required",
                "HISTORY seq=1 boot=1 uptime_ms=3 clock=2026-11-26T10:00:00 family=- model=- event=RESET cause=power-on",
                "OK history=2 skipped=0",
            ],
            other => panic!("{other:?} not asked"),
        };
        for line in lines {
            dash.apply_line(now, line);
        }
    }
}

fn with_fault() -> Dashboard {
    let mut dash = connected();
    dash.apply_line(S, "!LINK UP model=Powermax65/85/105 SYNC");
    answer_with_fault(&mut dash, S);
    answer_with_fault(&mut dash, 2 * S);
    dash
}

#[test]
fn the_screen_for_a_fault() {
    let screen = screen_text(&with_fault(), 2 * S, 100, 30);
    for wanted in [
        "model Powermax65  family SYNC",
        "unit link UP",
        "set    65 A  72 psi  CUT",
        "actual 0 A  0 psi",
        "● FAULT",
        "○ READY",
        "○ START",
        "FAULT 0-50-0 (steps required)",
        "The cartridge is off",
        "not reported by this bridge",
        "10:00:01 LINK UP model=Powermax65",
        "g gas check | r remote off | c clear warnings | q quit",
        "Actual current A and pressure psi",
        "History (bridge, newest first)",
        "11-26 10:00 FAULT code=0-50-0 action=required",
        "11-26 10:00 RESET cause=power-on",
    ] {
        assert!(screen.contains(wanted), "{wanted:?} missing:\n{screen}");
    }
}

#[test]
fn the_screen_for_a_lost_connection() {
    let mut dash = with_fault();
    dash.lost(3 * S, "the child exited");
    let screen = screen_text(&dash, 4 * S, 100, 30);
    assert!(
        screen.contains("sim sync65: LOST, reconnecting"),
        "{screen}"
    );
    assert!(
        screen.contains("10:00:03 connection lost: the child exited"),
        "{screen}"
    );
    // Nothing is known while the connection is lost: the lamps say so.
    assert!(screen.contains("reconnecting"), "{screen}");
    assert!(screen.contains("unit link -"), "{screen}");
    assert!(screen.contains("unknown: not connected"), "{screen}");
    assert!(screen.contains("? FAULT"), "{screen}");
    assert!(!screen.contains("● FAULT"), "{screen}");
    // What the bridge kept stays: it happened.
    assert!(screen.contains("11-26 10:00 FAULT code=0-50-0"), "{screen}");
}

/// A bridge that counts consumables: a set at 80 %, then the 90 % warning.
#[test]
fn the_screen_for_a_consumable_warning() {
    let mut dash = Dashboard::new("sim pm65", None, TEN_O_CLOCK);
    dash.connected(Duration::ZERO);
    for line in [
        "OK events=ON",
        "OK clock=2026-11-26T10:00:00",
        "OK CONSUMABLES source=COUNTED starts=120 arc_s=3400 start_limit=150 arc_limit_s=OFF used=80% wear_faults=0",
        "OK history=0 skipped=0",
    ] {
        dash.apply_line(Duration::ZERO, line);
    }
    let before = screen_text(&dash, S, 100, 30);
    assert!(before.contains("80 % used"), "{before}");
    assert!(
        before.contains("starts 120  arc 3400 s  COUNTED"),
        "{before}"
    );
    assert!(!before.contains("WARN"), "{before}");
    dash.apply_line(S, "!WARN CONSUMABLE used=90% starts=135 arc_s=3700");
    for command in dash.poll(S) {
        let reply = match command {
            Ask::Status => "OK link=UP model=Powermax65 family=LEGACY remote=ON mode=CUT amps=65 psi=AUTO out_amps=0 out_psi=0 fault=none start=OFF motion=OFF arc_ok=OFF ready=ON".to_string(),
            Ask::Counters => "OK link_ok=40 link_failed=0".to_string(),
            Ask::Consumables => "OK CONSUMABLES source=COUNTED starts=135 arc_s=3700 start_limit=150 arc_limit_s=OFF used=90% wear_faults=0".to_string(),
            Ask::History => "OK history=0 skipped=0".to_string(),
            other => panic!("{other:?} not asked"),
        };
        dash.apply_line(S, &reply);
    }
    let screen = screen_text(&dash, S, 100, 30);
    for wanted in [
        "90 % used",
        "starts 135  arc 3700 s",
        "WARN CONSUMABLE used=90% starts=135",
        "10:00:01 WARN CONSUMABLE used=90%",
    ] {
        assert!(screen.contains(wanted), "{wanted:?} missing:\n{screen}");
    }
}

#[test]
fn the_gas_checks_result_stays_on_screen() {
    let mut dash = with_fault();
    assert_eq!(
        dash.key(3 * S, 'g'),
        pbtool::monitor::state::KeyAction::Send(Ask::GasCheck)
    );
    dash.apply_line(
        3 * S,
        "OK GASTEST CHECK result=FAIL measured_psi=48 min_psi=65 max_psi=80",
    );
    let screen = screen_text(&dash, 3 * S, 100, 30);
    assert!(screen.contains("gas FAIL 48 psi (65-80)"), "{screen}");
    assert!(
        screen.contains("GASTEST CHECK: OK GASTEST CHECK result=FAIL"),
        "{screen}"
    );
}

#[test]
fn the_screen_for_the_unit_link_down() {
    let mut dash = connected();
    dash.poll(S);
    dash.apply_line(S, "!LINK DOWN reason=no_answer failures=3 last=timeout");
    dash.apply_line(S, "OK link=DOWN model=- family=- remote=OFF mode=- amps=- psi=- out_amps=- out_psi=- fault=none start=OFF motion=OFF arc_ok=OFF ready=OFF");
    let screen = screen_text(&dash, S, 100, 30);
    assert!(screen.contains("unit link DOWN"), "{screen}");
    assert!(screen.contains("LINK DOWN reason=no_answer"), "{screen}");
}

#[test]
fn a_small_terminal_gets_the_compact_layout() {
    let screen = screen_text(&with_fault(), 2 * S, 60, 12);
    for wanted in [
        "unit link UP",
        "● FAULT",
        "FAULT 0-50-0 (steps required)",
        "g gas check",
    ] {
        assert!(screen.contains(wanted), "{wanted:?} missing:\n{screen}");
    }
    assert!(!screen.contains("┌"), "no panels when small:\n{screen}");
}

#[test]
fn any_size_draws_without_a_panic() {
    let dash = with_fault();
    for (width, height) in [
        (0, 0),
        (1, 1),
        (10, 3),
        (79, 24),
        (80, 23),
        (80, 24),
        (250, 80),
    ] {
        let screen = screen_text(&dash, 2 * S, width, height);
        assert_eq!(screen.lines().count(), usize::from(height));
    }
}

fn pbtool_exe() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_pbtool"))
}

/// Steps `session` until `done`, for at most a minute (the child starts in real time).
fn step_until(session: &mut Session, done: impl Fn(&Dashboard) -> bool) {
    let deadline = Instant::now() + Duration::from_secs(60);
    while !done(&session.dashboard) {
        assert!(
            Instant::now() < deadline,
            "no such picture within a minute:\n{}",
            screen_text(&session.dashboard, session.now(), 100, 30)
        );
        session.step(Duration::from_millis(50));
    }
}

#[test]
fn the_real_simulator_through_the_transport() {
    let source = Source::child("sim", "sync65", Some("0-50-0"));
    let mut session = Session::new(source, pbtool_exe(), None);
    step_until(&mut session, |dash| {
        dash.fault.as_ref().is_some_and(|f| f.action == "required")
            && dash.status.is_some()
            && dash.errors_per_minute().is_some()
    });
    let dash = &session.dashboard;
    let status = dash.status.as_ref().expect("STATUS");
    assert_eq!(status.get("model"), Some("Powermax65"));
    assert_eq!(status.get("link"), Some("UP"));
    assert_eq!(dash.errors_per_minute(), Some(0.0));
    let fault = dash.fault.as_ref().expect("fault");
    assert_eq!(fault.code, "0-50-0");
    assert!(fault.text.starts_with("The cartridge is off"), "{fault:?}");
    // The bridge answers CONSUMABLES: a SYNC's cartridge, no limit set.
    let pbtool::monitor::state::Consumables::Reported(consumables) = &dash.consumables else {
        panic!("CONSUMABLES answered: {:?}", dash.consumables)
    };
    assert_eq!(consumables.get("source"), Some("cartridge"));
    assert_eq!(consumables.get("uid"), Some("E00401D0036FB25D"));
    assert_eq!(consumables.get("used"), Some("OFF"));
    assert!(
        dash.events.iter().any(|(_, e)| e.starts_with("LINK UP ")),
        "{:?}",
        dash.events
    );
    // A key's command goes out and its reply comes back on screen.
    assert!(session.key('c'));
    step_until(&mut session, |dash| {
        dash.last_action
            .as_deref()
            .is_some_and(|a| a.starts_with("CLEARWARN: ERR UNSUPPORTED"))
    });
}

/// Two HPRs on the simulated line, unit 1 with a fault: the dashboard shows unit 1, unit 2's
/// events are listed with their `unit=2`.
#[test]
fn two_units_through_the_transport_show_the_first() {
    let args = [
        "sim", "--ps", "hpr260", "--ps", "hpr130", "--events", "--fault", "044",
    ];
    let source = Source::Child {
        args: args.map(String::from).into(),
    };
    let mut session = Session::new(source, pbtool_exe(), None);
    step_until(&mut session, |dash| {
        dash.fault.as_ref().is_some_and(|f| f.action == "required")
            && dash.status.is_some()
            && dash
                .events
                .iter()
                .any(|(_, e)| e.starts_with("LINK UP model=HPR130") && e.ends_with(" unit=2"))
    });
    let dash = &session.dashboard;
    let status = dash.status.as_ref().expect("STATUS");
    assert_eq!(status.get("model"), Some("HPR260"));
    assert_eq!(dash.fault.as_ref().map(|f| f.code.as_str()), Some("044"));
}

#[test]
fn a_child_that_cannot_start_is_shown_and_retried() {
    let source = Source::child("sim", "sync65", None);
    let mut session = Session::new(source, Path::new("/nonexistent/pbtool"), None);
    session.step(Duration::ZERO);
    let screen = screen_text(&session.dashboard, session.now(), 100, 30);
    assert!(
        screen.contains("sim sync65: LOST, reconnecting"),
        "{screen}"
    );
    assert!(
        screen.contains("│cannot start /nonexistent/pbtool"),
        "{screen}"
    );
    assert!(screen.contains("connection lost: cannot start"), "{screen}");
    // No second attempt within the reconnect interval: one note only.
    session.step(Duration::ZERO);
    let attempts = session
        .dashboard
        .events
        .iter()
        .filter(|(_, e)| e.starts_with("connection lost"))
        .count();
    assert_eq!(attempts, 1);
}

#[test]
fn snapshot_prints_one_frame() {
    let output = Command::new(pbtool_exe())
        .args([
            "monitor",
            "--sim",
            "pm65",
            "--fault",
            "0-50-0",
            "--snapshot",
            "--size",
            "100x30",
        ])
        .output()
        .expect("pbtool runs");
    assert!(output.status.success(), "{output:?}");
    let screen = String::from_utf8(output.stdout).expect("UTF-8");
    assert_eq!(screen.lines().count(), 30, "{screen}");
    assert!(
        screen.contains("sim pm65 --fault 0-50-0: connected"),
        "{screen}"
    );
    assert!(screen.contains("FAULT 0-50-0"), "{screen}");
    // The bridge answers CONSUMABLES; no limit set: the counts, no bar.
    assert!(screen.contains("starts 0  arc 0 s  bridge"), "{screen}");
    assert!(screen.contains("no limit set (used=OFF)"), "{screen}");
    // The simulator's history: the unit's fault, its time from the clock the monitor set.
    let fault = screen
        .lines()
        .find(|l| l.contains(" FAULT code=0-50-0 action=required"))
        .unwrap_or_else(|| panic!("no history entry for the fault:\n{screen}"));
    assert!(!fault.contains("boot "), "a wall-clock time: {fault}");
}

/// Every simulated family on one screen: the unit and its link, the consumables as the bridge
/// reports them (the cartridge's on a SYNC, the bridge's own count elsewhere) and the history
/// panel with the unit's fault.
#[test]
fn every_simulated_family_on_the_dashboard() {
    for (model, family, fault, source) in [
        ("sync65", "SYNC", "0-50-0", "cartridge"),
        ("pm85", "LEGACY", "0-50-0", "bridge"),
        ("hpr260", "HPR", "044", "bridge"),
        ("maxpro200", "MAXPRO200", "044", "bridge"),
    ] {
        let output = Command::new(pbtool_exe())
            .args([
                "monitor",
                "--sim",
                model,
                "--fault",
                fault,
                "--snapshot",
                "--size",
                "100x30",
            ])
            .output()
            .expect("pbtool runs");
        assert!(output.status.success(), "{model}: {output:?}");
        let screen = String::from_utf8(output.stdout).expect("UTF-8");
        for wanted in [
            format!("family {family}"),
            "unit link UP".to_string(),
            format!("arc 0 s  {source}"),
            "History (bridge, newest first)".to_string(),
        ] {
            assert!(screen.contains(&wanted), "{model}: no {wanted:?}\n{screen}");
        }
        assert!(
            screen
                .lines()
                .any(|l| l.contains(&format!(" FAULT code={fault}"))),
            "{model}: no history entry for the fault\n{screen}"
        );
    }
}

#[test]
fn a_child_that_exits_is_restarted() {
    // `pbtool decode` without frames exits at once: the monitor restarts it every second.
    let source = Source::Child {
        args: vec!["decode".to_string()],
    };
    let mut session = Session::new(source, pbtool_exe(), None);
    let connections = |dash: &Dashboard| {
        dash.events
            .iter()
            .filter(|(_, e)| e.starts_with("connected to decode"))
            .count()
    };
    step_until(&mut session, |dash| connections(dash) >= 2);
    let times: Vec<Duration> = session
        .dashboard
        .events
        .iter()
        .filter(|(_, e)| e.starts_with("connected to"))
        .map(|(at, _)| *at)
        .collect();
    assert!(
        times[1] - times[0] >= pbtool::monitor::RECONNECT_EVERY,
        "{times:?}"
    );
    assert!(
        session
            .dashboard
            .events
            .iter()
            .any(|(_, e)| e.starts_with("connection lost: ")),
        "{:?}",
        session.dashboard.events
    );
}

/// Two minutes of cutting at 45 A on a SYNC unit, then the gas pressure drops: the README's
/// screen.
fn readme_dashboard() -> (Dashboard, Duration) {
    let mut dash = connected();
    dash.apply_line(S, "!LINK UP model=Powermax65/85/105 SYNC");
    dash.apply_line(S, "!REMOTE ON");
    dash.apply_line(S, "!SETTINGS applied mode=CUT amps=45 psi=72");
    let mut now = S;
    for second in 2..150u32 {
        now = second * S;
        let cutting = (second / 20) % 2 == 1 && second < 140;
        if second % 20 == 0 && second < 140 {
            dash.apply_line(now, "!ARC ON");
        } else if second % 20 == 19 && second < 140 {
            dash.apply_line(now, "!ARC OFF");
        }
        let (on, amps, psi) = if cutting {
            ("ON", "44.5", "71")
        } else {
            ("OFF", "0", "72")
        };
        let fault = if second >= 145 { "0-20-0" } else { "none" };
        for command in dash.poll(now) {
            let reply = match command {
                Ask::Status => format!(
                    "OK link=UP model=Powermax65 family=SYNC remote=ON mode=CUT amps=45 psi=72 out_amps={amps} out_psi={psi} fault={fault} start={on} motion={on} arc_ok={on} ready=ON"
                ),
                Ask::Fault => "OK fault=0-20-0 action=recommended text=The gas pressure is lower than the minimum pressure for the selected process, operating mode, torch, lead length, and cartridge type.".to_string(),
                Ask::History => {
                    // What the bridge kept: its start, the process set, the fault once it came.
                    let mut entries = vec![
                        "HISTORY seq=14 boot=3 uptime_ms=1250 clock=2026-11-26T10:00:01 family=SYNC model=Powermax65 event=PROCESS from_amps=65 to_amps=45 by=TEXT",
                        "HISTORY seq=13 boot=3 uptime_ms=3 clock=2026-11-26T10:00:00 family=- model=- event=RESET cause=power-on",
                        "HISTORY seq=12 boot=2 uptime_ms=5020410 clock=- family=SYNC model=Powermax65 event=FAULT_CLEARED code=0-50-0",
                        "HISTORY seq=11 boot=2 uptime_ms=5012010 clock=- family=SYNC model=Powermax65 event=FAULT code=0-50-0 action=required",
                    ];
                    if second > 145 {
                        entries.insert(0, "HISTORY seq=15 boot=3 uptime_ms=145250 clock=2026-11-26T10:02:25 family=SYNC model=Powermax65 event=FAULT code=0-20-0 action=recommended");
                    }
                    entries.truncate(6);
                    for entry in &entries {
                        dash.apply_line(now, entry);
                    }
                    format!("OK history={} skipped=0", entries.len())
                }
                _ => format!("OK link_ok={} link_failed={}", second * 20, second / 30),
            };
            dash.apply_line(now, &reply);
        }
        if second == 145 {
            dash.apply_line(now, "!FAULT 0-20-0 action=recommended text=The gas pressure is lower than the minimum pressure for the selected process, operating mode, torch, lead length, and cartridge type.");
        }
    }
    (dash, now)
}

#[test]
fn the_readme_shows_the_screen_as_drawn() {
    let (dash, now) = readme_dashboard();
    let screen = screen_text(&dash, now, 100, 30);
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md"))
        .expect("README.md");
    let start = "<!-- monitor screen: tests/pbtool_monitor.rs -->\n```text\n";
    let shown = readme
        .split_once(start)
        .and_then(|(_, rest)| rest.split_once("```\n"))
        .map(|(block, _)| block)
        .expect("the README's monitor screen block");
    assert_eq!(
        shown, screen,
        "the README's screen differs from the drawn one:\n{screen}"
    );
}

#[test]
fn a_port_that_is_not_there_is_shown() {
    let framing = plasma_protocol::serial::PortConfig::MODBUS_DEFAULT;
    let source = Source::Port {
        device: "/dev/nonexistent-pbtool-monitor".to_string(),
        framing,
    };
    let mut session = Session::new(source, pbtool_exe(), Some("19200 8E1".to_string()));
    session.step(Duration::ZERO);
    let screen = screen_text(&session.dashboard, session.now(), 100, 30);
    assert!(
        screen.contains("/dev/nonexistent-pbtool-monitor: LOST,"),
        "{screen}"
    );
    assert!(screen.contains("framing 19200 8E1"), "{screen}");
    assert!(
        screen.contains("connection lost: serial port"),
        "the port's error:\n{screen}"
    );
}
