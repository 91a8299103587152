//! Scenario tests on HPR / MaxPro200 units: a cut through the HF-ignition burst, the command
//! allow-list as seen by the unit, power cycles.

use host_tests::harness::{World, WorldOptions};
use plasma_firmware::io::Interlock;
use plasma_firmware::link::{CommandOutput, LinkCommand, LinkEvent, RAW_CAPACITY, Refusal};
use plasma_protocol::hpr::{self, Class, GasCode, GasPair, StateCode};
use plasma_protocol::powermax::TorchKind;
use plasma_protocol::time::Duration;
use plasma_sim::hpr::{Hpr, HprConfig};
use plasma_sim::{Model, SimulatedUnit};

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn secs(n: u64) -> Duration {
    Duration::from_secs(n)
}

/// A world whose HPR is past its purge and ready for a start, as the link reports it.
fn ready(model: Model) -> World {
    let mut world = World::new(model, WorldOptions::default());
    world.wait_link_up(secs(2)).expect("link up");
    world
        .run_until(|w| w.link().status().ready, secs(6))
        .expect("unit ready");
    world
}

/// An HPR frame `>IDDdata CK<` with its checksum computed.
fn hpr_frame(id: u16, data: &str) -> heapless::Vec<u8, RAW_CAPACITY> {
    let text = format!(">{id:03}{data}{:02X}<", hpr::checksum(id, data.as_bytes()));
    heapless::Vec::from_slice(text.as_bytes()).unwrap()
}

#[test]
fn hf_ignition_noise_during_a_cut_causes_no_link_down_and_commands_succeed() {
    let mut world = ready(Model::Hpr260);
    {
        // A full 1 s HF burst: the arc transfers only after 1 s of pilot arc.
        let timings = &mut world.sim::<Hpr>().config_mut().timings;
        timings.transfer_delay = Some(secs(1));
        timings.pilot_timeout = secs(2);
    }
    let mark = world.events().len();
    let errors_before = world.link().diagnostics().clone();
    world.set_torch(true);
    assert!(world.io().outputs().start);
    world
        .run_until(|w| w.sim_ref::<Hpr>().state_code() == 5, secs(2))
        .expect("pilot arc");
    let burst_start = world.now();
    // Commands while the HF ignition fires.
    let corner = world
        .submit(LinkCommand::HprSetCornerCurrent { percent: 80 })
        .unwrap();
    world.run_for(ms(200));
    let amps = world
        .submit(LinkCommand::HprSetNominalAmps { amps: 200 })
        .unwrap();
    assert_eq!(
        world.wait_command(corner, secs(5)).unwrap(),
        Ok(CommandOutput::Value(80))
    );
    assert_eq!(
        world.wait_command(amps, secs(5)).unwrap(),
        Ok(CommandOutput::Value(200))
    );
    world
        .run_until(|w| w.io().outputs().arc_ok, secs(3))
        .expect("arc transferred, ARC_OK on");

    // The burst was real: 1 s long, traffic was damaged and retried.
    assert!(
        world
            .noise_bursts()
            .iter()
            .any(|&(at, len)| at == burst_start && len == secs(1)),
        "{:?}",
        world.noise_bursts()
    );
    assert!(world.line().stats().noise > 100);
    let d = world.link().diagnostics();
    let failed_attempts = (d.timeouts + d.bad_checksums + d.malformed + d.mismatches)
        - (errors_before.timeouts
            + errors_before.bad_checksums
            + errors_before.malformed
            + errors_before.mismatches);
    assert!(failed_attempts > 0, "noise hit the traffic: {d:?}");
    assert_eq!(d.link_downs, 0);

    // Cut on, then off; the unit finishes its sequence without an error.
    world.run_for(secs(1));
    world.set_torch(false);
    world
        .run_until(
            |w| w.link().status().hpr.state == Some(StateCode(3)),
            secs(5),
        )
        .expect("back to idle");
    let events: Vec<LinkEvent> = world.events()[mark..].iter().map(|(_, e)| *e).collect();
    assert!(
        !events.iter().any(|e| matches!(
            e,
            LinkEvent::LinkDown { .. } | LinkEvent::FaultRaised { .. }
        )),
        "{events:?}"
    );
    assert!(world.link().status().link_up);
    let hpr = world.sim::<Hpr>();
    assert_eq!(hpr.corner_percent(), 80);
    assert_eq!(hpr.nominal_amps(), 200);
    assert_eq!(hpr.counters().starts, 1);
    assert_eq!(hpr.active_fault(), 0);
}

