//! The arbiter against simulated units sharing one line ([`MultiDrop`], which counts two
//! transmitters at once as collisions), byte by byte in virtual time.

use std::vec::Vec;

use plasma_protocol::time::{Duration, Instant};
use plasma_sim::clock::earliest;
use plasma_sim::multidrop::{MultiDrop, units_for_one_line};
use plasma_sim::{Model, SimOptions};

use super::*;
use crate::link::test_support::{hf, ms};
use crate::link::{ConfigError, Family};

const SLEEP: &[u8] = b">0869E<";

fn wake(id: u8) -> Vec<u8> {
    hf(85, &std::format!("{id}"))
}

/// The arbiter on a line of simulated units.
struct LineBench {
    line: SharedLine,
    units: MultiDrop,
    now: Instant,
    /// Every frame the arbiter sent, with the instant it began.
    sent: Vec<(Instant, Vec<u8>)>,
}

impl LineBench {
    fn new(models: &[Model], addresses: &[LineUnit]) -> Self {
        let options = SimOptions {
            modbus_address: 1,
            ..SimOptions::default()
        };
        let units = MultiDrop::new(units_for_one_line(models, &options).unwrap()).unwrap();
        let line = SharedLine::new(LinkConfig::default(), addresses, Instant::ZERO).unwrap();
        LineBench {
            line,
            units,
            now: Instant::ZERO,
            sent: Vec::new(),
        }
    }

    fn hprs(count: u8) -> Self {
        let models: Vec<Model> = (0..count).map(|_| Model::Hpr260).collect();
        let ids: Vec<LineUnit> = (0..count).map(|id| LineUnit::Hpr { id }).collect();
        Self::new(&models, &ids)
    }

    fn run(&mut self, until: Instant) {
        loop {
            let now = self.now;
            self.units.advance(now);
            if let Some(bytes) = self.units.poll_transmit(now) {
                self.line.handle_rx(now, &bytes);
            }
            while let Some(frame) = self.line.poll_transmit(self.now).map(<[u8]>::to_vec) {
                // The master is busy until its last stop bit; the units hear the frame then.
                let end = self.now
                    + Duration::from_micros(
                        frame.len() as u64 * self.units.port().char_time_ns() / 1000,
                    );
                self.sent.push((self.now, frame.clone()));
                self.units.advance(end);
                for &byte in &frame {
                    self.units.receive(end, byte);
                }
                self.now = end;
                self.line.handle_transmitted(end);
            }
            let at = self.line.poll_at();
            if let Some(at) = at {
                assert!(at > self.now, "poll_at {at:?} not after {:?}", self.now);
            }
            match earliest(at, self.units.next_wakeup()) {
                Some(next) if next <= until => self.now = self.now.max(next),
                _ => break,
            }
        }
        self.now = self.now.max(until);
    }

    fn all_up(&self) -> bool {
        (0..self.line.len()).all(|i| self.line.unit(i).unwrap().status().link_up)
    }

    fn fault(&mut self, unit: usize, code: u16) {
        let now = self.now;
        self.units.unit_mut(unit).unwrap().inject_fault(now, code);
    }

    /// Requests (not SLEEP / WAKE) sent since `from`, each with the id awake when it went
    /// out, as the line's own SLEEP / WAKE traffic says.
    fn requests_by_unit(&self, from: Instant) -> Vec<(Instant, u8)> {
        let mut awake = None;
        let mut out = Vec::new();
        for (at, frame) in &self.sent {
            if frame == SLEEP {
                awake = None;
            } else if frame.starts_with(b">085") {
                awake = Some(frame[4] - b'0');
            } else if *at >= from {
                out.push((*at, awake.expect("a request with no unit awake")));
            }
        }
        out
    }
}

#[test]
fn a_sleep_goes_before_the_first_wake() {
    let mut bench = LineBench::hprs(2);
    bench.run(ms(2000));
    assert_eq!(bench.sent[0].1, SLEEP, "id 0 powers up awake");
    assert_eq!(bench.sent[1].1, wake(0));
    assert!(bench.all_up());
    assert_eq!(bench.units.collisions(), 0);
}

