//! `pbtool history`: the bridge's event history (`HISTORY N`) as a table, JSON or CSV.
//!
//! The bridge writes one `HISTORY seq=.. boot=.. uptime_ms=.. clock=.. family=.. model=.. event=..`
//! line per entry, newest first, then `OK history=N skipped=K` (docs/cnc-protocol.md); an
//! entry about a unit beyond the first ends in `unit=N`, and the table and CSV give every
//! entry its unit (1 where the line has none, as for every reply). Before
//! reading, pbtool sets the bridge's clock (`CLOCK`) to the PC's, so that the entries of this
//! boot carry the wall-clock time.

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use plasma_protocol::cnc::clock::WallClock;
use plasma_sim::Model;

use host_tests::harness::{World, WorldOptions, is_reply_line};
use plasma_firmware::settings::Settings;
use plasma_protocol::serial::PortConfig;

use crate::serial::{Port, Rx, SerialError};

/// The columns every entry has, in the table's order; the event's own fields follow.
pub const COLUMNS: [&str; 8] = [
    "seq",
    "boot",
    "uptime_ms",
    "clock",
    "unit",
    "family",
    "model",
    "event",
];

/// The longest wait for the bridge's reply on a port.
pub const PORT_REPLY_TIMEOUT: Duration = Duration::from_secs(2);

/// One entry: its fields in the bridge's order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Row {
    /// `(key, value)` pairs as written.
    pub fields: Vec<(String, String)>,
}

impl Row {
    /// A `HISTORY ...` line's fields, or `None` for any other line.
    pub fn parse(line: &str) -> Option<Row> {
        let rest = line.strip_prefix("HISTORY ")?;
        let fields = rest
            .split(' ')
            .filter_map(|pair| pair.split_once('='))
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        Some(Row { fields })
    }

    /// The value of `key` (empty when absent).
    pub fn get(&self, key: &str) -> &str {
        self.fields
            .iter()
            .find(|(k, _)| k == key)
            .map_or("", |(_, v)| v.as_str())
    }

    /// The cell of `column`: its value, and for `unit` the first unit when the line names
    /// none (only the units beyond the first are tagged).
    pub fn cell(&self, column: &str) -> &str {
        match self.get(column) {
            "" if column == "unit" => "1",
            value => value,
        }
    }

