//! Scenario tests of [`Interlocks`], one per rule, with exact times. Every step is also
//! checked by the independent [`SafetyMonitor`].

use std::vec::Vec;

use super::*;
use crate::io::SafetyMonitor;
use plasma_protocol::time::{Duration, Instant};

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

fn us(v: u64) -> Instant {
    Instant::from_micros(v)
}

/// The machine under test, its supply state, and a monitor fed every input edge as the board
/// receives it and the START pin after every step.
struct Rig {
    io: Interlocks,
    supply: SupplyState,
    monitor: SafetyMonitor,
    transitions: Vec<Transition>,
    events: Vec<IoEvent>,
}

impl Rig {
    fn new(config: IoConfig, inputs: Inputs) -> Self {
        let io = Interlocks::new(config, ms(0), inputs);
        let mut monitor = SafetyMonitor::new(inputs.torch_on);
        monitor.ready_interlock(config.ready_required);
        monitor.input(Input::NotReady, inputs.not_ready);
        let mut rig = Rig {
            io,
            supply: SupplyState::default(),
            monitor,
            transitions: Vec::new(),
            events: Vec::new(),
        };
        rig.after(ms(0));
        rig
    }

    /// Default config, nothing active, healthy supply reported at 0 ms, logs cleared.
    fn healthy() -> Self {
        Self::healthy_with(IoConfig::default())
    }

    fn healthy_with(config: IoConfig) -> Self {
        let mut rig = Rig::new(config, Inputs::NONE);
        rig.supply(ms(0), SupplyState::HEALTHY);
        rig.clear();
        rig
    }

    fn after(&mut self, now: Instant) {
        self.monitor.check(
            now,
            self.io.outputs().start,
            self.supply.restart_blackout_until,
        );
        assert!(
            self.monitor.is_clean(),
            "safety violation: {:?}",
            self.monitor.violations()
        );
        while let Some(t) = self.io.poll_transition() {
            self.transitions.push(t);
        }
        while let Some(e) = self.io.poll_event() {
            self.events.push(e);
        }
    }

    fn input(&mut self, now: Instant, input: Input, active: bool) {
        self.monitor.input(input, active);
        self.io.on_input(now, input, active);
        self.after(now);
    }

    fn torch(&mut self, now: Instant, active: bool) {
        self.input(now, Input::TorchOn, active);
    }

    fn motion(&mut self, now: Instant, active: bool) {
        self.input(now, Input::Motion, active);
    }

    fn supply(&mut self, now: Instant, supply: SupplyState) {
        self.supply = supply;
        self.monitor.link_reports(supply.link_up, supply.unit_ready);
        self.io.on_supply(now, supply);
        self.after(now);
    }

    fn poll(&mut self, now: Instant) {
        self.io.poll(now);
        self.after(now);
    }

    fn start(&self) -> bool {
        self.io.outputs().start
    }

    fn clear(&mut self) {
        self.transitions.clear();
        self.events.clear();
    }

    /// The logged transitions of one output since the last clear.
    fn log(&self, output: Output) -> Vec<(bool, Reason, Instant)> {
        self.transitions
            .iter()
            .filter(|t| t.output == output)
            .map(|t| (t.level, t.reason, t.at))
            .collect()
    }
}

// ---- START follows TORCH_ON ----

#[test]
fn everything_is_off_at_reset_except_fault_for_the_missing_link() {
    let rig = Rig::new(IoConfig::default(), Inputs::NONE);
    let out = rig.io.outputs();
    assert_eq!(
        out,
        Outputs {
            fault: true,
            ..Outputs::OFF
        }
    );
    assert_eq!(
        rig.transitions,
        [Transition {
            output: Output::Fault,
            level: true,
            reason: Reason::LinkDown,
            at: ms(0)
        }]
    );
    assert!(rig.events.is_empty());
    assert_eq!(rig.io.poll_at(), None);
}

#[test]
fn start_follows_torch_on_in_the_same_call() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    assert!(rig.start());
    rig.torch(ms(200), false);
    assert!(!rig.start());
    assert_eq!(
        rig.log(Output::Start),
        [
            (true, Reason::TorchOn, ms(100)),
            (false, Reason::TorchOff, ms(200))
        ]
    );
}

