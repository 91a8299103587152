//! Several units on one line: a sans-IO arbiter that owns one [`PsLink`] per unit and gives
//! the line to one of them at a time.
//!
//! [`SharedLine`] has the port-facing entry points of a single link (`handle_rx`,
//! `handle_rx_error`, `poll_transmit`, `handle_transmitted`, `port_config`, `poll_at`), so a
//! port loop drives it as it drives one link. Each unit's link runs unchanged: its own
//! detection, polls, commands, time-outs and link-down.
//!
//! # Turns
//! - The line goes to one unit at a time for one attempt: its request and the reply (or the
//!   time-out). Then the next unit in turn that has something due gets it (round robin from
//!   the unit after the last one), so a unit waits for at most one attempt of each other
//!   unit; a unit with nothing due is passed over, and one alone with work keeps the line.
//! - Replies go to the unit whose attempt is on the wire. Bytes between turns go to the last
//!   unit that had the line, which counts them as a single link would.
//! - A unit waiting for its turn is not called: its reply time-out runs only for an attempt
//!   that went out, so waiting never counts as silence, and a poll or retry that falls due
//!   meanwhile simply goes out at its turn (a retry later than its schedule still rides
//!   through an HF-ignition blackout). A unit that does not answer costs one reply time-out
//!   per turn: the others each wait one time-out per round at most.
//! - Turns are kept short: with more than one unit, each link is told it shares the line
//!   (an HPR's poll is then mostly the short fault read 003, the full 079 one poll in
//!   `SHARED_LINE_FULL_POLL_EVERY`), and its due poll goes before its slow data.
//! - One long attempt per round: a full poll or one slow-data read (version, error log,
//!   timers, gases) goes out only once as many turns as there are units went by since the
//!   last one, or when nothing else is due. The slow read follows its unit's answered poll
//!   at once, in the same turn (no switch); a unit that stopped answering gets no such
//!   second attempt.
//!
//! So with `n` idle HPRs (START off, not cutting) a unit's two fault reads are at most
//! `n` x (switch + fault read) + one long attempt apart (switch: SLEEP, WAKE and its echo;
//! long: 079 or a slow read, up to about 97 characters with the answer): four HPR260s at
//! 19200 baud, each answering within 7 ms, about 200 ms; a silent unit's turn costs a switch
//! and one reply time-out instead of its fault read. From START on and while cutting a
//! unit's every poll is the full one.
//!
//! # HF ignition
//! An HPR in pilot arc fires its HF ignition, and the manual has serial traffic stop for it
//! (up to 1 s, HPR manual section VIII). On a shared line that noise is on every drop, so
//! while any unit's link keeps its pilot-arc pause nothing at all goes out. A unit's state
//! is polled in full at every turn from its START on ([`SharedLine::set_start`], which the
//! bridge calls from the unit's discrete outputs), so its pilot arc is read at its next turn
//! rather than at the next full poll; a pilot arc shorter than a round of turns can still
//! pass unseen, as one shorter than the poll interval does on a line of its own.
//!
//! # Switching an HPR line
//! HPR units share the line by SLEEP / WAKE ([`switch`]): before a unit that is not the one
//! awake sends a request, SLEEP (unless no unit is awake) and WAKE with its id go out, and
//! the WAKE's echo is awaited. So a round of turns costs one switch per unit that changes
//! hands, none while one unit keeps the line. (Starting each round with the unit already
//! awake would save one switch a round, but that unit then has two turns in a row and every
//! other unit waits one more attempt: worse for fault latency than the switch it saves.)
//! A WAKE nobody echoes costs the waiting unit's attempt: its time-out runs from the WAKE,
//! and the line state is unknown again (a SLEEP goes first next time). A unit's own SLEEP and
//! WAKE (its detection sends them) go out as they are, a SLEEP before its WAKE if another
//! unit may be awake. On a line that echoes our own frames (2-wire, receiver on), told by a
//! copy of the SLEEP nobody answers, the unit's WAKE echo is the second copy; every unit's
//! link is told the line echoes. Powermax units share by node address: no switching.
//!
//! ```
//! use plasma_firmware::link::{LinkConfig, LineUnit, SharedLine};
//! use plasma_protocol::time::Instant;
//!
//! let units = [LineUnit::Hpr { id: 0 }, LineUnit::Hpr { id: 1 }];
//! let mut line = SharedLine::new(LinkConfig::default(), &units, Instant::ZERO).unwrap();
//! // Any unit may be awake at power-up: SLEEP first, then WAKE 0.
//! assert_eq!(line.poll_transmit(Instant::ZERO).unwrap(), b">0869E<");
//! line.handle_transmitted(Instant::from_millis(4));
//! // WAKE 0 as soon as the SLEEP has left the wire.
//! assert_eq!(line.poll_transmit(Instant::from_millis(4)).unwrap(), b">0850CD<");
//! ```

