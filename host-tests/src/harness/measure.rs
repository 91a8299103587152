//! Measurements of the link against the simulators, in virtual time (deterministic): bus
//! efficiency, fault-detection latency (idle, and while a CNC keeps commands in flight, with
//! the commands' latency) and the cost of a status cycle. The `bus` benchmark prints them
//! ([`report`]); tests assert the goals that are met.
//!
//! # Definitions
//! - A *status cycle* is the set of poll requests that refresh settings, outputs and fault
//!   (SYNC: one function-04 read of 0x3010-0x301A; legacy: the 0x2093-0x209F block, or its
//!   documented parts when the unit refuses the block; HPR: one GET_PS_INFO).
//! - *Wire-limited maximum*: status cycles per second if the line carried nothing but the
//!   cycle's characters back to back: `1 / (characters of requests and replies x character
//!   time)`. The unit's response latency and everything else on the bus count against the
//!   efficiency.
//! - *Efficiency*: measured status cycles per second / wire-limited maximum, under continuous
//!   polling (the link's shortest poll interval).
//! - A *fault check* is a read of the fault register alone between two status cycles; it is
//!   no status-cycle request and counts apart from the other traffic.

pub mod shared_line;

use plasma_firmware::link::{LinkCommand, LinkConfig, LinkEvent, Ticket};
use plasma_protocol::powermax::{Amps, OperatingMode, Pressure};
use plasma_protocol::time::{Duration, Instant};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::WorldOptions;
use super::trace::TraceFrame;
use super::world::{Timeout, World};
use plasma_sim::powermax::{Powermax, UndocumentedAddresses};
use plasma_sim::{Family, Model};

/// The configurations measured, one per protocol variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setup {
    /// Powermax SYNC (a Powermax65 SYNC).
    Sync,
    /// Legacy Powermax that accepts the block read over undocumented addresses (Powermax85).
    LegacyBlock,
    /// Legacy Powermax that refuses it: documented parts (Powermax85).
    LegacyParts,
    /// HPR260 (automatic gas console).
    Hpr,
    /// MaxPro200.
    MaxPro200,
}

