//! What the [`World`](super::World) needs of its endpoint beyond the power-supply port.
//!
//! The port side is the firmware's [`PsEndpoint`], the trait the board's tasks, pbtool and the
//! fuzz target drive too, so the World moves bytes exactly as they do. [`WorldEndpoint`] adds
//! only what the World itself observes or simulates: link events for the scenario's record,
//! the unit's status for its waits, and the exchange with the discrete I/O it runs. It is
//! implemented for [`PsLink`] here and for the `Bridge` and the harness's `BridgeEndpoint` in
//! `bridge.rs`, so scenarios run unchanged against either.

use plasma_firmware::io::{Inputs, IoConfig, IoEvent, Outputs, SupplyState};
use plasma_firmware::link::{Diagnostics, LinkEvent, PsLink, UnitStatus};
use plasma_firmware::platform::PsEndpoint;
use plasma_protocol::time::Instant;

/// A [`PsEndpoint`] as the [`World`](super::World) observes it.
pub trait WorldEndpoint: PsEndpoint {
    /// Let time pass. Link events the endpoint does not consume itself (a bare [`PsLink`]
    /// consumes none) are appended to `events`.
    fn poll(&mut self, now: Instant, events: &mut Vec<LinkEvent>);
    /// What the endpoint knows about the unit.
    fn status(&self) -> &UnitStatus;
    /// Link counters.
    fn diagnostics(&self) -> &Diagnostics;
    /// The copy of unit `unit`'s link view that goes to its discrete I/O (0 = the first
    /// unit; the firmware's own translation, what `Bridge::supply_state_of` uses: not a copy
    /// of it). An endpoint of one unit knows no other: a supply without a link.
    fn supply_state_of(&self, unit: usize) -> SupplyState {
        match unit {
            0 => SupplyState::from(self.status()),
            _ => SupplyState::default(),
        }
    }
    /// Unit `unit`'s discrete I/O levels after a step (the `Bridge` shows them in STATUS).
    fn set_io_snapshot_of(&mut self, _unit: usize, _inputs: Inputs, _outputs: Outputs) {}
    /// An event of unit `unit`'s discrete I/O (arc on/off, transfer time-out...).
    fn on_io_event_of(&mut self, _unit: usize, _now: Instant, _event: IoEvent) {}
    /// A new interlock configuration to apply now (the `Bridge` after `CONFIG <io key>`);
    /// it is every unit's.
    fn take_io_config_change(&mut self) -> Option<IoConfig> {
        None
    }
    /// A level the simulated CNC's TORCH_ON input of a unit (0 = the first) should take now
    /// (the `Bridge`'s simulator-only `TORCH ON|OFF`, `@N TORCH ON`), oldest first.
    fn poll_torch_request(&mut self) -> Option<(usize, bool)> {
        None
    }
}

impl WorldEndpoint for PsLink {
    fn poll(&mut self, _now: Instant, events: &mut Vec<LinkEvent>) {
        while let Some(event) = self.poll_event() {
            events.push(event);
        }
    }

    fn status(&self) -> &UnitStatus {
        PsLink::status(self)
    }

    fn diagnostics(&self) -> &Diagnostics {
        PsLink::diagnostics(self)
    }
}
