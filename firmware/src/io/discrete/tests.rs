use super::*;
use crate::io::{Interlock, IoEvent, Output, Polarity, Reason};
use crate::platform::pins;
use plasma_protocol::time::Duration;

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

/// TORCH_ON pressed on the reference wiring (active low).
const TORCH: PinLevels = PinLevels::ALL_HIGH.with(Input::TorchOn, false);

fn healthy_with(config: IoConfig, pins: PinLevels) -> DiscreteIo {
    let mut io = DiscreteIo::new(config, ms(0), pins);
    io.on_supply(ms(0), SupplyState::HEALTHY);
    io
}

fn healthy() -> DiscreteIo {
    healthy_with(IoConfig::default(), PinLevels::ALL_HIGH)
}

fn with_torch(polarity: Polarity, debounce_ms: u64) -> IoConfig {
    let mut config = IoConfig::default();
    config.inputs.set_polarity(Input::TorchOn, polarity);
    config
        .inputs
        .set_debounce(Input::TorchOn, Duration::from_millis(debounce_ms));
    config
}

/// Presses TORCH_ON (pins `pressed`) at `at` and returns once START is on.
fn fire(io: &mut DiscreteIo, at: u64, pressed: PinLevels) {
    io.on_pins(ms(at), pressed);
    io.poll(ms(at + 100));
    assert!(io.outputs().start, "a fresh press fires");
}

#[test]
fn start_follows_the_debounced_pin_and_drops_at_once() {
    let mut io = healthy();
    io.on_pins(ms(100), TORCH);
    assert!(!io.outputs().start);
    assert_eq!(io.poll_at(), Some(ms(101)));
    io.poll(ms(101));
    assert!(io.outputs().start);
    let last = core::iter::from_fn(|| io.poll_transition()).last().unwrap();
    assert_eq!((last.output, last.reason), (Output::Start, Reason::TorchOn));
    io.on_pins(ms(150), PinLevels::ALL_HIGH);
    assert!(!io.outputs().start);
}

#[test]
fn torch_on_held_at_power_up_does_not_fire() {
    let mut io = DiscreteIo::new(IoConfig::default(), ms(0), TORCH);
    io.on_supply(ms(1), SupplyState::HEALTHY);
    io.poll(ms(500));
    assert!(!io.outputs().start);
    assert_eq!(
        io.interlocks().start_locked_by(),
        Some(Interlock::TorchOnAtPowerUp)
    );
}

#[test]
fn inverting_torch_on_while_its_pin_is_held_never_fires() {
    // The pin idles low (as an inverted table drives it): under the reference level that is
    // a held TORCH_ON, so power-up locks it.
    let mut io = healthy_with(IoConfig::default(), TORCH);
    assert!(!io.outputs().start);
    // Declared active high while low: TORCH_ON reads released, nothing fires.
    assert!(io.reconfigure(ms(100), with_torch(Polarity::ActiveHigh, 1), TORCH));
    io.poll(ms(200));
    assert!(!io.outputs().start);
    // The other way round: the pin is high (released on the reference wiring) and the
    // change makes that level active. It becomes active by the change alone: refused.
    let mut io = healthy();
    assert!(io.reconfigure(
        ms(100),
        with_torch(Polarity::ActiveHigh, 1),
        PinLevels::ALL_HIGH
    ));
    io.poll(ms(500));
    assert!(!io.outputs().start, "a change alone never fires");
    assert_eq!(
        io.interlocks().start_locked_by(),
        Some(Interlock::TorchOnAtWiringChange)
    );
    let refused = core::iter::from_fn(|| io.poll_event()).collect::<Vec<_>>();
    assert!(refused.contains(&IoEvent::StartRefused {
        reason: Interlock::TorchOnAtWiringChange
    }));
    // Seen inactive, then pressed: a fresh press fires.
    io.on_pins(ms(600), TORCH);
    assert!(!io.outputs().start);
    fire(&mut io, 700, PinLevels::ALL_HIGH);
}

#[test]
fn inverting_torch_on_during_a_cut_drops_start_and_needs_a_new_press() {
    let mut io = healthy();
    fire(&mut io, 100, TORCH);
    // The operator declares the level the pin has now (low) inactive: START drops at once.
    assert!(io.reconfigure(ms(300), with_torch(Polarity::ActiveHigh, 1), TORCH));
    assert!(!io.outputs().start);
    // And back: the held pin is active again by the change; it must be released first.
    assert!(io.reconfigure(ms(400), IoConfig::default(), TORCH));
    io.poll(ms(900));
    assert!(!io.outputs().start);
    assert_eq!(
        io.interlocks().start_locked_by(),
        Some(Interlock::TorchOnAtWiringChange)
    );
    io.on_pins(ms(1_000), PinLevels::ALL_HIGH);
    fire(&mut io, 1_100, TORCH);
}