#[test]
fn every_wake_follows_a_sleep() {
    let mut bench = LineBench::hprs(4);
    bench.run(ms(5000));
    assert!(bench.all_up(), "{:?}", bench.line);
    // The first WAKE follows the first SLEEP; after a WAKE, another needs a SLEEP first.
    let mut asleep = false;
    for (_, frame) in &bench.sent {
        if frame == SLEEP {
            asleep = true;
        } else if frame.starts_with(b">085") {
            assert!(asleep, "a WAKE with a unit possibly awake");
            asleep = false;
        }
    }
    assert_eq!(bench.units.collisions(), 0);
    for index in 0..4 {
        let status = bench.line.unit(index).unwrap().status();
        assert_eq!(status.family, Some(Family::Hpr));
    }
}

#[test]
fn the_units_take_turns_one_attempt_each() {
    let mut bench = LineBench::hprs(4);
    bench.run(ms(6000));
    assert!(bench.all_up());
    let requests = bench.requests_by_unit(ms(4000));
    // Round robin: while every unit polls continuously, the turns go 0, 1, 2, 3, 0...
    for pair in requests.windows(2) {
        assert_eq!((pair[0].1 + 1) % 4, pair[1].1, "{requests:?}");
    }
    // One switch per turn: as many WAKEs as requests.
    let wakes = bench
        .sent
        .iter()
        .filter(|(at, f)| *at >= ms(4000) && f.starts_with(b">085"))
        .count();
    assert!(
        wakes.abs_diff(requests.len()) <= 1,
        "{wakes} for {}",
        requests.len()
    );
}

#[test]
fn a_unit_alone_keeps_the_line_without_switching() {
    let mut bench = LineBench::hprs(1);
    bench.run(ms(5000));
    assert!(bench.all_up());
    let stats = bench.line.stats();
    assert_eq!((stats.sleeps, stats.wakes), (1, 1), "{stats:?}");
    assert!(bench.requests_by_unit(ms(1000)).len() > 20);
}

#[test]
fn a_unit_with_work_while_the_others_have_none_keeps_the_line() {
    // Unit 1 is not there: between its probes (detection pauses, retry gaps) unit 0 polls on
    // without a hand-over.
    let mut bench = LineBench::hprs(2);
    bench.units.set_connected(1, false);
    bench.run(ms(6000));
    let requests = bench.requests_by_unit(ms(3000));
    let mut run = 0;
    let mut longest = 0;
    let mut last_wake_count = 0;
    for (at, _) in &requests {
        let wakes = bench
            .sent
            .iter()
            .filter(|(t, f)| t <= at && f.starts_with(b">085"))
            .count();
        run = if wakes == last_wake_count { run + 1 } else { 1 };
        last_wake_count = wakes;
        longest = longest.max(run);
    }
    assert!(longest >= 3, "{requests:?}");
    assert_eq!(bench.units.collisions(), 0);
}

#[test]
fn a_unit_that_comes_later_is_detected_without_a_collision() {
    // Unit 1's detection sends its own SLEEP and WAKE: with unit 0 awake, a SLEEP goes first.
    let mut bench = LineBench::hprs(2);
    bench.units.set_connected(1, false);
    bench.run(ms(3000));
    assert!(bench.line.unit(0).unwrap().status().link_up);
    assert!(!bench.line.unit(1).unwrap().status().link_up);
    bench.units.set_connected(1, true);
    bench.run(ms(8000));
    assert!(bench.all_up());
    assert_eq!(bench.units.collisions(), 0);
}

#[test]
fn a_reply_reaches_the_unit_that_asked() {
    let mut bench = LineBench::hprs(3);
    bench.run(ms(4000));
    assert!(bench.all_up());
    bench.fault(1, 44);
    bench.run(ms(5000));
    let fault = |i: usize| bench.line.unit(i).unwrap().status().active_fault;
    assert!(fault(1).is_some(), "unit 1's fault seen");
    assert_eq!((fault(0), fault(2)), (None, None));
}