mod config;
mod links;
mod switch;
mod turn;

#[cfg(test)]
mod tests;

use heapless::Vec;
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

use crate::link::{LinkConfig, LinkEvent, PowermaxProcess, PsLink};
pub use config::{LineError, LineUnit, MAX_UNITS, NamedUnits, UnitsError};
use links::{Links, Making};
use switch::{Awake, CONTROL_CAPACITY, Switch, SwitchOut, emit_control};

/// Counters of the arbiter's own traffic.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LineStats {
    /// SLEEP frames the arbiter sent (the units' own not counted).
    pub sleeps: u32,
    /// WAKE frames the arbiter sent: hand-overs of the line.
    pub wakes: u32,
    /// WAKEs nobody echoed.
    pub unanswered_wakes: u32,
    /// Characters heard while the line was being switched, outside a WAKE echo.
    pub stray: u32,
}

/// What the arbiter handed out last.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Out {
    Control,
    Unit,
}

/// Up to [`MAX_UNITS`] units on one line. See the [module docs](self).
#[derive(Debug)]
pub struct SharedLine {
    links: Links,
    units: Vec<LineUnit, MAX_UNITS>,
    /// The unit whose attempt is on the wire, or that had the line last.
    owner: usize,
    /// An HPR line: units share it by SLEEP / WAKE.
    switching: bool,
    awake: Awake,
    /// The line echoes our own frames: heard by a switch (a copy of its SLEEP) or a link.
    line_echoes: bool,
    switch: Option<Switch>,
    out: Option<Out>,
    control: [u8; CONTROL_CAPACITY],
    control_len: usize,
    /// Unit turns since the last long attempt went out (a full status poll, HPR 079, or
    /// slow data): the next is allowed after a turn of every unit, so at most one goes out
    /// per round.
    turns_since_long: usize,
    /// The HF-ignition quiet the line keeps, as of the last [`SharedLine::poll_transmit`].
    quiet_until: Option<Instant>,
    stats: LineStats,
}

impl SharedLine {
    /// `units` on one line, in order (unit 0 first), each with `base` for its link settings
    /// and its own protocol and address; they start detecting at `now`. Refused when the units
    /// cannot share a line.
    pub fn new(base: LinkConfig, units: &[LineUnit], now: Instant) -> Result<Self, LineError> {
        config::link_configs(base, units)?;
        let mut line = SharedLine::alone(base, None, now);
        line.rebuild(base, units, None, now)?;
        Ok(line)
    }

    /// One unit alone, `base` as it is (auto-detected), restoring `process`: a line's storage
    /// with its first link only, built as one expression so that the board's bridge is built
    /// in its static slot ([`SharedLine::rebuild`] fills the others in place).
    pub(crate) fn alone(base: LinkConfig, process: Option<PowermaxProcess>, now: Instant) -> Self {
        SharedLine {
            links: Links::alone(Making::first_alone(base, process, now)),
            units: Vec::new(),
            owner: 0,
            switching: false,
            awake: Awake::Unknown,
            line_echoes: false,
            switch: None,
            out: None,
            control: [0; CONTROL_CAPACITY],
            control_len: 0,
            turns_since_long: usize::MAX,
            quiet_until: None,
            stats: LineStats::default(),
        }
    }

