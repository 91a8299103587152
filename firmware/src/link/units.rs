//! The units the bridge drives: one alone on its line (found by auto-detection, whatever its
//! family), or up to four named ones sharing a line ([`SharedLine`]).
//!
//! One unit alone is driven as a bare [`PsLink`], exactly as it always was: a line of one
//! would send an HPR SLEEP / WAKE it does not need and force a family the link can find by
//! itself.
//!
//! ```
//! use plasma_firmware::link::{LineUnit, LinkConfig, Units};
//! use plasma_protocol::time::Instant;
//!
//! let mut units = Units::alone(LinkConfig::default(), None, Instant::ZERO);
//! assert_eq!(units.count(), 1);
//! let two = [LineUnit::Hpr { id: 0 }, LineUnit::Hpr { id: 1 }];
//! units.rebuild(LinkConfig::default(), &two, None, Instant::ZERO).unwrap();
//! assert_eq!(units.count(), 2);
//! assert_eq!(units.link(1).config().hpr_id, 1);
//! ```

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

use crate::link::{
    LineError, LineStats, LineUnit, LinkConfig, LinkEvent, PowermaxProcess, PsLink, SharedLine,
};

/// One unit, or several on one line. See the [module docs](self).
///
/// It always holds the line's storage for [`MAX_UNITS`](crate::link::MAX_UNITS) links (the
/// bridge lives in one static slot on the board, sized for four units whatever is in use),
/// and changes its units in place ([`Units::rebuild`]): one link is built at a time, never a
/// whole line on the stack.
#[derive(Debug)]
pub struct Units {
    line: SharedLine,
    /// One unit, auto-detected: its link is driven directly, as a link alone always was.
    alone: bool,
}

impl Units {
    /// One unit, auto-detected, with `base` for its link settings, detecting from `now` and
    /// restoring `process` (the persisted one). Named units follow in place
    /// ([`Units::rebuild`]): so the board's bridge is built in its static slot, never as a
    /// 15 KB value on its stack.
    pub fn alone(base: LinkConfig, process: Option<PowermaxProcess>, now: Instant) -> Units {
        Units {
            line: SharedLine::alone(base, process, now),
            alone: true,
        }
    }

    /// In place: the units `named` (none: one unit, auto-detected) start afresh at `now`,
    /// the first restoring `process`. Refused, and nothing changes, when they cannot share a
    /// line.
    pub fn rebuild(
        &mut self,
        base: LinkConfig,
        named: &[LineUnit],
        process: Option<PowermaxProcess>,
        now: Instant,
    ) -> Result<(), LineError> {
        self.line.rebuild(base, named, process, now)?;
        self.alone = named.is_empty();
        Ok(())
    }

    /// The line's own traffic (SLEEP / WAKE hand-overs; none for a unit alone).
    pub fn line_stats(&self) -> LineStats {
        self.line.stats()
    }

    /// How many units (1-4).
    pub fn count(&self) -> usize {
        self.line.len()
    }

    /// Unit `index`'s link (0 = the first unit); the first unit's for an index beyond
    /// [`Units::count`] (callers check the index against the count first).
    // Out of line: the CNC session reaches its unit's link this way in dozens of places.
    #[inline(never)]
    pub fn link(&self, index: usize) -> &PsLink {
        match self.line.unit(index) {
            Some(link) => link,
            None => self.line.first(),
        }
    }

    /// Unit `index`'s link, for its commands; as [`Units::link`] for an index out of range.
    #[inline(never)]
    pub fn link_mut(&mut self, index: usize) -> &mut PsLink {
        self.line.unit_or_first_mut(index)
    }

    /// Every unit's link, in order.
    pub fn links(&self) -> impl Iterator<Item = &PsLink> {
        (0..self.count()).map(|index| self.link(index))
    }

    /// The next event of any unit, with the unit's index.
    pub fn poll_event(&mut self) -> Option<(usize, LinkEvent)> {
        self.line.poll_event()
    }

    /// Some unit holds events nobody has taken yet.
    pub(crate) fn has_events(&self) -> bool {
        self.links().any(PsLink::has_events)
    }

    /// Every unit takes `base` for its link settings (each keeps its own protocol and
    /// address on a shared line).
    pub fn reconfigure(&mut self, now: Instant, base: LinkConfig) {
        if self.alone {
            self.line.first_mut().reconfigure(now, base);
        } else {
            self.line.reconfigure(now, base);
        }
    }

    /// Unit `unit`'s START output is on or off: on a shared line its state is then polled
    /// at every turn and its HF ignition keeps the whole line quiet
    /// ([`SharedLine::set_start`]); one unit alone keeps its own pilot-arc pause as always.
    pub fn set_start(&mut self, unit: usize, on: bool) {
        if !self.alone {
            self.line.set_start(unit, on);
        }
    }

    /// Bytes received from the line.
    pub fn handle_rx(&mut self, now: Instant, bytes: &[u8]) {
        match self.alone {
            true => self.line.first_mut().handle_rx(now, bytes),
            false => self.line.handle_rx(now, bytes),
        }
    }

    /// A character received with a parity or framing error.
    pub fn handle_rx_error(&mut self, now: Instant) {
        match self.alone {
            true => self.line.first_mut().handle_rx_error(now),
            false => self.line.handle_rx_error(now),
        }
    }

    /// The next whole frame to transmit.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        match self.alone {
            true => self.line.first_mut().poll_transmit(now),
            false => self.line.poll_transmit(now),
        }
    }

    /// The frame handed out last left the wire at `at`.
    pub fn handle_transmitted(&mut self, at: Instant) {
        match self.alone {
            true => self.line.first_mut().handle_transmitted(at),
            false => self.line.handle_transmitted(at),
        }
    }

    /// The line settings the port must use now.
    pub fn port_config(&self) -> PortConfig {
        match self.alone {
            true => self.line.first().port_config(),
            false => self.line.port_config(),
        }
    }

    /// When [`Units::poll_transmit`] must be called at the latest.
    pub fn poll_at(&self) -> Option<Instant> {
        match self.alone {
            true => self.line.first().poll_at(),
            false => self.line.poll_at(),
        }
    }
}
