//! Property: random interleavings of CNC input (valid commands, junk, Phoenix frames, the
//! simulator's TORCH ON/OFF), TORCH_ON edges on the discrete input, the arc (MOTION comes
//! from the simulator's own arc timing), unit faults, unit and bridge power cycles never break
//! a safety rule (the World's SafetyMonitor, checked after every step, panics on the first)
//! and never panic the bridge; every line the CNC gets stays well formed.

mod common;

use common::{phoenix_113, well_formed};
use host_tests::harness::{BridgeEndpoint, World, WorldOptions};
use plasma_firmware::settings::Settings;
use plasma_protocol::time::Duration;
use plasma_sim::Model;
use proptest::prelude::*;

/// Command lines a CNC (or a confused operator) might send.
const LINES: &[&str] = &[
    "STATUS",
    "ID",
    "FAULT",
    "FAULTLOG",
    "COUNTERS",
    "LIMITS",
    "CARTRIDGE",
    "HELP",
    "SET PROCESS CUT 45 AUTO",
    "SET PROCESS GOUGE 40 70",
    "SET PROCESS CPA 300 AUTO",
    "SET AMPS 30",
    "SET AMPS 130",
    "SET PSI AUTO",
    "SET MODE EXPANDED",
    "REMOTE OFF",
    "GASTEST ON",
    "GASTEST OFF",
    "GASTEST CHECK",
    "RESTART",
    "GASES O2 AIR",
    "CORNER 70",
    "RESET",
    "CLEARWARN",
    "EVENTS ON",
    "EVENTS OFF",
    "CONFIG",
    "CONFIG arc_ok_debounce_ms 0",
    "CONFIG arc_ok_debounce_ms 40",
    "CONFIG interlock_fault OFF",
    "CONFIG interlock_fault ON",
    "CONFIG interlock_link OFF",
    "CONFIG interlock_ready OFF",
    "CONFIG interlock_ready ON",
    "CONFIG transfer_timeout_ms 100",
    "CONFIG transfer_timeout_drops_start OFF",
    "CONFIG poll_ms 20",
    "CONFIG protocol HPR",
    "CONFIG timeout_ms 60",
    "CONFIG SAVE",
    "RAW :0104301A0001B0",
    "RAW >12093<",
    "RAW >00292<",
    "TORCH ON",
    "TORCH OFF",
    "TORCH ON",
    "TORCH OFF",
];

#[derive(Debug, Clone)]
enum Op {
    /// A command line (CR LF appended).
    Line(usize),
    /// Arbitrary bytes (junk, half lines, stray SOH/STX).
    Bytes(Vec<u8>),
    /// A Phoenix message, good or with a wrong check byte.
    Phoenix(usize, bool),
    /// The CNC's TORCH_ON input.
    Torch(bool),
    /// Let time pass (the arc transfers or not on its own timing).
    Run(u64),
    /// A unit fault (Powermax decimal code / HPR error).
    Fault(u16),
    ClearFault,
    UnitPowerCycle(u64),
    BridgePowerCycle,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        6 => (0..LINES.len()).prop_map(Op::Line),
        2 => prop::collection::vec(any::<u8>(), 0..40).prop_map(Op::Bytes),
        1 => ((0..LINES.len()), any::<bool>()).prop_map(|(i, good)| Op::Phoenix(i, good)),
        5 => any::<bool>().prop_map(Op::Torch),
        6 => prop_oneof![0u64..60, 60u64..3_500].prop_map(Op::Run),
        1 => prop::sample::select(vec![200u16, 500, 510, 1_300, 21, 44, 80]).prop_map(Op::Fault),
        1 => Just(Op::ClearFault),
        1 => (0u64..3_000).prop_map(Op::UnitPowerCycle),
        1 => Just(Op::BridgePowerCycle),
    ]
}

fn model() -> impl Strategy<Value = Model> {
    prop::sample::select(vec![
        Model::Sync65,
        Model::Sync45,
        Model::Pm85,
        Model::Hpr260,
        Model::MaxPro200,
    ])
}

fn apply(w: &mut World<BridgeEndpoint>, op: &Op) {
    match op {
        Op::Line(i) => w.cnc_send(format!("{}\r\n", LINES[*i]).as_bytes()),
        Op::Bytes(bytes) => w.cnc_send(bytes),
        Op::Phoenix(i, good) => {
            let frame = phoenix_113(LINES[*i], (!good).then_some(0xFF));
            w.cnc_send(&frame);
        }
        Op::Torch(on) => w.set_torch(*on),
        Op::Run(ms) => w.run_for(Duration::from_millis(*ms)),
        Op::Fault(code) => w.inject_fault(*code),
        Op::ClearFault => w.clear_fault(),
        Op::UnitPowerCycle(off_ms) => {
            w.power_off();
            w.run_for(Duration::from_millis(*off_ms));
            w.power_on();
        }
        Op::BridgePowerCycle => w.power_cycle_bridge(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn cnc_input_torch_edges_and_faults_never_break_a_safety_rule(
        model in model(),
        seed in 1u64..1_000,
        events in any::<bool>(),
        ops in prop::collection::vec(op(), 1..40),
    ) {
        let options = WorldOptions { seed, ..WorldOptions::default() };
        let settings = Settings { events, ..Settings::default() };
        let mut w = World::with_bridge(model, options, settings);
        w.run_for(Duration::from_millis(700));
        for op in &ops {
            apply(&mut w, op);
        }
        // Release the torch and let everything settle: START must follow at once.
        w.set_torch(false);
        prop_assert!(!w.io().outputs().start);
        w.run_for(Duration::from_secs(3));
        w.assert_safe();
        for line in w.cnc_lines() {
            prop_assert!(well_formed(line), "malformed CNC line {:?}", line);
        }
        // The session still answers (after ending a half line the ops may have left).
        w.cnc_send(b"\r\n");
        w.run_for(Duration::from_millis(100));
        // A command still under way answers first (GASTEST CHECK lets the gas flow for up to
        // 10 s), then ID.
        let mark = w.cnc_lines().count();
        w.cnc_send(b"ID\r\n");
        let answered = w.run_until(
            |w| w.cnc_lines().skip(mark).any(|l| l.starts_with("OK bridge=plasma-bridge")),
            Duration::from_secs(20),
        );
        prop_assert!(answered.is_ok(), "no ID reply: {:?}", w.cnc_lines().collect::<Vec<_>>());
    }
}
