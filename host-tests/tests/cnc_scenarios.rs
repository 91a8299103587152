//! The CNC side end to end: the firmware's `Bridge` in the scenario `World`, driven with CNC
//! bytes against the simulated units, with the discrete I/O, the line and the safety monitor
//! (checked after every step; a broken rule fails the test) in the loop.

mod common;

use common::{bridge_world, bridge_world_with, field, hpr, modbus, ready_hpr, settle, well_formed};
use host_tests::harness::{CncItem, World, WorldOptions};
use plasma_firmware::io::{Input, Interlock, IoEvent, Output, Reason};
use plasma_firmware::link::{Family, Refusal};
use plasma_firmware::settings::{SaveError, Settings};
use plasma_firmware::texts::{self, UnsupportedText, unsupported};
use plasma_protocol::cnc::ErrorCode;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::Model;
use plasma_sim::hpr::Hpr;
use plasma_sim::powermax::Powermax;

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

/// Every reply so far is well formed, and there are `count` of them.
fn assert_replies(world: &World<host_tests::harness::BridgeEndpoint>, count: usize) {
    let replies: Vec<&str> = world.cnc_replies().collect();
    assert_eq!(replies.len(), count, "{replies:#?}");
    for line in world.cnc_lines() {
        assert!(well_formed(line), "malformed line {line:?}");
    }
}

/// True when `text` matches `pattern`, where `*` stands for any run of characters.
fn glob(pattern: &str, text: &str) -> bool {
    let mut parts = pattern.split('*');
    let first = parts.next().unwrap_or("");
    let Some(mut rest) = text.strip_prefix(first) else {
        return false;
    };
    let parts: Vec<&str> = parts.collect();
    let Some((last, middle)) = parts.split_last() else {
        return rest.is_empty();
    };
    for part in middle {
        match rest.find(part) {
            Some(at) => rest = &rest[at + part.len()..],
            None => return false,
        }
    }
    rest.len() >= last.len() && rest.ends_with(last)
}

/// Assert that `reply` matches `pattern` (see [`glob`]): `ERR` replies are matched by their
/// code and the values that matter, not by their wording.
#[track_caller]
fn assert_err(reply: &str, pattern: &str) {
    assert!(glob(pattern, reply), "{reply:?} does not match {pattern:?}");
}

/// An `ERR` line with `code` and `text` (texts taken from where the bridge writes them).
fn err(code: ErrorCode, text: impl std::fmt::Display) -> String {
    format!("ERR {code} {text}")
}

/// The `ERR` line of a command the link refused.
fn refusal_line(refusal: &Refusal, family: Option<Family>) -> String {
    let mut line = String::new();
    texts::write_refusal(&mut line, refusal, family, Instant::ZERO).unwrap();
    line.trim_end().to_string()
}

/// Run each (command, expected) pair; `*` in the expected text stands for any characters.
fn expect_all(world: &mut World<host_tests::harness::BridgeEndpoint>, table: &[(&str, &str)]) {
    for &(command, expected) in table {
        let reply = world.cnc_line(command);
        assert!(
            glob(expected, &reply),
            "{command}: {reply:?} does not match {expected:?}"
        );
    }
}

// --- a cut -------------------------------------------------------------------------------

#[test]
fn a_sync_session_sets_a_process_and_cuts() {
    let mut w = bridge_world(Model::Sync65);
    assert_eq!(w.cnc_line("EVENTS ON"), "OK events=ON");
    assert_eq!(
        w.cnc_line("SET PROCESS CUT 45 AUTO"),
        "OK mode=CUT amps=45 psi=AUTO"
    );
    // The unit got all three in one write and is in remote mode.
    let unit = w.sim_ref::<Powermax>();
    assert!(w.unit_ref().in_remote_mode());
    assert_eq!(unit.settings().current, 45 * 64);
    assert_eq!(unit.settings().pressure, 0);

    assert_eq!(w.cnc_line("TORCH ON"), "OK torch=ON");
    assert!(w.io().outputs().start);
    w.wait_cnc_line("!ARC ON", Duration::from_secs(2)).unwrap();
    let status = w.cnc_line("STATUS");
    for (key, value) in [
        ("link", "UP"),
        ("remote", "ON"),
        ("mode", "CUT"),
        ("amps", "45"),
        ("start", "ON"),
        ("motion", "ON"),
        ("arc_ok", "ON"),
        ("ready", "ON"),
        ("fault", "none"),
    ] {
        assert_eq!(field(&status, key), Some(value), "{key} in {status}");
    }
    w.run_for(ms(500));
    assert_eq!(
        field(&w.cnc_line("STATUS"), "out_amps"),
        Some("45"),
        "the unit cuts at 45 A"
    );

    assert_eq!(w.cnc_line("TORCH OFF"), "OK torch=OFF");
    assert!(!w.io().outputs().start);
    w.wait_cnc_line("!ARC OFF", Duration::from_secs(2)).unwrap();
    let status = w.cnc_line("STATUS");
    assert_eq!(field(&status, "start"), Some("OFF"));
    assert_eq!(field(&status, "arc_ok"), Some("OFF"));

    // The output log says why START moved.
    let start: Vec<_> = w
        .transitions()
        .iter()
        .filter(|t| t.output == Output::Start)
        .map(|t| (t.level, t.reason))
        .collect();
    assert_eq!(start, [(true, Reason::TorchOn), (false, Reason::TorchOff)]);
    assert_eq!(
        w.sim_ref::<Powermax>().counters().transfers,
        1,
        "one transfer on the unit"
    );
    assert_replies(&w, 7);
}

