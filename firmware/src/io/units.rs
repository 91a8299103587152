//! Every unit's discrete I/O on one board: one [`DiscreteIo`] per unit set of the pin table,
//! each with its own input filter and interlocks, so one unit's TORCH_ON never starts another
//! and one unit's fault or lost link never blocks another's START.
//!
//! A unit the bridge does not drive (`CONFIG units` names fewer) is *inert*: no interlocks run
//! for it, its outputs are off (the safe state's levels) and it raises no events, whatever the
//! settings allow, so `link_required off` cannot start a unit nobody configured. Until told
//! how many units the bridge drives, only the first is driven (the one-unit default). A unit
//! that becomes driven starts as at power-up: a TORCH_ON already active waits for its release.
//!
//! ```
//! use plasma_firmware::io::{Input, IoConfig, PinLevels, SupplyState, UnitsIo};
//! use plasma_protocol::time::Instant;
//!
//! let t = Instant::from_millis;
//! let idle = |_unit: usize| PinLevels::ALL_HIGH;
//! let mut io = UnitsIo::<2>::new(IoConfig::default(), t(0), idle);
//! io.set_unit_count(t(1), 2, idle);
//! io.on_supply(t(1), 1, SupplyState::HEALTHY);
//! // The second unit's CNC pulls its TORCH_ON low: its START comes on, the first's stays off.
//! let second_torch = |unit: usize| PinLevels::ALL_HIGH.with(Input::TorchOn, unit != 1);
//! io.on_pins(t(100), second_torch);
//! io.poll(t(101));
//! assert!(io.outputs(1).start);
//! assert!(!io.outputs(0).start);
//! ```

use super::config::IoConfig;
use super::discrete::DiscreteIo;
use super::input_filter::PinLevels;
use super::signals::{Outputs, SupplyState};
use plasma_protocol::time::Instant;

/// The discrete I/O of up to `N` units (the board's unit sets), unit 0 first.
#[derive(Debug, Clone)]
pub struct UnitsIo<const N: usize> {
    /// Each unit's I/O; `None` while the unit is inert.
    units: [Option<DiscreteIo>; N],
    /// Each unit's latest supply state, kept for a unit that becomes driven.
    supplies: [SupplyState; N],
    config: IoConfig,
}

impl<const N: usize> UnitsIo<N> {
    /// Power-up with the pins as `pins(unit)` reads them now: the first unit driven, the others
    /// inert until [`set_unit_count`](Self::set_unit_count).
    pub fn new(config: IoConfig, now: Instant, pins: impl Fn(usize) -> PinLevels) -> Self {
        let mut index = 0;
        UnitsIo {
            units: [(); N].map(|()| {
                let unit = index;
                index += 1;
                (unit == 0).then(|| DiscreteIo::new(config, now, pins(unit)))
            }),
            supplies: [SupplyState::default(); N],
            config,
        }
    }

    /// The bridge drives `count` units: the units from that index on become inert (their
    /// outputs off at once), the ones below it driven (as at power-up, with the pins as
    /// `pins(unit)` reads them now). Returns whether any unit changed.
    pub fn set_unit_count(
        &mut self,
        now: Instant,
        count: usize,
        pins: impl Fn(usize) -> PinLevels,
    ) -> bool {
        let mut changed = false;
        for (unit, (io, supply)) in self.units.iter_mut().zip(&self.supplies).enumerate() {
            match (io.is_some(), unit < count) {
                (true, false) => *io = None,
                (false, true) => {
                    let mut fresh = DiscreteIo::new(self.config, now, pins(unit));
                    fresh.on_supply(now, *supply);
                    *io = Some(fresh);
                }
                _ => continue,
            }
            changed = true;
        }
        changed
    }

    /// Whether unit `unit` is driven (not inert).
    pub fn is_driven(&self, unit: usize) -> bool {
        matches!(self.units.get(unit), Some(Some(_)))
    }

    /// Unit `unit`'s supply, as its link sees it, changed (kept for an inert unit).
    pub fn on_supply(&mut self, now: Instant, unit: usize, supply: SupplyState) {
        if let Some(kept) = self.supplies.get_mut(unit) {
            *kept = supply;
        }
        if let Some(Some(io)) = self.units.get_mut(unit) {
            io.on_supply(now, supply);
        }
    }

    /// New settings for every unit ([`DiscreteIo::reconfigure`]); whether anything changed.
    pub fn reconfigure(
        &mut self,
        now: Instant,
        config: IoConfig,
        pins: impl Fn(usize) -> PinLevels,
    ) -> bool {
        let changed = self.config != config;
        self.config = config;
        for (unit, io) in self.driven() {
            io.reconfigure(now, config, pins(unit));
        }
        changed
    }

    /// Every unit's pins were read at `now` (`pins(unit)`).
    pub fn on_pins(&mut self, now: Instant, pins: impl Fn(usize) -> PinLevels) {
        for (unit, io) in self.driven() {
            io.on_pins(now, pins(unit));
        }
    }

    /// Let time pass for every unit.
    pub fn poll(&mut self, now: Instant) {
        for (_, io) in self.driven() {
            io.poll(now);
        }
    }

    /// The earliest instant [`poll`](Self::poll) has something to do for any unit.
    pub fn poll_at(&self) -> Option<Instant> {
        self.units
            .iter()
            .flatten()
            .filter_map(DiscreteIo::poll_at)
            .min()
    }

    /// Unit `unit`'s logical output levels: all off for an inert unit.
    pub fn outputs(&self, unit: usize) -> Outputs {
        match self.units.get(unit) {
            Some(Some(io)) => io.outputs(),
            _ => Outputs::OFF,
        }
    }

    /// Unit `unit`'s levels for the pin table ([`DiscreteIo::table_outputs`]); an inert
    /// unit's all off, the levels of the board's safe state.
    pub fn table_outputs(&self, unit: usize) -> Outputs {
        match self.units.get(unit) {
            Some(Some(io)) => io.table_outputs(),
            _ => Outputs::OFF,
        }
    }

    /// Every driven unit's I/O with its index, for its transitions, events and levels.
    pub fn driven(&mut self) -> impl Iterator<Item = (usize, &mut DiscreteIo)> {
        self.units
            .iter_mut()
            .enumerate()
            .filter_map(|(unit, io)| Some((unit, io.as_mut()?)))
    }

    /// The settings in use.
    pub fn config(&self) -> &IoConfig {
        &self.config
    }
}

#[cfg(test)]
mod tests;