#[test]
fn changing_torch_on_debounce_mid_press_never_fires() {
    // Pressed, half-way through a 20 ms debounce; the change to 1 ms takes the level at once:
    // held, so locked like at power-up.
    let mut io = healthy_with(with_torch(Polarity::ActiveLow, 20), PinLevels::ALL_HIGH);
    io.on_pins(ms(100), TORCH);
    io.poll(ms(110));
    assert!(!io.outputs().start);
    assert!(io.reconfigure(ms(110), with_torch(Polarity::ActiveLow, 1), TORCH));
    io.poll(ms(1_000));
    assert!(!io.outputs().start);
    // A change during a cut drops START the same way.
    io.on_pins(ms(1_100), PinLevels::ALL_HIGH);
    fire(&mut io, 1_200, TORCH);
    assert!(io.reconfigure(ms(1_400), with_torch(Polarity::ActiveLow, 5), TORCH));
    assert!(!io.outputs().start);
    io.poll(ms(2_000));
    assert!(!io.outputs().start);
    assert_eq!(
        io.config().inputs.get(Input::TorchOn).debounce,
        Duration::from_millis(5)
    );
}

#[test]
fn other_inputs_change_without_touching_start() {
    let mut io = healthy();
    fire(&mut io, 100, TORCH);
    let mut config = IoConfig::default();
    config
        .inputs
        .set_polarity(Input::Hold, Polarity::ActiveHigh);
    config
        .inputs
        .set_debounce(Input::NotReady, Duration::from_millis(50));
    // HOLD's pin is high: active under the new level, passed through at once.
    assert!(io.reconfigure(ms(200), config, TORCH));
    assert!(
        io.outputs().start,
        "not TORCH_ON's setting: the cut goes on"
    );
    assert!(io.outputs().hold);
}

#[test]
fn inverting_an_output_never_drives_start() {
    let mut io = healthy();
    fire(&mut io, 100, TORCH);
    let mut config = IoConfig::default();
    config
        .outputs
        .set(Output::Fault, Polarity::ActiveLow)
        .unwrap();
    config
        .outputs
        .set(Output::Hold, Polarity::ActiveLow)
        .unwrap();
    assert!(
        config
            .outputs
            .set(Output::Start, Polarity::ActiveLow)
            .is_err(),
        "START keeps the table's level"
    );
    assert!(io.reconfigure(ms(200), config, TORCH));
    assert!(
        io.outputs().start,
        "an output level is not an input setting"
    );
    let table = io.table_outputs();
    assert!(table.start);
    // FAULT and HOLD are off; their pins go to the configured inactive level: high.
    assert!(pins::output(Output::Fault).level(table.fault));
    assert!(pins::output(Output::Hold).level(table.hold));
    io.on_pins(ms(300), PinLevels::ALL_HIGH);
    assert!(!io.table_outputs().start);
}

#[test]
fn interlock_settings_apply_live() {
    let discrete_only = IoConfig {
        link_required: false,
        ..IoConfig::default()
    };
    let mut io = DiscreteIo::new(discrete_only, ms(0), PinLevels::ALL_HIGH);
    io.on_pins(ms(100), TORCH);
    io.poll(ms(101));
    assert!(io.outputs().start, "no link needed");

    // Looser: START stays on.
    let longer_gap = IoConfig {
        start_gap: Duration::from_millis(200),
        ..discrete_only
    };
    assert!(io.reconfigure(ms(150), longer_gap, TORCH));
    assert!(io.outputs().start);
    // Stricter: the link is required now and down, START drops in the same call.
    assert!(io.reconfigure(ms(160), IoConfig::default(), TORCH));
    assert!(!io.outputs().start);
    assert_eq!(io.interlocks().start_locked_by(), Some(Interlock::LinkDown));
}

#[test]
fn same_settings_change_nothing() {
    let mut io = healthy();
    fire(&mut io, 100, TORCH);
    assert!(!io.reconfigure(ms(200), IoConfig::default(), TORCH));
    assert!(io.outputs().start);
}

#[test]
fn inverted_polarity_input_reaches_the_interlocks() {
    let mut config = IoConfig::default();
    config
        .inputs
        .set_polarity(Input::Hold, Polarity::ActiveHigh);
    let idle = PinLevels::ALL_HIGH.with(Input::Hold, false);
    let mut io = DiscreteIo::new(config, ms(0), idle);
    assert!(!io.outputs().hold);
    io.on_pins(ms(10), PinLevels::ALL_HIGH);
    io.poll(ms(15));
    assert!(io.inputs().hold);
    assert!(io.outputs().hold);
}

mod random_changes {
    use super::*;
    use crate::io::SafetyMonitor;
    use proptest::prelude::*;

