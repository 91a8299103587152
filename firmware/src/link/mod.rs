//! The power-supply link: a sans-IO state machine that speaks Modbus ASCII to Powermax units
//! and `>ID data CK<` to HPR / MaxPro200 units.
//!
//! It never reads a clock or touches a UART: the caller feeds it received bytes and the time,
//! transmits what [`PsLink::poll_transmit`] returns with the port settings of
//! [`PsLink::port_config`], and wakes it at [`PsLink::poll_at`].
//!
//! # Board glue
//! - Received characters go to [`PsLink::handle_rx`] in any chunking. A character the UART
//!   flags with a parity or framing error goes to [`PsLink::handle_rx_error`] instead, in its
//!   place in the stream (the characters before it first): it breaks the frame it falls in,
//!   which the 8-bit LRC alone would not always notice.
//! - A frame from [`PsLink::poll_transmit`] is put on the wire at once and completely, with
//!   the port settings of [`PsLink::port_config`] applied first.
//! - The task sleeps until [`PsLink::poll_at`] or the next received character.
//! - On 2-wire RS-485 the glue may leave the receiver on while it transmits: a received frame
//!   equal to the request just sent is taken for its echo, counted
//!   ([`Diagnostics::echoes`]) and ignored. A reply that repeats its request (Modbus 05/06,
//!   some HPR settings) is told apart once the line is known to echo: the first copy in an
//!   attempt is the echo, the second the reply.
//!
//! # Detection and link-down
//! - Auto-detection asks Read Device Identification, then (no answer) the legacy register
//!   probe, then HPR HELLO at 8N1, in rounds over the Modbus parity / stop-bit combinations
//!   (the configured one first).
//! - Once a unit has been found, what found it (probe and port settings) is asked first after
//!   a link-down, and again between every two probes of that search, so a unit switched off
//!   and on is back within about half a second of its return while another kind of unit is
//!   still found. While a Modbus unit is expected back, the HPR probe's retries follow at
//!   once instead of riding through an HF-ignition blackout (no HPR cuts without a link).
//! - A step whose replies all arrived damaged (bad LRC, garbled) is asked again, up to
//!   [`DETECT_REASKS`](detect::DETECT_REASKS) times: a damaged reply shows a unit that speaks this protocol at this
//!   framing. Only silence or a clean exception moves detection on (a SYNC unit also answers
//!   the legacy probe, so it must not get there by accident).
//! - A unit the legacy probe found (no model known) is asked for its device identification
//!   again at every slow-data refresh; a SYNC unit then changes family (pending commands fail
//!   as on a link-down, `LinkUp` reports the unit again, kept settings are re-applied).
//! - Only silence counts toward link-down: [`LinkConfig::failures_before_down`] failed
//!   transactions in a row that heard nothing. Damaged replies prove the unit is there: they
//!   are counted and retried, and only [`UNANSWERED_FACTOR`](schedule::UNANSWERED_FACTOR) times as many failures in a row
//!   without a valid reply take the link down.
//!
//! # Kept settings
//! Settings the CNC set and the unit confirmed are kept ([`kept`], the one place that decides
//! what is re-applied and when) and re-applied when the link returns (after the unit's own
//! power cycle only with [`LinkConfig::reapply_after_power_cycle`]: [`kept`] tells the two
//! apart and reports [`LinkEvent::UnitPowerCycled`]): Powermax mode, current and pressure ([`Kept::powermax`], and once after start-up
//! the persisted process, [`PsLink::restore`]); HPR / MaxPro200 nominal current, corner
//! current, process and inlet gases ([`Kept::hpr_requests`], a later setting replacing what
//! it sets again), re-applied after 004 REMOTE_MODE once the unit is in state 2 or 3
//! (another HPR model on the line does not get them: `ProcessFailed { OutsideLimits }`).
//! An HPR setting counts as done only when the unit's answer shows the value asked for;
//! otherwise 004 is sent again and the setting once more (the unit may have restarted and
//! left remote mode), then it fails `NotAccepted`. An HPR that shows a restart the link did
//! not see as a link-down (a power blip: its state back to power-up, or a set point other than
//! the kept one) was power-cycled, like a Powermax that reads back other settings. A re-apply that
//! fails reports `ProcessFailed` and is tried again after a back-off: a setting is never
//! silently lost.
//!
//! # Scheduling
//! One request at a time, chosen in this order: the rest of a poll cycle split into parts,
//! the active command (or a re-apply of kept settings), then polls and everything else in
//! turn: after a poll, whatever else is due (slow data, the SYNC cartridge check, the
//! slow-data refresh, HPR error log and timers) gets one transaction before the next poll.
//! So even the shortest poll interval (a poll always due) starves nothing, and a poll waits
//! for at most one other transaction (a new fault is still known within 250 ms p99 on SYNC).
//!
//! Slow data (limits first) is read at start, on a cartridge change, on request and at each
//! refresh. A read that fails on the line is tried again soon, at the first turn after a
//! short wait (`slow::SLOW_RETRY_FIRST`), the wait doubling with each further failure up to
//! the slow-data interval; an exception waits for the next refresh.
//!
//! ```
//! use plasma_firmware::link::{LinkConfig, PsLink};
//! use plasma_protocol::time::Instant;
//!
//! let mut link = PsLink::new(LinkConfig::default(), Instant::ZERO);
//! // Auto-detection starts with Read Device Identification at node 1, 8E1.
//! let frame = link.poll_transmit(Instant::ZERO).unwrap();
//! assert_eq!(frame, b":012B0E0401C1\r\n");
//! // The unit answers: a Powermax65/85/105 SYNC.
//! link.handle_rx(Instant::from_millis(20), b":012B0E0481000101010630383133333504\r\n");
//! assert!(link.status().link_up);
//! ```
//!
//! # Where things are
//! - This file: the public types and [`PsLink`]'s entry points. `core.rs`: `Core`, the state
//!   the family drivers and detection share (configuration, status, counters, kept settings,
//!   events).
//! - The link's own machinery, as `impl PsLink` blocks: `detect.rs` (auto-detection),
//!   `schedule.rs` (the transaction in flight, link-down counting), `receive.rs` (received
//!   frames to answers), `phase.rs` (link up, re-identification, link down).
//! - The family drivers, their own types: `powermax/` (with the Modbus pieces, `modbus.rs`,
//!   and the SYNC and legacy register maps, `sync.rs` and `legacy.rs`) and `hpr/`.
//! - Shared parts: `transaction.rs`, `slow.rs`, `kept.rs`, `event.rs`, `status.rs`,
//!   `diagnostics.rs`, `config.rs`.
//! - Tests sit beside the file they test (`detect/tests.rs` for `detect.rs`, ...), with the
//!   byte-level test bench in `test_support.rs`.

