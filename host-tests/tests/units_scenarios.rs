//! Several units behind one bridge (issue 21), end to end: the whole `Bridge` with `CONFIG
//! units` naming the simulated units of one multi-drop line, driven from the CNC side. Each
//! unit has its own discrete I/O and its own independent safety monitor, fed only what that
//! unit's pins and link show (checked after every step; a broken rule of any unit fails the
//! test), and the line counts every character two units sent at once.
//!
//! HPRs share a line by SLEEP / WAKE (HPR manual, 002_72b43a5685974c77.txt, lines 93-109);
//! Powermax units by node address (SYNC manual, 000_dd931256418ae627.txt, lines 383-392).

mod common;

use common::field;
use host_tests::harness::{BridgeEndpoint, SharedLineError, World, WorldOptions};
use plasma_firmware::io::Interlock;
use plasma_firmware::link::{LineError, UnitsError};
use plasma_firmware::settings::Settings;
use plasma_protocol::hpr::command::id as hpr_id;
use plasma_protocol::time::Duration;
use plasma_sim::hpr::Hpr;
use plasma_sim::multidrop;
use plasma_sim::powermax::Powermax;
use plasma_sim::{Model, SimulatedUnit};

fn secs(n: u64) -> Duration {
    Duration::from_secs(n)
}

/// HPR error 044 (a gas pressure fault).
const HPR_FAULT: u16 = 44;

/// The bridge (events on) with `models` on one line, every unit's link up, ready for a start
/// (an HPR past its purge) and its settings read (a Powermax's process).
fn line(models: &[Model]) -> World<BridgeEndpoint> {
    let settings = Settings {
        events: true,
        ..Settings::default()
    };
    let mut world = World::with_bridge_on_line(models, WorldOptions::default(), settings)
        .expect("units that share a line");
    assert_eq!(world.bridge().unit_count(), models.len());
    assert_eq!(world.pin_sets(), models.len());
    world.wait_units_up(secs(10)).expect("every unit detected");
    world
        .run_until(
            |w| {
                (0..models.len()).all(|u| {
                    let status = w.bridge().status_of(u);
                    let settings_known = status.hpr.state.is_some() || status.settings.is_some();
                    status.ready && settings_known
                })
            },
            secs(20),
        )
        .expect("every unit ready");
    world
}

/// Run until unit `unit` is ready for a start again (an HPR after its post-flow).
fn wait_ready(world: &mut World<BridgeEndpoint>, unit: usize) {
    world
        .run_until(|w| w.bridge().status_of(unit).ready, secs(10))
        .unwrap_or_else(|t| panic!("unit {} not ready again: {t}", unit + 1));
}

/// Simulated unit `index` of the line.
fn sim(world: &mut World<BridgeEndpoint>, index: usize) -> &mut dyn SimulatedUnit {
    world.units().unit_mut(index).expect("no such unit")
}

/// The line's last SLEEP / WAKE, complete, is a WAKE of a unit other than `id`.
fn another_unit_awake(world: &World<BridgeEndpoint>, id: u8) -> bool {
    let last_switch = world
        .trace()
        .requests()
        .filter(|f| matches!(f.hpr_id(), Some(hpr_id::SLEEP | hpr_id::WAKE)))
        .last();
    last_switch.is_some_and(|f| {
        f.hpr_id() == Some(hpr_id::WAKE)
            && f.bytes.get(4) != Some(&(b'0' + id))
            && f.end <= world.now()
    })
}

/// Which units' START is on.
fn starts(world: &World<BridgeEndpoint>) -> Vec<bool> {
    (0..world.pin_sets())
        .map(|u| world.io_of(u).outputs().start)
        .collect()
}

/// What every scenario ends with: no unit's monitor saw a broken rule, no two units ever
/// answered at once.
fn assert_clean(world: &World<BridgeEndpoint>) {
    for unit in 0..world.pin_sets() {
        let monitor = world.monitor_of(unit);
        assert!(
            monitor.is_clean(),
            "unit {}: {:?}",
            unit + 1,
            monitor.violations()
        );
    }
    assert_eq!(world.collisions(), 0, "two units answered at once");
}

