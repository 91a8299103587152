//! Consumable life against every simulated family: the bridge's counts (legacy Powermax, HPR,
//! MaxPro200) and a SYNC cartridge's own (SYNC manual 000_dd931256418ae627.txt lines
//! 1464-1498), the limits, the 90 % and 100 % warnings once each, a new cartridge and
//! `CONSUMABLES NEW` as a new record, and all of it across a power cycle of the bridge. The
//! safety monitor watches every scenario.

mod common;

use common::{bridge_world, field, ready_hpr};
use host_tests::harness::{BridgeEndpoint, World};
use plasma_firmware::io::Input;
use plasma_protocol::time::Duration;
use plasma_sim::Model;
use plasma_sim::powermax::Powermax;
use plasma_sim::sync::{Cartridge, CartridgeKind};

fn secs(s: u64) -> Duration {
    Duration::from_secs(s)
}

/// One cut: TORCH_ON until the arc has burnt `arc` after `!ARC ON`, then released until
/// `!ARC OFF`.
fn cut(w: &mut World<BridgeEndpoint>, arc: Duration) {
    let arcs_off = w.cnc_events().filter(|e| *e == "!ARC OFF").count();
    // An HPR goes through post-flow after a cut: the ready interlock waits for state 3.
    w.run_until(|w| w.bridge().supply_state().unit_ready, secs(10))
        .unwrap_or_else(|t| panic!("the unit is not ready for a start: {t}"));
    w.set_torch(true);
    w.wait_cnc_line("!ARC ON", secs(10))
        .unwrap_or_else(|t| panic!("no arc: {t}"));
    w.run_for(arc);
    w.set_torch(false);
    w.run_until(
        |w| w.cnc_events().filter(|e| *e == "!ARC OFF").count() > arcs_off,
        secs(10),
    )
    .unwrap_or_else(|t| panic!("the arc did not go out: {t}"));
    w.run_for(Duration::from_millis(300));
}

fn warnings(w: &World<BridgeEndpoint>) -> Vec<String> {
    w.cnc_events()
        .filter(|e| e.starts_with("!WARN CONSUMABLE"))
        .map(str::to_string)
        .collect()
}

fn number(line: &str, key: &str) -> u32 {
    field(line, key)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no {key} in {line}"))
}

/// The newest `HISTORY` entry (empty when there is none).
fn newest_entry(w: &mut World<BridgeEndpoint>) -> String {
    let mark = w.cnc_output().len();
    let reply = w.cnc_line("HISTORY 1");
    assert!(reply.starts_with("OK history="), "{reply}");
    w.cnc_output()[mark..]
        .iter()
        .filter_map(|r| r.item.line())
        .find(|l| l.starts_with("HISTORY "))
        .unwrap_or_default()
        .to_string()
}

/// Limits stored with CONFIG SAVE, so that they survive the power cycle too.
fn set_start_limit(w: &mut World<BridgeEndpoint>, limit: u32) {
    assert_eq!(w.cnc_line("EVENTS ON"), "OK events=ON");
    assert_eq!(
        w.cnc_line(&format!("CONFIG consumable_start_limit {limit}")),
        format!("OK consumable_start_limit={limit}")
    );
    assert_eq!(w.cnc_line("CONFIG SAVE"), "OK config=saved");
}

/// The bridge counts the starts and arc seconds of a legacy Powermax, an HPR and a
/// MaxPro200: warnings at 90 % and 100 % once each, the counts and the warnings given kept
/// across a power cycle, and `CONSUMABLES NEW` starts from zero.
#[test]
fn the_bridge_counts_the_cuts_of_every_family_without_a_cartridge() {
    for model in [Model::Pm65, Model::Hpr260, Model::MaxPro200] {
        let mut w = match model {
            Model::Pm65 => bridge_world(model),
            _ => ready_hpr(model),
        };
        let first = w.cnc_line("CONSUMABLES");
        assert!(
            first.starts_with("OK source=bridge starts=0 arc_s=0 start_limit=OFF"),
            "{model:?}: {first}"
        );
        assert_eq!(field(&first, "used"), Some("OFF"), "{model:?}");
        set_start_limit(&mut w, 10);
        for _ in 0..8 {
            cut(&mut w, secs(1));
        }
        let reply = w.cnc_line("CONSUMABLES");
        assert_eq!(number(&reply, "starts"), 8, "{model:?}: {reply}");
        // Eight arcs of at least a second each (the unit's ramp-down may add a little).
        let arc_s = number(&reply, "arc_s");
        assert!((8..=12).contains(&arc_s), "{model:?}: {reply}");
        assert_eq!(field(&reply, "used"), Some("80%"), "{model:?}");
        assert_eq!(
            field(&w.cnc_line("STATUS"), "consumables"),
            Some("80%"),
            "{model:?}"
        );
        assert!(warnings(&w).is_empty(), "{model:?}");
        for _ in 0..3 {
            cut(&mut w, secs(1));
        }
        let given = warnings(&w);
        assert_eq!(given.len(), 2, "{model:?}: {given:?}");
        assert!(
            given[0].starts_with("!WARN CONSUMABLE used=90% threshold=90% source=bridge starts=9 "),
            "{model:?}: {given:?}"
        );
        assert!(
            given[1]
                .starts_with("!WARN CONSUMABLE used=100% threshold=100% source=bridge starts=10 "),
            "{model:?}: {given:?}"
        );
        // The eleventh start's count is saved within a minute of its arc-off.
        w.run_for(secs(61));
        w.power_cycle_bridge();
        common::settle(&mut w);
        assert_eq!(w.cnc_line("EVENTS ON"), "OK events=ON");
        let reply = w.cnc_line("CONSUMABLES");
        assert_eq!(number(&reply, "starts"), 11, "{model:?}: {reply}");
        assert_eq!(field(&reply, "start_limit"), Some("10"), "{model:?}");
        cut(&mut w, secs(1));
        assert_eq!(warnings(&w).len(), 2, "not again after a reset: {model:?}");

        if model != Model::Pm65 {
            // The HPR's RAMPDOWN_ERROR output: a sign of wear (HPR manual
            // 002_72b43a5685974c77.txt line 56).
            w.set_input(Input::RampdownError, true);
            w.run_for(Duration::from_millis(100));
            w.set_input(Input::RampdownError, false);
            w.run_for(Duration::from_millis(100));
            let reply = w.cnc_line("CONSUMABLES");
            assert_eq!(
                field(&reply, "rampdown_errors"),
                Some("1"),
                "{model:?}: {reply}"
            );
        }

        let reply = w.cnc_line("CONSUMABLES NEW");
        assert!(
            reply.starts_with("OK source=bridge starts=0 arc_s=0 start_limit=10 "),
            "{model:?}: {reply}"
        );
        assert!(
            newest_entry(&mut w).ends_with(" event=CONSUMABLES_CHANGED"),
            "{model:?}"
        );
        w.assert_safe();
    }
}

