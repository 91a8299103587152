//! `pbtool sniff`: a passive tap on a live line. One port hears a 2-wire bus (both
//! directions); two ports hear the two pairs of a 4-wire line. Every frame is printed with
//! its time, decoded as `pbtool decode` does; a reply is paired with its request (and the time
//! it took), and a request that got none, a bad checksum, characters with parity or framing
//! errors, a pause inside a frame and noise between frames are flagged. Nothing is ever
//! written to a port.

use std::io::{self, Write};
use std::sync::mpsc::Receiver;

use plasma_protocol::time::{Duration, Instant};
use serde_json::json;

use crate::decode::{FrameReport, FrameStream, Kind, lines, to_json};
use crate::framer::{Framer, Piece};
use crate::realtime::{Arrival, Clock, wait};
use crate::serial::SerialError;

/// A frame that stops arriving for this long is reported as incomplete (Modbus ASCII allows
/// up to a second between characters).
const FRAME_TIMEOUT: Duration = Duration::from_secs(1);
/// A pause inside a frame longer than this is flagged (USB adapters deliver in chunks a few
/// milliseconds apart; more is the sender's pause).
const GAP_FLAG: Duration = Duration::from_millis(50);
/// With two ports (a 4-wire line), how long a frame waits before it is reported, so that a
/// frame the other port's reader had earlier, but handed over later, still comes first: the
/// two directions are read by two threads (and, on a real line, two USB adapters).
const REORDER: Duration = Duration::from_millis(30);

/// How a sniff ended.
#[derive(Debug)]
pub enum Stop {
    /// A port failed.
    Port(SerialError),
    /// Writing the report failed.
    Output(io::Error),
}

/// The request waiting for its reply.
#[derive(Debug, Clone, Copy)]
struct Waiting {
    number: usize,
    at: Instant,
}

/// The tap's state: one framer per port, one decoder for the line.
pub struct Sniffer {
    names: Vec<String>,
    framers: Vec<Framer>,
    stream: FrameStream,
    waiting: Option<Waiting>,
    count: usize,
    json: bool,
    clock: Clock,
    /// Frames not reported yet: (when framed, port, frame); reported in the order of their
    /// first character once [`REORDER`] has passed (at once with one port).
    held: Vec<(Instant, usize, Piece)>,
}

impl Sniffer {
    /// A tap on the ports `names` (their reader threads tag arrivals with the index).
    pub fn new(names: Vec<String>, json: bool, clock: Clock) -> Sniffer {
        Sniffer {
            framers: names.iter().map(|_| Framer::default()).collect(),
            names,
            stream: FrameStream::default(),
            waiting: None,
            count: 0,
            json,
            clock,
            held: Vec::new(),
        }
    }

    fn reorder(&self) -> Duration {
        if self.names.len() > 1 {
            REORDER
        } else {
            Duration::ZERO
        }
    }

    /// Reports the held frames that have waited long enough (all of them with `all`), in the
    /// order of their first character.
    fn release(&mut self, now: Instant, all: bool, out: &mut dyn Write) -> io::Result<()> {
        let reorder = self.reorder();
        let (mut due, kept): (Vec<_>, Vec<_>) = std::mem::take(&mut self.held)
            .into_iter()
            .partition(|(framed, _, _)| all || now >= *framed + reorder);
        self.held = kept;
        due.sort_by_key(|(_, _, piece)| piece.at);
        for (_, port, piece) in due {
            self.report(port, &piece, out)?;
        }
        Ok(())
    }

    /// Reports what passes until a port fails.
    pub fn run(&mut self, inbox: &Receiver<Arrival>, out: &mut dyn Write) -> Stop {
        loop {
            let wake = self
                .framers
                .iter()
                .filter_map(Framer::pending_since)
                .map(|t| t + FRAME_TIMEOUT)
                .chain(
                    self.held
                        .iter()
                        .map(|(framed, _, _)| *framed + self.reorder()),
                )
                .min();
            let arrival = wait(inbox, &self.clock, wake);
            let now = self.clock.now();
            let mut pieces = Vec::new();
            match arrival {
                Some(Arrival::Serial { port, rx, read_at }) => {
                    let read_at = self.clock.at(read_at);
                    if let Some(framer) = self.framers.get_mut(port) {
                        for item in rx {
                            for piece in framer.push_one(read_at, item) {
                                pieces.push((port, piece));
                            }
                        }
                    }
                }
                Some(Arrival::Failed(e)) => {
                    // What was framed before the port failed is still reported.
                    return match self.release(now, true, out) {
                        Ok(()) => Stop::Port(e),
                        Err(e) => Stop::Output(e),
                    };
                }
                _ => {}
            }
            for (port, framer) in self.framers.iter_mut().enumerate() {
                if framer
                    .pending_since()
                    .is_some_and(|t| now >= t + FRAME_TIMEOUT)
                {
                    pieces.extend(framer.flush().map(|p| (port, p)));
                }
            }
            self.held
                .extend(pieces.into_iter().map(|(port, piece)| (now, port, piece)));
            if let Err(e) = self.release(now, false, out) {
                return Stop::Output(e);
            }
        }
    }