impl Setup {
    /// Every setup.
    pub const ALL: [Setup; 5] = [
        Setup::Sync,
        Setup::LegacyBlock,
        Setup::LegacyParts,
        Setup::Hpr,
        Setup::MaxPro200,
    ];

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Setup::Sync => "SYNC (65)",
            Setup::LegacyBlock => "legacy, block (85)",
            Setup::LegacyParts => "legacy, parts (85)",
            Setup::Hpr => "HPR260",
            Setup::MaxPro200 => "MaxPro200",
        }
    }

    /// The simulated model.
    pub fn model(self) -> Model {
        match self {
            Setup::Sync => Model::Sync65,
            Setup::LegacyBlock | Setup::LegacyParts => Model::Pm85,
            Setup::Hpr => Model::Hpr260,
            Setup::MaxPro200 => Model::MaxPro200,
        }
    }

    /// A world for this setup with `link` as the link configuration.
    pub fn world(self, link: LinkConfig, seed: u64) -> World {
        let mut options = WorldOptions::with_link(link);
        options.seed = seed;
        options.sim.seed = seed;
        let mut world = World::new(self.model(), options);
        if self == Setup::LegacyParts {
            world.sim::<Powermax>().config_mut().undocumented = UndocumentedAddresses::Refuse;
        }
        world
    }

    /// True when `frame` is one of this setup's status-cycle requests.
    pub fn is_poll(self, frame: &TraceFrame) -> bool {
        if self.is_fault_check(frame) {
            return false;
        }
        match self.model().family() {
            Family::Sync => {
                frame.modbus_function() == Some(0x04)
                    && matches!(frame.modbus_address(), Some(0x3010) | Some(0x3018))
            }
            Family::Legacy => {
                frame.modbus_function() == Some(0x04)
                    && frame
                        .modbus_address()
                        .is_some_and(|a| (0x2093..=0x209F).contains(&a))
            }
            Family::Hpr => frame.hpr_id() == Some(79),
        }
    }

    /// True when `frame` reads the fault register alone (the check between two polls).
    pub fn is_fault_check(self, frame: &TraceFrame) -> bool {
        let fault = match self.model().family() {
            Family::Sync => plasma_protocol::powermax::sync::ACTIVE_FAULT,
            Family::Legacy => plasma_protocol::powermax::legacy::FAULT_CODE,
            Family::Hpr => return false,
        };
        frame.is_request()
            && frame.modbus_function() == Some(0x04)
            && frame.modbus_address() == Some(fault)
            && frame.modbus_quantity() == Some(1)
    }

    /// The commands a CNC keeps in flight, one after the other (SET PROCESS, COUNTERS, SET
    /// PROCESS with another current; on an HPR and a MaxPro200 the set-current command).
    pub fn command_stream(self) -> [LinkCommand<'static>; 3] {
        let apply = |amps| match self.model().family() {
            Family::Hpr => LinkCommand::HprSetNominalAmps { amps },
            _ => LinkCommand::ApplyProcess {
                mode: OperatingMode::Cut,
                current: Amps::from_whole(amps).expect("40 A and 45 A are currents"),
                pressure: Pressure::Auto,
            },
        };
        let mut stream = [apply(45), apply(40), apply(40)];
        stream[COUNTERS_INDEX] = LinkCommand::RefreshSlowData;
        stream
    }

    /// The fault injected for latency measurements (Powermax 0-30-0; HPR error 044).
    pub fn fault_code(self) -> u16 {
        match self.model().family() {
            Family::Hpr => 44,
            _ => 300,
        }
    }
}

/// Bus efficiency under continuous polling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BusEfficiency {
    /// What was measured.
    pub setup: Setup,
    /// Poll interval configured.
    pub poll_interval: Duration,
    /// Requests per status cycle.
    pub requests_per_cycle: f64,
    /// Characters (requests and replies) per status cycle.
    pub chars_per_cycle: f64,
    /// Character time, microseconds.
    pub char_time_us: f64,
    /// Wire-limited maximum, status cycles per second.
    pub wire_max_per_s: f64,
    /// Measured status cycles per second.
    pub cycles_per_s: f64,
    /// Measured / wire-limited maximum.
    pub efficiency: f64,
    /// Fraction of the time the wire carried characters (any frame, either direction).
    pub bus_busy: f64,
    /// Fraction of the time spent in other transactions (slow data, cartridge check).
    pub other_traffic: f64,
    /// Fraction of the time spent reading the fault register alone between polls.
    pub fault_check_traffic: f64,
    /// Mean time from the end of a request to the start of its reply (unit latency), ms.
    pub unit_latency_ms: f64,
    /// Mean time from the end of a reply to the start of the next request (link turnaround),
    /// ms.
    pub turnaround_ms: f64,
}

