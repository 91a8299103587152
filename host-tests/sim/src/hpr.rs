//! HyPerformance HPR130/260/400 (and XD) with a manual or automatic gas console, and the
//! MaxPro200, written from the *HPR / MaxPro200 Serial Interface Protocol and CNC Signal
//! Listing* (seed 002).
//!
//! # What is modelled
//! - Framing `>ID data CK<`, error replies 500 (bad checksum, also for a frame with a damaged
//!   character) and 501 (unknown command, or a command the system does not have: e.g. 058 on a
//!   manual gas console, 137 on an HPR).
//! - Replies 1-7 ms after the request (XD: half), plus 1.0-1.8 ms with command 136 enabled; the
//!   value is drawn from the seeded PRNG.
//! - Multi-drop: a unit with dip-switch id 0 powers up talking, others asleep; 086 SLEEP puts
//!   every unit to sleep without a reply, 085 WAKE + id wakes that unit (echo); 087 BROADCAST
//!   MODE: units act on commands but do not answer until woken. A sleeping unit answers nothing,
//!   not even 500/501.
//! - States (section V) through a cut, on the discrete Start / Hold / Corner inputs:
//!   HPR 0 idle -> 2 purge -> 3 idle2; Start -> 4 preflow (held while Hold is on; 60 s -> error
//!   032) -> 5 pilot arc (HF ignition: a noise burst of up to 1 s, see
//!   [`SimulatedUnit::take_noise_bursts`]) -> 6 transfer (Motion on) -> 7 ramp-up -> 8 steady
//!   state; Start off -> 9 ramp-down -> 10 final ramp-down -> 11 auto off -> 3. Start removed
//!   before steady state: error 031; no transfer within the pilot time-out: error 021.
//!   MaxPro200: 0 power up -> 1 initial checks -> 2 gas purge -> 3 ready; Start -> 4 preflow
//!   (5 preflow hold) -> 6 ignite -> 7 pilot arc -> 8 ramp-up -> 9 main arc; Start off -> 10
//!   ramp-down -> 11 ramp-down complete -> 12 end of cycle -> 3.
//! - Errors (section IV): codes below 43 are warnings (Start still works; 131 clears them);
//!   43-79 block Start while present; above 79 shut down (state 14) until 068 SOFTWARE_RESET.
//!   Error log (134) of the last 4 errors since power-up, timers/counters (125).
//! - Settings: 004 remote mode, 058 nominal amps (clamped to 5..=130/260/400/200 and echoed),
//!   070 corner current (50-100 %), 095 all parameters, 096 inlet gases (a change of gas purges;
//!   refused in states 4-10), 137 process (MaxPro200, states 2-3 only), 136 response delay (XD).
//!   By default settings commands are refused until 004 has been accepted
//!   ([`HprConfig::require_remote_mode`]); the manual does not say a unit requires it, so a
//!   bridge that always sends 004 first works either way.
//! - Every command id received is logged ([`Hpr::commands_received`]) so scenario tests can check
//!   that the bridge never sent a factory-only or dangerous command (101, 102, 119, 120, ...).
//!
//! # Manual corrections
//! The HELLO samples read `HYPERPERFORMANCE...`; their checksums (B5, 30, 1E) only match
//! `HYPERFORMANCE130MANUAL`, `HYPERFORMANCE130AUTO`, `HYPERFORMANCE130AUTOMIX`. The revision
//! history names the XD identity `HYPERFORMANCE400XD`; the 130XD/260XD strings follow that
//! pattern (an assumption). The 125 sample's checksum (58) matches no reading of its data; the
//! reply follows the text (7 fields of 7 digits, each followed by a space).
//!
//! # Not modelled
//! The factory-test and diagnostic commands (074, 100-124 except those listed, 126-130, 132,
//! 133, 135, 139-147) answer 501.

use std::any::Any;
use std::collections::VecDeque;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::clock::{Accumulator, earliest};
use super::hpr_wire::{self, Assembler, Incoming};
use super::{Model, SimulatedUnit};

/// Gas console of an HPR.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GasConsole {
    /// Manual gas console: gases and pressures set by knobs.
    Manual,
    /// Automatic gas console: the CNC sets gases and pressures.
    Auto,
}

/// Durations of the sequence steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HprTimings {
    /// Power-up checks before the purge (MaxPro200: initial checks too).
    pub power_up: Duration,
    /// Gas purge after power-up or a gas change.
    pub purge: Duration,
    /// Preflow before ignition.
    pub preflow: Duration,
    /// Pilot arc to transfer; `None`: never transfers.
    pub transfer_delay: Option<Duration>,
    /// A pilot arc that has not transferred by then fails with error 021.
    pub pilot_timeout: Duration,
    /// Transfer to steady state (ramp-up).
    pub rampup: Duration,
    /// Ramp-down after Start goes off.
    pub rampdown: Duration,
    /// Gas flow after the arc (auto off / end of cycle).
    pub postflow: Duration,
    /// Longest HF ignition burst.
    pub hf_max: Duration,
}

impl Default for HprTimings {
    fn default() -> Self {
        HprTimings {
            power_up: Duration::from_millis(500),
            purge: Duration::from_secs(2),
            preflow: Duration::from_millis(500),
            transfer_delay: Some(Duration::from_millis(50)),
            pilot_timeout: Duration::from_millis(300),
            rampup: Duration::from_millis(50),
            rampdown: Duration::from_millis(100),
            postflow: Duration::from_secs(2),
            hf_max: Duration::from_secs(1),
        }
    }
}

/// Everything that makes one simulated HPR / MaxPro200.
#[derive(Debug, Clone, PartialEq)]
pub struct HprConfig {
    /// The model.
    pub model: Model,
    /// Dip-switch id, 0-3.
    pub id: u8,
    /// Gas console (ignored on the MaxPro200).
    pub console: GasConsole,
    /// Serial settings.
    pub port: PortConfig,
    /// Sequence timing.
    pub timings: HprTimings,
    /// Firmware versions reported by 001.
    pub version: String,
    /// Settings commands are refused until 004 REMOTE_MODE.
    pub require_remote_mode: bool,
    /// PRNG seed (response time).
    pub seed: u64,
}