#[test]
fn an_hpr_session_sets_amps_gases_corner_and_cuts() {
    let mut w = ready_hpr(Model::Hpr260);
    expect_all(
        &mut w,
        &[
            ("EVENTS ON", "OK events=ON"),
            ("SET AMPS 200", "OK amps=200"),
            ("CORNER 80", "OK corner=80"),
            // The HPR manual's 095 and 078 samples (002_72b43a5685974c77.txt lines 180, 165).
            (
                "SET HPR_PARAMETERS 100 75 O2 N2 55 45 35 25 0 0",
                "OK amps=100 corner=75 plasma=O2 shield=N2 plasma_cutflow_psi=55 \
                 plasma_preflow_psi=45 shield_cutflow_psi=35 shield_preflow_psi=25 n2_mix_psi=0 \
                 gas2_mix_psi=0",
            ),
            (
                "SET HPR_GAS_FLOWS 55 45 35 25 50 50",
                "OK plasma_cutflow_psi=55 plasma_preflow_psi=45 shield_cutflow_psi=35 \
                 shield_preflow_psi=25 n2_mix_psi=50 gas2_mix_psi=50",
            ),
            ("SET AMPS 200", "OK amps=200"),
            ("CORNER 80", "OK corner=80"),
        ],
    );
    assert_eq!(w.sim_ref::<Hpr>().nominal_amps(), 200);
    assert_eq!(w.sim_ref::<Hpr>().corner_percent(), 80);
    // A gas change purges the unit: wait for it to be ready again.
    assert_eq!(w.cnc_line("GASES O2 AIR"), "OK plasma=O2 shield=AIR");
    w.run_until(|w| w.bridge().status().ready, Duration::from_secs(10))
        .unwrap();

    assert_eq!(w.cnc_line("TORCH ON"), "OK torch=ON");
    // Preflow, HF ignition (the link rides through its noise), pilot arc, transfer.
    w.wait_cnc_line("!ARC ON", Duration::from_secs(5)).unwrap();
    let status = w.cnc_line("STATUS");
    assert_eq!(field(&status, "start"), Some("ON"), "{status}");
    assert_eq!(field(&status, "motion"), Some("ON"), "{status}");
    assert_eq!(field(&status, "arc_ok"), Some("ON"), "{status}");
    // Steady state; corner current from the CNC reaches the unit: 80 % of 200 A.
    w.run_until(
        |w| w.sim_ref::<Hpr>().state_code() == 8,
        Duration::from_secs(2),
    )
    .unwrap();
    w.set_input(Input::CornerCurrent, true);
    w.run_for(ms(50));
    assert!(w.io().outputs().corner_current);
    assert_eq!(w.sim_ref::<Hpr>().actual_amps(), 160);
    w.set_input(Input::CornerCurrent, false);
    w.run_for(ms(50));
    assert_eq!(w.sim_ref::<Hpr>().actual_amps(), 200);
    // STATUS shows the output current the bridge reads with 028 while the arc is on.
    w.run_until(
        |w| w.bridge().status().hpr.actual_amps == Some(200),
        Duration::from_secs(2),
    )
    .unwrap();
    assert_eq!(field(&w.cnc_line("STATUS"), "out_amps"), Some("200"));

    assert_eq!(w.cnc_line("TORCH OFF"), "OK torch=OFF");
    w.wait_cnc_line("!ARC OFF", Duration::from_secs(2)).unwrap();
    w.run_until(|w| w.bridge().status().ready, Duration::from_secs(10))
        .unwrap();
    assert_eq!(w.sim_ref::<Hpr>().counters().starts, 1);
    assert_eq!(w.unit_ref().active_fault(), 0, "a clean cut, no error");
    assert_eq!(w.cnc_line("FAULTLOG"), "OK log=none");
}

#[test]
fn hold_from_the_cnc_keeps_the_hpr_in_preflow() {
    let mut w = ready_hpr(Model::Hpr130);
    assert_eq!(w.cnc_line("EVENTS ON"), "OK events=ON");
    w.set_input(Input::Hold, true);
    assert_eq!(w.cnc_line("TORCH ON"), "OK torch=ON");
    w.run_for(ms(2_000));
    assert_eq!(w.sim_ref::<Hpr>().state_code(), 4, "held in preflow");
    // One state change is reported, and no other event while the start is held.
    assert_eq!(
        w.cnc_events().collect::<Vec<_>>(),
        ["!STATE 4 name=PREFLOW from=3"]
    );
    assert!(!w.unit_ref().motion());
    w.set_input(Input::Hold, false);
    w.run_until(|w| w.io().outputs().arc_ok, Duration::from_secs(5))
        .expect("ignites and transfers once HOLD is released");
    assert_eq!(w.cnc_line("TORCH OFF"), "OK torch=OFF");
}

// --- every command, OK and ERR -------------------------------------------------------------
// The SYNC and HPR replies, byte for byte, are the session's tests
// (firmware/src/cnc/commands/tests.rs); here what needs the unit over time.

#[test]
fn sync_restart_clears_0_50_0_and_keeps_start_off_through_the_quiet_time() {
    let mut w = World::with_bridge(Model::Sync85, WorldOptions::default(), Settings::default());
    w.inject_fault(500);
    settle(&mut w);
    assert_eq!(field(&w.cnc_line("STATUS"), "fault"), Some("0-50-0"));
    assert!(
        w.cnc_line("FAULT")
            .starts_with("OK fault=0-50-0 action=required text=The cartridge is off")
    );
    assert!(w.io().outputs().fault);
    assert!(!w.io().outputs().ready);
    // START refused while the fault requires action (`interlock_fault` is on).
    w.cnc_line("TORCH ON");
    assert!(!w.io().outputs().start);
    assert_eq!(
        w.io().start_locked_by(),
        Some(Interlock::FaultRequiresAction)
    );
    w.cnc_line("TORCH OFF");

    assert_eq!(w.cnc_line("RESTART"), "OK restart=done quiet_ms=2000");
    // Commands that need the unit wait out the quiet time.
    assert_err(&w.cnc_line("SET AMPS 40"), "ERR BUSY *");
    // TORCH_ON during the quiet time is refused (the monitor checks the blackout too).
    w.run_for(ms(100));
    w.cnc_line("TORCH ON");
    assert!(!w.io().outputs().start);
    w.cnc_line("TORCH OFF");
    w.run_for(ms(2_500));
    let status = w.cnc_line("STATUS");
    assert_eq!(field(&status, "fault"), Some("none"), "{status}");
    assert_eq!(field(&status, "ready"), Some("ON"), "{status}");
    assert_eq!(w.cnc_line("FAULTLOG"), "OK log=0-50-0");
    w.cnc_line("TORCH ON");
    assert!(w.io().outputs().start, "cuts again after the quiet time");
    w.cnc_line("TORCH OFF");
}

