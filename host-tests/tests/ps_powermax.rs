//! Scenario tests on Powermax units (SYNC and legacy): remote settings on the wire, refusals
//! before sending, fault reporting, quick restart, power cycles, block-read fallbacks.

use host_tests::harness::{World, WorldOptions};
use plasma_firmware::io::{Interlock, IoConfig};
use plasma_firmware::link::{
    ActiveFault, CommandOutput, Family, LinkCommand, LinkConfig, LinkEvent, PowermaxProcess,
    Refusal,
};
use plasma_protocol::modbus_ascii;
use plasma_protocol::powermax::{Amps, FaultCode, OperatingMode, Pressure, Psi};
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::powermax::{Powermax, Process, UndocumentedAddresses};
use plasma_sim::sync::Cartridge;
use plasma_sim::{Model, SimulatedUnit};

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn secs(n: u64) -> Duration {
    Duration::from_secs(n)
}

fn amps(a: u16) -> Amps {
    Amps::from_whole(a).unwrap()
}

fn psi(p: u16) -> Psi {
    Psi::from_whole(p).unwrap()
}

/// A world whose link is up with the slow data (limits) read.
fn ready(model: Model, options: WorldOptions) -> World {
    let mut world = World::new(model, options);
    world.wait_link_up(secs(1)).expect("link up");
    world
        .run_until(|w| w.link().status().limits.is_some(), secs(2))
        .expect("limits read");
    world.run_for(ms(500));
    world
}

/// A Modbus ASCII frame for node 1, computed (LRC included) from its PDU.
fn frame(pdu: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 600];
    let n = modbus_ascii::encode(1, pdu, &mut out).unwrap();
    out[..n].to_vec()
}

fn write_single(address: u16, value: u16) -> Vec<u8> {
    let [ah, al] = address.to_be_bytes();
    let [vh, vl] = value.to_be_bytes();
    frame(&[0x06, ah, al, vh, vl])
}

/// Requests since `mark` that write (functions 05, 06, 0F, 10).
fn writes_since(world: &World, mark: usize) -> Vec<Vec<u8>> {
    world
        .trace()
        .since(mark)
        .iter()
        .filter(|f| f.is_request())
        .filter(|f| matches!(f.modbus_function(), Some(0x05 | 0x06 | 0x0F | 0x10)))
        .map(|f| f.bytes.clone())
        .collect()
}

fn apply(mode: OperatingMode, current: u16, pressure: Pressure) -> LinkCommand<'static> {
    LinkCommand::ApplyProcess {
        mode,
        current: amps(current),
        pressure,
    }
}

#[test]
fn cut_at_63_a_with_automatic_pressure_puts_the_manuals_frame_on_the_wire() {
    let mut world = ready(Model::Sync65, WorldOptions::default());
    let mark = world.trace().len();
    let result = world.command(apply(OperatingMode::Cut, 63, Pressure::Auto), secs(2));
    // Read back: 0x3012 shows the pressure the unit chose for "automatic" (the cartridge's
    // automatic set point), which confirms an automatic-pressure request.
    let auto_psi = Psi::from_raw(world.sim::<Powermax>().limits().auto_pressure);
    let read_back = PowermaxProcess {
        mode: Some(OperatingMode::Cut),
        current: amps(63),
        pressure: Pressure::Set(auto_psi),
    };
    assert_eq!(result, Ok(CommandOutput::Process(read_back)));
    let expected = PowermaxProcess {
        pressure: Pressure::Auto,
        ..read_back
    };

    // Exactly the SYNC guide's frame (LRC 0x66 checked: the bytes 01 10 30 80 00 03 06 00 01
    // 0F C0 00 00 sum to 0x19A, and -0x9A = 0x66), once, followed by the read-back.
    let frames = world.trace().since(mark).to_vec();
    let requests: Vec<_> = frames.iter().filter(|f| f.is_request()).collect();
    let writes = writes_since(&world, mark);
    assert_eq!(writes, vec![b":0110308000030600010FC0000066\r\n".to_vec()]);
    let write_at = requests
        .iter()
        .position(|f| f.modbus_function() == Some(0x10))
        .unwrap();
    assert_eq!(
        requests[write_at + 1].bytes,
        frame(&[0x04, 0x30, 0x10, 0x00, 0x03]),
        "read back 0x3010-0x3012"
    );

    // The unit took it: remote mode, 63 A x 64 = 0x0FC0, automatic pressure.
    let sim = world.sim::<Powermax>();
    assert!(sim.in_remote_mode());
    assert_eq!(
        sim.settings(),
        Process {
            mode: 1,
            current: 0x0FC0,
            pressure: 0
        }
    );
    let events: Vec<_> = world.events().iter().map(|(_, e)| *e).collect();
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: true }));
    assert!(events.contains(&LinkEvent::ProcessApplied {
        settings: read_back,
        reapplied: false
    }));
    world.run_for(secs(1));
    let status = world.link().status();
    assert!(status.remote);
    assert_eq!(status.settings, Some(read_back), "polls read it back");
    assert_eq!(
        world.link().kept().powermax(),
        Some(expected),
        "automatic pressure is what is kept"
    );
}

