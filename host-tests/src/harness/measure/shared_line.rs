//! Several HPR260s on one line ([`World::on_one_line`]): each unit's fault-detection latency
//! and fault reads per second, with every unit answering or one silent (its drop cut). The
//! figures show what sharing costs: each unit waits for one attempt of every other unit (and
//! the SLEEP / WAKE that hands the line over), a silent unit one reply time-out per round.
//! The same measurement runs on the bare line and through the whole bridge
//! ([`World::with_bridge_on_line`], with each unit's discrete I/O), so the two can be compared.

use plasma_firmware::bridge::Bridge;
use plasma_firmware::link::{LinkConfig, SharedLine, UnitStatus};
use plasma_firmware::settings::Settings;
use plasma_protocol::hpr::command::id;
use plasma_protocol::time::{Duration, Instant};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::Latencies;
use crate::harness::{BridgeEndpoint, World, WorldEndpoint, WorldOptions};
use plasma_sim::Model;

/// The HPR error injected (as in the single-unit table).
const FAULT: u16 = 44;

/// One line measured.
#[derive(Debug, Clone, PartialEq)]
pub struct SharedLineFigures {
    /// HPR260s on the line.
    pub units: usize,
    /// The unit whose drop is cut, if any.
    pub silent: Option<usize>,
    /// Per unit (the silent one's empty): from its fault appearing to the bridge's status
    /// showing it.
    pub faults: Vec<Latencies>,
    /// Per unit: fault reads (GET_PS_INFO or, on a shared line, mostly the short
    /// CURRENT_ERROR) per second over the window, idle.
    pub cycles_per_s: Vec<f64>,
    /// Hand-overs of the line (WAKEs sent by the bridge) per second over the window.
    pub switches_per_s: f64,
}

/// What drives the measured line: the bare [`SharedLine`] or the whole bridge.
pub trait LineDriver: WorldEndpoint + Sized {
    /// `models` on one line with `options`.
    fn on_line(models: &[Model], options: WorldOptions) -> World<Self>;
    /// Unit `unit`'s status as the driver knows it.
    fn status_of(&self, unit: usize) -> &UnitStatus;
    /// WAKEs the line's arbiter sent so far.
    fn wakes(&self) -> u32;
}

impl LineDriver for SharedLine {
    fn on_line(models: &[Model], options: WorldOptions) -> World<Self> {
        World::on_one_line(models, options).expect("HPRs share a line")
    }
    fn status_of(&self, unit: usize) -> &UnitStatus {
        self.unit(unit).expect("no such unit on the line").status()
    }
    fn wakes(&self) -> u32 {
        self.stats().wakes
    }
}

impl LineDriver for BridgeEndpoint {
    fn on_line(models: &[Model], options: WorldOptions) -> World<Self> {
        let settings = Settings {
            link: options.link,
            ..Settings::default()
        };
        World::with_bridge_on_line(models, options, settings).expect("HPRs share a line")
    }
    fn status_of(&self, unit: usize) -> &UnitStatus {
        Bridge::status_of(self.bridge(), unit)
    }
    fn wakes(&self) -> u32 {
        self.bridge().units().line_stats().wakes
    }
}

/// A line of `units` HPR260s (ids 0, 1...), `silent` cut off, every other unit up and past its
/// purge and first slow data.
fn line<E: LineDriver>(units: usize, silent: Option<usize>, seed: u64) -> World<E> {
    let mut options = WorldOptions::with_link(LinkConfig::default());
    options.seed = seed;
    options.sim.seed = seed;
    let models = vec![Model::Hpr260; units];
    let mut world = E::on_line(&models, options);
    if let Some(silent) = silent {
        world.connect_unit(silent, false);
    }
    let live: Vec<usize> = (0..units).filter(|&u| Some(u) != silent).collect();
    world
        .run_until(
            |w| live.iter().all(|&u| w.endpoint().status_of(u).link_up),
            Duration::from_secs(10),
        )
        .expect("every connected unit detected");
    world.run_for(Duration::from_secs(5));
    world
}

/// Fault reads (GET_PS_INFO or CURRENT_ERROR) per unit from `from`, each counted for the unit the line's SLEEP /
/// WAKE traffic had awake when it went out.
fn polls_per_unit<E: LineDriver>(world: &World<E>, units: usize, from: Instant) -> Vec<usize> {
    let mut counts = vec![0; units];
    let mut awake: Option<usize> = None;
    for frame in world.trace().requests() {
        match frame.hpr_id() {
            Some(id::SLEEP) => awake = None,
            Some(id::WAKE) => {
                awake = frame
                    .bytes
                    .get(4)
                    .map(|&digit| usize::from(digit.wrapping_sub(b'0')));
            }
            Some(id::GET_PS_INFO | id::CURRENT_ERROR) if frame.start >= from => {
                if let Some(count) = awake.and_then(|u| counts.get_mut(u)) {
                    *count += 1;
                }
            }
            _ => {}
        }
    }
    counts
}

