//! Several units on one simulated line: who answers, and what two answering units sound like.

use super::*;
use crate::hpr::{Hpr, HprConfig};
use crate::line::{Line, RxByte, Wiring};
use crate::powermax::{Powermax, PowermaxConfig};
use crate::tests::over_the_line;
use crate::{hpr_wire, modbus_wire};

fn ms(t: u64) -> Instant {
    Instant::from_millis(t)
}

fn text(heard: &[RxByte]) -> String {
    String::from_utf8_lossy(&heard.iter().map(|b| b.byte).collect::<Vec<_>>()).into_owned()
}

/// A line of units and the master's line to it.
struct Bench {
    drop: MultiDrop,
    line: Line,
    at: u64,
}

impl Bench {
    fn new(units: Vec<Box<dyn SimulatedUnit>>) -> Bench {
        let drop = MultiDrop::new(units).unwrap();
        let line = Line::new(drop.port(), drop.port(), Wiring::FourWire, 9);
        Bench { drop, line, at: 0 }
    }

    fn of(models: &[Model], options: &SimOptions) -> Bench {
        Bench::new(units_for_one_line(models, options).unwrap())
    }

    /// Sends `request` 100 ms after the last one; what the master heard within 100 ms.
    fn ask(&mut self, request: &[u8]) -> String {
        self.at += 100;
        text(&over_the_line(
            &mut self.drop,
            &mut self.line,
            ms(self.at),
            request,
            ms(self.at + 100),
        ))
    }

    fn hpr(&mut self, id: u16, data: &str) -> String {
        self.ask(&hpr_wire::encode(id, data))
    }

    fn hpr_unit(&self, index: usize) -> &Hpr {
        self.drop
            .unit(index)
            .unwrap()
            .as_any()
            .downcast_ref::<Hpr>()
            .unwrap()
    }
}

fn two_hprs() -> Bench {
    Bench::of(&[Model::Hpr260, Model::Hpr400], &SimOptions::default())
}

fn hello(model: &str) -> String {
    String::from_utf8(hpr_wire::encode(0, &format!("HYPERFORMANCE{model}AUTO"))).unwrap()
}

// HPR manual (002_72b43a5685974c77.txt) line 107: only ID 0 powers up with its serial
// interface enabled.
#[test]
fn at_power_up_only_id_0_answers() {
    let mut bench = two_hprs();
    assert_eq!(bench.hpr_unit(0).config().id, 0);
    assert_eq!(bench.hpr_unit(1).config().id, 1);
    assert_eq!(bench.hpr(0, ""), hello("260"));
    // Not even a bad checksum draws an answer from the sleeping unit.
    assert_eq!(bench.ask(b">00091<"), ">50095<");
    assert_eq!(bench.drop.collisions(), 0);
}

// HPR manual lines 109 (SLEEP all, WAKE one, SLEEP before the next) and 172-173 (WAKE echoes,
// SLEEP has no response).
#[test]
fn sleep_then_wake_talks_to_one_unit_at_a_time() {
    let mut bench = two_hprs();
    assert_eq!(bench.hpr(86, ""), "");
    assert_eq!(bench.hpr(0, ""), "", "all asleep");
    assert_eq!(bench.hpr(85, "1"), ">0851CE<");
    assert_eq!(bench.hpr(0, ""), hello("400"));
    assert_eq!(bench.hpr(86, ""), "");
    assert_eq!(bench.hpr(85, "0"), ">0850CD<");
    assert_eq!(bench.hpr(0, ""), hello("260"));
    // A WAKE for an id nobody has: silence.
    assert_eq!(bench.hpr(86, ""), "");
    assert_eq!(bench.hpr(85, "3"), "");
    assert_eq!(bench.drop.collisions(), 0);
    // A power cycle brings the power-up rule back: id 1 asleep, id 0 awake.
    assert_eq!(bench.hpr(85, "1"), ">0851CE<");
    for unit in 0..2 {
        let u = bench.drop.unit_mut(unit).unwrap();
        u.power_off(ms(bench.at + 50));
        u.power_on(ms(bench.at + 60));
    }
    assert_eq!(bench.hpr(0, ""), hello("260"));
}

// HPR manual line 173: SLEEP tells the systems to disconnect their transmitters, so a reply
// still due when it arrives is never sent.
#[test]
fn a_sleep_right_after_a_request_stops_the_reply_still_due() {
    let mut bench = two_hprs();
    for &b in hpr_wire::encode(0, "")
        .iter()
        .chain(&hpr_wire::encode(86, ""))
    {
        bench.drop.receive(ms(10), b);
    }
    assert_eq!(bench.drop.poll_transmit(ms(30)), None);
    assert!(bench.drop.take_transmissions().is_empty());
}

