//! Several units on one line (issue 21): the bridge's [`SharedLine`] against simulated units
//! that each answer as their manual says, on one [`MultiDrop`] line that counts every
//! character two units sent at once. HPRs share by SLEEP / WAKE (HPR manual,
//! 002_72b43a5685974c77.txt, lines 107-109 and 172-173), Powermax units by node address (SYNC
//! manual, 000_dd931256418ae627.txt, lines 383-392).
//!
//! [`MultiDrop`]: plasma_sim::multidrop::MultiDrop

use host_tests::harness::{World, WorldEndpoint, WorldOptions};
use plasma_firmware::link::{Diagnostics, Family, LinkEvent, SharedLine, UnitStatus};
use plasma_firmware::platform::PsEndpoint;
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::Model;

fn secs(n: u64) -> Duration {
    Duration::from_secs(n)
}

/// HPR error 044 (the benchmark's), Powermax 0-30-0.
const HPR_FAULT: u16 = 44;
const POWERMAX_FAULT: u16 = 300;

fn line(models: &[Model]) -> World<SharedLine> {
    let mut world = World::on_one_line(models, WorldOptions::default()).expect("a valid line");
    world.wait_all_up(secs(10)).expect("every unit detected");
    world
}

/// Each unit's fault in turn is seen on that unit only, within a second.
fn each_fault_is_seen_on_its_unit(world: &mut World<SharedLine>, code: u16) {
    let count = world.endpoint().len();
    for unit in 0..count {
        world.inject_fault_on(unit, code);
        world
            .run_until(|w| w.unit_status(unit).active_fault.is_some(), secs(1))
            .unwrap_or_else(|t| panic!("unit {unit}'s fault not seen: {t}"));
        for other in (0..count).filter(|&o| o != unit) {
            assert!(
                world.unit_status(other).active_fault.is_none(),
                "unit {unit}'s fault seen on unit {other}"
            );
        }
        world.clear_fault_on(unit);
        world
            .run_until(|w| w.unit_status(unit).active_fault.is_none(), secs(1))
            .expect("fault cleared");
    }
}

#[test]
fn two_hpr260s_are_each_detected_and_each_fault_is_seen() {
    let mut world = line(&[Model::Hpr260, Model::Hpr260]);
    for unit in 0..2 {
        assert_eq!(world.unit_status(unit).family, Some(Family::Hpr));
    }
    each_fault_is_seen_on_its_unit(&mut world, HPR_FAULT);
    assert_eq!(world.collisions(), 0);
}

#[test]
fn four_hpr260s_are_each_detected_and_each_fault_is_seen() {
    let mut world = line(&[Model::Hpr260; 4]);
    each_fault_is_seen_on_its_unit(&mut world, HPR_FAULT);
    world.run_for(secs(5));
    for unit in 0..4 {
        let link = world.endpoint().unit(unit).unwrap();
        assert_eq!(link.diagnostics().link_downs, 0, "unit {unit}");
    }
    assert_eq!(world.collisions(), 0);
}

#[test]
fn hprs_of_different_models_are_each_known_by_their_model() {
    let models = [Model::Hpr130, Model::Hpr400, Model::Hpr260Xd];
    let mut world = line(&models);
    world.run_for(secs(2));
    let names: Vec<String> = (0..3)
        .map(|u| format!("{:?}", world.unit_status(u).model))
        .collect();
    assert!(names[0].contains("130"), "{names:?}");
    assert!(names[1].contains("400"), "{names:?}");
    assert!(names[2].contains("260"), "{names:?}");
    assert_eq!(world.collisions(), 0);
}

#[test]
fn a_silent_unit_leaves_the_others_their_status() {
    let mut world = World::on_one_line(&[Model::Hpr260; 4], WorldOptions::default()).unwrap();
    world.connect_unit(2, false);
    let others = [0, 1, 3];
    world
        .run_until(
            |w| others.iter().all(|&u| w.unit_status(u).link_up),
            secs(10),
        )
        .expect("the others detected");
    world.run_for(secs(10));
    for unit in others {
        let link = world.endpoint().unit(unit).unwrap();
        assert!(link.status().link_up, "unit {unit}");
        assert_eq!(link.diagnostics().link_downs, 0, "unit {unit}");
    }
    assert!(!world.unit_status(2).link_up);
    world.inject_fault_on(3, HPR_FAULT);
    world
        .run_until(|w| w.unit_status(3).active_fault.is_some(), secs(1))
        .expect("unit 3's fault seen with unit 2 silent");
    // Unit 2 back on the line: found again, nobody else disturbed.
    world.connect_unit(2, true);
    world.wait_all_up(secs(10)).expect("unit 2 found again");
    assert_eq!(world.collisions(), 0);
}

