//! The bridge façade: the power-supply link, the CNC session and the settings behind one
//! sans-IO object.
//!
//! The discrete I/O ([`Interlocks`](crate::io::Interlocks)) is *not* inside: on the board it
//! runs in a higher-priority context so that START never waits behind serial work. The two
//! exchange small copies: [`Bridge::supply_state`] goes to the interlocks;
//! [`Bridge::set_io_snapshot`] and [`Bridge::on_io_event`] come back (STATUS fields and
//! `!ARC ON` style events).
//!
//! # Driving it
//! A host loop (simulator, `pbtool sim`) or the board's tasks do, in any order and as often
//! as they like:
//!
//! - bytes from the power supply → [`Bridge::handle_ps_rx`]; bytes for it ←
//!   [`Bridge::poll_ps_transmit`] (one whole frame, with the UART settings of
//!   [`Bridge::ps_port_config`]);
//! - bytes from the CNC → [`Bridge::handle_cnc_rx`]; bytes for it ← [`Bridge::poll_cnc_output`];
//! - [`Bridge::poll`] no later than [`Bridge::poll_at`];
//! - after `CONFIG SAVE`, and when the consumable record is due: [`Bridge::take_save_request`],
//!   store, [`Bridge::save_finished`] (at boot, [`Bridge::restore_consumables`]);
//! - the history: write every [`Bridge::take_history_draft`] in the background; after
//!   `HISTORY`: [`Bridge::take_history_request`], read or erase,
//!   [`Bridge::history_finished`] (both with [`serve`](crate::storage::history::serve) and its store);
//! - simulator only: [`Bridge::poll_sim_command`] (`TORCH ON|OFF`).
//!
//! ```
//! use plasma_firmware::bridge::Bridge;
//! use plasma_firmware::settings::Settings;
//! use plasma_protocol::time::Instant;
//!
//! let mut bridge = Bridge::new(Settings::default(), Instant::ZERO);
//! // The link starts looking for a unit at once.
//! assert!(bridge.poll_ps_transmit(Instant::ZERO).is_some());
//!
//! bridge.handle_cnc_rx(Instant::from_millis(1), b"SET AMPS 45\r\n");
//! let reply = bridge.poll_cnc_output().unwrap();
//! let expected = format!("ERR LINK {}\r\n", plasma_firmware::texts::NO_LINK);
//! assert_eq!(reply, expected.as_bytes());
//! ```

use crate::cnc::history::HistoryLog;
use crate::cnc::units::{restart_units, unit_process};
use crate::cnc::{Context, Session, SessionStats};
pub use crate::cnc::{FRAME_IDLE_TIMEOUT, MAX_REPLY_LEN, OUTPUT_CAPACITY, SimCommand};
use crate::consumables::{ConsumableSet, Consumables};
use crate::io::{Inputs, IoConfig, IoEvent, Outputs, SupplyState};
use crate::link::{Diagnostics, MAX_UNITS, PsLink, UnitStatus, Units};
use crate::platform::runner::PsEndpoint;
use crate::platform::safe_state::ResetCause;
use crate::platform::supervisor::BridgeEndpoint;
use crate::settings::{SaveError, Settings};
use crate::storage::history::{Draft, Event, HistoryAnswer, HistoryRequest, Unit};
use plasma_protocol::cnc::HistoryCommand;
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

/// The bridge: link, CNC session and settings. See the module docs.
#[derive(Debug)]
pub struct Bridge {
    units: Units,
    /// The named units are still to be built (at the first call that drives the line).
    units_pending: bool,
    session: Session,
    settings: Settings,
    /// Each unit's discrete-I/O snapshot.
    io: [Option<(Inputs, Outputs)>; MAX_UNITS],
    boot_report: Option<&'static str>,
    history: HistoryLog,
    consumables: Consumables,
    /// The save under way is the consumable record's.
    saving_consumables: bool,
    now: Instant,
}

