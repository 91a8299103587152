//! The bridge's power-supply side as the [`World`](super::World) drives it.
//!
//! [`PsEndpoint`] is the small surface the harness needs: bytes in and out, the port settings,
//! time, and the copy of the supply state the discrete I/O gets. It is implemented for
//! [`PsLink`] here; the `Bridge` façade (link + CNC session) implements it with the same
//! names, so scenarios run unchanged against either.

use plasma_firmware::io::{Inputs, IoConfig, IoEvent, Outputs, SupplyState};
use plasma_firmware::link::{Diagnostics, LinkEvent, PsLink, UnitStatus};
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

/// What drives the power-supply UART, as seen by the harness.
pub trait PsEndpoint {
    /// Bytes received on the PS UART.
    fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]);
    /// A character received with a UART parity or framing error, in its place in the stream.
    fn handle_ps_rx_error(&mut self, now: Instant);
    /// One whole frame to transmit now, if any.
    fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]>;
    /// The frame from [`PsEndpoint::poll_ps_transmit`] left the wire at `at` (the line
    /// model's end of its last stop bit): the reply time-out runs from there.
    fn ps_transmitted(&mut self, at: Instant);
    /// The settings the PS UART must use now.
    fn ps_port_config(&self) -> PortConfig;
    /// Let time pass. Link events the endpoint does not consume itself (a bare [`PsLink`]
    /// consumes none) are appended to `events`.
    fn poll(&mut self, now: Instant, events: &mut Vec<LinkEvent>);
    /// Earliest time the endpoint needs attention without new input.
    fn poll_at(&self) -> Option<Instant>;
    /// The copy of the link's view that goes to the discrete I/O.
    fn supply_state(&self) -> SupplyState;
    /// What the endpoint knows about the unit.
    fn status(&self) -> &UnitStatus;
    /// Link counters.
    fn diagnostics(&self) -> &Diagnostics;
    /// The discrete I/O levels after a step (the `Bridge` shows them in STATUS).
    fn set_io_snapshot(&mut self, _inputs: Inputs, _outputs: Outputs) {}
    /// An event of the discrete I/O (arc on/off, transfer time-out...).
    fn on_io_event(&mut self, _now: Instant, _event: IoEvent) {}
    /// A new interlock configuration to apply now (the `Bridge` after `CONFIG <io key>`).
    fn take_io_config_change(&mut self) -> Option<IoConfig> {
        None
    }
    /// A level the simulated CNC's TORCH_ON input should take now (the `Bridge`'s
    /// simulator-only `TORCH ON|OFF`), oldest first.
    fn poll_torch_request(&mut self) -> Option<bool> {
        None
    }
}

impl PsEndpoint for PsLink {
    fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.handle_rx(now, bytes);
    }

    fn handle_ps_rx_error(&mut self, now: Instant) {
        self.handle_rx_error(now);
    }

    fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        self.poll_transmit(now)
    }

    fn ps_transmitted(&mut self, at: Instant) {
        self.handle_transmitted(at);
    }

    fn ps_port_config(&self) -> PortConfig {
        self.port_config()
    }

    fn poll(&mut self, _now: Instant, events: &mut Vec<LinkEvent>) {
        while let Some(event) = self.poll_event() {
            events.push(event);
        }
    }

    fn poll_at(&self) -> Option<Instant> {
        PsLink::poll_at(self)
    }

    fn supply_state(&self) -> SupplyState {
        // The firmware's own translation (what `Bridge::supply_state` uses), not a copy.
        SupplyState::from(PsLink::status(self))
    }

    fn status(&self) -> &UnitStatus {
        PsLink::status(self)
    }

    fn diagnostics(&self) -> &Diagnostics {
        PsLink::diagnostics(self)
    }
}
