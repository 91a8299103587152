//! The power-supply link (see notes/LINK-DESIGN.md): a sans-IO state machine that speaks
//! Modbus ASCII to Powermax units and `>ID data CK<` to HPR / MaxPro200 units.
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
//!   [`DETECT_REASKS`] times: a damaged reply shows a unit that speaks this protocol at this
//!   framing. Only silence or a clean exception moves detection on (a SYNC unit also answers
//!   the legacy probe, so it must not get there by accident).
//! - A unit the legacy probe found (no model known) is asked for its device identification
//!   again at every slow-data refresh; a SYNC unit then changes family (pending commands fail
//!   as on a link-down, `LinkUp` reports the unit again, kept settings are re-applied).
//! - Only silence counts toward link-down: [`LinkConfig::failures_before_down`] failed
//!   transactions in a row that heard nothing. Damaged replies prove the unit is there: they
//!   are counted and retried, and only [`UNANSWERED_FACTOR`] times as many failures in a row
//!   without a valid reply take the link down.
//!
//! # Kept settings
//! Settings the CNC set and the unit confirmed are kept and re-applied after the unit
//! power-cycles or the link returns: Powermax mode, current and pressure
//! ([`UnitStatus::desired`]); HPR / MaxPro200 nominal current, corner current, process,
//! all parameters and inlet gases ([`PsLink::hpr_kept_settings`], a later setting replacing
//! what it sets again), re-applied after 004 REMOTE_MODE once the unit is in state 2 or 3
//! (another HPR model on the line does not get them: `SettingsFailed { OutsideLimits }`).
//! An HPR setting counts as done only when the unit's answer shows the value asked for;
//! otherwise 004 is sent again and the setting once more (the unit may have restarted and
//! left remote mode), then it fails `NotAccepted`. An HPR that shows a restart the link did
//! not see as a link-down (a power blip: its state back to power-up, or a set point other than
//! the kept one) has remote mode entered again and its settings re-applied. A re-apply that
//! fails reports `SettingsFailed` and is tried again after a back-off: a setting is never
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
//! refresh. A read that fails on the line is tried again soon, at the first turn after
//! [`slow::SLOW_RETRY_FIRST`], the wait doubling with each further failure up to the
//! slow-data interval; an exception waits for the next refresh.
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

pub mod command;
pub mod config;
pub mod diagnostics;
pub mod event;
pub mod hpr;
pub mod legacy;
pub mod modbus;
pub mod powermax;
pub mod slow;
pub mod status;
pub mod support;
pub mod sync;
pub mod transaction;

#[cfg(test)]
mod tests;

use heapless::Vec;
use plasma_protocol::hpr::{self as hpr_wire, Reply, SystemId};
use plasma_protocol::modbus_ascii::{self, Response};
use plasma_protocol::powermax::{
    AddressingSystem, PowerSupplyModel, device_id, legacy as pm_legacy,
};

pub use command::{HprGasFlow, HprValue, LinkCommand, Refusal};
pub use config::{ConfigError, LinkConfig, ProtocolChoice};
pub use diagnostics::Diagnostics;
pub use event::{
    CommandFailure, CommandOutput, LinkDownReason, LinkEvent, SettingsFailure, Ticket,
};
pub use status::{ActiveFault, Family, Limits, Model, PowermaxSettings, UnitStatus};
pub use transaction::TransactionError;

use event::EventQueue;
pub use hpr::HprKept;
use hpr::{HprDriver, HprExpect, HprPurpose};
use modbus::MbRequest;
use powermax::{MbPurpose, PowermaxDriver, Variant};
use transaction::{Outcome, RetrySpacing, TX_CAPACITY, Transaction};

use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_protocol::time::{Duration, Instant};

/// Pause between two detection rounds, so a silent line is not hammered.
pub const DETECT_ROUND_PAUSE: Duration = Duration::from_millis(250);
/// A unit that answers, but only with damaged replies, is declared down after this many
/// times [`LinkConfig::failures_before_down`] failed transactions in a row (a line too noisy
/// to carry a single valid reply is no link, but a damaged reply is no silence either).
pub const UNANSWERED_FACTOR: u8 = 4;
/// Times a detection step whose replies all arrived damaged is asked again before detection
/// moves on (a damaged reply shows a unit that speaks this protocol at this framing).
pub const DETECT_REASKS: u8 = 3;
/// Quiet time after HPR SLEEP (086), which no unit answers.
pub const SLEEP_QUIET: Duration = Duration::from_millis(20);

/// Modbus line settings tried in turn by auto-detection (the configured one first).
const MODBUS_FRAMINGS: [(Parity, StopBits); 6] = [
    (Parity::Even, StopBits::One),
    (Parity::Odd, StopBits::One),
    (Parity::None, StopBits::One),
    (Parity::Even, StopBits::Two),
    (Parity::Odd, StopBits::Two),
    (Parity::None, StopBits::Two),
];

