//! The link's phase, and the moves between detecting and talking to a unit: link up (a
//! family driver takes over and the known-good probe is remembered), re-identification of a
//! unit the legacy probe found, and link down (pending commands fail, detection starts
//! again).

use plasma_protocol::hpr::SystemId;
use plasma_protocol::modbus_ascii::pdu::DeviceIdentification;
use plasma_protocol::powermax::{AddressingSystem, device_id};
use plasma_protocol::time::Instant;

use crate::link::detect::{DetectStep, Detector};
use crate::link::hpr::HprDriver;
use crate::link::powermax::{PowermaxDriver, Variant};
use crate::link::transaction::TransactionError;
use crate::link::{Family, LinkDownReason, LinkEvent, Model, ProtocolChoice, PsLink};

/// What the link is doing: detecting, or talking to a unit through its family's driver.
// One phase at a time, held inline (no allocator).
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
pub(super) enum Phase {
    Detecting(Detector),
    Powermax(PowermaxDriver),
    Hpr(HprDriver),
}

impl PsLink {
    /// A unit answered detection: `model` of `family`; its driver takes over.
    pub(super) fn link_up(&mut self, now: Instant, model: Model, family: Family) {
        self.remember_known_good();
        self.consecutive_failures = 0;
        self.unanswered = 0;
        self.core.status.family = Some(family);
        self.core.status.model = Some(model);
        self.core.status.link_up = true;
        self.core.emit(LinkEvent::LinkUp { model, family });
        self.phase = match family {
            Family::PowermaxSync | Family::PowermaxLegacy => {
                let variant = if family == Family::PowermaxSync {
                    Variant::Sync
                } else {
                    Variant::Legacy
                };
                Phase::Powermax(PowermaxDriver::new(variant, now, &self.core))
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

    /// A Modbus unit answered device identification with `id`, or refused it (`None`).
    pub(super) fn detected_modbus(&mut self, now: Instant, id: Option<&DeviceIdentification<'_>>) {
        let model = id.and_then(|id| device_id::model_from_device_id(id).ok().flatten());
        let choice = self.core.config.protocol;
        let variant = match (choice, model.map(|m| m.addressing())) {
            (ProtocolChoice::Sync, _) => Some(Family::PowermaxSync),
            (ProtocolChoice::Legacy, _) => Some(Family::PowermaxLegacy),
            (_, Some(AddressingSystem::Sync)) => Some(Family::PowermaxSync),
            (_, Some(AddressingSystem::Legacy)) => Some(Family::PowermaxLegacy),
            (_, None) => None,
        };
        let Some(family) = variant else {
            // Unknown product code: the legacy register read decides.
            return self.detect_next(now, DetectStep::DeviceId);
        };
        self.core.status.device_id_conformity = id.map(|id| id.conformity);
        let model = model.map_or(Model::PowermaxUnidentified, Model::Powermax);
        self.link_up(now, model, family);
    }

    /// A unit running as legacy (found by the register probe) answered device
    /// identification with `id`. A SYNC unit changes family: pending commands fail as on a
    /// link-down (kept settings stay and are re-applied), and `LinkUp` reports the unit again
    /// with its model and family.
    pub(super) fn reidentified(&mut self, now: Instant, id: &DeviceIdentification<'_>) {
        let Ok(Some(model)) = device_id::model_from_device_id(id) else {
            return;
        };
        if model.addressing() != AddressingSystem::Sync {
            self.core.status.model = Some(Model::Powermax(model));
            self.core.status.device_id_conformity = Some(id.conformity);
            return;
        }
        if let Phase::Powermax(driver) = &mut self.phase {
            driver.abort(&mut self.core);
        }
        // Device identification found it, not the legacy probe.
        self.known_good_asks(DetectStep::DeviceId);
        self.core.status.forget_unit();
        self.core.status.device_id_conformity = Some(id.conformity);
        self.link_up(now, Model::Powermax(model), Family::PowermaxSync);
    }

    pub(super) fn link_down(&mut self, now: Instant, count: u8, last_error: TransactionError) {
        if !self.abort_unit() {
            return;
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

    /// The unit's driver gives up whatever it was doing (every pending command fails).
    /// False while detecting (no unit to abort).
    pub(super) fn abort_unit(&mut self) -> bool {
        match &mut self.phase {
            Phase::Powermax(driver) => driver.abort(&mut self.core),
            Phase::Hpr(driver) => driver.abort(&mut self.core),
            Phase::Detecting(_) => return false,
        }
        true
    }
}

#[cfg(test)]
mod tests;
