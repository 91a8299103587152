//! What the unit's answers mean: polls update the status (settings, outputs, the active
//! fault), slow data and the cartridge block fill in the rest, and a failed transaction ends
//! what it was for.

use plasma_protocol::modbus_ascii::{Registers, Response};
use plasma_protocol::powermax::sync::{Cartridge, FaultLog, Identification, PsCounters};
use plasma_protocol::powermax::{CartridgeName, CartridgeUid, FaultCode, LeadLength};
use plasma_protocol::time::Instant;

use super::{FAULT_CHECK_INTERVAL, MbPurpose, PowermaxDriver, Variant};
use crate::link::core::Core;
use crate::link::event::LinkEvent;
use crate::link::powermax::legacy;
use crate::link::powermax::modbus::{self, read_values};
use crate::link::powermax::sync::{self, SlowItem};
use crate::link::status::ActiveFault;
use crate::link::transaction::TransactionError;

impl PowermaxDriver {
    /// A valid reply arrived for `purpose`. `raw_len` is the length of the reply frame kept
    /// for a RAW command.
    pub(crate) fn on_response(
        &mut self,
        now: Instant,
        purpose: MbPurpose,
        response: &Response<'_>,
        raw_len: usize,
        core: &mut Core,
    ) {
        self.now = now;
        match purpose {
            MbPurpose::Poll(part) => match read_values(response) {
                Some(values) => {
                    if self.poll.on_values(part, values) {
                        self.finish_poll(now, core);
                    }
                }
                None => self.on_failed(now, purpose, TransactionError::Mismatch, core),
            },
            MbPurpose::Slow(SlowItem::TorchLead) => {
                let error = match response {
                    // Bits 11 are not listed (legacy guide): the lead stays unknown.
                    Response::ReadCoils { bits } => {
                        core.status.legacy_lead = LeadLength::from_legacy_coils(bits).ok();
                        None
                    }
                    _ => Some(TransactionError::Mismatch),
                };
                self.slow_done(now, SlowItem::TorchLead, error, core);
            }
            MbPurpose::Slow(item) => {
                let error = read_values(response).and_then(|values| store_slow(item, values, core));
                self.slow_done(now, item, error, core);
            }
            MbPurpose::CartridgeBlock(part) => {
                let Some(values) = read_values(response) else {
                    return self.on_failed(now, purpose, TransactionError::Mismatch, core);
                };
                if self.cartridge.on_values(part, values) {
                    self.finish_cartridge(now, core);
                }
            }
            MbPurpose::UidCheck => {
                let uid = read_values(response).and_then(|v| CartridgeUid::decode(v).ok());
                if let (Some(uid), Some(known)) = (uid, core.status.cartridge)
                    && uid != known.uid
                {
                    // The cartridge block read emits CartridgeChanged with the new data.
                    self.slow.request(SlowItem::CARTRIDGE_ITEMS);
                }
            }
            MbPurpose::FaultCheck => match read_values(response).and_then(|v| v.get(0)) {
                Some(code) => self.update_fault(now, FaultCode(code), core),
                None => self.on_failed(now, purpose, TransactionError::Mismatch, core),
            },
            MbPurpose::Active => self.advance_active(now, response, raw_len, core),
            // The link itself acts on the answer (it may change the family).
            MbPurpose::Identify => {}
        }
    }

