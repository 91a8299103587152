//! A [`World`] with several units on one line: the firmware's [`SharedLine`] (or the whole
//! bridge with `CONFIG units` naming them, [`World::with_bridge_on_line`]) as the endpoint
//! and a [`MultiDrop`] of simulated units at the far end of the world's [`Line`], so the
//! line's wiring, noise and damage apply to all of them as to one unit.
//!
//! The world has one set of discrete I/O per unit: unit k's START drives unit k alone, its
//! MOTION comes from unit k, its interlocks follow unit k's link and its own safety monitor
//! checks it. The line has its own independent observer: the [`MultiDrop`] counts every
//! character two units sent at once ([`World::collisions`]).
//!
//! [`Line`]: plasma_sim::line::Line

use std::fmt;

use plasma_firmware::io::SupplyState;
use plasma_firmware::link::{
    Diagnostics, LineUnit, LinkConfig, LinkEvent, NamedUnits, SharedLine, UnitStatus,
};
use plasma_firmware::settings::Settings;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::multidrop::{self, MultiDrop, units_for_one_line};
use plasma_sim::{Family, Model, SimOptions};

use super::bridge::BridgeEndpoint;
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

/// The world observes the first unit's status and diagnostics, and each unit's supply state
/// for its own discrete I/O; every unit's events go to the world's record (without the unit:
/// [`World::unit_status`] tells them apart).
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

    fn supply_state_of(&self, unit: usize) -> SupplyState {
        self.unit(unit)
            .map(|link| SupplyState::from(link.status()))
            .unwrap_or_default()
    }
}

/// How the bridge addresses the simulated units [`units_for_one_line`] builds: HPR ids and
/// Powermax nodes in order from `sim`'s first.
fn addresses(models: &[Model], sim: &SimOptions) -> Vec<LineUnit> {
    models
        .iter()
        .enumerate()
        .map(|(index, &model)| {
            let offset = index as u8;
            match (model, model.family()) {
                (Model::MaxPro200, _) => LineUnit::MaxPro200,
                (_, Family::Hpr) => LineUnit::Hpr {
                    id: sim.hpr_id.wrapping_add(offset),
                },
                _ => LineUnit::Powermax {
                    node: sim.modbus_address.wrapping_add(offset),
                },
            }
        })
        .collect()
}

/// `models` on one simulated line and how the bridge addresses them, with the options the
/// world is built with (a Powermax node 0 becomes 1).
fn simulated_line(
    models: &[Model],
    mut options: WorldOptions,
) -> Result<(MultiDrop, Vec<LineUnit>, WorldOptions), SharedLineError> {
    options.sim.modbus_address = options.sim.modbus_address.max(1);
    let units = units_for_one_line(models, &options.sim).map_err(SharedLineError::Units)?;
    let units = MultiDrop::new(units).map_err(SharedLineError::Units)?;
    Ok((units, addresses(models, &options.sim), options))
}

/// `models` on one simulated line as [`simulated_line`] builds them, with the bridge's
/// `CONFIG units` naming them (`link`: the link settings they share).
fn bridge_line(
    models: &[Model],
    options: WorldOptions,
    link: LinkConfig,
) -> Result<(MultiDrop, NamedUnits, WorldOptions), SharedLineError> {
    let (units, addresses, options) = simulated_line(models, options)?;
    let named = NamedUnits::new(link, &addresses).map_err(SharedLineError::Bridge)?;
    Ok((units, named, options))
}

/// What the bridge's `CONFIG units` says for `models` on one simulated line (`link`: the link
/// settings they share), and the simulator options that build them there (HPR ids and
/// Powermax nodes in order from `sim`'s; a Powermax node 0 becomes 1); refused, with the
/// reason, exactly as [`World::with_bridge_on_line`] refuses them. For a bridge that is not a
/// world's (the emulated board), told the units as a CNC tells it.
pub fn named_units_on_line(
    models: &[Model],
    sim: SimOptions,
    link: LinkConfig,
) -> Result<(NamedUnits, SimOptions), SharedLineError> {
    let options = WorldOptions {
        sim,
        ..WorldOptions::default()
    };
    let (_, named, options) = bridge_line(models, options, link)?;
    Ok((named, options.sim))
}

/// The whole bridge driving several units on one line.
impl World<BridgeEndpoint> {
    /// The bridge with `settings` and `CONFIG units` naming `models` as they sit on one
    /// simulated line (HPR ids and Powermax nodes in order from those of `options.sim`; a
    /// Powermax node 0 becomes 1): one set of discrete I/O and one safety monitor per unit.
    pub fn with_bridge_on_line(
        models: &[Model],
        options: WorldOptions,
        mut settings: Settings,
    ) -> Result<Self, SharedLineError> {
        let (units, named, options) = bridge_line(models, options, settings.link)?;
        settings.units = named;
        Ok(World::with_bridge_unit(Box::new(units), options, settings))
    }

    /// Run until the bridge has every unit's link up.
    pub fn wait_units_up(&mut self, timeout: Duration) -> Result<Instant, super::Timeout> {
        self.run_until(
            |w| (0..w.bridge().unit_count()).all(|i| w.bridge().status_of(i).link_up),
            timeout,
        )
    }
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
        let (units, addresses, options) = simulated_line(models, options)?;
        let line = SharedLine::new(options.link, &addresses, Instant::ZERO)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_named_units_are_the_ids_and_nodes_the_simulated_line_answers_at() {
        let link = Settings::default().link;
        let (named, sim) =
            named_units_on_line(&[Model::Hpr260, Model::Hpr130], SimOptions::default(), link)
                .unwrap();
        assert_eq!(named.to_string(), "HPR:0,HPR:1");
        assert_eq!(sim.hpr_id, 0);
        // A node 0 (learned by a unit alone) cannot be shared: the line starts at node 1.
        let (named, sim) =
            named_units_on_line(&[Model::Sync65, Model::Pm85], SimOptions::default(), link)
                .unwrap();
        assert_eq!(named.to_string(), "POWERMAX:1,POWERMAX:2");
        assert_eq!(sim.modbus_address, 1);
    }

    #[test]
    fn units_that_cannot_share_a_line_are_refused_as_the_world_refuses_them() {
        let link = Settings::default().link;
        for models in [
            [Model::Hpr260, Model::Sync65],
            [Model::MaxPro200, Model::Hpr260],
        ] {
            let named = named_units_on_line(&models, SimOptions::default(), link);
            let world =
                World::with_bridge_on_line(&models, WorldOptions::default(), Settings::default());
            assert!(named.is_err(), "{models:?}");
            assert_eq!(named.err(), world.err(), "{models:?}");
        }
    }
}