#[test]
fn a_repeated_level_is_not_an_edge() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(150), true);
    assert!(rig.start());
    assert_eq!(rig.log(Output::Start).len(), 1);
    rig.torch(ms(200), false);
    rig.torch(ms(210), false);
    assert_eq!(rig.log(Output::Start).len(), 2);
}

// ---- power-up ----

#[test]
fn torch_on_at_power_up_is_ignored_until_seen_inactive() {
    let stuck = Inputs {
        torch_on: true,
        ..Inputs::NONE
    };
    let mut rig = Rig::new(IoConfig::default(), stuck);
    assert_eq!(rig.events, [IoEvent::StuckTorchOnAtPowerUp]);
    rig.supply(ms(10), SupplyState::HEALTHY);
    rig.poll(ms(5000));
    assert!(!rig.start());
    assert_eq!(rig.io.start_locked_by(), Some(Interlock::TorchOnAtPowerUp));

    rig.torch(ms(6000), false);
    assert_eq!(rig.io.start_locked_by(), None);
    rig.torch(ms(6100), true);
    assert!(rig.start());
    assert_eq!(rig.log(Output::Start), [(true, Reason::TorchOn, ms(6100))]);
}

#[test]
fn reset_counts_as_a_start_falling_edge() {
    let mut rig = Rig::healthy();
    rig.torch(ms(10), true);
    assert!(!rig.start());
    assert_eq!(rig.events, [IoEvent::StartDelayed { until: ms(50) }]);
    assert_eq!(rig.io.poll_at(), Some(ms(50)));
    rig.poll(us(49_999));
    assert!(!rig.start());
    rig.poll(ms(50));
    assert!(rig.start());
    assert_eq!(
        rig.log(Output::Start),
        [(true, Reason::StartGapElapsed, ms(50))]
    );
}

// ---- 50 ms between starts ----

#[test]
fn torch_on_inside_the_gap_is_delayed_to_the_gap_end() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(200), false);
    rig.clear();
    rig.torch(ms(220), true);
    assert!(!rig.start());
    assert_eq!(rig.events, [IoEvent::StartDelayed { until: ms(250) }]);
    assert_eq!(rig.io.poll_at(), Some(ms(250)));
    rig.poll(us(249_999));
    assert!(!rig.start());
    rig.poll(ms(250));
    assert!(rig.start());
    assert_eq!(
        rig.log(Output::Start),
        [(true, Reason::StartGapElapsed, ms(250))]
    );
}

#[test]
fn torch_on_exactly_at_the_gap_end_starts_at_once() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(200), false);
    rig.torch(ms(250), true);
    assert!(rig.start());
}

#[test]
fn torch_on_released_inside_the_gap_is_forgotten() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(200), false);
    rig.torch(ms(210), true);
    rig.torch(ms(230), false);
    assert_eq!(rig.io.poll_at(), None);
    rig.poll(ms(250));
    assert!(!rig.start());
    // A new request after the gap is served at once.
    rig.torch(ms(260), true);
    assert!(rig.start());
}

#[test]
fn a_delayed_start_is_refused_if_an_interlock_falls_during_the_gap() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(200), false);
    rig.torch(ms(210), true);
    rig.clear();
    rig.supply(
        ms(220),
        SupplyState {
            fault_requires_action: true,
            ..SupplyState::HEALTHY
        },
    );
    assert_eq!(
        rig.events,
        [IoEvent::StartRefused {
            reason: Interlock::FaultRequiresAction
        }]
    );
    rig.supply(ms(230), SupplyState::HEALTHY);
    rig.poll(ms(300));
    assert!(!rig.start());
}

#[test]
fn a_longer_gap_can_be_configured_but_not_a_shorter_one() {
    let mut rig = Rig::healthy_with(IoConfig {
        start_gap: Duration::from_millis(10),
        ..IoConfig::default()
    });
    rig.torch(ms(100), true);
    rig.torch(ms(200), false);
    rig.torch(ms(220), true);
    assert!(!rig.start());
    assert_eq!(rig.io.poll_at(), Some(ms(250)));

    let mut rig = Rig::healthy_with(IoConfig {
        start_gap: Duration::from_millis(120),
        ..IoConfig::default()
    });
    rig.torch(ms(200), true);
    rig.torch(ms(300), false);
    rig.torch(ms(400), true);
    assert!(!rig.start());
    rig.poll(ms(420));
    assert!(rig.start());
}

