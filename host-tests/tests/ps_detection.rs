//! Scenario tests: auto-detection of every simulated unit, pinned protocols, units that do not
//! answer device identification, other Modbus framings, HPR multi-drop.

use host_tests::harness::{World, WorldOptions};
use plasma_firmware::link::{Family, LinkConfig, LinkEvent, Model as LinkModel, ProtocolChoice};
use plasma_protocol::hpr::{GasConsole as IdConsole, HprRating, SystemId};
use plasma_protocol::powermax::PowerSupplyModel;
use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_protocol::time::Duration;
use plasma_sim::hpr::{GasConsole, Hpr};
use plasma_sim::powermax::{DeviceIdSupport, Powermax, PowermaxConfig};
use plasma_sim::{Family as SimFamily, Model, SimOptions};

const SECOND: Duration = Duration::from_secs(1);

fn secs(n: u64) -> Duration {
    Duration::from_secs(n)
}

/// What the link must report for each simulated model (SYNC guide Table 2; HPR HELLO).
fn expected(model: Model) -> (LinkModel, Family) {
    use PowerSupplyModel as P;
    let hpr = |rating, xd, console| {
        (
            LinkModel::Hpr(SystemId::Hpr {
                rating,
                xd,
                console,
            }),
            Family::Hpr,
        )
    };
    match model {
        Model::Sync45 => (LinkModel::Powermax(P::Powermax45Sync), Family::PowermaxSync),
        Model::Sync65 | Model::Sync85 | Model::Sync105 => (
            LinkModel::Powermax(P::Powermax65_85_105Sync),
            Family::PowermaxSync,
        ),
        Model::Pm45Xp => (LinkModel::Powermax(P::Powermax45Xp), Family::PowermaxLegacy),
        Model::Pm65 | Model::Pm85 | Model::Pm105 => (
            LinkModel::Powermax(P::Powermax65_85_105),
            Family::PowermaxLegacy,
        ),
        Model::Pm125 => (LinkModel::Powermax(P::Powermax125), Family::PowermaxLegacy),
        Model::Hpr130 => hpr(HprRating::Hpr130, false, Some(IdConsole::Auto)),
        Model::Hpr260 => hpr(HprRating::Hpr260, false, Some(IdConsole::Auto)),
        Model::Hpr400 => hpr(HprRating::Hpr400, false, Some(IdConsole::Auto)),
        Model::Hpr130Xd => hpr(HprRating::Hpr130, true, None),
        Model::Hpr260Xd => hpr(HprRating::Hpr260, true, None),
        Model::Hpr400Xd => hpr(HprRating::Hpr400, true, None),
        Model::MaxPro200 => (LinkModel::Hpr(SystemId::MaxPro200), Family::MaxPro200),
    }
}

fn link_ups(world: &World) -> Vec<(LinkModel, Family)> {
    world
        .events()
        .iter()
        .filter_map(|(_, e)| match e {
            LinkEvent::LinkUp { model, family } => Some((*model, *family)),
            _ => None,
        })
        .collect()
}

/// Requests that started before `up` (the first poll goes out at the instant of link-up).
fn requests_before(world: &World, up: plasma_protocol::time::Instant) -> usize {
    world.trace().requests().filter(|f| f.start < up).count()
}

fn assert_detected(world: &World, model: Model) {
    let (link_model, family) = expected(model);
    assert_eq!(link_ups(world), vec![(link_model, family)], "{model}");
    let status = world.link().status();
    assert!(status.link_up, "{model}");
    assert_eq!(status.model, Some(link_model), "{model}");
    assert_eq!(status.family, Some(family), "{model}");
}

#[test]
fn every_simulated_model_is_detected_automatically() {
    for model in Model::ALL {
        let mut world = World::new(model, WorldOptions::default());
        let up = world
            .wait_link_up(secs(2))
            .unwrap_or_else(|t| panic!("{model}: {t}\n{}", world.trace().tail(20)));
        assert_detected(&world, model);
        let first = &world.trace().frames()[0];
        assert_eq!(
            first.bytes, b":012B0E0401C1\r\n",
            "{model}: starts with device id"
        );
        assert_eq!(first.port, PortConfig::MODBUS_DEFAULT);
        match model.family() {
            // Powermax units answer the first request: up within one transaction.
            SimFamily::Sync | SimFamily::Legacy => {
                assert!(up.as_millis() < 50, "{model} up at {} ms", up.as_millis());
                assert_eq!(requests_before(&world, up), 1, "{model}");
            }
            // HPR: device id and the legacy probe time out (3 attempts each), then HELLO at
            // 8N1 answers at once.
            SimFamily::Hpr => {
                let requests: Vec<_> = world.trace().requests().filter(|f| f.start < up).collect();
                let hello = requests.last().unwrap();
                assert_eq!(hello.bytes, b">00090<", "{model}");
                assert_eq!(hello.port, PortConfig::HPR, "{model}");
                assert_eq!(requests.len(), 7, "{model}: 3 device id + 3 probe + HELLO");
                assert!(requests[..6].iter().all(|f| f.is_modbus()), "{model}");
                assert!(!hello.bytes.ends_with(b"\r\n"), "no trailing CR LF on HPR");
            }
        }
        // The unit answered and the link is still up a while later (polling works).
        world.run_for(secs(3));
        assert!(world.link().status().link_up, "{model}");
        assert_eq!(world.link().diagnostics().link_downs, 0, "{model}");
        assert_eq!(
            world.stats().stale_wakeups,
            0,
            "{model}: poll_at never in the past"
        );
    }
}