#[test]
fn legacy_commands_ok_and_err() {
    let mut w = bridge_world(Model::Pm85);
    expect_all(
        &mut w,
        &[
            (
                "ID",
                "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=* family=LEGACY *",
            ),
            ("STATUS", "OK link=UP model=* family=LEGACY remote=OFF *"),
            ("LIMITS", "OK modes=CUT,CPA,GOUGE amps=*scope=unit"),
            ("FAULT", "OK fault=none"),
            (
                "FAULTLOG",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::FAULT_LOG, Family::PowermaxLegacy),
                )
                .as_str(),
            ),
            ("COUNTERS", "OK arc_s=0 link_ok=*"),
            (
                "CARTRIDGE",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::CARTRIDGE, Family::PowermaxLegacy),
                )
                .as_str(),
            ),
            (
                "SET AMPS 45",
                err(ErrorCode::State, texts::SETTINGS_UNKNOWN).as_str(),
            ),
            ("SET PROCESS CPA 45 AUTO", "OK mode=CPA amps=45 psi=AUTO"),
            ("SET AMPS 50", "OK mode=CPA amps=50 psi=AUTO"),
            (
                "SET PROCESS CUT 200 AUTO",
                "ERR RANGE amps 200 outside *for this unit",
            ),
            ("SET MODE GOUGE", "OK mode=GOUGE amps=50 psi=AUTO"),
            ("GASTEST ON", "OK gastest=ON"),
            ("GASTEST OFF", "OK gastest=OFF"),
            (
                "RESTART",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::RESTART, Family::PowermaxLegacy),
                )
                .as_str(),
            ),
            (
                "GASES N2 N2",
                "ERR UNSUPPORTED GASES is an HPR/MaxPro200 command; *",
            ),
            ("CORNER 80", "ERR UNSUPPORTED CORNER *"),
            ("RESET", "ERR UNSUPPORTED RESET *"),
            ("CLEARWARN", "ERR UNSUPPORTED CLEARWARN *"),
            ("RAW :010420900001*", "ERR REFUSED *"),
            ("REMOTE OFF", "OK remote=OFF"),
        ],
    );
    assert!(!w.unit_ref().in_remote_mode());
    // RAW read of a documented legacy register (0x2098 fault code).
    let frame = modbus("010320980001");
    assert!(
        w.cnc_line(&format!("RAW {frame}"))
            .starts_with("OK reply=:010302"),
        "{frame}"
    );
}

/// An HPR error above 79 shuts the unit down, and RESET (068) is allowed then: the unit over
/// time. Every command's reply text on each family is the session's test
/// (firmware/src/cnc/commands/tests.rs, `every_command_on_a_sync_unit`, `every_command_on_an_hpr`).
#[test]
fn an_hpr_shut_down_by_an_error_above_79_is_reset_from_the_cnc() {
    let mut w = ready_hpr(Model::Hpr260);
    w.inject_fault(80);
    w.run_until(
        |w| w.bridge().status().hpr.state.is_some_and(|s| s.0 == 14),
        Duration::from_secs(2),
    )
    .unwrap();
    assert!(
        w.cnc_line("FAULT")
            .starts_with("OK fault=080 action=required text=")
    );
    assert_eq!(w.cnc_line("RESET"), "OK reset=done");
    assert_eq!(w.cnc_line("FAULTLOG"), "OK log=080");
}

#[test]
fn maxpro200_commands_ok_and_err() {
    let mut w = ready_hpr(Model::MaxPro200);
    expect_all(
        &mut w,
        &[
            (
                "ID",
                "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=MaxPro200 family=MAXPRO200 \
                 torch=MACHINE lead_ft=25 firmware=A.0 gas_firmware=A.2",
            ),
            (
                "STATUS",
                "OK link=UP model=MaxPro200 family=MAXPRO200 *ready=ON state=3 \
                 state_name=READY_FOR_START gastest=OFF shield_psi=35 plasma=O2 shield=AIR",
            ),
            ("LIMITS", "OK amps=5..200"),
            (
                "FAULTLOG",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::FAULT_LOG, Family::MaxPro200),
                )
                .as_str(),
            ),
            ("COUNTERS", "OK link_ok=*"),
            ("SET AMPS 200", "OK amps=200"),
            ("SET AMPS 201", "ERR RANGE *201*5..200*"),
            ("GASES AIR AIR", "OK plasma=AIR shield=AIR"),
            (
                "SET MODE CUT",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::SET_MODE, Family::MaxPro200),
                )
                .as_str(),
            ),
            (
                "GASTEST CUTFLOW ON",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::GAS_FLOW_TEST, Family::MaxPro200),
                )
                .as_str(),
            ),
            (
                "CORNER 80",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::CORNER, Family::MaxPro200),
                )
                .as_str(),
            ),
            (
                "CLEARWARN",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::CLEAR_WARN, Family::MaxPro200),
                )
                .as_str(),
            ),
            ("GASES O2 AIR", "OK plasma=O2 shield=AIR"),
            (
                "SET HPR_PROCESS 150 N2 AIR",
                "OK amps=150 plasma=N2 shield=AIR",
            ),
            (
                "SET HPR_PROCESS 150.5 N2 AIR",
                "ERR RANGE *150.5*whole amps",
            ),
            ("SET HPR_PROCESS 201 N2 AIR", "ERR RANGE *201*5..200*"),
            // 095 and 078 in the MaxPro200's form (HPR manual (002_72b43a5685974c77.txt)
            // lines 180 and 165), answered once its 079 shows them.
            (
                "SET HPR_PARAMETERS 120 O2 AIR 60 40",
                "OK amps=120 plasma=O2 shield=AIR plasma_psi=60 shield_psi=40",
            ),
            ("SET HPR_GAS_FLOWS 50 58", "OK plasma_psi=50 shield_psi=58"),
            (
                "SET HPR_GAS_FLOWS 55 45 35 25 50 50",
                err(
                    ErrorCode::Unsupported,
                    UnsupportedText(unsupported::HPR_GAS_FLOWS_FORM, Family::MaxPro200),
                )
                .as_str(),
            ),
            ("RESET", "OK reset=done"),
        ],
    );
    assert_eq!(w.sim_ref::<Hpr>().nominal_amps(), 120);
}

/// `GASTEST ON|OFF` on a MaxPro200 is 143 SET TEST MODE 1 / 0: "1 Test Gas, plasma and
/// shield gases flow at set value", only in state 3 (HPR manual (002_72b43a5685974c77.txt)
/// line 283); STATUS shows it from the 079 display mode 3 "Test Mode" (line 168).
#[test]
fn a_maxpro200_gas_test_runs_143_test_gas() {
    let mut w = ready_hpr(Model::MaxPro200);
    assert_eq!(w.cnc_line("GASTEST ON"), "OK gastest=ON");
    assert!(w.sim_ref::<Hpr>().test_gas());
    w.run_for(ms(300));
    assert_eq!(field(&w.cnc_line("STATUS"), "gastest"), Some("ON"));
    assert_eq!(w.cnc_line("GASTEST OFF"), "OK gastest=OFF");
    assert!(!w.sim_ref::<Hpr>().test_gas());
    w.run_for(ms(300));
    assert_eq!(field(&w.cnc_line("STATUS"), "gastest"), Some("OFF"));
    let received = w.sim_ref::<Hpr>().commands_received();
    assert!(received.contains(&143));
    assert!(!received.iter().any(|id| (64..=67).contains(id)));
}

