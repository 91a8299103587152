//! Powermax register values, named from the catalogue and scaled exactly.

use plasma_protocol::modbus_ascii::Registers;
use plasma_protocol::powermax::registers::{self as catalogue, Access, RegisterInfo, ValueKind};
use plasma_protocol::powermax::sync::{self, Identification, PermittedModes};
use plasma_protocol::powermax::{
    Amps, CartridgeName, CartridgeUid, FaultCode, OperatingMode, PartNumber, Pressure, Psi,
    StepsRequired,
};

use super::{Fault, FrameReport, RegisterValue};

/// Names the registers of `start..start + quantity` (a read request or a write reply).
pub(super) fn describe_range(start: u16, quantity: u16, report: &mut FrameReport) {
    for address in (0..quantity).map_while(|i| start.checked_add(i)) {
        report.registers.push(RegisterValue {
            address: Some(address),
            name: name_of(address),
            raw: None,
            value: None,
            unit: None,
        });
    }
}

/// One register and its value.
pub(super) fn explain_one(address: u16, raw: u16, report: &mut FrameReport) {
    explain_block(Some(address), &[raw], report);
}

/// Consecutive register values from `start` (unknown when a reply is decoded without its
/// request: then the values are shown raw). Adds the registers, their faults, and the values
/// that span registers (32-bit counters low word first, ASCII strings).
pub(super) fn explain_block(start: Option<u16>, words: &[u16], report: &mut FrameReport) {
    let Some(start) = start else {
        for &raw in words {
            report.registers.push(RegisterValue {
                address: None,
                name: "register (address unknown)".to_owned(),
                raw: Some(raw),
                value: Some(format!("{raw:#06X}")),
                unit: None,
            });
        }
        return;
    };
    let addressed: Vec<(u16, u16)> = words
        .iter()
        .enumerate()
        .map_while(|(i, &raw)| Some((start.checked_add(u16::try_from(i).ok()?)?, raw)))
        .collect();
    for &(address, raw) in &addressed {
        let (value, unit) = match catalogue::register(address) {
            Some(info) => scale(info, address, raw, report),
            None => (format!("{raw:#06X}"), None),
        };
        report.registers.push(RegisterValue {
            address: Some(address),
            name: name_of(address),
            raw: Some(raw),
            value: Some(value),
            unit,
        });
    }
    combine(&addressed, report);
}

fn name_of(address: u16) -> String {
    catalogue::register(address)
        .map_or_else(|| "undocumented register".to_owned(), |r| r.name.to_owned())
}

fn is_legacy(address: u16) -> bool {
    address < 0x3000
}

/// The value of one register as a technician reads it, and its unit.
fn scale(
    info: &RegisterInfo,
    address: u16,
    raw: u16,
    report: &mut FrameReport,
) -> (String, Option<&'static str>) {
    match info.kind {
        ValueKind::Amps => (Amps::from_raw(raw).to_string(), Some("A")),
        // Setting registers use 0 for automatic pressure; actual readings do not.
        ValueKind::Psi if info.name.starts_with("actual") => {
            (Psi::from_raw(raw).to_string(), Some("psi"))
        }
        ValueKind::Psi => match Pressure::from_raw(raw) {
            Pressure::Auto => ("auto".to_owned(), None),
            Pressure::Set(psi) => (psi.to_string(), Some("psi")),
        },
        ValueKind::Fault => {
            let fault = fault(address, raw);
            let value = match &fault.text {
                Some(text) => format!("{} {}{}", fault.code, text, steps_suffix(raw)),
                None => format!("{} (not in the fault tables)", fault.code),
            };
            report.faults.push(fault);
            (value, None)
        }
        ValueKind::Mode => {
            let mode = if is_legacy(address) {
                OperatingMode::from_legacy(raw).map(OperatingMode::legacy_name)
            } else {
                OperatingMode::from_sync(raw).map(OperatingMode::sync_name)
            };
            let value = match (mode, raw) {
                (Some(name), _) => name.to_owned(),
                (None, 0) if info.access == Access::Write => {
                    "0 (with current and pressure 0: leave remote control)".to_owned()
                }
                (None, _) => format!("{raw} (not a mode)"),
            };
            (value, None)
        }
        ValueKind::BytePair => (byte_pair(address, raw), None),
        ValueKind::Ascii => (printable(&raw.to_be_bytes()), None),
        ValueKind::Counter32 { .. } | ValueKind::Count => (raw.to_string(), None),
        ValueKind::TwoSeconds => ((u32::from(raw) * 2).to_string(), Some("s")),
        ValueKind::Raw => {
            let known = match address {
                sync::QUICK_RESTART_COMMAND if raw == sync::QUICK_RESTART_COMMAND_VALUE => {
                    " (the quick restart command word)"
                }
                sync::QUICK_RESTART_APPROVAL if raw == sync::QUICK_RESTART_APPROVAL_VALUE => {
                    " (the quick restart approval word)"
                }
                _ => "",
            };
            (format!("{raw:#06X}{known}"), None)
        }
    }
}

/// The fault code with the text of the table of its register family (the other table when
/// that one does not list it).
fn fault(address: u16, raw: u16) -> Fault {
    let code = FaultCode(raw);
    let sync_row = code.info();
    let text = match (is_legacy(address), sync_row, code.legacy_info()) {
        (true, _, Some(text)) | (false, None, Some(text)) => Some(text.to_string()),
        (_, Some(info), _) => Some(info.text.to_string()),
        (_, None, None) => None,
    };
    // The steps the bridge goes by: the SYNC row's, or the crate's documented choice for a
    // code it has no row for (the legacy list has no steps column).
    let steps = Some(code.steps_required());
    Fault {
        address: Some(address),
        code: code.to_string(),
        raw,
        text,
        action_required: steps.map(|s| s == StepsRequired::Yes),
        steps_required: steps.map(steps_word),
    }
}