impl HprConfig {
    /// Defaults for `model` (an HPR model or the MaxPro200).
    pub fn for_model(model: Model) -> HprConfig {
        HprConfig {
            model,
            id: 0,
            console: GasConsole::Auto,
            port: PortConfig::HPR,
            timings: HprTimings::default(),
            version: "A.0 A.25".into(),
            require_remote_mode: true,
            seed: 1,
        }
    }
}

/// Where the sequence is (mapped to the section V state codes by [`Hpr::state_code`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Power-up (HPR 0 idle, MaxPro 0 power up).
    PowerUp,
    /// MaxPro 1 initial checks.
    InitialChecks,
    /// 2 purge.
    Purge,
    /// 3 idle2 / ready for start.
    Ready,
    /// 4 preflow.
    Preflow,
    /// MaxPro 5 preflow hold (HPR stays in 4).
    PreflowHold,
    /// MaxPro 6 ignite.
    Ignite,
    /// Pilot arc (HPR 5, MaxPro 7).
    Pilot,
    /// HPR 6 transfer.
    Transfer,
    /// Ramp-up (HPR 7, MaxPro 8).
    Rampup,
    /// Steady state / main arc (HPR 8, MaxPro 9).
    Steady,
    /// Ramp-down (HPR 9, MaxPro 10).
    Rampdown,
    /// HPR 10 final ramp-down.
    FinalRampdown,
    /// HPR 11 auto off / MaxPro 11 ramp-down complete.
    AutoOff,
    /// MaxPro 12 end of cycle.
    EndOfCycle,
    /// 14 shutdown.
    Shutdown,
    /// HPR 12 test cutflow.
    TestCutflow,
    /// HPR 20 test preflow.
    TestPreflow,
}

/// Counters reported by 125 GET_TIMER_COUNTER.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct HprCounters {
    /// Arc on time.
    pub arc_on: Accumulator,
    /// Powered time.
    pub system_on: Accumulator,
    /// Arc transfers.
    pub starts: u32,
    /// Failed to transfer.
    pub start_errors: u32,
    /// Failed to ramp down.
    pub rampdown_errors: u32,
}

/// A simulated HPR or MaxPro200.
#[derive(Debug)]
pub struct Hpr {
    config: HprConfig,
    rng: Xoshiro256PlusPlus,
    now: Instant,
    powered: bool,
    awake: bool,
    broadcast: bool,
    assembler: Assembler,
    outbox: VecDeque<(Instant, Vec<u8>)>,
    phase: Phase,
    phase_since: Instant,
    start: bool,
    hold: bool,
    corner: bool,
    error: u16,
    error_log: [u16; 4],
    remote: bool,
    response_delay: bool,
    amps: u16,
    corner_pct: u16,
    gases: (u16, u16),
    /// Plasma cutflow, plasma preflow, shield cutflow, shield preflow, N2 mix, gas 2 mix (psi).
    flows: [u16; 6],
    counters: HprCounters,
    noise: Vec<(Instant, Duration)>,
    received: Vec<u16>,
}

impl Hpr {
    /// A unit switched on at time zero.
    pub fn new(config: HprConfig) -> Hpr {
        let max = max_amps(config.model);
        let mut unit = Hpr {
            rng: Xoshiro256PlusPlus::seed_from_u64(config.seed),
            now: Instant::ZERO,
            powered: false,
            awake: false,
            broadcast: false,
            assembler: Assembler::default(),
            outbox: VecDeque::new(),
            phase: Phase::PowerUp,
            phase_since: Instant::ZERO,
            start: false,
            hold: false,
            corner: false,
            error: 0,
            error_log: [0; 4],
            remote: false,
            response_delay: false,
            amps: max,
            corner_pct: 100,
            gases: (1, 5),
            flows: [55, 45, 35, 25, 0, 0],
            counters: HprCounters::default(),
            noise: Vec::new(),
            received: Vec::new(),
            config,
        };
        unit.power_on(Instant::ZERO);
        unit
    }

    /// The configuration.
    pub fn config(&self) -> &HprConfig {
        &self.config
    }

    /// Changes the configuration (takes effect for what happens next).
    pub fn config_mut(&mut self) -> &mut HprConfig {
        &mut self.config
    }

    fn is_maxpro(&self) -> bool {
        self.config.model == Model::MaxPro200
    }

    fn is_xd(&self) -> bool {
        matches!(
            self.config.model,
            Model::Hpr130Xd | Model::Hpr260Xd | Model::Hpr400Xd
        )
    }

    fn auto_gas(&self) -> bool {
        self.is_maxpro() || self.config.console == GasConsole::Auto
    }

    /// The HELLO (000) identity string.
    pub fn identity(&self) -> String {
        let amps = max_amps(self.config.model);
        match self.config.model {
            Model::MaxPro200 => "MaxPro200".into(),
            _ if self.is_xd() => format!("HYPERFORMANCE{amps}XD"),
            _ => match self.config.console {
                GasConsole::Manual => format!("HYPERFORMANCE{amps}MANUAL"),
                GasConsole::Auto => format!("HYPERFORMANCE{amps}AUTO"),
            },
        }
    }

    /// Where the sequence is.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The section V state code (HPR or MaxPro200 column).
    pub fn state_code(&self) -> u16 {
        let maxpro = self.is_maxpro();
        match self.phase {
            Phase::PowerUp => 0,
            Phase::InitialChecks => 1,
            Phase::Purge => 2,
            Phase::Ready => 3,
            Phase::Preflow => 4,
            Phase::PreflowHold => {
                if maxpro {
                    5
                } else {
                    4
                }
            }
            Phase::Ignite => 6,
            Phase::Pilot => {
                if maxpro {
                    7
                } else {
                    5
                }
            }
            Phase::Transfer => 6,
            Phase::Rampup => {
                if maxpro {
                    8
                } else {
                    7
                }
            }
            Phase::Steady => {
                if maxpro {
                    9
                } else {
                    8
                }
            }
            Phase::Rampdown => {
                if maxpro {
                    10
                } else {
                    9
                }
            }
            Phase::FinalRampdown => 10,
            Phase::AutoOff => 11,
            Phase::EndOfCycle => 12,
            Phase::Shutdown => 14,
            Phase::TestCutflow => 12,
            Phase::TestPreflow => 20,
        }
    }

