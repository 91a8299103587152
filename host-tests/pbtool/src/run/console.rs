//! `pbtool run`'s console: the CNC protocol on stdin/stdout, paced as `pbtool sim` paces it.

use std::collections::VecDeque;
use std::io::Write;
use std::sync::mpsc::Receiver;

use host_tests::harness::CncItem;
use plasma_protocol::time::{Duration, Instant};

use super::{LineBridge, Stop};
use crate::realtime::{Arrival, wait};
use crate::sim::{Pacer, REPLY_TIMEOUT, settled};

/// The longest wait for the link (and the unit's limits) before the first console command:
/// detection tries every framing in turn on a real line.
pub const SETTLE_TIMEOUT: Duration = Duration::from_secs(15);
/// After the link is up: one more status cycle, so faults and settings are known.
const SETTLE_EXTRA: Duration = Duration::from_millis(250);
/// After the end of input and the last reply: what may still come (a second reply line).
const LINGER: Duration = Duration::from_millis(100);

/// Whether commands may go out yet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Settle {
    /// Waiting for the link; `Some` once it is up, with the instant to start at.
    Waiting(Option<Instant>),
    /// Commands go out.
    Ready,
}

/// The console's state between two arrivals.
struct Console<'a> {
    bridge: &'a mut LineBridge,
    out: &'a mut dyn Write,
    err: &'a mut dyn Write,
    started: Instant,
    settle: Settle,
    printed: usize,
    lines: VecDeque<Vec<u8>>,
    pacer: Pacer,
    /// The reply count to reach, and until when.
    waiting: Option<(usize, Instant)>,
    ended: bool,
    /// Since when there is nothing left to do after the end of input.
    done_since: Option<Instant>,
}

/// How the console treats commands typed before the link is up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstCommand {
    /// A person at a terminal: answered at once, as the board answers (`link=DOWN` while
    /// detection runs), never a silent wait of up to [`SETTLE_TIMEOUT`].
    AtOnce,
    /// A script on a pipe: the first command waits for the link (or [`SETTLE_TIMEOUT`]), so
    /// that its replies describe the unit, as `pbtool sim`'s do.
    AfterDetection,
}

