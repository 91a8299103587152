//! Plain-text output: one block per frame, for a technician's terminal.

use super::{FrameReport, Kind, Protocol};

/// The explanation of one frame, one line each (without the frame itself).
pub fn lines(report: &FrameReport) -> Vec<String> {
    let mut out = Vec::new();
    let mut head = match report.protocol {
        Some(Protocol::ModbusAscii) => "Modbus ASCII".to_owned(),
        Some(Protocol::Hpr) => "HPR".to_owned(),
        None => "unknown protocol".to_owned(),
    };
    if let Some(ck) = report.checksum {
        let what = if report.protocol == Some(Protocol::Hpr) {
            "checksum"
        } else {
            "LRC"
        };
        if ck.ok() {
            head += &format!(", {what} {:02X} correct", ck.found);
        } else {
            head += &format!(
                ", {what} {:02X} WRONG, should be {:02X}",
                ck.found, ck.expected
            );
        }
    }
    out.push(head);

    let mut what = Vec::new();
    if let Some(address) = report.address {
        what.push(format!("node {address}"));
    }
    if let Some(f) = &report.function {
        what.push(format!("function {:02X} {}", f.code, f.name));
    }
    if let Some(c) = &report.command {
        let name = c.name.unwrap_or("(not in the command table)");
        match c.class {
            Some(class) => what.push(format!("command {:03} {name} [{class}]", c.id)),
            None => what.push(format!("command {:03} {name}", c.id)),
        }
    }
    if let Some(kind) = report.kind {
        let mut k = match kind {
            Kind::Request => "REQUEST".to_owned(),
            Kind::Reply => "REPLY".to_owned(),
        };
        if let Some(reason) = &report.kind_reason {
            k += &format!(" ({reason})");
        }
        what.push(k);
    } else if let Some(reason) = &report.kind_reason {
        what.push(reason.clone());
    }
    if !what.is_empty() {
        out.push(what.join(", "));
    }
    if let Some(error) = &report.error {
        out.push(format!("INVALID: {error}"));
    }
    out.extend(report.notes.iter().cloned());
    for r in &report.registers {
        let address = r
            .address
            .map_or_else(|| "?".to_owned(), |a| format!("{a:#06X}"));
        let line = match (&r.value, r.raw) {
            (Some(value), Some(raw)) => {
                format!(
                    "{address} {} = {}{} (raw {raw:#06X})",
                    r.name,
                    value,
                    unit(r.unit)
                )
            }
            _ => format!("{address} {}", r.name),
        };
        out.push(line);
    }
    for c in &report.coils {
        let state = match c.on {
            Some(true) => " = on",
            Some(false) => " = off",
            None => "",
        };
        out.push(format!("coil {:#06X} {}{state}", c.address, c.name));
    }
    for f in &report.fields {
        out.push(format!("{}: {}{}", f.name, f.value, unit(f.unit)));
    }
    // Register faults are already on their register's line.
    for f in report.faults.iter().filter(|f| f.address.is_none()) {
        let text = f.text.as_deref().unwrap_or("not in the error table");
        out.push(format!("error {} {text}", f.code));
    }
    if let Some(meant) = &report.meant {
        out.push(format!("the manual meant {}:", meant.frame));
        out.extend(lines(meant).into_iter().map(|line| format!("  {line}")));
    }
    out
}

fn unit(unit: Option<&str>) -> String {
    unit.map_or_else(String::new, |u| format!(" {u}"))
}

/// All frames as text: the frame, then its explanation indented.
pub fn to_text(reports: &[FrameReport]) -> String {
    let mut text = String::new();
    for (i, report) in reports.iter().enumerate() {
        if i > 0 {
            text.push('\n');
        }
        text += &format!("{}\n", report.input.trim_end());
        for line in lines(report) {
            text += &format!("  {line}\n");
        }
    }
    text
}