#[test]
fn legacy_settings_are_written_to_the_force_registers_in_order() {
    let mut world = ready(Model::Pm85, WorldOptions::default());
    let mark = world.trace().len();
    let result = world.command(apply(OperatingMode::Cut, 63, Pressure::Auto), secs(2));
    assert!(
        matches!(result, Ok(CommandOutput::Process(_))),
        "{result:?}"
    );
    // Mode, current, a permitted pressure (the guide's "non-zero"), then 0 = automatic.
    let min_psi = world.sim::<Powermax>().limits().pressure.0;
    assert_eq!(
        writes_since(&world, mark),
        vec![
            write_single(0x2093, 1),
            write_single(0x2094, 0x0FC0),
            write_single(0x2096, min_psi),
            write_single(0x2096, 0),
        ]
    );
    let sim = world.sim::<Powermax>();
    assert!(sim.in_remote_mode());
    assert_eq!(
        sim.settings(),
        Process {
            mode: 1,
            current: 0x0FC0,
            pressure: 0
        }
    );
    assert_eq!(sim.active_fault(), 0, "no 0-11-n fault");

    // Leaving remote writes zeros to all three.
    let mark = world.trace().len();
    assert_eq!(
        world.command(LinkCommand::ExitRemote, secs(2)),
        Ok(CommandOutput::Done)
    );
    assert_eq!(
        writes_since(&world, mark),
        vec![
            write_single(0x2093, 0),
            write_single(0x2094, 0),
            write_single(0x2096, 0),
        ]
    );
    assert!(!world.sim::<Powermax>().in_remote_mode());
    assert!(!world.link().status().remote);
    assert_eq!(world.link().kept().powermax(), None);
}

#[test]
fn sync_exit_remote_writes_zeros_in_one_request() {
    let mut world = ready(Model::Sync105, WorldOptions::default());
    world
        .command(
            apply(OperatingMode::Cut, 80, Pressure::Set(psi(70))),
            secs(2),
        )
        .unwrap();
    let mark = world.trace().len();
    assert_eq!(
        world.command(LinkCommand::ExitRemote, secs(2)),
        Ok(CommandOutput::Done)
    );
    assert_eq!(
        writes_since(&world, mark),
        vec![frame(&[
            0x10, 0x30, 0x80, 0x00, 0x03, 0x06, 0, 0, 0, 0, 0, 0
        ])]
    );
    assert!(!world.sim::<Powermax>().in_remote_mode());
}