    /// Drives the Hold Ignition input.
    pub fn set_hold(&mut self, now: Instant, on: bool) {
        self.advance(now);
        let released = self.hold && !on;
        self.hold = on;
        if released && matches!(self.phase, Phase::Preflow | Phase::PreflowHold) {
            // Ignition follows the release once the preflow time is served.
            let preflow = self.config.timings.preflow;
            let since = self.phase_since.max(now - preflow);
            self.phase = Phase::Preflow;
            self.phase_since = since;
        }
    }

    /// Drives the Corner Current input.
    pub fn set_corner(&mut self, now: Instant, on: bool) {
        self.advance(now);
        self.corner = on;
    }

    /// Set current, amps.
    pub fn nominal_amps(&self) -> u16 {
        self.amps
    }

    /// Plasma and shield gas type codes (table VI).
    pub fn gases(&self) -> (u16, u16) {
        self.gases
    }

    /// Corner current percentage.
    pub fn corner_percent(&self) -> u16 {
        self.corner_pct
    }

    /// True when the unit answers (woken, or id 0 at power-up).
    pub fn is_awake(&self) -> bool {
        self.awake
    }

    /// Every command id received with a good checksum, in order.
    pub fn commands_received(&self) -> &[u16] {
        &self.received
    }

    /// The timers and counters.
    pub fn counters(&self) -> HprCounters {
        self.counters
    }

    /// Sets the timers and counters (a unit with a history).
    pub fn set_counters(&mut self, counters: HprCounters) {
        self.counters = counters;
    }

    /// The error log, most recent first.
    pub fn error_log(&self) -> [u16; 4] {
        self.error_log
    }

    /// The output current now (corner current applied while CORNER_CURRENT is on).
    pub fn actual_amps(&self) -> u16 {
        match self.phase {
            Phase::Transfer | Phase::Rampup | Phase::Steady if self.corner => {
                self.amps * self.corner_pct / 100
            }
            Phase::Transfer | Phase::Rampup | Phase::Steady => self.amps,
            _ => 0,
        }
    }

    fn cutting(&self) -> bool {
        let code = self.state_code();
        !matches!(self.phase, Phase::TestCutflow | Phase::TestPreflow) && (4..=10).contains(&code)
    }

    fn error_blocks_start(&self) -> bool {
        self.error >= 43
    }

    fn raise(&mut self, code: u16) {
        if code == 0 {
            return;
        }
        self.error = code;
        self.error_log.rotate_right(1);
        self.error_log[0] = code;
        if code > 79 {
            self.enter(Phase::Shutdown, self.now);
        } else if code >= 43 && self.arc_on() {
            self.enter(Phase::AutoOff, self.now);
        }
    }

    fn arc_on(&self) -> bool {
        matches!(
            self.phase,
            Phase::Preflow
                | Phase::PreflowHold
                | Phase::Ignite
                | Phase::Pilot
                | Phase::Transfer
                | Phase::Rampup
                | Phase::Steady
        )
    }

    fn enter(&mut self, phase: Phase, at: Instant) {
        self.phase = phase;
        self.phase_since = at;
        if matches!(phase, Phase::Pilot | Phase::Ignite) {
            let t = &self.config.timings;
            let until_transfer = t.transfer_delay.unwrap_or(t.pilot_timeout);
            let length = if until_transfer < t.hf_max {
                until_transfer
            } else {
                t.hf_max
            };
            if phase == Phase::Pilot || self.is_maxpro() {
                self.noise.push((at, length));
            }
        }
    }

    /// When the current phase ends by itself, and what follows.
    fn phase_deadline(&self) -> Option<(Instant, Phase)> {
        let t = &self.config.timings;
        let maxpro = self.is_maxpro();
        let at = |d: Duration| self.phase_since + d;
        match self.phase {
            Phase::PowerUp if maxpro => Some((at(t.power_up), Phase::InitialChecks)),
            Phase::PowerUp | Phase::InitialChecks => Some((at(t.power_up), Phase::Purge)),
            Phase::Purge => Some((at(t.purge), Phase::Ready)),
            Phase::Preflow | Phase::PreflowHold if self.hold => {
                Some((at(Duration::from_secs(60)), Phase::AutoOff))
            }
            Phase::Preflow | Phase::PreflowHold => Some((
                at(t.preflow),
                if maxpro { Phase::Ignite } else { Phase::Pilot },
            )),
            Phase::Ignite => Some((at(Duration::from_millis(10)), Phase::Pilot)),
            Phase::Pilot => match t.transfer_delay {
                Some(d) if d < t.pilot_timeout => Some((
                    at(d),
                    if maxpro {
                        Phase::Rampup
                    } else {
                        Phase::Transfer
                    },
                )),
                _ => Some((at(t.pilot_timeout), Phase::AutoOff)),
            },
            Phase::Transfer => Some((at(Duration::from_millis(10)), Phase::Rampup)),
            Phase::Rampup => Some((at(t.rampup), Phase::Steady)),
            Phase::Rampdown if maxpro => Some((at(t.rampdown), Phase::AutoOff)),
            Phase::Rampdown => Some((at(t.rampdown), Phase::FinalRampdown)),
            Phase::FinalRampdown => Some((at(t.rampdown), Phase::AutoOff)),
            Phase::AutoOff if maxpro => Some((at(t.postflow), Phase::EndOfCycle)),
            Phase::AutoOff => Some((at(t.postflow), Phase::Ready)),
            Phase::EndOfCycle => Some((at(Duration::from_millis(100)), Phase::Ready)),
            _ => None,
        }
    }

    fn accrue(&mut self, until: Instant) {
        let d = until.saturating_since(self.now);
        self.counters.system_on.add(d);
        if matches!(self.phase, Phase::Transfer | Phase::Rampup | Phase::Steady) {
            self.counters.arc_on.add(d);
        }
        self.now = self.now.max(until);
    }

    fn run_timers(&mut self, now: Instant) {
        while let Some((at, next)) = self.phase_deadline().filter(|&(at, _)| at <= now) {
            self.accrue(at);
            let from = self.phase;
            self.enter(next, at);
            match (from, next) {
                (Phase::Preflow | Phase::PreflowHold, Phase::AutoOff) => self.raise(32),
                (Phase::Pilot, Phase::AutoOff) => {
                    self.counters.start_errors += 1;
                    self.raise(21);
                }
                (Phase::Pilot, _) => self.counters.starts += 1,
                _ => {}
            }
        }
        if self.is_maxpro() && self.phase == Phase::Preflow && self.hold {
            self.phase = Phase::PreflowHold;
        }
        self.accrue(now);
    }

