//! Several simulated units on one serial line (multi-drop): every unit hears the master, and
//! the units' transmitters share the pair that goes back to the master.
//!
//! # Who answers
//! Each unit decides for itself, as the manuals say, so a master that gets the addressing
//! wrong hears what it would hear on a real line:
//! - HPR: only id 0 powers up with its serial interface enabled; SLEEP (086) puts every unit
//!   to sleep, WAKE (085) with an id wakes that one (HPR manual, 002_72b43a5685974c77.txt,
//!   lines 107-109 and 172-173). A master that wakes a second unit without a SLEEP first has
//!   two units answering.
//! - The MaxPro200 has no WAKE or SLEEP (the command table gives 085-087 to the HPR systems
//!   only, same manual lines 172-174), so it answers every request: it cannot share a line.
//! - Powermax: each unit answers its own node address, 1-255; node 0 takes the address of the
//!   first request after power-up and is meant for a single unit (SYNC manual,
//!   000_dd931256418ae627.txt, lines 383-392): two such units both take it and both answer.
//!
//! [`units_for_one_line`] builds the units a configuration names, refusing a set the manuals
//! say cannot share a line; [`MultiDrop::new`] puts any units with the same serial settings on
//! one line, so the tests can also show what a wrong set does.
//!
//! # Collisions
//! The units' characters are laid on the line's timeline, one character time each (the
//! units' shared [`PortConfig`]). A character is handed to the line when its time comes. Where
//! it overlaps a character of another unit, the two drivers fight: the master's receiver
//! reads the bitwise AND of the characters (bits both drivers agree on survive, a bit they
//! fight over reads low), and a character that starts while another unit's is already on the
//! wire is lost into it. Each such character counts as a collision ([`MultiDrop::collisions`]).
//! A character already handed over when a later one starts over it stays as it was: the
//! master's view is right from the next character on.
//!
//! With a single unit nothing can collide and its transmissions are handed over whole, exactly
//! as the unit alone would send them.

use std::any::Any;
use std::collections::VecDeque;
use std::fmt;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};

use crate::clock::earliest;
use crate::{Family, Model, SimOptions, SimulatedUnit};

/// The most HPR / MaxPro200 units one line can address (ids 0-3, HPR manual lines 93-105).
pub const MAX_HPR_UNITS: usize = 4;

/// Why a set of units cannot share one line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineError {
    /// No unit at all.
    NoUnits,
    /// A Modbus unit (Powermax) and an HPR-protocol unit: different framing and protocol.
    MixedProtocols(Model, Model),
    /// A MaxPro200 with other units: it has no WAKE / SLEEP, so it answers everything.
    NoMultiDrop(Model),
    /// An HPR id above 3 (ids are 0-3).
    IdOutOfRange(u16),
    /// Several Powermax units with node 0 (learn from the first request): single unit only.
    LearnedNodeShared,
    /// A Powermax node address above 255.
    NodeOutOfRange(u16),
    /// Units with different serial settings on one pair.
    PortsDiffer(PortConfig, PortConfig),
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LineError::NoUnits => f.write_str("a line needs at least one unit"),
            LineError::MixedProtocols(a, b) => write!(
                f,
                "{a} and {b} cannot share a line: a Powermax speaks Modbus ASCII, an HPR or \
                 MaxPro200 its own protocol"
            ),
            LineError::NoMultiDrop(model) => write!(
                f,
                "a {model} cannot share a line: it has no WAKE/SLEEP (085/086), so it answers \
                 every request"
            ),
            LineError::IdOutOfRange(id) => write!(
                f,
                "HPR id {id} does not exist: ids are 0-3, so at most {MAX_HPR_UNITS} units \
                 from id 0"
            ),
            LineError::LearnedNodeShared => f.write_str(
                "node address 0 (taken from the first request) is for a single Powermax: \
                 give several units a node address, 1-255",
            ),
            LineError::NodeOutOfRange(node) => write!(
                f,
                "node address {node} does not exist: Powermax node addresses are 1-255"
            ),
            LineError::PortsDiffer(a, b) => write!(
                f,
                "units set to different serial settings ({a:?} and {b:?}) cannot share a line"
            ),
        }
    }
}

impl std::error::Error for LineError {}