/// The CNC protocol on a console: `inbox` brings the PS port's characters and stdin's lines.
/// One command at a time, every line the bridge writes printed as it comes (ACK/NAK as
/// `<ACK>`/`<NAK>`); the first command as `first` says; returns after the last reply once
/// input has ended (at once when input ends with nothing sent, detection or not).
pub fn run_console(
    bridge: &mut LineBridge,
    inbox: &Receiver<Arrival>,
    first: FirstCommand,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<(), Stop> {
    let started = bridge.now();
    writeln!(
        err,
        "pbtool run: detecting the power supply (every framing in turn, up to {} s); {}",
        SETTLE_TIMEOUT.as_millis() / 1000,
        match first {
            FirstCommand::AtOnce => "commands are answered meanwhile (link=DOWN until it answers)",
            FirstCommand::AfterDetection => "the first command waits for it",
        }
    )?;
    // What the bridge wrote before (the reply to setting its clock) is not the console's.
    let printed = bridge.cnc_records().len();
    let mut console = Console {
        bridge,
        out,
        err,
        started,
        settle: match first {
            FirstCommand::AtOnce => Settle::Ready,
            FirstCommand::AfterDetection => Settle::Waiting(None),
        },
        printed,
        lines: VecDeque::new(),
        pacer: Pacer::default(),
        waiting: None,
        ended: false,
        done_since: None,
    };
    loop {
        let arrival = wait(inbox, &console.bridge.clock, console.wake());
        let now = console.bridge.now();
        console.take(now, arrival)?;
        console.bridge.service(now)?;
        console.bridge.write_flash(now, false)?;
        console.print()?;
        console.settle(now)?;
        console.check_reply(now)?;
        console.send_lines(now)?;
        if console.finished(now) {
            return Ok(());
        }
    }
}

impl Console<'_> {
    /// The earliest instant something is due.
    fn wake(&self) -> Option<Instant> {
        let settle = match self.settle {
            Settle::Waiting(at) => at,
            Settle::Ready => None,
        };
        [
            self.bridge.wake(),
            settle,
            self.waiting.map(|w| w.1),
            self.done_since.map(|t| t + LINGER),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn take(&mut self, now: Instant, arrival: Option<Arrival>) -> Result<(), Stop> {
        match arrival {
            Some(Arrival::Serial { rx, .. }) => self.bridge.ps_rx(now, &rx),
            Some(Arrival::Line(line)) => self.lines.push_back(line),
            Some(Arrival::EndOfInput) => self.ended = true,
            Some(Arrival::Failed(e)) => return Err(e.into()),
            None => {}
        }
        Ok(())
    }

    /// Ready once the link is up and a status cycle later, or with a warning after
    /// [`SETTLE_TIMEOUT`].
    fn settle(&mut self, now: Instant) -> Result<(), Stop> {
        let Settle::Waiting(at) = self.settle else {
            return Ok(());
        };
        match at {
            None if settled(self.bridge.bridge()) => {
                self.settle = Settle::Waiting(Some(now + SETTLE_EXTRA));
            }
            Some(at) if now >= at => self.settle = Settle::Ready,
            _ if now.saturating_since(self.started) >= SETTLE_TIMEOUT => {
                writeln!(
                    self.err,
                    "pbtool run: no power supply answered on the PS port within {} s; commands \
                     go on without it",
                    SETTLE_TIMEOUT.as_millis() / 1000
                )?;
                self.settle = Settle::Ready;
            }
            _ => {}
        }
        Ok(())
    }

    /// The awaited reply came, or its time is up (and the console says so).
    fn check_reply(&mut self, now: Instant) -> Result<(), Stop> {
        let Some((count, deadline)) = self.waiting else {
            return Ok(());
        };
        if self.bridge.reply_count() >= count {
            self.waiting = None;
        } else if now >= deadline {
            writeln!(
                self.err,
                "pbtool run: no reply within {} s",
                REPLY_TIMEOUT.as_millis() / 1000
            )?;
            self.waiting = None;
        }
        Ok(())
    }

    /// The next lines, one at a time, while no reply is awaited.
    fn send_lines(&mut self, now: Instant) -> Result<(), Stop> {
        while self.settle == Settle::Ready && self.waiting.is_none() {
            let Some(line) = self.lines.pop_front() else {
                break;
            };
            let before = self.bridge.reply_count();
            let awaits = self.pacer.awaits_reply(&line);
            self.bridge.cnc_rx(now, &line);
            self.bridge.service(now)?;
            self.print()?;
            if awaits {
                self.waiting = Some((before + 1, now + REPLY_TIMEOUT));
            }
        }
        Ok(())
    }

    /// True once input has ended, everything is answered and [`LINGER`] has passed.
    fn finished(&mut self, now: Instant) -> bool {
        // With no line left, detection has nothing to hold back: Ctrl-D never waits for it.
        let idle = self.ended && self.lines.is_empty() && self.waiting.is_none();
        match (idle, self.done_since) {
            (false, _) => self.done_since = None,
            (true, None) => self.done_since = Some(now),
            (true, Some(since)) => return now >= since + LINGER,
        }
        false
    }

    /// What the bridge wrote since the last call.
    fn print(&mut self) -> std::io::Result<()> {
        let records = self.bridge.cnc_records();
        for record in &records[self.printed..] {
            match &record.item {
                CncItem::Ack => write!(self.out, "<ACK>")?,
                CncItem::Nak => write!(self.out, "<NAK>")?,
                CncItem::Line(line) => writeln!(self.out, "{line}")?,
            }
        }
        self.printed = records.len();
        self.out.flush()
    }
}