#[test]
fn settings_outside_the_limits_are_refused_before_anything_is_sent() {
    for model in [Model::Sync65, Model::Sync45, Model::Pm85] {
        let mut world = ready(model, WorldOptions::default());
        let limits = world.sim::<Powermax>().limits();
        let (min, max) = (
            Amps::from_raw(limits.current.0),
            Amps::from_raw(limits.current.1),
        );
        let (pmin, pmax) = (
            Psi::from_raw(limits.pressure.0),
            Psi::from_raw(limits.pressure.1),
        );
        let mark = world.trace().len();
        let too_high = Amps::from_raw(limits.current.1 + 64);
        assert_eq!(
            world.submit(LinkCommand::ApplyProcess {
                mode: OperatingMode::Cut,
                current: too_high,
                pressure: Pressure::Auto
            }),
            Err(Refusal::CurrentOutOfRange {
                requested: too_high,
                min,
                max
            }),
            "{model}"
        );
        let too_low = Amps::from_raw(limits.current.0 - 64);
        assert_eq!(
            world.submit(LinkCommand::ApplyProcess {
                mode: OperatingMode::Cut,
                current: too_low,
                pressure: Pressure::Auto
            }),
            Err(Refusal::CurrentOutOfRange {
                requested: too_low,
                min,
                max
            }),
            "{model}"
        );
        assert_eq!(
            world.submit(LinkCommand::ApplyProcess {
                mode: OperatingMode::Cut,
                current: max,
                pressure: Pressure::Set(psi(95))
            }),
            Err(Refusal::PressureOutOfRange {
                requested: psi(95),
                min: pmin,
                max: pmax
            }),
            "{model}"
        );
        if model == Model::Sync45 {
            // A cut cartridge on a Powermax45 SYNC permits cutting only.
            assert!(
                matches!(
                    world.submit(LinkCommand::ApplyProcess {
                        mode: OperatingMode::Gouge,
                        current: max,
                        pressure: Pressure::Auto
                    }),
                    Err(Refusal::ModeNotPermitted {
                        mode: OperatingMode::Gouge,
                        ..
                    })
                ),
                "{model}"
            );
        }
        world.run_for(secs(1));
        assert_eq!(writes_since(&world, mark), Vec::<Vec<u8>>::new(), "{model}");
        assert!(!world.sim::<Powermax>().in_remote_mode(), "{model}");
        assert_eq!(world.link().kept().powermax(), None, "{model}");
    }
}

#[test]
fn a_fault_raised_while_idle_is_reported_within_250_ms_on_sync() {
    let mut world = ready(Model::Sync85, WorldOptions::default());
    let code = FaultCode(300);
    // A few phases of the poll schedule, including right after a poll went out.
    for delay_us in [0u64, 13_000, 37_500, 61_000, 99_000, 250_000, 777_000] {
        world.run_for(Duration::from_micros(delay_us));
        let injected = world.now();
        world.inject_fault(code.0);
        let (at, event) = world
            .wait_event(|e| matches!(e, LinkEvent::FaultRaised { .. }), ms(250))
            .expect("fault reported within 250 ms");
        assert_eq!(
            event,
            LinkEvent::FaultRaised {
                code: ActiveFault::Powermax(code),
                action_required: code.info().unwrap().action_required(),
            }
        );
        assert!(at.saturating_since(injected) <= ms(250));
        assert_eq!(
            world.link().status().active_fault,
            Some(ActiveFault::Powermax(code))
        );
        // The discrete FAULT output follows.
        world.run_for(ms(1));
        assert!(world.io().outputs().fault);
        world.clear_fault();
        world
            .wait_event(
                |e| {
                    *e == LinkEvent::FaultCleared {
                        code: ActiveFault::Powermax(code),
                    }
                },
                ms(250),
            )
            .expect("cleared");
        world.run_for(ms(1));
        assert!(!world.io().outputs().fault);
        assert_eq!(world.link().status().active_fault, None);
    }
}

#[test]
fn a_fault_that_requires_action_holds_start_off() {
    let mut world = ready(Model::Sync65, WorldOptions::default());
    world.inject_fault(300);
    world
        .wait_event(|e| matches!(e, LinkEvent::FaultRaised { .. }), ms(250))
        .unwrap();
    world.set_torch(true);
    world.run_for(ms(200));
    assert!(!world.io().outputs().start);
    assert_eq!(
        world.io().start_locked_by(),
        Some(Interlock::FaultRequiresAction)
    );
    assert_eq!(world.sim::<Powermax>().counters().starts, 0, "never fired");
    world.set_torch(false);
}