#[test]
fn a_silent_unit_costs_the_others_one_time_out_per_round() {
    let mut bench = LineBench::hprs(3);
    bench.units.set_connected(1, false);
    bench.run(ms(4000));
    assert!(bench.line.unit(0).unwrap().status().link_up);
    assert!(bench.line.unit(2).unwrap().status().link_up);
    let from = ms(4000);
    bench.run(ms(14000));
    let timeout = LinkConfig::default().response_timeout;
    // Between two polls of unit 0: unit 2's turn (a switch and its poll, under 100 ms),
    // and at most one WAKE of unit 1 nobody echoes (a switch and one time-out).
    let polls: Vec<Instant> = bench
        .requests_by_unit(from)
        .into_iter()
        .filter(|&(_, id)| id == 0)
        .map(|(at, _)| at)
        .collect();
    let longest = polls
        .windows(2)
        .map(|w| w[1].saturating_since(w[0]))
        .max()
        .unwrap();
    assert!(
        longest <= Duration::from_millis(2 * 100) + timeout + Duration::from_millis(100),
        "{longest:?}"
    );
    for index in [0, 2] {
        let link = bench.line.unit(index).unwrap();
        assert!(link.status().link_up);
        assert_eq!(link.diagnostics().link_downs, 0, "unit {index}");
    }
    assert!(!bench.line.unit(1).unwrap().status().link_up);
    assert!(bench.line.stats().unanswered_wakes > 0);
    assert_eq!(bench.units.collisions(), 0);
}

#[test]
fn powermax_units_share_by_node_address_without_switching() {
    let mut bench = LineBench::new(
        &[Model::Sync65, Model::Sync65],
        &[
            LineUnit::Powermax { node: 1 },
            LineUnit::Powermax { node: 2 },
        ],
    );
    bench.run(ms(3000));
    assert!(bench.all_up());
    assert_eq!(bench.line.stats(), LineStats::default());
    bench.fault(0, 300);
    bench.run(ms(4000));
    assert!(bench.line.unit(0).unwrap().status().active_fault.is_some());
    assert!(bench.line.unit(1).unwrap().status().active_fault.is_none());
    assert_eq!(bench.units.collisions(), 0);
}

#[test]
fn units_that_cannot_share_a_line_are_refused() {
    let base = LinkConfig::default();
    let new = |units: &[LineUnit]| SharedLine::new(base, units, Instant::ZERO).map(|_| ());
    let hpr = |id| LineUnit::Hpr { id };
    let pm = |node| LineUnit::Powermax { node };
    assert_eq!(new(&[]), Err(LineError::NoUnits));
    assert_eq!(
        new(&[hpr(0), hpr(1), hpr(2), hpr(3), hpr(0)]),
        Err(LineError::TooManyUnits { count: 5 })
    );
    assert_eq!(
        new(&[hpr(0), pm(1)]),
        Err(LineError::MixedProtocols { unit: 1 })
    );
    assert_eq!(
        new(&[pm(1), LineUnit::MaxPro200]),
        Err(LineError::MixedProtocols { unit: 1 })
    );
    assert_eq!(
        new(&[hpr(0), LineUnit::MaxPro200]),
        Err(LineError::NoMultiDrop)
    );
    assert_eq!(
        new(&[hpr(1), hpr(2), hpr(1)]),
        Err(LineError::SameAddress {
            first: 0,
            second: 2
        })
    );
    assert_eq!(
        new(&[hpr(0), hpr(4)]),
        Err(LineError::Link {
            unit: 1,
            error: ConfigError::HprIdOutOfRange { id: 4 }
        })
    );
    assert_eq!(
        new(&[pm(0), pm(1)]),
        Err(LineError::Link {
            unit: 0,
            error: ConfigError::NodeAddressZero
        })
    );
    assert_eq!(new(&[LineUnit::MaxPro200]), Ok(()));
    assert_eq!(new(&[pm(1), pm(2), pm(3), pm(4)]), Ok(()));
}

/// Each unit's polls since `from` (GET_PS_INFO or CURRENT_ERROR), by the id awake.
fn polls_by_unit(bench: &LineBench, units: usize, from: Instant) -> Vec<Vec<u16>> {
    let mut awake = None;
    let mut polls = std::vec![Vec::new(); units];
    for (at, frame) in &bench.sent {
        let id = core::str::from_utf8(&frame[1..4])
            .ok()
            .and_then(|s| s.parse::<u16>().ok());
        match id {
            Some(86) => awake = None,
            Some(85) => awake = Some(usize::from(frame[4] - b'0')),
            Some(id @ (3 | 79)) if *at >= from => polls[awake.unwrap()].push(id),
            _ => {}
        }
    }
    polls
}

