//! Modbus ASCII frames: LRC, request or reply, and what the PDU says.

use plasma_protocol::Error;
use plasma_protocol::modbus_ascii::{
    self, DeviceIdentification, Frame, MAX_PDU_LEN, Request, Response, lrc, validate_reply,
};
use plasma_protocol::powermax::device_id::{PRODUCT_CODE_OBJECT, model_from_device_id};
use plasma_protocol::powermax::registers as catalogue;
use plasma_protocol::powermax::{LeadLength, legacy};

use super::registers::{describe_range, explain_block, explain_one, printable};
use super::{CoilValue, Field, FrameReport, Function, Kind};

/// A decoded frame kept after the call (the crate's `Frame` borrows a buffer).
pub(super) struct OwnedFrame {
    address: u8,
    pdu: Vec<u8>,
}

impl OwnedFrame {
    fn frame(&self) -> Frame<'_> {
        Frame {
            address: self.address,
            pdu: &self.pdu,
        }
    }
}

/// Decodes one Modbus frame into `report`; returns it when it is a request, for the next frame
/// to be matched against.
pub(super) fn decode(
    text: &str,
    previous: Option<&OwnedFrame>,
    report: &mut FrameReport,
) -> Option<OwnedFrame> {
    let owned = read_frame(text, report)?;
    let frame = owned.frame();
    report.address = Some(frame.address);
    let Some(&function) = frame.pdu.first() else {
        report.fail("no function code");
        return None;
    };
    report.function = Some(Function {
        code: function,
        name: function_name(function),
    });
    if frame.address == 0 {
        report.note("address 0 is a broadcast: every unit acts on it and none replies");
    }

    if let Some(request_frame) = previous
        && let Ok(request) = Request::parse(&request_frame.pdu)
    {
        if let Ok(response) = validate_reply(&request, request_frame.address, &frame) {
            report.kind = Some(Kind::Reply);
            report.kind_reason = Some("answers the request before it".into());
            report.answers_request = Some(true);
            describe_response(&response, Some(&request), report);
            return None;
        }
        if guess(&frame) == Guess::Reply {
            report.answers_request = Some(false);
            let why = mismatch_reason(&request, request_frame.address, &frame);
            let problem = format!("reply does not answer the request before it: {why}");
            if report.error.is_some() {
                // Keep the first error (a bad LRC) as the error.
                report.note(problem);
            } else {
                report.fail(problem);
            }
        }
    }

    match guess(&frame) {
        Guess::Request(request, reason) => {
            report.kind = Some(Kind::Request);
            report.kind_reason = Some(reason);
            describe_request(&request, report);
            Some(owned)
        }
        Guess::Reply => {
            report.kind = Some(Kind::Reply);
            report.kind_reason = Some(reply_reason(frame.pdu));
            match Response::parse(frame.pdu) {
                Ok(response) => describe_response(&response, None, report),
                Err(e) => report.fail(format!("malformed reply: {e}")),
            }
            None
        }
        Guess::Neither { request, reply } => {
            report.fail(format!(
                "malformed PDU: not a valid request ({request}) nor a valid reply ({reply})"
            ));
            None
        }
    }
}

/// Hex-decodes the frame and checks its LRC. A frame with a bad LRC is still returned (its
/// contents are decoded so the technician sees what was meant), but marked invalid.
fn read_frame(text: &str, report: &mut FrameReport) -> Option<OwnedFrame> {
    let mut buf = [0u8; MAX_PDU_LEN];
    let result =
        modbus_ascii::decode(text.as_bytes(), &mut buf).map(|f| (f.address, f.pdu.to_vec()));
    let (address, pdu) = match result {
        Ok(frame) => frame,
        Err(Error::BadChecksum { .. }) if strip_hex_crlf(text).is_some() => {
            // The legacy guide prints CR LF as the hex digits "0D0A" (`:010420980001420D0A`).
            let stripped = strip_hex_crlf(text)?;
            report.note("the trailing \"0D0A\" is CR LF written in hex (as the legacy guide prints it); it was removed");
            report.frame = stripped.to_owned();
            return read_frame(stripped, report);
        }
        Err(Error::BadChecksum { expected, found }) => {
            report.checksum = Some(super::Checksum { found, expected });
            report.fail(format!("LRC {found:02X} wrong, should be {expected:02X}"));
            let bytes = hex_bytes(text)?;
            let (&address, rest) = bytes.split_first()?;
            let pdu = rest.split_last().map(|(_, pdu)| pdu.to_vec())?;
            report.note("the contents below are decoded despite the bad LRC");
            return Some(OwnedFrame { address, pdu });
        }
        Err(e) => {
            report.fail(format!("not a valid Modbus ASCII frame: {e}"));
            return None;
        }
    };
    let mut body = vec![address];
    body.extend_from_slice(&pdu);
    let sum = lrc(&body);
    report.checksum = Some(super::Checksum {
        found: sum,
        expected: sum,
    });
    Some(OwnedFrame { address, pdu })
}