#[test]
fn without_a_unit_commands_that_need_one_answer_err_link() {
    let mut w = World::with_bridge(Model::Sync65, WorldOptions::default(), Settings::default());
    w.power_off();
    w.run_for(ms(1_000));
    let raw_refused = refusal_line(&Refusal::LinkNotUp, None);
    expect_all(
        &mut w,
        &[
            (
                "ID",
                "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=DOWN model=- family=-",
            ),
            (
                "STATUS",
                "OK link=DOWN model=- family=- remote=OFF mode=- amps=- psi=- out_amps=- out_psi=- fault=none start=OFF motion=OFF arc_ok=OFF ready=OFF",
            ),
            ("RAW :0104301A0001B0", raw_refused.as_str()),
            // Without a unit, COUNTERS still has the link's own counters.
            ("COUNTERS", "OK link_ok=0 link_failed=*"),
            ("TORCH ON", "OK torch=ON"),
        ],
    );
    for line in [
        "SET PROCESS CUT 45 AUTO",
        "SET AMPS 45",
        "REMOTE OFF",
        "GASTEST ON",
        "RESTART",
        "GASES O2 AIR",
        "CORNER 80",
        "RESET",
        "CLEARWARN",
        "FAULT",
        "FAULTLOG",
        "LIMITS",
        "CARTRIDGE",
    ] {
        assert_eq!(
            w.cnc_line(line),
            err(ErrorCode::Link, texts::NO_LINK),
            "{line}"
        );
    }
    // The link is down: the interlocks refuse START.
    assert!(!w.io().outputs().start);
    assert!(w.io().outputs().fault);
    assert_eq!(w.io().start_locked_by(), Some(Interlock::LinkDown));
    w.cnc_line("TORCH OFF");
}

// --- events --------------------------------------------------------------------------------

/// Events as the unit, the torch and the cable make them over time, with the I/O they drive.
/// Each line's exact text is the session's test
/// (`event_lines_say_exactly_what_happened_and_events_off_silences_them`,
/// firmware/src/cnc/events/tests.rs).
#[test]
fn events_follow_the_unit_the_torch_and_the_cable_over_time() {
    let mut w = World::with_bridge(
        Model::Sync65,
        WorldOptions::default(),
        Settings {
            events: true,
            ..Settings::default()
        },
    );
    w.wait_cnc_line(
        "!LINK UP model=Powermax65/85/105 SYNC",
        Duration::from_secs(1),
    )
    .unwrap();
    settle(&mut w);
    w.inject_fault(200);
    assert!(
        w.wait_cnc_line("!FAULT 0-20-0 ", Duration::from_secs(1))
            .unwrap()
            .contains("gas pressure")
    );
    assert!(w.io().outputs().fault);
    w.clear_fault();
    w.wait_cnc_line("!FAULT CLEARED code=0-20-0", Duration::from_secs(1))
        .unwrap();

    w.cnc_line("SET PROCESS CUT 45 AUTO");
    let events: Vec<&str> = w.cnc_events().collect();
    assert!(events.contains(&"!REMOTE ON"), "{events:?}");
    assert!(
        events
            .iter()
            .any(|e| e.starts_with("!SETTINGS applied mode=CUT amps=45")),
        "{events:?}"
    );

    w.cnc_line("TORCH ON");
    w.wait_cnc_line("!ARC ON", Duration::from_secs(1)).unwrap();
    w.cnc_line("TORCH OFF");
    w.wait_cnc_line("!ARC OFF", Duration::from_secs(1)).unwrap();
    w.run_for(ms(100));

    // START within 50 ms of the last: delayed, then on.
    w.cnc_line("TORCH ON");
    assert!(
        !w.cnc_events().any(|e| e.starts_with("!START DELAYED")),
        "the last START fell long ago"
    );
    w.cnc_line("TORCH OFF");
    w.cnc_line("TORCH ON");
    let delayed = w.cnc_events().last().unwrap().to_string();
    assert!(delayed.starts_with("!START DELAYED ms="), "{delayed}");
    w.run_for(ms(60));
    assert!(w.io().outputs().start);
    w.cnc_line("TORCH OFF");

    // The unit's cable is pulled and plugged back (its own power cycle: see
    // `after_the_units_own_power_cycle_it_stays_local_until_the_cnc_asks_again`).
    w.pull_cable(true);
    w.wait_cnc_line("!LINK DOWN reason=no_answer", Duration::from_secs(3))
        .unwrap();
    let status = w.cnc_line("STATUS");
    assert_eq!(field(&status, "link"), Some("DOWN"));
    w.pull_cable(false);
    w.wait_cnc_line("!LINK UP", Duration::from_secs(5)).unwrap();
    // The link puts the kept process back on the unit.
    w.wait_cnc_line("!SETTINGS applied mode=CUT amps=45", Duration::from_secs(5))
        .unwrap();
    assert!(w.unit_ref().in_remote_mode());

    // Off: no more event lines.
    assert_eq!(w.cnc_line("EVENTS OFF"), "OK events=OFF");
    let before = w.cnc_events().count();
    w.inject_fault(200);
    w.run_for(ms(1_000));
    assert_eq!(w.cnc_events().count(), before);
    assert_eq!(field(&w.cnc_line("STATUS"), "fault"), Some("0-20-0"));
}

// HPR manual (002_72b43a5685974c77.txt) line 54: Remote Power, an input of the unit, "is
// used to turn the power on or off"; line 51: System Error, an output of the unit, "indicates
// that an error has occurred in the plasma system".
#[test]
fn power_switches_an_hpr_off_and_on_and_system_error_is_a_fault() {
    let mut w = ready_hpr(Model::Hpr130);
    w.cnc_line("EVENTS ON");
    assert_eq!(w.cnc_line("POWER ON"), "OK power=ON");
    assert!(w.io().outputs().remote_power);
    assert_eq!(field(&w.cnc_line("STATUS"), "power"), Some("ON"));
    assert_eq!(w.cnc_line("POWER OFF"), "OK power=OFF");
    assert!(!w.unit_ref().is_powered());
    w.wait_cnc_line("!LINK DOWN reason=no_answer", Duration::from_secs(10))
        .unwrap();
    assert!(w.io().outputs().fault && !w.io().outputs().ready);
    // A unit that is off has no link: POWER needs none.
    assert_eq!(w.cnc_line("POWER ON"), "OK power=ON");
    w.wait_cnc_line("!LINK UP", Duration::from_secs(10))
        .unwrap();
    w.run_until(|w| !w.io().outputs().fault, Duration::from_secs(10))
        .expect("FAULT clears with the link back");

    w.set_input(Input::SystemError, true);
    w.run_for(ms(10));
    assert!(w.cnc_events().any(|e| e.starts_with("!SYSTEM ERROR")));
    assert!(w.io().outputs().fault);
    assert_eq!(field(&w.cnc_line("STATUS"), "system_error"), Some("ON"));
    let fault_on = w
        .transitions()
        .iter()
        .rev()
        .find(|t| t.output == Output::Fault);
    assert_eq!(fault_on.map(|t| t.reason), Some(Reason::SystemErrorSignal));
    w.set_input(Input::SystemError, false);
    w.run_for(ms(50));
    assert!(!w.io().outputs().fault);
    assert_eq!(field(&w.cnc_line("STATUS"), "system_error"), None);
}

