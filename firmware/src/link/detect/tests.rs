//! Detection, byte by byte: which probe goes out at which port settings, and what an answer, a
//! damaged reply or silence leads to.

use std::vec::Vec;

use plasma_protocol::hpr::SystemId;
use plasma_protocol::powermax::PowerSupplyModel;
use plasma_protocol::serial::{Parity, PortConfig};
use plasma_protocol::time::{Duration, Instant};

use crate::link::test_support::*;
use crate::link::{Family, LinkConfig, LinkEvent, Model, ProtocolChoice};

#[test]
fn detects_sync_by_device_identification() {
    let mut bench = Bench::new(LinkConfig::default());
    assert_eq!(bench.link.port_config(), PortConfig::MODBUS_DEFAULT);
    let request = bench.next_tx(ms(0)).unwrap();
    // SYNC guide example request (LRC C1 rechecked).
    assert_lrc(b":012B0E0401C1\r\n");
    assert_eq!(request, b":012B0E0401C1\r\n");
    let reply = b":012B0E0481000101010630383133333504\r\n";
    assert_lrc(reply);
    // Any chunking: byte by byte.
    for &b in reply.iter() {
        bench.rx(0, &[b]);
    }
    assert_eq!(
        bench.events().first(),
        Some(&LinkEvent::LinkUp {
            model: Model::Powermax(PowerSupplyModel::Powermax65_85_105Sync),
            family: Family::PowermaxSync,
        })
    );
    // First SYNC poll: 0x3010-0x301A in ONE function-04 request.
    let poll = bench.next_tx(ms(10)).unwrap();
    assert_eq!(poll, mb(&[0x04, 0x30, 0x10, 0x00, 0x0B]));
}

#[test]
fn detects_legacy_by_device_identification() {
    let mut bench = Bench::with_unit(LinkConfig::default(), "pm65");
    bench.run(ms(100));
    assert_eq!(bench.link.status().family, Some(Family::PowermaxLegacy));
    assert_eq!(
        bench.link.status().model,
        Some(Model::Powermax(PowerSupplyModel::Powermax65_85_105))
    );
}

#[test]
fn finds_a_legacy_unit_without_device_identification_by_a_register_read() {
    let mut bench = Bench::new(LinkConfig::default());
    // Three attempts of 2B/0E time out (100 ms each, immediate retries).
    for attempt in 0..3 {
        assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
        assert_eq!(bench.now, ms(100 * attempt));
    }
    // Then the plain legacy fault read (legacy guide sample, LRC 42 rechecked).
    let probe = bench.next_tx(ms(1000)).unwrap();
    assert_lrc(b":01042098000142\r\n");
    assert_eq!(probe, b":01042098000142\r\n");
    assert_eq!(bench.now, ms(300));
    assert_eq!(bench.link.diagnostics().timeouts, 3);
    assert_eq!(bench.link.diagnostics().retries, 2);
    let reply = b":010402006F8A\r\n";
    assert_lrc(reply);
    bench.rx(5, reply);
    assert_eq!(bench.link.status().family, Some(Family::PowermaxLegacy));
    assert_eq!(bench.link.status().model, Some(Model::PowermaxUnidentified));
}

#[test]
fn a_unit_refusing_device_identification_is_probed_with_a_register_read() {
    let mut bench = Bench::new(LinkConfig::default());
    bench.next_tx(ms(0)).unwrap();
    bench.rx(5, &mb(&[0xAB, 0x01]));
    assert_eq!(bench.link.diagnostics().exceptions[0], 1);
    // Not retried: an exception is the unit's answer.
    assert_eq!(bench.next_tx(ms(10)).unwrap(), b":01042098000142\r\n");
}

#[test]
fn finds_hpr_after_modbus_silence_and_switches_to_8n1() {
    let mut bench = Bench::new(LinkConfig::default());
    for _ in 0..6 {
        let frame = bench.next_tx(ms(5000)).unwrap();
        assert_eq!(frame[0], b':');
    }
    let hello = bench.next_tx(ms(5000)).unwrap();
    assert_eq!(hello, b">00090<", "HELLO, no CR/LF");
    assert_eq!(bench.link.port_config(), PortConfig::HPR);
    // The manual's sample prints HYPERPERFORMANCE; its checksum only fits HYPERFORMANCE.
    let reply = hf(0, "HYPERFORMANCE130AUTO");
    assert_eq!(reply, b">000HYPERFORMANCE130AUTO30<");
    bench.rx(5, &reply);
    assert_eq!(bench.link.status().family, Some(Family::Hpr));
    let poll = bench.next_tx(ms(5000)).unwrap();
    assert_eq!(poll, b">079A0<");
    assert!(hpr_checksum_ok(&poll));
}

