//! JSON output: one object per frame, one line each.

use serde_json::{Value, json};

use super::FrameReport;

/// The JSON object of one frame.
pub fn to_json(report: &FrameReport) -> Value {
    json!({
        "input": report.input,
        "frame": report.frame,
        "protocol": report.protocol.map(|p| p.json_name()),
        "valid": report.valid,
        "checksum": report.checksum.map(|c| json!({
            "found": format!("{:02X}", c.found),
            "expected": format!("{:02X}", c.expected),
            "ok": c.ok(),
        })),
        "address": report.address,
        "function": report.function.as_ref().map(|f| json!({"code": f.code, "name": f.name})),
        "command": report.command.as_ref().map(|c| json!({"id": c.id, "name": c.name, "class": c.class})),
        "kind": report.kind.map(|k| k.name()),
        "kind_reason": report.kind_reason,
        "answers_request": report.answers_request,
        "registers": report.registers.iter().map(|r| json!({
            "address": r.address,
            "name": r.name,
            "raw": r.raw,
            "value": r.value,
            "unit": r.unit,
        })).collect::<Vec<_>>(),
        "coils": report.coils.iter().map(|c| json!({
            "address": c.address,
            "name": c.name,
            "on": c.on,
        })).collect::<Vec<_>>(),
        "fields": report.fields.iter().map(|f| json!({
            "name": f.name,
            "value": f.value,
            "unit": f.unit,
        })).collect::<Vec<_>>(),
        "fault": report.faults.iter().map(|f| json!({
            "address": f.address,
            "code": f.code,
            "raw": f.raw,
            "text": f.text,
            "action_required": f.action_required,
            "steps_required": f.steps_required,
        })).collect::<Vec<_>>(),
        "notes": report.notes,
        "text": super::lines(report),
        "error": report.error,
        "meant": report.meant.as_deref().map(to_json),
    })
}