// HPR manual (002_72b43a5685974c77.txt) line 55: NOT READY FOR START, "purging or in test gas
// mode"; lines 456-459: state 02 PURGE, 03 IDLE2 (ready for start).
#[test]
fn an_hpr_still_purging_refuses_start_as_not_ready_and_a_fresh_press_fires_once_ready() {
    let mut w = bridge_world(Model::Hpr130);
    w.cnc_line("EVENTS ON");
    w.run_until(
        |w| w.bridge().status().hpr.state == Some(plasma_protocol::hpr::StateCode(2)),
        Duration::from_secs(5),
    )
    .expect("the link sees the purge");
    let status = w.cnc_line("STATUS");
    assert_eq!(field(&status, "ready"), Some("OFF"), "{status}");
    w.set_torch(true);
    w.run_until(
        |w| {
            w.cnc_events()
                .any(|e| e == "!START REFUSED reason=not_ready")
        },
        ms(500),
    )
    .expect("the refusal reaches the CNC");
    assert_eq!(w.io().start_locked_by(), Some(Interlock::NotReady));
    assert!(!w.io().outputs().start);
    assert_eq!(field(&w.cnc_line("STATUS"), "start"), Some("OFF"));

    w.run_until(|w| w.bridge().status().ready, Duration::from_secs(10))
        .expect("the purge ends");
    w.run_for(ms(200));
    assert!(
        !w.io().outputs().start,
        "the refusal latches until released"
    );
    assert_eq!(w.sim_ref::<Hpr>().counters().starts, 0);
    w.set_torch(false);
    w.set_torch(true);
    assert!(w.io().outputs().start);
    w.wait_cnc_line("!STATE 4 name=PREFLOW from=3", Duration::from_secs(1))
        .unwrap();
    // The unit left IDLE2 because it took the start: START stays on.
    w.run_for(ms(300));
    assert!(w.io().outputs().start);
}

#[test]
fn hpr_events_report_state_changes_and_a_transfer_timeout() {
    let mut w = ready_hpr(Model::Hpr130);
    w.cnc_line("EVENTS ON");
    // The torch never reaches the plate.
    w.sim::<Hpr>().config_mut().timings.transfer_delay = None;
    w.cnc_line("TORCH ON");
    w.wait_cnc_line("!STATE 4 name=PREFLOW from=3", Duration::from_secs(1))
        .unwrap();
    w.wait_cnc_line("!TRANSFER TIMEOUT", Duration::from_secs(4))
        .unwrap();
    assert!(
        w.cnc_events()
            .any(|e| e == "!START DROPPED reason=transfer_timeout"),
        "{:?}",
        w.cnc_events().collect::<Vec<_>>()
    );
    assert!(!w.io().outputs().start);
    assert!(
        w.io_events()
            .iter()
            .any(|(_, e)| *e == IoEvent::TransferTimeout)
    );
    w.cnc_line("TORCH OFF");
}

// --- Phoenix serial messaging ----------------------------------------------------------------
// ACK/NAK, the formats, bad input and the queue are the session's rules, tested next to it
// (firmware/src/cnc/input/tests.rs); here only what needs the clock: a message cut off.

#[test]
fn a_phoenix_message_that_stops_arriving_is_naked_and_text_goes_on() {
    let mut w = bridge_world(Model::Sync65);
    w.cnc_send(b"\x01\x02FAU");
    w.wait_cnc_replies(1, Duration::from_secs(1)).unwrap();
    assert_eq!(w.cnc_output()[0].item, CncItem::Nak);
    assert_eq!(
        w.cnc_replies().next(),
        Some(err(ErrorCode::Syntax, texts::PHOENIX_TRUNCATED).as_str())
    );
    assert_eq!(w.cnc_line("FAULT"), "OK fault=none");
}

// --- the allow-list --------------------------------------------------------------------------
// What a refusal says is the session's test (`raw_replies_carry_the_units_answer_or_say_why_
// the_frame_is_refused`, firmware/src/cnc/commands/tests.rs); here that a refused frame never
// reaches the unit or the wire.

#[test]
fn raw_refuses_dangerous_hpr_commands_and_they_never_reach_the_unit() {
    let mut w = ready_hpr(Model::Hpr260);
    // 120 IGNORE_ALL_INTERLOCKS, 102 gas valves (factory testing), 086 SLEEP (the link's).
    for (frame, id) in [(hpr("120"), 120), (hpr("1020001"), 102), (hpr("086"), 86)] {
        let reply = w.cnc_line(&format!("RAW {frame}"));
        assert_eq!(
            reply,
            format!("ERR REFUSED raw command {id:03} not allowed"),
            "{frame}"
        );
    }
    // An allowed one does arrive.
    assert!(
        w.cnc_line(&format!("RAW {}", hpr("002")))
            .starts_with("OK reply=>002")
    );
    let received = w.sim_ref::<Hpr>().commands_received();
    for id in [120, 102, 86] {
        assert!(
            !received.contains(&id),
            "{id} reached the unit: {received:?}"
        );
    }
    assert!(received.contains(&2));
    assert!(
        !w.trace()
            .requests()
            .any(|f| f.bytes.starts_with(b">120") || f.bytes.starts_with(b">102")),
        "on the wire"
    );
}

#[test]
fn raw_refuses_a_modbus_write_to_an_undocumented_register_and_it_never_reaches_the_unit() {
    let mut w = bridge_world(Model::Sync65);
    // 0x3013 lies between the settings and the actual outputs: undocumented.
    let undocumented = modbus("010630130001");
    assert_err(
        &w.cnc_line(&format!("RAW {undocumented}")),
        "ERR REFUSED *3013*",
    );
    // Also a write to a documented read-only register.
    let read_only = modbus("010630100001");
    assert_err(
        &w.cnc_line(&format!("RAW {read_only}")),
        "ERR REFUSED *3010*",
    );
    // A frame for another node address.
    let other_node = modbus("0204301A0001");
    assert!(
        w.cnc_line(&format!("RAW {other_node}"))
            .starts_with("ERR REFUSED")
    );
    // A documented read passes.
    assert!(
        w.cnc_line(&format!("RAW {}", modbus("0104301A0001")))
            .starts_with("OK reply=:0104")
    );
    let sent: Vec<&[u8]> = w.trace().requests().map(|f| &f.bytes[..]).collect();
    assert!(
        !sent.iter().any(|f| f.starts_with(b":01063013")
            || f.starts_with(b":01063010")
            || f.starts_with(b":02")),
        "never on the wire"
    );
}