// HPR manual line 109: the SLEEP must be sent before the WAKE of the next system. A master
// that forgets it has two transmitters on the line.
#[test]
fn a_forgotten_sleep_makes_two_units_answer_at_once() {
    let mut bench = two_hprs();
    // Id 0 is awake from power-up; waking id 1 leaves it awake.
    assert_eq!(bench.hpr(85, "1"), ">0851CE<");
    assert!(bench.hpr_unit(0).is_awake() && bench.hpr_unit(1).is_awake());
    let heard = bench.hpr(0, "");
    assert!(
        !heard.contains(&hello("260")) && !heard.contains(&hello("400")),
        "{heard:?}"
    );
    assert!(bench.drop.collisions() > 0);
    let sent = bench.drop.take_transmissions();
    assert!(
        sent.iter()
            .any(|t| t.unit == 0 && t.bytes == hello("260").as_bytes())
    );
    assert!(
        sent.iter()
            .any(|t| t.unit == 1 && t.bytes == hello("400").as_bytes())
    );
    // The SLEEP and WAKE the master should have sent: one unit, a clean line.
    let before = bench.drop.collisions();
    assert_eq!(bench.hpr(86, ""), "");
    assert_eq!(bench.hpr(85, "1"), ">0851CE<");
    assert_eq!(bench.hpr(0, ""), hello("400"));
    assert_eq!(bench.drop.collisions(), before);
}

#[test]
fn colliding_characters_read_as_the_and_of_both_and_a_late_start_is_lost() {
    let mut a = HprConfig::for_model(Model::Hpr260);
    a.id = 0;
    let mut b = a.clone();
    b.id = 1;
    let mut drop = MultiDrop::new(vec![Box::new(Hpr::new(a)), Box::new(Hpr::new(b))]).unwrap();
    let char_ns = drop.port().char_time_ns();
    // Unit 0 starts two characters at 0; unit 1 one half a character later.
    drop.lay(0, 0, b"\x0F\xF0".to_vec());
    assert_eq!(drop.poll_transmit(Instant::ZERO), Some(vec![0x0F]));
    let half = instant_from_ns(char_ns / 2);
    drop.lay(1, ns(half), b"\x3C".to_vec());
    // Unit 1's character starts while unit 0's first is on the wire: lost into it.
    assert_eq!(drop.poll_transmit(half), None);
    // Unit 0's second overlaps it: both drivers, the AND.
    assert_eq!(
        drop.poll_transmit(instant_from_ns(char_ns)),
        Some(vec![0xF0 & 0x3C])
    );
    assert_eq!(drop.collisions(), 2);
    assert_eq!(drop.next_wakeup().map(|t| t > ms(100)), Some(true));
}

#[test]
fn a_late_poll_lays_each_reply_where_it_was_due() {
    let mut bench = two_hprs();
    assert_eq!(bench.hpr(85, "1"), ">0851CE<");
    bench.drop.take_transmissions();
    for &b in &hpr_wire::encode(0, "") {
        bench.drop.receive(ms(1_000), b);
    }
    // Both replies are due within 7 ms; the first poll comes 50 ms late.
    let heard = bench.drop.poll_transmit(ms(1_050)).unwrap();
    let sent = bench.drop.take_transmissions();
    assert_eq!(sent.len(), 2);
    assert!(sent.iter().all(|t| t.at < ms(1_008)), "{sent:?}");
    assert!(bench.drop.collisions() > 0);
    let heard = String::from_utf8_lossy(&heard).into_owned();
    assert!(!heard.contains(&hello("260")) && !heard.contains(&hello("400")));
}

#[test]
fn a_lone_unit_sounds_exactly_as_without_the_multi_drop() {
    let mut bench = Bench::of(&[Model::Hpr260], &SimOptions::default());
    let mut alone = Model::Hpr260.build(&SimOptions::default());
    let mut line = Line::new(alone.port(), alone.port(), Wiring::FourWire, 9);
    let reference = over_the_line(&mut *alone, &mut line, ms(100), b">00090<", ms(200));
    let heard = over_the_line(
        &mut bench.drop,
        &mut bench.line,
        ms(100),
        b">00090<",
        ms(200),
    );
    assert_eq!(heard, reference);
}

#[test]
fn an_awake_unit_among_sleeping_ones_keeps_its_character_timing() {
    let mut alone = Bench::of(&[Model::Hpr260], &SimOptions::default());
    let mut shared = two_hprs();
    let reference = over_the_line(
        &mut alone.drop,
        &mut alone.line,
        ms(100),
        b">00090<",
        ms(200),
    );
    let heard = over_the_line(
        &mut shared.drop,
        &mut shared.line,
        ms(100),
        b">00090<",
        ms(200),
    );
    assert_eq!(text(&heard), text(&reference));
    // Handed over character by character at whole microseconds: at most 1 us later each.
    for (h, r) in heard.iter().zip(&reference) {
        let late = h.at.as_micros() - r.at.as_micros();
        assert!(late <= 1, "{late} us");
    }
}

fn read_request(node: u8) -> Vec<u8> {
    // Read holding register 0x2093 (the legacy map, which SYNC units also answer).
    modbus_wire::encode(node, &[0x03, 0x20, 0x93, 0x00, 0x01])
}