    /// The event's own fields, `key=value` separated by spaces.
    pub fn details(&self) -> String {
        self.fields
            .iter()
            .filter(|(k, _)| !COLUMNS.contains(&k.as_str()))
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// The PC's clock now: unix seconds, UTC.
pub fn pc_unix_seconds() -> u32 {
    let seconds = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    u32::try_from(seconds).unwrap_or(u32::MAX)
}

/// The `CLOCK` command that sets the bridge's wall clock to `unix_seconds`
/// (`CLOCK 2026-11-26T07:30:00`).
pub fn clock_command(unix_seconds: u32) -> String {
    format!("CLOCK {}", WallClock::from_unix_seconds(unix_seconds))
}

/// The entries among a reply's lines.
pub fn rows<'a>(lines: impl IntoIterator<Item = &'a str>) -> Vec<Row> {
    lines.into_iter().filter_map(Row::parse).collect()
}

/// A table with a header, columns padded to their widest cell.
pub fn table(rows: &[Row]) -> String {
    let header: Vec<String> = COLUMNS
        .iter()
        .map(|c| c.to_string())
        .chain(["details".to_string()])
        .collect();
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            COLUMNS
                .iter()
                .map(|c| r.cell(c).to_string())
                .chain([r.details()])
                .collect()
        })
        .collect();
    let widths: Vec<usize> = (0..header.len())
        .map(|i| {
            cells
                .iter()
                .chain([&header])
                .map(|row| row[i].len())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for row in [&header].into_iter().chain(&cells) {
        let line: Vec<String> = row
            .iter()
            .zip(&widths)
            .map(|(cell, w)| format!("{cell:<w$}"))
            .collect();
        out.push_str(line.join("  ").trim_end());
        out.push('\n');
    }
    out
}

/// CSV: the columns, then `details` (the event's fields), one row per entry.
pub fn csv(rows: &[Row]) -> String {
    let quote = |cell: &str| {
        if cell.contains([',', '"', ' ']) {
            format!("\"{}\"", cell.replace('"', "\"\""))
        } else {
            cell.to_string()
        }
    };
    let mut out = COLUMNS.join(",") + ",details\n";
    for row in rows {
        let cells: Vec<String> = COLUMNS
            .iter()
            .map(|c| quote(row.cell(c)))
            .chain([quote(&row.details())])
            .collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out
}

/// JSON: an array of objects, one per entry, every field as written.
pub fn json(rows: &[Row]) -> String {
    let entries: Vec<serde_json::Value> = rows
        .iter()
        .map(|r| {
            serde_json::Value::Object(
                r.fields
                    .iter()
                    .map(|(k, v)| (k.clone(), serde_json::Value::String(v.clone())))
                    .collect(),
            )
        })
        .collect();
    serde_json::to_string_pretty(&entries).unwrap_or_default() + "\n"
}

/// The history of a bridge against a simulated `model` (virtual time), with `fault` raised
/// from the start; the clock set first. Returns the `HISTORY` lines and the closing reply.
pub fn from_sim(model: Model, fault: Option<u16>, count: u8) -> (Vec<String>, String) {
    let mut world = World::with_bridge(model, WorldOptions::default(), Settings::default());
    if let Some(code) = fault {
        world.inject_fault(code);
    }
    let _ = world.wait_link_up(plasma_protocol::time::Duration::from_secs(5));
    world.run_for(plasma_protocol::time::Duration::from_millis(500));
    world.cnc_line(&clock_command(pc_unix_seconds()));
    let mark = world.cnc_output().len();
    let reply = world.cnc_line(&format!("HISTORY {count}"));
    let lines = world.cnc_output()[mark..]
        .iter()
        .filter_map(|r| r.item.line())
        .filter(|l| l.starts_with("HISTORY "))
        .map(str::to_string)
        .collect();
    (lines, reply)
}

/// The history of the firmware on the emulated board wired to `unit` (QEMU, real time), once
/// the link is up, the clock set first.
pub fn from_emu(unit: &crate::emu::EmuUnit, count: u8) -> Result<(Vec<String>, String), String> {
    use crate::emu::console::{REPLY_TIMEOUT, settle};
    let mut board = unit.boot().map_err(|e| e.to_string())?;
    // A unit not found still leaves the bridge's own entries (its reset) to read.
    settle(&mut board, unit.count()).map_err(|e| e.to_string())?;
    board
        .command(&clock_command(pc_unix_seconds()), REPLY_TIMEOUT)
        .map_err(|e| e.to_string())?;
    let cnc = board.cnc();
    cnc.send(&format!("HISTORY {count}"))
        .map_err(|e| e.to_string())?;
    let mut lines = Vec::new();
    loop {
        let line = cnc.reply(REPLY_TIMEOUT).map_err(|e| e.to_string())?;
        if is_reply_line(&line) {
            return Ok((lines, line));
        }
        lines.push(line);
    }
}

/// Sends `command` on `port`; the lines up to the reply (`OK`/`ERR`) and the reply. Lines
/// with a flagged character and event lines are left out.
pub fn port_command(port: &mut Port, command: &str) -> Result<(Vec<String>, String), String> {
    port.write_all(format!("{command}\r\n").as_bytes())
        .map_err(|e| e.to_string())?;
    let deadline = Instant::now() + PORT_REPLY_TIMEOUT;
    let mut received = Vec::new();
    let mut lines = Vec::new();
    loop {
        while let Some(end) = received.iter().position(|&r| r == Rx::Byte(b'\n')) {
            let line: Vec<Rx> = received.drain(..=end).collect();
            if line.contains(&Rx::Error) {
                continue;
            }
            let text = String::from_utf8_lossy(&Rx::cnc_bytes(&line))
                .trim()
                .to_string();
            if is_reply_line(&text) {
                return Ok((lines, text));
            }
            if !text.starts_with('!') {
                lines.push(text);
            }
        }
        let now = Instant::now();
        if now >= deadline {
            return Err(format!(
                "no reply to {command} within {PORT_REPLY_TIMEOUT:?}"
            ));
        }
        port.read(deadline - now, &mut received)
            .map_err(|e: SerialError| e.to_string())?;
    }
}

/// The history of the bridge on the serial port `name` at `framing`, the clock set first.
pub fn over_port(
    name: &str,
    framing: PortConfig,
    count: u8,
) -> Result<(Vec<String>, String), String> {
    let mut port = Port::open(name, framing).map_err(|e| e.to_string())?;
    port_command(&mut port, &clock_command(pc_unix_seconds()))?;
    port_command(&mut port, &format!("HISTORY {count}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const LINES: [&str; 4] = [
        "HISTORY seq=5 boot=1 uptime_ms=2100 clock=- family=HPR model=HPR260 event=FAULT code=046 action=required unit=2",
        "HISTORY seq=4 boot=1 uptime_ms=812 clock=- family=- model=- event=RESET cause=power-on",
        "HISTORY seq=3 boot=0 uptime_ms=2500 clock=2026-11-26T07:30:02 family=SYNC model=Powermax65 event=FAULT code=0-50-0 action=required",
        "OK history=3 skipped=0",
    ];

    #[test]
    fn entries_as_table_csv_and_json() {
        let rows = rows(LINES);
        assert_eq!(rows.len(), 3);
        assert_eq!(
            table(&rows),
            "seq  boot  uptime_ms  clock                unit  family  model       event  details\n\
             5    1     2100       -                    2     HPR     HPR260      FAULT  code=046 action=required\n\
             4    1     812        -                    1     -       -           RESET  cause=power-on\n\
             3    0     2500       2026-11-26T07:30:02  1     SYNC    Powermax65  FAULT  code=0-50-0 action=required\n"
        );
        assert_eq!(
            csv(&rows),
            "seq,boot,uptime_ms,clock,unit,family,model,event,details\n\
             5,1,2100,-,2,HPR,HPR260,FAULT,\"code=046 action=required\"\n\
             4,1,812,-,1,-,-,RESET,cause=power-on\n\
             3,0,2500,2026-11-26T07:30:02,1,SYNC,Powermax65,FAULT,\"code=0-50-0 action=required\"\n"
        );
        let parsed: serde_json::Value = serde_json::from_str(&json(&rows)).unwrap();
        assert_eq!(parsed[2]["code"], "0-50-0");
        assert_eq!(parsed[1]["event"], "RESET");
        assert_eq!(parsed[0]["unit"], "2");
        // JSON gives the fields as written: no unit where the line has none.
        assert!(parsed[1].get("unit").is_none());
    }

    #[test]
    fn the_simulated_bridge_keeps_the_units_fault() {
        let (lines, reply) = from_sim(Model::Sync65, Some(500), 5);
        assert_eq!(reply, "OK history=1 skipped=0", "{lines:?}");
        let rows = rows(lines.iter().map(String::as_str));
        assert_eq!(rows[0].get("event"), "FAULT");
        assert_eq!(rows[0].get("code"), "0-50-0");
        // The clock was set after the fault: the entry shows it all the same.
        assert_ne!(rows[0].get("clock"), "-");
    }
}
