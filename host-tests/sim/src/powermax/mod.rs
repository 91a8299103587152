//! The Powermax simulator shared by both families: Modbus ASCII server (node address and
//! address learning, response latency, exceptions), the arc sequence on the discrete Start /
//! Motion signals, the life counters, faults, remote mode and power cycling.
//!
//! The register maps live in [`super::sync`] (0x3xxx, SYNC only) and [`super::legacy`] (0x2xxx
//! and the 0x08xx coils, which SYNC units also answer).
//!
//! # Behaviour not stated by the manuals (choices of this model, each configurable or noted)
//! - Undocumented addresses inside a documented block (SYNC 0x3006-0x300F, 0x3013-0x3017,
//!   0x301B-0x3027, 0x303D-0x303F; legacy 0x2095, 0x2097, 0x209B; coils 0x080A-0x080F) read as
//!   0 or are refused with exception 02: [`UndocumentedAddresses`].
//! - A written value outside the permitted range is acknowledged and raises 0-11-0/1/2 (the
//!   legacy guide's example reads 0-11-1 "current setting value is out of range" after such a
//!   write), or is refused with exception 03: [`OutOfRange`].
//! - Entering remote mode (SYNC): a write that sets mode, current and pressure in one request
//!   enters it. A write that leaves one of the three out does not, and raises 0-11-n for the
//!   first register missing in the order mode (0-11-0), current (0-11-1), pressure (0-11-2):
//!   the guide's "to avoid 0-11-n faults, write all 3 registers in 1 request". Once in remote
//!   mode single registers may be written (legacy guide). Zero in all three exits.
//! - Entering remote mode (legacy): the three force registers are written with function 06,
//!   so the unit enters remote mode once all three have been written (legacy guide: "write to
//!   all three force registers together, once").
//! - 0x3080-0x3082, 0x308E/0x308F are write-only (reads: exception 02).
//! - The quick restart drops remote mode and the arc, keeps a learned address, clears 0-50-0 if
//!   a cartridge is installed, and leaves the unit deaf for [`PowermaxConfig::quick_restart_time`]
//!   counted from the end of the request.
//! - Power cycling clears the active fault (0-50-0 comes back without a cartridge, 0-51-0 with
//!   Start held on); an injected hardware fault must be injected again if it should persist.
//! - Actual current (0x3018) reads the set current while transferred and 0 otherwise; actual
//!   pressure reads the set (or automatic) pressure while gas flows and 0 otherwise; a gas
//!   supply below that pressure ([`Powermax::set_supply_psi`]) holds it at the supply's, as
//!   a compressor that cannot keep up does in the SYNC manual's gas test figure (Figure 16,
//!   "gas test to check air supply capacity").
//!
//! By job: `config` what makes a unit, `arc` the arc sequence, faults and counters, `remote`
//! remote mode and the quick restart, `server` the Modbus server; this file the unit's state
//! and its [`SimulatedUnit`] face.

use std::any::Any;
use std::collections::VecDeque;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

use super::clock::earliest;
use super::modbus_wire::Assembler;
use super::sync::Cartridge;
use super::{Family, Model, SimulatedUnit};

mod arc;
mod config;
mod remote;
mod server;

pub use config::{
    ArcState, ArcTimings, Counters, DeviceIdSupport, Limits, OutOfRange, PowermaxConfig, Process,
    UndocumentedAddresses,
};
pub(crate) use server::Cell;

/// A simulated Powermax (SYNC or legacy).
#[derive(Debug)]
pub struct Powermax {
    config: PowermaxConfig,
    rng: Xoshiro256PlusPlus,
    now: Instant,
    powered: bool,
    deaf_until: Instant,
    learned: Option<u8>,
    assembler: Assembler,
    outbox: VecDeque<(Instant, Vec<u8>)>,
    start_input: bool,
    arc: ArcState,
    arc_since: Instant,
    gas_test: bool,
    /// The inlet supply's pressure while gas flows, psi (`None`: ample).
    supply_psi: Option<u16>,
    fault: u16,
    counters: Counters,
    cartridge: Option<Cartridge>,
    panel: Process,
    force: Process,
    force_written: [bool; 3],
    remote: bool,
    requests: u64,
}

impl Powermax {
    /// A unit switched on at time zero.
    pub fn new(config: PowermaxConfig) -> Powermax {
        let sync = config.model.family() == Family::Sync;
        let cartridge = sync.then(|| Cartridge::default_for(config.model));
        let mut unit = Powermax {
            rng: Xoshiro256PlusPlus::seed_from_u64(config.seed),
            now: Instant::ZERO,
            powered: false,
            deaf_until: Instant::ZERO,
            learned: None,
            assembler: Assembler::default(),
            outbox: VecDeque::new(),
            start_input: false,
            arc: ArcState::Idle,
            arc_since: Instant::ZERO,
            gas_test: false,
            supply_psi: None,
            fault: 0,
            counters: Counters::default(),
            cartridge,
            panel: Process::default(),
            force: Process::default(),
            force_written: [false; 3],
            remote: false,
            requests: 0,
            config,
        };
        let limits = unit.limits();
        unit.panel = Process {
            mode: limits.modes.0,
            current: limits.current.1,
            pressure: 0,
        };
        unit.power_on(Instant::ZERO);
        unit
    }