    /// One step of the world.
    #[derive(Debug, Clone)]
    enum Step {
        /// The TORCH_ON pin goes to this level.
        TorchPin(bool),
        /// Another input's pin (index into `Input::ALL`, skipping TORCH_ON).
        OtherPin(usize, bool),
        /// Time passes (µs).
        Wait(u64),
        /// TORCH_ON's active level and debounce change.
        TorchSetting(bool, u64),
        /// Another input's active level and debounce change.
        OtherSetting(usize, bool, u64),
        /// PS_HOLD and FAULT inverted or not.
        OutputLevels(bool, bool),
        /// The link comes or goes.
        Supply(bool),
    }

    fn step() -> impl Strategy<Value = Step> {
        prop_oneof![
            4 => any::<bool>().prop_map(Step::TorchPin),
            1 => (1usize..7, any::<bool>()).prop_map(|(i, h)| Step::OtherPin(i, h)),
            4 => (0u64..80_000).prop_map(Step::Wait),
            2 => (any::<bool>(), 0u64..20).prop_map(|(h, d)| Step::TorchSetting(h, d)),
            1 => (1usize..7, any::<bool>(), 0u64..20)
                .prop_map(|(i, h, d)| Step::OtherSetting(i, h, d)),
            1 => (any::<bool>(), any::<bool>()).prop_map(|(h, f)| Step::OutputLevels(h, f)),
            1 => any::<bool>().prop_map(Step::Supply),
        ]
    }

    fn polarity(high: bool) -> Polarity {
        if high {
            Polarity::ActiveHigh
        } else {
            Polarity::ActiveLow
        }
    }

    proptest! {
        /// Random CONFIG changes interleaved with input edges: START rises only after a fresh
        /// TORCH_ON press (as the CNC means it: the pin under the level set at that moment),
        /// never from a change alone, and no rule of the SafetyMonitor breaks. START reaches
        /// the pin exactly as the logic has it, whatever the output levels.
        #[test]
        fn changes_never_fire_the_torch(
            torch_pin_high in any::<bool>(),
            steps in prop::collection::vec(step(), 0..120),
        ) {
            let mut config = IoConfig::default();
            let mut pins = PinLevels::ALL_HIGH.with(Input::TorchOn, torch_pin_high);
            let mut now = 0u64;
            let t = Instant::from_micros;
            let mut io = DiscreteIo::new(config, t(now), pins);
            io.on_supply(t(now), SupplyState::HEALTHY);
            let means = |c: &IoConfig, p: PinLevels| {
                c.inputs.get(Input::TorchOn).polarity.is_active(p.is_high(Input::TorchOn))
            };
            let mut monitor = SafetyMonitor::new(means(&config, pins));
            // A press seen since the last START rise and the last TORCH_ON setting change.
            let mut fresh = false;
            let mut start = false;
            monitor.check(t(now), io.table_outputs().start, None);
            for step in steps {
                match step {
                    Step::TorchPin(high) => {
                        let was = means(&config, pins);
                        pins = pins.with(Input::TorchOn, high);
                        let active = means(&config, pins);
                        monitor.input(Input::TorchOn, active);
                        fresh = active && (fresh || !was);
                        io.on_pins(t(now), pins);
                    }
                    Step::OtherPin(i, high) => {
                        pins = pins.with(Input::ALL[i], high);
                        io.on_pins(t(now), pins);
                    }
                    Step::Wait(us) => {
                        now += us;
                        io.poll(t(now));
                    }
                    Step::TorchSetting(high, debounce) => {
                        let before = config.inputs.get(Input::TorchOn);
                        config.inputs.set_polarity(Input::TorchOn, polarity(high));
                        config
                            .inputs
                            .set_debounce(Input::TorchOn, Duration::from_millis(debounce));
                        if config.inputs.get(Input::TorchOn) != before {
                            monitor.torch_on_redefined(means(&config, pins));
                            fresh = false;
                        }
                        io.reconfigure(t(now), config, pins);
                    }
                    Step::OtherSetting(i, high, debounce) => {
                        config.inputs.set_polarity(Input::ALL[i], polarity(high));
                        config
                            .inputs
                            .set_debounce(Input::ALL[i], Duration::from_millis(debounce));
                        io.reconfigure(t(now), config, pins);
                    }
                    Step::OutputLevels(hold, fault) => {
                        config.outputs.set(Output::Hold, polarity(!hold)).unwrap();
                        config.outputs.set(Output::Fault, polarity(!fault)).unwrap();
                        io.reconfigure(t(now), config, pins);
                    }
                    Step::Supply(up) => {
                        let supply = if up { SupplyState::HEALTHY } else { SupplyState::default() };
                        io.on_supply(t(now), supply);
                    }
                }
                let table = io.table_outputs();
                prop_assert_eq!(table.start, io.outputs().start, "START never inverted");
                if table.start && !start {
                    prop_assert!(fresh, "START at {} us without a fresh press", now);
                    fresh = false;
                }
                start = table.start;
                monitor.check(t(now), table.start, None);
                prop_assert_eq!(monitor.violations(), &[][..]);
            }
        }
    }
}