/// `text` without a trailing hex "0D0A", when that leaves a frame with a correct LRC.
fn strip_hex_crlf(text: &str) -> Option<&str> {
    let stripped = text.get(..text.len().checked_sub(4)?)?;
    if !text[stripped.len()..].eq_ignore_ascii_case("0D0A") {
        return None;
    }
    let mut buf = [0u8; MAX_PDU_LEN];
    modbus_ascii::decode(stripped.as_bytes(), &mut buf)
        .ok()
        .map(|_| stripped)
}

/// The binary bytes of `:` + hex digits (already known to be well formed up to the LRC).
fn hex_bytes(text: &str) -> Option<Vec<u8>> {
    let digits = text.strip_prefix(':')?.trim_end_matches(['\r', '\n']);
    (0..digits.len() / 2)
        .map(|i| u8::from_str_radix(digits.get(2 * i..2 * i + 2)?, 16).ok())
        .collect()
}

/// Name of a function byte.
pub(super) fn function_name(code: u8) -> &'static str {
    match code & 0x7F {
        0x01 => "Read Coils",
        0x03 => "Read Holding Registers",
        0x04 => "Read Input Registers",
        0x05 => "Write Single Coil",
        0x06 => "Write Single Register",
        0x10 => "Write Multiple Registers",
        0x2B => "Read Device Identification",
        _ => "unknown function",
    }
}

#[derive(Debug, PartialEq)]
enum Guess<'a> {
    Request(Request<'a>, String),
    Reply,
    Neither { request: Error, reply: Error },
}

/// A frame alone does not say which way it went: the PDU length decides (manual layouts of
/// each function), and where both fit, the request is taken and the reason says so.
fn guess<'a>(frame: &Frame<'a>) -> Guess<'a> {
    let pdu = frame.pdu;
    let function = pdu.first().copied().unwrap_or(0);
    if function & 0x80 != 0 {
        return Guess::Reply;
    }
    match (Request::parse(pdu), Response::parse(pdu)) {
        (Ok(request), reply) => {
            let len = pdu.len();
            let reason = match function {
                0x05 | 0x06 => format!(
                    "taken as the request: the reply to function {function:02X} echoes the request byte for byte, so this frame may also be the reply"
                ),
                0x01 if reply.is_ok() => format!(
                    "PDU of {len} bytes: a read request (it could also be a reply carrying 3 bytes of coils)"
                ),
                0x01 | 0x03 | 0x04 => format!(
                    "PDU of {len} bytes: a read request is 5 bytes (start, quantity), its reply 2 + 2 per register"
                ),
                0x10 => format!(
                    "PDU of {len} bytes: a write request is at least 8 bytes (start, quantity, count, values), its reply 5"
                ),
                0x2B => format!(
                    "PDU of {len} bytes: a device identification request is 4 bytes, its reply longer"
                ),
                _ => format!("PDU of {len} bytes parses as a request"),
            };
            Guess::Request(request, reason)
        }
        (Err(_), Ok(_)) => Guess::Reply,
        (Err(request), Err(reply)) => Guess::Neither { request, reply },
    }
}

fn reply_reason(pdu: &[u8]) -> String {
    let len = pdu.len();
    match pdu.first().copied().unwrap_or(0) {
        f if f & 0x80 != 0 => {
            format!("function {f:02X} has the 0x80 bit set: an exception reply")
        }
        0x01 | 0x03 | 0x04 => {
            format!("PDU of {len} bytes: a read reply is 2 + byte count, a read request exactly 5")
        }
        0x10 => format!("PDU of {len} bytes: a write reply is 5 bytes, a write request at least 8"),
        0x2B => format!("PDU of {len} bytes: longer than the 4-byte device identification request"),
        _ => format!("PDU of {len} bytes parses only as a reply"),
    }
}

