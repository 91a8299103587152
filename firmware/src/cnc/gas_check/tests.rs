extern crate std;
use std::string::String;
use std::vec::Vec;

use plasma_protocol::cnc::ErrorCode;

use plasma_protocol::time::Duration;

use super::MAX_FLOW_TIME;
use crate::cnc::rig::{Rig, err, is_reply};
use crate::cnc::texts;
use crate::io::{Inputs, Outputs};
use crate::settings::Settings;

/// The SYNC gas-test coil (SYNC manual, 000_dd931256418ae627.txt line 532).
const SYNC_GAS_TEST: u16 = 0x3180;

fn gas_test_writes(rig: &mut Rig) -> Vec<u16> {
    rig.writes()
        .into_iter()
        .filter(|(address, _)| *address == SYNC_GAS_TEST)
        .map(|(_, values)| values[0])
        .collect()
}

fn newest_history(rig: &mut Rig) -> String {
    let tokens = rig.send_bytes(b"HISTORY 1\r\n", 1);
    let lines: Vec<String> = tokens.into_iter().filter(|t| !t.starts_with('!')).collect();
    assert!(lines.last().is_some_and(|l| is_reply(l)), "{lines:?}");
    lines[0].clone()
}

/// The SYNC simulator's cartridge permits 58-78 psi (0x3004/0x3005, the guide's example at
/// SYNC manual lines 784-785) and sets 72 psi automatically.
#[test]
fn a_sync_unit_with_ample_gas_passes_and_the_test_is_ended() {
    let mut rig = Rig::sync65(Settings::default());
    let reply = rig.cmd("GASTEST CHECK");
    assert_eq!(
        reply,
        "OK GASTEST CHECK result=PASS measured_psi=76 min_psi=58 max_psi=78"
    );
    assert_eq!(gas_test_writes(&mut rig), [1, 0]);
    assert!(!rig.ps().powermax().gas_test_active());
    rig.run(100);
    assert!(
        newest_history(&mut rig)
            .ends_with(" event=GAS_CHECK result=PASS psi=76 min_psi=58 max_psi=78"),
    );
}

#[test]
fn a_weak_supply_fails_and_the_test_is_ended() {
    let mut rig = Rig::sync65(Settings::default());
    rig.ps().powermax().set_supply_psi(Some(45));
    let reply = rig.cmd("GASTEST CHECK");
    assert_eq!(
        reply,
        "OK GASTEST CHECK result=FAIL measured_psi=45 min_psi=58 max_psi=78"
    );
    assert!(!rig.ps().powermax().gas_test_active());
    rig.run(100);
    assert!(newest_history(&mut rig).contains(" event=GAS_CHECK result=FAIL psi=45 "));
}

#[test]
fn refused_while_the_torch_is_on_and_nothing_is_sent() {
    let mut rig = Rig::sync65(Settings::default());
    let torch = Inputs {
        torch_on: true,
        ..Inputs::NONE
    };
    rig.bridge.set_io_snapshot(torch, Outputs::OFF);
    assert_eq!(
        rig.cmd("GASTEST CHECK"),
        err(ErrorCode::State, texts::GAS_CHECK_TORCH_ON)
    );
    assert!(gas_test_writes(&mut rig).is_empty());
}

#[test]
fn refused_while_a_fault_requires_action_not_for_a_low_pressure_warning() {
    let mut rig = Rig::sync65(Settings::default());
    rig.fault(500);
    rig.run(300);
    let reply = rig.cmd("GASTEST CHECK");
    assert_eq!(
        reply,
        err(
            ErrorCode::State,
            std::format!("{} 0-50-0", texts::GAS_CHECK_FAULTED)
        )
    );
    assert!(gas_test_writes(&mut rig).is_empty());
    // 0-12-1 "the gas pressure output is low", "No, but recommended" (SYNC manual line 945).
    rig.fault(0);
    rig.fault(121);
    rig.run(300);
    assert!(
        rig.cmd("GASTEST CHECK")
            .starts_with("OK GASTEST CHECK result=")
    );
}

#[test]
fn the_torch_coming_on_ends_the_test_at_once() {
    let mut rig = Rig::sync65(Settings::default());
    let tokens = rig.send_bytes(b"GASTEST CHECK\r\n", 0);
    assert!(tokens.is_empty(), "{tokens:?}");
    rig.run(1000);
    assert!(rig.ps().powermax().gas_test_active());
    let start = Outputs {
        start: true,
        ..Outputs::OFF
    };
    rig.bridge.set_io_snapshot(Inputs::NONE, start);
    rig.run(200);
    assert_eq!(
        rig.received.last().map(String::as_str),
        Some(err(ErrorCode::State, texts::GAS_CHECK_STOPPED_TORCH).as_str())
    );
    assert!(!rig.ps().powermax().gas_test_active());
    assert_eq!(gas_test_writes(&mut rig), [1, 0]);
}

