//! `pbtool unit`: simulated units ([`plasma_sim`]) served on a serial port in real time,
//! answering any master: the bridge on a PC, a real board, CNC software.
//!
//! The units are the same sans-IO simulators the scenario tests use, driven by the wall clock:
//! each gets every character with the instant it arrived and is woken when it asked to be.
//! Several units share the port as they would share a line ([`MultiDrop`]): HPRs with ids 0,
//! 1, ... (SLEEP/WAKE), Powermax units at node addresses in order; two answering at once
//! collide on the port. The port takes the units' framing (19200 8E1 for a Powermax, 8N1 for
//! an HPR). Lines on stdin control them while they run ([`Control`], `@N ` first for unit N):
//! a fault raised and cleared, a unit switched off and on, its cable cut and mended.

use std::io::Write;
use std::sync::mpsc::Receiver;

use plasma_protocol::powermax::FaultCode;
use plasma_protocol::time::Instant;
use plasma_sim::hpr::Hpr;
use plasma_sim::multidrop::{MultiDrop, units_for_one_line};
use plasma_sim::powermax::Powermax;
use plasma_sim::sync::Cartridge;
use plasma_sim::{Family, Model, SimOptions, SimulatedUnit};

use crate::decode::{FrameStream, lines};
use crate::framer::{Framer, Piece};
use crate::realtime::{Arrival, Clock, wait};
use crate::serial::{Port, Rx, SerialError, describe};
use crate::sim::parse_fault;

/// How `pbtool unit` runs.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitOptions {
    /// The models on the line, unit 1 first.
    pub models: Vec<Model>,
    /// A fault on unit 1 from the start.
    pub fault: Option<u16>,
    /// Simulator options (seed; unit 1's Modbus address or HPR id, the others' follow).
    pub sim: SimOptions,
    /// Each frame, decoded, on the log.
    pub log: bool,
}

/// A control line on stdin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// `FAULT CODE`: raise a fault (as `--fault`).
    Fault(u16),
    /// `CLEAR`: clear the active fault.
    Clear,
    /// `POWER OFF` / `POWER ON`.
    Power(bool),
    /// `SILENT` (the cable cut: the unit neither hears nor answers, and keeps its state) /
    /// `ANSWER` (mended).
    Silent(bool),
    /// `CARTRIDGE UID` (SYNC): another cartridge of the same kind, with this UID (up to 16
    /// characters) and fresh counters, is put on the torch.
    Cartridge([u8; 16]),
}

impl Control {
    /// Parses a control line for `model`; `Err` says what is accepted.
    pub fn parse(model: Model, line: &str) -> Result<Option<Control>, String> {
        let words: Vec<String> = line
            .split_ascii_whitespace()
            .map(str::to_ascii_uppercase)
            .collect();
        let words: Vec<&str> = words.iter().map(String::as_str).collect();
        Ok(Some(match words.as_slice() {
            [] => return Ok(None),
            ["FAULT", code] => Control::Fault(parse_fault(model, code)?),
            ["CLEAR"] => Control::Clear,
            ["POWER", "OFF"] => Control::Power(false),
            ["POWER", "ON"] => Control::Power(true),
            ["SILENT"] => Control::Silent(true),
            ["ANSWER"] => Control::Silent(false),
            ["CARTRIDGE", uid] if model.family() == Family::Sync => {
                Control::Cartridge(parse_uid(uid)?)
            }
            _ => {
                let cartridge = if model.family() == Family::Sync {
                    ", CARTRIDGE UID"
                } else {
                    ""
                };
                return Err(format!(
                    "unknown control {line:?}: FAULT CODE, CLEAR, POWER OFF|ON, SILENT, \
                     ANSWER{cartridge} (@N first for unit N)"
                ));
            }
        }))
    }

    /// Parses a control line for one of `models` (unit 1 first): `@N ` first addresses unit
    /// N, without it unit 1. Returns the unit's index (0 = unit 1) and the control.
    pub fn parse_addressed(
        models: &[Model],
        line: &str,
    ) -> Result<Option<(usize, Control)>, String> {
        let line = line.trim_start();
        let (index, rest) = match line.strip_prefix('@') {
            Some(addressed) => {
                let (number, rest) = addressed
                    .split_once(|c: char| c.is_ascii_whitespace())
                    .unwrap_or((addressed, ""));
                match number.parse::<usize>() {
                    Ok(n @ 1..) if n <= models.len() => (n - 1, rest),
                    _ => {
                        return Err(format!(
                            "no unit @{number}: units are @1 to @{}",
                            models.len()
                        ));
                    }
                }
            }
            None => (0, line),
        };
        let Some(&model) = models.get(index) else {
            return Err("no unit on the line".to_string());
        };
        Ok(Control::parse(model, rest)?.map(|control| (index, control)))
    }
}