/// Builds `models` for one line, in order: HPRs take ids from `options.hpr_id` on (0, 1, ...),
/// Powermax units node addresses from `options.modbus_address` on; each unit's response-time
/// jitter gets its own seed. A single unit is built exactly as [`Model::build`] does.
pub fn units_for_one_line(
    models: &[Model],
    options: &SimOptions,
) -> Result<Vec<Box<dyn SimulatedUnit>>, LineError> {
    let Some(&first) = models.first() else {
        return Err(LineError::NoUnits);
    };
    let several = models.len() > 1;
    let modbus = |m: Model| m.family() != Family::Hpr;
    if let Some(&other) = models.iter().find(|&&m| modbus(m) != modbus(first)) {
        return Err(LineError::MixedProtocols(first, other));
    }
    if several && models.contains(&Model::MaxPro200) {
        return Err(LineError::NoMultiDrop(Model::MaxPro200));
    }
    let mut units = Vec::with_capacity(models.len());
    for (index, &model) in models.iter().enumerate() {
        let offset = index as u16;
        let mut unit_options = SimOptions {
            seed: options.seed.wrapping_add(u64::from(offset)),
            ..*options
        };
        if modbus(model) {
            if several && options.modbus_address == 0 {
                return Err(LineError::LearnedNodeShared);
            }
            let node = u16::from(options.modbus_address) + offset;
            unit_options.modbus_address =
                u8::try_from(node).map_err(|_| LineError::NodeOutOfRange(node))?;
        } else {
            let id = u16::from(options.hpr_id) + offset;
            if id >= MAX_HPR_UNITS as u16 {
                return Err(LineError::IdOutOfRange(id));
            }
            unit_options.hpr_id = id as u8;
        }
        units.push(model.build(&unit_options));
    }
    Ok(units)
}

/// One character of one unit on the line's timeline.
#[derive(Debug, Clone, Copy)]
struct Character {
    unit: usize,
    begin_ns: u64,
    end_ns: u64,
    byte: u8,
    fate: Fate,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Fate {
    /// Its time has not come.
    Waiting,
    /// Handed to the line.
    Sent,
    /// Started while another unit's character was on the wire.
    Lost,
}

/// A transmission one unit started, as that unit sent it (for logs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transmission {
    /// The unit's index on the line.
    pub unit: usize,
    /// When its first character started.
    pub at: Instant,
    /// What the unit sent.
    pub bytes: Vec<u8>,
}

/// Several units sharing one line. See the [module docs](self).
pub struct MultiDrop {
    units: Vec<Box<dyn SimulatedUnit>>,
    port: PortConfig,
    /// Units cut off the line: they hear nothing and what they send is lost.
    disconnected: Vec<bool>,
    /// Characters not yet handed over, and handed-over ones that may still overlap a later
    /// character; in order of start.
    timeline: Vec<Character>,
    /// Per unit: when its last queued character ends.
    busy_until_ns: Vec<u64>,
    /// When the last character handed to the line ends.
    wire_until_ns: u64,
    /// The latest transmissions, for [`take_transmissions`](MultiDrop::take_transmissions).
    transmissions: VecDeque<Transmission>,
    collisions: u64,
}

/// Transmissions kept for a caller that does not take them.
const KEPT_TRANSMISSIONS: usize = 64;

fn ns(t: Instant) -> u64 {
    t.as_micros().saturating_mul(1000)
}

fn instant_from_ns(t: u64) -> Instant {
    Instant::from_micros(t.div_ceil(1000))
}

impl MultiDrop {
    /// `units` on one line, in order (index 0 first); they must share their serial settings.
    pub fn new(units: Vec<Box<dyn SimulatedUnit>>) -> Result<MultiDrop, LineError> {
        let port = units.first().ok_or(LineError::NoUnits)?.port();
        if let Some(other) = units.iter().map(|u| u.port()).find(|&p| p != port) {
            return Err(LineError::PortsDiffer(port, other));
        }
        let count = units.len();
        Ok(MultiDrop {
            units,
            port,
            disconnected: vec![false; count],
            timeline: Vec::new(),
            busy_until_ns: vec![0; count],
            wire_until_ns: 0,
            transmissions: VecDeque::new(),
            collisions: 0,
        })
    }

    /// Unit 0 (a line is built with at least one unit).
    fn first(&self) -> &dyn SimulatedUnit {
        &**self
            .units
            .first()
            .expect("MultiDrop::new refuses a line without units")
    }