/// Why `reply` does not answer `request` sent to `address`.
fn mismatch_reason(request: &Request<'_>, address: u8, reply: &Frame<'_>) -> String {
    let sent = request.function().to_u8();
    let got = reply.pdu.first().copied().unwrap_or(0);
    if reply.address != address {
        format!(
            "it comes from node {}, the request went to node {address}",
            reply.address
        )
    } else if got & 0x7F != sent {
        format!("function {got:02X}, the request was function {sent:02X}")
    } else {
        match request {
            Request::ReadCoils { quantity, .. } => format!(
                "the request asked for {quantity} coils ({} data bytes)",
                usize::from(*quantity).div_ceil(8)
            ),
            Request::ReadHoldingRegisters { quantity, .. }
            | Request::ReadInputRegisters { quantity, .. } => format!(
                "the request asked for {quantity} registers ({} data bytes)",
                usize::from(*quantity) * 2
            ),
            Request::ReadDeviceIdentification { .. } => {
                "its access code is not the request's".to_owned()
            }
            _ => "its echo differs from the request".to_owned(),
        }
    }
}

fn describe_request(request: &Request<'_>, report: &mut FrameReport) {
    match *request {
        Request::ReadCoils { start, quantity } => {
            report.note(format!("read {quantity} coil(s) from {start:#06X}"));
            for address in range(start, quantity) {
                report.coils.push(CoilValue {
                    address,
                    name: coil_name(address),
                    on: None,
                });
            }
        }
        Request::ReadHoldingRegisters { start, quantity }
        | Request::ReadInputRegisters { start, quantity } => {
            report.note(format!("read {quantity} register(s) from {start:#06X}"));
            describe_range(start, quantity, report);
        }
        Request::WriteSingleCoil { address, on } => {
            let writable = if catalogue::coil_writable(address) {
                ""
            } else {
                " (not a writable coil)"
            };
            report.note(format!("set coil {address:#06X} {}{writable}", on_off(on)));
            report.coils.push(CoilValue {
                address,
                name: coil_name(address),
                on: Some(on),
            });
        }
        Request::WriteSingleRegister { address, value } => {
            report.note(format!("write register {address:#06X}"));
            explain_one(address, value, report);
            writable_note(address, 1, report);
        }
        Request::WriteMultipleRegisters { start, values } => {
            report.note(format!(
                "write {} register(s) from {start:#06X}",
                values.len()
            ));
            let words: Vec<u16> = values.iter().collect();
            explain_block(Some(start), &words, report);
            writable_note(start, values.len() as u16, report);
        }
        Request::ReadDeviceIdentification { code, object_id } => {
            report.note(format!(
                "read device identification, access code {:02X}, from object {object_id:02X} ({})",
                code.to_u8(),
                object_name(object_id)
            ));
            if object_id == PRODUCT_CODE_OBJECT {
                report.note("the product code tells the model (SYNC guide Table 2)");
            }
        }
    }
}

/// The legacy `torch_index` coils' lead length, in the legacy guide's words.
fn legacy_lead_length(bits: &[u8]) -> String {
    match LeadLength::from_legacy_coils(bits) {
        Ok(LeadLength::Upto7m6) => "15-25 ft (up to 7.6 m)".to_owned(),
        Ok(LeadLength::Upto15m) => "35-50 ft (up to 15 m)".to_owned(),
        Ok(LeadLength::Upto23m) => "75 ft (up to 23 m)".to_owned(),
        Err(_) => {
            let pair = bits.first().map_or(0, |b| b & 0b11);
            format!("bits {pair:02b}: not a length the legacy guide lists")
        }
    }
}

/// The two torch-lead coils (0x0808 in bit 0, 0x0809 in bit 1) out of a coil reply `bits`
/// to a read of `quantity` coils from `start`, when the read covers both.
fn lead_coils_of(start: u16, quantity: u16, bits: &[u8]) -> Option<u8> {
    let offset = usize::from(legacy::TORCH_LEAD_BIT0_COIL.checked_sub(start)?);
    if offset + 2 > usize::from(quantity) {
        return None;
    }
    let bit = |i: usize| bits.get(i / 8).map(|b| b >> (i % 8) & 1);
    Some(bit(offset)? | bit(offset + 1)? << 1)
}

