//! Receive and dispatch.
//!
//! Owns the way from received characters to an answer: the decoder of the wire in use
//! turns characters into frames; each frame is checked against the request in flight (its
//! echo on a 2-wire line, error replies, a reply that answers something else), the reply of
//! a RAW command is kept for [`PsLink::raw_reply`], and the answer goes to detection or to
//! the family driver.

use heapless::Vec;
use plasma_protocol::hpr::{self as hpr_wire, Reply};
use plasma_protocol::modbus_ascii::{self, Response};
use plasma_protocol::time::Instant;

use crate::link::detect::{DetectExpect, device_identification};
use crate::link::hpr::HprExpect;
use crate::link::powermax::MbPurpose;
use crate::link::powermax::modbus::{self, MbRequest};
use crate::link::schedule::Tag;
use crate::link::transaction::{TX_CAPACITY, TransactionError};
use crate::link::{Phase, PsLink};

/// A Modbus frame as decoded (address and PDU), or why it was rejected.
type ModbusFrame = plasma_protocol::Result<(u8, Vec<u8, { modbus_ascii::MAX_FRAME_BYTES }>)>;
/// An HPR frame as decoded (id and data), or why it was rejected.
type HprFrame = plasma_protocol::Result<(u16, Vec<u8, { hpr_wire::MAX_FRAME_LEN }>)>;

impl PsLink {
    /// Feed `bytes` to the Modbus decoder and handle the frame it completes, if any.
    /// Returns how many bytes were used.
    pub(super) fn receive_modbus(&mut self, now: Instant, bytes: &[u8]) -> usize {
        let (used, result) = self.modbus_rx.feed(bytes);
        // Copied out of the decoder, which the handling below must not borrow.
        let owned = result.map(|r| {
            r.and_then(|frame| {
                Vec::from_slice(frame.pdu)
                    .map(|pdu| (frame.address, pdu))
                    .map_err(|_| plasma_protocol::Error::Overlong)
            })
        });
        if let Some(result) = owned {
            self.on_modbus_frame(now, result);
        }
        used
    }

    /// Feed `bytes` to the HPR decoder and handle the frame it completes, if any. Returns
    /// how many bytes were used.
    pub(super) fn receive_hpr(&mut self, now: Instant, bytes: &[u8]) -> usize {
        let (used, result) = self.hpr_rx.feed(bytes);
        let owned = result.map(|r| {
            r.and_then(|frame| {
                Vec::from_slice(frame.data)
                    .map(|data| (frame.id, data))
                    .map_err(|_| plasma_protocol::Error::Overlong)
            })
        });
        if let Some(result) = owned {
            self.on_hpr_frame(now, result);
        }
        used
    }

    /// The tag of the transaction awaiting a reply; `None` (counted as unsolicited) when
    /// nothing awaits one.
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

    /// Keep `frame` as the reply of the RAW command in flight.
    fn keep_raw_reply(&mut self, frame: &[u8]) {
        self.raw_reply = Vec::from_slice(frame).unwrap_or_default();
    }

    // --- Modbus ----------------------------------------------------------------------------

    fn on_modbus_frame(&mut self, now: Instant, result: ModbusFrame) {
        let Some(tag) = self.awaited_tag() else {
            return;
        };
        let Some((request, raw)) = self.modbus_expectation(&tag) else {
            return;
        };
        let (address, pdu) = match result {
            Ok(frame) => frame,
            Err(error) => return self.attempt_failed(now, modbus::classify(error)),
        };
        let frame = modbus_ascii::Frame { address, pdu: &pdu };
        let node = self.core.config.node_address;
        let validated = modbus_ascii::validate_reply(&request.as_request(), node, &frame);
        let mut own = [0u8; TX_CAPACITY];
        let own_len = modbus_ascii::encode(address, &pdu, &mut own).unwrap_or(0);
        let own = own.get(..own_len).unwrap_or(&[]);
        if self.is_echo(own, validated.is_ok()) {
            return;
        }
        let response = match validated {
            Ok(response) => response,
            Err(error) => return self.attempt_failed(now, modbus::classify(error)),
        };
        if let Response::Exception { code, .. } = response {
            let error = TransactionError::Exception(code);
            if !raw {
                return self.attempt_refused(now, error);
            }
            // A RAW command forwards the exception as its reply.
            self.core.diagnostics.record_error(error);
        }
        let raw_len = if raw {
            self.keep_raw_reply(own);
            own.len()
        } else {
            0
        };
        if let Some(tag) = self.transaction_ok() {
            self.dispatch_modbus(now, tag, &response, raw_len);
        }
    }

    /// The request a Modbus reply must answer, and whether it is a RAW forward (its reply
    /// is kept as is). `None` when the transaction in flight is no Modbus one.
    fn modbus_expectation(&self, tag: &Tag) -> Option<(MbRequest, bool)> {
        match tag {
            Tag::Detect(_, DetectExpect::Modbus(request)) => Some((request.clone(), false)),
            Tag::Modbus(purpose, request) => Some((
                request.clone(),
                *purpose == MbPurpose::Active
                    && matches!(&self.phase, Phase::Powermax(d) if d.active_is_raw()),
            )),
            _ => None,
        }
    }