#[test]
fn quick_restart_clears_0_50_0_then_nothing_is_sent_for_2_s_and_start_stays_off() {
    // Fault interlock off: the blackout alone must hold START.
    let options = WorldOptions {
        io: IoConfig {
            refuse_start_on_fault: false,
            ..IoConfig::default()
        },
        ..WorldOptions::default()
    };
    let mut world = ready(Model::Sync85, options);

    // Refused while 0-50-0 is not active.
    assert_eq!(
        world.submit(LinkCommand::QuickRestart),
        Err(Refusal::QuickRestartNeeds050 { active: None })
    );

    // The cartridge comes off: 0-50-0. A new one goes on; the fault stays until a restart.
    let now = world.now();
    world.sim::<Powermax>().remove_cartridge(now);
    world
        .wait_event(
            |e| {
                *e == LinkEvent::FaultRaised {
                    code: ActiveFault::Powermax(FaultCode(500)),
                    action_required: true,
                }
            },
            ms(250),
        )
        .unwrap();
    let now = world.now();
    world
        .sim::<Powermax>()
        .install_cartridge(now, Cartridge::default_for(Model::Sync85));
    world.run_for(ms(300));
    assert_eq!(world.sim::<Powermax>().active_fault(), 500);

    let mark = world.trace().len();
    assert_eq!(
        world.command(LinkCommand::QuickRestart, secs(1)),
        Ok(CommandOutput::Done)
    );
    let done_at = world.now();
    let restart = world
        .trace()
        .since(mark)
        .iter()
        .find(|f| f.is_request() && f.modbus_function() == Some(0x10))
        .cloned()
        .expect("quick restart on the wire");
    assert_eq!(restart.modbus_address(), Some(0x308E));
    assert_eq!(
        world
            .trace()
            .since(mark)
            .iter()
            .filter(|f| f.is_request() && f.modbus_function() == Some(0x10))
            .count(),
        1,
        "never repeated\n{}",
        world.trace().tail(40)
    );
    let until = world
        .link()
        .status()
        .restart_blackout_until
        .expect("blackout exposed");
    assert!(
        until >= restart.end + secs(2),
        "{until:?} vs {:?}",
        restart.end
    );

    // During the blackout: commands are refused, TORCH_ON does not fire the torch.
    assert_eq!(
        world.submit(LinkCommand::RefreshSlowData),
        Err(Refusal::Blackout { until })
    );
    world.run_for(ms(100));
    world.set_torch(true);
    world.run_for(ms(500));
    assert!(!world.io().outputs().start);
    assert_eq!(
        world.io().start_locked_by(),
        Some(Interlock::RestartBlackout)
    );
    world
        .run_until(|w| w.now() >= until + ms(500), secs(3))
        .unwrap();
    // Still off after the blackout: a refused TORCH_ON latches until released.
    assert!(!world.io().outputs().start);
    assert_eq!(world.sim::<Powermax>().counters().starts, 0);

    // Nothing on the wire for 2 s after the restart request.
    let next = world
        .trace()
        .requests()
        .find(|f| f.start > restart.start)
        .expect("polling resumes");
    assert!(
        next.start >= restart.end + secs(2),
        "next request at {:?}, restart ended at {:?}",
        next.start,
        restart.end
    );
    assert!(next.start >= until);
    assert!(done_at < until);

    // The fault is gone, reported, and a fresh TORCH_ON fires.
    assert_eq!(world.link().status().active_fault, None);
    assert!(world.events().iter().any(|(_, e)| *e
        == LinkEvent::FaultCleared {
            code: ActiveFault::Powermax(FaultCode(500))
        }));
    world.set_torch(false);
    world.run_for(ms(100));
    world.set_torch(true);
    world.run_for(ms(300));
    assert!(world.io().outputs().start);
    assert_eq!(world.sim::<Powermax>().counters().starts, 1);
    world.set_torch(false);
    world.run_for(ms(100));
}