/// A cartridge UID as typed: 1 to 16 ASCII letters and digits (the SYNC manual's UIDs are
/// 16 hex digits, 000_dd931256418ae627.txt line 1460), zero padded.
fn parse_uid(text: &str) -> Result<[u8; 16], String> {
    if text.is_empty() || text.len() > 16 || !text.bytes().all(|b| b.is_ascii_alphanumeric()) {
        return Err(format!(
            "cartridge UID {text:?}: 1 to 16 letters and digits"
        ));
    }
    let mut uid = [0u8; 16];
    uid[..text.len()].copy_from_slice(text.as_bytes());
    Ok(uid)
}

/// The units on their port.
pub struct UnitServer {
    line: MultiDrop,
    port: Port,
    clock: Clock,
    log: bool,
    framer: Framer,
    stream: FrameStream,
    collisions: u64,
}

/// The units `options` name, on one line, or why they cannot share one.
pub fn build_line(options: &UnitOptions) -> Result<MultiDrop, plasma_sim::multidrop::LineError> {
    MultiDrop::new(units_for_one_line(&options.models, &options.sim)?)
}

impl UnitServer {
    /// Serves `line`; `port` is its writing handle (a reader thread has the other). The port
    /// is set to the units' framing.
    pub fn new(
        options: &UnitOptions,
        mut line: MultiDrop,
        mut port: Port,
        clock: Clock,
    ) -> Result<Self, SerialError> {
        port.set_config(line.port())?;
        if let (Some(code), Some(unit)) = (options.fault, line.unit_mut(0)) {
            unit.inject_fault(clock.now(), code);
        }
        Ok(UnitServer {
            line,
            port,
            clock,
            log: options.log,
            framer: Framer::default(),
            stream: FrameStream::default(),
            collisions: 0,
        })
    }