#[test]
fn one_unit_cuts_through_its_hf_ignition_while_the_other_keeps_its_link() {
    // The world's one set of discrete I/O drives unit 1 (index 0), under the safety monitor;
    // its pilot arc's HF noise reaches the whole line.
    let mut world = line(&[Model::Hpr260, Model::Hpr260]);
    world
        .run_until(|w| w.unit_status(0).ready, secs(10))
        .expect("unit 1 ready");
    world.set_torch(true);
    world
        .run_until(|w| w.unit_ref().motion(), secs(3))
        .expect("unit 1's arc transfers");
    world.run_for(secs(2));
    world.set_torch(false);
    world.run_for(secs(3));
    assert!(
        !world.noise_bursts().is_empty(),
        "the HF ignition was on the line"
    );
    for unit in 0..2 {
        let link = world.endpoint().unit(unit).unwrap();
        assert!(link.status().link_up, "unit {unit}");
        assert_eq!(link.diagnostics().link_downs, 0, "unit {unit}");
    }
    assert!(
        !world.units().unit(1).unwrap().motion(),
        "unit 2 never started"
    );
    assert_eq!(world.collisions(), 0);
}

#[test]
fn a_unit_that_falls_silent_goes_down_alone() {
    let mut world = line(&[Model::Hpr260; 3]);
    world.connect_unit(1, false);
    world
        .run_until(|w| !w.unit_status(1).link_up, secs(10))
        .expect("unit 1's link goes down");
    world.run_for(secs(5));
    for unit in [0, 2] {
        let link = world.endpoint().unit(unit).unwrap();
        assert!(link.status().link_up, "unit {unit}");
        assert_eq!(link.diagnostics().link_downs, 0, "unit {unit}");
    }
    world.inject_fault_on(2, HPR_FAULT);
    world
        .run_until(|w| w.unit_status(2).active_fault.is_some(), secs(1))
        .expect("unit 2's fault seen with unit 1 silent");
    assert_eq!(world.collisions(), 0);
}

#[test]
fn hprs_on_a_two_wire_line_that_echoes_the_bridge() {
    // The bridge hears its own WAKE before the unit's echo: on a line known to echo, the
    // second copy hands the line over.
    let options = WorldOptions {
        wiring: plasma_sim::line::Wiring::TwoWire { master_echo: true },
        ..WorldOptions::default()
    };
    let mut world = World::on_one_line(&[Model::Hpr260; 2], options).unwrap();
    world.wait_all_up(secs(10)).expect("both detected");
    world.run_for(secs(10));
    for unit in 0..2 {
        let link = world.endpoint().unit(unit).unwrap();
        assert_eq!(link.diagnostics().link_downs, 0, "unit {unit}");
    }
    each_fault_is_seen_on_its_unit(&mut world, HPR_FAULT);
    assert_eq!(world.collisions(), 0);
}

#[test]
fn two_powermax_sync_units_are_each_detected_and_each_fault_is_seen() {
    let mut world = line(&[Model::Sync65, Model::Sync65]);
    for unit in 0..2 {
        assert_eq!(world.unit_status(unit).family, Some(Family::PowermaxSync));
    }
    each_fault_is_seen_on_its_unit(&mut world, POWERMAX_FAULT);
    assert_eq!(world.endpoint().stats().wakes, 0, "no SLEEP/WAKE on Modbus");
    assert_eq!(world.collisions(), 0);
}

#[test]
fn a_set_that_cannot_share_a_line_is_refused() {
    for models in [
        &[Model::Hpr260, Model::Sync65][..],
        &[Model::MaxPro200, Model::Hpr260][..],
    ] {
        let error = World::on_one_line(models, WorldOptions::default())
            .err()
            .unwrap_or_else(|| panic!("{models:?} accepted"));
        assert!(!error.to_string().is_empty());
    }
}

/// The arbiter with its SLEEPs lost on the way to the wire.
struct ForgetsSleep(SharedLine, Vec<u8>);

const SLEEP: &[u8] = b">0869E<";

impl PsEndpoint for ForgetsSleep {
    fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.0.handle_rx(now, bytes);
    }
    fn handle_ps_rx_error(&mut self, now: Instant) {
        self.0.handle_rx_error(now);
    }
    fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        self.1 = self.0.poll_transmit(now)?.to_vec();
        if self.1 == SLEEP {
            self.0.handle_transmitted(now);
            return None;
        }
        Some(&self.1)
    }
    fn ps_transmitted(&mut self, at: Instant) {
        self.0.handle_transmitted(at);
    }
    fn ps_port_config(&self) -> PortConfig {
        self.0.port_config()
    }
    fn poll_at(&self) -> Option<Instant> {
        self.0.poll_at()
    }
}

impl WorldEndpoint for ForgetsSleep {
    fn poll(&mut self, now: Instant, events: &mut Vec<LinkEvent>) {
        self.0.poll(now, events);
    }
    fn status(&self) -> &UnitStatus {
        WorldEndpoint::status(&self.0)
    }
    fn diagnostics(&self) -> &Diagnostics {
        WorldEndpoint::diagnostics(&self.0)
    }
}

#[test]
fn a_forgotten_sleep_would_collide() {
    // What the zero-collision checks above guard against: with the SLEEPs lost, id 0 (awake
    // from power-up) and the unit woken next answer together.
    let mut world = World::on_one_line_with(&[Model::Hpr260; 2], WorldOptions::default(), |line| {
        ForgetsSleep(line, Vec::new())
    })
    .unwrap();
    world.run_for(secs(3));
    assert!(world.collisions() > 0);
}