pub(crate) mod command;
pub(crate) mod config;
mod core;
mod detect;
pub(crate) mod diagnostics;
pub(crate) mod event;
pub(crate) mod hpr;
pub(crate) mod kept;
mod line;
pub(crate) mod model_code;
mod phase;
pub(crate) mod powermax;
mod receive;
mod schedule;
pub(crate) mod slow;
pub(crate) mod status;
pub(crate) mod transaction;
mod units;

#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;

use heapless::Vec;
use plasma_protocol::hpr as hpr_wire;
use plasma_protocol::modbus_ascii;

pub use command::{HprValue, LinkCommand, RAW_CAPACITY, Refusal};
pub use config::{ConfigError, LinkConfig, ProtocolChoice};
pub use diagnostics::Diagnostics;
pub use event::{CommandFailure, CommandOutput, LinkDownReason, LinkEvent, ProcessFailure, Ticket};
pub use status::{
    ActiveFault, Family, Firmware, HprStatus, Limits, Model, PowermaxProcess, Revision, UnitStatus,
};
pub use transaction::TransactionError;

use self::core::Core;
use detect::{DetectStep, Detector, KnownGood};
pub use kept::Kept;
pub use line::{LineError, LineStats, LineUnit, MAX_UNITS, NamedUnits, SharedLine, UnitsError};
use phase::Phase;
pub use powermax::FAULT_CHECK_INTERVAL;
use schedule::Tag;
pub use transaction::TX_CAPACITY;
use transaction::Transaction;
pub use units::Units;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

/// Which framing the receiver expects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wire {
    Modbus,
    Hpr,
}