/// What [`Bridge::take_save_request`] asks the board to store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SaveRequest {
    /// The settings, under [`SETTINGS_KEY`](crate::storage::SETTINGS_KEY) (`CONFIG SAVE`).
    Settings(Settings),
    /// The consumable record, under [`CONSUMABLES_KEY`](crate::storage::CONSUMABLES_KEY).
    Consumables(ConsumableSet),
}

/// A [`Context`] of `$bridge` at `$now` about `$unit` (the first unit by default; a macro, so
/// that the session can be borrowed at the same time as the other fields).
macro_rules! ctx {
    ($bridge:ident, $now:expr) => {
        ctx!($bridge, $now, 0)
    };
    ($bridge:ident, $now:expr, $unit:expr) => {
        Context {
            now: $now,
            units: &mut $bridge.units,
            unit: $unit,
            settings: &mut $bridge.settings,
            ios: &$bridge.io,
            boot_report: $bridge.boot_report,
            history: &mut $bridge.history,
            consumables: &mut $bridge.consumables,
        }
    };
}

impl Bridge {
    /// A bridge that runs with `settings` (loaded from flash, or the defaults) from `now`.
    /// The process persisted in the settings goes to the first unit's link, which applies it
    /// again once a Powermax answers (the link decides what is re-applied and when:
    /// [`crate::link::kept`]).
    ///
    /// Named units (`CONFIG units`) start at the first call that drives the line: the
    /// bridge is built with the first unit's link alone, so that the board builds it (23 KB)
    /// straight in its static slot, and the others are filled in place.
    pub fn new(settings: Settings, now: Instant) -> Self {
        Bridge {
            units: Units::alone(
                settings.link,
                settings.process.as_ref().map(unit_process),
                now,
            ),
            units_pending: !settings.units.as_slice().is_empty(),
            session: Session::new(&settings),
            settings,
            io: [None; MAX_UNITS],
            boot_report: None,
            history: HistoryLog::default(),
            consumables: Consumables::default(),
            saving_consumables: false,
            now,
        }
    }

    /// Accept simulator-only commands (`TORCH ON|OFF`, see [`Bridge::poll_sim_command`]).
    /// Never on the board.
    pub fn enable_sim_commands(&mut self) {
        self.session.enable_sim_commands();
    }

    /// Why the board started (reset cause text): `ID` reports it, and with events on a
    /// `!BOOT reason=...` line goes out.
    pub fn set_boot_report(&mut self, now: Instant, reason: &'static str) {
        self.boot_report = Some(reason);
        let ctx = ctx!(self, now);
        self.session.boot_event(&ctx, reason);
    }

    // --- power-supply side --------------------------------------------------------------