/// State shared by the link and its family drivers.
#[derive(Debug)]
pub struct Core {
    /// The (validated) configuration.
    pub config: LinkConfig,
    /// What is known about the unit.
    pub status: UnitStatus,
    /// Counters.
    pub diagnostics: Diagnostics,
    /// HPR / MaxPro200 settings to keep and re-apply (the Powermax ones are
    /// [`UnitStatus::desired`]).
    pub hpr_kept: HprKept,
    events: EventQueue,
}

impl Core {
    /// Queue an event.
    pub fn emit(&mut self, event: LinkEvent) {
        self.events.push(event, &mut self.diagnostics);
    }

    /// The link went down: the active command (`active`, when there is one) and every queued
    /// one fail.
    pub fn fail_commands<J, const N: usize>(
        &mut self,
        active: Option<Ticket>,
        queue: &mut heapless::Deque<(Ticket, J), N>,
    ) {
        let queued = core::iter::from_fn(|| queue.pop_front().map(|(ticket, _)| ticket));
        for ticket in active.into_iter().chain(queued) {
            self.emit(LinkEvent::CommandDone {
                ticket,
                result: Err(CommandFailure::LinkDown),
            });
        }
    }

    /// The unit's active fault is now `new`: a change is reported (the old fault cleared,
    /// the new one raised). False when nothing changed.
    pub fn set_active_fault(&mut self, new: Option<ActiveFault>) -> bool {
        if self.status.active_fault == new {
            return false;
        }
        if let Some(old) = self.status.active_fault {
            self.emit(LinkEvent::FaultCleared { code: old });
        }
        if let Some(fault) = new {
            self.emit(LinkEvent::FaultRaised {
                code: fault,
                action_required: fault.action_required(),
            });
        }
        self.status.active_fault = new;
        true
    }
}

/// Which framing the receiver expects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wire {
    Modbus,
    Hpr,
}

/// Auto-detection steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DetectStep {
    /// Read Device Identification (2B/0E, code 04, object 01).
    DeviceId,
    /// Plain legacy register read (0x2098) for units without device identification.
    LegacyProbe,
    /// HPR multi-drop: SLEEP all systems.
    HprSleep,
    /// HPR multi-drop: WAKE the configured id.
    HprWake,
    /// HPR HELLO (000).
    HprHello,
}

#[derive(Debug, Clone)]
struct Detector {
    /// The step asked now.
    step: DetectStep,
    /// True while asking the last known-good probe ([`KnownGood`]); false in the search.
    good: bool,
    /// The full search: its round (which Modbus framing) and the step it asks next.
    round: u32,
    search: DetectStep,
    not_before: Instant,
    /// Times this step was asked again because its replies arrived damaged.
    reasks: u8,
}

/// What found the unit last time: the probe (its first step) and the port settings. After a
/// link-down it is asked first, and again between every two probes of the full search, so
/// a unit that was switched off is found again within a probe or two of its return.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct KnownGood {
    step: DetectStep,
    port: PortConfig,
}

#[derive(Debug, Clone)]
enum DetectExpect {
    Modbus(MbRequest),
    Hpr(hpr_wire::Request),
}

#[derive(Debug, Clone)]
enum Tag {
    Detect(DetectStep, DetectExpect),
    Modbus(MbPurpose, MbRequest),
    Hpr(HprPurpose, HprExpect),
}