    fn report(&mut self, port: usize, piece: &Piece, out: &mut dyn Write) -> io::Result<()> {
        self.count += 1;
        let number = self.count;
        let mut flags = Vec::new();
        let mut reply_to = None;
        let report = if piece.complete {
            let report = self.stream.decode(&piece.text);
            self.pair(number, piece.at, &report, &mut flags, &mut reply_to);
            if report.checksum.is_some_and(|c| !c.ok()) {
                flags.push("bad checksum".to_string());
            }
            Some(report)
        } else {
            flags.push(if piece.text.starts_with([':', '>']) {
                "incomplete frame".to_string()
            } else {
                "noise between frames".to_string()
            });
            None
        };
        if piece.flagged > 0 {
            flags.push(format!(
                "{} character(s) with parity or framing errors",
                piece.flagged
            ));
        }
        if piece.longest_gap > GAP_FLAG {
            flags.push(format!(
                "a pause of {} ms inside the frame",
                piece.longest_gap.as_millis()
            ));
        }
        let seconds = self.clock.seconds(piece.at);
        let port_name = &self.names[port];
        if self.json {
            let object = json!({
                "n": number,
                "t_s": seconds,
                "port": port_name,
                "text": piece.text,
                "complete": piece.complete,
                "reply_to": reply_to.map(|(n, _)| n),
                "reply_after_ms": reply_to.map(|(_, ms)| ms),
                "flags": flags,
                "decoded": report.as_ref().map(to_json),
            });
            writeln!(out, "{object}")?;
        } else {
            writeln!(
                out,
                "#{number:<5} {seconds:>10.3} s  {port_name}  {}",
                piece.text.trim_end().escape_debug()
            )?;
            if let Some(report) = &report {
                for line in lines(report) {
                    writeln!(out, "        {line}")?;
                }
            }
            if let Some((n, ms)) = reply_to {
                writeln!(out, "        reply to #{n} after {ms:.1} ms")?;
            }
            for flag in &flags {
                writeln!(out, "        ! {flag}")?;
            }
        }
        out.flush()
    }

    /// Pairs a reply with the request before it; flags a request left without one.
    fn pair(
        &mut self,
        number: usize,
        at: Instant,
        report: &FrameReport,
        flags: &mut Vec<String>,
        reply_to: &mut Option<(usize, f64)>,
    ) {
        match report.kind {
            Some(Kind::Request) => {
                if let Some(earlier) = self.waiting.replace(Waiting { number, at }) {
                    flags.push(format!("request #{} got no reply", earlier.number));
                }
            }
            Some(Kind::Reply) => {
                if let Some(request) = self.waiting.take()
                    && report.answers_request == Some(true)
                {
                    let ms = at.saturating_since(request.at).as_micros() as f64 / 1000.0;
                    *reply_to = Some((request.number, ms));
                }
            }
            None => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::serial::Rx;
    use std::sync::mpsc;

    fn serial(port: usize, text: &str, read_at: std::time::Instant) -> Arrival {
        Arrival::Serial {
            port,
            rx: text.bytes().map(Rx::Byte).collect(),
            read_at,
        }
    }

    #[test]
    fn a_reply_handed_over_after_the_next_request_is_still_paired_with_its_own() {
        // A 4-wire tap: the reply's reader had it 2 ms before the next request was read, but
        // its thread ran late and handed it over after.
        let clock = Clock::start();
        let t0 = std::time::Instant::now();
        let ms = std::time::Duration::from_millis;
        let (inbox, arrivals) = mpsc::channel();
        inbox.send(serial(0, ":012B0E0401C1\r\n", t0)).unwrap();
        inbox
            .send(serial(0, ":01043010000BB0\r\n", t0 + ms(5)))
            .unwrap();
        inbox
            .send(serial(
                1,
                ":012B0E0481000101010630383133333504\r\n",
                t0 + ms(3),
            ))
            .unwrap();
        inbox
            .send(Arrival::Failed(SerialError::Missing("tap".to_string())))
            .unwrap();
        let mut sniffer = Sniffer::new(vec!["req".to_string(), "rep".to_string()], false, clock);
        let mut out = Vec::new();
        assert!(matches!(sniffer.run(&arrivals, &mut out), Stop::Port(_)));
        let text = String::from_utf8(out).unwrap();
        let order: Vec<&str> = text.lines().filter(|l| l.starts_with('#')).collect();
        assert_eq!(order.len(), 3, "{text}");
        assert!(order[0].contains("req  :012B0E0401C1"), "{text}");
        assert!(order[1].contains("rep  :012B0E0481"), "{text}");
        assert!(order[2].contains("req  :01043010000BB0"), "{text}");
        assert!(text.contains("reply to #1 after 3.0 ms"), "{text}");
        assert!(!text.contains("got no reply"), "{text}");
    }
}