    fn flag(ok: bool) -> String {
        if ok { "1".into() } else { "0".into() }
    }

    fn settings_allowed(&self) -> bool {
        self.remote || !self.config.require_remote_mode
    }

    fn change_gases(&mut self, gases: (u16, u16), now: Instant) {
        if gases != self.gases {
            self.gases = gases;
            self.enter(Phase::Purge, now);
        }
    }

    /// Acts on one command; `None` means no reply.
    fn command(&mut self, now: Instant, id: u16, data: &str) -> Option<(u16, String)> {
        let hpr = !self.is_maxpro();
        let auto = self.auto_gas();
        let fields: Vec<&str> = data.split_whitespace().collect();
        let numbers: Option<Vec<u16>> = fields.iter().map(|f| f.parse().ok()).collect();
        let unknown = Some((501, String::new()));
        let reply = |s: String| Some((id, s));
        match id {
            0 => reply(self.identity()),
            1 => reply(self.config.version.clone()),
            2 => reply(format!("{:04}", self.state_code())),
            3 => reply(format!("{:04}", self.error)),
            4 => {
                self.remote = true;
                reply("1".into())
            }
            28 if hpr => reply(format!("{:04}", self.actual_amps())),
            58 if auto => {
                if let (true, Some([amps])) = (self.settings_allowed(), numbers.as_deref()) {
                    self.amps = (*amps).clamp(5, max_amps(self.config.model));
                }
                reply(format!("{:04}", self.amps))
            }
            64..=67 if hpr => {
                let ok = !self.cutting() && !self.error_blocks_start();
                if ok {
                    let phase = match id {
                        64 => Phase::TestPreflow,
                        66 => Phase::TestCutflow,
                        _ => Phase::Ready,
                    };
                    let stopping = id == 65 || id == 67;
                    let running = matches!(self.phase, Phase::TestPreflow | Phase::TestCutflow);
                    if !stopping || running {
                        self.enter(phase, now);
                    }
                }
                reply(Self::flag(ok))
            }
            68 => {
                let ok = if hpr {
                    self.error > 79 && self.phase == Phase::Shutdown
                } else {
                    !self.cutting()
                };
                if ok {
                    self.error = 0;
                    self.enter(Phase::PowerUp, now);
                }
                reply(Self::flag(ok))
            }
            70 if hpr => {
                if let (true, Some([pct])) = (self.settings_allowed(), numbers.as_deref()) {
                    self.corner_pct = (*pct).clamp(50, 100);
                }
                reply(format!("{:04}", self.corner_pct))
            }
            72 if hpr => reply("1200".into()),
            79 if hpr => {
                let [pc, pp, sc, sp, _, _] = self.flows;
                let measured = |v: u16| if auto { v } else { 0 };
                reply(format!(
                    "PC{pc:04} PP{pp:04} SC{sc:04} SP{sp:04} CS{:04} ST{:04} ER{:04} CG{:04} CG{:04} MV{:04} MV{:04}",
                    self.amps,
                    self.state_code(),
                    self.error,
                    measured(100),
                    measured(100),
                    measured(self.flows[4]),
                    measured(self.flows[5]),
                ))
            }
            79 => reply(format!(
                "st{:04} er{:04} pg{:04} ps{:04} sg{:04} ss{:04} cs{:04} dm0001 lm0000",
                self.state_code(),
                self.error,
                self.gases.0,
                self.flows[0],
                self.gases.1,
                self.flows[2],
                self.amps
            )),
            85 if hpr => {
                if fields.first().and_then(|f| f.parse::<u8>().ok()) == Some(self.config.id) {
                    self.awake = true;
                    self.broadcast = false;
                    return reply(data.into());
                }
                None
            }
            86 if hpr => {
                self.awake = false;
                self.broadcast = false;
                None
            }
            87 if hpr => {
                self.broadcast = true;
                None
            }
            94 if hpr => {
                let [pc, pp, sc, sp, n2, g2] = self.flows;
                let m = |v: u16| if auto { v } else { 0 };
                reply(format!(
                    "PC{pc:04} PP{pp:04} SC{sc:04} SP{sp:04} CG{:04} CG{:04} MV{:04} MV{:04}",
                    m(100),
                    m(100),
                    m(n2),
                    m(g2)
                ))
            }
            95 if auto => {
                let ok =
                    self.settings_allowed() && self.set_all_parameters(now, numbers.as_deref());
                if hpr {
                    reply(Self::flag(ok))
                } else {
                    reply(if ok { "1".into() } else { "2".into() })
                }
            }
            96 if auto => {
                let ok = match numbers.as_deref() {
                    Some(&[p, s]) if self.settings_allowed() && !self.cutting() => {
                        valid_gas(p) && valid_gas(s) && {
                            self.change_gases((p, s), now);
                            true
                        }
                    }
                    _ => false,
                };
                reply(Self::flag(ok))
            }
            97 if hpr => reply(format!("{:04}", self.corner_pct)),
            98 => reply(format!("{:04} {:04}", self.gases.0, self.gases.1)),
            99 if hpr && auto => {
                let f = self.flows;
                reply(format!(
                    "{:04} {:04} {:04} {:04} {:04} {:04}",
                    f[0], f[1], f[2], f[3], f[4], f[5]
                ))
            }
            125 if hpr => {
                let c = self.counters;
                let fields = [
                    c.arc_on.secs(),
                    c.system_on.secs() / 60,
                    c.starts.into(),
                    c.start_errors.into(),
                    c.rampdown_errors.into(),
                    0,
                    0,
                ];
                reply(
                    fields
                        .iter()
                        .map(|v| format!("{:07} ", v % 10_000_000))
                        .collect(),
                )
            }
            131 if hpr => {
                if self.error < 43 {
                    self.error = 0;
                }
                reply("1".into())
            }
            134 if hpr => reply(
                self.error_log
                    .iter()
                    .map(|e| format!("{e:03}"))
                    .collect::<Vec<_>>()
                    .join(" "),
            ),
            136 if self.is_xd() => match data {
                "0" | "1" => {
                    self.response_delay = data == "1";
                    reply(data.into())
                }
                _ => reply("0".into()),
            },
            137 if !hpr => {
                let ok = match numbers.as_deref() {
                    Some(&[amps, p, s])
                        if self.settings_allowed()
                            && matches!(self.phase, Phase::Purge | Phase::Ready)
                            && (5..=200).contains(&amps)
                            && valid_gas(p)
                            && valid_gas(s) =>
                    {
                        self.amps = amps;
                        self.change_gases((p, s), now);
                        true
                    }
                    _ => false,
                };
                reply(if ok { "1".into() } else { "2".into() })
            }
            138 if !hpr => reply(Self::flag(
                self.phase == Phase::Ready && !self.error_blocks_start(),
            )),
            _ => unknown,
        }
    }