#[test]
fn time_running_backwards_cannot_shorten_the_gap() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(200), false);
    // A caller passing an older instant is treated as "still 200 ms".
    rig.io.on_input(ms(150), Input::TorchOn, true);
    assert!(!rig.io.outputs().start);
    rig.io.poll(ms(249));
    assert!(!rig.io.outputs().start);
    rig.io.poll(ms(250));
    assert!(rig.io.outputs().start);
}

// ---- quick-restart blackout ----

fn blackout_until(t: Instant) -> SupplyState {
    SupplyState {
        restart_blackout_until: Some(t),
        ..SupplyState::HEALTHY
    }
}

#[test]
fn torch_on_during_a_blackout_is_refused_and_stays_off_until_reasserted() {
    let mut rig = Rig::healthy();
    rig.supply(ms(100), blackout_until(ms(2100)));
    rig.clear();
    rig.torch(ms(500), true);
    assert!(!rig.start());
    assert_eq!(
        rig.events,
        [IoEvent::StartRefused {
            reason: Interlock::RestartBlackout
        }]
    );
    assert_eq!(rig.io.poll_at(), Some(ms(2100)));
    rig.poll(ms(2100));
    assert!(!rig.start(), "the end of a blackout never fires the torch");
    rig.torch(ms(2200), false);
    rig.torch(ms(2300), true);
    assert!(rig.start());
}

#[test]
fn torch_on_at_the_blackout_end_is_served() {
    let mut rig = Rig::healthy();
    rig.supply(ms(100), blackout_until(ms(2100)));
    rig.torch(us(2_099_999), true);
    assert!(!rig.start());
    rig.torch(ms(2099), false);
    rig.torch(ms(2100), true);
    assert!(rig.start());
}

#[test]
fn a_blackout_drops_a_running_start_at_once() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.clear();
    rig.supply(ms(300), blackout_until(ms(2300)));
    assert!(!rig.start());
    assert_eq!(
        rig.log(Output::Start),
        [(
            false,
            Reason::Interlock(Interlock::RestartBlackout),
            ms(300)
        )]
    );
    assert!(rig.events.contains(&IoEvent::StartDropped {
        reason: Interlock::RestartBlackout
    }));
}

#[test]
fn a_later_report_cannot_shorten_a_blackout() {
    let mut rig = Rig::healthy();
    rig.supply(ms(100), blackout_until(ms(2100)));
    rig.supply(ms(200), SupplyState::HEALTHY);
    rig.supply(ms(300), blackout_until(ms(1000)));
    rig.torch(ms(1500), true);
    assert!(!rig.start());
    assert_eq!(rig.io.start_locked_by(), Some(Interlock::RestartBlackout));
}

// ---- fault and link interlocks ----

fn fault_requiring_action() -> SupplyState {
    SupplyState {
        fault_requires_action: true,
        fault_active: true,
        ..SupplyState::HEALTHY
    }
}

fn link_down() -> SupplyState {
    SupplyState {
        link_up: false,
        ..SupplyState::HEALTHY
    }
}

#[test]
fn a_fault_requiring_action_refuses_start_and_clearing_it_does_not_fire() {
    let mut rig = Rig::healthy();
    rig.supply(ms(100), fault_requiring_action());
    rig.clear();
    rig.torch(ms(200), true);
    assert!(!rig.start());
    assert_eq!(
        rig.events,
        [IoEvent::StartRefused {
            reason: Interlock::FaultRequiresAction
        }]
    );
    rig.supply(ms(300), SupplyState::HEALTHY);
    assert!(!rig.start());
    rig.torch(ms(400), false);
    rig.torch(ms(500), true);
    assert!(rig.start());
}

#[test]
fn a_fault_requiring_action_drops_a_running_start_at_once() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.supply(ms(150), fault_requiring_action());
    assert!(!rig.start());
    assert_eq!(
        rig.log(Output::Start).last(),
        Some(&(
            false,
            Reason::Interlock(Interlock::FaultRequiresAction),
            ms(150)
        ))
    );
}