/// Measure the bus efficiency of `setup` with `poll_interval` over `window` of steady state.
pub fn bus_efficiency(setup: Setup, poll_interval: Duration, window: Duration) -> BusEfficiency {
    let link = LinkConfig {
        poll_interval,
        ..LinkConfig::default()
    };
    let mut world = setup.world(link, 7);
    world
        .wait_link_up(Duration::from_secs(5))
        .expect("link comes up");
    // Past detection, slow data and (HPR) the purge.
    world.run_for(Duration::from_secs(4));
    let from = world.now();
    world.run_for(window);
    let to = world.now();

    let frames: Vec<&TraceFrame> = world
        .trace()
        .frames()
        .iter()
        .filter(|f| f.start >= from && f.end <= to)
        .collect();
    let mut cycles = 0usize;
    let mut poll_requests = 0usize;
    // Poll requests before the last cycle began: whole cycles only, so a cycle cut off by the
    // end of the window does not count as a shorter one.
    let mut whole_cycle_requests = 0usize;
    let mut other_us = 0u64;
    let mut fault_check_us = 0u64;
    let mut char_time_us = 0.0;
    let mut latency_us = Vec::new();
    let mut turnaround_us = Vec::new();
    let mut marker: Option<&[u8]> = None;
    // Per kind of poll request: its length and the lengths of its replies.
    let mut kinds: Vec<(&[u8], Vec<usize>)> = Vec::new();
    for (i, frame) in frames.iter().enumerate() {
        if !frame.is_request() {
            continue;
        }
        let reply = frames.get(i + 1).filter(|r| !r.is_request());
        if let Some(r) = reply {
            latency_us.push(r.start.saturating_since(frame.end).as_micros());
            if let Some(next) = frames.get(i + 2).filter(|n| n.is_request()) {
                turnaround_us.push(next.start.saturating_since(r.end).as_micros());
            }
        }
        if setup.is_poll(frame) {
            char_time_us = frame.port.char_time_ns() as f64 / 1000.0;
            let first = *marker.get_or_insert(&frame.bytes);
            if frame.bytes == first {
                cycles += 1;
                whole_cycle_requests = poll_requests;
            }
            poll_requests += 1;
            let at = match kinds.iter().position(|(k, _)| *k == &frame.bytes[..]) {
                Some(at) => at,
                None => {
                    kinds.push((&frame.bytes, Vec::new()));
                    kinds.len() - 1
                }
            };
            if let Some(r) = reply {
                kinds[at].1.push(r.bytes.len());
            }
        } else {
            let us = frame.end.saturating_since(frame.start).as_micros()
                + reply.map_or(0, |r| r.end.saturating_since(r.start).as_micros());
            if setup.is_fault_check(frame) {
                fault_check_us += us;
            } else {
                other_us += us;
            }
        }
    }
    let busy_us: u64 = frames
        .iter()
        .map(|f| f.end.saturating_since(f.start).as_micros())
        .sum();
    let secs = to.saturating_since(from).as_micros() as f64 / 1e6;
    let chars_per_cycle: f64 = kinds
        .iter()
        .map(|(request, replies)| {
            request.len() as f64
                + replies.iter().sum::<usize>() as f64 / replies.len().max(1) as f64
        })
        .sum();
    let wire_max_per_s = 1e6 / (chars_per_cycle * char_time_us);
    let cycles_per_s = cycles as f64 / secs;
    let mean = |v: &[u64]| v.iter().sum::<u64>() as f64 / v.len().max(1) as f64 / 1000.0;
    BusEfficiency {
        setup,
        poll_interval,
        requests_per_cycle: if cycles > 1 {
            whole_cycle_requests as f64 / (cycles - 1) as f64
        } else {
            poll_requests as f64
        },
        chars_per_cycle,
        char_time_us,
        wire_max_per_s,
        cycles_per_s,
        efficiency: cycles_per_s / wire_max_per_s,
        bus_busy: busy_us as f64 / (secs * 1e6),
        other_traffic: other_us as f64 / (secs * 1e6),
        fault_check_traffic: fault_check_us as f64 / (secs * 1e6),
        unit_latency_ms: mean(&latency_us),
        turnaround_ms: mean(&turnaround_us),
    }
}

/// Latencies, sorted, with nearest-rank quantiles.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Latencies {
    /// The samples, shortest first.
    pub samples: Vec<Duration>,
}

impl Latencies {
    fn new(mut samples: Vec<Duration>) -> Self {
        samples.sort();
        Latencies { samples }
    }

    /// The `q` quantile (nearest rank), e.g. 0.99.
    pub fn quantile(&self, q: f64) -> Duration {
        if self.samples.is_empty() {
            return Duration::ZERO;
        }
        let rank = (q * self.samples.len() as f64).ceil() as usize;
        self.samples[rank.clamp(1, self.samples.len()) - 1]
    }