    /// Hand a Modbus `response` to whoever asked for it.
    fn dispatch_modbus(&mut self, now: Instant, tag: Tag, response: &Response<'_>, raw_len: usize) {
        match tag {
            Tag::Detect(step, _) => self.modbus_probe_answered(now, step, response),
            Tag::Modbus(MbPurpose::Identify, _) => {
                if let Some(id) = device_identification(response) {
                    self.reidentified(now, id);
                }
            }
            Tag::Modbus(purpose, _) => {
                if let Phase::Powermax(driver) = &mut self.phase {
                    driver.on_response(now, purpose, response, raw_len, &mut self.core);
                }
            }
            Tag::Hpr(..) => {}
        }
    }

    // --- HPR -------------------------------------------------------------------------------

    fn on_hpr_frame(&mut self, now: Instant, result: HprFrame) {
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
        let Some(expect) = hpr_expectation(&tag) else {
            return;
        };
        let answers = match &expect {
            HprExpect::Typed(request) => Reply::parse_for(request, &frame).is_ok(),
            HprExpect::Raw(raw_id) => id == *raw_id,
        };
        let mut own = [0u8; TX_CAPACITY];
        let own_len = frame.emit(&mut own).unwrap_or(0);
        let own = own.get(..own_len).unwrap_or(&[]);
        if self.is_echo(own, answers) {
            return;
        }
        if id == hpr_wire::command::id::BAD_CHECKSUM {
            // The unit saw our request damaged: send it again.
            return self.attempt_failed(now, TransactionError::HprBadChecksum500);
        }
        let reply = match expect {
            HprExpect::Raw(raw_id) => {
                if !self.raw_hpr_reply(now, id, raw_id, own) {
                    return;
                }
                None
            }
            HprExpect::Typed(request) => match self.typed_hpr_reply(now, &request, &frame) {
                Some(reply) => Some(reply),
                None => return,
            },
        };
        let raw_len = self.raw_reply.len();
        if let Some(tag) = self.transaction_ok() {
            self.dispatch_hpr(now, tag, reply.as_ref(), raw_len);
        }
    }

    /// A reply with `id` (re-encoded: `frame`) to the RAW command `raw_id`: kept as its reply
    /// when it answers it or is 501. False when the attempt failed instead.
    fn raw_hpr_reply(&mut self, now: Instant, id: u16, raw_id: u16, frame: &[u8]) -> bool {
        let unknown = id == hpr_wire::command::id::UNKNOWN_COMMAND;
        if id != raw_id && !unknown {
            self.attempt_failed(now, TransactionError::Mismatch);
            return false;
        }
        if unknown {
            self.core
                .diagnostics
                .record_error(TransactionError::HprUnknownCommand501);
        }
        self.keep_raw_reply(frame);
        true
    }

    /// `frame` parsed as the reply to `request`; `None` when the attempt failed instead
    /// (501, a reply to something else, garbled data).
    fn typed_hpr_reply<'a>(
        &mut self,
        now: Instant,
        request: &hpr_wire::Request,
        frame: &hpr_wire::Frame<'a>,
    ) -> Option<Reply<'a>> {
        if frame.id == hpr_wire::command::id::UNKNOWN_COMMAND {
            self.attempt_refused(now, TransactionError::HprUnknownCommand501);
            return None;
        }
        match Reply::parse_for(request, frame) {
            Ok(reply) => Some(reply),
            Err(plasma_protocol::Error::Mismatch) => {
                self.attempt_failed(now, TransactionError::Mismatch);
                None
            }
            Err(_) => {
                self.attempt_failed(now, TransactionError::Malformed);
                None
            }
        }
    }

    /// Hand an HPR `reply` to whoever asked for it.
    fn dispatch_hpr(&mut self, now: Instant, tag: Tag, reply: Option<&Reply<'_>>, raw_len: usize) {
        match tag {
            Tag::Detect(step, _) => self.hpr_probe_answered(now, step, reply),
            Tag::Hpr(purpose, _) => {
                if let Phase::Hpr(driver) = &mut self.phase {
                    driver.on_reply(now, purpose, reply, raw_len, &mut self.core);
                }
            }
            Tag::Modbus(..) => {}
        }
    }
}

/// What an HPR reply must answer; `None` when the transaction in flight is no HPR one.
fn hpr_expectation(tag: &Tag) -> Option<HprExpect> {
    match tag {
        Tag::Detect(_, DetectExpect::Hpr(request)) => Some(HprExpect::Typed(*request)),
        Tag::Hpr(_, expect) => Some(expect.clone()),
        _ => None,
    }
}

#[cfg(test)]
mod tests;