    /// A line saying what is served where.
    pub fn banner(&self) -> String {
        let units: Vec<&dyn SimulatedUnit> = (0..self.line.len())
            .filter_map(|i| self.line.unit(i))
            .collect();
        let what = match units.as_slice() {
            [one] => format!("a simulated {}", one.model()),
            several => format!(
                "{} simulated units on one line: {}",
                several.len(),
                several
                    .iter()
                    .enumerate()
                    .map(|(i, u)| format!("@{} {} ({})", i + 1, u.model(), address_of(*u)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        format!(
            "pbtool unit: {what} on {} at {}",
            self.port.name(),
            describe(self.line.port())
        )
    }

    /// Serves until a port fails (that error) or `inbox` closes. Stdin lines are controls;
    /// what happens is logged on `log`.
    pub fn run(
        &mut self,
        inbox: &Receiver<Arrival>,
        log: &mut dyn Write,
    ) -> Result<(), SerialError> {
        let models: Vec<Model> = (0..self.line.len())
            .filter_map(|i| self.line.unit(i).map(|u| u.model()))
            .collect();
        loop {
            let arrival = wait(inbox, &self.clock, self.line.next_wakeup());
            let now = self.clock.now();
            match arrival {
                Some(Arrival::Serial { rx, .. }) => self.received(now, &rx, log),
                Some(Arrival::Line(line)) => {
                    let text = String::from_utf8_lossy(&line);
                    match Control::parse_addressed(&models, &text) {
                        Ok(Some((unit, control))) => self.control(now, unit, control, log),
                        Ok(None) => {}
                        Err(e) => {
                            let _ = writeln!(log, "pbtool unit: {e}");
                        }
                    }
                }
                Some(Arrival::Failed(e)) => return Err(e),
                Some(Arrival::EndOfInput) | None => {}
            }
            self.line.advance(now);
            let bytes = self.line.poll_transmit(now);
            for sent in self.line.take_transmissions() {
                let direction = match self.line.len() {
                    1 => "tx".to_string(),
                    _ => format!("tx @{}", sent.unit + 1),
                };
                self.log_frame(
                    sent.at,
                    &direction,
                    &String::from_utf8_lossy(&sent.bytes),
                    log,
                );
            }
            if let Some(bytes) = bytes {
                self.port.write_all(&bytes)?;
            }
            let collisions = self.line.collisions();
            if collisions > self.collisions {
                let _ = writeln!(
                    log,
                    "pbtool unit: collision: two units answering at once ({collisions} \
                     characters garbled so far)"
                );
                self.collisions = collisions;
            }
        }
    }

    fn received(&mut self, now: Instant, rx: &[Rx], log: &mut dyn Write) {
        if !(0..self.line.len()).any(|i| self.line.is_connected(i)) {
            // Every unit's cable cut: nothing on this side of the cut hears it.
            return;
        }
        let mut pieces = Vec::new();
        for &item in rx {
            match item {
                Rx::Byte(b) => self.line.receive(now, b),
                Rx::Error => self.line.receive_error(now),
            }
            if self.log {
                self.framer.push(now, item, &mut pieces);
            }
        }
        for piece in pieces {
            self.log_piece(&piece, log);
        }
    }

    fn control(&mut self, now: Instant, index: usize, control: Control, log: &mut dyn Write) {
        if let Control::Silent(silent) = control {
            self.line.set_connected(index, !silent);
        }
        let Some(unit) = self.line.unit_mut(index) else {
            return;
        };
        let said = match control {
            Control::Fault(code) => {
                unit.inject_fault(now, code);
                // As the unit's display and the manuals show it: 0-50-0, HPR error 44.
                if unit.model().family() == Family::Hpr {
                    format!("error {code} raised")
                } else {
                    format!("fault {} raised", FaultCode(code))
                }
            }
            Control::Clear => {
                unit.clear_fault(now);
                "fault cleared".to_string()
            }
            Control::Power(on) => {
                if on {
                    unit.power_on(now);
                } else {
                    unit.power_off(now);
                }
                format!("power {}", if on { "on" } else { "off" })
            }
            Control::Silent(silent) => if silent { "silent" } else { "answering" }.to_string(),
            Control::Cartridge(uid) => {
                let model = unit.model();
                match unit.as_any_mut().downcast_mut::<Powermax>() {
                    Some(pm) => {
                        let kind = pm
                            .cartridge()
                            .map_or(Cartridge::default_for(model).kind, |c| c.kind);
                        let mut cartridge = Cartridge::new(kind, "");
                        cartridge.uid = uid;
                        pm.install_cartridge(now, cartridge);
                        let typed = String::from_utf8_lossy(&uid);
                        format!("cartridge {} installed", typed.trim_end_matches('\0'))
                    }
                    None => "not a Powermax: no cartridge".to_string(),
                }
            }
        };
        let who = match self.line.len() {
            1 => String::new(),
            _ => format!("@{} ", index + 1),
        };
        let _ = writeln!(log, "pbtool unit: {who}{said}");
    }

    fn log_piece(&mut self, piece: &Piece, log: &mut dyn Write) {
        if piece.complete && piece.flagged == 0 {
            self.log_frame(piece.at, "rx", &piece.text, log);
        } else {
            let _ = writeln!(
                log,
                "[{:>10.3}] rx {:?} (not a whole frame{})",
                self.clock.seconds(piece.at),
                piece.text,
                match piece.flagged {
                    0 => String::new(),
                    n => format!(", {n} characters with parity or framing errors"),
                }
            );
        }
    }

    fn log_frame(&mut self, at: Instant, direction: &str, text: &str, log: &mut dyn Write) {
        if !self.log {
            return;
        }
        let report = self.stream.decode(text);
        let _ = writeln!(
            log,
            "[{:>10.3}] {direction} {}",
            self.clock.seconds(at),
            text.trim_end()
        );
        for line in lines(&report) {
            let _ = writeln!(log, "             {line}");
        }
        let _ = log.flush();
    }
}

/// How the unit is addressed on its line: `id 1` (HPR), `node 7` (Powermax).
fn address_of(unit: &dyn SimulatedUnit) -> String {
    if let Some(hpr) = unit.as_any().downcast_ref::<Hpr>() {
        return format!("id {}", hpr.config().id);
    }
    match unit
        .as_any()
        .downcast_ref::<Powermax>()
        .and_then(Powermax::address)
    {
        Some(node) => format!("node {node}"),
        None => "node from the first request".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_lines_are_read() {
        let pm = Model::Sync65;
        assert_eq!(
            Control::parse(pm, "fault 0-50-0"),
            Ok(Some(Control::Fault(500)))
        );
        assert_eq!(Control::parse(pm, " clear \n"), Ok(Some(Control::Clear)));
        assert_eq!(
            Control::parse(pm, "POWER off"),
            Ok(Some(Control::Power(false)))
        );
        assert_eq!(
            Control::parse(pm, "silent"),
            Ok(Some(Control::Silent(true)))
        );
        assert_eq!(
            Control::parse(pm, "answer"),
            Ok(Some(Control::Silent(false)))
        );
        assert_eq!(Control::parse(pm, "\n"), Ok(None));
        assert_eq!(
            Control::parse(pm, "cartridge E00401D0036FB25E"),
            Ok(Some(Control::Cartridge(*b"E00401D0036FB25E")))
        );
        assert!(Control::parse(pm, "cartridge E00401D0036FB25E0").is_err());
        assert!(Control::parse(Model::Pm65, "cartridge A1").is_err());
        assert!(Control::parse(pm, "explode").is_err());
        assert!(Control::parse(Model::Hpr260, "fault 0-50-0").is_err());
    }

    #[test]
    fn a_control_goes_to_unit_1_unless_at_n_names_another() {
        let line = [Model::Hpr260, Model::Hpr400];
        assert_eq!(
            Control::parse_addressed(&line, "FAULT 44"),
            Ok(Some((0, Control::Fault(44))))
        );
        assert_eq!(
            Control::parse_addressed(&line, "@2 power off"),
            Ok(Some((1, Control::Power(false))))
        );
        assert_eq!(
            Control::parse_addressed(&line, " @1 silent"),
            Ok(Some((0, Control::Silent(true))))
        );
        assert_eq!(Control::parse_addressed(&line, "@2"), Ok(None));
        for bad in ["@3 clear", "@0 clear", "@x clear"] {
            let e = Control::parse_addressed(&line, bad).unwrap_err();
            assert!(e.contains("units are @1 to @2"), "{e}");
        }
        assert!(Control::parse_addressed(&[Model::Sync65], "@2 clear").is_err());
        assert!(Control::parse_addressed(&line, "@2 explode").is_err());
    }
}