    /// The longest.
    pub fn max(&self) -> Duration {
        self.samples.last().copied().unwrap_or(Duration::ZERO)
    }
}

/// What else the link has to do while faults are injected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Load {
    /// Nothing: the default schedule of polls and slow data.
    Idle,
    /// A CNC keeps one command in flight all the time ([`Setup::command_stream`], round
    /// robin, the next sent the moment the last one is answered).
    Commands,
}

/// Fault-detection latency over many injections.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultLatency {
    /// What was measured.
    pub setup: Setup,
    /// With what else to do.
    pub load: Load,
    /// From the fault appearing at the unit to the link's `FaultRaised`.
    pub faults: Latencies,
    /// From submitting a setting command (SET PROCESS; HPR: set current) to its result
    /// ([`Load::Commands`]; empty when idle).
    pub settings: Latencies,
    /// From submitting COUNTERS (the slow data read again) to its result.
    pub counters: Latencies,
}

/// One command in flight at a time, in [`Setup::command_stream`] order.
struct CommandStream {
    commands: [LinkCommand<'static>; 3],
    next: usize,
    /// The command in flight: its ticket, when it was submitted, the event count then.
    in_flight: Option<(Ticket, Instant, usize)>,
    /// Latency of each command answered, by its index in `commands`.
    latencies: Vec<(usize, Duration)>,
}

impl CommandStream {
    fn new(setup: Setup) -> Self {
        CommandStream {
            commands: setup.command_stream(),
            next: 0,
            in_flight: None,
            latencies: Vec::new(),
        }
    }

    /// When the command in flight was answered.
    fn answered(&self, world: &World) -> Option<Instant> {
        let (ticket, _, mark) = self.in_flight?;
        world.events()[mark..].iter().find_map(|(at, e)| match e {
            LinkEvent::CommandDone { ticket: t, .. } if *t == ticket => Some(*at),
            _ => None,
        })
    }