// --- CONFIG, SAVE, power cycles ------------------------------------------------------------

#[test]
fn a_config_change_of_an_io_key_applies_live() {
    let mut w = bridge_world(Model::Sync65);
    let arc_delay = |w: &mut World<host_tests::harness::BridgeEndpoint>| {
        w.cnc_line("TORCH ON");
        let on = w.now();
        w.run_until(|w| w.io().outputs().arc_ok, Duration::from_secs(2))
            .unwrap();
        let delay = w.now().saturating_since(on);
        w.cnc_line("TORCH OFF");
        w.run_for(ms(300));
        delay
    };
    let default = arc_delay(&mut w);
    assert_eq!(
        w.cnc_line("CONFIG arc_ok_debounce_ms 60"),
        "OK arc_ok_debounce_ms=60"
    );
    assert_eq!(w.io().config().arc_ok_debounce, ms(60));
    let slower = arc_delay(&mut w);
    assert_eq!(
        slower.as_micros() - default.as_micros(),
        58_000,
        "debounce 2 ms -> 60 ms: {default:?} {slower:?}"
    );

    // interlock_fault OFF: a fault that requires action (0-50-0) no longer refuses START.
    w.inject_fault(500);
    w.run_for(ms(300));
    w.cnc_line("TORCH ON");
    assert!(!w.io().outputs().start);
    w.cnc_line("TORCH OFF");
    assert_eq!(
        w.cnc_line("CONFIG interlock_fault OFF"),
        "OK interlock_fault=OFF"
    );
    assert!(!w.io().config().refuse_start_on_fault);
    w.run_for(ms(100));
    w.cnc_line("TORCH ON");
    assert!(
        w.io().outputs().start,
        "START follows with the interlock off"
    );
    // And back on: stricter at once, START drops.
    assert_eq!(
        w.cnc_line("CONFIG interlock_fault ON"),
        "OK interlock_fault=ON"
    );
    assert!(!w.io().outputs().start);
    w.cnc_line("TORCH OFF");
}

/// A power cycle of the whole installation: each layer's saved keys (I/O, link, session) come
/// back and the process is applied again. The CONFIG text and the record codec themselves are
/// the session's test (`config_get_set_and_save_round_trip_through_the_settings_record`,
/// firmware/src/cnc/commands/tests.rs).
#[test]
fn config_save_and_a_power_cycle_keep_the_config_and_reapply_the_process() {
    let mut w = bridge_world(Model::Sync65);
    expect_all(
        &mut w,
        &[
            ("SET PROCESS CUT 40 AUTO", "OK mode=CUT amps=40 psi=AUTO"),
            ("CONFIG arc_ok_debounce_ms 7", "OK arc_ok_debounce_ms=7"),
            ("EVENTS ON", "OK events=ON"),
            (
                "CONFIG reapply_after_power_cycle on",
                "OK reapply_after_power_cycle=ON",
            ),
            (
                "CONFIG timeout_ms 250",
                "OK timeout_ms=250 link=redetecting",
            ),
            ("CONFIG SAVE", "OK config=saved"),
        ],
    );
    let saved = w.saved_settings().expect("stored");
    assert!(saved.events);
    assert_eq!(saved.io.arc_ok_debounce, ms(7));
    assert_eq!(saved.link.response_timeout, ms(250));
    assert!(saved.link.reapply_after_power_cycle);
    assert_eq!(saved.process.map(|p| p.amps.raw()), Some(40 * 64));

    // The whole installation loses power; the bridge comes back first.
    w.power_off();
    w.power_cycle_bridge();
    assert_eq!(
        w.io().config().arc_ok_debounce,
        ms(7),
        "the interlocks use the stored io settings"
    );
    w.run_for(ms(500));
    w.power_on();
    w.wait_cnc_line("!SETTINGS applied mode=CUT amps=40", Duration::from_secs(5))
        .unwrap();
    assert!(w.unit_ref().in_remote_mode());
    assert_eq!(w.sim_ref::<Powermax>().settings().current, 40 * 64);
    assert_eq!(
        w.cnc_line("CONFIG arc_ok_debounce_ms"),
        "OK arc_ok_debounce_ms=7"
    );
    assert_eq!(w.cnc_line("CONFIG events"), "OK events=ON");
    assert_eq!(w.cnc_line("CONFIG timeout_ms"), "OK timeout_ms=250");
    assert_eq!(
        w.cnc_line("CONFIG reapply_after_power_cycle"),
        "OK reapply_after_power_cycle=ON"
    );

    // Unsaved changes do not survive.
    assert_eq!(
        w.cnc_line("CONFIG arc_ok_debounce_ms 9"),
        "OK arc_ok_debounce_ms=9"
    );
    w.power_cycle_bridge();
    settle(&mut w);
    assert_eq!(
        w.cnc_line("CONFIG arc_ok_debounce_ms"),
        "OK arc_ok_debounce_ms=7"
    );
}

#[test]
fn a_failed_save_says_so_and_keeps_the_old_record() {
    let mut w = bridge_world(Model::Sync65);
    assert_eq!(w.cnc_line("CONFIG SAVE"), "OK config=saved");
    w.cnc_line("CONFIG poll_ms 200");
    w.endpoint_mut().fail_next_save(SaveError::Flash);
    assert_err(&w.cnc_line("CONFIG SAVE"), "ERR STORAGE *");
    assert_eq!(w.saved_settings(), Some(Settings::default()));
    assert_eq!(w.endpoint().saves(), 2);
}

#[test]
fn a_torch_on_held_through_a_bridge_power_cycle_is_ignored_until_released() {
    let mut w = bridge_world_with(
        Model::Pm65,
        Settings {
            events: true,
            ..Settings::default()
        },
    );
    w.cnc_line("CONFIG SAVE");
    w.set_torch(true);
    w.run_for(ms(200));
    assert!(w.io().outputs().start);
    w.power_cycle_bridge();
    assert!(!w.io().outputs().start, "off at reset");
    settle(&mut w);
    assert!(!w.io().outputs().start, "a held TORCH_ON is ignored");
    assert_eq!(w.io().start_locked_by(), Some(Interlock::TorchOnAtPowerUp));
    assert!(
        w.cnc_events()
            .any(|e| e == "!START REFUSED reason=torch_on_at_power_up"),
        "{:?}",
        w.cnc_events().collect::<Vec<_>>()
    );
    w.set_torch(false);
    w.run_for(ms(100));
    w.set_torch(true);
    assert!(w.io().outputs().start, "a fresh TORCH_ON works");
    w.set_torch(false);
}