#[test]
fn on_a_shared_line_a_polls_turn_is_the_short_fault_read_and_every_nth_the_full_status() {
    let mut bench = LineBench::hprs(4);
    bench.run(ms(8000));
    assert!(bench.all_up());
    let every = usize::from(crate::link::hpr::SHARED_LINE_FULL_POLL_EVERY);
    for (unit, polls) in polls_by_unit(&bench, 4, ms(3000)).iter().enumerate() {
        let full: Vec<usize> = (0..polls.len()).filter(|&i| polls[i] == 79).collect();
        assert!(full.len() >= 2, "unit {unit}: {polls:?}");
        for pair in full.windows(2) {
            // Between two full polls, at least N - 1 short ones (003 CURRENT_ERROR); more
            // only while another unit's full poll holds this one back.
            let gap = pair[1] - pair[0];
            assert!(gap >= every && gap < 2 * every, "unit {unit}: {polls:?}");
        }
    }
    // At most one full poll per round (one long attempt): every other unit has a turn
    // between two of them.
    let turns: Vec<u8> = bench
        .sent
        .iter()
        .filter(|(at, f)| *at >= ms(3000) && (f.starts_with(b">003") || f.starts_with(b">079")))
        .map(|(_, f)| f[3])
        .collect();
    let full: Vec<usize> = (0..turns.len()).filter(|&i| turns[i] == b'9').collect();
    for pair in full.windows(2) {
        assert!(pair[1] - pair[0] >= 4, "{turns:?}");
    }
    // A fault still reaches its unit, by the short read.
    bench.fault(2, 44);
    bench.run(ms(8300));
    assert!(bench.line.unit(2).unwrap().status().active_fault.is_some());
}

/// Each unit's fault reads (GET_PS_INFO or CURRENT_ERROR) from its first: when they went
/// out, by the id awake.
fn fault_reads_at(bench: &LineBench, units: usize) -> Vec<Vec<Instant>> {
    let mut awake = None;
    let mut reads = std::vec![Vec::new(); units];
    for (at, frame) in &bench.sent {
        match &frame[..4] {
            b">086" => awake = None,
            b">085" => awake = Some(usize::from(frame[4] - b'0')),
            b">003" | b">079" => reads[awake.unwrap()].push(*at),
            _ => {}
        }
    }
    reads
}

/// The worst gap between two fault reads of one unit: see the module docs' bound.
#[test]
fn on_a_line_of_four_hprs_a_units_fault_reads_are_never_more_than_a_bounded_round_apart() {
    let mut bench = LineBench::hprs(4);
    // Detection, the first slow data (version, error log, timers, gases of every unit), the
    // steady state and the first refresh (30 s).
    bench.run(ms(34_000));
    assert!(bench.all_up());
    // HPR manual (002_72b43a5685974c77.txt): SLEEP `>0869E<` 7 characters, WAKE and its echo
    // 8 each, 003 CURRENT_ERROR 7 out and 11 back, 079 GET_PS_INFO 7 out and up to 90 back;
    // a simulated unit answers within 7 ms.
    let char_time_ns = bench.units.port().char_time_ns();
    let answer_us = 7_000;
    let attempt_us = |chars: u64| chars * char_time_ns / 1000 + answer_us;
    let (switch, fault_read, long_read) = (
        attempt_us(7 + 8 + 8),
        attempt_us(7 + 11),
        attempt_us(7 + 90),
    );
    let bound = Duration::from_micros(4 * (switch + fault_read) + long_read);
    for (unit, reads) in fault_reads_at(&bench, 4).iter().enumerate() {
        assert!(
            reads.len() > 100,
            "unit {unit}: {} fault reads",
            reads.len()
        );
        let (longest, at) = reads
            .windows(2)
            .map(|w| (w[1].saturating_since(w[0]), w[0]))
            .max()
            .unwrap();
        assert!(
            longest <= bound,
            "unit {unit}: {} ms from {at:?}, bound {} ms",
            longest.as_millis(),
            bound.as_millis()
        );
    }
    assert_eq!(bench.units.collisions(), 0);
}