    /// Record the answered command and send the next one.
    fn pump(&mut self, world: &mut World) {
        if let Some((_, since, _)) = self.in_flight {
            let Some(at) = self.answered(world) else {
                return;
            };
            let index = (self.next - 1) % self.commands.len();
            self.latencies.push((index, at.saturating_since(since)));
        }
        let command = self.commands[self.next % self.commands.len()];
        self.next += 1;
        let mark = world.events().len();
        let since = world.now();
        let ticket = world
            .submit(command)
            .unwrap_or_else(|r| panic!("{command:?} refused: {r:?}"));
        self.in_flight = Some((ticket, since, mark));
    }
}

/// Run `world` (keeping `stream` busy, if any) until `done` holds, at most `timeout`.
fn run_until(
    world: &mut World,
    stream: &mut Option<CommandStream>,
    mut done: impl FnMut(&World) -> bool,
    timeout: Duration,
) -> Result<Instant, Timeout> {
    let deadline = world.now() + timeout;
    loop {
        if let Some(stream) = stream.as_mut() {
            stream.pump(world);
        }
        let left = deadline.saturating_since(world.now());
        let answered = |w: &World| stream.as_ref().is_some_and(|s| s.answered(w).is_some());
        let at = world.run_until(|w| done(w) || answered(w), left)?;
        if done(world) {
            return Ok(at);
        }
    }
}

/// Run until an event after this call matches `pred`.
fn wait_event(
    world: &mut World,
    stream: &mut Option<CommandStream>,
    pred: impl Fn(&LinkEvent) -> bool,
    timeout: Duration,
) -> Result<Instant, Timeout> {
    let mark = world.events().len();
    let found = |w: &World| {
        w.events()[mark..]
            .iter()
            .find(|(_, e)| pred(e))
            .map(|(at, _)| *at)
    };
    run_until(world, stream, |w| found(w).is_some(), timeout)?;
    Ok(found(world).expect("found by run_until"))
}

/// Inject `trials` faults at random phases of the default schedule, with `load`, and measure
/// the time until the link reports `FaultRaised`.
pub fn fault_latency(setup: Setup, load: Load, trials: usize, seed: u64) -> FaultLatency {
    let mut world = setup.world(LinkConfig::default(), seed);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    world
        .wait_link_up(Duration::from_secs(5))
        .expect("link comes up");
    // Past detection and the first slow data (the limits SET PROCESS needs).
    world.run_for(Duration::from_secs(4));
    let mut stream = (load == Load::Commands).then(|| CommandStream::new(setup));
    let code = setup.fault_code();
    let mut samples = Vec::with_capacity(trials);
    for _ in 0..trials {
        let phase = Duration::from_micros(rng.random_range(0..1_000_000));
        let _ = run_until(&mut world, &mut stream, |_| false, phase);
        let injected = world.now();
        world.inject_fault(code);
        let raised = |e: &LinkEvent| matches!(e, LinkEvent::FaultRaised { .. });
        let at = wait_event(&mut world, &mut stream, raised, Duration::from_secs(3))
            .expect("fault reported");
        samples.push(at.saturating_since(injected));
        world.clear_fault();
        let cleared = |e: &LinkEvent| matches!(e, LinkEvent::FaultCleared { .. });
        wait_event(&mut world, &mut stream, cleared, Duration::from_secs(3))
            .expect("fault cleared");
    }
    let latencies = stream.map(|s| s.latencies).unwrap_or_default();
    let of_kind = |counters: bool| {
        latencies
            .iter()
            .filter(|(index, _)| (*index == COUNTERS_INDEX) == counters)
            .map(|(_, latency)| *latency)
            .collect()
    };
    FaultLatency {
        setup,
        load,
        faults: Latencies::new(samples),
        settings: Latencies::new(of_kind(false)),
        counters: Latencies::new(of_kind(true)),
    }
}

/// Where COUNTERS is in [`Setup::command_stream`].
const COUNTERS_INDEX: usize = 1;

/// Faults injected per row of the latency table.
pub const FAULT_TRIALS: usize = 500;

/// The reference: LinuxCNC's pmx485 reads six single registers per cycle on the legacy
/// addresses. One read is 17 request characters and 15 reply characters.
pub const PMX485_REQUESTS_PER_CYCLE: usize = 6;
/// Characters per pmx485 cycle (6 x (17 + 15)).
pub const PMX485_CHARS_PER_CYCLE: usize = PMX485_REQUESTS_PER_CYCLE * (17 + 15);

fn ms(d: Duration) -> f64 {
    d.as_micros() as f64 / 1000.0
}

/// Run every measurement and format the tables (what `cargo bench --bench bus` prints).
pub fn report() -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let window = Duration::from_secs(20);
    let min = LinkConfig::MIN_POLL_INTERVAL;
    let default = LinkConfig::default().poll_interval;

    let _ = writeln!(
        out,
        "(a) Bus efficiency, continuous polling (poll interval {} ms), 19200 baud, {} s of virtual time",
        min.as_millis(),
        window.as_micros() / 1_000_000
    );
    let _ = writeln!(
        out,
        "{:<20} {:>6} {:>7} {:>9} {:>9} {:>7} {:>7} {:>7} {:>8} {:>8} | {:>9} {:>7} {:>7}",
        "protocol",
        "req/c",
        "chars/c",
        "max c/s",
        "meas c/s",
        "eff %",
        "busy %",
        "other %",
        "unit ms",
        "turn ms",
        "@100ms c/s",
        "busy %",
        "fault %"
    );
    for setup in Setup::ALL {
        let e = bus_efficiency(setup, min, window);
        let d = bus_efficiency(setup, default, window);
        let _ = writeln!(
            out,
            "{:<20} {:>6.2} {:>7.1} {:>9.2} {:>9.2} {:>7.1} {:>7.1} {:>7.1} {:>8.2} {:>8.3} | {:>9.2} {:>7.1} {:>7.1}",
            setup.label(),
            e.requests_per_cycle,
            e.chars_per_cycle,
            e.wire_max_per_s,
            e.cycles_per_s,
            e.efficiency * 100.0,
            e.bus_busy * 100.0,
            e.other_traffic * 100.0,
            e.unit_latency_ms,
            e.turnaround_ms,
            d.cycles_per_s,
            d.bus_busy * 100.0,
            d.fault_check_traffic * 100.0,
        );
    }