    fn set_all_parameters(&mut self, now: Instant, numbers: Option<&[u16]>) -> bool {
        if self.cutting() {
            return false;
        }
        let max = max_amps(self.config.model);
        match numbers {
            Some(&[amps, corner, p, s, pc, pp, sc, sp, n2, g2]) if !self.is_maxpro() => {
                let ok = (5..=max).contains(&amps)
                    && (50..=100).contains(&corner)
                    && valid_gas(p)
                    && valid_gas(s)
                    && [pc, pp, sc, sp].iter().all(|&v| v <= 99)
                    && n2 <= 100
                    && g2 <= 100;
                if ok {
                    self.amps = amps;
                    self.corner_pct = corner;
                    self.flows = [pc, pp, sc, sp, n2, g2];
                    self.change_gases((p, s), now);
                }
                ok
            }
            Some(&[amps, p, s, pp, sp]) if self.is_maxpro() => {
                let ok = matches!(self.phase, Phase::Purge | Phase::Ready)
                    && amps <= 200
                    && valid_gas(p)
                    && valid_gas(s)
                    && pp <= 99
                    && sp <= 99;
                if ok {
                    self.amps = amps;
                    self.flows[0] = pp;
                    self.flows[2] = sp;
                    self.change_gases((p, s), now);
                }
                ok
            }
            _ => false,
        }
    }

    fn response_time(&mut self) -> Duration {
        // 1-7 ms (XD about half), plus 1.0-1.8 ms with 136 enabled.
        let (lo, hi) = if self.is_xd() {
            (500, 3_500)
        } else {
            (1_000, 7_000)
        };
        let mut us = self.rng.random_range(lo..=hi);
        if self.response_delay {
            us += self.rng.random_range(1_000..=1_800);
        }
        Duration::from_micros(us)
    }

    fn on_frame(&mut self, now: Instant, frame: Incoming) {
        let (id, data) = match frame {
            Incoming::BadChecksum => {
                if self.awake && !self.broadcast {
                    self.send(now, 500, String::new());
                }
                return;
            }
            Incoming::Command { id: None, .. } => {
                if self.awake && !self.broadcast {
                    self.send(now, 501, String::new());
                }
                return;
            }
            Incoming::Command { id: Some(id), data } => (id, data),
        };
        self.received.push(id);
        // Asleep: only WAKE (and SLEEP) matter.
        if !self.awake && !self.broadcast && !matches!(id, 85 | 86) {
            return;
        }
        let reply = self.command(now, id, &data);
        if let (Some((rid, text)), true) = (reply, self.awake && !self.broadcast) {
            self.send(now, rid, text);
        }
    }

    fn send(&mut self, now: Instant, id: u16, data: String) {
        let due = now + self.response_time();
        self.outbox.push_back((due, hpr_wire::encode(id, &data)));
    }
}

/// Highest current, amps.
pub fn max_amps(model: Model) -> u16 {
    match model {
        Model::Hpr130 | Model::Hpr130Xd => 130,
        Model::Hpr260 | Model::Hpr260Xd => 260,
        Model::MaxPro200 => 200,
        _ => 400,
    }
}

/// A gas type code a CNC may select (table VI; 9, 10 and 12 are internal marking modes).
fn valid_gas(code: u16) -> bool {
    matches!(code, 1..=8 | 11)
}

impl SimulatedUnit for Hpr {
    fn model(&self) -> Model {
        self.config.model
    }

    fn port(&self) -> PortConfig {
        self.config.port
    }

    fn receive(&mut self, now: Instant, byte: u8) {
        self.advance(now);
        if !self.powered {
            return;
        }
        if let Some(frame) = self.assembler.push(byte) {
            self.on_frame(now, frame);
        }
    }

    fn receive_error(&mut self, now: Instant) {
        self.advance(now);
        self.assembler.damage();
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        self.advance(now);
        match self.outbox.front() {
            Some(&(due, _)) if due <= now && self.powered => {
                self.outbox.pop_front().map(|(_, b)| b)
            }
            _ => None,
        }
    }

    fn next_wakeup(&self) -> Option<Instant> {
        if !self.powered {
            return None;
        }
        earliest(
            self.outbox.front().map(|&(due, _)| due),
            self.phase_deadline().map(|(at, _)| at),
        )
    }

    fn advance(&mut self, now: Instant) {
        if now < self.now {
            return;
        }
        if !self.powered {
            self.now = now;
            return;
        }
        self.run_timers(now);
    }

    fn set_start(&mut self, now: Instant, on: bool) {
        self.advance(now);
        let was = self.start;
        self.start = on;
        if !self.powered || on == was {
            return;
        }
        if on {
            if self.phase == Phase::Ready && !self.error_blocks_start() {
                let hold = self.hold && self.is_maxpro();
                self.enter(
                    if hold {
                        Phase::PreflowHold
                    } else {
                        Phase::Preflow
                    },
                    now,
                );
            }
            return;
        }
        if self.error == 50 {
            self.error = 0;
        }
        match self.phase {
            Phase::Steady => self.enter(Phase::Rampdown, now),
            Phase::Preflow
            | Phase::PreflowHold
            | Phase::Ignite
            | Phase::Pilot
            | Phase::Transfer
            | Phase::Rampup => {
                self.enter(Phase::AutoOff, now);
                self.raise(31);
            }
            _ => {}
        }
    }

    fn motion(&self) -> bool {
        self.powered && matches!(self.phase, Phase::Transfer | Phase::Rampup | Phase::Steady)
    }

    fn power_off(&mut self, now: Instant) {
        self.advance(now);
        self.powered = false;
        self.outbox.clear();
        self.assembler.reset();
        self.enter(Phase::PowerUp, now);
        self.noise.clear();
    }