#[test]
fn quick_restart_is_refused_for_other_faults_and_on_legacy_units() {
    let mut world = ready(Model::Sync65, WorldOptions::default());
    world.inject_fault(300);
    world
        .wait_event(|e| matches!(e, LinkEvent::FaultRaised { .. }), ms(250))
        .unwrap();
    assert_eq!(
        world.submit(LinkCommand::QuickRestart),
        Err(Refusal::QuickRestartNeeds050 {
            active: Some(FaultCode(300))
        })
    );
    let mut world = ready(Model::Pm65, WorldOptions::default());
    assert_eq!(
        world.submit(LinkCommand::QuickRestart),
        Err(Refusal::NotSupported {
            family: Family::PowermaxLegacy
        })
    );
    world.run_for(ms(300));
    assert!(
        world
            .trace()
            .requests()
            .all(|f| f.modbus_address() != Some(0x308E))
    );
}

/// Options with `reapply_after_power_cycle` as given.
fn reapply_after_power_cycle(on: bool) -> WorldOptions {
    WorldOptions {
        link: LinkConfig {
            reapply_after_power_cycle: on,
            ..LinkConfig::default()
        },
        ..WorldOptions::default()
    }
}

/// Power off long enough for link-down, then on: the link comes back and sees the unit on its
/// own settings, a power cycle. Re-applied only when configured (SYNC manual
/// (000_dd931256418ae627.txt) line 1189: switching the unit off is how an operator ends remote
/// control).
fn power_cycle(model: Model, pressure: Pressure, expected_sim: Process, reapply: bool) {
    let mut world = ready(model, reapply_after_power_cycle(reapply));
    let desired = PowermaxProcess {
        mode: Some(OperatingMode::Cut),
        current: amps(45),
        pressure,
    };
    world
        .command(apply(OperatingMode::Cut, 45, pressure), secs(2))
        .unwrap();
    world.run_for(secs(1));

    let mark = world.events().len();
    world.power_off();
    let (down_at, _) = world
        .wait_event(|e| matches!(e, LinkEvent::LinkDown { .. }), secs(2))
        .expect("link down");
    assert!(!world.link().status().link_up);
    world.run_for(ms(10));
    assert!(world.io().outputs().fault, "FAULT while the link is down");
    assert!(!world.io().outputs().ready);
    world.run_for(secs(2));
    world.power_on();
    let trace_mark = world.trace().len();
    world
        .wait_event(
            |e| matches!(e, LinkEvent::UnitPowerCycled { .. }),
            // The last known-good framing is asked first and between every two probes of
            // the search (see a_unit_switched_off_and_on_is_found_again_within_a_second).
            secs(3),
        )
        .unwrap_or_else(|t| panic!("{model}: not seen: {t}\n{}", world.trace().tail(30)));
    if reapply {
        world
            .wait_event(
                |e| {
                    matches!(
                        e,
                        LinkEvent::ProcessApplied {
                            reapplied: true,
                            ..
                        }
                    )
                },
                secs(3),
            )
            .unwrap_or_else(|t| panic!("{model}: not re-applied: {t}"));
    }
    world.run_for(secs(1));

    let events: Vec<LinkEvent> = world.events()[mark..].iter().map(|(_, e)| *e).collect();
    let kinds: Vec<&str> = events
        .iter()
        .filter_map(|e| match e {
            LinkEvent::LinkDown { .. } => Some("down"),
            LinkEvent::LinkUp { .. } => Some("up"),
            LinkEvent::UnitPowerCycled { .. } => Some("power cycled"),
            LinkEvent::ProcessApplied { .. } => Some("applied"),
            _ => None,
        })
        .collect();
    let expected = if reapply {
        vec!["down", "up", "power cycled", "applied"]
    } else {
        vec!["down", "up", "power cycled"]
    };
    assert_eq!(kinds, expected, "{model}");
    assert!(events.contains(&LinkEvent::UnitPowerCycled { reapply }));
    let status = world.link().status();
    assert!(status.link_up, "{model}");
    let sim = world.sim::<Powermax>();
    if reapply {
        assert!(sim.in_remote_mode(), "{model}");
        assert_eq!(sim.settings(), expected_sim, "{model}");
        assert!(!writes_since(&world, trace_mark).is_empty());
        assert!(world.link().status().remote, "{model}");
        assert_eq!(world.link().kept().powermax(), Some(desired), "{model}");
    } else {
        assert!(!sim.in_remote_mode(), "{model}");
        assert!(writes_since(&world, trace_mark).is_empty(), "{model}");
        assert!(!world.link().status().remote, "{model}");
        assert_eq!(world.link().kept().powermax(), None, "{model}");
    }
    assert!(down_at > Instant::ZERO);
}