    fn first_mut(&mut self) -> &mut dyn SimulatedUnit {
        &mut **self
            .units
            .first_mut()
            .expect("MultiDrop::new refuses a line without units")
    }

    /// The serial settings every unit on the line has.
    pub fn port(&self) -> PortConfig {
        self.port
    }

    /// How many units share the line.
    pub fn len(&self) -> usize {
        self.units.len()
    }

    /// Always false: a line has at least one unit.
    pub fn is_empty(&self) -> bool {
        self.units.is_empty()
    }

    /// Unit `index` (0 = the first).
    pub fn unit(&self, index: usize) -> Option<&dyn SimulatedUnit> {
        self.units.get(index).map(|u| &**u)
    }

    /// Unit `index`, to drive its inputs, faults and power.
    pub fn unit_mut(&mut self, index: usize) -> Option<&mut (dyn SimulatedUnit + 'static)> {
        self.units.get_mut(index).map(|u| &mut **u)
    }

    /// Cuts unit `index`'s drop (`false`) or mends it: a cut unit keeps its state, hears
    /// nothing and what it sends is lost.
    pub fn set_connected(&mut self, index: usize, connected: bool) {
        if let Some(cut) = self.disconnected.get_mut(index) {
            *cut = !connected;
        }
    }

    /// True unless unit `index`'s drop is cut.
    pub fn is_connected(&self, index: usize) -> bool {
        self.disconnected.get(index).is_some_and(|cut| !cut)
    }

    /// Characters garbled or lost so far because two units drove the line at once.
    pub fn collisions(&self) -> u64 {
        self.collisions
    }

    /// The transmissions the units started since the last call (at most the latest 64), as
    /// each unit sent them.
    pub fn take_transmissions(&mut self) -> Vec<Transmission> {
        self.transmissions.drain(..).collect()
    }

    /// A character from the master arrived at `now`: every connected unit hears it.
    pub fn receive(&mut self, now: Instant, byte: u8) {
        for (unit, cut) in self.units.iter_mut().zip(&self.disconnected) {
            if !cut {
                unit.receive(now, byte);
            }
        }
    }

    /// A character from the master arrived with a parity or framing error at `now`.
    pub fn receive_error(&mut self, now: Instant) {
        for (unit, cut) in self.units.iter_mut().zip(&self.disconnected) {
            if !cut {
                unit.receive_error(now);
            }
        }
    }

    /// Runs every unit's timers up to `now`.
    pub fn advance(&mut self, now: Instant) {
        for unit in &mut self.units {
            unit.advance(now);
        }
    }

    /// When a unit or a character on the timeline next needs [`poll_transmit`](Self::poll_transmit).
    pub fn next_wakeup(&self) -> Option<Instant> {
        let units = self
            .units
            .iter()
            .map(|u| u.next_wakeup())
            .fold(None, earliest);
        let character = self
            .timeline
            .iter()
            .find(|c| c.fate == Fate::Waiting)
            .map(|c| instant_from_ns(c.begin_ns));
        earliest(units, character)
    }