#[test]
fn detects_maxpro200() {
    let config = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        ..LinkConfig::default()
    };
    let mut bench = Bench::new(config);
    assert_eq!(bench.next_tx(ms(0)).unwrap(), b">00090<");
    let reply = b">000MaxPro20079<";
    assert!(hpr_checksum_ok(reply));
    bench.rx(3, reply);
    assert_eq!(bench.link.status().family, Some(Family::MaxPro200));
    assert_eq!(
        bench.link.status().model,
        Some(Model::Hpr(SystemId::MaxPro200))
    );
}

#[test]
fn multi_drop_id_sleeps_the_line_then_wakes_the_unit() {
    let config = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        hpr_id: 2,
        ..LinkConfig::default()
    };
    let mut bench = Bench::new(config);
    assert_eq!(bench.next_tx(ms(0)).unwrap(), b">0869E<");
    // SLEEP has no reply: WAKE follows after the quiet time.
    assert_eq!(bench.next_tx(ms(100)).unwrap(), hf(85, "2"));
    assert_eq!(bench.now, ms(20));
    bench.rx(2, &hf(85, "2"));
    assert_eq!(bench.next_tx(ms(100)).unwrap(), b">00090<");
}

#[test]
fn auto_detection_tries_other_modbus_framings_in_later_rounds() {
    let mut bench = Bench::new(LinkConfig::default());
    let mut ports = Vec::new();
    while bench.now < ms(8000) {
        if bench.next_tx(ms(8000)).is_some() {
            ports.push(bench.link.port_config());
        } else {
            break;
        }
    }
    assert!(ports.iter().any(|p| p.parity == Parity::Odd));
    assert!(ports.contains(&PortConfig::HPR));
}

#[test]
fn damaged_device_id_replies_are_asked_again_not_taken_for_silence() {
    let mut bench = Bench::new(LinkConfig::default());
    let damaged = b":012B0E0481000101010630383133333505\r\n";
    for _ in 0..3 {
        assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
        bench.rx(20, damaged);
    }
    // Not the legacy probe: device identification again.
    assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
    bench.rx(20, b":012B0E0481000101010630383133333504\r\n");
    assert_eq!(bench.link.status().family, Some(Family::PowermaxSync));
}

#[test]
fn after_a_link_down_the_known_good_probe_alternates_with_the_search() {
    let mut bench = sync_bench();
    bench.unplug(true);
    bench.run(bench.now + Duration::from_millis(1100));
    assert!(!bench.link.status().link_up);
    let device_id = b":012B0E0401C1\r\n".to_vec();
    // Probes (3 attempts each) and their ports for the next 8 s, nobody answering.
    let mut probes: Vec<(Instant, PortConfig, Vec<u8>)> = Vec::new();
    let until = bench.now + Duration::from_secs(8);
    let mut last: Option<(PortConfig, Vec<u8>)> = None;
    let mut repeats = 0;
    while let Some(frame) = bench.next_tx(until) {
        let port = bench.link.port_config();
        let same = last
            .as_ref()
            .is_some_and(|(p, f)| *p == port && *f == frame);
        if same && repeats < 2 {
            repeats += 1;
            continue;
        }
        repeats = 0;
        last = Some((port, frame.clone()));
        probes.push((bench.now, port, frame));
    }
    let good =
        |p: &(Instant, PortConfig, Vec<u8>)| p.1 == PortConfig::MODBUS_DEFAULT && p.2 == device_id;
    assert!(good(&probes[0]), "the known-good probe first");
    // Every other probe is the known-good one; the search goes on in between.
    for pair in probes.chunks(2) {
        assert!(good(&pair[0]), "{:?}", pair[0]);
        if let Some(search) = pair.get(1) {
            assert!(!good(search), "{search:?}");
        }
    }
    // The gap between two known-good probes stays short (here: under 1 s).
    for w in probes
        .iter()
        .filter(|p| good(p))
        .collect::<Vec<_>>()
        .windows(2)
    {
        assert!(w[1].0.saturating_since(w[0].0) < Duration::from_secs(1));
    }
    // The search still covers the legacy probe, HPR and the other framings.
    assert!(probes.iter().any(|p| p.2 == b":01042098000142\r\n"));
    assert!(probes.iter().any(|p| p.1 == PortConfig::HPR));
    assert!(probes.iter().any(|p| p.1.parity == Parity::Odd));
    // Another kind of unit on the line is still found: an HPR answers HELLO.
    while bench.link.port_config() != PortConfig::HPR {
        bench.next_tx(bench.now + Duration::from_secs(5)).unwrap();
    }
    bench.rx(3, &hf(0, "HYPERFORMANCE130AUTO"));
    assert_eq!(bench.link.status().family, Some(Family::Hpr));
}