/// The power-supply link.
#[derive(Debug)]
pub struct PsLink {
    core: Core,
    phase: Phase,
    port: PortConfig,
    wire: Wire,
    txn: Option<Transaction<Tag>>,
    modbus_rx: modbus_ascii::Decoder,
    hpr_rx: hpr_wire::Decoder,
    /// Failed transactions in a row that heard nothing at all (silence).
    consecutive_failures: u8,
    /// Failed transactions in a row, silent or with damaged replies only.
    unanswered: u8,
    next_ticket: u32,
    raw_reply: Vec<u8, TX_CAPACITY>,
    /// The line has been heard echoing our requests (2-wire, receiver on).
    line_echoes: bool,
    /// What found the unit last time (kept across link-downs).
    last_good: Option<KnownGood>,
    /// The echo of the attempt on the wire has been heard.
    echo_in_attempt: bool,
    now: Instant,
}

impl PsLink {
    /// A link that starts detecting at `now`. Fields out of range are clamped into range;
    /// use [`PsLink::try_new`] to have them refused instead.
    pub fn new(config: LinkConfig, now: Instant) -> Self {
        let config = config.clamped();
        let mut link = PsLink {
            core: Core::new(config),
            phase: Phase::Detecting(Detector::searching(DetectStep::DeviceId, 0, now)),
            port: config.modbus_port(),
            wire: Wire::Modbus,
            txn: None,
            modbus_rx: modbus_ascii::Decoder::new(),
            hpr_rx: hpr_wire::Decoder::new(),
            consecutive_failures: 0,
            unanswered: 0,
            next_ticket: 1,
            raw_reply: Vec::new(),
            line_echoes: false,
            echo_in_attempt: false,
            last_good: None,
            now,
        };
        link.start_detection(now, 0);
        link
    }

    /// A link for a configuration that passes [`LinkConfig::validate`].
    pub fn try_new(config: LinkConfig, now: Instant) -> Result<Self, ConfigError> {
        config.validate()?;
        Ok(Self::new(config, now))
    }