    /// In place, `units` (none: one unit alone with `base` as it is) start afresh at `now`,
    /// the first restoring `process`: one link is built at a time, never the whole line, so
    /// that a bridge on a small stack can change its units. Refused (nothing changes) when
    /// they cannot share a line.
    pub(crate) fn rebuild(
        &mut self,
        base: LinkConfig,
        units: &[LineUnit],
        process: Option<PowermaxProcess>,
        now: Instant,
    ) -> Result<(), LineError> {
        let configs = match units.is_empty() {
            true => None,
            false => Some(config::link_configs(base, units)?),
        };
        let configs = configs.as_deref().unwrap_or(core::slice::from_ref(&base));
        self.links.refill(Making {
            base,
            configs,
            process,
            now,
        });
        self.units.clear();
        for unit in units {
            // At most MAX_UNITS: checked with the configurations.
            let _ = self.units.push(*unit);
        }
        self.owner = units.len().saturating_sub(1);
        self.switching =
            !units.is_empty() && units.iter().all(|u| matches!(u, LineUnit::Hpr { .. }));
        self.awake = Awake::Unknown;
        self.line_echoes = false;
        self.switch = None;
        self.out = None;
        self.control_len = 0;
        self.turns_since_long = usize::MAX;
        self.quiet_until = None;
        self.stats = LineStats::default();
        Ok(())
    }

    /// The first unit's link, to be driven as a link alone.
    pub(crate) fn first_mut(&mut self) -> &mut PsLink {
        self.links.get_or_first_mut(0)
    }

    /// How many units share the line.
    pub fn len(&self) -> usize {
        self.links.len()
    }

    /// Always false: a line has at least one unit.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The first unit's link (a line always has one).
    pub fn first(&self) -> &PsLink {
        self.links.first()
    }

    /// Unit `index`'s link, or the first unit's for an index out of range.
    pub fn unit_or_first_mut(&mut self, index: usize) -> &mut PsLink {
        self.links.get_or_first_mut(index)
    }

    /// Every unit takes `base` for its link settings, each with its own protocol and
    /// address (see [`PsLink::reconfigure`]).
    pub fn reconfigure(&mut self, now: Instant, base: LinkConfig) {
        for (unit, link) in self.units.iter().zip(self.links.iter_mut()) {
            link.reconfigure(now, unit.link_config(base));
        }
        self.switch = None;
        self.awake = Awake::Unknown;
        self.out = None;
    }

    /// Unit `index`'s link (0 = the first unit).
    pub fn unit(&self, index: usize) -> Option<&PsLink> {
        self.links.get(index)
    }

    /// Unit `index`'s link, for its commands and events.
    pub fn unit_mut(&mut self, index: usize) -> Option<&mut PsLink> {
        self.links.get_mut(index)
    }

    /// How the units are addressed, in order.
    pub fn units(&self) -> &[LineUnit] {
        &self.units
    }

    /// The next event of any unit, with the unit's index (lower indexes first).
    pub fn poll_event(&mut self) -> Option<(usize, LinkEvent)> {
        self.links
            .iter_mut()
            .enumerate()
            .find_map(|(index, link)| link.poll_event().map(|event| (index, event)))
    }

    /// The arbiter's own traffic so far.
    pub fn stats(&self) -> LineStats {
        self.stats
    }

    /// Bytes received on the line (any chunking): the WAKE echo while the line is being
    /// switched, otherwise the reply of the unit whose attempt is on the wire.
    pub fn handle_rx(&mut self, now: Instant, bytes: &[u8]) {
        if let Some(switch) = &mut self.switch {
            let stray = switch.hear(bytes);
            self.stats.stray = self
                .stats
                .stray
                .saturating_add(u32::try_from(stray).unwrap_or(u32::MAX));
            if switch.line_echoes() && !self.line_echoes {
                self.learn_line_echo();
            }
        } else if let Some(link) = self.links.get_mut(self.owner) {
            link.handle_rx(now, bytes);
        }
    }