#[test]
fn the_link_pauses_while_it_sees_the_pilot_arc() {
    let mut world = ready(Model::Hpr400);
    {
        let timings = &mut world.sim::<Hpr>().config_mut().timings;
        // A pilot arc long enough for a poll to see state 5, and (to isolate the pause from
        // the retries) an ignition that makes no noise: with noise, the polls in the burst
        // fail and the link rides through on its retry spacing instead.
        timings.transfer_delay = Some(ms(900));
        timings.pilot_timeout = secs(2);
        timings.hf_max = Duration::ZERO;
    }
    world.set_torch(true);
    let (seen_at, _) = world
        .wait_event(
            |e| {
                matches!(
                    e,
                    LinkEvent::StateChanged {
                        to: StateCode(5),
                        ..
                    }
                )
            },
            secs(2),
        )
        .expect("pilot arc seen");
    world.run_for(secs(2));
    let during: Vec<_> = world
        .trace()
        .requests_between(seen_at + ms(1), seen_at + ms(999))
        .collect();
    assert!(during.is_empty(), "quiet during the HF burst: {during:?}");
    assert_eq!(world.link().diagnostics().link_downs, 0);
    world.set_torch(false);
    world.run_for(secs(3));
}

#[test]
fn factory_only_dangerous_and_line_control_commands_never_reach_the_unit() {
    let mut world = ready(Model::Hpr260);
    // Every id the allow-list refuses, through RAW: refused before anything is sent.
    let mut refused = 0;
    for id in 0..=150u16 {
        if hpr::is_allowed(id) && !matches!(id, 85..=87) {
            continue;
        }
        let data = if id == 85 { "0" } else { "" };
        assert_eq!(
            world.submit(LinkCommand::Raw(&hpr_frame(id, data))),
            Err(Refusal::RawCommandNotAllowed { id }),
            "id {id:03}"
        );
        refused += 1;
    }
    assert!(refused > 40, "{refused}");
    // Typed commands that the state does not allow are refused too.
    assert!(matches!(
        world.submit(LinkCommand::HprSoftwareReset),
        Err(Refusal::StateForbids { .. })
    ));
    // The allowed ones work, RAW included.
    let state = world.command(LinkCommand::Raw(&hpr_frame(2, "")), secs(3));
    assert!(matches!(state, Ok(CommandOutput::Raw { .. })), "{state:?}");
    assert_eq!(world.link().raw_reply(), &hpr_frame(2, "0003")[..]);
    for command in [
        LinkCommand::HprSetNominalAmps { amps: 130 },
        LinkCommand::HprSetCornerCurrent { percent: 70 },
        LinkCommand::HprClearWarnings,
        LinkCommand::HprReadErrorLog,
        LinkCommand::HprReadTimers,
        LinkCommand::HprGasTest {
            cutflow: false,
            on: true,
        },
        LinkCommand::HprGasTest {
            cutflow: false,
            on: false,
        },
        LinkCommand::HprGasTest {
            cutflow: true,
            on: true,
        },
        LinkCommand::HprGasTest {
            cutflow: true,
            on: false,
        },
        LinkCommand::HprSetInletGases(GasPair {
            plasma: GasCode::OXYGEN,
            shield: GasCode::AIR,
        }),
        LinkCommand::RefreshSlowData,
    ] {
        let result = world.command(command, secs(5));
        assert!(result.is_ok(), "{command:?}: {result:?}");
    }
    world.run_for(secs(3));

    // What the unit heard: allowed commands only, never a factory-only or dangerous one.
    let received = world.sim::<Hpr>().commands_received().to_vec();
    assert!(received.len() > 50);
    for id in &received {
        assert!(hpr::is_allowed(*id), "{id:03} reached the unit");
        assert_eq!(hpr::classify(*id), Some(Class::Normal), "{id:03}");
    }
    for dangerous in [71, 84, 101, 102, 119, 120, 121, 123, 124] {
        assert!(!received.contains(&dangerous), "{dangerous:03}");
    }
    assert_eq!(world.sim::<Hpr>().nominal_amps(), 130);
    assert_eq!(world.sim::<Hpr>().corner_percent(), 70);
}