#[test]
fn mode_aliases_are_answered_in_the_family_s_own_word() {
    let mut w = bridge_world(Model::Sync65);
    assert_eq!(
        w.cnc_line("SET PROCESS CPA 45 AUTO"),
        "OK mode=EXPANDED amps=45 psi=AUTO"
    );
    let mut w = bridge_world(Model::Pm65);
    assert_eq!(
        w.cnc_line("SET PROCESS EXPANDED 45 AUTO"),
        "OK mode=CPA amps=45 psi=AUTO"
    );
}

#[test]
fn the_bare_bridge_is_an_endpoint_too() {
    use plasma_firmware::bridge::Bridge;
    use plasma_protocol::time::Instant;
    for model in [
        Model::Sync105,
        Model::Pm125,
        Model::Hpr400Xd,
        Model::MaxPro200,
    ] {
        let unit = model.build(&Default::default());
        let bridge = Bridge::new(Settings::default(), Instant::ZERO);
        let mut w = World::with_endpoint(bridge, unit, WorldOptions::default());
        w.wait_link_up(Duration::from_secs(2))
            .unwrap_or_else(|t| panic!("{model}: {t}"));
        // The bridge consumes the link's events itself.
        assert!(w.events().is_empty());
        assert!(w.io().outputs().ready || model.family() == plasma_sim::Family::Hpr);
    }
}

#[test]
fn a_torch_on_wiring_change_during_a_cut_drops_start_until_released() {
    let mut w = bridge_world_with(
        Model::Pm65,
        Settings {
            events: true,
            ..Settings::default()
        },
    );
    settle(&mut w);
    w.set_torch(true);
    w.run_for(ms(200));
    assert!(w.io().outputs().start);
    assert_eq!(
        w.cnc_line("CONFIG torch_on_debounce_ms 3"),
        "OK torch_on_debounce_ms=3"
    );
    w.run_for(ms(100));
    assert!(
        !w.io().outputs().start,
        "a change never keeps or fires START"
    );
    assert_eq!(
        w.io().start_locked_by(),
        Some(Interlock::TorchOnAtWiringChange)
    );
    assert!(
        w.cnc_events()
            .any(|e| e == "!START DROPPED reason=torch_on_at_config"),
        "{:?}",
        w.cnc_events().collect::<Vec<_>>()
    );
    w.set_torch(false);
    w.run_for(ms(100));
    w.set_torch(true);
    w.run_for(ms(100));
    assert!(w.io().outputs().start, "a fresh press fires");
    assert_eq!(w.cnc_line("CONFIG SAVE"), "OK config=saved");
    let saved = w.saved_settings().unwrap();
    assert_eq!(
        saved.io.inputs.get(Input::TorchOn).debounce,
        Duration::from_millis(3)
    );
    w.assert_safe();
}

/// The history survives the bridge's power cycle, and every family's faults go into it with
/// their codes (a Powermax X-YY-Z, an HPR error number) and the unit's model, named as STATUS
/// names it. The entries' order, numbering and link events are the session's test
/// (firmware/src/cnc/history.rs, `faults_the_link_and_a_reset_are_kept_newest_first`).
#[test]
fn the_history_keeps_faults_across_a_power_cycle_on_every_family() {
    for (model, code, written) in [
        (Model::Sync65, 500, "0-50-0"),
        (Model::Pm65, 500, "0-50-0"),
        (Model::Hpr260, 44, "044"),
        (Model::MaxPro200, 44, "044"),
    ] {
        let mut w = World::with_bridge(model, WorldOptions::default(), Settings::default());
        w.wait_link_up(Duration::from_secs(5)).unwrap();
        w.run_for(Duration::from_millis(500));
        let status = w.cnc_line("STATUS");
        let named = status
            .split(' ')
            .find(|f| f.starts_with("model="))
            .unwrap_or_else(|| panic!("{status}"))
            .to_string();
        assert_ne!(named, "model=-", "{status}");
        assert_eq!(
            w.cnc_line("CLOCK 2026-11-26T07:30:00"),
            "OK clock=2026-11-26T07:30:00"
        );
        w.inject_fault(code);
        w.run_for(Duration::from_secs(2));
        w.clear_fault();
        w.run_for(Duration::from_secs(2));
        w.power_cycle_bridge();
        w.wait_link_up(Duration::from_secs(5)).unwrap();
        let mark = w.cnc_output().len();
        assert_eq!(
            w.cnc_line("HISTORY 3"),
            "OK history=3 skipped=0",
            "{model:?}"
        );
        let lines: Vec<&str> = w.cnc_output()[mark..]
            .iter()
            .filter_map(|r| r.item.line())
            .collect();
        assert!(
            lines[0].contains(" boot=1 ")
                && lines[0].ends_with(" family=- model=- event=RESET cause=power-on"),
            "{model:?}: {lines:?}"
        );
        assert!(
            lines[1].contains(" boot=0 ") && lines[1].contains(" clock=2026-11-26T07:30:0"),
            "{model:?}: {lines:?}"
        );
        assert!(
            lines[1].ends_with(&format!(" event=FAULT_CLEARED code={written}")),
            "{model:?}: {lines:?}"
        );
        assert!(
            lines[2].contains(&format!(" event=FAULT code={written} action=")),
            "{model:?}: {lines:?}"
        );
        for entry in &lines[1..3] {
            assert!(entry.contains(&format!(" {named} ")), "{named}: {lines:?}");
        }
        // The new boot's clock is unset until the CNC sets it again.
        assert_eq!(w.cnc_line("CLOCK"), "OK clock=unset");
    }
}

/// A manual gas console HPR (HELLO `HYPERFORMANCE130MANUAL`) is never sent what the manual's
/// "System" column leaves it out of: 058 SET_NOMINAL_AMPS and 096 SET_INLET_GASES are "Auto
/// Gas System MaxPro200" (HPR manual (002_72b43a5685974c77.txt) lines 149, 180). LIMITS says
/// the CNC sets no current; STATUS shows the knobs' gases from 122 READ_GAS_SWITCH (line 252).
#[test]
fn a_manual_gas_console_hpr_gets_no_setting_its_console_does_not_take() {
    use plasma_firmware::link::Refusal;
    let mut options = WorldOptions::default();
    options.sim.gas_console = plasma_sim::hpr::GasConsole::Manual;
    let mut w = World::with_bridge(Model::Hpr130, options, Settings::default());
    settle(&mut w);
    w.run_until(|w| w.bridge().status().ready, Duration::from_secs(10))
        .expect("ready");
    let system = plasma_protocol::hpr::SystemId::parse(b"HYPERFORMANCE130MANUAL").unwrap();
    let refusal = |id| refusal_line(&Refusal::NotOnThisSystem { id, system }, Some(Family::Hpr));
    expect_all(
        &mut w,
        &[
            ("LIMITS", "OK amps=- corner=50..100 console=MANUAL"),
            ("SET AMPS 100", refusal(58).as_str()),
            ("GASES O2 N2", refusal(96).as_str()),
            // Lines 165 and 180: 078 and 095 are "Auto Gas System MaxPro200" too.
            (
                "SET HPR_PARAMETERS 100 75 O2 N2 55 45 35 25 0 0",
                refusal(95).as_str(),
            ),
            ("SET HPR_GAS_FLOWS 55 45 35 25 50 50", refusal(78).as_str()),
            ("CORNER 80", "OK corner=80"),
            ("RAW >05813031<", refusal(58).as_str()),
        ],
    );
    assert!(
        refusal(58).contains("manual gas console"),
        "{}",
        refusal(58)
    );
    w.run_for(ms(500));
    let status = w.cnc_line("STATUS");
    assert_eq!(field(&status, "console"), Some("MANUAL"), "{status}");
    assert_eq!(field(&status, "amps"), Some("130"), "{status}");
    assert_eq!(field(&status, "plasma"), Some("O2"), "{status}");
    assert_eq!(field(&status, "shield"), Some("AIR"), "{status}");
    let received = w.sim_ref::<Hpr>().commands_received();
    assert!(received.contains(&122));
    for id in [58, 78, 95, 96, 99, 98] {
        assert!(
            !received.contains(&id),
            "{id:03} reached the manual console"
        );
    }
}