/// Unit `unit`'s TORCH_ON (driven at its own pin) starts that unit and no other; off again.
fn each_torch_on_starts_its_unit_only(world: &mut World<BridgeEndpoint>) {
    let count = world.pin_sets();
    for unit in 0..count {
        wait_ready(world, unit);
        world.set_torch_of(unit, true);
        let expected: Vec<bool> = (0..count).map(|u| u == unit).collect();
        assert_eq!(starts(world), expected, "TORCH_ON of unit {}", unit + 1);
        world
            .run_until(|w| w.io_of(unit).inputs().motion, secs(3))
            .unwrap_or_else(|t| panic!("unit {} never transferred: {t}", unit + 1));
        for other in (0..count).filter(|&o| o != unit) {
            assert!(!world.io_of(other).inputs().motion, "unit {}", other + 1);
            assert!(!world.units().unit(other).unwrap().motion());
        }
        world.set_torch_of(unit, false);
        assert_eq!(starts(world), vec![false; count]);
        world
            .run_until(|w| !w.io_of(unit).inputs().motion, secs(3))
            .expect("arc off");
        // The interlocks' gap between two starts.
        world.run_for(secs(1));
    }
}

#[test]
fn two_hprs_each_torch_on_starts_its_own_unit_only() {
    let mut world = line(&[Model::Hpr260, Model::Hpr260]);
    each_torch_on_starts_its_unit_only(&mut world);
    assert_clean(&world);
}

#[test]
fn four_hprs_each_torch_on_starts_its_own_unit_only() {
    let mut world = line(&[Model::Hpr260; 4]);
    each_torch_on_starts_its_unit_only(&mut world);
    assert_clean(&world);
}

#[test]
fn unit_2s_torch_on_never_starts_unit_1_and_the_reverse() {
    let mut world = line(&[Model::Hpr260, Model::Hpr130]);
    // Both held together, released in the other order: each START is its own TORCH_ON's.
    world.set_torch_of(1, true);
    assert_eq!(starts(&world), [false, true]);
    world.run_for(secs(1));
    world.set_torch_of(0, true);
    assert_eq!(starts(&world), [true, true]);
    world.run_for(secs(1));
    world.set_torch_of(1, false);
    assert_eq!(starts(&world), [true, false]);
    world.set_torch_of(0, false);
    assert_eq!(starts(&world), [false, false]);
    // Through the CNC's simulator command: `TORCH` is unit 1's, `@2 TORCH` unit 2's.
    wait_ready(&mut world, 1);
    assert_eq!(world.cnc_line("@2 TORCH ON"), "OK torch=ON unit=2");
    assert_eq!(
        starts(&world),
        [false, true],
        "{:?}",
        world.io_of(1).start_locked_by()
    );
    world
        .wait_cnc_line("!ARC ON", secs(3))
        .map(|event| assert!(field(&event, "unit") == Some("2"), "{event}"))
        .expect("unit 2's arc");
    assert_eq!(world.cnc_line("@2 TORCH OFF"), "OK torch=OFF unit=2");
    wait_ready(&mut world, 0);
    assert_eq!(world.cnc_line("TORCH ON"), "OK torch=ON");
    assert_eq!(starts(&world), [true, false]);
    let arc = world
        .wait_cnc_line("!ARC ON", secs(3))
        .expect("unit 1's arc");
    assert!(!arc.contains("unit="), "{arc}");
    // STATUS shows each unit's own pins.
    let first = world.cnc_line("STATUS");
    let second = world.cnc_line("@2 STATUS");
    assert_eq!(field(&first, "start"), Some("ON"), "{first}");
    assert_eq!(field(&second, "start"), Some("OFF"), "{second}");
    assert_eq!(world.cnc_line("TORCH OFF"), "OK torch=OFF");
    assert_clean(&world);
}

/// The nominal current each of the first `count` simulated HPRs holds.
fn nominal_amps(world: &mut World<BridgeEndpoint>, count: usize) -> Vec<u16> {
    (0..count)
        .map(|u| {
            sim(world, u)
                .as_any()
                .downcast_ref::<Hpr>()
                .unwrap()
                .nominal_amps()
        })
        .collect()
}

#[test]
fn mixed_hpr_models_answer_for_themselves_and_a_setting_reaches_only_its_unit() {
    let models = [Model::Hpr260, Model::Hpr130, Model::Hpr400];
    let mut world = line(&models);
    for (unit, name) in ["HPR260", "HPR130", "HPR400"].iter().enumerate() {
        let reply = world.cnc_line(&format!("@{} ID", unit + 1));
        assert!(reply.contains(&format!(" model={name} ")), "{reply}");
    }
    let before = nominal_amps(&mut world, 3);
    let reply = world.cnc_line("@2 SET AMPS 80");
    assert!(
        reply.starts_with("OK ") && field(&reply, "unit") == Some("2"),
        "{reply}"
    );
    world.run_for(secs(1));
    let after = nominal_amps(&mut world, 3);
    assert_eq!(after, [before[0], 80, before[2]]);
    assert_eq!(field(&world.cnc_line("@2 STATUS"), "amps"), Some("80"));
    assert_clean(&world);
}

