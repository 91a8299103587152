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
//!   pressure reads the set (or automatic) pressure while gas flows and 0 otherwise.

use std::any::Any;
use std::collections::VecDeque;

use plasma_protocol::modbus_ascii::{DeviceIdCode, ExceptionCode, Request};
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::clock::{Accumulator, earliest};
use super::modbus_wire::{self, Assembler, Reply};
use super::sync::Cartridge;
use super::{Family, Model, SimulatedUnit, legacy, sync};

/// What a block read does with an undocumented address inside a documented block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UndocumentedAddresses {
    /// Reads as 0.
    Accept,
    /// The whole read is refused with exception 02 (illegal data address).
    Refuse,
}

/// What a write of an out-of-range setting does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutOfRange {
    /// Acknowledged; the setting is not applied and fault 0-11-0/1/2 is raised.
    Fault,
    /// Refused with exception 03 (illegal data value).
    Exception,
}

/// How a unit treats Read Device Identification (0x2B / 0x0E).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeviceIdSupport {
    /// Answers with its product code (SYNC guide Table 2).
    Answers,
    /// Refuses with exception 01.
    IllegalFunction,
    /// Does not answer at all.
    Silent,
}

/// Timing of the arc sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ArcTimings {
    /// Pilot arc to transfer (torch reaching the plate); `None`: never transfers.
    pub transfer_delay: Option<Duration>,
    /// A pilot arc that has not transferred goes out after this long.
    pub pilot_timeout: Duration,
    /// Gas keeps flowing this long after the arc.
    pub postflow: Duration,
}

impl Default for ArcTimings {
    fn default() -> Self {
        ArcTimings {
            transfer_delay: Some(Duration::from_millis(100)),
            pilot_timeout: Duration::from_secs(5),
            postflow: Duration::from_secs(10),
        }
    }
}

/// Everything that makes one simulated Powermax.
#[derive(Debug, Clone, PartialEq)]
pub struct PowermaxConfig {
    /// The model.
    pub model: Model,
    /// Node address setting, 0 = learn from the first valid request after power-up.
    pub address: u8,
    /// Serial settings (SYNC units can be set to odd / no parity and 2 stop bits).
    pub port: PortConfig,
    /// Time from the end of a request to the start of the reply.
    pub latency: Duration,
    /// Random extra latency, up to this much.
    pub latency_jitter: Duration,
    /// Block reads over undocumented addresses.
    pub undocumented: UndocumentedAddresses,
    /// Out-of-range setting writes.
    pub out_of_range: OutOfRange,
    /// Read Device Identification.
    pub device_id: DeviceIdSupport,
    /// Holding / input registers the unit refuses to read (a read touching one is refused
    /// whole with exception 02), as a unit might for write-only or unsupported registers.
    pub refused_registers: Vec<u16>,
    /// Remote settings take effect. `false` models a faulty unit that acknowledges the
    /// writes but keeps cutting with its panel settings, so that a read-back differs.
    pub remote_settings_apply: bool,
    /// Arc sequence timing.
    pub timings: ArcTimings,
    /// After power-on the unit ignores the line this long.
    pub boot_time: Duration,
    /// After a quick restart the unit ignores the line this long.
    pub quick_restart_time: Duration,
    /// Torch type / lead length id (SYNC guide Table 3): high byte of 0x3000, and the legacy
    /// lead-length coils.
    pub torch_id: u8,
    /// Power supply type id (SYNC guide Table 4): low byte of 0x3000.
    pub type_id: u8,
    /// Output current range of the power supply, amps.
    pub amps: (u16, u16),
    /// Permitted gas pressure, psi (legacy units; SYNC units take it from the cartridge).
    pub psi: (u16, u16),
    /// Pressure the unit picks in automatic mode, psi (legacy units).
    pub auto_psi: u16,
    /// PRNG seed (latency jitter).
    pub seed: u64,
}