    /// The electrical noise the units made since the last call (start, length).
    pub fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)> {
        self.units
            .iter_mut()
            .flat_map(|u| u.take_noise_bursts())
            .collect()
    }

    /// The characters the line carries from `now` on, if any started by `now`.
    ///
    /// A caller that comes late (a real-time loop on a loaded machine) changes nothing: each
    /// unit's transmission is laid on the timeline at the moment the unit asked for, so two
    /// replies due 4 ms apart overlap however late the call.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        let mut caught_up: Option<Instant> = None;
        while let Some(due) = self
            .units
            .iter()
            .filter_map(|u| u.next_wakeup())
            .filter(|&t| t <= now && caught_up.is_none_or(|done| t > done))
            .min()
        {
            self.lay_due(due);
            caught_up = Some(due);
        }
        self.lay_due(now);
        let now_ns = ns(now);
        let lone = self.units.len() == 1;
        let mut out = Vec::new();
        for i in 0..self.timeline.len() {
            let c = self.timeline[i];
            if c.fate != Fate::Waiting || (c.begin_ns > now_ns && !lone) {
                continue;
            }
            if c.begin_ns < self.wire_until_ns {
                self.timeline[i].fate = Fate::Lost;
                self.collisions += 1;
                continue;
            }
            let overlapping = self
                .timeline
                .iter()
                .filter(|o| o.unit != c.unit && o.begin_ns < c.end_ns && c.begin_ns < o.end_ns);
            let mut byte = c.byte;
            let mut collided = false;
            for o in overlapping {
                byte &= o.byte;
                collided = true;
            }
            if collided {
                self.collisions += 1;
            }
            self.timeline[i].fate = Fate::Sent;
            self.wire_until_ns = c.end_ns;
            out.push(byte);
        }
        // Nothing that starts from now on can overlap a character that has ended.
        self.timeline
            .retain(|c| c.fate == Fate::Waiting || c.end_ns > now_ns);
        (!out.is_empty()).then_some(out)
    }

    /// Lays what each connected unit sends at `at`.
    fn lay_due(&mut self, at: Instant) {
        for index in 0..self.units.len() {
            while let Some(bytes) = self.units[index].poll_transmit(at) {
                if !self.disconnected[index] {
                    self.lay(index, ns(at), bytes);
                }
            }
        }
    }

    /// Puts unit `index`'s `bytes` on the timeline from `now_ns` (or after its own last
    /// character), keeping the timeline in order of start.
    fn lay(&mut self, index: usize, now_ns: u64, bytes: Vec<u8>) {
        let char_ns = self.port.char_time_ns();
        let start = now_ns.max(self.busy_until_ns[index]);
        for (k, &byte) in bytes.iter().enumerate() {
            let begin_ns = start + k as u64 * char_ns;
            let c = Character {
                unit: index,
                begin_ns,
                end_ns: begin_ns + char_ns,
                byte,
                fate: Fate::Waiting,
            };
            let at = self
                .timeline
                .partition_point(|o| (o.begin_ns, o.unit) <= (c.begin_ns, c.unit));
            self.timeline.insert(at, c);
        }
        self.busy_until_ns[index] = start + bytes.len() as u64 * char_ns;
        if self.transmissions.len() == KEPT_TRANSMISSIONS {
            self.transmissions.pop_front();
        }
        self.transmissions.push_back(Transmission {
            unit: index,
            at: instant_from_ns(start),
            bytes,
        });
    }
}

/// The line as one unit, for a port loop that drives one: the traffic is every unit's; the
/// discrete I/O, power and faults of the trait are unit 0's (reach the others with
/// [`MultiDrop::unit_mut`]). Downcasts (`as_any`) to the [`MultiDrop`].
impl SimulatedUnit for MultiDrop {
    fn model(&self) -> Model {
        self.first().model()
    }
    fn port(&self) -> PortConfig {
        MultiDrop::port(self)
    }
    fn receive(&mut self, now: Instant, byte: u8) {
        MultiDrop::receive(self, now, byte);
    }
    fn receive_error(&mut self, now: Instant) {
        MultiDrop::receive_error(self, now);
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        MultiDrop::poll_transmit(self, now)
    }
    fn next_wakeup(&self) -> Option<Instant> {
        MultiDrop::next_wakeup(self)
    }
    fn advance(&mut self, now: Instant) {
        MultiDrop::advance(self, now);
    }
    fn set_start(&mut self, now: Instant, on: bool) {
        self.first_mut().set_start(now, on);
    }
    fn motion(&self) -> bool {
        self.first().motion()
    }
    fn power_off(&mut self, now: Instant) {
        self.first_mut().power_off(now);
    }
    fn power_on(&mut self, now: Instant) {
        self.first_mut().power_on(now);
    }
    fn is_powered(&self) -> bool {
        self.first().is_powered()
    }
    fn inject_fault(&mut self, now: Instant, code: u16) {
        self.first_mut().inject_fault(now, code);
    }
    fn clear_fault(&mut self, now: Instant) {
        self.first_mut().clear_fault(now);
    }
    fn active_fault(&self) -> u16 {
        self.first().active_fault()
    }
    fn in_remote_mode(&self) -> bool {
        self.first().in_remote_mode()
    }
    fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)> {
        MultiDrop::take_noise_bursts(self)
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

impl fmt::Debug for MultiDrop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MultiDrop")
            .field(
                "units",
                &self.units.iter().map(|u| u.model()).collect::<Vec<_>>(),
            )
            .field("port", &self.port)
            .field("collisions", &self.collisions)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests;
