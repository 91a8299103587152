//! A probe's findings for a person (text) or a program (JSON).

use serde_json::{Value, json};

use super::{Probe, Reading};
use crate::decode::{FrameReport, to_json};
use crate::serial::describe;

fn family_name(family: plasma_sim::Family) -> &'static str {
    match family {
        plasma_sim::Family::Sync => "SYNC",
        plasma_sim::Family::Legacy => "LEGACY",
        plasma_sim::Family::Hpr => "HPR",
    }
}

/// The values a reply carries, one per line (registers, coils, fields, faults, problems).
fn values(report: &FrameReport) -> Vec<String> {
    let mut out = Vec::new();
    for r in &report.registers {
        let address = r.address.map(|a| format!("0x{a:04X} ")).unwrap_or_default();
        let value = r.value.clone().unwrap_or_else(|| {
            r.raw
                .map_or_else(String::new, |raw| format!("raw 0x{raw:04X}"))
        });
        let unit = r.unit.map(|u| format!(" {u}")).unwrap_or_default();
        out.push(format!("{address}{}: {value}{unit}", r.name));
    }
    for c in &report.coils {
        let state = match c.on {
            Some(true) => "ON",
            Some(false) => "OFF",
            None => "?",
        };
        out.push(format!("coil 0x{:04X} {}: {state}", c.address, c.name));
    }
    for f in &report.fields {
        let unit = f.unit.map(|u| format!(" {u}")).unwrap_or_default();
        out.push(format!("{}: {}{unit}", f.name, f.value));
    }
    for f in &report.faults {
        let action = match f.action_required {
            Some(true) => ", action required",
            Some(false) => ", no action required",
            None => "",
        };
        out.push(format!(
            "fault {}: {}{action}",
            f.code,
            f.text.as_deref().unwrap_or("(no text)")
        ));
    }
    if let Some(error) = &report.error {
        out.push(format!("problem: {error}"));
    }
    out
}

/// What to check when no unit answered, most likely first.
pub const NO_UNIT_HINTS: &str = concat!(
    "  check the wiring: + to +, - to -; 4-wire: the unit's TX pair to the adapter's RX pair\n",
    "  check the adapter's 2W/4W switch: it must match the wiring\n",
    "  check the termination: 120 ohm at both ends of a long line, none in the middle\n",
    "  check the signal ground between the adapter and the unit\n",
    "  check the unit: powered, its serial option fitted, its address (a Powermax at another\n",
    "    node: --address N; an HPR answers at the id its switches set)\n",
);

/// The text report.
pub fn to_text(probe: &Probe) -> String {
    let mut text = String::new();
    let Some(found) = &probe.found else {
        return format!("no unit answered on {}\n{NO_UNIT_HINTS}", probe.port);
    };
    text += &format!(
        "{} unit on {} at {}\n",
        family_name(found.family),
        probe.port,
        describe(found.framing)
    );
    for line in values(&found.identity) {
        text += &format!("  {line}\n");
    }
    for Reading { what, reply, .. } in &probe.readings {
        text += &format!("{what}\n");
        match reply {
            Some(report) => {
                let lines = values(report);
                if lines.is_empty() {
                    // Nothing the decoder names: the reply as it came.
                    text += &format!("  reply: {}\n", report.frame);
                }
                for line in lines {
                    text += &format!("  {line}\n");
                }
            }
            None => text += "  no answer\n",
        }
    }
    text
}

/// The JSON report (one object).
pub fn to_json_report(probe: &Probe) -> Value {
    json!({
        "port": probe.port,
        "found": probe.found.is_some(),
        "family": probe.found.as_ref().map(|f| family_name(f.family)),
        "framing": probe.found.as_ref().map(|f| describe(f.framing)),
        "identity": probe.found.as_ref().map(|f| to_json(&f.identity)),
        "readings": probe.readings.iter().map(|r| json!({
            "what": r.what,
            "request": r.request.trim_end(),
            "reply": r.reply.as_ref().map(to_json),
        })).collect::<Vec<_>>(),
    })
}