#[test]
fn a_fault_that_needs_no_action_does_not_stop_the_torch() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.supply(
        ms(150),
        SupplyState {
            fault_active: true,
            ..SupplyState::HEALTHY
        },
    );
    assert!(rig.start());
    assert!(rig.io.outputs().fault);
    assert!(rig.io.outputs().ready);
}

#[test]
fn the_fault_interlock_can_be_switched_off() {
    let mut rig = Rig::healthy_with(IoConfig {
        refuse_start_on_fault: false,
        ..IoConfig::default()
    });
    rig.supply(ms(100), fault_requiring_action());
    rig.torch(ms(200), true);
    assert!(rig.start());
    // READY still tells the truth.
    assert!(!rig.io.outputs().ready);
}

#[test]
fn a_lost_link_refuses_and_drops_start() {
    let mut rig = Rig::healthy();
    rig.supply(ms(100), link_down());
    rig.torch(ms(200), true);
    assert_eq!(rig.io.start_locked_by(), Some(Interlock::LinkDown));
    rig.torch(ms(300), false);
    rig.supply(ms(400), SupplyState::HEALTHY);
    rig.torch(ms(500), true);
    assert!(rig.start());
    rig.supply(ms(600), link_down());
    assert!(!rig.start());
    assert_eq!(
        rig.log(Output::Start).last(),
        Some(&(false, Reason::Interlock(Interlock::LinkDown), ms(600)))
    );
}

#[test]
fn a_discrete_only_installation_needs_no_link() {
    let mut rig = Rig::new(
        IoConfig {
            link_required: false,
            ..IoConfig::default()
        },
        Inputs::NONE,
    );
    assert!(!rig.io.outputs().fault);
    rig.torch(ms(100), true);
    assert!(rig.start());
}

// ---- ARC_OK ----

#[test]
fn arc_ok_follows_motion_after_the_debounce() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.clear();
    rig.motion(ms(500), true);
    assert!(!rig.io.outputs().arc_ok);
    assert_eq!(rig.io.poll_at(), Some(ms(502)));
    rig.poll(us(501_999));
    assert!(!rig.io.outputs().arc_ok);
    rig.poll(ms(502));
    assert!(rig.io.outputs().arc_ok);
    rig.motion(ms(900), false);
    rig.poll(us(901_999));
    assert!(rig.io.outputs().arc_ok);
    rig.poll(ms(902));
    assert!(!rig.io.outputs().arc_ok);
    assert_eq!(
        rig.log(Output::ArcOk),
        [
            (true, Reason::ArcTransferred, ms(502)),
            (false, Reason::ArcLost, ms(902))
        ]
    );
    assert_eq!(rig.events, [IoEvent::ArcOn, IoEvent::ArcOff]);
    assert!(rig.start(), "losing the arc is the CNC's call, not ours");
}

#[test]
fn a_bouncing_motion_restarts_the_debounce() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.motion(ms(500), true);
    rig.motion(ms(501), false);
    rig.motion(us(501_500), true);
    rig.poll(ms(502));
    assert!(!rig.io.outputs().arc_ok);
    rig.poll(us(503_500));
    assert!(rig.io.outputs().arc_ok);
}

#[test]
fn the_debounce_is_configurable() {
    let mut rig = Rig::healthy_with(IoConfig {
        arc_ok_debounce: Duration::from_millis(10),
        ..IoConfig::default()
    });
    rig.torch(ms(100), true);
    rig.motion(ms(500), true);
    rig.poll(ms(509));
    assert!(!rig.io.outputs().arc_ok);
    rig.poll(ms(510));
    assert!(rig.io.outputs().arc_ok);

    let mut rig = Rig::healthy_with(IoConfig {
        arc_ok_debounce: Duration::ZERO,
        ..IoConfig::default()
    });
    rig.torch(ms(100), true);
    rig.motion(ms(500), true);
    assert!(rig.io.outputs().arc_ok);
}

#[test]
fn arc_ok_drops_with_start_in_the_same_call() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.motion(ms(500), true);
    rig.poll(ms(502));
    rig.clear();
    rig.torch(ms(800), false);
    assert_eq!(rig.log(Output::ArcOk), [(false, Reason::StartOff, ms(800))]);
}