    /// The configuration.
    pub fn config(&self) -> &PowermaxConfig {
        &self.config
    }

    /// Changes the configuration (takes effect for what happens next).
    pub fn config_mut(&mut self) -> &mut PowermaxConfig {
        &mut self.config
    }

    pub(crate) fn is_sync(&self) -> bool {
        self.config.model.family() == Family::Sync
    }

    /// The node address the unit answers to, if it has one (set, or learned).
    pub fn address(&self) -> Option<u8> {
        match self.config.address {
            0 => self.learned,
            a => Some(a),
        }
    }

    /// The settings the unit cuts with now (remote if in remote mode, else the front panel).
    pub fn settings(&self) -> Process {
        if !self.remote || !self.config.remote_settings_apply {
            return self.panel;
        }
        // On the way back to manual (legacy: one force register at a time), a register already
        // set to zero no longer overrides the panel.
        let or_panel = |forced: u16, panel: u16| if forced != 0 { forced } else { panel };
        Process {
            mode: or_panel(self.force.mode, self.panel.mode),
            current: or_panel(self.force.current, self.panel.current),
            pressure: self.force.pressure,
        }
    }

    /// The force registers as written (0x3080-0x3082 / 0x2093, 0x2094, 0x2096).
    pub fn force_registers(&self) -> Process {
        self.force
    }

    /// Pilot plus transferred arc time, whole seconds.
    pub fn total_arc_secs(&self) -> u64 {
        (self.counters.pilot.as_micros() + self.counters.transfer.as_micros()) / 1_000_000
    }

    /// Sets the front-panel settings (used outside remote mode).
    pub fn set_panel(&mut self, settings: Process) {
        self.panel = settings;
    }

    /// The life counters.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Sets the life counters (e.g. to test 32-bit word order).
    pub fn set_counters(&mut self, counters: Counters) {
        self.counters = counters;
    }

    /// Where the arc sequence is.
    pub fn arc_state(&self) -> ArcState {
        self.arc
    }

    /// True while a gas test runs.
    pub fn gas_test_active(&self) -> bool {
        self.gas_test
    }

    /// The gas supply delivers at most `psi` while gas flows (`None`: as much as the unit
    /// asks for): a weak compressor or a long, thin hose.
    pub fn set_supply_psi(&mut self, psi: Option<u16>) {
        self.supply_psi = psi;
    }

    /// The installed cartridge (SYNC).
    pub fn cartridge(&self) -> Option<&Cartridge> {
        self.cartridge.as_ref()
    }

    /// Mutable access to the installed cartridge (SYNC), e.g. to preset its counters.
    pub fn cartridge_mut(&mut self) -> Option<&mut Cartridge> {
        self.cartridge.as_mut()
    }

    /// Takes the cartridge off the torch: fault 0-50-0 (SYNC).
    pub fn remove_cartridge(&mut self, now: Instant) {
        self.advance(now);
        self.cartridge = None;
        self.raise(500);
    }

    /// Puts a cartridge on the torch. 0-50-0 stays until a quick restart or power cycle.
    pub fn install_cartridge(&mut self, now: Instant, cartridge: Cartridge) {
        self.advance(now);
        self.cartridge = Some(cartridge);
    }

    /// True while the unit ignores the line (booting or quick restart).
    pub fn is_deaf(&self, now: Instant) -> bool {
        !self.powered || now < self.deaf_until
    }

    /// Requests the unit has acted on since it was built.
    pub fn requests_handled(&self) -> u64 {
        self.requests
    }

    /// Permitted settings now (cartridge on SYNC, power supply on legacy units).
    pub fn limits(&self) -> Limits {
        if let (true, Some(c)) = (self.is_sync(), &self.cartridge) {
            let (lo, hi) = self.config.amps;
            Limits {
                modes: c.modes(self.config.model),
                current: (lo.max(c.min_amps) * 64, hi.min(c.nominal_amps) * 64),
                pressure: (c.psi.0 * 128, c.psi.1 * 128),
                auto_pressure: c.auto_psi * 128,
            }
        } else if self.is_sync() {
            // No cartridge: nothing is permitted.
            Limits {
                modes: (0, 0),
                current: (0, 0),
                pressure: (0, 0),
                auto_pressure: 0,
            }
        } else {
            Limits {
                modes: (1, 3),
                current: (self.config.amps.0 * 64, self.config.amps.1 * 64),
                pressure: (self.config.psi.0 * 128, self.config.psi.1 * 128),
                auto_pressure: self.config.auto_psi * 128,
            }
        }
    }

    /// Pressure the unit uses now, psi x 128 (the automatic value when set to 0).
    pub fn effective_pressure(&self) -> u16 {
        match self.settings().pressure {
            0 => self.limits().auto_pressure,
            p => p,
        }
    }

    pub(crate) fn actual_current(&self) -> u16 {
        if self.arc == ArcState::Transferred {
            self.settings().current
        } else {
            0
        }
    }