    /// Bytes received on the PS UART (any chunking).
    pub fn handle_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.now = now;
        let mut rest = bytes;
        while !rest.is_empty() {
            let used = match self.wire {
                Wire::Modbus => self.receive_modbus(now, rest),
                Wire::Hpr => self.receive_hpr(now, rest),
            };
            rest = rest.get(used..).unwrap_or(&[]);
            if used == 0 {
                break;
            }
        }
        self.core.status.update_ready(now);
    }

    /// A character arrived with a UART parity or framing error.
    ///
    /// The board glue calls this where the flagged character falls in the received stream:
    /// `handle_rx` with the characters before it, then `handle_rx_error`, then `handle_rx`
    /// with the rest (the flagged character itself is not handed over). A flagged character
    /// breaks the frame in progress: the frame is rejected at once, like a reply with a bad
    /// checksum (the attempt is retried), even when the 8-bit LRC or checksum would have let
    /// two cancelling errors through. A flagged character between frames only counts. Every
    /// call counts in [`Diagnostics::rx_errors`].
    pub fn handle_rx_error(&mut self, now: Instant) {
        self.now = now;
        self.core.diagnostics.record_rx_error();
        let in_frame = match self.wire {
            Wire::Modbus => self.modbus_rx.in_frame(),
            Wire::Hpr => self.hpr_rx.in_frame(),
        };
        if in_frame {
            self.modbus_rx.reset();
            self.hpr_rx.reset();
            match &self.txn {
                Some(txn) if txn.is_awaiting_reply() => {
                    self.attempt_failed(now, TransactionError::Malformed);
                }
                _ => self.core.diagnostics.record_unsolicited(),
            }
        }
        self.core.status.update_ready(now);
    }

    /// Bytes to put on the wire now (one whole frame), if any. The caller transmits them
    /// completely before calling again. Returns None while waiting for a reply/time-out.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        self.now = now;
        self.handle_timeout(now);
        if self.txn.is_none() {
            self.start_next(now);
        }
        self.core.status.update_ready(now);
        let wire = self.wire;
        let frame = self.txn.as_mut()?.poll_transmit(now)?;
        // A new attempt starts with a clean receiver: leftovers of a damaged reply must not
        // be taken for the answer.
        self.echo_in_attempt = false;
        match wire {
            Wire::Modbus => self.modbus_rx.reset(),
            Wire::Hpr => self.hpr_rx.reset(),
        }
        Some(frame)
    }

    /// The port settings the UART must use now (changes during auto-detection).
    pub fn port_config(&self) -> PortConfig {
        self.port
    }

    /// Earliest time at which `poll_transmit`/timers need attention. None = only new rx or
    /// commands matter. After a `poll_transmit` that sent nothing, this is always later than
    /// that call's `now`: a task sleeping until then never spins.
    pub fn poll_at(&self) -> Option<Instant> {
        if let Some(txn) = &self.txn {
            return Some(txn.poll_at());
        }
        match &self.phase {
            Phase::Detecting(d) => Some(d.not_before()),
            Phase::Powermax(d) => d.wake_at(&self.core),
            Phase::Hpr(d) => d.wake_at(&self.core),
        }
    }

    /// Drain events for the rest of the bridge.
    pub fn poll_event(&mut self) -> Option<LinkEvent> {
        self.core.pop_event()
    }

    /// True while events wait for [`PsLink::poll_event`].
    pub(crate) fn has_events(&self) -> bool {
        self.core.has_events()
    }

    /// Ask for an operation. Validates against the unit's limits BEFORE anything is sent;
    /// Err = refused with a precise reason, nothing sent.
    // Not inlined into its one caller in the image (the session): that costs ~300 B of flash.
    #[inline(never)]
    pub fn submit(&mut self, now: Instant, command: LinkCommand<'_>) -> Result<Ticket, Refusal> {
        self.now = now;
        let ticket = Ticket(self.next_ticket);
        match &mut self.phase {
            Phase::Detecting(_) => return Err(Refusal::LinkNotUp),
            Phase::Powermax(driver) => driver.submit(now, ticket, &command, &mut self.core)?,
            Phase::Hpr(driver) => driver.submit(now, ticket, &command, &mut self.core)?,
        }
        self.next_ticket = self.next_ticket.wrapping_add(1).max(1);
        Ok(ticket)
    }

    /// Snapshot of what the bridge knows about the unit.
    pub fn status(&self) -> &UnitStatus {
        &self.core.status
    }

    /// Diagnostics counters.
    pub fn diagnostics(&self) -> &Diagnostics {
        &self.core.diagnostics
    }

    /// What the link re-applies (see [`kept`]).
    pub fn kept(&self) -> &Kept {
        &self.core.kept
    }

    /// Apply `settings` (the persisted process) once a Powermax with known limits answers,
    /// unless the CNC sets a process first. Refused settings are reported with
    /// [`LinkEvent::RestoreRefused`] and dropped.
    pub fn restore(&mut self, settings: PowermaxProcess) {
        self.core.kept.restore(settings);
    }

    /// The reply frame of the last RAW command (see [`CommandOutput::Raw`]).
    pub fn raw_reply(&self) -> &[u8] {
        &self.raw_reply
    }

    /// Use another configuration: whatever is in progress is abandoned (pending commands fail
    /// with [`CommandFailure::LinkDown`], a link that was up reports
    /// [`LinkDownReason::Reconfigured`]) and detection starts again. Kept settings stay.
    /// A change of [`LinkConfig::reapply_after_power_cycle`] alone is taken as it is, without
    /// detection ([`LinkConfig::needs_redetect`]).
    pub fn reconfigure(&mut self, now: Instant, config: LinkConfig) {
        self.now = now;
        if config != self.core.config && !self.core.config.needs_redetect(&config) {
            self.core.config = config;
            return;
        }
        let was_up = self.abort_unit();
        let config = config.clamped();
        let old = self.core.config;
        if (
            config.protocol,
            config.modbus_port(),
            config.hpr_id,
            config.node_address,
        ) != (
            old.protocol,
            old.modbus_port(),
            old.hpr_id,
            old.node_address,
        ) {
            self.last_good = None;
        }
        self.core.config = config;
        self.core.status.forget_unit();
        if was_up {
            self.core.emit(LinkEvent::LinkDown {
                reason: LinkDownReason::Reconfigured,
            });
        }
        self.txn = None;
        self.consecutive_failures = 0;
        self.unanswered = 0;
        self.modbus_rx.reset();
        self.hpr_rx.reset();
        self.start_detection(now, 0);
    }

    /// The configuration in use (after clamping).
    pub fn config(&self) -> &LinkConfig {
        &self.core.config
    }
}
