//! `pbtool decode`: explain Modbus ASCII and HPR frames to a technician.
//!
//! Each frame (one argv item) becomes a [`FrameReport`]: protocol, checksum found and expected,
//! request or reply (and why), and every field in the units the manuals use. A frame that
//! answers the request just before it is read in the light of that request (register names,
//! scaling, fault texts); one that does not is reported as a mismatch.
//!
//! ```
//! use pbtool::decode::{decode_frames, Kind};
//!
//! let reports = decode_frames(&[":010430440004".to_owned() + "83", ":010408007900790000000001".into()]);
//! assert_eq!(reports[1].kind, Some(Kind::Reply));
//! assert_eq!(reports[1].faults[0].code, "0-12-1");
//! ```

mod hpr;
mod json;
mod modbus;
mod registers;
mod stream;
mod text;

pub use json::to_json;
pub use stream::FrameStream;
pub use text::{lines, to_text};

/// Wire protocol of a frame, from its first character.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Protocol {
    /// `:` ... LRC CR LF (Powermax).
    ModbusAscii,
    /// `>` id data checksum `<` (HPR, MaxPro200).
    Hpr,
}

impl Protocol {
    /// Name used in JSON output.
    pub fn json_name(self) -> &'static str {
        match self {
            Protocol::ModbusAscii => "modbus_ascii",
            Protocol::Hpr => "hpr",
        }
    }
}

/// Which way a frame goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// CNC (or bridge) to power supply.
    Request,
    /// Power supply to CNC.
    Reply,
}

impl Kind {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Request => "request",
            Kind::Reply => "reply",
        }
    }
}

/// Checksum carried by the frame and the one its bytes call for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Checksum {
    /// Value in the frame.
    pub found: u8,
    /// Value computed over the frame's bytes.
    pub expected: u8,
}

impl Checksum {
    /// True when the frame's checksum is right.
    pub fn ok(&self) -> bool {
        self.found == self.expected
    }
}

/// One register with its catalogue name and scaled value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RegisterValue {
    /// Register address; `None` in a read reply decoded without its request.
    pub address: Option<u16>,
    /// Catalogue name (`undocumented register` when the catalogue has none).
    pub name: String,
    /// Register value; `None` for the registers a read request asks for.
    pub raw: Option<u16>,
    /// Value as a technician reads it (`63`, `auto`, `0-50-0`, `cut`).
    pub value: Option<String>,
    /// Unit of `value` (`A`, `psi`, `s`).
    pub unit: Option<&'static str>,
}

/// One coil and its state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CoilValue {
    /// Coil address.
    pub address: u16,
    /// Catalogue name.
    pub name: String,
    /// State; `None` for the coils a read request asks for.
    pub on: Option<bool>,
}

/// A named value that is not a single register: a request parameter, a 32-bit counter, a
/// string spread over registers, an HPR field.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// What it is.
    pub name: String,
    /// Its value.
    pub value: String,
    /// Unit, if any.
    pub unit: Option<&'static str>,
}

impl Field {
    pub(crate) fn new(
        name: impl Into<String>,
        value: impl ToString,
        unit: Option<&'static str>,
    ) -> Self {
        Field {
            name: name.into(),
            value: value.to_string(),
            unit,
        }
    }
}

/// A fault (Powermax) or error code (HPR) with its table text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fault {
    /// Register it was read from (Powermax).
    pub address: Option<u16>,
    /// Code as displayed: `0-50-0` (Powermax) or `020` (HPR).
    pub code: String,
    /// Raw number.
    pub raw: u16,
    /// The manual's description; `None` for a code the tables do not list.
    pub text: Option<String>,
    /// SYNC table "Steps Required to Remove?" = Yes; `None` for a code no table lists, or an
    /// HPR error.
    pub action_required: Option<bool>,
    /// The "Steps Required to Remove?" words (`yes`, `no, but recommended`, `no`); a code only
    /// the legacy list has reads `yes` (the protocol crate's documented choice).
    pub steps_required: Option<&'static str>,
}

/// HPR command id, name and class.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Command {
    /// Command id (500/501 for error replies).
    pub id: u16,
    /// Name as printed in the manual.
    pub name: Option<&'static str>,
    /// `normal`, `factory testing only` or `dangerous`.
    pub class: Option<&'static str>,
}

/// Modbus function code and its name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Function {
    /// Function byte as received (0x80 set in an exception reply).
    pub code: u8,
    /// Name of the function.
    pub name: &'static str,
}