    /// Bytes received from the power supply (any chunking).
    pub fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.start_units(now);
        self.units.handle_rx(now, bytes);
        self.service(now);
    }

    /// A character from the power supply that the UART flagged with a parity or framing
    /// error, in its place among the received bytes (see
    /// [`PsLink::handle_rx_error`](crate::link::PsLink::handle_rx_error)).
    pub fn handle_ps_rx_error(&mut self, now: Instant) {
        self.start_units(now);
        self.units.handle_rx_error(now);
        self.service(now);
    }

    /// The frame from [`Bridge::poll_ps_transmit`] has left the wire (its last stop bit) at
    /// `at`: its reply time-out runs from there.
    pub fn ps_transmitted(&mut self, at: Instant) {
        self.units.handle_transmitted(at);
    }

    /// The next frame to transmit to the power supply, if any (write it completely, then
    /// call again). The link's time-outs run here: when they raise events, [`Bridge::poll_at`]
    /// asks for a [`Bridge::poll`] at once (the frame borrows the link, so the events cannot
    /// be moved in the same call).
    pub fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        self.service(now);
        self.units.poll_transmit(now)
    }

    /// The UART settings the power-supply port must use now.
    pub fn ps_port_config(&self) -> PortConfig {
        self.units.port_config()
    }

    // --- CNC side -----------------------------------------------------------------------

    /// The UART settings the CNC port must use (`cnc_baud`, `cnc_parity`, `cnc_stop_bits`;
    /// changed by `CONFIG`, applied by the driver whenever it differs from the port's).
    pub fn cnc_port_config(&self) -> PortConfig {
        self.settings.cnc_port_config()
    }

    /// Bytes received from the CNC (any chunking).
    pub fn handle_cnc_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.service(now);
        self.session.handle_rx(&mut ctx!(self, now), bytes);
        self.service(now);
    }

    /// Bytes to write to the CNC UART: reply lines (CR LF), event lines, ACK/NAK bytes.
    /// The bytes are taken: write them all before calling again.
    pub fn poll_cnc_output(&mut self) -> Option<&[u8]> {
        self.session.poll_output()
    }

    /// The next simulator command (`TORCH ON|OFF`) for the simulator's driver.
    pub fn poll_sim_command(&mut self) -> Option<SimCommand> {
        self.session.poll_sim_command()
    }

    // --- time ---------------------------------------------------------------------------

    /// Move link events into the session (replies, event lines), answer waiting lines.
    pub fn poll(&mut self, now: Instant) {
        self.service(now);
    }

    /// When [`Bridge::poll`] / [`Bridge::poll_ps_transmit`] need to be called next: at once
    /// while the link holds events the session has not taken.
    pub fn poll_at(&self) -> Option<Instant> {
        if self.units_pending || self.units.has_events() {
            return Some(self.now);
        }
        match (self.units.poll_at(), self.session.poll_at()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// The named units, built in place once (see [`Bridge::new`]).
    fn start_units(&mut self, now: Instant) {
        if core::mem::take(&mut self.units_pending) {
            restart_units(&mut self.units, &self.settings, now);
        }
    }

    fn service(&mut self, now: Instant) {
        self.start_units(now);
        self.now = now;
        while let Some((unit, event)) = self.units.poll_event() {
            self.session
                .on_link_event(&mut ctx!(self, now, unit), &event);
        }
        self.session.poll(&mut ctx!(self, now));
        self.session.pump(&mut ctx!(self, now));
    }

    // --- discrete I/O exchange ----------------------------------------------------------

    /// What the interlocks need to know about the supply (the first unit's).
    pub fn supply_state(&self) -> SupplyState {
        self.supply_state_of(0)
    }

    /// How many units the bridge drives (`CONFIG units`; 1 by default).
    pub fn unit_count(&self) -> usize {
        self.units.count()
    }

    /// What unit `unit`'s interlocks need to know about its supply (0 = the first unit);
    /// a unit the bridge does not drive is a supply with no link.
    pub fn supply_state_of(&self, unit: usize) -> SupplyState {
        if unit >= self.units.count() {
            return SupplyState::default();
        }
        SupplyState::from(self.units.link(unit).status())
    }

    /// The interlocks' configuration (changes after `CONFIG <io key> <value>`).
    pub fn io_config(&self) -> IoConfig {
        self.settings.io
    }

    /// The new interlock configuration, once after a `CONFIG` change of an I/O key.
    pub fn take_io_config_change(&mut self) -> Option<IoConfig> {
        self.session
            .take_io_config_change()
            .then_some(self.settings.io)
    }

    /// The first unit's interlock inputs and outputs now (for STATUS).
    pub fn set_io_snapshot(&mut self, inputs: Inputs, outputs: Outputs) {
        self.set_io_snapshot_of(0, inputs, outputs);
    }

    /// Unit `unit`'s interlock inputs and outputs now (ignored for a unit out of range).
    pub fn set_io_snapshot_of(&mut self, unit: usize, inputs: Inputs, outputs: Outputs) {
        let Some(slot) = self.io.get_mut(unit) else {
            return;
        };
        *slot = Some((inputs, outputs));
        self.units.set_start(unit, outputs.start);
        let now = self.now;
        self.session.io_changed(&mut ctx!(self, now, unit));
    }

    /// Something the first unit's interlocks report (`!ARC ON`, `!START REFUSED ...` with
    /// events on).
    pub fn on_io_event(&mut self, now: Instant, event: IoEvent) {
        self.on_io_event_of(0, now, event);
    }

    /// Something unit `unit`'s interlocks report (its events carry `unit=N` beyond the
    /// first; ignored for a unit the bridge does not drive).
    pub fn on_io_event_of(&mut self, unit: usize, now: Instant, event: IoEvent) {
        if unit < self.units.count() {
            self.session.on_io_event(&mut ctx!(self, now, unit), event);
        }
    }

    // --- persistence --------------------------------------------------------------------

    /// The consumable record kept in flash ([`CONSUMABLES_KEY`](crate::storage::CONSUMABLES_KEY)),
    /// once at boot; without one the bridge starts a new set.
    pub fn restore_consumables(&mut self, set: ConsumableSet) {
        self.consumables.restore(set);
    }

    /// What to store now (once each): the settings after `CONFIG SAVE`, or the consumable
    /// record when it is due ([`crate::consumables`] says how often). The board writes it to
    /// flash and calls [`Bridge::save_finished`] before it asks again.
    pub fn take_save_request(&mut self) -> Option<SaveRequest> {
        if self.session.take_save_request() {
            return Some(SaveRequest::Settings(self.settings));
        }
        let set = self.consumables.take_save(self.now)?;
        self.saving_consumables = true;
        Some(SaveRequest::Consumables(set))
    }

    /// The store finished: answers `CONFIG SAVE` (`OK config=saved` or `ERR STORAGE ...`); a
    /// consumable record that was not stored is offered again later.
    pub fn save_finished(&mut self, now: Instant, result: Result<(), SaveError>) {
        if core::mem::take(&mut self.saving_consumables) {
            if result.is_err() {
                self.consumables.save_failed();
            }
            return;
        }
        self.session.save_finished(&mut ctx!(self, now), result);
        self.service(now);
    }

    // --- history ------------------------------------------------------------------------

    /// The board's reset and its cause go into the history (once, at boot).
    pub fn record_reset(&mut self, now: Instant, cause: ResetCause) {
        let event = Event::BridgeReset { cause };
        self.history.note(now, Unit::default(), event);
    }

    /// The oldest event waiting to be written to the history (never blocks anything: the
    /// queue is bounded, see [`Pending`](crate::storage::history::Pending)).
    pub fn take_history_draft(&mut self) -> Option<Draft> {
        self.history.take()
    }

    /// Whether events are still waiting for the history's writer.
    pub fn history_drafts_waiting(&self) -> bool {
        self.history.has_drafts()
    }

    /// After `HISTORY`: what to read or erase (once). Serve it ([`serve`](crate::storage::history::serve)) and call
    /// [`Bridge::history_finished`].
    pub fn take_history_request(&mut self) -> Option<HistoryRequest> {
        let command = self.session.take_history_request()?;
        Some(match command {
            HistoryCommand::Newest(n) => HistoryRequest::Newest(n),
            HistoryCommand::Clear => {
                let unit = crate::cnc::history::unit_on(&self.units, 0);
                HistoryRequest::Clear(self.history.stamp(self.now, unit))
            }
        })
    }

    /// The history's answer: the `HISTORY` lines and their closing reply.
    pub fn history_finished(&mut self, now: Instant, answer: &HistoryAnswer) {
        self.session.history_finished(&mut ctx!(self, now), answer);
        self.service(now);
    }

    // --- views --------------------------------------------------------------------------

    /// The settings in use (CONFIG changes and the confirmed process included).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// What the bridge knows about the (first) unit.
    pub fn status(&self) -> &UnitStatus {
        self.units.link(0).status()
    }

    /// What the bridge knows about unit `unit` (the first unit's for one out of range).
    pub fn status_of(&self, unit: usize) -> &UnitStatus {
        self.units.link(unit).status()
    }

    /// The (first) unit's link counters.
    pub fn diagnostics(&self) -> &Diagnostics {
        self.units.link(0).diagnostics()
    }

    /// CNC-side counters.
    pub fn session_stats(&self) -> &SessionStats {
        self.session.stats()
    }

    /// The (first) unit's link (read only), e.g. for its configuration.
    pub fn link(&self) -> &PsLink {
        self.units.link(0)
    }

    /// The units (read only).
    pub fn units(&self) -> &Units {
        &self.units
    }
}

/// The one translation of the link's view into what the interlocks need: the board's
/// [`Bridge::supply_state`] and a host loop driving a bare [`PsLink`] both use it.
impl From<&UnitStatus> for SupplyState {
    fn from(status: &UnitStatus) -> SupplyState {
        SupplyState {
            link_up: status.link_up,
            fault_requires_action: status.active_fault.is_some_and(|f| f.action_required()),
            fault_active: status.active_fault.is_some(),
            restart_blackout_until: status.restart_blackout_until,
            unit_ready: status.link_up && status.state_ready(),
        }
    }
}

// --- the loops' view ------------------------------------------------------------------

impl PsEndpoint for Bridge {
    fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]) {
        Bridge::handle_ps_rx(self, now, bytes);
    }

    fn handle_ps_rx_error(&mut self, now: Instant) {
        Bridge::handle_ps_rx_error(self, now);
    }

    fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        Bridge::poll_ps_transmit(self, now)
    }

    fn ps_transmitted(&mut self, at: Instant) {
        Bridge::ps_transmitted(self, at);
    }

    fn ps_port_config(&self) -> PortConfig {
        Bridge::ps_port_config(self)
    }

    fn poll_at(&self) -> Option<Instant> {
        Bridge::poll_at(self)
    }
}

