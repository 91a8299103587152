//! `pbtool unit`: one of the simulated units ([`plasma_sim`]) served on a serial port in real
//! time, answering any master: the bridge on a PC, a real board, CNC software.
//!
//! The unit is the same sans-IO simulator the scenario tests use, driven by the wall clock: it
//! gets each character with the instant it arrived and is woken when it asked to be. The port
//! takes the unit's framing (19200 8E1 for a Powermax, 8N1 for an HPR). Lines on stdin control
//! it while it runs ([`Control`]): a fault raised and cleared, the unit switched off and on,
//! the cable cut and mended.

use std::io::Write;
use std::sync::mpsc::Receiver;

use plasma_protocol::powermax::FaultCode;
use plasma_protocol::time::Instant;
use plasma_sim::{Family, Model, SimOptions, SimulatedUnit};

use crate::decode::{FrameStream, lines};
use crate::framer::{Framer, Piece};
use crate::realtime::{Arrival, Clock, wait};
use crate::serial::{Port, Rx, SerialError, describe};
use crate::sim::parse_fault;

/// How `pbtool unit` runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitOptions {
    /// The model.
    pub model: Model,
    /// A fault from the start.
    pub fault: Option<u16>,
    /// Simulator options (seed, Modbus address, HPR id).
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
            _ => {
                return Err(format!(
                    "unknown control {line:?}: FAULT CODE, CLEAR, POWER OFF|ON, SILENT, ANSWER"
                ));
            }
        }))
    }
}

/// The unit on its port.
pub struct UnitServer {
    unit: Box<dyn SimulatedUnit>,
    port: Port,
    clock: Clock,
    silent: bool,
    log: bool,
    framer: Framer,
    stream: FrameStream,
}

impl UnitServer {
    /// Builds the unit; `port` is its writing handle (a reader thread has the other). The
    /// port is set to the unit's framing.
    pub fn new(options: &UnitOptions, mut port: Port, clock: Clock) -> Result<Self, SerialError> {
        let mut unit = options.model.build(&options.sim);
        port.set_config(unit.port())?;
        if let Some(code) = options.fault {
            unit.inject_fault(clock.now(), code);
        }
        Ok(UnitServer {
            unit,
            port,
            clock,
            silent: false,
            log: options.log,
            framer: Framer::default(),
            stream: FrameStream::default(),
        })
    }

    /// A line saying what is served where.
    pub fn banner(&self) -> String {
        format!(
            "pbtool unit: a simulated {} on {} at {}",
            self.unit.model(),
            self.port.name(),
            describe(self.unit.port())
        )
    }

    /// Serves until a port fails (that error) or `inbox` closes. Stdin lines are controls;
    /// what happens is logged on `log`.
    pub fn run(
        &mut self,
        inbox: &Receiver<Arrival>,
        log: &mut dyn Write,
    ) -> Result<(), SerialError> {
        loop {
            let arrival = wait(inbox, &self.clock, self.unit.next_wakeup());
            let now = self.clock.now();
            match arrival {
                Some(Arrival::Serial { rx, .. }) => self.received(now, &rx, log),
                Some(Arrival::Line(line)) => {
                    let text = String::from_utf8_lossy(&line);
                    match Control::parse(self.unit.model(), &text) {
                        Ok(Some(control)) => self.control(now, control, log),
                        Ok(None) => {}
                        Err(e) => {
                            let _ = writeln!(log, "pbtool unit: {e}");
                        }
                    }
                }
                Some(Arrival::Failed(e)) => return Err(e),
                Some(Arrival::EndOfInput) | None => {}
            }
            self.unit.advance(now);
            if let Some(bytes) = self.unit.poll_transmit(now)
                && !self.silent
            {
                self.port.write_all(&bytes)?;
                self.log_frame(now, "tx", &String::from_utf8_lossy(&bytes), log);
            }
        }
    }

    fn received(&mut self, now: Instant, rx: &[Rx], log: &mut dyn Write) {
        if self.silent {
            return;
        }
        let mut pieces = Vec::new();
        for &item in rx {
            match item {
                Rx::Byte(b) => self.unit.receive(now, b),
                Rx::Error => self.unit.receive_error(now),
            }
            if self.log {
                self.framer.push(now, item, &mut pieces);
            }
        }
        for piece in pieces {
            self.log_piece(&piece, log);
        }
    }

    fn control(&mut self, now: Instant, control: Control, log: &mut dyn Write) {
        let said = match control {
            Control::Fault(code) => {
                self.unit.inject_fault(now, code);
                // As the unit's display and the manuals show it: 0-50-0, HPR error 44.
                if self.unit.model().family() == Family::Hpr {
                    format!("error {code} raised")
                } else {
                    format!("fault {} raised", FaultCode(code))
                }
            }
            Control::Clear => {
                self.unit.clear_fault(now);
                "fault cleared".to_string()
            }
            Control::Power(on) => {
                if on {
                    self.unit.power_on(now);
                } else {
                    self.unit.power_off(now);
                }
                format!("power {}", if on { "on" } else { "off" })
            }
            Control::Silent(silent) => {
                self.silent = silent;
                if silent { "silent" } else { "answering" }.to_string()
            }
        };
        let _ = writeln!(log, "pbtool unit: {said}");
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
        assert!(Control::parse(pm, "explode").is_err());
        assert!(Control::parse(Model::Hpr260, "fault 0-50-0").is_err());
    }
}