#[test]
fn three_powermax_units_sync_and_legacy_share_a_line_by_node() {
    // Nodes 1, 2, 3.
    let models = [Model::Sync65, Model::Pm85, Model::Sync45];
    let mut world = line(&models);
    for (unit, family) in ["SYNC", "LEGACY", "SYNC"].iter().enumerate() {
        let reply = world.cnc_line(&format!("@{} ID", unit + 1));
        assert_eq!(field(&reply, "family"), Some(*family), "{reply}");
    }
    each_torch_on_starts_its_unit_only(&mut world);
    assert_clean(&world);
}

#[test]
fn a_powermax_setting_reaches_only_the_unit_named() {
    let mut world = line(&[Model::Sync65, Model::Pm85]);
    // SET AMPS is checked against the unit's permitted limits, read with its slow data.
    world
        .run_until(|w| w.bridge().status_of(0).limits.is_some(), secs(10))
        .expect("unit 1's limits read");
    let current = |w: &mut World<BridgeEndpoint>, u: usize| {
        let unit = sim(w, u).as_any().downcast_ref::<Powermax>();
        unit.expect("a Powermax").settings().current
    };
    let before: Vec<u16> = (0..2).map(|u| current(&mut world, u)).collect();
    let reply = world.cnc_line("SET AMPS 30");
    assert!(
        reply.starts_with("OK ") && !reply.contains("unit="),
        "{reply}"
    );
    let reply = world.cnc_line("@2 SET AMPS 40");
    assert!(
        reply.starts_with("OK ") && field(&reply, "unit") == Some("2"),
        "{reply}"
    );
    let after: Vec<u16> = (0..2).map(|u| current(&mut world, u)).collect();
    assert_ne!(before, after);
    assert_eq!(after, [30 * 64, 40 * 64]);
    assert_clean(&world);
}

#[test]
fn a_faulted_unit_does_not_block_anothers_start() {
    let mut world = line(&[Model::Hpr260, Model::Hpr260]);
    let now = world.now();
    sim(&mut world, 1).inject_fault(now, HPR_FAULT);
    let event = world
        .wait_cnc_line("!FAULT", secs(2))
        .expect("unit 2's fault");
    assert!(field(&event, "unit") == Some("2"), "{event}");
    assert!(world.io_of(1).outputs().fault);
    assert!(!world.io_of(0).outputs().fault);
    assert_eq!(world.cnc_line("FAULT"), "OK fault=none");
    assert!(world.cnc_line("@2 FAULT").starts_with("OK fault=044 "));

    // Unit 2's TORCH_ON is refused by its own interlock; unit 1 cuts meanwhile.
    world.set_torch_of(1, true);
    assert_eq!(starts(&world), [false, false]);
    assert_eq!(
        world.io_of(1).start_locked_by(),
        Some(Interlock::FaultRequiresAction)
    );
    world.set_torch_of(0, true);
    assert_eq!(starts(&world), [true, false]);
    world
        .run_until(|w| w.io_of(0).outputs().arc_ok, secs(3))
        .expect("unit 1 cuts");
    world.set_torch_of(0, false);
    world.set_torch_of(1, false);
    assert_clean(&world);
}

#[test]
fn a_silent_unit_leaves_the_others_their_status_and_start() {
    let mut world = line(&[Model::Hpr260, Model::Hpr130, Model::Hpr400]);
    // A unit cut while awake stays awake and, mended, answers with the unit awake then until
    // the next SLEEP, which nothing on the line can hear coming: cut unit 3 while another
    // unit is awake (HPR manual, 002_72b43a5685974c77.txt, lines 93-109).
    world
        .run_until(|w| another_unit_awake(w, 2), secs(1))
        .expect("a turn of unit 1 or 2");
    world.connect_unit(2, false);
    world
        .run_until(|w| !w.bridge().status_of(2).link_up, secs(5))
        .expect("unit 3's link lost");
    assert_eq!(field(&world.cnc_line("@3 STATUS"), "link"), Some("DOWN"));
    // The others keep their link, their status and their START.
    for unit in 0..2 {
        let status = world.cnc_line(&format!("@{} STATUS", unit + 1));
        assert_eq!(field(&status, "link"), Some("UP"), "{status}");
        assert!(world.bridge().status_of(unit).link_up);
    }
    world.set_torch_of(2, true);
    assert_eq!(starts(&world), [false, false, false]);
    assert_eq!(world.io_of(2).start_locked_by(), Some(Interlock::LinkDown));
    for unit in 0..2 {
        wait_ready(&mut world, unit);
        world.set_torch_of(unit, true);
        assert!(world.io_of(unit).outputs().start, "unit {}", unit + 1);
        world
            .run_until(|w| w.io_of(unit).outputs().arc_ok, secs(3))
            .expect("cuts");
        world.set_torch_of(unit, false);
        world.run_for(secs(1));
    }
    world.set_torch_of(2, false);
    // Mended, it comes back without disturbing the others.
    world.connect_unit(2, true);
    world.wait_units_up(secs(10)).expect("unit 3 back");
    assert_clean(&world);
}