#[test]
fn maxpro200_process_and_refusals() {
    let mut world = ready(Model::MaxPro200);
    assert_eq!(
        world.submit(LinkCommand::HprSetCornerCurrent { percent: 80 }),
        Err(Refusal::NotSupported {
            family: plasma_firmware::link::Family::MaxPro200
        })
    );
    // 137 SET PROCESS (current and gases, air/air): no CNC command sends it, RAW does, in
    // remote mode (which the typed SET AMPS enters).
    let result = world.command(LinkCommand::HprSetNominalAmps { amps: 100 }, secs(3));
    assert!(result.is_ok(), "{result:?}");
    let gases = GasPair {
        plasma: GasCode::AIR,
        shield: GasCode::AIR,
    };
    let data = format!("130 {} {}", gases.plasma.0, gases.shield.0);
    let result = world.command(LinkCommand::Raw(&hpr_frame(137, &data)), secs(3));
    assert!(result.is_ok(), "{result:?}");
    assert_eq!(world.link().raw_reply(), &hpr_frame(137, "1")[..]);
    assert_eq!(world.sim::<Hpr>().nominal_amps(), 130);
    assert!(
        world
            .sim::<Hpr>()
            .commands_received()
            .iter()
            .all(|id| hpr::is_allowed(*id))
    );
}

#[test]
fn an_hpr_error_that_blocks_start_holds_start_off_and_is_reported() {
    let mut world = ready(Model::Hpr130);
    world.inject_fault(44);
    let (at, event) = world
        .wait_event(|e| matches!(e, LinkEvent::FaultRaised { .. }), ms(500))
        .expect("error reported");
    assert!(matches!(
        event,
        LinkEvent::FaultRaised {
            action_required: true,
            ..
        }
    ));
    assert!(at.as_millis() > 0);
    world.set_torch(true);
    world.run_for(ms(300));
    assert!(!world.io().outputs().start);
    assert_eq!(
        world.io().start_locked_by(),
        Some(Interlock::FaultRequiresAction)
    );
    world.set_torch(false);
    assert_eq!(world.sim::<Hpr>().counters().starts, 0);
}

/// Switched off long enough for a link-down and on again: the HPR comes back powering up on
/// its own set point, a power cycle. Its nominal current is set again only when configured.
#[test]
fn hpr_nominal_amps_after_a_power_cycle_only_when_configured() {
    for reapply in [false, true] {
        let link = plasma_firmware::link::LinkConfig {
            reapply_after_power_cycle: reapply,
            ..plasma_firmware::link::LinkConfig::default()
        };
        let mut world = World::new(Model::Hpr260, WorldOptions::with_link(link));
        world.wait_link_up(secs(2)).expect("link up");
        world
            .run_until(|w| w.link().status().ready, secs(6))
            .expect("unit ready");
        assert_eq!(
            world.command(LinkCommand::HprSetNominalAmps { amps: 130 }, secs(3)),
            Ok(CommandOutput::Value(130))
        );
        world.power_off();
        world
            .wait_event(|e| matches!(e, LinkEvent::LinkDown { .. }), secs(6))
            .expect("link down");
        world.power_on();
        world.wait_link_up(secs(20)).expect("link back");
        world
            .wait_event(|e| *e == LinkEvent::UnitPowerCycled { reapply }, secs(5))
            .expect("power cycle seen");
        world.run_for(secs(5));
        let expected = if reapply { 130 } else { 260 };
        assert_eq!(world.sim::<Hpr>().nominal_amps(), expected, "{reapply}");
    }
}

#[test]
fn after_an_hpr_power_blip_settings_still_take_effect() {
    let mut world = ready(Model::Hpr260);
    assert_eq!(
        world.command(LinkCommand::HprSetNominalAmps { amps: 200 }, secs(3)),
        Ok(CommandOutput::Value(200))
    );
    world.power_off();
    world.run_for(ms(300));
    world.power_on();
    world
        .run_until(|w| w.link().status().ready, secs(8))
        .expect("ready again");
    assert_eq!(
        world.link().diagnostics().link_downs,
        0,
        "a blip, not a loss"
    );
    assert_eq!(
        world.command(LinkCommand::HprSetNominalAmps { amps: 130 }, secs(3)),
        Ok(CommandOutput::Value(130))
    );
    assert_eq!(world.sim::<Hpr>().nominal_amps(), 130);
}

#[test]
fn continuous_polling_does_not_starve_hpr_slow_data() {
    let link = plasma_firmware::link::LinkConfig {
        poll_interval: plasma_firmware::link::LinkConfig::MIN_POLL_INTERVAL,
        ..plasma_firmware::link::LinkConfig::default()
    };
    let mut world = World::new(Model::Hpr260, WorldOptions::with_link(link));
    world.wait_link_up(secs(2)).expect("link up");
    world
        .run_until(
            |w| {
                let hpr = &w.link().status().hpr;
                hpr.error_log.is_some() && hpr.timers.is_some()
            },
            secs(2),
        )
        .expect("slow data read at start");
    assert_eq!(
        world.command(LinkCommand::RefreshSlowData, secs(2)),
        Ok(CommandOutput::Done)
    );
    let amps = world.command(LinkCommand::HprSetNominalAmps { amps: 150 }, secs(3));
    assert_eq!(amps, Ok(CommandOutput::Value(150)));
}