impl PowermaxConfig {
    /// Defaults for `model` (a Powermax SYNC or legacy model).
    pub fn for_model(model: Model) -> PowermaxConfig {
        let sync = model.family() == Family::Sync;
        PowermaxConfig {
            model,
            address: 0,
            port: PortConfig::MODBUS_DEFAULT,
            latency: Duration::from_millis(3),
            latency_jitter: Duration::ZERO,
            undocumented: UndocumentedAddresses::Accept,
            out_of_range: OutOfRange::Fault,
            device_id: DeviceIdSupport::Answers,
            refused_registers: Vec::new(),
            remote_settings_apply: true,
            timings: ArcTimings::default(),
            boot_time: Duration::ZERO,
            quick_restart_time: Duration::from_secs(2),
            torch_id: 0x04,
            type_id: if sync { sync::type_id(model) } else { 0 },
            amps: if sync {
                sync::current_range(model)
            } else {
                legacy::current_range(model)
            },
            psi: (63, 78),
            auto_psi: 70,
            seed: 1,
        }
    }
}

/// Operating settings: mode, current (amps x 64), pressure (psi x 128, 0 = automatic).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Settings {
    /// Operating mode (SYNC: 1 cut, 2 expanded metal, 3 gouge; legacy: 1 normal, 2 CPA,
    /// 3 gouge).
    pub mode: u16,
    /// Current, amps x 64.
    pub current: u16,
    /// Pressure, psi x 128; 0 = automatic.
    pub pressure: u16,
}

/// Power supply life counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counters {
    /// Pilot arc starts.
    pub starts: u32,
    /// Pilot arc time.
    pub pilot: Accumulator,
    /// Arc transfers.
    pub transfers: u32,
    /// Transferred arc time.
    pub transfer: Accumulator,
}

/// Where the arc sequence is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArcState {
    /// No gas, no arc.
    Idle,
    /// Pilot arc.
    Pilot,
    /// Arc transferred to the work; Motion is on.
    Transferred,
    /// Gas postflow after the arc.
    Postflow,
}

/// Permitted settings, as the unit reports them (0x3001-0x3005, 0x2099-0x209D).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Lowest and highest permitted mode.
    pub modes: (u16, u16),
    /// Current range, amps x 64.
    pub current: (u16, u16),
    /// Pressure range, psi x 128.
    pub pressure: (u16, u16),
    /// Automatic pressure, psi x 128.
    pub auto_pressure: u16,
}

/// One read cell of a register or coil map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Cell {
    Value(u16),
    /// Undocumented address inside a documented block.
    Gap,
    /// Not an address of this unit.
    Unknown,
}

/// Faults that leave the unit able to fire (SYNC guide Table 6: "No" or "No, but recommended"
/// in "Steps required to remove?"; the legacy warnings 0-12-0 and 0-13-0 likewise).
fn fault_allows_start(code: u16) -> bool {
    matches!(
        code,
        0 | 110
            | 111
            | 112
            | 120
            | 121
            | 122
            | 123
            | 130
            | 141
            | 200
            | 321
            | 502
            | 503
            | 980
            | 981
            | 982
    )
}

