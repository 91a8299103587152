//! `GASTEST CHECK` end to end on every family: the bridge in the scenario `World` with the
//! discrete I/O and the safety monitor in the loop (checked after every step), against the
//! simulated SYNC, legacy Powermax, HPR and MaxPro200 units with an ample and a weak gas
//! supply.
//!
//! Manuals: SYNC manual (000_dd931256418ae627.txt) lines 531-532 (the gas-test coil 0x3180,
//! legacy 0x0832), 1278-1282 (0x3019 actual pressure), 441 (legacy 0x204C), 752-754
//! (0x3004/0x3005 permitted pressure); HPR manual (002_72b43a5685974c77.txt) lines 154-155
//! (066/067 the cutflow test), 168 (079 measured pressures; a MaxPro200's set points only),
//! 281 (141, a MaxPro200's measured pressures), 283 (143 test gas), 382-389 (the limits).

mod common;

use common::{bridge_world, field, ready_hpr};
use host_tests::harness::{BridgeEndpoint, World};
use plasma_firmware::texts;
use plasma_protocol::cnc::ErrorCode;
use plasma_protocol::time::Duration;
use plasma_sim::Model;
use plasma_sim::hpr::Hpr;
use plasma_sim::powermax::Powermax;

const FAMILIES: [Model; 4] = [Model::Sync65, Model::Pm65, Model::Hpr130, Model::MaxPro200];

/// HPR state 12: TEST CUTFLOW (HPR manual line 468).
const HPR_TEST_CUTFLOW: u16 = 12;

fn world(model: Model) -> World<BridgeEndpoint> {
    match model {
        Model::Hpr130 | Model::MaxPro200 => ready_hpr(model),
        _ => bridge_world(model),
    }
}

/// The unit's gas test runs.
fn gas_flowing(w: &World<BridgeEndpoint>) -> bool {
    match w.unit_ref().model() {
        Model::Hpr130 => w.sim_ref::<Hpr>().state_code() == HPR_TEST_CUTFLOW,
        Model::MaxPro200 => w.sim_ref::<Hpr>().test_gas(),
        _ => w.sim_ref::<Powermax>().gas_test_active(),
    }
}

fn err(code: ErrorCode, text: &str) -> String {
    format!("ERR {} {text}", code.as_str())
}

/// The newest history entry.
fn newest_entry(w: &mut World<BridgeEndpoint>) -> String {
    w.run_for(Duration::from_millis(200));
    let mark = w.cnc_lines().count();
    assert!(w.cnc_line("HISTORY 1").starts_with("OK history=1"));
    w.cnc_lines().nth(mark).expect("one entry").to_string()
}

#[test]
fn an_ample_supply_passes_on_every_family_and_the_test_is_ended() {
    for model in FAMILIES {
        let mut w = world(model);
        let reply = w.cnc_line("GASTEST CHECK");
        assert!(
            reply.starts_with("OK GASTEST CHECK result=PASS "),
            "{model:?}: {reply}"
        );
        assert!(!gas_flowing(&w), "{model:?}: the test was ended");
        let entry = newest_entry(&mut w);
        assert!(
            entry.contains(" event=GAS_CHECK result=PASS "),
            "{model:?}: {entry}"
        );
        w.assert_safe();
    }
}

#[test]
fn a_weak_supply_fails_on_every_family_and_the_test_is_ended() {
    for model in FAMILIES {
        let mut w = world(model);
        // Below every permitted range: the SYNC cartridge's 58 psi, the legacy unit's 63 psi,
        // the HPR's and MaxPro200's 50 psi plasma.
        w.set_gas_supply(Some(30));
        let reply = w.cnc_line("GASTEST CHECK");
        assert!(
            reply.starts_with("OK GASTEST CHECK result=FAIL "),
            "{model:?}: {reply}"
        );
        let measured = match model {
            Model::Hpr130 | Model::MaxPro200 => field(&reply, "plasma_psi"),
            _ => field(&reply, "measured_psi"),
        };
        assert_eq!(measured, Some("30"), "{model:?}: {reply}");
        assert!(!gas_flowing(&w), "{model:?}: the test was ended");
        let entry = newest_entry(&mut w);
        assert!(
            entry.contains(" event=GAS_CHECK result=FAIL psi=30 "),
            "{model:?}: {entry}"
        );
        w.assert_safe();
    }
}

#[test]
fn refused_while_the_torch_is_on_and_no_test_starts() {
    for model in FAMILIES {
        let mut w = world(model);
        w.set_torch(true);
        w.run_for(Duration::from_millis(300));
        assert_eq!(
            w.cnc_line("GASTEST CHECK"),
            err(ErrorCode::State, texts::GAS_CHECK_TORCH_ON),
            "{model:?}"
        );
        assert!(!gas_flowing(&w), "{model:?}");
        w.set_torch(false);
        w.run_for(Duration::from_millis(500));
        w.assert_safe();
    }
}

/// A world whose `GASTEST CHECK` has the gas flowing, and the reply count before it.
fn check_under_way(model: Model) -> (World<BridgeEndpoint>, usize) {
    let mut w = world(model);
    let mark = w.cnc_reply_count();
    w.cnc_send(b"GASTEST CHECK\r\n");
    w.run_until(gas_flowing, Duration::from_secs(2))
        .unwrap_or_else(|t| panic!("{model:?}: the gas test never ran: {t}"));
    (w, mark)
}

/// The reply after the first `mark` replies, waited for up to `timeout`.
fn reply_after(
    w: &mut World<BridgeEndpoint>,
    mark: usize,
    timeout: Duration,
    model: Model,
) -> String {
    w.wait_cnc_replies(mark + 1, timeout)
        .unwrap_or_else(|t| panic!("{model:?}: no reply: {t}"));
    w.cnc_replies().nth(mark).expect("waited").to_string()
}

#[test]
fn torch_on_during_the_check_ends_the_test_and_the_cut_goes_on_safely() {
    for model in FAMILIES {
        let (mut w, mark) = check_under_way(model);
        w.set_torch(true);
        let reply = reply_after(&mut w, mark, Duration::from_secs(2), model);
        assert_eq!(
            reply,
            err(ErrorCode::State, texts::GAS_CHECK_STOPPED_TORCH),
            "{model:?}"
        );
        w.run_until(|w| !gas_flowing(w), Duration::from_secs(2))
            .unwrap_or_else(|t| panic!("{model:?}: the gas test was not ended: {t}"));
        w.set_torch(false);
        w.run_for(Duration::from_secs(1));
        w.assert_safe();
    }
}

#[test]
fn a_link_lost_mid_check_ends_it_and_the_test_is_stopped_once_the_link_is_back() {
    for model in FAMILIES {
        let (mut w, mark) = check_under_way(model);
        w.pull_cable(true);
        let reply = reply_after(&mut w, mark, Duration::from_secs(10), model);
        // The loss itself, or the reading it left unanswered.
        assert!(reply.starts_with("ERR LINK "), "{model:?}: {reply}");
        w.pull_cable(false);
        w.wait_link_up(Duration::from_secs(10))
            .unwrap_or_else(|t| panic!("{model:?}: link not back: {t}"));
        w.run_until(|w| !gas_flowing(w), Duration::from_secs(3))
            .unwrap_or_else(|t| panic!("{model:?}: the gas test was not ended: {t}"));
        w.assert_safe();
    }
}
