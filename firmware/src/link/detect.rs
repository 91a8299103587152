//! Auto-detection.
//!
//! Owns which probe is asked at which port settings (the search over the Modbus framings,
//! then HPR), the known-good probe asked first after a link-down, re-asking a probe whose
//! replies arrived damaged, and what a probe's answer or failure means. The move to a
//! family driver once a unit is found is [`crate::link::phase`]'s.

use heapless::Vec;
use plasma_protocol::hpr::{self as hpr_wire, Reply, SystemId};
use plasma_protocol::modbus_ascii::Response;
use plasma_protocol::modbus_ascii::pdu::DeviceIdentification;
use plasma_protocol::powermax::{device_id, legacy as pm_legacy};
use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_protocol::time::{Duration, Instant};

use crate::link::powermax::modbus::MbRequest;
use crate::link::transaction::{Outgoing, RetrySpacing, TX_CAPACITY, TransactionError};
use crate::link::{Family, Model, Phase, ProtocolChoice, PsLink, Wire};

/// Pause between two detection rounds, so a silent line is not hammered.
pub(crate) const DETECT_ROUND_PAUSE: Duration = Duration::from_millis(250);
/// Times a detection step whose replies all arrived damaged is asked again before detection
/// moves on (a damaged reply shows a unit that speaks this protocol at this framing).
pub(crate) const DETECT_REASKS: u8 = 3;

/// Modbus line settings tried in turn by auto-detection (the configured one first).
const MODBUS_FRAMINGS: [(Parity, StopBits); 6] = [
    (Parity::Even, StopBits::One),
    (Parity::Odd, StopBits::One),
    (Parity::None, StopBits::One),
    (Parity::Even, StopBits::Two),
    (Parity::Odd, StopBits::Two),
    (Parity::None, StopBits::Two),
];

/// Auto-detection steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum DetectStep {
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
pub(super) struct Detector {
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

impl Detector {
    /// The search at `step` of round `round`, asked from `not_before`.
    pub(super) fn searching(step: DetectStep, round: u32, not_before: Instant) -> Self {
        Detector {
            step,
            good: false,
            round,
            search: step,
            not_before,
            reasks: 0,
        }
    }

    /// When the next probe may go out.
    pub(super) fn not_before(&self) -> Instant {
        self.not_before
    }
}

/// What found the unit last time: the probe (its first step) and the port settings. After a
/// link-down it is asked first, and again between every two probes of the full search, so
/// a unit that was switched off is found again within a probe or two of its return.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct KnownGood {
    step: DetectStep,
    port: PortConfig,
}

/// What a probe expects back.
#[derive(Debug, Clone)]
pub(super) enum DetectExpect {
    Modbus(MbRequest),
    Hpr(hpr_wire::Request),
}

impl PsLink {
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
    pub(super) fn start_detection(&mut self, not_before: Instant, round: u32) {
        self.resume_detection(not_before, self.first_step(), round);
    }