fn is_setting_fault(code: u16) -> bool {
    matches!(code, 110..=112)
}

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
    fault: u16,
    counters: Counters,
    cartridge: Option<Cartridge>,
    panel: Settings,
    force: Settings,
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
            fault: 0,
            counters: Counters::default(),
            cartridge,
            panel: Settings::default(),
            force: Settings::default(),
            force_written: [false; 3],
            remote: false,
            requests: 0,
            config,
        };
        let limits = unit.limits();
        unit.panel = Settings {
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
    pub fn settings(&self) -> Settings {
        if !self.remote || !self.config.remote_settings_apply {
            return self.panel;
        }
        // On the way back to manual (legacy: one force register at a time), a register already
        // set to zero no longer overrides the panel.
        let or_panel = |forced: u16, panel: u16| if forced != 0 { forced } else { panel };
        Settings {
            mode: or_panel(self.force.mode, self.panel.mode),
            current: or_panel(self.force.current, self.panel.current),
            pressure: self.force.pressure,
        }
    }

    /// The force registers as written (0x3080-0x3082 / 0x2093, 0x2094, 0x2096).
    pub fn force_registers(&self) -> Settings {
        self.force
    }

    /// Pilot plus transferred arc time, whole seconds.
    pub fn total_arc_secs(&self) -> u64 {
        (self.counters.pilot.as_micros() + self.counters.transfer.as_micros()) / 1_000_000
    }

    /// Sets the front-panel settings (used outside remote mode).
    pub fn set_panel(&mut self, settings: Settings) {
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
            self.effective_pressure()
        } else {
            0
        }
    }

    pub(crate) fn start_input(&self) -> bool {
        self.start_input
    }

    fn raise(&mut self, code: u16) {
        if code == 0 {
            return;
        }
        if self.fault == 0 || is_setting_fault(self.fault) || !is_setting_fault(code) {
            self.fault = code;
        }
        if let Some(c) = &mut self.cartridge {
            c.log_fault(code);
        }
        if !fault_allows_start(code) && matches!(self.arc, ArcState::Pilot | ArcState::Transferred)
        {
            self.enter(ArcState::Postflow, self.now);
        }
    }

    fn enter(&mut self, state: ArcState, at: Instant) {
        self.arc = state;
        self.arc_since = at;
    }

    fn can_fire(&self) -> bool {
        self.powered
            && self.now >= self.deaf_until
            && fault_allows_start(self.fault)
            && !self.gas_test
            && matches!(self.arc, ArcState::Idle | ArcState::Postflow)
            && (!self.is_sync() || self.cartridge.is_some())
    }

    fn accrue(&mut self, until: Instant) {
        let d = until.saturating_since(self.now);
        match self.arc {
            ArcState::Pilot => {
                self.counters.pilot.add(d);
                if let Some(c) = &mut self.cartridge {
                    c.pilot.add(d);
                }
            }
            ArcState::Transferred => {
                self.counters.transfer.add(d);
                if let Some(c) = &mut self.cartridge {
                    c.transfer.add(d);
                }
            }
            _ => {}
        }
        self.now = self.now.max(until);
    }

    fn arc_deadline(&self) -> Option<Instant> {
        let t = &self.config.timings;
        match self.arc {
            ArcState::Pilot => {
                let timeout = self.arc_since + t.pilot_timeout;
                Some(match t.transfer_delay {
                    Some(d) if d < t.pilot_timeout => self.arc_since + d,
                    _ => timeout,
                })
            }
            ArcState::Postflow => Some(self.arc_since + t.postflow),
            _ => None,
        }
    }

    fn run_timers(&mut self, now: Instant) {
        while let Some(at) = self.arc_deadline().filter(|&at| at <= now) {
            self.accrue(at);
            match self.arc {
                ArcState::Pilot => {
                    let transfers = self
                        .config
                        .timings
                        .transfer_delay
                        .is_some_and(|d| d < self.config.timings.pilot_timeout);
                    if transfers {
                        self.counters.transfers = self.counters.transfers.wrapping_add(1);
                        if let Some(c) = &mut self.cartridge {
                            c.transfers = c.transfers.wrapping_add(1);
                        }
                        self.enter(ArcState::Transferred, at);
                    } else {
                        self.enter(ArcState::Postflow, at);
                    }
                }
                _ => self.enter(ArcState::Idle, at),
            }
        }
        self.accrue(now);
    }

    fn fire(&mut self, now: Instant) {
        self.counters.starts = self.counters.starts.wrapping_add(1);
        if let Some(c) = &mut self.cartridge {
            c.starts = c.starts.wrapping_add(1);
        }
        self.enter(ArcState::Pilot, now);
    }

    fn exit_remote(&mut self) {
        self.remote = false;
        self.force = Settings::default();
        self.force_written = [false; 3];
        if is_setting_fault(self.fault) {
            self.fault = 0;
        }
    }

    /// Quick restart (SYNC 0x308E/0x308F).
    pub(crate) fn quick_restart(&mut self, now: Instant) {
        self.exit_remote();
        self.accrue(now);
        self.enter(ArcState::Idle, now);
        self.gas_test = false;
        if self.fault == 500 && self.cartridge.is_some() {
            self.fault = 0;
        }
        self.deaf_until = now + self.config.quick_restart_time;
        self.assembler.reset();
    }

    /// Which setting fault a bad value at force-register `index` raises.
    fn setting_fault(index: usize) -> u16 {
        110 + index as u16
    }

    fn valid_setting(&self, index: usize, value: u16) -> bool {
        let l = self.limits();
        match index {
            0 => value >= l.modes.0 && value <= l.modes.1 && value != 0,
            1 => value >= l.current.0 && value <= l.current.1 && value != 0,
            _ => value == 0 || (value >= l.pressure.0 && value <= l.pressure.1),
        }
    }

    fn force_value_mut(&mut self, index: usize) -> &mut u16 {
        match index {
            0 => &mut self.force.mode,
            1 => &mut self.force.current,
            _ => &mut self.force.pressure,
        }
    }

    /// Writes to the force registers (index 0 mode, 1 current, 2 pressure) in one request.
    /// `one_request_enters`: SYNC rule (all three in one request) vs legacy (all three written).
    pub(crate) fn write_force(
        &mut self,
        writes: &[(usize, u16)],
        one_request_enters: bool,
    ) -> Result<(), ExceptionCode> {
        if self.config.out_of_range == OutOfRange::Exception
            && writes
                .iter()
                .any(|&(i, v)| v != 0 && !self.valid_setting(i, v))
        {
            return Err(ExceptionCode::IllegalDataValue);
        }
        let previous = self.force;
        for &(i, v) in writes {
            *self.force_value_mut(i) = v;
            self.force_written[i] = true;
        }
        if self.force == Settings::default() {
            self.exit_remote();
            return Ok(());
        }
        if !self.remote {
            let covered = |i: usize| writes.iter().any(|&(w, _)| w == i);
            let complete = if one_request_enters {
                (0..3).all(covered)
            } else {
                self.force_written.iter().all(|&w| w)
            };
            if !complete {
                if one_request_enters {
                    let missing = (0..3).find(|&i| !covered(i)).unwrap_or(0);
                    self.raise(Self::setting_fault(missing));
                    self.force = Settings::default();
                    self.force_written = [false; 3];
                }
                return Ok(());
            }
            let values = [self.force.mode, self.force.current, self.force.pressure];
            if let Some(bad) = (0..3).find(|&i| !self.valid_setting(i, values[i])) {
                self.raise(Self::setting_fault(bad));
                if one_request_enters {
                    // The request as a whole did not take.
                    self.force = Settings::default();
                    self.force_written = [false; 3];
                } else {
                    // The registers keep what was written; the bad one must be written again.
                    *self.force_value_mut(bad) = 0;
                    self.force_written[bad] = false;
                }
                return Ok(());
            }
            self.remote = true;
            if is_setting_fault(self.fault) {
                self.fault = 0;
            }
            return Ok(());
        }
        let mut bad = None;
        for &(i, v) in writes {
            // Zero is accepted on the way back to manual control.
            if v != 0 && !self.valid_setting(i, v) {
                let old = [previous.mode, previous.current, previous.pressure][i];
                *self.force_value_mut(i) = old;
                bad.get_or_insert(i);
            }
        }
        match bad {
            Some(i) => self.raise(Self::setting_fault(i)),
            None if is_setting_fault(self.fault) => self.fault = 0,
            None => {}
        }
        Ok(())
    }

    /// Gas test coil (SYNC 0x3180, old 0x0832).
    pub(crate) fn set_gas_test(&mut self, on: bool) {
        if !on {
            self.gas_test = false;
        } else if self.arc == ArcState::Idle && fault_allows_start(self.fault) {
            self.gas_test = true;
        }
    }

    fn read_block(
        &self,
        start: u16,
        quantity: u16,
        max: u16,
        lookup: impl Fn(&Self, u16) -> Cell,
    ) -> Result<Vec<u16>, ExceptionCode> {
        if quantity == 0 || quantity > max {
            return Err(ExceptionCode::IllegalDataValue);
        }
        let end = u32::from(start) + u32::from(quantity);
        if end > 0x1_0000 {
            return Err(ExceptionCode::IllegalDataAddress);
        }
        (start..=(end - 1) as u16)
            .map(|a| match lookup(self, a) {
                Cell::Value(v) => Ok(v),
                Cell::Gap if self.config.undocumented == UndocumentedAddresses::Accept => Ok(0),
                _ => Err(ExceptionCode::IllegalDataAddress),
            })
            .collect()
    }

    fn register(&self, address: u16) -> Cell {
        if self.config.refused_registers.contains(&address) {
            return Cell::Unknown;
        }
        match (self.is_sync(), address) {
            (true, 0x3000..=0x3FFF) => sync::register(self, address),
            (_, 0x2000..=0x2FFF) => legacy::register(self, address),
            _ => Cell::Unknown,
        }
    }

    fn coil(&self, address: u16) -> Cell {
        match (self.is_sync(), address) {
            (true, 0x3000..=0x3FFF) => sync::coil(self, address),
            _ => legacy::coil(self, address),
        }
    }

    /// Acts on one request addressed to this unit.
    fn handle(&mut self, now: Instant, request: &Request<'_>) -> Option<Reply> {
        use ExceptionCode::*;
        let function = request.function().to_u8();
        let refuse = |code| Some(Reply::exception(function, code));
        self.requests += 1;
        match *request {
            Request::ReadCoils { start, quantity } => {
                match self.read_block(start, quantity, 2000, Self::coil) {
                    Ok(bits) => {
                        let mut packed = vec![0u8; bits.len().div_ceil(8)];
                        for (i, b) in bits.iter().enumerate() {
                            if *b != 0 {
                                packed[i / 8] |= 1 << (i % 8);
                            }
                        }
                        Some(Reply::Coils(packed))
                    }
                    Err(code) => refuse(code),
                }
            }
            Request::ReadHoldingRegisters { start, quantity }
            | Request::ReadInputRegisters { start, quantity } => {
                match self.read_block(start, quantity, 125, Self::register) {
                    Ok(values) if function == 0x03 => Some(Reply::HoldingRegisters(values)),
                    Ok(values) => Some(Reply::InputRegisters(values)),
                    Err(code) => refuse(code),
                }
            }
            Request::WriteSingleCoil { address, on } => {
                let gas_test = address == 0x0832 || (self.is_sync() && address == 0x3180);
                if !gas_test {
                    return refuse(IllegalDataAddress);
                }
                self.set_gas_test(on);
                Some(Reply::WriteSingleCoil { address, on })
            }
            Request::WriteSingleRegister { address, value } => {
                let (index, one_request) = match (self.is_sync(), address) {
                    (true, 0x3080..=0x3082) => ((address - 0x3080) as usize, true),
                    // The old addresses take one register per request (function 06), so
                    // on every unit they follow the legacy rule.
                    (_, 0x2093 | 0x2094 | 0x2096) => {
                        (legacy::force_index(address).unwrap_or(0), false)
                    }
                    _ => return refuse(IllegalDataAddress),
                };
                match self.write_force(&[(index, value)], one_request) {
                    Ok(()) => Some(Reply::WriteSingleRegister { address, value }),
                    Err(code) => refuse(code),
                }
            }
            Request::WriteMultipleRegisters { start, values } => {
                let quantity = values.len() as u16;
                let words: Vec<u16> = values.iter().collect();
                let result = if self.is_sync() && (0x3080..=0x308F).contains(&start) {
                    sync::write_multiple(self, now, start, &words)
                } else if (0x2093..=0x2096).contains(&start) {
                    legacy::write_multiple(self, start, &words)
                } else {
                    Err(IllegalDataAddress)
                };
                match result {
                    Ok(()) => Some(Reply::WriteMultipleRegisters { start, quantity }),
                    Err(code) => refuse(code),
                }
            }
            Request::ReadDeviceIdentification { code, object_id } => match self.config.device_id {
                DeviceIdSupport::Silent => None,
                DeviceIdSupport::IllegalFunction => refuse(IllegalFunction),
                DeviceIdSupport::Answers => {
                    if code != DeviceIdCode::Specific {
                        return refuse(IllegalDataValue);
                    }
                    if object_id != 0x01 {
                        return refuse(IllegalDataAddress);
                    }
                    let product = if self.is_sync() {
                        sync::product_code(self.config.model)
                    } else {
                        legacy::product_code(self.config.model)
                    };
                    // Header as in the SYNC guide's example reply: conformity 0x81,
                    // next object id 0x01.
                    Some(Reply::DeviceIdentification {
                        code,
                        conformity: 0x81,
                        next_object_id: 0x01,
                        objects: vec![(0x01, product.as_bytes().to_vec())],
                    })
                }
            },
        }
    }

    fn on_frame(&mut self, now: Instant, address: u8, pdu: &[u8]) {
        let broadcast = address == 0;
        if !broadcast {
            match self.address() {
                None => self.learned = Some(address),
                Some(a) if a == address => {}
                Some(_) => return,
            }
        }
        let reply = match modbus_wire::parse_request(pdu) {
            Ok(request) => self.handle(now, &request),
            Err(refused) => Some(Reply::exception(refused.function, refused.code)),
        };
        if let (Some(reply), false) = (reply, broadcast) {
            let jitter = self.config.latency_jitter.as_micros();
            let extra = if jitter > 0 {
                self.rng.random_range(0..=jitter)
            } else {
                0
            };
            let due = now + self.config.latency + Duration::from_micros(extra);
            let bytes = modbus_wire::encode(address, &reply.to_pdu());
            self.outbox.push_back((due, bytes));
        }
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