    let _ = writeln!(
        out,
        "\n(b) Fault-detection latency, default schedule (poll {} ms, fault register at least every {} ms), {} injections at random phases;\n    idle, and (busy) with a CNC keeping one command in flight (SET PROCESS 45 A, COUNTERS, SET PROCESS 40 A; HPR: set current),\n    with the latency of the setting commands (set) and of COUNTERS (cnt)",
        default.as_millis(),
        plasma_firmware::link::FAULT_CHECK_INTERVAL.as_millis(),
        FAULT_TRIALS
    );
    let _ = writeln!(
        out,
        "{:<20} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8}",
        "protocol",
        "p50 ms",
        "p99 ms",
        "max ms",
        "busy p50",
        "p99",
        "max",
        "set p50",
        "p99",
        "max",
        "cnt p50",
        "p99",
        "max"
    );
    for setup in Setup::ALL {
        let idle = fault_latency(setup, Load::Idle, FAULT_TRIALS, 11);
        let busy = fault_latency(setup, Load::Commands, FAULT_TRIALS, 11);
        let _ = writeln!(
            out,
            "{:<20} {:>8.1} {:>8.1} {:>8.1} | {:>8.1} {:>8.1} {:>8.1} | {:>8.1} {:>8.1} {:>8.1} | {:>8.1} {:>8.1} {:>8.1}",
            setup.label(),
            ms(idle.faults.quantile(0.5)),
            ms(idle.faults.quantile(0.99)),
            ms(idle.faults.max()),
            ms(busy.faults.quantile(0.5)),
            ms(busy.faults.quantile(0.99)),
            ms(busy.faults.max()),
            ms(busy.settings.quantile(0.5)),
            ms(busy.settings.quantile(0.99)),
            ms(busy.settings.max()),
            ms(busy.counters.quantile(0.5)),
            ms(busy.counters.quantile(0.99)),
            ms(busy.counters.max()),
        );
    }

    let _ = writeln!(
        out,
        "\n(c) Cost of a full status cycle (settings, outputs, fault; legacy: + limits, arc time)"
    );
    let _ = writeln!(
        out,
        "{:<20} {:>12} {:>8} {:>12}",
        "", "transactions", "chars", "wire ms/cycle"
    );
    let char_us =
        plasma_protocol::serial::PortConfig::MODBUS_DEFAULT.char_time_ns() as f64 / 1000.0;
    let _ = writeln!(
        out,
        "{:<20} {:>12} {:>8} {:>12.1}",
        "pmx485 (LinuxCNC)",
        PMX485_REQUESTS_PER_CYCLE,
        PMX485_CHARS_PER_CYCLE,
        PMX485_CHARS_PER_CYCLE as f64 * char_us / 1000.0
    );
    for setup in Setup::ALL {
        let e = bus_efficiency(setup, default, Duration::from_secs(5));
        let _ = writeln!(
            out,
            "{:<20} {:>12.2} {:>8.1} {:>12.1}",
            setup.label(),
            e.requests_per_cycle,
            e.chars_per_cycle,
            e.chars_per_cycle * e.char_time_us / 1000.0
        );
    }
    shared_line::report(&mut out);
    out
}