/// A SYNC's counts are its cartridge's own; another cartridge is a new record by itself
/// (and `CONSUMABLES NEW` is refused); the warnings follow the cartridge's counts.
#[test]
fn a_sync_cartridge_counts_itself_and_another_one_starts_a_new_record() {
    let mut w = bridge_world(Model::Sync65);
    w.run_until(|w| w.bridge().status().cartridge.is_some(), secs(10))
        .expect("the cartridge is read");
    w.run_for(secs(1));
    let first = w.cnc_line("CONSUMABLES");
    assert!(first.starts_with("OK source=cartridge "), "{first}");
    let uid = field(&first, "uid")
        .expect("the cartridge's UID")
        .to_string();
    // The first cartridge a bridge sees starts its record, not a change of consumables.
    assert!(!newest_entry(&mut w).ends_with(" event=CONSUMABLES_CHANGED"));
    set_start_limit(&mut w, 20);
    for _ in 0..3 {
        cut(&mut w, secs(1));
    }
    // The cartridge's counters are read with the slow data.
    let sim_starts = w
        .sim_ref::<Powermax>()
        .cartridge()
        .map(|c| c.starts)
        .expect("a cartridge");
    assert!(sim_starts >= 3, "the simulated cartridge counts its starts");
    w.run_until(
        |w| w.bridge().status().cartridge.map(|c| c.counters.starts) == Some(sim_starts),
        secs(70),
    )
    .unwrap_or_else(|t| panic!("the cartridge's starts are not read: {t}"));
    let reply = w.cnc_line("CONSUMABLES");
    assert_eq!(number(&reply, "starts"), u32::from(sim_starts), "{reply}");

    // Worn to 95 % (the cartridge's own count): one warning, from the cartridge.
    w.sim::<Powermax>()
        .cartridge_mut()
        .expect("a cartridge")
        .starts = 19;
    // Read again within the slow-data interval (30 s by default).
    w.wait_cnc_line(
        "!WARN CONSUMABLE used=95% threshold=90% source=cartridge starts=19 ",
        secs(70),
    )
    .unwrap_or_else(|t| panic!("no warning: {t}: {:?}", warnings(&w)));

    // A 0-32-x fault (cartridge at end of life) is a sign of wear.
    w.inject_fault(320);
    w.run_for(secs(1));
    w.clear_fault();
    w.run_for(secs(1));
    assert_eq!(field(&w.cnc_line("CONSUMABLES"), "wear_faults"), Some("1"));

    // The cable pulled: the cartridge's last counts, still.
    w.pull_cable(true);
    w.run_until(|w| !w.bridge().status().link_up, secs(10))
        .expect("the link goes down");
    let reply = w.cnc_line("CONSUMABLES");
    assert!(
        reply.starts_with("OK source=cartridge starts=19 "),
        "{reply}"
    );
    assert_eq!(field(&reply, "uid"), Some(uid.as_str()), "{reply}");
    w.pull_cable(false);
    common::settle(&mut w);

    let refused = w.cnc_line("CONSUMABLES NEW");
    assert!(
        refused.starts_with("ERR UNSUPPORTED CONSUMABLES NEW "),
        "{refused}"
    );

    // The record survives a power cycle: the same cartridge is not a new one.
    w.run_for(secs(61));
    w.power_cycle_bridge();
    common::settle(&mut w);
    w.run_for(secs(3));
    assert!(!newest_entry(&mut w).ends_with(" event=CONSUMABLES_CHANGED"));

    // Another cartridge.
    let now = w.now();
    w.sim::<Powermax>().install_cartridge(
        now,
        Cartridge::new(CartridgeKind::Cut65, "NEWCARTRIDGE0001"),
    );
    w.run_until(
        |w| w.bridge().status().cartridge.map(|c| c.uid.0) == Some(*b"NEWCARTRIDGE0001"),
        secs(10),
    )
    .unwrap_or_else(|t| panic!("the new cartridge is not read: {t}"));
    w.run_for(Duration::from_millis(200));
    let reply = w.cnc_line("CONSUMABLES");
    assert_eq!(number(&reply, "starts"), 0, "{reply}");
    assert_eq!(field(&reply, "uid"), Some("NEWCARTRIDGE0001"), "{reply}");
    assert_ne!(uid, "NEWCARTRIDGE0001");
    assert!(newest_entry(&mut w).ends_with(" event=CONSUMABLES_CHANGED"));
    w.assert_safe();
}