const SYNC_45_A_70_PSI: Process = Process {
    mode: 1,
    current: 45 * 64,
    pressure: 70 * 128,
};

const LEGACY_45_A_AUTO: Process = Process {
    mode: 1,
    current: 45 * 64,
    pressure: 0,
};

#[test]
fn after_a_power_cycle_a_sync_unit_stays_in_local_control() {
    power_cycle(
        Model::Sync65,
        Pressure::Set(psi(70)),
        SYNC_45_A_70_PSI,
        false,
    );
}

#[test]
fn after_a_power_cycle_sync_settings_are_reapplied_when_configured() {
    power_cycle(
        Model::Sync65,
        Pressure::Set(psi(70)),
        SYNC_45_A_70_PSI,
        true,
    );
}

#[test]
fn after_a_power_cycle_a_legacy_unit_stays_in_local_control() {
    power_cycle(Model::Pm85, Pressure::Auto, LEGACY_45_A_AUTO, false);
}

#[test]
fn after_a_power_cycle_legacy_settings_are_reapplied_when_configured() {
    power_cycle(Model::Pm85, Pressure::Auto, LEGACY_45_A_AUTO, true);
}

#[test]
fn a_power_blip_shorter_than_link_down_is_noticed_as_a_power_cycle() {
    for reapply in [false, true] {
        let mut world = ready(Model::Sync105, reapply_after_power_cycle(reapply));
        world
            .command(apply(OperatingMode::Cut, 90, Pressure::Auto), secs(2))
            .unwrap();
        world.run_for(ms(300));
        let mark = world.events().len();
        world.power_off();
        world.run_for(ms(150));
        world.power_on();
        world
            .wait_event(|e| *e == LinkEvent::UnitPowerCycled { reapply }, secs(2))
            .expect("noticed");
        world.run_for(secs(2));
        let events: Vec<LinkEvent> = world.events()[mark..].iter().map(|(_, e)| *e).collect();
        assert!(
            !events
                .iter()
                .any(|e| matches!(e, LinkEvent::LinkDown { .. })),
            "{events:?}"
        );
        assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: false }));
        let reapplied = events.iter().any(|e| {
            matches!(
                e,
                LinkEvent::ProcessApplied {
                    reapplied: true,
                    ..
                }
            )
        });
        assert_eq!(reapplied, reapply, "{events:?}");
        let sim = world.sim::<Powermax>();
        assert_eq!(sim.in_remote_mode(), reapply);
        if reapply {
            assert_eq!(sim.settings().current, 90 * 64);
        }
    }
}