#[test]
fn motion_without_our_start_is_not_arc_ok_by_default() {
    let mut rig = Rig::healthy();
    rig.motion(ms(100), true);
    rig.poll(ms(102));
    assert!(!rig.io.outputs().arc_ok);
    assert_eq!(rig.events, [IoEvent::ArcOn]);
    // START coming on with MOTION already there raises ARC_OK with START.
    rig.torch(ms(200), true);
    assert_eq!(rig.log(Output::ArcOk), [(true, Reason::StartOn, ms(200))]);
}

#[test]
fn arc_ok_can_follow_motion_without_start() {
    let mut rig = Rig::healthy_with(IoConfig {
        arc_ok_requires_start: false,
        ..IoConfig::default()
    });
    rig.motion(ms(100), true);
    rig.poll(ms(102));
    assert!(rig.io.outputs().arc_ok);
    assert!(!rig.start());
}

// ---- transfer time-out ----

#[test]
fn no_transfer_within_the_timeout_drops_start_until_reasserted() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.clear();
    assert_eq!(rig.io.poll_at(), Some(ms(3100)));
    rig.poll(us(3_099_999));
    assert!(rig.start());
    assert!(rig.events.is_empty());
    rig.poll(ms(3100));
    assert!(!rig.start());
    assert_eq!(
        rig.events,
        [
            IoEvent::TransferTimeout,
            IoEvent::StartDropped {
                reason: Interlock::TransferTimeout
            }
        ]
    );
    assert_eq!(
        rig.log(Output::Start),
        [(
            false,
            Reason::Interlock(Interlock::TransferTimeout),
            ms(3100)
        )]
    );
    rig.poll(ms(9000));
    assert!(!rig.start());
    rig.torch(ms(9100), false);
    rig.torch(ms(9200), true);
    assert!(rig.start());
}

#[test]
fn a_transfer_in_time_prevents_the_timeout() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.motion(ms(3000), true);
    rig.poll(ms(3002));
    assert_eq!(rig.io.poll_at(), None);
    rig.motion(ms(3050), false); // arc lost later: not a transfer failure
    rig.poll(ms(3052));
    rig.poll(ms(4000));
    assert!(rig.start());
    assert!(!rig.events.contains(&IoEvent::TransferTimeout));
}

#[test]
fn the_timeout_can_only_report_and_is_reported_once() {
    let mut rig = Rig::healthy_with(IoConfig {
        drop_start_on_transfer_timeout: false,
        transfer_timeout: Duration::from_millis(500),
        ..IoConfig::default()
    });
    rig.torch(ms(100), true);
    rig.poll(ms(600));
    rig.poll(ms(700));
    assert!(rig.start());
    assert_eq!(rig.events, [IoEvent::TransferTimeout]);
    assert_eq!(rig.io.poll_at(), None);
}

#[test]
fn the_timeout_restarts_with_each_start() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(2000), false);
    rig.torch(ms(2100), true);
    rig.poll(ms(3100));
    assert!(rig.start());
    rig.poll(ms(5100));
    assert!(!rig.start());
}

#[test]
fn a_zero_timeout_refuses_every_start() {
    let mut rig = Rig::healthy_with(IoConfig {
        transfer_timeout: Duration::ZERO,
        ..IoConfig::default()
    });
    rig.torch(ms(100), true);
    assert!(!rig.start());
    assert_eq!(
        rig.events,
        [
            IoEvent::TransferTimeout,
            IoEvent::StartRefused {
                reason: Interlock::TransferTimeout
            }
        ]
    );
    assert_eq!(rig.io.poll_at(), None);
}

// ---- READY and FAULT ----