fn describe_response(
    response: &Response<'_>,
    request: Option<&Request<'_>>,
    report: &mut FrameReport,
) {
    match *response {
        Response::ReadCoils { bits } => {
            match request {
                Some(&Request::ReadCoils { start, quantity }) => {
                    for (i, address) in range(start, quantity).enumerate() {
                        let on = bits.get(i / 8).is_some_and(|b| b >> (i % 8) & 1 == 1);
                        report.coils.push(CoilValue {
                            address,
                            name: coil_name(address),
                            on: Some(on),
                        });
                    }
                    if let Some(pair) = lead_coils_of(start, quantity, bits) {
                        report.field("torch lead length", legacy_lead_length(&[pair]), None);
                    }
                }
                _ => {
                    let hex: Vec<String> = bits.iter().map(|b| format!("{b:02X}")).collect();
                    report.field("coil bytes (first coil in bit 0)", hex.join(" "), None);
                    report.note("coil addresses are unknown without the request: give the request frame first");
                    // A reply to the two lead coils is one byte, the bits above them zero.
                    if matches!(*bits, [0..=0b11]) && LeadLength::from_legacy_coils(bits).is_ok() {
                        report.note(format!(
                            "if this answers the legacy torch-lead read (2 coils from 0x0808), the torch lead is {}",
                            legacy_lead_length(bits)
                        ));
                    }
                }
            }
        }
        Response::ReadHoldingRegisters { values } | Response::ReadInputRegisters { values } => {
            let words: Vec<u16> = values.iter().collect();
            let start = match request {
                Some(
                    Request::ReadHoldingRegisters { start, .. }
                    | Request::ReadInputRegisters { start, .. },
                ) => Some(*start),
                _ => {
                    report.note("register addresses are unknown without the request: give the request frame first to get names and units");
                    None
                }
            };
            explain_block(start, &words, report);
        }
        Response::WriteSingleCoil { address, on } => {
            report.note(format!("coil {address:#06X} set {} (echo)", on_off(on)));
            report.coils.push(CoilValue {
                address,
                name: coil_name(address),
                on: Some(on),
            });
        }
        Response::WriteSingleRegister { address, value } => {
            report.note(format!("register {address:#06X} written (echo)"));
            explain_one(address, value, report);
        }
        Response::WriteMultipleRegisters { start, quantity } => {
            report.note(format!("{quantity} register(s) written from {start:#06X}"));
            describe_range(start, quantity, report);
        }
        Response::ReadDeviceIdentification(id) => describe_device_id(&id, report),
        Response::Exception { function, code } => {
            report.field(
                "exception",
                format!("{:02X} {}", code.to_u8(), code.name()),
                None,
            );
            report.note(format!(
                "the unit refused function {function:02X} ({}): {} ({})",
                function_name(function),
                code.name(),
                code.description()
            ));
        }
    }
}

fn describe_device_id(id: &DeviceIdentification<'_>, report: &mut FrameReport) {
    report.field("access code", format!("{:02X}", id.code.to_u8()), None);
    report.field("conformity level", format!("{:02X}", id.conformity), None);
    if id.more_follows {
        report.field(
            "more follows, next object",
            format!("{:02X}", id.next_object_id),
            None,
        );
    }
    for (object, value) in id.objects() {
        report.fields.push(Field::new(
            format!("object {object:02X} {}", object_name(object)),
            printable(value),
            None,
        ));
    }
    match model_from_device_id(id) {
        Ok(Some(model)) => {
            report.field("model", model.name(), None);
            let family = match model.addressing() {
                plasma_protocol::powermax::AddressingSystem::Sync => "SYNC registers 0x3xxx",
                plasma_protocol::powermax::AddressingSystem::Legacy => "legacy registers 0x2xxx",
            };
            report.note(format!(
                "{} (product code {}): uses {family}",
                model.name(),
                model.product_code()
            ));
        }
        Ok(None) => report.note("no product code of SYNC guide Table 2 in this reply"),
        Err(e) => report.fail(format!("object list: {e}")),
    }
}

fn writable_note(start: u16, quantity: u16, report: &mut FrameReport) {
    if !catalogue::registers_writable(start, quantity) {
        report.note("not every register written is a documented writable register");
    }
}

fn range(start: u16, quantity: u16) -> impl Iterator<Item = u16> {
    (0..quantity).map_while(move |i| start.checked_add(i))
}

fn coil_name(address: u16) -> String {
    catalogue::coil(address).map_or_else(|| "undocumented coil".to_owned(), |c| c.name.to_owned())
}

fn on_off(on: bool) -> &'static str {
    if on { "on" } else { "off" }
}

/// Standard Read Device Identification object names.
fn object_name(id: u8) -> &'static str {
    match id {
        0x00 => "vendor name",
        0x01 => "product code",
        0x02 => "revision",
        0x03 => "vendor URL",
        0x04 => "product name",
        0x05 => "model name",
        0x06 => "user application name",
        _ => "private object",
    }
}