#[test]
fn units_that_cannot_share_a_line_are_refused_with_the_reason() {
    // By the bridge, when the CNC names them.
    let mut world = line(&[Model::Hpr260, Model::Hpr130]);
    let reply = world.cnc_line("CONFIG units HPR:0,POWERMAX:1");
    let reason = UnitsError::Line(LineError::MixedProtocols { unit: 1 }).to_string();
    assert!(
        reply.starts_with("ERR ") && reply.contains(&reason),
        "{reply}"
    );
    assert_eq!(world.cnc_line("CONFIG units"), "OK units=HPR:0,HPR:1");
    // The units it drives are untouched.
    assert!((0..2).all(|u| world.bridge().status_of(u).link_up));
    assert_clean(&world);

    // And by the simulated line, for the same reason.
    let refused = World::with_bridge_on_line(
        &[Model::Hpr260, Model::Sync65],
        WorldOptions::default(),
        Settings::default(),
    )
    .err();
    assert_eq!(
        refused,
        Some(SharedLineError::Units(
            multidrop::LineError::MixedProtocols(Model::Hpr260, Model::Sync65)
        ))
    );
}

/// The `HISTORY` entries of `count` newest, newest first.
fn history(world: &mut World<BridgeEndpoint>, count: usize) -> Vec<String> {
    let mark = world.cnc_output().len();
    let reply = world.cnc_line(&format!("HISTORY {count}"));
    assert!(reply.starts_with("OK history="), "{reply}");
    world.cnc_output()[mark..]
        .iter()
        .filter_map(|r| r.item.line())
        .filter(|l| l.starts_with("HISTORY "))
        .map(str::to_string)
        .collect()
}

/// On a two-torch table the history says which torch faulted: unit 2's entry ends in
/// `unit=2`, unit 1's names no unit (as every reply about the first unit).
#[test]
fn the_history_says_which_unit_faulted() {
    let mut world = line(&[Model::Hpr260, Model::Hpr260]);
    let now = world.now();
    sim(&mut world, 1).inject_fault(now, HPR_FAULT);
    world
        .wait_cnc_line("!FAULT", secs(2))
        .expect("unit 2's fault");
    let now = world.now();
    sim(&mut world, 0).inject_fault(now, HPR_FAULT);
    world
        .wait_cnc_line("!FAULT", secs(2))
        .expect("unit 1's fault");
    // Unit 2's own interlock refuses its TORCH_ON: an I/O event of that unit's pin set.
    let mark = world.cnc_lines().count();
    world.set_torch_of(1, true);
    let refused: Vec<&str> = world.cnc_lines().skip(mark).collect();
    assert_eq!(refused, ["!START REFUSED reason=fault unit=2"]);
    world.set_torch_of(1, false);
    let entries = history(&mut world, 3);
    let kept: Vec<(Option<&str>, Option<&str>)> = entries
        .iter()
        .map(|l| (field(l, "event"), field(l, "unit")))
        .collect();
    assert_eq!(
        kept,
        [
            (Some("START_REFUSED"), Some("2")),
            (Some("FAULT"), None),
            (Some("FAULT"), Some("2")),
        ],
        "{entries:?}"
    );
    // The unit's tag comes last, after the event's own fields; docs/cnc-protocol.md
    // (HISTORY, and section 10) quotes this line.
    assert!(
        entries[2].ends_with(
            " clock=- family=HPR model=HPR260 event=FAULT code=044 action=required unit=2"
        ),
        "{}",
        entries[2]
    );
    assert_clean(&world);
}