#[test]
fn ready_needs_link_no_action_fault_no_blackout_and_a_ready_unit() {
    let mut rig = Rig::new(IoConfig::default(), Inputs::NONE);
    rig.clear();
    rig.supply(ms(10), SupplyState::HEALTHY);
    assert_eq!(
        rig.log(Output::Ready),
        [(true, Reason::SupplyReady, ms(10))]
    );

    let cases = [
        (link_down(), Reason::LinkDown),
        (fault_requiring_action(), Reason::FaultRequiresAction),
        (
            SupplyState {
                unit_ready: false,
                ..SupplyState::HEALTHY
            },
            Reason::UnitNotReady,
        ),
        // Last: a blackout outlives later reports.
        (blackout_until(ms(10_000)), Reason::RestartBlackout),
    ];
    for (i, (state, reason)) in cases.into_iter().enumerate() {
        let t = ms(100 * (i as u64 + 1));
        rig.clear();
        rig.supply(t, state);
        assert_eq!(rig.log(Output::Ready), [(false, reason, t)], "{reason}");
        rig.supply(t + Duration::from_millis(1), SupplyState::HEALTHY);
    }
    rig.clear();
    rig.poll(ms(10_000));
    assert_eq!(
        rig.log(Output::Ready),
        [(true, Reason::SupplyReady, ms(10_000))]
    );
}

#[test]
fn ready_comes_back_when_the_blackout_ends() {
    let mut rig = Rig::healthy();
    rig.supply(ms(100), blackout_until(ms(2100)));
    assert!(!rig.io.outputs().ready);
    assert_eq!(rig.io.poll_at(), Some(ms(2100)));
    rig.poll(us(2_099_999));
    assert!(!rig.io.outputs().ready);
    rig.poll(ms(2100));
    assert!(rig.io.outputs().ready);
    assert_eq!(rig.io.poll_at(), None);
}

// A unit that is not ready for a start: HPR manual (002_72b43a5685974c77.txt) line 55, the
// NOT_READY signal ("not ready for a plasma start signal ... purging or in test gas mode"),
// and the state codes at lines 456-470 (03 IDLE2 / READY FOR START; a start takes it to 04
// PREFLOW and on, so readiness is asked before START rises, never while it is on).

fn unit_not_ready() -> SupplyState {
    SupplyState {
        unit_ready: false,
        ..SupplyState::HEALTHY
    }
}

#[test]
fn a_unit_not_ready_refuses_start_and_becoming_ready_does_not_fire() {
    let mut rig = Rig::healthy();
    rig.supply(ms(10), unit_not_ready()); // an HPR in PURGE (state 02)
    rig.torch(ms(100), true);
    assert!(!rig.start());
    assert_eq!(rig.io.start_locked_by(), Some(Interlock::NotReady));
    assert_eq!(
        rig.events,
        [IoEvent::StartRefused {
            reason: Interlock::NotReady
        }]
    );
    rig.supply(ms(200), SupplyState::HEALTHY);
    assert!(
        !rig.start(),
        "the refusal latches until TORCH_ON is released"
    );
    rig.torch(ms(300), false);
    rig.torch(ms(400), true);
    assert!(rig.start());
}

#[test]
fn the_not_ready_signal_refuses_start() {
    let mut rig = Rig::healthy();
    rig.input(ms(100), Input::NotReady, true);
    rig.torch(ms(200), true);
    assert!(!rig.start());
    assert_eq!(rig.io.start_locked_by(), Some(Interlock::NotReady));
    rig.input(ms(300), Input::NotReady, false);
    rig.torch(ms(400), false);
    rig.torch(ms(500), true);
    assert!(rig.start());
}

#[test]
fn a_unit_leaving_its_ready_state_during_a_cut_keeps_start() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    assert!(rig.start());
    // The HPR took the start: PREFLOW, and its NOT_READY signal on.
    rig.supply(ms(150), unit_not_ready());
    rig.input(ms(160), Input::NotReady, true);
    rig.poll(ms(500));
    assert!(
        rig.start(),
        "readiness is asked before START rises, never during a cut"
    );
    assert!(
        rig.events
            .iter()
            .all(|e| !matches!(e, IoEvent::StartDropped { .. }))
    );
}

#[test]
fn a_unit_not_ready_refuses_start_also_at_the_end_of_the_start_gap() {
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    rig.torch(ms(110), false);
    rig.torch(ms(120), true); // inside the 50 ms gap: delayed to 160 ms
    assert!(!rig.start());
    rig.supply(ms(130), unit_not_ready());
    rig.poll(ms(160));
    assert!(!rig.start());
    assert_eq!(rig.io.start_locked_by(), Some(Interlock::NotReady));
}