    /// `purpose` failed for good (retries used, or a final answer such as an exception).
    pub(crate) fn on_failed(
        &mut self,
        now: Instant,
        purpose: MbPurpose,
        error: TransactionError,
        core: &mut Core,
    ) {
        self.now = now;
        match purpose {
            MbPurpose::Poll(part) => {
                if modbus::is_illegal_address(error) {
                    if self.poll.on_illegal_address(part) {
                        self.finish_poll(now, core);
                    }
                } else {
                    self.poll.abort();
                    self.next_poll_at = now + core.config.poll_interval;
                    self.fault_check_at = now + FAULT_CHECK_INTERVAL;
                }
            }
            // A unit that refuses the register alone is left to the polls; after silence or
            // a damaged reply the other work gets the line before the next check.
            MbPurpose::FaultCheck => match error {
                TransactionError::Exception(_) => self.fault_read_refused = true,
                _ => self.fault_check_at = now + FAULT_CHECK_INTERVAL,
            },
            MbPurpose::Slow(item) => self.slow_done(now, item, Some(error), core),
            MbPurpose::CartridgeBlock(part) => {
                if modbus::is_illegal_address(error) {
                    if self.cartridge.on_illegal_address(part) {
                        self.finish_cartridge(now, core);
                    }
                } else {
                    self.cartridge.abort();
                    self.slow_done(now, SlowItem::Cartridge, Some(error), core);
                }
            }
            MbPurpose::UidCheck => {}
            MbPurpose::Identify => {
                if matches!(error, TransactionError::Exception(_)) {
                    self.identify_refused = true;
                }
            }
            MbPurpose::Active => self.active_failed(now, error, core),
        }
    }

    fn finish_poll(&mut self, now: Instant, core: &mut Core) {
        self.next_poll_at = (self.poll_started + core.config.poll_interval).max(now);
        match self.variant {
            Variant::Sync => {
                if !self.poll.complete() {
                    return;
                }
                let Some(data) = sync::decode_poll(self.poll.registers()) else {
                    return;
                };
                core.status.settings = Some(data.settings);
                core.status.actual_current = Some(data.actual_current);
                core.status.actual_pressure = Some(data.actual_pressure);
                self.update_fault(now, data.fault, core);
                self.check_revert(now, Some(&data.settings), core);
            }
            Variant::Legacy => {
                let Some(data) = legacy::decode_poll(&self.poll) else {
                    return;
                };
                core.status.limits = Some(data.limits);
                core.status.arc_seconds = Some(data.arc_seconds);
                self.update_fault(now, data.fault, core);
                if let Some(settings) = data.settings {
                    core.status.settings = Some(settings);
                }
                self.check_revert(now, data.settings.as_ref(), core);
            }
        }
    }

    pub(super) fn update_fault(&mut self, now: Instant, code: FaultCode, core: &mut Core) {
        let new = (!code.is_none()).then_some(ActiveFault::Powermax(code));
        if core.set_active_fault(new) {
            // Cartridge faults come and go with cartridge changes: look at the UID soon.
            self.next_uid_check_at = now;
        }
    }

    fn finish_cartridge(&mut self, now: Instant, core: &mut Core) {
        if self.cartridge.complete()
            && let Ok(cartridge) = Cartridge::decode(self.cartridge.registers())
        {
            if core
                .status
                .cartridge
                .is_some_and(|known| known.uid != cartridge.uid)
            {
                core.emit(LinkEvent::CartridgeChanged {
                    uid: cartridge.uid.0,
                });
            }
            core.status.cartridge = Some(cartridge);
        }
        self.slow_done(now, SlowItem::Cartridge, None, core);
    }

    /// A slow-data item is read (`error` = None) or failed for good (see [`SlowData::finish`]).
    fn slow_done(
        &mut self,
        now: Instant,
        item: SlowItem,
        error: Option<TransactionError>,
        core: &mut Core,
    ) {
        let interval = core.config.slow_data_interval;
        self.slow.finish(now, item.bit(), error, interval, core);
    }
}

/// Store the slow-data `item` read as `values`; an error when it must be read again soon.
fn store_slow(item: SlowItem, values: Registers<'_>, core: &mut Core) -> Option<TransactionError> {
    match item {
        SlowItem::Permitted => match sync::limits(values) {
            Some(limits) => core.status.limits = Some(limits),
            // Settings depend on them: read them again soon.
            None => return Some(TransactionError::Malformed),
        },
        SlowItem::Identification => {
            core.status.identification = Identification::decode(values).ok();
        }
        SlowItem::PsCounters => core.status.ps_counters = PsCounters::decode(values).ok(),
        SlowItem::FaultLog => core.status.fault_log = FaultLog::decode(values).ok(),
        SlowItem::CartridgeName => {
            core.status.cartridge_name = CartridgeName::decode(values).ok();
        }
        SlowItem::Cartridge | SlowItem::TorchLead => {}
    }
    None
}
