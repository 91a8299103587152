use super::*;
use crate::io::{Input, IoEvent};

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

/// Every unit's pins idle (the reference wiring: inputs active low, open reads high).
fn idle(_: usize) -> PinLevels {
    PinLevels::ALL_HIGH
}

/// TORCH_ON pressed on unit `pressed` only.
fn torch_on(pressed: usize) -> impl Fn(usize) -> PinLevels {
    move |unit| PinLevels::ALL_HIGH.with(Input::TorchOn, unit != pressed)
}

/// TORCH_ON pressed on every unit.
fn every_torch_on(_: usize) -> PinLevels {
    PinLevels::ALL_HIGH.with(Input::TorchOn, false)
}

/// Two units, both driven, both supplies healthy.
fn two_healthy() -> UnitsIo<2> {
    let mut io = UnitsIo::<2>::new(IoConfig::default(), ms(0), idle);
    assert!(io.set_unit_count(ms(0), 2, idle));
    io.on_supply(ms(0), 0, SupplyState::HEALTHY);
    io.on_supply(ms(0), 1, SupplyState::HEALTHY);
    io
}

fn starts(io: &UnitsIo<2>) -> [bool; 2] {
    [io.outputs(0).start, io.outputs(1).start]
}

fn events(io: &mut UnitsIo<2>) -> Vec<(usize, IoEvent)> {
    let mut all = Vec::new();
    for (unit, discrete) in io.driven() {
        all.extend(core::iter::from_fn(|| discrete.poll_event()).map(|e| (unit, e)));
    }
    all
}

#[test]
fn each_units_torch_on_starts_that_unit_only() {
    let mut io = two_healthy();
    io.on_pins(ms(100), torch_on(1));
    io.poll(ms(101));
    assert_eq!(starts(&io), [false, true], "unit 2's TORCH_ON");
    io.on_pins(ms(200), idle);
    assert_eq!(starts(&io), [false, false]);
    io.on_pins(ms(300), torch_on(0));
    io.poll(ms(301));
    assert_eq!(starts(&io), [true, false], "unit 1's TORCH_ON");
    // The table levels follow each unit's own outputs.
    assert!(io.table_outputs(0).start);
    assert!(!io.table_outputs(1).start);
}

#[test]
fn one_units_fault_or_lost_link_never_blocks_anothers_start() {
    // A fault that refuses START (the default `refuse_start_on_fault`).
    let faulted = SupplyState {
        fault_active: true,
        fault_requires_action: true,
        ..SupplyState::HEALTHY
    };
    for (what, first_supply) in [("fault", faulted), ("lost link", SupplyState::default())] {
        let mut io = two_healthy();
        io.on_supply(ms(50), 0, first_supply);
        io.on_pins(ms(100), every_torch_on);
        io.poll(ms(101));
        assert_eq!(starts(&io), [false, true], "{what} on unit 1");
        let got = events(&mut io);
        assert!(
            got.iter()
                .all(|&(unit, e)| unit == 0 && matches!(e, IoEvent::StartRefused { .. })),
            "{what}: {got:?}"
        );
        assert!(!got.is_empty(), "{what}: unit 1's refusal reported");
        // Unit 2 stops when its own CNC releases, not when unit 1's supply changes.
        io.on_supply(ms(150), 0, SupplyState::HEALTHY);
        io.poll(ms(151));
        assert!(io.outputs(1).start, "{what}");
    }
}

#[test]
fn a_unit_the_bridge_does_not_drive_never_starts_even_without_a_required_link() {
    let config = IoConfig {
        link_required: false,
        ..IoConfig::default()
    };
    let mut io = UnitsIo::<2>::new(config, ms(0), idle);
    // Before the count arrives, and after it says one unit: the second set is inert.
    for count in [None, Some(1)] {
        if let Some(count) = count {
            io.set_unit_count(ms(10), count, idle);
        }
        io.on_supply(ms(20), 1, SupplyState::HEALTHY);
        io.on_pins(ms(100), every_torch_on);
        io.poll(ms(200));
        assert!(!io.is_driven(1));
        assert_eq!(starts(&io), [true, false], "count {count:?}");
        assert_eq!(io.table_outputs(1), Outputs::OFF);
        assert!(events(&mut io).iter().all(|&(unit, _)| unit == 0));
        io.on_pins(ms(300), idle);
        io.poll(ms(400));
    }
    assert_eq!(io.poll_at(), None, "nothing waits on an inert unit");
}

#[test]
fn a_unit_driven_while_its_torch_on_is_held_waits_for_a_fresh_press() {
    let mut io = UnitsIo::<2>::new(IoConfig::default(), ms(0), idle);
    io.on_supply(ms(0), 1, SupplyState::HEALTHY);
    io.set_unit_count(ms(100), 2, torch_on(1));
    assert!(io.is_driven(1));
    io.on_pins(ms(110), torch_on(1));
    io.poll(ms(200));
    assert!(!io.outputs(1).start, "held across the change: ignored");
    assert_eq!(events(&mut io), [(1, IoEvent::StuckTorchOnAtPowerUp)]);
    io.on_pins(ms(300), idle);
    io.on_pins(ms(400), torch_on(1));
    io.poll(ms(401));
    assert!(io.outputs(1).start, "the supply kept while inert applies");
}

#[test]
fn a_unit_no_longer_driven_drops_its_outputs_at_once() {
    let mut io = two_healthy();
    io.on_pins(ms(100), every_torch_on);
    io.poll(ms(101));
    assert_eq!(starts(&io), [true, true]);
    assert!(io.set_unit_count(ms(200), 1, every_torch_on));
    assert_eq!(starts(&io), [true, false]);
    assert_eq!(io.table_outputs(1), Outputs::OFF);
    assert!(!io.set_unit_count(ms(300), 1, every_torch_on), "no change");
}

#[test]
fn new_settings_reach_every_driven_unit() {
    let mut io = two_healthy();
    let config = IoConfig {
        link_required: false,
        ..IoConfig::default()
    };
    assert!(io.reconfigure(ms(50), config, idle));
    assert!(!io.reconfigure(ms(60), config, idle));
    assert_eq!(*io.config(), config);
    for (_, unit) in io.driven() {
        assert_eq!(*unit.config(), config);
    }
}