/// Measure a line of `units` HPR260s (`silent` cut off) on the bare line: `trials` faults
/// per answering unit, at random phases, and the fault reads over `window` of idle polling.
pub fn shared_line(
    units: usize,
    silent: Option<usize>,
    trials: usize,
    window: Duration,
    seed: u64,
) -> SharedLineFigures {
    measure_line::<SharedLine>(units, silent, trials, window, seed)
}

/// As [`shared_line`], through the whole bridge (`CONFIG units` naming the line's units,
/// each unit's discrete I/O running): the fault counts when the bridge's status shows it.
pub fn bridge_line(
    units: usize,
    silent: Option<usize>,
    trials: usize,
    window: Duration,
    seed: u64,
) -> SharedLineFigures {
    measure_line::<BridgeEndpoint>(units, silent, trials, window, seed)
}

fn measure_line<E: LineDriver>(
    units: usize,
    silent: Option<usize>,
    trials: usize,
    window: Duration,
    seed: u64,
) -> SharedLineFigures {
    let mut world = line::<E>(units, silent, seed);
    let from = world.now();
    let wakes_before = world.endpoint().wakes();
    world.run_for(window);
    let secs = window.as_micros() as f64 / 1e6;
    let cycles_per_s = polls_per_unit(&world, units, from)
        .into_iter()
        .map(|n| n as f64 / secs)
        .collect();
    let switches_per_s = f64::from(world.endpoint().wakes() - wakes_before) / secs;

    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let live: Vec<usize> = (0..units).filter(|&u| Some(u) != silent).collect();
    let mut samples = vec![Vec::new(); units];
    for trial in 0..trials * live.len() {
        let unit = live[trial % live.len()];
        let phase = Duration::from_micros(rng.random_range(0..1_000_000));
        world.run_for(phase);
        let injected = world.now();
        world.inject_fault_on(unit, FAULT);
        let seen = world
            .run_until(
                |w| w.endpoint().status_of(unit).active_fault.is_some(),
                Duration::from_secs(3),
            )
            .expect("fault seen");
        samples[unit].push(seen.saturating_since(injected));
        world.clear_fault_on(unit);
        world
            .run_until(
                |w| w.endpoint().status_of(unit).active_fault.is_none(),
                Duration::from_secs(3),
            )
            .expect("fault cleared");
    }
    SharedLineFigures {
        units,
        silent,
        faults: samples.into_iter().map(Latencies::new).collect(),
        cycles_per_s,
        switches_per_s,
    }
}

/// The lines the benchmark measures: 1, 2 and 4 HPR260s, and 4 with the third silent.
pub const LINES: [(usize, Option<usize>); 4] = [(1, None), (2, None), (4, None), (4, Some(2))];

/// Faults injected per answering unit in the benchmark's table.
pub const SHARED_LINE_TRIALS: usize = 200;

/// The tables `cargo bench --bench bus` prints for [`LINES`]: the bare line, then through
/// the bridge.
pub fn report(out: &mut String) {
    table(out, "on the bare line (SharedLine)", shared_line);
    table(
        out,
        "through the bridge (CONFIG units, each unit's discrete I/O)",
        bridge_line,
    );
}

type Measure = fn(usize, Option<usize>, usize, Duration, u64) -> SharedLineFigures;

fn table(out: &mut String, through: &str, measure: Measure) {
    use std::fmt::Write;
    let ms = |d: Duration| d.as_micros() as f64 / 1000.0;
    let window = Duration::from_secs(20);
    let _ = writeln!(
        out,
        "\n(d) Several HPR260s on one line (ids 0-3, SLEEP/WAKE), {through}, default schedule: per unit, fault-detection latency over {} injections\n    at random phases (p50/p99/max ms) and fault reads (079 or 003) per second ({} s idle); the bridge's WAKEs (line hand-overs) per second",
        SHARED_LINE_TRIALS,
        window.as_micros() / 1_000_000
    );
    let _ = writeln!(
        out,
        "{:<22} {:>6} {:>8} {:>8} {:>8} {:>8} {:>9}",
        "line", "unit", "p50 ms", "p99 ms", "max ms", "c/s", "wakes/s"
    );
    for (units, silent) in LINES {
        let f = measure(units, silent, SHARED_LINE_TRIALS, window, 13);
        let label = match silent {
            Some(s) => format!("{units} x HPR260, {} silent", s + 1),
            None => format!("{units} x HPR260"),
        };
        for (unit, faults) in f.faults.iter().enumerate() {
            let figures = if Some(unit) == silent {
                format!("{:>8} {:>8} {:>8}", "-", "-", "-")
            } else {
                format!(
                    "{:>8.1} {:>8.1} {:>8.1}",
                    ms(faults.quantile(0.5)),
                    ms(faults.quantile(0.99)),
                    ms(faults.max())
                )
            };
            let _ = writeln!(
                out,
                "{:<22} {:>6} {} {:>8.2} {:>9}",
                if unit == 0 { label.as_str() } else { "" },
                unit + 1,
                figures,
                f.cycles_per_s[unit],
                if unit == 0 {
                    format!("{:.2}", f.switches_per_s)
                } else {
                    String::new()
                }
            );
        }
    }
}