#[test]
fn sync_block_read_over_undocumented_registers_falls_back_and_remembers() {
    let mut world = World::new(Model::Sync65, WorldOptions::default());
    world.sim::<Powermax>().config_mut().undocumented = UndocumentedAddresses::Refuse;
    world.wait_link_up(secs(1)).unwrap();
    world.run_for(secs(5));
    let block = frame(&[0x04, 0x30, 0x10, 0x00, 0x0B]);
    let settings = frame(&[0x04, 0x30, 0x10, 0x00, 0x03]);
    let outputs = frame(&[0x04, 0x30, 0x18, 0x00, 0x03]);
    let trace = world.trace();
    assert_eq!(trace.count_requests(&block), 1, "tried once");
    let polls = trace.count_requests(&settings);
    assert!(polls >= 40, "{polls}");
    // In pairs (the window may end between the two reads of the last cycle); between
    // cycles the fault register alone (0x301A).
    let outputs = trace.count_requests(&outputs);
    assert!(polls - outputs <= 1, "{polls} {outputs}");
    let fault = frame(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    assert!(trace.count_requests(&fault) >= 40);
    assert!(
        world.link().diagnostics().exceptions[1] >= 1,
        "exception 02 seen"
    );
    // The values are right all the same.
    world.inject_fault(300);
    world
        .wait_event(|e| matches!(e, LinkEvent::FaultRaised { .. }), ms(250))
        .expect("fault seen through the split poll");
    let status = world.link().status();
    let sim = world.sim_ref::<Powermax>();
    assert_eq!(
        status.settings.map(|s| s.current.raw()),
        Some(sim.settings().current)
    );
    // The cartridge block (gap 0x303D-0x303F) fell back too and was still read.
    assert!(status.cartridge.is_some());
}

#[test]
fn legacy_block_read_accepted_is_one_request_per_cycle() {
    let mut world = World::new(Model::Pm105, WorldOptions::default());
    world.wait_link_up(secs(1)).unwrap();
    let from = world.now();
    world.run_for(secs(3));
    let full = frame(&[0x04, 0x20, 0x93, 0x00, 0x0D]);
    let fault = frame(&[0x04, 0x20, 0x98, 0x00, 0x01]);
    let requests: Vec<_> = world.trace().requests_between(from, world.now()).collect();
    let polls = requests.iter().filter(|f| f.bytes == full).count();
    assert!(polls >= 29, "{polls}");
    // Between two polls, the fault register alone.
    let checks = requests.iter().filter(|f| f.bytes == fault).count();
    assert!(checks.abs_diff(polls) <= 1, "{polls} {checks}");
    // The torch-lead coils, slow data, once after link-up (the refresh is 30 s away).
    let lead = frame(&[0x01, 0x08, 0x08, 0x00, 0x02]);
    let leads = requests.iter().filter(|f| f.bytes == lead).count();
    assert!(leads <= 1, "{leads}");
    assert_eq!(
        polls + checks + leads,
        requests.len(),
        "only the block, the fault and the torch lead"
    );
    assert_eq!(world.link().diagnostics().exceptions[1], 0);
    let limits = world.link().status().limits.unwrap();
    assert_eq!(limits.max_current, amps(105));
}

#[test]
fn legacy_block_read_refused_falls_back_to_the_documented_parts_and_remembers() {
    let mut world = World::new(Model::Pm105, WorldOptions::default());
    world.sim::<Powermax>().config_mut().undocumented = UndocumentedAddresses::Refuse;
    world.wait_link_up(secs(1)).unwrap();
    world.run_for(secs(3));
    let full = frame(&[0x04, 0x20, 0x93, 0x00, 0x0D]);
    let parts = [
        frame(&[0x04, 0x20, 0x93, 0x00, 0x02]),
        frame(&[0x04, 0x20, 0x96, 0x00, 0x01]),
        frame(&[0x04, 0x20, 0x98, 0x00, 0x03]),
        frame(&[0x04, 0x20, 0x9C, 0x00, 0x04]),
    ];
    let trace = world.trace();
    assert_eq!(trace.count_requests(&full), 1, "the block is tried once");
    let cycles = trace.count_requests(&parts[0]);
    assert!(cycles >= 25, "{cycles}");
    // Every part in every cycle (the last cycle may be cut off by the end of the run).
    for part in &parts {
        let count = trace.count_requests(part);
        assert!(
            count <= cycles && count + 1 >= cycles,
            "{count} of {cycles}"
        );
    }
    // Besides, the fault register alone (a cycle of four parts takes 100 ms: the fault is
    // read again between two of its reads in the cycle).
    let fault = frame(&[0x04, 0x20, 0x98, 0x00, 0x01]);
    // The torch-lead coils, slow data, once after link-up (the refresh is 30 s away).
    let lead = frame(&[0x01, 0x08, 0x08, 0x00, 0x02]);
    assert_eq!(trace.count_requests(&lead), 1);
    let others = trace
        .requests()
        .filter(|f| {
            f.bytes != full && f.bytes != fault && f.bytes != lead && !parts.contains(&f.bytes)
        })
        .count();
    assert_eq!(others, 1, "only the detection request besides");
    let limits = world.link().status().limits.unwrap();
    assert_eq!(limits.max_current, amps(105));
    // Settings still work and are confirmed through the parts.
    let result = world.command(apply(OperatingMode::Cut, 100, Pressure::Auto), secs(2));
    assert!(
        matches!(result, Ok(CommandOutput::Process(_))),
        "{result:?}"
    );
    world.run_for(ms(500));
    assert_eq!(
        world.link().status().settings.map(|s| s.current),
        Some(amps(100))
    );
}

/// Time from power-on to link-up for a unit switched off for `off`.
fn reconnect_time(model: Model, off: Duration) -> Duration {
    let mut world = ready(model, WorldOptions::default());
    world.power_off();
    world.run_for(off);
    let on = world.now();
    world.power_on();
    let up = world
        .run_until(|w| w.link().status().link_up, secs(30))
        .expect("link returns");
    up.saturating_since(on)
}

#[test]
fn a_unit_switched_off_and_on_is_found_again_within_a_second() {
    for model in [Model::Sync65, Model::Pm85] {
        for off_ms in [1_500u64, 2_000, 3_000, 4_000, 6_000, 8_000, 10_000] {
            let back = reconnect_time(model, ms(off_ms));
            assert!(
                back <= secs(1),
                "{model} off {off_ms} ms: back {} ms after power-on",
                back.as_millis()
            );
        }
    }
}

#[test]
fn continuous_polling_does_not_starve_slow_data_and_the_cartridge_check() {
    let link = plasma_firmware::link::LinkConfig {
        poll_interval: plasma_firmware::link::LinkConfig::MIN_POLL_INTERVAL,
        ..plasma_firmware::link::LinkConfig::default()
    };
    let mut world = World::new(Model::Sync85, WorldOptions::with_link(link));
    world.wait_link_up(secs(1)).expect("link up");
    world
        .run_until(|w| w.link().status().limits.is_some(), secs(2))
        .expect("limits read at start");
    assert_eq!(
        world.command(LinkCommand::RefreshSlowData, secs(3)),
        Ok(CommandOutput::Done)
    );
    let now = world.now();
    let mut other = Cartridge::default_for(Model::Sync85);
    other.uid = *b"E00401D0FFFFFFFF";
    world.sim::<Powermax>().install_cartridge(now, other);
    world
        .wait_event(|e| matches!(e, LinkEvent::CartridgeChanged { .. }), secs(3))
        .expect("cartridge change noticed");
}

#[test]
fn a_cartridge_change_is_noticed_with_the_default_schedule() {
    let mut world = ready(Model::Sync85, WorldOptions::default());
    let now = world.now();
    let mut other = Cartridge::default_for(Model::Sync85);
    other.uid = *b"E00401D0FFFFFFFF";
    world.sim::<Powermax>().install_cartridge(now, other);
    let (_, event) = world
        .wait_event(|e| matches!(e, LinkEvent::CartridgeChanged { .. }), secs(3))
        .expect("cartridge change noticed");
    assert_eq!(
        event,
        LinkEvent::CartridgeChanged {
            uid: *b"E00401D0FFFFFFFF"
        }
    );
    assert_eq!(
        world.link().status().cartridge.map(|c| c.uid.0),
        Some(*b"E00401D0FFFFFFFF")
    );
}