/// Everything `pbtool decode` found in one frame.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FrameReport {
    /// The argument as given.
    pub input: String,
    /// The frame after removing line endings.
    pub frame: String,
    /// Protocol, when the first character says which.
    pub protocol: Option<Protocol>,
    /// False for a bad checksum, a malformed frame or a reply that does not answer its request.
    pub valid: bool,
    /// Checksum found and expected, when the frame got that far.
    pub checksum: Option<Checksum>,
    /// Modbus node address.
    pub address: Option<u8>,
    /// Modbus function.
    pub function: Option<Function>,
    /// HPR command.
    pub command: Option<Command>,
    /// Request or reply.
    pub kind: Option<Kind>,
    /// Why `kind` was chosen.
    pub kind_reason: Option<String>,
    /// Some when the frame was matched against the request before it.
    pub answers_request: Option<bool>,
    /// Registers named and scaled.
    pub registers: Vec<RegisterValue>,
    /// Coils named.
    pub coils: Vec<CoilValue>,
    /// Other values.
    pub fields: Vec<Field>,
    /// Fault or error codes with their texts.
    pub faults: Vec<Fault>,
    /// Further explanation (exception meaning, table rows, models).
    pub notes: Vec<String>,
    /// Why the frame is invalid, or what could not be decoded.
    pub error: Option<String>,
    /// For a manual's sample printed with a typo: the frame the manual meant, decoded.
    pub meant: Option<Box<FrameReport>>,
}

impl FrameReport {
    fn new(input: &str) -> Self {
        FrameReport {
            input: input.to_owned(),
            valid: true,
            ..Default::default()
        }
    }

    pub(crate) fn fail(&mut self, error: impl Into<String>) {
        self.valid = false;
        self.error = Some(error.into());
    }

    pub(crate) fn note(&mut self, note: impl Into<String>) {
        self.notes.push(note.into());
    }

    pub(crate) fn field(
        &mut self,
        name: impl Into<String>,
        value: impl ToString,
        unit: Option<&'static str>,
    ) {
        self.fields.push(Field::new(name, value, unit));
    }
}

/// A request remembered so the next frame can be matched against it.
enum Pending {
    Modbus(modbus::OwnedFrame),
    Hpr(protocol_hpr::Request),
}

use plasma_protocol::errata;
use plasma_protocol::hpr as protocol_hpr;

/// Decodes frames given as separate arguments, in order; a frame right after a request is
/// checked as its reply. A manual's sample printed with a typo is decoded as given (and is
/// invalid), and the frame the manual meant is decoded beside it ([`FrameReport::meant`]) and
/// read in the light of the request before it.
pub fn decode_frames<S: AsRef<str>>(inputs: &[S]) -> Vec<FrameReport> {
    let mut pending: Option<Pending> = None;
    inputs
        .iter()
        .map(|input| {
            let mut report = FrameReport::new(input.as_ref());
            let frame = clean(input.as_ref(), &mut report);
            report.frame = frame.clone();
            let next = decode_one(&frame, pending.as_ref(), &mut report);
            pending = match errata::erratum_for(&frame) {
                Some(erratum) => {
                    report.note(format!(
                        "{} is printed with a typo: {}; the manual meant {}",
                        erratum.sample, erratum.why, erratum.meant
                    ));
                    let mut meant = FrameReport::new(erratum.meant);
                    meant.frame = erratum.meant.to_owned();
                    let next = decode_one(erratum.meant, pending.as_ref(), &mut meant);
                    report.meant = Some(Box::new(meant));
                    next
                }
                None => next,
            };
            report
        })
        .collect()
}

/// Decodes one cleaned frame into `report`; returns the request to match the next frame
/// against.
fn decode_one(frame: &str, pending: Option<&Pending>, report: &mut FrameReport) -> Option<Pending> {
    match frame.as_bytes().first() {
        Some(b':') => {
            report.protocol = Some(Protocol::ModbusAscii);
            let previous = match pending {
                Some(Pending::Modbus(request)) => Some(request),
                _ => None,
            };
            modbus::decode(frame, previous, report).map(Pending::Modbus)
        }
        Some(b'>') => {
            report.protocol = Some(Protocol::Hpr);
            let previous = match pending {
                Some(Pending::Hpr(request)) => Some(request),
                _ => None,
            };
            hpr::decode(frame, previous, report).map(Pending::Hpr)
        }
        _ => {
            report.fail("not a frame: Modbus ASCII frames start with ':', HPR frames with '>'");
            None
        }
    }
}

/// True when every frame is valid (the CLI's exit status 0).
pub fn all_valid(reports: &[FrameReport]) -> bool {
    reports.iter().all(|r| r.valid)
}

/// Removes what the manuals and terminals put around a frame: surrounding blanks, real CR/LF,
/// the manuals' literal `<CR><LF>`, and a typed `\r\n`.
fn clean(input: &str, report: &mut FrameReport) -> String {
    let mut frame = input.trim().to_owned();
    let mut removed_literal = false;
    let mut removed_crlf = false;
    loop {
        let upper = frame.to_ascii_uppercase();
        if let Some(suffix) = ["<CR><LF>", "<CR>", "<LF>", "\\R\\N", "\\R", "\\N"]
            .into_iter()
            .find(|s| upper.ends_with(s))
        {
            frame.truncate(frame.len() - suffix.len());
            removed_literal = true;
        } else if frame.ends_with(['\r', '\n']) {
            frame.pop();
            removed_crlf = true;
        } else {
            break;
        }
        frame = frame.trim_end().to_owned();
    }
    if removed_literal {
        report.note("the manuals' end-of-message marker (<CR><LF>) was removed before decoding");
    }
    if (removed_literal || removed_crlf) && frame.starts_with('>') {
        report.note("an HPR frame ends at '<': a CR/LF after it can lock up older control boards");
    }
    frame
}
