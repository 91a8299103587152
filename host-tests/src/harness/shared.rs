//! A [`World`] with several units on one line: the firmware's [`SharedLine`] as the endpoint
//! and a [`MultiDrop`] of simulated units at the far end of the world's [`Line`], so the
//! line's wiring, noise and damage apply to all of them as to one unit.
//!
//! The world's discrete I/O is one set, the first unit's: its START drives unit 0, its
//! safety monitor checks unit 0's view (per-unit pins come with the bridge's side of a shared
//! line). The line has its own independent observer: the [`MultiDrop`] counts every character
//! two units sent at once ([`World::collisions`]).
//!
//! [`Line`]: plasma_sim::line::Line

use std::fmt;

use plasma_firmware::link::{Diagnostics, LineUnit, LinkEvent, SharedLine, UnitStatus};
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::multidrop::{self, MultiDrop, units_for_one_line};
use plasma_sim::{Family, Model};

use super::endpoint::WorldEndpoint;
use super::options::WorldOptions;
use super::world::World;

/// Why a world of several units could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SharedLineError {
    /// The simulated units cannot share a line.
    Units(multidrop::LineError),
    /// The bridge refuses the set.
    Bridge(plasma_firmware::link::LineError),
}

impl fmt::Display for SharedLineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SharedLineError::Units(e) => write!(f, "simulated units: {e}"),
            SharedLineError::Bridge(e) => write!(f, "bridge: {e}"),
        }
    }
}

impl std::error::Error for SharedLineError {}

/// The world observes the first unit: its status, diagnostics and the I/O; every unit's
/// events go to the world's record (without the unit: [`World::unit_status`] tells them apart).
impl WorldEndpoint for SharedLine {
    fn poll(&mut self, _now: Instant, events: &mut Vec<LinkEvent>) {
        while let Some((_, event)) = self.poll_event() {
            events.push(event);
        }
    }

    fn status(&self) -> &UnitStatus {
        self.unit(0).expect("a line has a unit").status()
    }

    fn diagnostics(&self) -> &Diagnostics {
        self.unit(0).expect("a line has a unit").diagnostics()
    }
}

/// How the bridge addresses the simulated units [`units_for_one_line`] builds: HPR ids and
/// Powermax nodes in order from `options`' first.
fn addresses(models: &[Model], options: &WorldOptions) -> Vec<LineUnit> {
    models
        .iter()
        .enumerate()
        .map(|(index, &model)| {
            let offset = index as u8;
            match (model, model.family()) {
                (Model::MaxPro200, _) => LineUnit::MaxPro200,
                (_, Family::Hpr) => LineUnit::Hpr {
                    id: options.sim.hpr_id.wrapping_add(offset),
                },
                _ => LineUnit::Powermax {
                    node: options.sim.modbus_address.wrapping_add(offset),
                },
            }
        })
        .collect()
}

impl World<SharedLine> {
    /// `models` on one line (HPR ids and Powermax node addresses in order from those of
    /// `options.sim`; a Powermax node 0 becomes 1), the bridge's [`SharedLine`] with
    /// `options.link` for each unit's link settings.
    pub fn on_one_line(models: &[Model], options: WorldOptions) -> Result<Self, SharedLineError> {
        Self::on_one_line_with(models, options, |line| line)
    }

    /// Unit `index`'s status as the bridge knows it.
    pub fn unit_status(&self, index: usize) -> &UnitStatus {
        self.endpoint()
            .unit(index)
            .expect("no such unit on the line")
            .status()
    }

    /// Run until every unit's link is up.
    pub fn wait_all_up(&mut self, timeout: Duration) -> Result<Instant, super::Timeout> {
        self.run_until(
            |w| (0..w.endpoint().len()).all(|i| w.unit_status(i).link_up),
            timeout,
        )
    }
}

impl<E: WorldEndpoint> World<E> {
    /// Like [`World::on_one_line`], with the [`SharedLine`] inside an endpoint `wrap` makes
    /// of it.
    pub fn on_one_line_with(
        models: &[Model],
        options: WorldOptions,
        wrap: impl FnOnce(SharedLine) -> E,
    ) -> Result<Self, SharedLineError> {
        let mut options = options;
        options.sim.modbus_address = options.sim.modbus_address.max(1);
        let units = units_for_one_line(models, &options.sim).map_err(SharedLineError::Units)?;
        let units = MultiDrop::new(units).map_err(SharedLineError::Units)?;
        let line = SharedLine::new(options.link, &addresses(models, &options), Instant::ZERO)
            .map_err(SharedLineError::Bridge)?;
        Ok(World::with_endpoint(wrap(line), Box::new(units), options))
    }

    /// The simulated units on the line (a world built by [`World::on_one_line_with`]).
    pub fn units(&mut self) -> &mut MultiDrop {
        self.sim::<MultiDrop>()
    }

    /// Characters two units sent at once so far.
    pub fn collisions(&self) -> u64 {
        self.sim_ref::<MultiDrop>().collisions()
    }

    /// Raise fault `code` on unit `index` now (Powermax decimal code, HPR error id).
    pub fn inject_fault_on(&mut self, index: usize, code: u16) {
        let now = self.now();
        self.units()
            .unit_mut(index)
            .expect("no such unit on the line")
            .inject_fault(now, code);
        self.drive(|_, _| ());
    }

    /// Clear unit `index`'s fault now.
    pub fn clear_fault_on(&mut self, index: usize) {
        let now = self.now();
        self.units()
            .unit_mut(index)
            .expect("no such unit on the line")
            .clear_fault(now);
        self.drive(|_, _| ());
    }

    /// Cut unit `index`'s drop (`false`: it neither hears nor is heard) or mend it.
    pub fn connect_unit(&mut self, index: usize, connected: bool) {
        self.units().set_connected(index, connected);
        self.drive(|_, _| ());
    }
}