    pub(crate) fn actual_pressure(&self) -> u16 {
        if self.gas_test || self.arc != ArcState::Idle {
            let supply = self
                .supply_psi
                .map_or(u16::MAX, |psi| psi.saturating_mul(128));
            self.effective_pressure().min(supply)
        } else {
            0
        }
    }

    pub(crate) fn start_input(&self) -> bool {
        self.start_input
    }
}

impl SimulatedUnit for Powermax {
    fn model(&self) -> Model {
        self.config.model
    }

    fn port(&self) -> PortConfig {
        self.config.port
    }

    fn receive(&mut self, now: Instant, byte: u8) {
        self.advance(now);
        if self.is_deaf(now) {
            return;
        }
        if let Some((address, pdu)) = self.assembler.push(byte) {
            self.on_frame(now, address, &pdu);
        }
    }

    fn receive_error(&mut self, now: Instant) {
        self.advance(now);
        self.assembler.reset();
    }

    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        self.advance(now);
        match self.outbox.front() {
            Some(&(due, _)) if due <= now && self.powered => {
                self.outbox.pop_front().map(|(_, bytes)| bytes)
            }
            _ => None,
        }
    }

    fn next_wakeup(&self) -> Option<Instant> {
        if !self.powered {
            return None;
        }
        let reply = self.outbox.front().map(|&(due, _)| due);
        let deaf = (self.deaf_until > self.now).then_some(self.deaf_until);
        earliest(earliest(reply, self.arc_deadline()), deaf)
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
        let was = self.start_input;
        self.start_input = on;
        if !self.powered {
            return;
        }
        if on && !was && self.can_fire() {
            self.fire(now);
        } else if !on && was {
            if self.fault == 510 {
                self.fault = 0;
            }
            if matches!(self.arc, ArcState::Pilot | ArcState::Transferred) {
                self.enter(ArcState::Postflow, now);
            }
        }
    }

    fn motion(&self) -> bool {
        self.powered && self.arc == ArcState::Transferred
    }

    fn power_off(&mut self, now: Instant) {
        self.advance(now);
        self.powered = false;
        self.outbox.clear();
        self.assembler.reset();
        self.exit_remote();
        self.enter(ArcState::Idle, now);
        self.gas_test = false;
    }

    fn power_on(&mut self, now: Instant) {
        self.advance(now);
        if self.powered {
            return;
        }
        self.powered = true;
        self.learned = None;
        self.fault = 0;
        self.deaf_until = now + self.config.boot_time;
        if self.is_sync() && self.cartridge.is_none() {
            self.raise(500);
        }
        if self.start_input {
            self.raise(510);
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
        self.fault = 0;
    }

    fn active_fault(&self) -> u16 {
        self.fault
    }

    fn in_remote_mode(&self) -> bool {
        self.remote
    }

    fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)> {
        // Powermax units start the pilot arc by blowback, without HF ignition.
        Vec::new()
    }

    fn as_any(&self) -> &dyn Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

/// Test helpers shared by the SYNC and legacy tests: one request in, one reply out.
#[cfg(test)]
pub(crate) mod testing {
    use super::*;
    use crate::modbus_wire;

    /// Sends `frame` at `now` and returns the unit's reply (or None if it stays silent).
    pub fn exchange(unit: &mut Powermax, now: Instant, frame: &[u8]) -> Option<Vec<u8>> {
        for &b in frame {
            unit.receive(now, b);
        }
        let due = unit.outbox.back().map(|&(due, _)| due)?;
        let mut last = None;
        while let Some(bytes) = unit.poll_transmit(due) {
            last = Some(bytes);
        }
        last
    }

    /// A request frame for `address` and `pdu`.
    pub fn request(address: u8, pdu: &[u8]) -> Vec<u8> {
        modbus_wire::encode(address, pdu)
    }

    /// The PDU of a reply frame (checks the LRC).
    pub fn pdu(reply: &[u8]) -> Vec<u8> {
        assert!(
            reply.starts_with(b":") && reply.ends_with(b"\r\n"),
            "{reply:?}"
        );
        modbus_wire::decode(reply).expect("reply LRC").1
    }

    /// Reads `quantity` registers with function 04 and returns the values.
    pub fn read(unit: &mut Powermax, now: Instant, start: u16, quantity: u16) -> Vec<u16> {
        let mut p = vec![0x04];
        p.extend_from_slice(&start.to_be_bytes());
        p.extend_from_slice(&quantity.to_be_bytes());
        let address = unit.address().unwrap_or(1);
        let reply = pdu(&exchange(unit, now, &request(address, &p)).expect("reply"));
        assert_eq!(reply[0], 0x04, "exception {reply:02X?}");
        reply[2..]
            .chunks(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect()
    }

    /// Function 0x10 PDU.
    pub fn write_multiple_pdu(start: u16, values: &[u16]) -> Vec<u8> {
        let mut p = vec![0x10];
        p.extend_from_slice(&start.to_be_bytes());
        p.extend_from_slice(&(values.len() as u16).to_be_bytes());
        p.push((values.len() * 2) as u8);
        for v in values {
            p.extend_from_slice(&v.to_be_bytes());
        }
        p
    }
}
