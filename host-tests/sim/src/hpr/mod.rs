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
//! - MaxPro200 143 SET TEST MODE 1 (Test Gas, state 3 only) and 0; the gases flow (079 display
//!   mode 3), no start is taken until mode 0 or a software reset ends it.
//! - Settings: 004 remote mode, 058 nominal amps (clamped to 5..=130/260/400/200 and echoed),
//!   070 corner current (50-100 %), 078 all gas flows, 095 all parameters, 096 inlet gases (a change of gas purges;
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
//! 133, 135, 139-142, 144, 146, 147) answer 501 (145 READ TORCH ID gives the configured
//! torch). A manual gas console answers 501 to what its "System" column leaves out (058,
//! 078, 095, 096, 099) and 122 gives its knobs' positions.
//!
//! By job: `config` what makes a unit, `sequence` the arc sequence and errors, `commands` the
//! serial command table; this file the unit's state and its [`SimulatedUnit`] face.

use std::any::Any;
use std::collections::VecDeque;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

use super::clock::earliest;
use super::hpr_wire::Assembler;
use super::{Model, SimulatedUnit};

mod commands;
mod config;
mod sequence;
#[cfg(test)]
mod tests;

pub use config::{GasConsole, HprConfig, HprCounters, HprTimings, Phase};

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
    /// MaxPro200 143 test mode 1 (Test Gas): the gases flow, no start.
    test_gas: bool,
    amps: u16,
    corner_pct: u16,
    gases: (u16, u16),
    /// Plasma cutflow, plasma preflow, shield cutflow, shield preflow, N2 mix, gas 2 mix (psi).
    flows: [u16; 6],
    /// The inlet supply's pressure, psi (`None`: ample); the measured pressures (079, 094,
    /// 141) stay below it.
    supply_psi: Option<u16>,
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
            test_gas: false,
            amps: max,
            corner_pct: 100,
            gases: (1, 5),
            flows: [55, 45, 35, 25, 0, 0],
            supply_psi: None,
            counters: HprCounters::default(),
            noise: Vec::new(),
            received: Vec::new(),
            config,
        };
        unit.power_on(Instant::ZERO);
        unit
    }

    /// The gas supply delivers at most `psi` (`None`: as much as the unit asks for): the
    /// measured pressures of 079, 094 and the MaxPro200's 141 (HPR manual lines 168, 177,
    /// 281) stay below it.
    pub fn set_supply_psi(&mut self, psi: Option<u16>) {
        self.supply_psi = psi;
    }

    /// A channel's measured pressure: its set point, held below the supply's.
    pub(super) fn measured_psi(&self, set: u16) -> u16 {
        set.min(self.supply_psi.unwrap_or(u16::MAX))
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

    /// True while a MaxPro200's 143 Test Gas runs.
    pub fn test_gas(&self) -> bool {
        self.test_gas
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
            if self.phase == Phase::Ready && !self.error_blocks_start() && !self.test_gas {
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
        self.test_gas = false;
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
