//! The units the bridge drives: one alone on its line (found by auto-detection, whatever its
//! family), or up to four named ones sharing a line ([`SharedLine`]).
//!
//! One unit alone is a bare [`PsLink`], exactly as it always was: a line of one would send
//! an HPR SLEEP / WAKE it does not need and force a family the link can find by itself.
//!
//! ```
//! use plasma_firmware::link::{LineUnit, LinkConfig, Units};
//! use plasma_protocol::time::Instant;
//!
//! let one = Units::new(LinkConfig::default(), &[], Instant::ZERO).unwrap();
//! assert_eq!(one.count(), 1);
//! let two = [LineUnit::Hpr { id: 0 }, LineUnit::Hpr { id: 1 }];
//! let line = Units::new(LinkConfig::default(), &two, Instant::ZERO).unwrap();
//! assert_eq!(line.count(), 2);
//! assert_eq!(line.link(1).config().hpr_id, 1);
//! ```

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

use crate::link::{LineError, LineUnit, LinkConfig, LinkEvent, PsLink, SharedLine};

/// One unit, or several on one line. See the [module docs](self).
// The bridge lives in one static slot on the board, sized for four units whichever variant
// is in use: boxing the line would need a heap the board does not have.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub enum Units {
    /// One unit, auto-detected (`CONFIG units auto`, the default).
    One(PsLink),
    /// Named units sharing the line.
    Line(SharedLine),
}

impl Units {
    /// The units `named` (none: one unit, auto-detected) with `base` for their link
    /// settings, detecting from `now`. Refused when they cannot share a line.
    pub fn new(base: LinkConfig, named: &[LineUnit], now: Instant) -> Result<Units, LineError> {
        if named.is_empty() {
            return Ok(Units::One(PsLink::new(base, now)));
        }
        SharedLine::new(base, named, now).map(Units::Line)
    }

    /// How many units (1-4).
    pub fn count(&self) -> usize {
        match self {
            Units::One(_) => 1,
            Units::Line(line) => line.len(),
        }
    }

    /// Unit `index`'s link (0 = the first unit); the first unit's for an index beyond
    /// [`Units::count`] (callers check the index against the count first).
    // Out of line: the CNC session reaches its unit's link this way in dozens of places.
    #[inline(never)]
    pub fn link(&self, index: usize) -> &PsLink {
        match self {
            Units::One(link) => link,
            Units::Line(line) => match line.unit(index) {
                Some(link) => link,
                None => line.first(),
            },
        }
    }

    /// Unit `index`'s link, for its commands; as [`Units::link`] for an index out of range.
    #[inline(never)]
    pub fn link_mut(&mut self, index: usize) -> &mut PsLink {
        match self {
            Units::One(link) => link,
            Units::Line(line) => line.unit_or_first_mut(index),
        }
    }

    /// Every unit's link, in order.
    pub fn links(&self) -> impl Iterator<Item = &PsLink> {
        (0..self.count()).map(|index| self.link(index))
    }

    /// The next event of any unit, with the unit's index.
    pub fn poll_event(&mut self) -> Option<(usize, LinkEvent)> {
        match self {
            Units::One(link) => link.poll_event().map(|event| (0, event)),
            Units::Line(line) => line.poll_event(),
        }
    }

    /// Some unit holds events nobody has taken yet.
    pub(crate) fn has_events(&self) -> bool {
        self.links().any(PsLink::has_events)
    }

    /// Every unit takes `base` for its link settings (each keeps its own protocol and
    /// address on a shared line).
    pub fn reconfigure(&mut self, now: Instant, base: LinkConfig) {
        match self {
            Units::One(link) => link.reconfigure(now, base),
            Units::Line(line) => line.reconfigure(now, base),
        }
    }

    /// Unit `unit`'s START output is on or off: on a shared line its state is then polled
    /// at every turn and its HF ignition keeps the whole line quiet
    /// ([`SharedLine::set_start`]); one unit alone keeps its own pilot-arc pause as always.
    pub fn set_start(&mut self, unit: usize, on: bool) {
        if let Units::Line(line) = self {
            line.set_start(unit, on);
        }
    }

    /// Bytes received from the line.
    pub fn handle_rx(&mut self, now: Instant, bytes: &[u8]) {
        match self {
            Units::One(link) => link.handle_rx(now, bytes),
            Units::Line(line) => line.handle_rx(now, bytes),
        }
    }

    /// A character received with a parity or framing error.
    pub fn handle_rx_error(&mut self, now: Instant) {
        match self {
            Units::One(link) => link.handle_rx_error(now),
            Units::Line(line) => line.handle_rx_error(now),
        }
    }

    /// The next whole frame to transmit.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        match self {
            Units::One(link) => link.poll_transmit(now),
            Units::Line(line) => line.poll_transmit(now),
        }
    }

    /// The frame handed out last left the wire at `at`.
    pub fn handle_transmitted(&mut self, at: Instant) {
        match self {
            Units::One(link) => link.handle_transmitted(at),
            Units::Line(line) => line.handle_transmitted(at),
        }
    }

    /// The line settings the port must use now.
    pub fn port_config(&self) -> PortConfig {
        match self {
            Units::One(link) => link.port_config(),
            Units::Line(line) => line.port_config(),
        }
    }

    /// When [`Units::poll_transmit`] must be called at the latest.
    pub fn poll_at(&self) -> Option<Instant> {
        match self {
            Units::One(link) => link.poll_at(),
            Units::Line(line) => line.poll_at(),
        }
    }
}