    /// Like [`PsLink::start_detection`], with the search going on at `search`.
    fn resume_detection(&mut self, not_before: Instant, search: DetectStep, round: u32) {
        let mut detector = Detector::searching(search, round, not_before);
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
    pub(super) fn detect_next(&mut self, now: Instant, step: DetectStep) {
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
        self.phase = Phase::Detecting(Detector::searching(step, round, now));
        self.set_port_for(step, round);
    }

    /// Detection found a unit: what found it (the probe being asked, and the port settings)
    /// is asked first after a link-down.
    pub(super) fn remember_known_good(&mut self) {
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
    }

    /// The known-good probe, if any, becomes `step` (same port settings).
    pub(super) fn known_good_asks(&mut self, step: DetectStep) {
        if let Some(good) = &mut self.last_good {
            good.step = step;
        }
    }

    /// The probe to send now, if detection is due for one (tagged with its step and what it
    /// expects back).
    pub(super) fn next_probe(
        &mut self,
        now: Instant,
    ) -> Option<Outgoing<(DetectStep, DetectExpect)>> {
        let Phase::Detecting(detector) = &self.phase else {
            return None;
        };
        if now < detector.not_before {
            return None;
        }
        let (step, good_probe) = (detector.step, detector.good);
        let expect = self.detect_request(step)?;
        let config = self.core.config;
        let mut buf = [0u8; TX_CAPACITY];
        let (len, spacing) = match &expect {
            DetectExpect::Modbus(request) => (
                request.encode(config.node_address, &mut buf).ok(),
                RetrySpacing::Immediate,
            ),
            DetectExpect::Hpr(request) => (
                request.emit(&mut buf).ok(),
                self.hpr_probe_spacing(good_probe),
            ),
        };
        let frame = len
            .and_then(|len| buf.get(..len))
            .and_then(|b| Vec::from_slice(b).ok())?;
        Some(Outgoing {
            tag: (step, expect),
            frame,
            retries: config.retries,
            spacing,
            no_reply: step == DetectStep::HprSleep,
        })
    }

    /// While a Modbus unit is expected back, HPR is only checked for in passing: its retries
    /// follow at once, so the known-good probe comes round again soon (no HPR is cutting
    /// while no link is up).
    fn hpr_probe_spacing(&self, good_probe: bool) -> RetrySpacing {
        if good_probe || self.last_good.is_none_or(|g| g.port == PortConfig::HPR) {
            RetrySpacing::RideThroughBlackout
        } else {
            RetrySpacing::Immediate
        }
    }

    /// The probe `step` failed for good with `error`; `heard_reply` when damaged replies
    /// arrived.
    pub(super) fn probe_failed(
        &mut self,
        now: Instant,
        step: DetectStep,
        error: TransactionError,
        heard_reply: bool,
    ) {
        match (step, error) {
            // A unit that refuses device identification is still a Modbus unit.
            (DetectStep::DeviceId, TransactionError::Exception(_)) => {
                self.detected_modbus(now, None)
            }
            // Damaged replies: a unit answers at this framing; ask it again rather than
            // take it for another kind (a SYNC unit also answers the legacy probe).
            _ if heard_reply && self.reask(now) => {}
            _ => self.detect_next(now, step),
        }
    }

    /// A Modbus probe `step` was answered with `response`.
    pub(super) fn modbus_probe_answered(
        &mut self,
        now: Instant,
        step: DetectStep,
        response: &Response<'_>,
    ) {
        match step {
            DetectStep::DeviceId => self.detected_modbus(now, device_identification(response)),
            DetectStep::LegacyProbe => {
                let family = match self.core.config.protocol {
                    ProtocolChoice::Sync => Family::PowermaxSync,
                    _ => Family::PowermaxLegacy,
                };
                self.link_up(now, Model::PowermaxUnidentified, family);
            }
            step => self.detect_next(now, step),
        }
    }

    /// An HPR probe `step` was answered (`reply`, parsed for it).
    pub(super) fn hpr_probe_answered(
        &mut self,
        now: Instant,
        step: DetectStep,
        reply: Option<&Reply<'_>>,
    ) {
        match (step, reply) {
            (DetectStep::HprHello, Some(Reply::Hello(system))) => {
                let family = if *system == SystemId::MaxPro200 {
                    Family::MaxPro200
                } else {
                    Family::Hpr
                };
                self.link_up(now, Model::Hpr(*system), family);
            }
            (step, _) => self.detect_next(now, step),
        }
    }
}

/// The device identification a `response` carries, if it is one.
pub(super) fn device_identification<'r>(
    response: &'r Response<'_>,
) -> Option<&'r DeviceIdentification<'r>> {
    match response {
        Response::ReadDeviceIdentification(id) => Some(id),
        _ => None,
    }
}

#[cfg(test)]
mod tests;