impl BridgeEndpoint for Bridge {
    type Saved = SaveRequest;
    type SaveError = SaveError;

    fn handle_cnc_rx(&mut self, now: Instant, bytes: &[u8]) {
        Bridge::handle_cnc_rx(self, now, bytes);
    }
    fn poll_cnc_output(&mut self) -> Option<&[u8]> {
        Bridge::poll_cnc_output(self)
    }
    fn cnc_port_config(&self) -> PortConfig {
        Bridge::cnc_port_config(self)
    }
    fn poll(&mut self, now: Instant) {
        Bridge::poll(self, now);
    }
    fn unit_count(&self) -> usize {
        Bridge::unit_count(self)
    }
    fn supply_state_of(&self, unit: usize) -> SupplyState {
        Bridge::supply_state_of(self, unit)
    }
    fn io_config(&self) -> IoConfig {
        Bridge::io_config(self)
    }
    fn set_io_snapshot_of(&mut self, unit: usize, inputs: Inputs, outputs: Outputs) {
        Bridge::set_io_snapshot_of(self, unit, inputs, outputs);
    }
    fn on_io_event_of(&mut self, unit: usize, now: Instant, event: IoEvent) {
        Bridge::on_io_event_of(self, unit, now, event);
    }
    fn take_save_request(&mut self) -> Option<SaveRequest> {
        Bridge::take_save_request(self)
    }
    fn save_finished(&mut self, now: Instant, result: Result<(), SaveError>) {
        Bridge::save_finished(self, now, result);
    }
    fn take_history_draft(&mut self) -> Option<Draft> {
        Bridge::take_history_draft(self)
    }
    fn history_drafts_waiting(&self) -> bool {
        Bridge::history_drafts_waiting(self)
    }
    fn take_history_request(&mut self) -> Option<HistoryRequest> {
        Bridge::take_history_request(self)
    }
    fn history_finished(&mut self, now: Instant, answer: &HistoryAnswer) {
        Bridge::history_finished(self, now, answer);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use plasma_protocol::cnc::{Amps, Mode, Pressure};

    use super::*;
    use crate::cnc::rig::{NAK_TOKEN, Rig};
    use plasma_protocol::time::Duration;

    fn with_process(amps: u16, events: bool) -> Settings {
        Settings {
            events,
            process: Some(crate::settings::Process {
                mode: Mode::Cut,
                amps: Amps::from_raw(amps * 64),
                pressure: Pressure::Auto,
            }),
            ..Settings::default()
        }
    }

    #[test]
    fn a_kept_process_is_applied_again_after_power_up() {
        let mut rig = Rig::new(with_process(45, true), Some("sync65"));
        rig.run(800);
        assert_eq!(rig.writes(), std::vec![(0x3080, std::vec![1, 2880, 0])]);
        assert!(
            rig.received
                .contains(&"!SETTINGS applied mode=CUT amps=45 psi=72".to_string()),
            "{:?}",
            rig.received
        );
        assert!(
            rig.received.iter().all(|t| t.starts_with('!')),
            "no reply lines"
        );
        assert!(rig.bridge.status().remote);
    }

    #[test]
    fn a_kept_process_outside_the_limits_is_reported_and_not_sent() {
        let mut rig = Rig::new(with_process(100, true), Some("sync65"));
        rig.run(800);
        assert!(rig.writes().is_empty());
        assert!(
            rig.received.contains(
                &"!SETTINGS failed reason=refused why=current_100_A_outside_20-65_A".to_string()
            ),
            "{:?}",
            rig.received
        );
    }

    #[test]
    fn supply_state_follows_the_link() {
        let mut rig = Rig::new(Settings::default(), Some("sync65"));
        assert_eq!(rig.bridge.supply_state(), SupplyState::default());
        rig.run(600);
        assert_eq!(rig.bridge.supply_state(), SupplyState::HEALTHY);
        rig.fault(500);
        rig.run(300);
        let state = rig.bridge.supply_state();
        // The fault is its own field: a Powermax has no ready state besides its faults.
        assert!(state.fault_active && state.fault_requires_action && state.unit_ready);
        assert_eq!(rig.cmd("RESTART"), "OK restart=done quiet_ms=2000");
        let until = rig.bridge.supply_state().restart_blackout_until.unwrap();
        assert!(until > rig.now);
        assert_eq!(rig.bridge.io_config(), crate::io::IoConfig::default());
    }

    #[test]
    fn a_phoenix_frame_that_stops_arriving_is_naked_after_the_idle_time() {
        let mut rig = Rig::new(Settings::default(), None);
        rig.bridge.handle_cnc_rx(rig.now, b"\x01\x02FAU");
        let deadline = rig.now + crate::cnc::FRAME_IDLE_TIMEOUT;
        assert!(rig.bridge.poll_at().is_some_and(|at| at <= deadline));
        rig.bridge.poll(deadline - Duration::from_millis(1));
        rig.collect();
        assert!(rig.received.is_empty());
        rig.bridge.poll(deadline);
        rig.collect();
        assert_eq!(
            rig.received,
            [
                NAK_TOKEN,
                std::format!("ERR SYNTAX {}", crate::cnc::texts::PHOENIX_TRUNCATED).as_str()
            ]
        );
        // Text lines work again at once.
        assert!(rig.cmd("ID").starts_with("OK bridge=plasma-bridge"));
    }

    #[test]
    fn the_boot_report_is_an_event_and_part_of_id() {
        let mut rig = Rig::new(
            Settings {
                events: true,
                ..Settings::default()
            },
            None,
        );
        rig.bridge.set_boot_report(rig.now, "watchdog");
        rig.collect();
        assert_eq!(rig.received, ["!BOOT reason=watchdog version=0.1.0"]);
        assert_eq!(
            rig.cmd("ID"),
            "OK bridge=plasma-bridge version=0.1.0 reset=watchdog link=DOWN model=- family=-"
        );
    }
}