/// The SYNC table's words for a steps value.
fn steps_word(steps: StepsRequired) -> &'static str {
    match steps {
        StepsRequired::Yes => "yes",
        StepsRequired::Recommended => "no, but recommended",
        StepsRequired::No => "no",
    }
}

fn steps_suffix(raw: u16) -> &'static str {
    let code = FaultCode(raw);
    if raw == 0 {
        return "";
    }
    match (code.info(), code.steps_required()) {
        (None, _) => " (action required: the SYNC table has no row for it, taken as required)",
        (Some(_), StepsRequired::Yes) => " (action required)",
        (Some(_), StepsRequired::Recommended) => " (no action required, but recommended)",
        (Some(_), StepsRequired::No) => " (no action required)",
    }
}

fn byte_pair(address: u16, raw: u16) -> String {
    let [high, low] = raw.to_be_bytes();
    match address {
        sync::IDENTIFICATION => {
            let Ok(id) = Identification::decode(Registers::Words(&[raw])) else {
                return format!("{raw:#06X}");
            };
            let torch = id.torch.map_or_else(
                || format!("unknown torch id {high:02X}"),
                |t| t.description().to_owned(),
            );
            let model = id.model.map_or_else(
                || format!("unknown power supply id {low:02X}"),
                |m| m.description().to_owned(),
            );
            format!("torch: {torch}; power supply: {model}")
        }
        sync::PERMITTED_MODES => {
            let modes = PermittedModes { high, low };
            let name = |m: Option<OperatingMode>, b: u8| {
                m.map_or_else(|| format!("{b} (not a mode)"), |m| m.sync_name().to_owned())
            };
            if high == low {
                format!("only {}", name(modes.high_mode(), high))
            } else {
                format!(
                    "{} and {}",
                    name(modes.high_mode(), high),
                    name(modes.low_mode(), low)
                )
            }
        }
        _ => format!("high byte {high:02X}, low byte {low:02X}"),
    }
}

/// Values spanning several registers of one read or write.
fn combine(addressed: &[(u16, u16)], report: &mut FrameReport) {
    // 32-bit counters: low word first, high word at the next address.
    for pair in addressed.windows(2) {
        let [(low_address, low), (high_address, high)] = pair else {
            continue;
        };
        let (Some(low_info), Some(high_info)) = (
            catalogue::register(*low_address),
            catalogue::register(*high_address),
        ) else {
            continue;
        };
        if low_info.kind == (ValueKind::Counter32 { high: false })
            && high_info.kind == (ValueKind::Counter32 { high: true })
        {
            let name = low_info.name.trim_end_matches(" (low word)");
            let value = u32::from(*high) << 16 | u32::from(*low);
            let unit = if name.contains("seconds") {
                Some("s")
            } else {
                None
            };
            report.field(name, value, unit);
        }
    }
    // Strings: the registers of one catalogue entry that this frame holds, high byte first.
    let mut i = 0;
    while let Some(&(address, _)) = addressed.get(i) {
        let entry = catalogue::register(address);
        let run: Vec<(u16, u16)> = addressed
            .iter()
            .skip(i)
            .take_while(|(a, _)| catalogue::register(*a) == entry)
            .copied()
            .collect();
        i += run.len().max(1);
        let Some(entry) = entry else { continue };
        let is_uid = entry.first == sync::CARTRIDGE_UID;
        if entry.kind != ValueKind::Ascii && !is_uid {
            continue;
        }
        let words: Vec<u16> = run.iter().map(|&(_, w)| w).collect();
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_be_bytes()).collect();
        let complete = run.first().map(|r| r.0) == Some(entry.first)
            && run.len() == usize::from(entry.last - entry.first) + 1;
        string_field(entry, &words, &bytes, complete, report);
    }
}

fn string_field(
    entry: &RegisterInfo,
    words: &[u16],
    bytes: &[u8],
    complete: bool,
    report: &mut FrameReport,
) {
    let registers = Registers::Words(words);
    let text = printable(bytes);
    let partial = if complete { "" } else { " (part)" };
    report.field(format!("{}{partial}", entry.name), &text, None);
    if !complete {
        return;
    }
    match entry.first {
        sync::CARTRIDGE_PART_NUMBER => {
            if let Ok(part) = PartNumber::decode(registers) {
                if part.is_read_failure() {
                    report.note("cartridge part number: cartridge communication failure or radio frequency error");
                } else if let Some(row) = part.cartridge_type() {
                    report.note(format!(
                        "cartridge {}: {}",
                        row.part_number, row.description
                    ));
                }
            }
        }
        sync::CARTRIDGE_NAME => {
            if let Some(row) = CartridgeName::decode(registers).ok().and_then(|n| n.info()) {
                report.note(format!("cartridge name {}: {}", row.name, row.description));
            }
        }
        sync::CARTRIDGE_UID
            if CartridgeUid::decode(registers).is_ok_and(|uid| uid.is_read_failure()) =>
        {
            report.note("cartridge UID all zero: cartridge communication failure");
        }
        _ => {}
    }
}

/// Bytes as text: up to the first NUL, printable ASCII as is, anything else as `\xNN`.
pub(super) fn printable(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    bytes[..end]
        .iter()
        .map(|&b| {
            if (0x20..0x7F).contains(&b) {
                char::from(b).to_string()
            } else {
                format!("\\x{b:02X}")
            }
        })
        .collect()
}