/// `SET HPR_PROCESS` on a MaxPro200 is 137 SET PROCESS, "recommended ... for MaxPro200
/// systems" (HPR manual (002_72b43a5685974c77.txt) line 180, the command at line 275): kept
/// and re-applied after the unit comes back, like the current: after its own power cycle only
/// when configured to (`reapply_after_power_cycle`; without it the unit stays local, the
/// manual's way to take it back).
#[test]
fn a_maxpro200_process_is_reapplied_after_a_power_cycle_when_configured() {
    let link = plasma_firmware::link::LinkConfig {
        reapply_after_power_cycle: true,
        ..plasma_firmware::link::LinkConfig::default()
    };
    let mut world = World::new(Model::MaxPro200, WorldOptions::with_link(link));
    world.wait_link_up(secs(2)).expect("link up");
    world
        .run_until(|w| w.link().status().ready, secs(6))
        .expect("unit ready");
    let gases = GasPair {
        plasma: GasCode::OXYGEN,
        shield: GasCode::AIR,
    };
    let process = LinkCommand::MaxProSetProcess { amps: 150, gases };
    assert_eq!(world.command(process, secs(3)), Ok(CommandOutput::Done));
    assert_eq!(world.sim::<Hpr>().nominal_amps(), 150);
    world.power_off();
    world
        .wait_event(|e| matches!(e, LinkEvent::LinkDown { .. }), secs(6))
        .expect("link down");
    world.power_on();
    world.wait_link_up(secs(20)).expect("link back");
    world
        .run_until(|w| w.sim_ref::<Hpr>().nominal_amps() == 150, secs(10))
        .expect("the process is set again");
    assert_eq!(world.sim::<Hpr>().gases(), (1, 5));
    let received = world.sim::<Hpr>().commands_received();
    assert_eq!(received.iter().filter(|&&id| id == 137).count(), 2);
}

/// What a technician asks first, read once after the unit is found where the manual's
/// "System" column names the system: the firmware of every system (001 VERSION, HPR manual
/// (002_72b43a5685974c77.txt) line 140) and a MaxPro200's torch (145 READ TORCH ID, line 290,
/// "MaxPro200" only); an automatic console's inlet gases (098 GET_INLET_GASES, line 187) come
/// with the slow data.
#[test]
fn firmware_torch_and_inlet_gases_are_read_where_the_system_takes_them() {
    let mut config = HprConfig::for_model(Model::MaxPro200);
    config.torch_id = 8; // "8 = 25 Ft hand torch"
    config.version = "B.1 C.3".into();
    let mut world = World::with_unit(Box::new(Hpr::new(config)), WorldOptions::default());
    world.wait_link_up(secs(2)).expect("link up");
    world
        .run_until(
            |w| {
                let hpr = &w.link().status().hpr;
                hpr.torch.is_some() && hpr.firmware.is_some()
            },
            secs(5),
        )
        .expect("torch and firmware read");
    let hpr = world.link().status().hpr;
    assert_eq!(
        hpr.torch.and_then(|t| t.torch()),
        Some((TorchKind::Hand, 25))
    );
    let firmware = hpr.firmware.unwrap();
    assert_eq!(firmware.power_supply.as_str(), "B.1");
    assert_eq!(
        firmware.gas_console.map(|r| r.as_str().to_owned()),
        Some("C.3".into())
    );
    world.run_for(secs(5));
    let received = world.sim::<Hpr>().commands_received();
    let count = |id: u16| received.iter().filter(|&&r| r == id).count();
    assert_eq!((count(1), count(145)), (1, 1));

    let mut world = ready(Model::Hpr260);
    world
        .run_until(
            |w| {
                let hpr = &w.link().status().hpr;
                hpr.inlet_gases.is_some() && hpr.firmware.is_some()
            },
            secs(5),
        )
        .expect("inlet gases and firmware read");
    let received = world.sim::<Hpr>().commands_received();
    assert!(!received.contains(&145), "145 is the MaxPro200's only");
    assert_eq!(received.iter().filter(|&&r| r == 1).count(), 1);
}