// --- the unit's power cycle or a pulled cable ------------------------------------------------

/// A unit with a setting the CNC made, events on, in remote control.
fn remote_unit(model: Model, setting: &str) -> World<host_tests::harness::BridgeEndpoint> {
    let mut w = if model.family() == plasma_sim::Family::Hpr {
        ready_hpr(model)
    } else {
        bridge_world(model)
    };
    assert_eq!(w.cnc_line("EVENTS ON"), "OK events=ON");
    let reply = w.cnc_line(setting);
    assert!(reply.starts_with("OK "), "{model:?} {setting}: {reply}");
    assert!(w.bridge().status().remote, "{model:?}");
    w
}

/// Events that arrived after the first `mark` lines.
fn events_since(w: &World<host_tests::harness::BridgeEndpoint>, mark: usize) -> Vec<String> {
    w.cnc_lines()
        .skip(mark)
        .filter(|l| l.starts_with('!'))
        .map(str::to_string)
        .collect()
}

const SETTINGS_BY_FAMILY: [(Model, &str); 3] = [
    (Model::Sync65, "SET PROCESS CUT 45 AUTO"),
    (Model::Pm65, "SET PROCESS CUT 45 AUTO"),
    (Model::Hpr130, "SET AMPS 100"),
];

/// A pulled cable is a lost link: the unit kept remote control and the bridge applies the
/// kept settings again when it answers, without a power-cycle event.
#[test]
fn after_a_pulled_cable_the_kept_settings_are_applied_again() {
    for (model, setting) in SETTINGS_BY_FAMILY {
        let mut w = remote_unit(model, setting);
        w.pull_cable(true);
        w.wait_cnc_line("!LINK DOWN", Duration::from_secs(5))
            .unwrap_or_else(|t| panic!("{model:?}: {t}"));
        let mark = w.cnc_lines().count();
        w.pull_cable(false);
        w.wait_cnc_line("!REMOTE ON", Duration::from_secs(10))
            .unwrap_or_else(|t| panic!("{model:?}: not re-applied: {t}"));
        let events = events_since(&w, mark);
        assert!(
            !events.iter().any(|e| e.starts_with("!UNIT POWER_CYCLED")),
            "{model:?}: {events:?}"
        );
        w.assert_safe();
    }
}

/// SYNC manual (000_dd931256418ae627.txt) line 1189: "You can also stop remote control mode by
/// setting the power switch on the plasma power supply to the OFF (O) position and waiting
/// approximately 1 minute." After that the bridge leaves the unit in local control, says so,
/// and takes it back only when the CNC sets a process again (or when configured to).
#[test]
fn after_the_units_own_power_cycle_it_stays_local_until_the_cnc_asks_again() {
    for (model, setting) in SETTINGS_BY_FAMILY {
        let mut w = remote_unit(model, setting);
        w.power_off();
        w.run_for(Duration::from_secs(60));
        assert!(!w.bridge().status().link_up, "{model:?}");
        let mark = w.cnc_lines().count();
        w.power_on();
        w.wait_cnc_line("!UNIT POWER_CYCLED reapply=OFF", Duration::from_secs(10))
            .unwrap_or_else(|t| panic!("{model:?}: {t}"));
        w.run_for(Duration::from_secs(10));
        assert!(!w.bridge().status().remote, "{model:?}: taken back");
        // The history keeps it, after the link lost while the unit was off.
        let history_mark = w.cnc_output().len();
        assert!(
            w.cnc_line("HISTORY 3").starts_with("OK history=3"),
            "{model:?}"
        );
        let entries: Vec<&str> = w.cnc_output()[history_mark..]
            .iter()
            .filter_map(|r| r.item.line())
            .filter(|l| l.starts_with("HISTORY "))
            .collect();
        let position = |event: &str| entries.iter().position(|l| l.contains(event));
        let (cycled, lost) = (
            position(" event=UNIT_POWER_CYCLED"),
            position(" event=LINK_LOST"),
        );
        assert!(
            cycled.is_some() && lost.is_some() && cycled < lost,
            "{model:?}: {entries:?}"
        );
        assert_eq!(w.bridge().settings().process, None, "{model:?}: not kept");
        let events = events_since(&w, mark);
        assert!(
            !events.iter().any(|e| e.starts_with("!REMOTE ON")),
            "{model:?}: {events:?}"
        );
        // The CNC asks again: remote control again.
        if model.family() == plasma_sim::Family::Hpr {
            w.run_until(|w| w.bridge().status().ready, Duration::from_secs(10))
                .expect("the unit becomes ready");
        }
        let reply = w.cnc_line(setting);
        assert!(reply.starts_with("OK "), "{model:?}: {reply}");
        assert!(w.bridge().status().remote, "{model:?}");
        // Configured to: the next power cycle gets the settings again.
        assert_eq!(
            w.cnc_line("CONFIG reapply_after_power_cycle ON"),
            "OK reapply_after_power_cycle=ON"
        );
        assert!(w.bridge().status().link_up, "no detection for the policy");
        w.power_off();
        w.run_for(Duration::from_secs(60));
        w.power_on();
        w.wait_cnc_line("!UNIT POWER_CYCLED reapply=ON", Duration::from_secs(10))
            .unwrap_or_else(|t| panic!("{model:?}: {t}"));
        w.wait_cnc_line("!REMOTE ON", Duration::from_secs(30))
            .unwrap_or_else(|t| panic!("{model:?}: not re-applied: {t}"));
        w.assert_safe();
    }
}