#[test]
fn a_link_lost_mid_check_ends_it_and_the_stop_goes_out_when_the_link_is_back() {
    let mut rig = Rig::sync65(Settings::default());
    rig.send_bytes(b"GASTEST CHECK\r\n", 0);
    rig.run(500);
    rig.unplug(true);
    rig.run(3000);
    assert_eq!(
        rig.received.last().map(String::as_str),
        Some(err(ErrorCode::Link, texts::GAS_CHECK_LINK_LOST).as_str())
    );
    // The unit never heard the stop: its gas still flows until the link is back.
    assert!(rig.ps().powermax().gas_test_active());
    rig.unplug(false);
    rig.run(2000);
    assert!(rig.bridge.status().link_up);
    assert!(!rig.ps().powermax().gas_test_active());
    assert_eq!(gas_test_writes(&mut rig), [1, 0]);
}

/// HPR manual (002_72b43a5685974c77.txt): 066/067 the cutflow test (line 154-155), 079's
/// measured pressures (line 168); the limits of errors 044/045 and 053/054 (lines 382-389).
#[test]
fn an_hpr_checks_both_gases_in_the_cutflow_test() {
    let mut rig = Rig::hpr("hpr130");
    let reply = rig.cmd("GASTEST CHECK");
    assert_eq!(
        reply,
        "OK GASTEST CHECK result=PASS plasma_psi=55 plasma_min_psi=50 plasma_max_psi=110 \
         shield_psi=35 shield_min_psi=2 shield_max_psi=110"
    );
    let sent = rig.hpr_commands();
    let start = sent.iter().position(|&id| id == 66).expect("066 sent");
    let stop = sent.iter().position(|&id| id == 67).expect("067 sent");
    assert!(start < stop && sent[start..stop].contains(&79), "{sent:?}");
}

#[test]
fn an_hpr_with_a_weak_supply_fails_on_its_plasma() {
    let mut rig = Rig::hpr("hpr130");
    rig.ps().hpr().set_supply_psi(Some(40));
    let reply = rig.cmd("GASTEST CHECK");
    assert!(
        reply.starts_with("OK GASTEST CHECK result=FAIL plasma_psi=40 "),
        "{reply}"
    );
    assert_eq!(rig.hpr_commands().last(), Some(&67));
}

/// HPR manual: 143 mode 1 "Test Gas" and mode 0 (line 283); 079 has only the set points on
/// a MaxPro200 (line 168), 141 the measured pressures `plap`/`shap` (line 281).
#[test]
fn a_maxpro200_reads_its_measured_pressures_during_the_test_gas() {
    let mut rig = Rig::hpr("maxpro200");
    rig.ps().hpr().set_supply_psi(Some(42));
    let reply = rig.cmd("GASTEST CHECK");
    assert_eq!(
        reply,
        "OK GASTEST CHECK result=FAIL plasma_psi=42 plasma_min_psi=50 plasma_max_psi=110 \
         shield_psi=35 shield_min_psi=2 shield_max_psi=110"
    );
    let sent = rig.hpr_commands();
    let start = sent.iter().position(|&id| id == 143).expect("143 sent");
    assert!(sent[start..].contains(&141), "{sent:?}");
    assert_eq!(sent.last(), Some(&143));
    assert!(!rig.ps().hpr().test_gas());
}

#[test]
fn a_pressure_that_never_settles_fails_once_the_flow_time_is_up() {
    let mut rig = Rig::sync65(Settings::default());
    rig.send_bytes(b"GASTEST CHECK\r\n", 0);
    // The supply saws 3 psi every 100 ms: two readings 500 ms apart never agree within 2 psi.
    let limit = rig.now + MAX_FLOW_TIME + Duration::from_secs(2);
    let mut step = 0u16;
    while rig.now < limit && !rig.received.iter().any(|t| is_reply(t)) {
        step += 1;
        let psi = 20 + (step * 3) % 50;
        rig.ps().powermax().set_supply_psi(Some(psi));
        rig.run(100);
    }
    let reply = rig.received.iter().find(|t| is_reply(t)).expect("a reply");
    assert!(
        reply.starts_with("OK GASTEST CHECK result=FAIL "),
        "{reply}"
    );
    assert!(reply.ends_with(" settled=NO"), "{reply}");
    assert!(!rig.ps().powermax().gas_test_active());
}