    /// A character received with a parity or framing error, in its place in the stream
    /// (see [`PsLink::handle_rx_error`]).
    pub fn handle_rx_error(&mut self, now: Instant) {
        if let Some(switch) = &mut self.switch {
            switch.hear_error();
        } else if let Some(link) = self.links.get_mut(self.owner) {
            link.handle_rx_error(now);
        }
    }

    /// The next whole frame to put on the wire, if any: a unit's request, or the SLEEP /
    /// WAKE that hands the line to it first.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        self.out = self.next_out(now);
        match self.out? {
            Out::Control => self.control.get(..self.control_len),
            Out::Unit => self.links.get(self.owner)?.frame_on_wire(),
        }
    }

    /// The frame handed out last left the wire (its last stop bit) at `at`.
    pub fn handle_transmitted(&mut self, at: Instant) {
        let owner = self.links.get_mut(self.owner);
        match (self.out, &mut self.switch, owner) {
            (Some(Out::Control), Some(switch), owner) => {
                // The waiting attempt's time-out runs from the WAKE: if nobody echoes it,
                // the attempt has cost its one time-out when the switch gives up.
                if switch.transmitted(at)
                    && let Some(link) = owner
                {
                    link.handle_transmitted(at);
                }
            }
            (Some(Out::Unit), _, Some(link)) => link.handle_transmitted(at),
            _ => {}
        }
    }

    /// The line settings the port must use now: the HPR's while switching, otherwise those
    /// of the unit that has (or had last) the line.
    pub fn port_config(&self) -> PortConfig {
        if self.switch.is_some() {
            return PortConfig::HPR;
        }
        self.links
            .get(self.owner)
            .map_or(PortConfig::HPR, PsLink::port_config)
    }

    /// When [`SharedLine::poll_transmit`] must be called at the latest: the switch's quiet
    /// or echo time-out, the attempt on the wire's deadline, or the earliest unit's.
    pub fn poll_at(&self) -> Option<Instant> {
        if let Some(quiet) = self.quiet_until {
            return Some(quiet);
        }
        if let Some(switch) = &self.switch {
            return Some(switch.poll_at());
        }
        if let Some(owner) = self.links.get(self.owner).filter(|l| l.holds_line()) {
            return owner.poll_at();
        }
        self.links.iter().filter_map(PsLink::poll_at).min()
    }

    /// Unit `unit`'s START output is on or off (the bridge follows its discrete I/O): from
    /// START on, that unit's state is polled in full at every turn, so that its pilot arc is
    /// seen at once and the whole line keeps the HF-ignition quiet (see the module docs).
    pub fn set_start(&mut self, unit: usize, on: bool) {
        if let Some(link) = self.links.get_mut(unit) {
            link.follow_start(on);
        }
    }

    /// The end of the HF-ignition quiet under way on the line, if any: the latest of the
    /// units' pilot-arc pauses.
    fn ignition_quiet_until(&self, now: Instant) -> Option<Instant> {
        self.links
            .iter()
            .filter_map(|link| link.ignition_quiet_until(now))
            .max()
    }

    /// Decide what goes out now, if anything.
    fn next_out(&mut self, now: Instant) -> Option<Out> {
        // A unit whose attempt waits for a switch is not told time passes: its attempt is
        // not on the wire yet.
        let held = self.switch.as_ref().map(|_| self.owner);
        for (index, link) in self.links.iter_mut().enumerate() {
            if Some(index) != held {
                link.handle_time(now);
            }
        }
        // One unit's HF ignition is noise on every drop: nothing goes out until it is over.
        self.quiet_until = self.ignition_quiet_until(now);
        if self.quiet_until.is_some() {
            return None;
        }
        if let Some(switch) = &mut self.switch {
            match switch.poll(now) {
                SwitchOut::Wait => return None,
                SwitchOut::Sleep => {
                    self.awake = Awake::Nobody;
                    self.stats.sleeps = self.stats.sleeps.saturating_add(1);
                    self.control_len = emit_control(None, &mut self.control);
                    return Some(Out::Control);
                }
                SwitchOut::Wake(id) => {
                    self.awake = Awake::Unit(id);
                    self.stats.wakes = self.stats.wakes.saturating_add(1);
                    self.control_len = emit_control(Some(id), &mut self.control);
                    return Some(Out::Control);
                }
                SwitchOut::Held => {
                    self.switch = None;
                    self.awake = Awake::Unit(self.hpr_id(self.owner));
                    return Some(Out::Unit);
                }
                SwitchOut::Failed => {
                    self.switch = None;
                    self.awake = Awake::Unknown;
                    self.stats.unanswered_wakes = self.stats.unanswered_wakes.saturating_add(1);
                    // Its time-out ran from the WAKE: it ends now.
                    if let Some(link) = self.links.get_mut(self.owner) {
                        link.handle_time(now);
                    }
                }
            }
        }
        if self.links.get(self.owner).is_some_and(PsLink::holds_line) {
            return None;
        }
        // A long attempt waits for its place in the round unless nothing else is due.
        let long_due = self.turns_since_long >= self.links.len();
        if self.hand_out(now, long_due) || self.hand_out(now, true) {
            return self.begin_turn(now);
        }
        None
    }

    /// The next unit in turn with something due hands out an attempt (true), a long one
    /// only if `long_allowed`; it becomes the owner.
    fn hand_out(&mut self, now: Instant, long_allowed: bool) -> bool {
        let count = self.links.len();
        // The round's long attempt may be the slow data of the unit that just polled, in its
        // own turn: no switch.
        let owner = self.links.get(self.owner);
        let first = usize::from(!(long_allowed && owner.is_some_and(PsLink::polled_last)));
        for step in first..=count {
            let index = (self.owner + step) % count;
            let Some(link) = self.links.get_mut(index) else {
                continue;
            };
            let due = link.poll_at().is_some_and(|at| at <= now);
            if !due {
                continue;
            }
            link.allow_long(long_allowed);
            if link.poll_transmit(now).is_none() {
                continue;
            }
            self.turns_since_long = match step == 0 || link.long_on_wire() {
                true => 0,
                false => self.turns_since_long.saturating_add(1),
            };
            self.owner = index;
            return true;
        }
        false
    }

    /// Unit `owner` has handed out an attempt: on an HPR line, switch to it first if needed.
    fn begin_turn(&mut self, now: Instant) -> Option<Out> {
        if !self.switching {
            return Some(Out::Unit);
        }
        let id = self.hpr_id(self.owner);
        let link = self.links.get(self.owner)?;
        let frame = link.frame_on_wire()?;
        let mut control = [0u8; CONTROL_CAPACITY];
        let sleep_len = emit_control(None, &mut control);
        if Some(frame) == control.get(..sleep_len) {
            // The unit's own SLEEP (its detection): no unit is awake after it.
            self.awake = Awake::Nobody;
            return Some(Out::Unit);
        }
        let wake_len = emit_control(Some(id), &mut control);
        let own_wake = Some(frame) == control.get(..wake_len);
        let timeout = link.config().response_timeout;
        if !self.line_echoes && self.links.iter().any(PsLink::hears_line_echo) {
            self.learn_line_echo();
        }
        match Switch::plan(self.awake, id, own_wake, timeout, self.line_echoes, now) {
            None => {
                if own_wake {
                    self.awake = Awake::Unit(id);
                }
                Some(Out::Unit)
            }
            Some(switch) => {
                self.switch = Some(switch);
                self.next_out(now)
            }
        }
    }

    /// The line echoes our own frames (2-wire, receiver on): every unit's link is told, as
    /// they all share the one line.
    fn learn_line_echo(&mut self) {
        self.line_echoes = true;
        for link in self.links.iter_mut() {
            link.learn_line_echo();
        }
    }

    fn hpr_id(&self, index: usize) -> u8 {
        match self.units.get(index) {
            Some(LineUnit::Hpr { id }) => *id,
            _ => 0,
        }
    }
}