#[test]
fn a_manual_gas_console_hpr_is_told_apart() {
    let options = WorldOptions {
        sim: SimOptions {
            gas_console: GasConsole::Manual,
            ..SimOptions::default()
        },
        ..WorldOptions::default()
    };
    let mut world = World::new(Model::Hpr130, options);
    world.wait_link_up(secs(2)).unwrap();
    assert_eq!(
        world.link().status().model,
        Some(LinkModel::Hpr(SystemId::Hpr {
            rating: HprRating::Hpr130,
            xd: false,
            console: Some(IdConsole::Manual)
        }))
    );
}

#[test]
fn pinned_protocols_skip_the_others() {
    for (model, choice) in [
        (Model::Sync85, ProtocolChoice::Sync),
        (Model::Pm105, ProtocolChoice::Legacy),
        (Model::Hpr400, ProtocolChoice::Hpr),
        (Model::MaxPro200, ProtocolChoice::Hpr),
    ] {
        let link = LinkConfig {
            protocol: choice,
            ..LinkConfig::default()
        };
        let mut world = World::new(model, WorldOptions::with_link(link));
        let up = world.wait_link_up(SECOND).unwrap();
        assert_detected(&world, model);
        world.run_for(secs(2));
        let trace = world.trace();
        match choice {
            ProtocolChoice::Hpr => {
                assert_eq!(requests_before(&world, up), 1, "{model}: HELLO first");
                assert!(trace.requests().all(|f| f.is_hpr()), "{model}: no Modbus");
                assert!(trace.requests().all(|f| f.port == PortConfig::HPR));
            }
            _ => {
                assert!(trace.requests().all(|f| f.is_modbus()), "{model}: no HPR");
                assert!(
                    trace
                        .requests()
                        .all(|f| f.port == PortConfig::MODBUS_DEFAULT)
                );
            }
        }
    }
}

#[test]
fn a_pinned_family_overrides_what_the_unit_claims() {
    // A SYNC unit also answers the old 0x2xxx registers: pinned to legacy, it is run as one.
    let link = LinkConfig {
        protocol: ProtocolChoice::Legacy,
        ..LinkConfig::default()
    };
    let mut world = World::new(Model::Sync65, WorldOptions::with_link(link));
    world.wait_link_up(SECOND).unwrap();
    assert_eq!(
        link_ups(&world),
        vec![(
            LinkModel::Powermax(PowerSupplyModel::Powermax65_85_105Sync),
            Family::PowermaxLegacy
        )]
    );
    world.run_for(SECOND);
    assert!(
        world
            .trace()
            .requests()
            .skip(1)
            .all(|f| f.modbus_address().is_some_and(|a| a < 0x3000)),
        "only 0x2xxx addresses"
    );
}

fn legacy_unit(model: Model, device_id: DeviceIdSupport) -> Box<Powermax> {
    let mut config = PowermaxConfig::for_model(model);
    config.device_id = device_id;
    Box::new(Powermax::new(config))
}

#[test]
fn a_legacy_unit_without_device_identification_is_found_by_a_register_read() {
    // Silent: the three device-id attempts time out, the 0x2098 read answers.
    let mut world = World::with_unit(
        legacy_unit(Model::Pm65, DeviceIdSupport::Silent),
        WorldOptions::default(),
    );
    let up = world.wait_link_up(secs(2)).unwrap();
    assert_eq!(
        link_ups(&world),
        vec![(LinkModel::PowermaxUnidentified, Family::PowermaxLegacy)]
    );
    let requests: Vec<_> = world
        .trace()
        .requests()
        .filter(|f| f.start < up)
        .map(|f| f.bytes.clone())
        .collect();
    assert_eq!(requests.len(), 4);
    assert!(requests[..3].iter().all(|r| r == b":012B0E0401C1\r\n"));
    assert_eq!(
        requests[3], b":01042098000142\r\n",
        "legacy fault register 0x2098"
    );
    assert!((300..350).contains(&up.as_millis()), "{up:?}");

    // Exception 01 (illegal function): the unit is there, the register read tells which.
    let mut world = World::with_unit(
        legacy_unit(Model::Pm125, DeviceIdSupport::IllegalFunction),
        WorldOptions::default(),
    );
    let up = world.wait_link_up(secs(2)).unwrap();
    assert_eq!(
        link_ups(&world),
        vec![(LinkModel::PowermaxUnidentified, Family::PowermaxLegacy)]
    );
    assert_eq!(requests_before(&world, up), 2, "no retry of a refusal");
    assert!(up.as_millis() < 50, "{up:?}");
    // And it is polled like any legacy unit: limits come from the status block.
    world.run_for(SECOND);
    let limits = world.link().status().limits.expect("limits read");
    assert_eq!(limits.max_current.round_whole(), 125);
}