/// 095 SET_ALL_PARAMETERS and 078 SET_ALL_GAS_FLOWS (HPR manual (002_72b43a5685974c77.txt)
/// lines 180 and 165, its sample values) only answer "1 = accepted": the link reads them back
/// (099, 097, 098 and 079 on an HPR) before they count, keeps them, and sends them again, in
/// order and read back again, when the unit answers after the cable was pulled.
#[test]
fn hpr_all_parameters_and_gas_flows_are_reapplied_after_a_link_loss() {
    use plasma_protocol::hpr::{GasFlows, HprParameters};
    let mut world = ready(Model::Hpr260);
    let parameters = HprParameters {
        amps: 100,
        corner_percent: 75,
        gases: GasPair {
            plasma: GasCode::OXYGEN,
            shield: GasCode::NITROGEN,
        },
        flows: GasFlows::from_array([55, 45, 35, 25, 0, 0]),
    };
    let flows = GasFlows::from_array([55, 45, 35, 25, 50, 50]);
    assert_eq!(
        world.command(LinkCommand::HprSetAllParameters(parameters), secs(3)),
        Ok(CommandOutput::Done)
    );
    assert_eq!(
        world.command(LinkCommand::HprSetAllGasFlows(flows), secs(3)),
        Ok(CommandOutput::Done)
    );
    assert_eq!(world.sim::<Hpr>().nominal_amps(), 100);
    assert_eq!(world.sim::<Hpr>().gases(), (1, 6));
    let sent = |world: &mut World, id: u16| {
        let received = world.sim::<Hpr>().commands_received();
        received.iter().filter(|&&r| r == id).count()
    };
    assert_eq!((sent(&mut world, 95), sent(&mut world, 78)), (1, 1));
    assert_eq!(sent(&mut world, 99), 2, "each read back with 099");
    world.pull_cable(true);
    world
        .wait_event(|e| matches!(e, LinkEvent::LinkDown { .. }), secs(6))
        .expect("link down");
    world.pull_cable(false);
    world.wait_link_up(secs(20)).expect("link back");
    world
        .run_until(
            |w| {
                let received = w.sim_ref::<Hpr>().commands_received();
                received.iter().filter(|&&r| r == 78).count() == 2
            },
            secs(10),
        )
        .expect("set again");
    world.run_for(secs(1));
    assert_eq!((sent(&mut world, 95), sent(&mut world, 78)), (2, 2));
    assert_eq!(sent(&mut world, 99), 4, "read back again");
    let received = world.sim::<Hpr>().commands_received().to_vec();
    let last_95 = received.iter().rposition(|&id| id == 95);
    let last_78 = received.iter().rposition(|&id| id == 78);
    assert!(last_95 < last_78, "the older setting first");
    assert!(
        !world.events().iter().any(|(_, e)| matches!(
            e,
            LinkEvent::UnitPowerCycled { .. } | LinkEvent::ProcessFailed { .. }
        )),
        "a lost link, re-applied"
    );
    assert_eq!(world.sim::<Hpr>().nominal_amps(), 100);
}

/// The MaxPro200 forms of 095 and 078 (HPR manual (002_72b43a5685974c77.txt) lines 180 and
/// 165), read back from its 079 (line 168), which carries gases, set points and current.
#[test]
fn maxpro200_all_parameters_and_gas_flows_are_read_back_from_its_079() {
    use plasma_protocol::hpr::{MaxProParameters, MaxProPressures};
    let mut world = ready(Model::MaxPro200);
    let parameters = MaxProParameters {
        amps: 150,
        gases: GasPair {
            plasma: GasCode::OXYGEN,
            shield: GasCode::AIR,
        },
        pressures: MaxProPressures {
            plasma: 60,
            shield: 40,
        },
    };
    assert_eq!(
        world.command(LinkCommand::MaxProSetAllParameters(parameters), secs(3)),
        Ok(CommandOutput::Done)
    );
    let pressures = MaxProPressures {
        plasma: 50,
        shield: 58,
    };
    assert_eq!(
        world.command(LinkCommand::MaxProSetAllGasFlows(pressures), secs(3)),
        Ok(CommandOutput::Done)
    );
    assert_eq!(world.sim::<Hpr>().nominal_amps(), 150);
    assert_eq!(world.sim::<Hpr>().gases(), (1, 5));
    let info = world.link().status().hpr.maxpro_info.expect("079 read");
    world
        .run_until(
            |w| {
                w.link()
                    .status()
                    .hpr
                    .maxpro_info
                    .is_some_and(|i| (i.plasma_setpoint, i.shield_setpoint) == (50, 58))
            },
            secs(2),
        )
        .unwrap_or_else(|_| panic!("polled set points {info:?}"));
}