#[test]
fn with_the_link_down_only_the_link_interlock_judges_the_units_state() {
    let config = IoConfig {
        link_required: false,
        ..IoConfig::default()
    };
    let mut rig = Rig::healthy_with(config);
    rig.supply(ms(10), SupplyState::default()); // link down: its state is unknown
    rig.torch(ms(100), true);
    assert!(rig.start(), "discrete-only wiring fires on TORCH_ON alone");
}

#[test]
fn with_the_ready_interlock_off_not_ready_only_clears_ready() {
    let config = IoConfig {
        ready_required: false,
        ..IoConfig::default()
    };
    let mut rig = Rig::healthy_with(config);
    rig.input(ms(100), Input::NotReady, true);
    assert_eq!(
        rig.log(Output::Ready),
        [(false, Reason::NotReadySignal, ms(100))]
    );
    rig.torch(ms(200), true);
    assert!(rig.start());
    rig.input(ms(300), Input::NotReady, false);
    assert!(rig.io.outputs().ready);
}

#[test]
fn fault_shows_an_active_fault_or_a_lost_link() {
    let mut rig = Rig::new(IoConfig::default(), Inputs::NONE);
    rig.clear();
    rig.supply(ms(10), SupplyState::HEALTHY);
    rig.supply(
        ms(20),
        SupplyState {
            fault_active: true,
            ..SupplyState::HEALTHY
        },
    );
    rig.supply(ms(30), SupplyState::HEALTHY);
    rig.supply(ms(40), link_down());
    assert_eq!(
        rig.log(Output::Fault),
        [
            (false, Reason::FaultCleared, ms(10)),
            (true, Reason::FaultActive, ms(20)),
            (false, Reason::FaultCleared, ms(30)),
            (true, Reason::LinkDown, ms(40)),
        ]
    );
}

// ---- pass-through and other inputs ----

#[test]
fn hold_pierce_and_corner_pass_through_at_once_and_ungated() {
    let mut rig = Rig::new(IoConfig::default(), Inputs::NONE); // link down, START off
    rig.clear();
    for ((input, output), t) in [
        (Input::Hold, Output::Hold),
        (Input::PierceComplete, Output::PierceComplete),
        (Input::CornerCurrent, Output::CornerCurrent),
    ]
    .into_iter()
    .zip([100, 300, 500])
    {
        rig.input(ms(t), input, true);
        assert!(rig.io.outputs().get(output));
        rig.input(ms(t + 100), input, false);
        assert!(!rig.io.outputs().get(output));
        assert_eq!(
            rig.log(output),
            [
                (true, Reason::CncInput, ms(t)),
                (false, Reason::CncInput, ms(t + 100))
            ]
        );
    }
}

#[test]
fn pass_through_inputs_active_at_power_up_pass_through() {
    let rig = Rig::new(
        IoConfig::default(),
        Inputs {
            hold: true,
            corner_current: true,
            ..Inputs::NONE
        },
    );
    let out = rig.io.outputs();
    assert!(out.hold && out.corner_current && !out.pierce_complete);
}

#[test]
fn rampdown_error_is_an_event_on_its_rising_edge() {
    let mut rig = Rig::healthy();
    rig.input(ms(100), Input::RampdownError, true);
    rig.input(ms(150), Input::RampdownError, true);
    rig.input(ms(200), Input::RampdownError, false);
    assert_eq!(rig.events, [IoEvent::RampdownError]);
    assert!(rig.transitions.is_empty());
}

#[test]
fn system_error_holds_fault_on_and_is_an_event_but_does_not_drop_start() {
    // HPR manual (002_72b43a5685974c77.txt) line 51: System Error, an output of the unit,
    // "indicates that an error has occurred in the plasma system. Use the serial interface
    // to query for the specific error code number." A fault seen on the wire, so FAULT; the
    // manual does not say the unit cannot cut, so START is left to the link's fault report.
    let mut rig = Rig::healthy();
    rig.torch(ms(100), true);
    assert!(rig.start());
    rig.clear();
    rig.input(ms(200), Input::SystemError, true);
    rig.input(ms(250), Input::SystemError, true);
    assert_eq!(rig.events, [IoEvent::SystemError]);
    assert!(rig.io.outputs().fault && rig.start() && rig.io.outputs().ready);
    assert_eq!(
        (rig.transitions[0].output, rig.transitions[0].reason),
        (Output::Fault, Reason::SystemErrorSignal)
    );
    rig.input(ms(300), Input::SystemError, false);
    assert!(!rig.io.outputs().fault);
    assert_eq!(
        rig.transitions.last().map(|t| t.reason),
        Some(Reason::FaultCleared)
    );
    assert_eq!(rig.events.len(), 1, "an event on the rising edge only");
}

