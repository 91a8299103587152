//! Property tests of the discrete I/O: random interleavings of CNC and supply edges, link
//! reports and time steps never break a safety rule (checked by the independent
//! `SafetyMonitor`), never panic, and never leave the bridge stuck.

use plasma_firmware::io::{
    Input, Inputs, Interlocks, IoConfig, Output, Outputs, SafetyMonitor, SupplyState, ViolationKind,
};
use plasma_protocol::time::{Duration, Instant};
use proptest::prelude::*;

#[derive(Debug, Clone)]
enum Op {
    Input(Input, bool),
    Supply(SupplyState),
    /// Let time pass; poll afterwards or not (an edge may be the next thing the board sees).
    Advance {
        micros: u64,
        poll: bool,
    },
    /// Jump to `poll_at()` and poll, as the board's timer would.
    PollAt,
}

fn any_input() -> impl Strategy<Value = Input> {
    prop::sample::select(Input::ALL.to_vec())
}

fn any_config() -> impl Strategy<Value = IoConfig> {
    (
        0u64..120,
        0u64..5,
        any::<bool>(),
        // A zero transfer time-out with drop-start refuses every start by design (unit test
        // `a_zero_timeout_refuses_every_start`); settings never allow it (100..10000 ms).
        1u64..4000,
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(
            |(gap, debounce, requires_start, timeout, drop, refuse_fault, link, ready, power)| {
                IoConfig {
                    start_gap: Duration::from_millis(gap),
                    arc_ok_debounce: Duration::from_millis(debounce),
                    arc_ok_requires_start: requires_start,
                    transfer_timeout: Duration::from_millis(timeout),
                    drop_start_on_transfer_timeout: drop,
                    refuse_start_on_fault: refuse_fault,
                    link_required: link,
                    ready_required: ready,
                    remote_power: power,
                    ..IoConfig::default()
                }
            },
        )
}

fn any_inputs() -> impl Strategy<Value = Inputs> {
    prop::array::uniform8(any::<bool>()).prop_map(|levels| {
        let mut inputs = Inputs::NONE;
        for (input, level) in Input::ALL.into_iter().zip(levels) {
            inputs.set(input, level);
        }
        inputs
    })
}

/// A supply report; the blackout is an offset from the time it is applied.
fn any_supply() -> impl Strategy<Value = (SupplyState, Option<u64>)> {
    (
        prop::bool::weighted(0.8),
        prop::bool::weighted(0.2),
        prop::bool::weighted(0.2),
        prop::option::weighted(0.2, 0u64..3_000_000),
        prop::bool::weighted(0.8),
    )
        .prop_map(|(link_up, action, active, blackout, ready)| {
            (
                SupplyState {
                    link_up,
                    fault_requires_action: action,
                    fault_active: active,
                    restart_blackout_until: None,
                    unit_ready: ready,
                },
                blackout,
            )
        })
}

fn any_op() -> impl Strategy<Value = (Op, Option<u64>)> {
    prop_oneof![
        4 => (any_input(), any::<bool>()).prop_map(|(i, a)| (Op::Input(i, a), None)),
        4 => (Just(Input::TorchOn), any::<bool>()).prop_map(|(i, a)| (Op::Input(i, a), None)),
        2 => any_supply().prop_map(|(s, b)| (Op::Supply(s), b)),
        3 => (prop_oneof![0u64..3_000, 0u64..100_000, 0u64..4_000_000], any::<bool>())
            .prop_map(|(micros, poll)| (Op::Advance { micros, poll }, None)),
        2 => Just((Op::PollAt, None)),
    ]
}

/// Runs the ops, checking after every step; returns the machine and the state of the run.
struct Run {
    io: Interlocks,
    monitor: SafetyMonitor,
    now: Instant,
    inputs: Inputs,
    supply: SupplyState,
    levels: Outputs,
    latest_blackout: Instant,
    /// When TORCH_ON last went from inactive to active.
    torch_rose_at: Option<Instant>,
    /// `now` of the previous call into the machine.
    previous_call: Instant,
}

impl Run {
    fn new(config: IoConfig, inputs: Inputs) -> Self {
        let io = Interlocks::new(config, Instant::ZERO, inputs);
        let mut monitor = SafetyMonitor::new(inputs.torch_on);
        monitor.ready_interlock(config.ready_required);
        monitor.input(Input::NotReady, inputs.not_ready);
        let mut run = Run {
            io,
            monitor,
            now: Instant::ZERO,
            inputs,
            supply: SupplyState::default(),
            levels: Outputs::OFF,
            latest_blackout: Instant::ZERO,
            torch_rose_at: None,
            previous_call: Instant::ZERO,
        };
        run.check(false);
        run
    }

    fn apply(&mut self, op: &Op, blackout: Option<u64>) {
        match *op {
            Op::Input(input, active) => {
                if input == Input::TorchOn && active && !self.inputs.torch_on {
                    self.torch_rose_at = Some(self.now);
                }
                self.inputs.set(input, active);
                self.monitor.input(input, active);
                self.io.on_input(self.now, input, active);
                self.check(false);
            }
            Op::Supply(mut supply) => {
                supply.restart_blackout_until =
                    blackout.map(|us| self.now + Duration::from_micros(us));
                if let Some(until) = supply.restart_blackout_until {
                    self.latest_blackout = self.latest_blackout.max(until);
                }
                self.supply = supply;
                self.monitor.link_reports(supply.link_up, supply.unit_ready);
                self.io.on_supply(self.now, supply);
                self.check(false);
            }
            Op::Advance { micros, poll } => {
                self.now = self.now + Duration::from_micros(micros);
                if poll {
                    self.io.poll(self.now);
                    self.check(true);
                }
            }
            Op::PollAt => {
                if let Some(at) = self.io.poll_at() {
                    self.now = self.now.max(at);
                }
                self.io.poll(self.now);
                self.check(true);
            }
        }
    }

    fn check(&mut self, polled: bool) {
        let out = self.io.outputs();
        self.monitor
            .check(self.now, out.start, self.supply.restart_blackout_until);
        assert!(
            self.monitor.is_clean(),
            "violations: {:?}",
            self.monitor.violations()
        );

        // The log tells the truth: every transition is a change, stamped now, and the
        // last one of each output is its current level.
        while let Some(t) = self.io.poll_transition() {
            assert_ne!(self.levels.get(t.output), t.level, "{t}");
            assert_eq!(t.at, self.now, "{t}");
            if t.output == Output::Start && t.level {
                // No surprise start: START only rises for a fresh TORCH_ON, in the call that
                // reports it or in the first call after the gap; never when an interlock
                // clears later on.
                let rose = self.torch_rose_at.expect("START without any TORCH_ON edge");
                let gap_end = rose + self.io.config().effective_start_gap();
                assert!(
                    t.at == rose || self.previous_call < gap_end,
                    "{t}: TORCH_ON at {rose:?}, previous call at {:?}",
                    self.previous_call
                );
            }
            set(&mut self.levels, t.output, t.level);
        }
        assert_eq!(self.levels, out);
        while self.io.poll_event().is_some() {}
        self.previous_call = self.now;

        let config = *self.io.config();
        if out.start {
            if config.link_required {
                assert!(self.supply.link_up, "START with the link down");
            }
            if config.refuse_start_on_fault {
                assert!(!self.supply.fault_requires_action, "START during a fault");
            }
        }
        if config.arc_ok_requires_start && out.arc_ok {
            assert!(out.start, "ARC_OK without START");
        }
        assert_eq!(out.hold, self.inputs.hold);
        assert_eq!(out.pierce_complete, self.inputs.pierce_complete);
        assert_eq!(out.corner_current, self.inputs.corner_current);
        if out.ready {
            assert!(!self.supply.fault_requires_action && self.supply.unit_ready);
            assert!(!self.inputs.not_ready);
        }
        if self.supply.fault_active
            || (config.link_required && !self.supply.link_up)
            || self.inputs.system_error
        {
            assert!(out.fault);
        }
        assert_eq!(out.remote_power, config.remote_power);
        if polled {
            // poll_at names every pending deadline: after a poll none is due.
            if let Some(at) = self.io.poll_at() {
                assert!(at > self.now, "poll_at {at:?} not after {:?}", self.now);
            }
        }
    }
}

fn set(outputs: &mut Outputs, output: Output, level: bool) {
    match output {
        Output::Start => outputs.start = level,
        Output::Hold => outputs.hold = level,
        Output::PierceComplete => outputs.pierce_complete = level,
        Output::CornerCurrent => outputs.corner_current = level,
        Output::ArcOk => outputs.arc_ok = level,
        Output::Ready => outputs.ready = level,
        Output::Fault => outputs.fault = level,
        Output::RemotePower => outputs.remote_power = level,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_interleavings_never_break_a_safety_rule(
        config in any_config(),
        initial in any_inputs(),
        ops in prop::collection::vec(any_op(), 0..200),
    ) {
        let mut run = Run::new(config, initial);
        for (op, blackout) in &ops {
            run.apply(op, *blackout);
        }

        // Never stuck: release the torch, heal the supply (and NOT_READY, SYSTEM_ERROR), wait
        // out every blackout and the gap, press again: START must come on at once.
        run.apply(&Op::Input(Input::TorchOn, false), None);
        run.apply(&Op::Input(Input::NotReady, false), None);
        run.apply(&Op::Input(Input::SystemError, false), None);
        run.apply(&Op::Supply(SupplyState::HEALTHY), None);
        run.now = run.now.max(run.latest_blackout) + Duration::from_millis(200);
        run.io.poll(run.now);
        run.check(true);
        run.apply(&Op::Input(Input::TorchOn, true), None);
        prop_assert!(run.io.outputs().start);
        prop_assert!(run.io.outputs().ready);
        prop_assert!(!run.io.outputs().fault);
    }

    /// The monitor can fail: a naive bridge that wires TORCH_ON straight to START is caught
    /// whenever the CNC holds TORCH_ON at power-up.
    #[test]
    fn the_monitor_catches_a_naive_bridge(
        steps in prop::collection::vec((any::<bool>(), 0u64..200_000), 0..50),
    ) {
        let mut monitor = SafetyMonitor::new(true);
        let mut now = Instant::ZERO;
        monitor.check(now, false, None); // power-up, START still off
        now = now + Duration::from_millis(1);
        monitor.check(now, true, None); // naive: START = TORCH_ON
        for (torch, dt) in steps {
            now = now + Duration::from_micros(dt);
            monitor.input(Input::TorchOn, torch);
            monitor.check(now, torch, None);
        }
        prop_assert!(!monitor.is_clean());
        prop_assert_eq!(
            monitor.violations()[0].kind,
            ViolationKind::StartFromTorchOnAtPowerUp
        );
    }
}