// SYNC manual (000_dd931256418ae627.txt) lines 389-391: with 2 or more Powermax units each has
// its own node address, 1-255, and the CNC uses it.
#[test]
fn powermax_units_answer_their_own_node_only() {
    let options = SimOptions {
        modbus_address: 7,
        ..SimOptions::default()
    };
    let mut bench = Bench::of(&[Model::Sync65, Model::Pm65], &options);
    let node = |bench: &Bench, i: usize| {
        bench
            .drop
            .unit(i)
            .unwrap()
            .as_any()
            .downcast_ref::<Powermax>()
            .unwrap()
            .address()
    };
    assert_eq!((node(&bench, 0), node(&bench, 1)), (Some(7), Some(8)));
    for n in [7u8, 8] {
        let heard = bench.ask(&read_request(n));
        assert!(heard.starts_with(&format!(":{n:02X}03")), "{heard:?}");
    }
    assert_eq!(bench.ask(&read_request(9)), "");
    assert_eq!(bench.drop.collisions(), 0);
    let handled = |bench: &Bench, i: usize| {
        bench
            .drop
            .unit(i)
            .unwrap()
            .as_any()
            .downcast_ref::<Powermax>()
            .unwrap()
            .requests_handled()
    };
    assert_eq!((handled(&bench, 0), handled(&bench, 1)), (1, 1));
}

// SYNC manual lines 385-387: node 0 takes the node address of the first request, "for cutting
// systems with 1 Powermax". Two such units both take it and both answer.
#[test]
fn two_units_learning_their_node_both_take_the_first_one_and_collide() {
    let unit = |latency_ms| {
        let mut config = PowermaxConfig::for_model(Model::Sync65);
        config.latency = Duration::from_millis(latency_ms);
        Box::new(Powermax::new(config)) as Box<dyn SimulatedUnit>
    };
    let mut bench = Bench::new(vec![unit(3), unit(4)]);
    let heard = bench.ask(&read_request(1));
    assert!(bench.drop.collisions() > 0);
    let clean = bench
        .drop
        .take_transmissions()
        .into_iter()
        .map(|t| String::from_utf8(t.bytes).unwrap())
        .collect::<Vec<_>>();
    assert_eq!(clean.len(), 2);
    assert!(
        clean.iter().all(|reply| !heard.contains(reply.as_str())),
        "{heard:?}"
    );
    for i in 0..2 {
        let pm = bench
            .drop
            .unit(i)
            .unwrap()
            .as_any()
            .downcast_ref::<Powermax>()
            .unwrap();
        assert_eq!(pm.address(), Some(1));
    }
}

#[test]
fn units_take_ids_and_nodes_in_order_and_a_set_that_cannot_share_a_line_is_refused() {
    let hprs = [Model::Hpr260, Model::Hpr130, Model::Hpr400, Model::Hpr260Xd];
    let units = units_for_one_line(&hprs, &SimOptions::default()).unwrap();
    let ids: Vec<u8> = units
        .iter()
        .map(|u| u.as_any().downcast_ref::<Hpr>().unwrap().config().id)
        .collect();
    assert_eq!(ids, [0, 1, 2, 3]);
    let err = |models: &[Model], options: SimOptions| units_for_one_line(models, &options).err();
    let default = SimOptions::default();
    assert_eq!(err(&[], default), Some(LineError::NoUnits));
    let five = [Model::Hpr260; 5];
    assert_eq!(err(&five, default), Some(LineError::IdOutOfRange(4)));
    let from_3 = SimOptions {
        hpr_id: 3,
        ..default
    };
    assert_eq!(
        err(&[Model::Hpr260, Model::Hpr260], from_3),
        Some(LineError::IdOutOfRange(4))
    );
    assert_eq!(
        err(&[Model::Sync65, Model::Hpr260], default),
        Some(LineError::MixedProtocols(Model::Sync65, Model::Hpr260))
    );
    // HPR manual lines 172-174: WAKE, SLEEP and BROADCAST are HPR commands only.
    assert_eq!(
        err(&[Model::Hpr260, Model::MaxPro200], default),
        Some(LineError::NoMultiDrop(Model::MaxPro200))
    );
    assert!(err(&[Model::MaxPro200], default).is_none());
    // SYNC manual lines 385-391: node 0 is for a single unit; several need 1-255.
    assert_eq!(
        err(&[Model::Sync65, Model::Pm85], default),
        Some(LineError::LearnedNodeShared)
    );
    assert!(err(&[Model::Sync65], default).is_none());
    let from_255 = SimOptions {
        modbus_address: 255,
        ..default
    };
    assert_eq!(
        err(&[Model::Sync65, Model::Sync65], from_255),
        Some(LineError::NodeOutOfRange(256))
    );
    let hpr = Model::Hpr260.build(&default);
    let pm = Model::Sync65.build(&default);
    assert_eq!(
        MultiDrop::new(vec![hpr, pm]).err(),
        Some(LineError::PortsDiffer(
            plasma_protocol::serial::PortConfig::HPR,
            plasma_protocol::serial::PortConfig::MODBUS_DEFAULT
        ))
    );
    // The messages say what to do.
    assert!(LineError::LearnedNodeShared.to_string().contains("1-255"));
    assert!(
        LineError::NoMultiDrop(Model::MaxPro200)
            .to_string()
            .contains("maxpro200")
    );
}