#[test]
fn a_unit_alone_on_its_line_polls_the_full_status_only() {
    let mut bench = LineBench::hprs(1);
    bench.run(ms(4000));
    assert!(bench.all_up());
    let polls = &polls_by_unit(&bench, 1, ms(1000))[0];
    assert!(
        polls.len() > 20 && polls.iter().all(|&id| id == 79),
        "{polls:?}"
    );
}

/// HPR manual (002_72b43a5685974c77.txt, section VIII): while the state is pilot arc "stop
/// serial communications" for the HF-ignition burst, up to 1 s. On a shared line every
/// unit's traffic crosses that noise, so the whole line keeps the quiet; and from START on the
/// unit's state is read at every turn, so the pilot arc is seen when it begins.
#[test]
fn from_start_on_a_units_state_is_read_every_turn_and_its_ignition_quiets_the_whole_line() {
    let mut bench = LineBench::hprs(3);
    bench.run(ms(8000));
    assert!(bench.all_up());
    // Through the gas purge to state 3, ready for start.
    let ready = |b: &LineBench| b.line.unit(1).unwrap().status().hpr.state.map(|s| s.0) == Some(3);
    while !ready(&bench) && bench.now < ms(20_000) {
        let next = bench.now + Duration::from_millis(100);
        bench.run(next);
        bench.now = bench.now.max(next);
    }
    assert!(ready(&bench));
    while bench.line.poll_event().is_some() {}
    // A pilot arc that waits 300 ms for the plate (the simulator's default transfers after
    // 50 ms, shorter than a round of three units' turns).
    let hpr: &mut plasma_sim::hpr::Hpr = bench
        .units
        .unit_mut(1)
        .unwrap()
        .as_any_mut()
        .downcast_mut()
        .unwrap();
    hpr.config_mut().timings.transfer_delay = Some(Duration::from_millis(300));
    let start = bench.now;
    bench.line.set_start(1, true);
    bench.units.unit_mut(1).unwrap().set_start(start, true);
    let mut pilot_arc_seen = None;
    let end = start + Duration::from_secs(8);
    while bench.now < end && pilot_arc_seen.is_none() {
        let step = bench.now + Duration::from_millis(5);
        bench.run(step);
        bench.now = bench.now.max(step);
        while let Some((unit, event)) = bench.line.poll_event() {
            if let (1, LinkEvent::StateChanged { to, .. }) = (unit, event)
                && to.0 == 5
            {
                pilot_arc_seen = Some(bench.now);
            }
        }
    }
    let seen = pilot_arc_seen.expect("unit 2's pilot arc seen");
    // Unit 2's polls after START are all the full status, never the short fault read.
    let polls = &polls_by_unit(&bench, 3, start + Duration::from_millis(150))[1];
    assert!(
        !polls.is_empty() && polls.iter().all(|&id| id == 79),
        "{polls:?}"
    );
    bench.run(seen + Duration::from_millis(1500));
    // Nothing at all went out on the line for a second after the pilot arc was read (the
    // reply came within the 5 ms step that ended at `seen`).
    let read_after = seen - Duration::from_millis(5);
    let quiet: Vec<&(Instant, Vec<u8>)> = bench
        .sent
        .iter()
        .filter(|(at, _)| *at > seen && *at < read_after + Duration::from_millis(1000))
        .collect();
    assert!(
        quiet.is_empty(),
        "sent during the ignition quiet: {quiet:?}"
    );
    assert!(
        bench
            .sent
            .iter()
            .any(|(at, _)| *at >= seen + Duration::from_millis(1000)),
        "the line talks again after the quiet"
    );
    assert_eq!(bench.units.collisions(), 0);
}

#[test]
fn three_sync_units_each_get_their_limits_read() {
    let mut bench = LineBench::new(
        &[Model::Sync65, Model::Sync65, Model::Sync65],
        &[
            LineUnit::Powermax { node: 1 },
            LineUnit::Powermax { node: 2 },
            LineUnit::Powermax { node: 3 },
        ],
    );
    bench.run(ms(10_000));
    assert!(bench.all_up());
    for unit in 0..3 {
        let status = bench.line.unit(unit).unwrap().status();
        assert!(
            status.limits.is_some(),
            "unit {unit}: {:?}",
            bench.line.unit(unit).unwrap().diagnostics()
        );
    }
    assert_eq!(bench.units.collisions(), 0);
}