#[test]
fn modbus_units_at_other_parity_and_stop_bits_are_found() {
    for (parity, stop_bits) in [
        (Parity::Odd, StopBits::One),
        (Parity::None, StopBits::One),
        (Parity::Odd, StopBits::Two),
        (Parity::None, StopBits::Two),
    ] {
        let port = PortConfig {
            parity,
            stop_bits,
            ..PortConfig::MODBUS_DEFAULT
        };
        let mut config = PowermaxConfig::for_model(Model::Sync105);
        config.port = port;
        let mut world = World::with_unit(Box::new(Powermax::new(config)), WorldOptions::default());
        world
            .wait_link_up(secs(10))
            .unwrap_or_else(|t| panic!("{port:?}: {t}"));
        assert_detected(&world, Model::Sync105);
        let link_port = world.link().port_config();
        assert_eq!(link_port.parity, parity, "{port:?}");
        // Polling carries on at that framing.
        world.run_for(SECOND);
        assert!(world.link().status().settings.is_some(), "{port:?}");
        assert_eq!(world.link().diagnostics().link_downs, 0);
    }
}

#[test]
fn a_configured_framing_is_tried_first() {
    let port = PortConfig {
        parity: Parity::Odd,
        ..PortConfig::MODBUS_DEFAULT
    };
    let mut config = PowermaxConfig::for_model(Model::Sync45);
    config.port = port;
    let link = LinkConfig {
        modbus_parity: Parity::Odd,
        ..LinkConfig::default()
    };
    let mut world = World::with_unit(
        Box::new(Powermax::new(config)),
        WorldOptions::with_link(link),
    );
    let up = world.wait_link_up(SECOND).unwrap();
    assert!(up.as_millis() < 50);
    assert_eq!(requests_before(&world, up), 1);
}

#[test]
fn hpr_multi_drop_id_2_is_woken_and_answers() {
    let link = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        hpr_id: 2,
        ..LinkConfig::default()
    };
    let options = WorldOptions {
        link,
        sim: SimOptions {
            hpr_id: 2,
            ..SimOptions::default()
        },
        ..WorldOptions::default()
    };
    let mut world = World::new(Model::Hpr260Xd, options);
    let up = world.wait_link_up(SECOND).unwrap();
    assert_detected(&world, Model::Hpr260Xd);
    let ids: Vec<u16> = world
        .trace()
        .requests()
        .filter(|f| f.start < up)
        .filter_map(|f| f.hpr_id())
        .collect();
    assert_eq!(ids, vec![86, 85, 0], "SLEEP, WAKE, HELLO");
    let wake = world.trace().requests().nth(1).unwrap();
    assert_eq!(wake.bytes[..5], *b">0852", "WAKE carries the id");
    assert!(world.sim::<Hpr>().is_awake());
    world.run_for(secs(3));
    assert!(world.link().status().link_up);
    assert!(world.link().status().hpr.ps_info.is_some(), "polled");
}

#[test]
fn hpr_multi_drop_id_2_is_also_found_by_auto_detection() {
    let link = LinkConfig {
        hpr_id: 2,
        ..LinkConfig::default()
    };
    let options = WorldOptions {
        link,
        sim: SimOptions {
            hpr_id: 2,
            ..SimOptions::default()
        },
        ..WorldOptions::default()
    };
    let mut world = World::new(Model::Hpr130, options);
    world.wait_link_up(secs(2)).unwrap();
    assert_detected(&world, Model::Hpr130);
}

#[test]
fn a_sleeping_hpr_is_not_talked_into_answering_by_a_link_without_its_id() {
    let link = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        ..LinkConfig::default()
    };
    let options = WorldOptions {
        link,
        sim: SimOptions {
            hpr_id: 2,
            ..SimOptions::default()
        },
        ..WorldOptions::default()
    };
    let mut world = World::new(Model::Hpr260, options);
    assert!(world.wait_link_up(secs(5)).is_err());
    assert!(
        world.trace().replies().next().is_none(),
        "asleep: no reply at all"
    );
    assert!(world.trace().requests().all(|f| f.hpr_id() == Some(0)));
    assert!(!world.sim::<Hpr>().is_awake());
}