#[test]
fn remote_power_follows_the_cnc_command_and_never_touches_start() {
    let mut rig = Rig::healthy();
    assert!(!rig.io.outputs().remote_power, "off from reset");
    let on = IoConfig {
        remote_power: true,
        ..IoConfig::default()
    };
    rig.io.set_config(ms(100), on);
    rig.after(ms(100));
    assert!(rig.io.outputs().remote_power && !rig.start());
    assert_eq!(
        (rig.transitions[0].output, rig.transitions[0].reason),
        (Output::RemotePower, Reason::CncCommand)
    );
    rig.torch(ms(200), true);
    rig.io.set_config(ms(300), IoConfig::default());
    rig.after(ms(300));
    assert!(!rig.io.outputs().remote_power);
    assert!(
        rig.start(),
        "START is the link's and TORCH_ON's, not POWER's"
    );
}

// ---- logs ----

#[test]
fn an_undrained_log_keeps_the_newest_and_counts_the_lost() {
    let mut io = Interlocks::new(IoConfig::default(), ms(0), Inputs::NONE);
    for i in 0..40 {
        io.on_input(ms(i), Input::Hold, i % 2 == 0);
    }
    // 1 FAULT transition at reset + 40 HOLD transitions, 32 kept.
    assert_eq!(io.lost_transitions(), 9);
    let mut last = None;
    let mut n = 0;
    while let Some(t) = io.poll_transition() {
        last = Some(t);
        n += 1;
    }
    assert_eq!(n, 32);
    assert_eq!(last.map(|t| (t.level, t.at)), Some((false, ms(39))));
}

#[test]
fn switching_an_interlock_on_while_running_drops_start_at_once() {
    let config = IoConfig {
        refuse_start_on_fault: false,
        ..IoConfig::default()
    };
    let mut rig = Rig::healthy_with(config);
    rig.supply(
        ms(10),
        SupplyState {
            fault_requires_action: true,
            fault_active: true,
            ..SupplyState::HEALTHY
        },
    );
    rig.torch(ms(100), true);
    assert!(
        rig.start(),
        "the fault interlock is off: START follows TORCH_ON"
    );
    rig.io.set_config(ms(200), IoConfig::default());
    rig.after(ms(200));
    assert!(
        !rig.start(),
        "switching the interlock on drops START in the same call"
    );
    assert_eq!(
        rig.io.start_locked_by(),
        Some(Interlock::FaultRequiresAction)
    );
}

#[test]
fn loosening_an_interlock_while_running_never_fires_the_torch() {
    let mut rig = Rig::healthy();
    rig.supply(
        ms(10),
        SupplyState {
            fault_requires_action: true,
            fault_active: true,
            ..SupplyState::HEALTHY
        },
    );
    rig.torch(ms(100), true);
    assert!(!rig.start());
    let loose = IoConfig {
        refuse_start_on_fault: false,
        ..IoConfig::default()
    };
    rig.io.set_config(ms(200), loose);
    rig.after(ms(200));
    rig.poll(ms(300));
    assert!(
        !rig.start(),
        "the refusal latches until TORCH_ON is released"
    );
    rig.torch(ms(400), false);
    rig.torch(ms(500), true);
    assert!(
        rig.start(),
        "a fresh TORCH_ON is honoured under the new setting"
    );
}

#[test]
fn a_new_debounce_time_applies_to_the_next_motion_edge() {
    let mut rig = Rig::healthy();
    let slow = IoConfig {
        arc_ok_debounce: Duration::from_millis(20),
        ..IoConfig::default()
    };
    rig.io.set_config(ms(1), slow);
    rig.after(ms(1));
    rig.torch(ms(100), true);
    rig.motion(ms(110), true);
    rig.poll(ms(125));
    assert!(!rig.io.outputs().arc_ok, "20 ms have not passed");
    rig.poll(ms(130));
    assert!(rig.io.outputs().arc_ok);
}