    fn power_on(&mut self, now: Instant) {
        self.advance(now);
        if self.powered {
            return;
        }
        self.powered = true;
        self.awake = self.config.id == 0;
        self.broadcast = false;
        self.remote = false;
        self.response_delay = false;
        self.error = 0;
        self.error_log = [0; 4];
        self.amps = max_amps(self.config.model);
        self.enter(Phase::PowerUp, now);
        if self.start {
            self.raise(50);
        }
    }

    fn is_powered(&self) -> bool {
        self.powered
    }

    fn inject_fault(&mut self, now: Instant, code: u16) {
        self.advance(now);
        self.raise(code);
    }

    fn clear_fault(&mut self, now: Instant) {
        self.advance(now);
        self.error = 0;
    }

    fn active_fault(&self) -> u16 {
        self.error
    }

    fn in_remote_mode(&self) -> bool {
        self.remote
    }

    fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)> {
        std::mem::take(&mut self.noise)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(t: u64) -> Instant {
        Instant::from_millis(t)
    }

    fn unit(model: Model) -> Hpr {
        Hpr::new(HprConfig::for_model(model))
    }

    /// Sends `frame` at `now`; returns the reply text (or None) and when it started.
    fn talk_at(u: &mut Hpr, now: Instant, frame: &str) -> Option<(String, Instant)> {
        for b in frame.bytes() {
            u.receive(now, b);
        }
        let due = u.outbox.back().map(|&(due, _)| due)?;
        let mut last = None;
        while let Some(bytes) = u.poll_transmit(due) {
            last = Some(String::from_utf8(bytes).unwrap());
        }
        last.map(|s| (s, due))
    }

    fn talk(u: &mut Hpr, now: Instant, frame: &str) -> Option<String> {
        talk_at(u, now, frame).map(|(s, _)| s)
    }

    fn cmd(u: &mut Hpr, now: Instant, id: u16, data: &str) -> Option<String> {
        let frame = String::from_utf8(hpr_wire::encode(id, data)).unwrap();
        talk(u, now, &frame)
    }

    #[test]
    fn hello_identifies_the_model() {
        let mut u = unit(Model::Hpr130);
        assert_eq!(
            talk(&mut u, ms(0), ">00090<").unwrap(),
            ">000HYPERFORMANCE130AUTO30<"
        );
        u.config_mut().console = GasConsole::Manual;
        assert_eq!(
            talk(&mut u, ms(10), ">00090<").unwrap(),
            ">000HYPERFORMANCE130MANUALB5<"
        );
        let mut u = unit(Model::MaxPro200);
        assert_eq!(talk(&mut u, ms(0), ">00090<").unwrap(), ">000MaxPro20079<");
        let mut u = unit(Model::Hpr400Xd);
        assert!(
            talk(&mut u, ms(0), ">00090<")
                .unwrap()
                .starts_with(">000HYPERFORMANCE400XD")
        );
    }

    #[test]
    fn error_replies_500_and_501() {
        let mut u = unit(Model::Hpr260);
        assert_eq!(talk(&mut u, ms(0), ">00091<").unwrap(), ">50095<");
        assert_eq!(talk(&mut u, ms(10), ">999AB<").unwrap(), ">50196<");
        // A command this system does not have.
        assert_eq!(cmd(&mut u, ms(20), 137, "200 5 5").unwrap(), ">50196<");
        // A damaged character makes the frame fail its check.
        for b in b">0".iter() {
            u.receive(ms(30), *b);
        }
        u.receive_error(ms(30));
        let r = talk(&mut u, ms(30), "090<");
        assert_eq!(r.unwrap(), ">50095<");
    }

    #[test]
    fn replies_come_1_to_7_ms_after_the_request_and_faster_on_xd() {
        let mut u = unit(Model::Hpr130);
        let mut t = ms(0);
        for _ in 0..50 {
            let (_, due) = talk_at(&mut u, t, ">00292<").unwrap();
            let d = due.saturating_since(t).as_micros();
            assert!((1_000..=7_000).contains(&d), "{d}");
            t = due + Duration::from_millis(1);
        }
        let mut u = unit(Model::Hpr260Xd);
        let (_, due) = talk_at(&mut u, ms(0), ">00292<").unwrap();
        assert!(due <= Instant::from_micros(3_500));
        // 136 adds 1.0-1.8 ms.
        assert_eq!(talk(&mut u, ms(10), ">1361CB<").unwrap(), ">1361CB<");
        let (_, due) = talk_at(&mut u, ms(20), ">00292<").unwrap();
        let d = due.saturating_since(ms(20)).as_micros();
        assert!((1_500..=5_300).contains(&d), "{d}");
        // Not on a plain HPR.
        let mut u = unit(Model::Hpr130);
        assert_eq!(talk(&mut u, ms(0), ">1361CB<").unwrap(), ">50196<");
    }

    #[test]
    fn states_through_a_cut() {
        let mut u = unit(Model::Hpr260);
        let state = |u: &mut Hpr, t| cmd(u, ms(t), 2, "").unwrap();
        assert_eq!(state(&mut u, 0), ">002000052<"); // 0 idle
        assert_eq!(u.state_code(), 0);
        u.advance(ms(600));
        assert_eq!(u.state_code(), 2); // purge
        u.advance(ms(2_600));
        assert_eq!(u.state_code(), 3); // idle2
        u.set_start(ms(3_000), true);
        assert_eq!(u.state_code(), 4); // preflow
        u.advance(ms(3_500));
        assert_eq!(u.state_code(), 5); // pilot arc
        assert_eq!(
            u.take_noise_bursts(),
            vec![(ms(3_500), Duration::from_millis(50))]
        );
        u.advance(ms(3_550));
        assert_eq!(u.state_code(), 6); // transfer
        assert!(u.motion());
        u.advance(ms(3_560));
        assert_eq!(u.state_code(), 7); // ramp-up
        u.advance(ms(3_610));
        assert_eq!(u.state_code(), 8); // steady state
        assert_eq!(
            cmd(&mut u, ms(4_000), 28, "").unwrap(),
            ">0280260".to_string() + &format!("{:02X}<", hpr_wire::checksum(b"0280260"))
        );
        u.set_start(ms(5_000), false);
        assert_eq!(u.state_code(), 9); // ramp-down
        assert!(!u.motion());
        u.advance(ms(5_100));
        assert_eq!(u.state_code(), 10); // final ramp-down
        u.advance(ms(5_200));
        assert_eq!(u.state_code(), 11); // auto off
        u.advance(ms(7_200));
        assert_eq!(u.state_code(), 3);
        assert_eq!(u.active_fault(), 0);
        // One transfer, 1.45 s of arc.
        assert_eq!(u.counters().starts, 1);
        assert_eq!(u.counters().arc_on.secs(), 1);
    }

    #[test]
    fn maxpro_states_through_a_cut() {
        let mut u = unit(Model::MaxPro200);
        u.advance(ms(500));
        assert_eq!(u.state_code(), 1);
        u.advance(ms(1_000));
        assert_eq!(u.state_code(), 2);
        u.advance(ms(3_000));
        assert_eq!(u.state_code(), 3);
        assert_eq!(cmd(&mut u, ms(3_000), 138, "").unwrap(), ">1381CD<");
        u.set_hold(ms(3_100), true);
        u.set_start(ms(3_100), true);
        assert_eq!(u.state_code(), 5); // preflow hold
        u.advance(ms(10_000));
        assert_eq!(u.state_code(), 5);
        u.set_hold(ms(10_000), false);
        u.advance(ms(10_001));
        assert_eq!(u.state_code(), 6); // ignite
        u.advance(ms(10_011));
        assert_eq!(u.state_code(), 7); // pilot arc
        u.advance(ms(10_061));
        assert_eq!(u.state_code(), 8); // ramp-up
        u.advance(ms(10_111));
        assert_eq!(u.state_code(), 9); // main arc
        u.set_start(ms(11_000), false);
        assert_eq!(u.state_code(), 10);
        u.advance(ms(11_100));
        assert_eq!(u.state_code(), 11);
        u.advance(ms(13_100));
        assert_eq!(u.state_code(), 12);
        u.advance(ms(13_200));
        assert_eq!(u.state_code(), 3);
    }

    #[test]
    fn start_lost_and_no_transfer_are_warnings() {
        let mut u = unit(Model::Hpr130);
        u.advance(ms(3_000));
        u.set_start(ms(3_000), true);
        u.set_start(ms(3_200), false);
        assert_eq!(u.active_fault(), 31);
        assert_eq!(cmd(&mut u, ms(3_300), 131, "").unwrap(), ">1311C6<");
        assert_eq!(u.active_fault(), 0);
        u.advance(ms(6_000));
        u.config_mut().timings.transfer_delay = None;
        u.set_start(ms(6_000), true);
        u.advance(ms(7_000));
        assert_eq!(u.active_fault(), 21);
        assert_eq!(u.counters().start_errors, 1);
        assert!(!u.motion());
        // The 1 s HF burst is cut short by the 300 ms pilot time-out.
        assert_eq!(
            u.take_noise_bursts(),
            vec![(ms(6_500), Duration::from_millis(300))]
        );
        assert_eq!(
            cmd(&mut u, ms(7_100), 134, "").unwrap(),
            format!(
                ">134021 031 000 000{:02X}<",
                hpr_wire::checksum(b"134021 031 000 000")
            )
        );
    }

    #[test]
    fn shutdown_errors_need_a_software_reset() {
        let mut u = unit(Model::Hpr400);
        u.advance(ms(3_000));
        assert_eq!(cmd(&mut u, ms(3_000), 68, "").unwrap(), ">0680CE<");
        u.inject_fault(ms(3_100), 93);
        assert_eq!(u.state_code(), 14);
        u.set_start(ms(3_200), true);
        assert_eq!(u.state_code(), 14);
        u.set_start(ms(3_300), false);
        assert_eq!(
            cmd(&mut u, ms(3_400), 3, "").unwrap(),
            format!(">0030093{:02X}<", hpr_wire::checksum(b"0030093"))
        );
        assert_eq!(cmd(&mut u, ms(3_500), 68, "").unwrap(), ">0681CF<");
        assert_eq!(u.active_fault(), 0);
        u.advance(ms(7_000));
        assert_eq!(u.state_code(), 3);
    }

    #[test]
    fn blocking_errors_prevent_a_start() {
        let mut u = unit(Model::Hpr130);
        u.advance(ms(3_000));
        u.inject_fault(ms(3_000), 44);
        u.set_start(ms(3_100), true);
        assert_eq!(u.state_code(), 3);
    }

    #[test]
    fn sleep_and_wake_on_a_multi_drop_line() {
        let mut id0 = unit(Model::Hpr130);
        let mut config = HprConfig::for_model(Model::Hpr260);
        config.id = 2;
        let mut id2 = Hpr::new(config);
        // At power-up only id 0 talks.
        assert!(talk(&mut id0, ms(0), ">00090<").is_some());
        assert!(talk(&mut id2, ms(0), ">00090<").is_none());
        assert!(talk(&mut id2, ms(0), ">00091<").is_none()); // not even 500
        // SLEEP: no reply from anyone.
        for u in [&mut id0, &mut id2] {
            assert!(talk(u, ms(10), ">0869E<").is_none());
        }
        // WAKE 2: echoed by id 2 only.
        assert!(talk(&mut id0, ms(20), ">0852CF<").is_none());
        assert_eq!(talk(&mut id2, ms(20), ">0852CF<").unwrap(), ">0852CF<");
        assert!(talk(&mut id0, ms(30), ">00090<").is_none());
        assert!(talk(&mut id2, ms(30), ">00090<").unwrap().contains("260"));
        // SLEEP, WAKE 0.
        for u in [&mut id0, &mut id2] {
            talk(u, ms(40), ">0869E<");
        }
        assert_eq!(talk(&mut id0, ms(50), ">0850CD<").unwrap(), ">0850CD<");
        assert!(talk(&mut id2, ms(50), ">0850CD<").is_none());
        // Power cycle: id 2 asleep again, id 0 awake.
        id2.power_off(ms(60));
        id2.power_on(ms(70));
        assert!(!id2.is_awake());
    }

    #[test]
    fn broadcast_mode_listens_without_answering() {
        let mut u = unit(Model::Hpr130);
        assert!(cmd(&mut u, ms(0), 87, "").is_none());
        assert!(cmd(&mut u, ms(10), 4, "").is_none());
        assert!(u.in_remote_mode());
        assert_eq!(talk(&mut u, ms(20), ">0850CD<").unwrap(), ">0850CD<");
        assert!(cmd(&mut u, ms(30), 0, "").is_some());
    }

    #[test]
    fn remote_settings_on_an_auto_gas_hpr() {
        let mut u = unit(Model::Hpr130);
        u.advance(ms(3_000));
        // Refused before remote mode: the set value is unchanged.
        assert_eq!(
            cmd(&mut u, ms(3_000), 58, "100").unwrap(),
            format!(">0580130{:02X}<", hpr_wire::checksum(b"0580130"))
        );
        assert_eq!(talk(&mut u, ms(3_010), ">00494<").unwrap(), ">0041C5<");
        assert_eq!(
            talk(&mut u, ms(3_020), ">05813031<").unwrap(),
            ">058013061<"
        );
        // Limited to 130 A on an HPR130.
        assert_eq!(cmd(&mut u, ms(3_030), 58, "260").unwrap(), ">058013061<");
        assert_eq!(talk(&mut u, ms(3_040), ">0707503<").unwrap(), ">070007563<");
        assert_eq!(talk(&mut u, ms(3_050), ">097A0<").unwrap(), ">09700756C<");
        // All parameters (the guide's sample): O2 plasma, N2 shield -> purge.
        assert_eq!(
            talk(&mut u, ms(3_060), ">095100 75 1 6 55 45 35 25 00 0084<").unwrap(),
            ">0951CF<"
        );
        assert_eq!(u.nominal_amps(), 100);
        assert_eq!(u.gases(), (1, 6));
        assert_eq!(u.state_code(), 2);
        assert_eq!(
            talk(&mut u, ms(3_070), ">098A1<").unwrap(),
            ">0980001 000648<"
        );
        assert_eq!(
            talk(&mut u, ms(3_080), ">099A2<").unwrap(),
            format!(
                ">0990055 0045 0035 0025 0000 0000{:02X}<",
                hpr_wire::checksum(b"0990055 0045 0035 0025 0000 0000")
            )
        );
        // Inlet gases: same gases, no purge needed; invalid gas refused.
        u.advance(ms(6_000));
        assert_eq!(talk(&mut u, ms(6_000), ">0961 626<").unwrap(), ">0961D0<");
        assert_eq!(u.state_code(), 3);
        assert_eq!(cmd(&mut u, ms(6_010), 96, "9 6").unwrap(), ">0960CF<");
        // Not while cutting.
        u.set_start(ms(6_100), true);
        assert_eq!(cmd(&mut u, ms(6_200), 96, "5 5").unwrap(), ">0960CF<");
        assert_eq!(
            cmd(&mut u, ms(6_200), 95, "100 75 1 6 55 45 35 25 0 0").unwrap(),
            ">0950CE<"
        );
    }

    #[test]
    fn a_manual_gas_console_has_no_remote_gas_commands() {
        let mut config = HprConfig::for_model(Model::Hpr260);
        config.console = GasConsole::Manual;
        let mut u = Hpr::new(config);
        cmd(&mut u, ms(0), 4, "");
        assert_eq!(talk(&mut u, ms(10), ">05813031<").unwrap(), ">50196<");
        assert_eq!(talk(&mut u, ms(20), ">0961 626<").unwrap(), ">50196<");
        // Corner current and gas tests work.
        assert_eq!(talk(&mut u, ms(30), ">0707503<").unwrap(), ">070007563<");
        u.advance(ms(3_000));
        assert_eq!(talk(&mut u, ms(3_000), ">0649A<").unwrap(), ">0641CB<");
        assert_eq!(u.state_code(), 20);
        assert_eq!(talk(&mut u, ms(3_100), ">0659B<").unwrap(), ">0651CC<");
        assert_eq!(u.state_code(), 3);
    }

    #[test]
    fn maxpro_process_and_info() {
        let mut u = unit(Model::MaxPro200);
        cmd(&mut u, ms(0), 4, "");
        // Not in state 2 or 3 yet (power up).
        assert_eq!(talk(&mut u, ms(10), ">137200 5 5D7<").unwrap(), ">1372CD<");
        u.advance(ms(3_000));
        assert_eq!(
            talk(&mut u, ms(3_000), ">137200 5 5D7<").unwrap(),
            ">1371CC<"
        );
        assert_eq!(u.gases(), (5, 5));
        let info = cmd(&mut u, ms(3_010), 79, "").unwrap();
        assert!(info.starts_with(">079st0002 er0000 pg0005"), "{info}");
        assert!(info.contains("cs0200"));
        // HPR-only commands are unknown here.
        assert_eq!(cmd(&mut u, ms(3_020), 85, "0").unwrap(), ">50196<");
        assert_eq!(cmd(&mut u, ms(3_030), 125, "").unwrap(), ">50196<");
    }

    #[test]
    fn timer_counter_and_info_formats() {
        let mut u = unit(Model::Hpr130);
        let r = cmd(&mut u, ms(0), 125, "").unwrap();
        let data = "0000000 0000000 0000000 0000000 0000000 0000000 0000000 ";
        assert_eq!(
            r,
            format!(
                ">125{data}{:02X}<",
                hpr_wire::checksum(format!("125{data}").as_bytes())
            )
        );
        let info = cmd(&mut u, ms(10), 79, "").unwrap();
        assert!(
            info.starts_with(">079PC0055 PP0045 SC0035 SP0025 CS0130 ST0000 ER0000 "),
            "{info}"
        );
    }

    #[test]
    fn every_command_is_logged() {
        let mut u = unit(Model::Hpr130);
        cmd(&mut u, ms(0), 0, "");
        cmd(&mut u, ms(10), 120, "");
        assert_eq!(u.commands_received(), &[0, 120]);
    }

    #[test]
    fn a_unit_that_is_off_needs_no_wakeup_and_does_not_answer() {
        let mut u = unit(Model::Hpr130);
        u.power_off(ms(100));
        assert_eq!(u.next_wakeup(), None);
        assert!(talk(&mut u, ms(200), ">00090<").is_none());
        u.power_on(ms(300));
        assert_eq!(u.next_wakeup(), Some(ms(800)));
    }

    #[test]
    fn start_held_at_power_up_is_error_050() {
        let mut u = unit(Model::Hpr130);
        u.power_off(ms(0));
        u.set_start(ms(10), true);
        u.power_on(ms(20));
        assert_eq!(u.active_fault(), 50);
        u.advance(ms(3_000));
        u.set_start(ms(3_000), false);
        assert_eq!(u.active_fault(), 0);
    }
}