// One phase at a time, held inline (no allocator).
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
enum Phase {
    Detecting(Detector),
    Powermax(PowermaxDriver),
    Hpr(HprDriver),
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

/// Clamp every field of `config` into its valid range (used by [`PsLink::new`]).
fn sanitize(config: LinkConfig) -> LinkConfig {
    let clamp = |d: Duration, lo: Duration, hi: Duration| d.max(lo).min(hi);
    LinkConfig {
        node_address: config.node_address.max(1),
        response_timeout: clamp(
            config.response_timeout,
            LinkConfig::MIN_RESPONSE_TIMEOUT,
            LinkConfig::MAX_RESPONSE_TIMEOUT,
        ),
        retries: config.retries.min(LinkConfig::MAX_RETRIES),
        poll_interval: clamp(
            config.poll_interval,
            LinkConfig::MIN_POLL_INTERVAL,
            LinkConfig::MAX_POLL_INTERVAL,
        ),
        slow_data_interval: clamp(
            config.slow_data_interval,
            LinkConfig::MIN_SLOW_DATA_INTERVAL,
            LinkConfig::MAX_SLOW_DATA_INTERVAL,
        ),
        hpr_id: config.hpr_id.min(LinkConfig::MAX_HPR_ID),
        failures_before_down: config
            .failures_before_down
            .clamp(1, LinkConfig::MAX_FAILURES_BEFORE_DOWN),
        ..config
    }
}

impl PsLink {
    /// A link that starts detecting at `now`. Fields out of range are clamped into range;
    /// use [`PsLink::try_new`] to have them refused instead.
    pub fn new(config: LinkConfig, now: Instant) -> Self {
        let config = sanitize(config);
        let mut link = PsLink {
            core: Core {
                config,
                status: UnitStatus::default(),
                diagnostics: Diagnostics::default(),
                hpr_kept: HprKept::default(),
                events: EventQueue::new(),
            },
            phase: Phase::Detecting(Detector {
                step: DetectStep::DeviceId,
                good: false,
                round: 0,
                search: DetectStep::DeviceId,
                not_before: now,
                reasks: 0,
            }),
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
            match self.wire {
                Wire::Modbus => {
                    let (used, result) = self.modbus_rx.feed(rest);
                    let owned = result.map(|r| {
                        r.and_then(|frame| {
                            Vec::<u8, { modbus_ascii::MAX_FRAME_BYTES }>::from_slice(frame.pdu)
                                .map(|pdu| (frame.address, pdu))
                                .map_err(|_| plasma_protocol::Error::Overlong)
                        })
                    });
                    rest = rest.get(used..).unwrap_or(&[]);
                    if let Some(result) = owned {
                        self.on_modbus_frame(now, result);
                    }
                    if used == 0 {
                        break;
                    }
                }
                Wire::Hpr => {
                    let (used, result) = self.hpr_rx.feed(rest);
                    let owned = result.map(|r| {
                        r.and_then(|frame| {
                            Vec::<u8, { hpr_wire::MAX_FRAME_LEN }>::from_slice(frame.data)
                                .map(|data| (frame.id, data))
                                .map_err(|_| plasma_protocol::Error::Overlong)
                        })
                    });
                    rest = rest.get(used..).unwrap_or(&[]);
                    if let Some(result) = owned {
                        self.on_hpr_frame(now, result);
                    }
                    if used == 0 {
                        break;
                    }
                }
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
            Phase::Detecting(d) => Some(d.not_before),
            Phase::Powermax(d) => d.wake_at(&self.core),
            Phase::Hpr(d) => d.wake_at(&self.core),
        }
    }

    /// Drain events for the rest of the bridge.
    pub fn poll_event(&mut self) -> Option<LinkEvent> {
        self.core.events.pop()
    }

    /// Ask for an operation. Validates against the unit's limits BEFORE anything is sent;
    /// Err = refused with a precise reason, nothing sent.
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

    /// The HPR / MaxPro200 settings the CNC set and the unit confirmed, kept across
    /// link-downs and re-applied (after 004 REMOTE_MODE) when the unit returns or restarts.
    pub fn hpr_kept_settings(&self) -> &[plasma_protocol::hpr::Request] {
        self.core.hpr_kept.as_slice()
    }

    /// The reply frame of the last RAW command (see [`CommandOutput::Raw`]).
    pub fn raw_reply(&self) -> &[u8] {
        &self.raw_reply
    }

    /// Use another configuration: whatever is in progress is abandoned (pending commands fail
    /// with [`CommandFailure::LinkDown`], a link that was up reports
    /// [`LinkDownReason::Reconfigured`]) and detection starts again. Kept settings stay.
    pub fn reconfigure(&mut self, now: Instant, config: LinkConfig) {
        self.now = now;
        let was_up = match &mut self.phase {
            Phase::Powermax(driver) => {
                driver.abort(&mut self.core);
                true
            }
            Phase::Hpr(driver) => {
                driver.abort(&mut self.core);
                true
            }
            Phase::Detecting(_) => false,
        };
        let config = sanitize(config);
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

    // --- detection ---------------------------------------------------------------------

    fn first_step(&self) -> DetectStep {
        match self.core.config.protocol {
            ProtocolChoice::Hpr => self.hpr_first_step(),
            _ => DetectStep::DeviceId,
        }
    }

    fn hpr_first_step(&self) -> DetectStep {
        if self.core.config.hpr_id == 0 {
            DetectStep::HprHello
        } else {
            DetectStep::HprSleep
        }
    }

    /// Begin detecting from `not_before`: the last known-good probe first, if any, then the
    /// full search from its `round`.
    fn start_detection(&mut self, not_before: Instant, round: u32) {
        self.resume_detection(not_before, self.first_step(), round);
    }

    /// Like [`PsLink::start_detection`], with the search going on at `search`.
    fn resume_detection(&mut self, not_before: Instant, search: DetectStep, round: u32) {
        let mut detector = Detector {
            step: search,
            good: false,
            round,
            search,
            not_before,
            reasks: 0,
        };
        match self.last_good {
            Some(good) => {
                detector.step = good.step;
                detector.good = true;
                self.use_port(good.step, good.port);
            }
            None => self.set_port_for(search, round),
        }
        self.phase = Phase::Detecting(detector);
    }

    fn set_port_for(&mut self, step: DetectStep, round: u32) {
        let port = self.port_for(step, round);
        self.use_port(step, port);
    }

    /// The port settings for `step` in search round `round`.
    fn port_for(&self, step: DetectStep, round: u32) -> PortConfig {
        match step {
            DetectStep::DeviceId | DetectStep::LegacyProbe => self.modbus_framing(round),
            DetectStep::HprSleep | DetectStep::HprWake | DetectStep::HprHello => PortConfig::HPR,
        }
    }

    fn use_port(&mut self, step: DetectStep, port: PortConfig) {
        let wire = match step {
            DetectStep::DeviceId | DetectStep::LegacyProbe => Wire::Modbus,
            DetectStep::HprSleep | DetectStep::HprWake | DetectStep::HprHello => Wire::Hpr,
        };
        self.port = port;
        if self.wire != wire {
            self.modbus_rx.reset();
            self.hpr_rx.reset();
        }
        self.wire = wire;
    }

    /// Modbus line settings for detection round `round`: the configured ones, and in auto
    /// mode the other parity / stop-bit combinations in turn.
    fn modbus_framing(&self, round: u32) -> PortConfig {
        let configured = self.core.config.modbus_port();
        if self.core.config.protocol != ProtocolChoice::Auto {
            return configured;
        }
        let index = (round % MODBUS_FRAMINGS.len() as u32) as usize;
        if index == 0 {
            return configured;
        }
        MODBUS_FRAMINGS
            .iter()
            .filter(|(p, s)| !(*p == configured.parity && *s == configured.stop_bits))
            .nth(index - 1)
            .map_or(configured, |&(parity, stop_bits)| PortConfig {
                parity,
                stop_bits,
                ..configured
            })
    }

    fn detect_request(&self, step: DetectStep) -> Option<DetectExpect> {
        match step {
            DetectStep::DeviceId => {
                MbRequest::from_request(&device_id::read_product_code()).map(DetectExpect::Modbus)
            }
            DetectStep::LegacyProbe => {
                MbRequest::from_request(&pm_legacy::read_fault()).map(DetectExpect::Modbus)
            }
            DetectStep::HprSleep => Some(DetectExpect::Hpr(hpr_wire::Request::Sleep)),
            DetectStep::HprWake => Some(DetectExpect::Hpr(hpr_wire::Request::Wake {
                system_id: self.core.config.hpr_id,
            })),
            DetectStep::HprHello => Some(DetectExpect::Hpr(hpr_wire::Request::Hello)),
        }
    }

    /// Ask the current detection step again (its replies were damaged), unless it has been
    /// asked again [`DETECT_REASKS`] times already. Returns false when it has.
    fn reask(&mut self, now: Instant) -> bool {
        let Phase::Detecting(detector) = &mut self.phase else {
            return false;
        };
        if detector.reasks >= DETECT_REASKS {
            return false;
        }
        detector.reasks += 1;
        detector.not_before = now;
        true
    }

    /// The step that follows `step` in a search round, `None` at the end of the round.
    fn step_after(&self, step: DetectStep) -> Option<DetectStep> {
        match (step, self.core.config.protocol) {
            (DetectStep::DeviceId, ProtocolChoice::Auto | ProtocolChoice::Legacy) => {
                Some(DetectStep::LegacyProbe)
            }
            (DetectStep::LegacyProbe, ProtocolChoice::Auto) => Some(self.hpr_first_step()),
            (DetectStep::HprSleep, _) => Some(DetectStep::HprWake),
            (DetectStep::HprWake, _) => Some(DetectStep::HprHello),
            _ => None,
        }
    }

    /// The search position after the probe that begins with `first` in round `round`, and
    /// whether the round ended (a pause follows).
    fn search_after(&self, first: DetectStep, round: u32) -> (DetectStep, u32, bool) {
        // SLEEP, WAKE and HELLO are one probe.
        let last = match first {
            DetectStep::HprSleep | DetectStep::HprWake => DetectStep::HprHello,
            other => other,
        };
        match self.step_after(last) {
            Some(next) => (next, round, false),
            None => (self.first_step(), round.wrapping_add(1), true),
        }
    }

    /// The step `step` did not find a unit: go on with the next one.
    fn detect_next(&mut self, now: Instant, step: DetectStep) {
        let Phase::Detecting(detector) = &self.phase else {
            return;
        };
        let (good_probe, round, search) = (detector.good, detector.round, detector.search);
        // SLEEP and WAKE go on to HELLO whatever came of them.
        let chained = matches!(step, DetectStep::HprSleep | DetectStep::HprWake);
        let Some(good) = self.last_good else {
            // No unit known yet: the search alone, a pause after each round.
            match self.step_after(step) {
                Some(next) => self.enter_search(now, next, round),
                None => self.start_detection(now + DETECT_ROUND_PAUSE, round.wrapping_add(1)),
            }
            return;
        };
        if chained && let Some(next) = self.step_after(step) {
            let port = self.port;
            self.use_port(next, port);
            if let Phase::Detecting(detector) = &mut self.phase {
                detector.step = next;
                detector.not_before = now;
                detector.reasks = 0;
            }
            return;
        }
        if good_probe {
            // The known-good probe found nothing: one probe of the search, unless that is
            // the known-good probe itself (then the one after it).
            let mut position = (search, round, false);
            if self.is_known_good(good, position.0, position.1) {
                position = self.search_after(position.0, position.1);
                if position.2 || self.is_known_good(good, position.0, position.1) {
                    // Nothing else to try in this round: pause, then the known-good again.
                    self.resume_detection(now + DETECT_ROUND_PAUSE, position.0, position.1);
                    return;
                }
            }
            self.enter_search(now, position.0, position.1);
            return;
        }
        // A search probe found nothing: remember where the search stands, then the
        // known-good probe again (after a pause at the end of a round).
        let first = if step == DetectStep::HprHello {
            self.hpr_first_step()
        } else {
            step
        };
        let (next, next_round, wrapped) = self.search_after(first, round);
        let pause = if wrapped {
            DETECT_ROUND_PAUSE
        } else {
            Duration::ZERO
        };
        self.resume_detection(now + pause, next, next_round);
    }

    /// True when the search probe `step` of round `round` is the known-good probe.
    fn is_known_good(&self, good: KnownGood, step: DetectStep, round: u32) -> bool {
        step == good.step && self.port_for(step, round) == good.port
    }

    fn enter_search(&mut self, now: Instant, step: DetectStep, round: u32) {
        self.phase = Phase::Detecting(Detector {
            step,
            good: false,
            round,
            search: step,
            not_before: now,
            reasks: 0,
        });
        self.set_port_for(step, round);
    }

    fn link_up(&mut self, now: Instant, model: Model, family: Family) {
        if let Phase::Detecting(detector) = &self.phase {
            let step = match detector.step {
                DetectStep::HprHello | DetectStep::HprWake | DetectStep::HprSleep => {
                    self.hpr_first_step()
                }
                other => other,
            };
            self.last_good = Some(KnownGood {
                step,
                port: self.port,
            });
        }
        self.consecutive_failures = 0;
        self.unanswered = 0;
        self.core.status.family = Some(family);
        self.core.status.model = Some(model);
        self.core.status.link_up = true;
        self.core.emit(LinkEvent::LinkUp { model, family });
        self.phase = match family {
            Family::PowermaxSync => {
                Phase::Powermax(PowermaxDriver::new(Variant::Sync, now, &self.core))
            }
            Family::PowermaxLegacy => {
                Phase::Powermax(PowermaxDriver::new(Variant::Legacy, now, &self.core))
            }
            Family::Hpr | Family::MaxPro200 => {
                let system = match model {
                    Model::Hpr(system) => system,
                    _ => SystemId::MaxPro200,
                };
                Phase::Hpr(HprDriver::new(system, now, &mut self.core))
            }
        };
    }

    /// A Modbus unit answered device identification (`model` if Table 2 knows it).
    fn detected_modbus(&mut self, now: Instant, model: Option<PowerSupplyModel>) {
        let choice = self.core.config.protocol;
        let variant = match (choice, model.map(|m| m.addressing())) {
            (ProtocolChoice::Sync, _) => Some(Family::PowermaxSync),
            (ProtocolChoice::Legacy, _) => Some(Family::PowermaxLegacy),
            (_, Some(AddressingSystem::Sync)) => Some(Family::PowermaxSync),
            (_, Some(AddressingSystem::Legacy)) => Some(Family::PowermaxLegacy),
            (_, None) => None,
        };
        match (variant, model) {
            (Some(family), Some(model)) => self.link_up(now, Model::Powermax(model), family),
            (Some(family), None) => self.link_up(now, Model::PowermaxUnidentified, family),
            // Unknown product code: the legacy register read decides.
            (None, _) => self.detect_next(now, DetectStep::DeviceId),
        }
    }

    /// A unit running as legacy (found by the register probe) answered device
    /// identification with `model`. A SYNC unit changes family: pending commands fail as on a
    /// link-down (kept settings stay and are re-applied), and `LinkUp` reports the unit again
    /// with its model and family.
    fn reidentified(&mut self, now: Instant, model: Option<PowerSupplyModel>) {
        let Some(model) = model else {
            return;
        };
        if model.addressing() != AddressingSystem::Sync {
            self.core.status.model = Some(Model::Powermax(model));
            return;
        }
        if let Phase::Powermax(driver) = &mut self.phase {
            driver.abort(&mut self.core);
        }
        if let Some(good) = &mut self.last_good {
            good.step = DetectStep::DeviceId;
        }
        self.core.status.forget_unit();
        self.link_up(now, Model::Powermax(model), Family::PowermaxSync);
    }

    fn link_down(&mut self, now: Instant, count: u8, last_error: TransactionError) {
        match &mut self.phase {
            Phase::Powermax(driver) => driver.abort(&mut self.core),
            Phase::Hpr(driver) => driver.abort(&mut self.core),
            Phase::Detecting(_) => return,
        }
        self.core.status.forget_unit();
        self.core.diagnostics.record_link_down();
        self.core.emit(LinkEvent::LinkDown {
            reason: LinkDownReason::ConsecutiveFailures { count, last_error },
        });
        self.txn = None;
        self.consecutive_failures = 0;
        self.unanswered = 0;
        self.start_detection(now, 0);
    }

    // --- transactions --------------------------------------------------------------------

    fn start_next(&mut self, now: Instant) {
        let config = self.core.config;
        let (tag, frame, retries, spacing, no_reply): (
            Tag,
            Vec<u8, TX_CAPACITY>,
            u8,
            RetrySpacing,
            bool,
        ) = match &mut self.phase {
            Phase::Detecting(detector) => {
                if now < detector.not_before {
                    return;
                }
                let (step, good_probe) = (detector.step, detector.good);
                let Some(expect) = self.detect_request(step) else {
                    return;
                };
                let mut buf = [0u8; TX_CAPACITY];
                let (len, spacing) = match &expect {
                    DetectExpect::Modbus(request) => (
                        request.encode(config.node_address, &mut buf).ok(),
                        RetrySpacing::Immediate,
                    ),
                    // While a Modbus unit is expected back, HPR is only checked for in
                    // passing: its retries follow at once, so the known-good probe comes
                    // round again soon (no HPR is cutting while no link is up).
                    DetectExpect::Hpr(request) => (
                        request.emit(&mut buf).ok(),
                        if good_probe || self.last_good.is_none_or(|g| g.port == PortConfig::HPR) {
                            RetrySpacing::RideThroughBlackout
                        } else {
                            RetrySpacing::Immediate
                        },
                    ),
                };
                let Some(frame) = len
                    .and_then(|len| buf.get(..len))
                    .and_then(|b| Vec::from_slice(b).ok())
                else {
                    return;
                };
                let no_reply = step == DetectStep::HprSleep;
                (
                    Tag::Detect(step, expect),
                    frame,
                    config.retries,
                    spacing,
                    no_reply,
                )
            }
            Phase::Powermax(driver) => {
                let Some((purpose, request, retries)) = driver.next_request(now, &mut self.core)
                else {
                    return;
                };
                let mut buf = [0u8; TX_CAPACITY];
                let Some(frame) = request
                    .encode(config.node_address, &mut buf)
                    .ok()
                    .and_then(|len| buf.get(..len))
                    .and_then(|b| Vec::from_slice(b).ok())
                else {
                    return;
                };
                (
                    Tag::Modbus(purpose, request),
                    frame,
                    retries.unwrap_or(config.retries),
                    RetrySpacing::Immediate,
                    false,
                )
            }
            Phase::Hpr(driver) => {
                let Some((purpose, expect, frame)) = driver.next_request(now, &mut self.core)
                else {
                    return;
                };
                let Ok(frame) = Vec::from_slice(&frame) else {
                    return;
                };
                (
                    Tag::Hpr(purpose, expect),
                    frame,
                    config.retries,
                    RetrySpacing::RideThroughBlackout,
                    false,
                )
            }
        };
        self.txn = if no_reply {
            Transaction::without_reply(tag, &frame, now, SLEEP_QUIET).ok()
        } else {
            Transaction::new(tag, &frame, now, config.response_timeout, retries, spacing).ok()
        };
    }

    fn handle_timeout(&mut self, now: Instant) {
        let Some(txn) = self.txn.as_mut() else {
            return;
        };
        match txn.handle_timeout(now) {
            None => {}
            Some(Outcome::Retrying(error)) => {
                self.core.diagnostics.record_error(error);
                self.core.diagnostics.record_retry();
            }
            Some(Outcome::Failed(error)) => {
                self.core.diagnostics.record_error(error);
                self.transaction_failed(now, error);
            }
            Some(Outcome::Sent) => {
                let tag = self.txn.take().map(|t| t.tag().clone());
                if let Some(Tag::Detect(step, _)) = tag {
                    self.detect_next(now, step);
                }
            }
        }
    }

    /// One attempt failed with `error` (a reply arrived but is unusable).
    fn attempt_failed(&mut self, now: Instant, error: TransactionError) {
        self.core.diagnostics.record_error(error);
        let Some(txn) = self.txn.as_mut() else {
            return;
        };
        match txn.attempt_failed(now, error) {
            Outcome::Retrying(_) => self.core.diagnostics.record_retry(),
            Outcome::Failed(error) => self.transaction_failed(now, error),
            Outcome::Sent => {}
        }
    }

    /// The transaction in flight failed for good.
    fn transaction_failed(&mut self, now: Instant, error: TransactionError) {
        let Some(txn) = self.txn.take() else {
            return;
        };
        self.core.diagnostics.record_failed();
        if matches!(txn.tag(), Tag::Modbus(MbPurpose::Identify, _)) {
            // Optional: a unit without device identification may stay silent to it.
        } else if !error.is_retryable() {
            // The unit answered (exception, unknown command): it is there.
            self.consecutive_failures = 0;
            self.unanswered = 0;
        } else if txn.heard_reply() {
            // Damaged replies: the unit is there, the line is noisy. Not silence.
            self.consecutive_failures = 0;
            self.unanswered = self.unanswered.saturating_add(1);
        } else {
            self.consecutive_failures = self.consecutive_failures.saturating_add(1);
            self.unanswered = self.unanswered.saturating_add(1);
        }
        match txn.tag().clone() {
            Tag::Detect(step, _) => match (step, error) {
                // A unit that refuses device identification is still a Modbus unit.
                (DetectStep::DeviceId, TransactionError::Exception(_)) => {
                    self.detected_modbus(now, None)
                }
                // Damaged replies: a unit answers at this framing; ask it again rather than
                // take it for another kind (a SYNC unit also answers the legacy probe).
                _ if txn.heard_reply() && self.reask(now) => {}
                _ => self.detect_next(now, step),
            },
            Tag::Modbus(purpose, _) => {
                if let Phase::Powermax(driver) = &mut self.phase {
                    driver.on_failed(now, purpose, error, &mut self.core);
                }
            }
            Tag::Hpr(purpose, _) => {
                if let Phase::Hpr(driver) = &mut self.phase {
                    driver.on_failed(now, purpose, error, &mut self.core);
                }
            }
        }
        let down = self.core.config.failures_before_down;
        if self.consecutive_failures >= down {
            self.link_down(now, self.consecutive_failures, error);
        } else if self.unanswered >= down.saturating_mul(UNANSWERED_FACTOR) {
            self.link_down(now, self.unanswered, error);
        }
    }

    fn transaction_ok(&mut self) -> Option<Tag> {
        let txn = self.txn.take()?;
        self.core.diagnostics.record_ok();
        self.consecutive_failures = 0;
        self.unanswered = 0;
        Some(txn.tag().clone())
    }

    fn awaited_tag(&mut self) -> Option<Tag> {
        match &self.txn {
            Some(txn) if txn.is_awaiting_reply() => Some(txn.tag().clone()),
            _ => {
                self.core.diagnostics.record_unsolicited();
                None
            }
        }
    }

    /// True when `received` (re-encoded) is the request just sent, heard back on a 2-wire
    /// line whose receiver stays on: it is counted and ignored. Most replies differ from
    /// their request, so such a frame is an echo. A request whose genuine reply repeats it
    /// (`answers`: Modbus 05/06, an HPR setting echoed unchanged) is only taken for its echo
    /// once the line is known to echo (an unambiguous echo was heard, e.g. of the detection
    /// request), and only the first such frame of an attempt.
    fn is_echo(&mut self, received: &[u8], answers: bool) -> bool {
        let Some(txn) = &self.txn else {
            return false;
        };
        if received.is_empty() || received != txn.frame() {
            return false;
        }
        let echo = !answers || (self.line_echoes && !self.echo_in_attempt);
        if echo {
            self.line_echoes = true;
            self.echo_in_attempt = true;
            self.core.diagnostics.record_echo();
        }
        echo
    }

    fn on_modbus_frame(
        &mut self,
        now: Instant,
        result: plasma_protocol::Result<(u8, Vec<u8, { modbus_ascii::MAX_FRAME_BYTES }>)>,
    ) {
        let Some(tag) = self.awaited_tag() else {
            return;
        };
        let (request, raw) = match &tag {
            Tag::Detect(_, DetectExpect::Modbus(request)) => (request.clone(), false),
            Tag::Modbus(purpose, request) => (
                request.clone(),
                *purpose == MbPurpose::Active
                    && matches!(&self.phase, Phase::Powermax(d) if d.active_is_raw()),
            ),
            _ => return,
        };
        let (address, pdu) = match result {
            Ok(frame) => frame,
            Err(error) => return self.attempt_failed(now, modbus::classify(error)),
        };
        let frame = modbus_ascii::Frame { address, pdu: &pdu };
        let validated = modbus_ascii::validate_reply(
            &request.as_request(),
            self.core.config.node_address,
            &frame,
        );
        let mut own = [0u8; TX_CAPACITY];
        let own_len = modbus_ascii::encode(address, &pdu, &mut own).unwrap_or(0);
        if self.is_echo(own.get(..own_len).unwrap_or(&[]), validated.is_ok()) {
            return;
        }
        let response = match validated {
            Ok(response) => response,
            Err(error) => return self.attempt_failed(now, modbus::classify(error)),
        };
        if let Response::Exception { code, .. } = response {
            let error = TransactionError::Exception(code);
            if !raw {
                self.core.diagnostics.record_error(error);
                if let Some(txn) = self.txn.as_mut()
                    && let Outcome::Failed(error) = txn.attempt_failed(now, error)
                {
                    self.transaction_failed(now, error);
                }
                return;
            }
            self.core.diagnostics.record_error(error);
        }
        let mut raw_len = 0;
        if raw {
            let mut buf = [0u8; TX_CAPACITY];
            raw_len = modbus_ascii::encode(address, &pdu, &mut buf).unwrap_or(0);
            self.raw_reply = buf
                .get(..raw_len)
                .and_then(|b| Vec::from_slice(b).ok())
                .unwrap_or_default();
        }
        let Some(tag) = self.transaction_ok() else {
            return;
        };
        match tag {
            Tag::Detect(DetectStep::DeviceId, _) => {
                let model = match response {
                    Response::ReadDeviceIdentification(id) => {
                        device_id::model_from_device_id(&id).ok().flatten()
                    }
                    _ => None,
                };
                self.detected_modbus(now, model);
            }
            Tag::Detect(DetectStep::LegacyProbe, _) => {
                let family = match self.core.config.protocol {
                    ProtocolChoice::Sync => Family::PowermaxSync,
                    _ => Family::PowermaxLegacy,
                };
                self.link_up(now, Model::PowermaxUnidentified, family);
            }
            Tag::Detect(step, _) => self.detect_next(now, step),
            Tag::Modbus(MbPurpose::Identify, _) => {
                if let Response::ReadDeviceIdentification(id) = response {
                    let model = device_id::model_from_device_id(&id).ok().flatten();
                    self.reidentified(now, model);
                }
            }
            Tag::Modbus(purpose, _) => {
                if let Phase::Powermax(driver) = &mut self.phase {
                    driver.on_response(now, purpose, &response, raw_len, &mut self.core);
                }
            }
            Tag::Hpr(..) => {}
        }
    }

    fn on_hpr_frame(
        &mut self,
        now: Instant,
        result: plasma_protocol::Result<(u16, Vec<u8, { hpr_wire::MAX_FRAME_LEN }>)>,
    ) {
        let Some(tag) = self.awaited_tag() else {
            return;
        };
        let (id, data) = match result {
            Ok(frame) => frame,
            Err(plasma_protocol::Error::BadChecksum { .. }) => {
                return self.attempt_failed(now, TransactionError::BadChecksum);
            }
            Err(_) => return self.attempt_failed(now, TransactionError::Malformed),
        };
        let frame = hpr_wire::Frame { id, data: &data };
        let (typed, raw_id, purpose) = match &tag {
            Tag::Detect(_, DetectExpect::Hpr(request)) => (Some(*request), None, None),
            Tag::Hpr(purpose, HprExpect::Typed(request)) => (Some(*request), None, Some(*purpose)),
            Tag::Hpr(purpose, HprExpect::Raw(raw_id)) => (None, Some(*raw_id), Some(*purpose)),
            _ => return,
        };
        let answers = match (typed, raw_id) {
            (Some(request), _) => Reply::parse_for(&request, &frame).is_ok(),
            (None, Some(raw_id)) => id == raw_id,
            (None, None) => false,
        };
        let mut own = [0u8; TX_CAPACITY];
        let own_len = frame.emit(&mut own).unwrap_or(0);
        if self.is_echo(own.get(..own_len).unwrap_or(&[]), answers) {
            return;
        }
        if id == hpr_wire::command::id::BAD_CHECKSUM {
            // The unit saw our request damaged: send it again.
            return self.attempt_failed(now, TransactionError::HprBadChecksum500);
        }
        let mut reply = None;
        if let Some(raw_id) = raw_id {
            if id != raw_id && id != hpr_wire::command::id::UNKNOWN_COMMAND {
                return self.attempt_failed(now, TransactionError::Mismatch);
            }
            if id == hpr_wire::command::id::UNKNOWN_COMMAND {
                self.core
                    .diagnostics
                    .record_error(TransactionError::HprUnknownCommand501);
            }
            let mut buf = [0u8; TX_CAPACITY];
            let len = frame.emit(&mut buf).unwrap_or(0);
            self.raw_reply = buf
                .get(..len)
                .and_then(|b| Vec::from_slice(b).ok())
                .unwrap_or_default();
        } else if let Some(request) = typed {
            if id == hpr_wire::command::id::UNKNOWN_COMMAND {
                self.core
                    .diagnostics
                    .record_error(TransactionError::HprUnknownCommand501);
                if let Some(txn) = self.txn.as_mut()
                    && let Outcome::Failed(error) =
                        txn.attempt_failed(now, TransactionError::HprUnknownCommand501)
                {
                    self.transaction_failed(now, error);
                }
                return;
            }
            match Reply::parse_for(&request, &frame) {
                Ok(parsed) => reply = Some(parsed),
                Err(plasma_protocol::Error::Mismatch) => {
                    return self.attempt_failed(now, TransactionError::Mismatch);
                }
                Err(_) => return self.attempt_failed(now, TransactionError::Malformed),
            }
        }
        let raw_len = self.raw_reply.len();
        let Some(tag) = self.transaction_ok() else {
            return;
        };
        match (tag, purpose) {
            (Tag::Detect(DetectStep::HprHello, _), _) => match reply {
                Some(Reply::Hello(system)) => {
                    let family = if system == SystemId::MaxPro200 {
                        Family::MaxPro200
                    } else {
                        Family::Hpr
                    };
                    self.link_up(now, Model::Hpr(system), family);
                }
                _ => self.detect_next(now, DetectStep::HprHello),
            },
            (Tag::Detect(step, _), _) => self.detect_next(now, step),
            (Tag::Hpr(..), Some(purpose)) => {
                if let Phase::Hpr(driver) = &mut self.phase {
                    driver.on_reply(now, purpose, reply.as_ref(), raw_len, &mut self.core);
                }
            }
            _ => {}
        }
    }
}
