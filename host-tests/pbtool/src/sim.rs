//! `pbtool sim`: the bridge's real behaviour against a simulated unit, with the CNC text
//! protocol on stdin/stdout.
//!
//! Several units share one simulated line as the bridge's `CONFIG units` names them
//! ([`World::with_bridge_on_line`]): `@N` addresses unit N on the console, `@N TORCH ON`
//! drives its TORCH_ON.
//!
//! The [`World`] of the scenario tests ([`World::with_bridge`]) runs either in real time
//! (advanced by the wall clock; a person types `SET PROCESS CUT 45 AUTO` and `STATUS` and sees
//! what a CNC would see) or in virtual time (`--fast`: no sleeps, the same output on every
//! run, for scripts and tests).
//!
//! Like a well-behaved CNC the console sends one command line at a time and the next only
//! when the reply has come (so a piped script never fills the bridge's queue), and it sends
//! the first command only once the link is up and the unit's limits are read (at most
//! [`SETTLE_TIMEOUT`]), so piped commands get meaningful replies. Every line the bridge
//! writes goes to stdout as it arrives (ACK/NAK as `<ACK>` / `<NAK>`); blank lines get no
//! reply and are not waited for. With `verbose`, every change of a discrete output (START,
//! ARC_OK, READY, FAULT and the HPR pass-throughs) is logged on stderr with its reason.

use std::io::{self, BufRead, Write};
use std::str::FromStr;
use std::sync::mpsc::Receiver;

use plasma_firmware::bridge::Bridge;
use plasma_firmware::link::LineUnit;
use plasma_firmware::settings::Settings;
use plasma_protocol::cnc::phoenix::{EOT, ETX, SOH, STX};
use plasma_protocol::powermax::FaultCode;
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};

use host_tests::harness::{BridgeEndpoint, CncItem, SharedLineError, World, WorldOptions};

use crate::realtime::{Arrival, Clock, receive_lines, wait};
use crate::serial::{Port, Rx, SerialError};
use plasma_sim::multidrop::MultiDrop;
use plasma_sim::{Family, Model, SimOptions};

/// The longest wait for the link (and the unit's limits) before the first command.
pub const SETTLE_TIMEOUT: Duration = Duration::from_secs(5);
/// After the link is up: one more status cycle, so faults and settings are known.
const SETTLE_EXTRA: Duration = Duration::from_millis(250);
/// The longest wait for one reply; beyond it the console moves on (and says so).
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(10);
/// Virtual time: how long the world runs on after the end of input.
const LINGER: Duration = Duration::from_millis(100);
/// Real time: the longest sleep between two looks at stdin and the clock.
const TICK: std::time::Duration = std::time::Duration::from_millis(10);

/// How `pbtool sim` runs.
#[derive(Debug, Clone, PartialEq)]
pub struct ConsoleOptions {
    /// The simulated units on the line, in order (HPR ids from 0, Powermax nodes from 1 when
    /// there are several).
    pub models: Vec<Model>,
    /// A fault the (first) unit has from the start (Powermax decimal code, HPR error number).
    pub fault: Option<u16>,
    /// Event lines on from the start.
    pub events: bool,
    /// Seed of the simulator and the line.
    pub seed: u64,
    /// Log the discrete outputs' transitions on stderr.
    pub verbose: bool,
    /// The CNC port's framing the bridge starts with (`cnc_baud`, `cnc_parity`,
    /// `cnc_stop_bits`; `CONFIG` may change it while it runs).
    pub cnc_framing: PortConfig,
}

/// A `--fault` argument for `model`: Powermax `X-YY-Z` (`0-50-0`) or decimal (`500`); HPR
/// error number (`44` or `044`).
pub fn parse_fault(model: Model, text: &str) -> Result<u16, String> {
    let text = text.trim();
    let code = if text.contains('-') {
        if model.family() == Family::Hpr {
            return Err(format!(
                "fault {text}: an HPR/MaxPro200 error is a number (e.g. 44), not X-YY-Z"
            ));
        }
        FaultCode::from_str(text)
            .map(|c| c.0)
            .map_err(|_| format!("fault {text}: expected X-YY-Z (e.g. 0-50-0) or a number"))?
    } else {
        text.parse::<u16>()
            .map_err(|_| format!("fault {text}: expected X-YY-Z (e.g. 0-50-0) or a number"))?
    };
    if code == 0 {
        return Err("fault 0 means no fault".to_string());
    }
    Ok(code)
}

/// The simulated installation and what has been printed of it.
pub struct Console {
    world: World<BridgeEndpoint>,
    verbose: bool,
    printed: usize,
    /// The CNC bytes written before the console took over (not the CNC's to see).
    before_console: usize,
    /// Per unit: its output transitions printed so far.
    transitions_printed: Vec<usize>,
    pacer: Pacer,
}

impl Console {
    /// The bridge (default settings, events as asked) against fresh simulated units; refused
    /// (with the reason) when they cannot share a line.
    pub fn new(options: ConsoleOptions) -> Result<Self, SharedLineError> {
        let world_options = WorldOptions {
            seed: options.seed,
            sim: SimOptions {
                seed: options.seed,
                ..SimOptions::default()
            },
            ..WorldOptions::default()
        };
        let mut settings = Settings {
            events: options.events,
            ..Settings::default()
        };
        settings.cnc.framing = options.cnc_framing;
        let mut world = match options.models.as_slice() {
            [one] => World::with_bridge(*one, world_options, settings),
            several => World::with_bridge_on_line(several, world_options, settings)?,
        };
        if let Some(code) = options.fault {
            world.inject_fault(code);
        }
        Ok(Console {
            world,
            verbose: options.verbose,
            printed: 0,
            before_console: 0,
            transitions_printed: Vec::new(),
            pacer: Pacer::default(),
        })
    }

    /// What the bridge drives, for a banner: `a simulated HPR260`, or `2 simulated units on
    /// one line: @1 HPR260 (id 0), @2 HPR130 (id 1)` (the addresses as `CONFIG units` names
    /// them).
    pub fn describe_units(&self) -> String {
        let named = self.world.bridge().settings().units;
        let Some(line) = self.world.unit_ref().as_any().downcast_ref::<MultiDrop>() else {
            return format!("a simulated {}", self.world.unit_ref().model());
        };
        let units: Vec<String> = named
            .as_slice()
            .iter()
            .enumerate()
            .map(|(index, unit)| {
                let model = line
                    .unit(index)
                    .map_or(String::new(), |u| format!("{} ", u.model()));
                let address = match unit {
                    LineUnit::Hpr { id } => format!("id {id}"),
                    LineUnit::Powermax { node } => format!("node {node}"),
                    LineUnit::MaxPro200 => "id 0".to_string(),
                };
                format!("@{} {model}({address})", index + 1)
            })
            .collect();
        format!(
            "{} simulated units on one line: {}",
            units.len(),
            units.join(", ")
        )
    }

    /// The world (for tests).
    pub fn world(&self) -> &World<BridgeEndpoint> {
        &self.world
    }

    /// True once the link is up and what the first commands need is known.
    /// Boots the bridge from a flash image (`--flash FILE`, see
    /// [`BridgeEndpoint::flash_image`]): a power cycle of the bridge's board, so its settings
    /// and history are the image's and the history records the reset.
    pub fn boot_from_flash(&mut self, image: &[u8]) -> Result<(), String> {
        self.world.endpoint_mut().load_flash_image(image)?;
        self.world.power_cycle_bridge();
        self.skip_output();
        Ok(())
    }

    /// Sets the bridge's wall clock to `unix_seconds` (as `CLOCK` from a CNC would; its
    /// reply is not printed): `pbtool run` is the bridge, and its clock is the PC's.
    pub fn set_clock(&mut self, unix_seconds: u32) -> String {
        let reply = self
            .world
            .cnc_line(&crate::history::clock_command(unix_seconds));
        self.skip_output();
        reply
    }

    /// What the bridge wrote so far is not the console's to print or send.
    fn skip_output(&mut self) {
        self.printed = self.world.cnc_output().len();
        self.before_console = self.world.cnc_bytes().len();
    }

    /// The bridge's flash now, for the file of `--flash`.
    pub fn flash_image(&mut self) -> Vec<u8> {
        self.world.endpoint_mut().flash_image()
    }

    fn settled(world: &World<BridgeEndpoint>) -> bool {
        settled(world.bridge())
    }

    /// Virtual time: run the commands of `input` one by one until its end.
    pub fn run_virtual(
        &mut self,
        input: &mut dyn BufRead,
        out: &mut dyn Write,
        err: &mut dyn Write,
    ) -> io::Result<()> {
        match self.world.run_until(Self::settled, SETTLE_TIMEOUT) {
            Ok(_) => self.world.run_for(SETTLE_EXTRA),
            Err(_) => no_unit_warning(err)?,
        }
        self.flush(out, err)?;
        while let Some(line) = read_line(input)? {
            if let Some(replies) = self.send(&line)
                && self.world.wait_cnc_replies(replies, REPLY_TIMEOUT).is_err()
            {
                writeln!(
                    err,
                    "pbtool sim: no reply within {} s",
                    REPLY_TIMEOUT.as_millis() / 1000
                )?;
            }
            self.flush(out, err)?;
        }
        // What a last line may still bring (a cut text line's second reply, a message the
        // input left open is abandoned after 50 ms).
        self.world.run_for(LINGER);
        self.flush(out, err)
    }

    /// Real time: lines from `input` (a reader thread's channel; closed at end of input) are
    /// sent as the bridge becomes free; returns after the last reply once input has ended.
    pub fn run_realtime(
        &mut self,
        input: Receiver<Vec<u8>>,
        out: &mut dyn Write,
        err: &mut dyn Write,
    ) -> io::Result<()> {
        let wall = std::time::Instant::now();
        let clock = |world: &World<BridgeEndpoint>| {
            let elapsed = u64::try_from(wall.elapsed().as_micros()).unwrap_or(u64::MAX);
            Instant::from_micros(elapsed).saturating_since(world.now())
        };
        let mut settle_until: Option<Instant> = None;
        let mut ready = false;
        let mut waiting: Option<(usize, Instant)> = None;
        let mut lines: std::collections::VecDeque<Vec<u8>> = std::collections::VecDeque::new();
        let mut ended = false;
        loop {
            let due = clock(&self.world);
            self.world.run_for(due);
            self.flush(out, err)?;
            let now = self.world.now();

            if !ready {
                if settle_until.is_none() && Self::settled(&self.world) {
                    settle_until = Some(now + SETTLE_EXTRA);
                }
                if settle_until.is_some_and(|t| now >= t) {
                    ready = true;
                } else if now >= Instant::ZERO + SETTLE_TIMEOUT {
                    no_unit_warning(err)?;
                    ready = true;
                }
            }
            if let Some((count, deadline)) = waiting {
                if self.world.cnc_reply_count() >= count {
                    waiting = None;
                } else if now >= deadline {
                    writeln!(
                        err,
                        "pbtool sim: no reply within {} s",
                        REPLY_TIMEOUT.as_millis() / 1000
                    )?;
                    waiting = None;
                }
            }
            while ready && waiting.is_none() {
                let Some(line) = lines.pop_front() else { break };
                waiting = self.send(&line).map(|count| (count, now + REPLY_TIMEOUT));
                self.flush(out, err)?;
            }
            if ended && lines.is_empty() && waiting.is_none() {
                return Ok(());
            }

            let sleep = self
                .world
                .next_wakeup()
                .map(|t| std::time::Duration::from_micros(t.saturating_since(now).as_micros()))
                .unwrap_or(TICK)
                .min(TICK);
            if ended {
                std::thread::sleep(sleep);
                continue;
            }
            ended = !receive_lines(&input, sleep, &mut lines);
        }
    }

    /// The framing the bridge wants on its CNC port.
    pub fn cnc_port_config(&self) -> PortConfig {
        self.world.bridge().cnc_port_config()
    }

    /// Real time, the CNC on a serial port: `inbox` brings the port's characters (from its
    /// reader thread), `cnc` is its writing handle; the bytes pass as they are. Runs until the
    /// port fails.
    pub fn run_cnc_port(&mut self, inbox: &Receiver<Arrival>, cnc: &mut Port) -> SerialError {
        let clock = Clock::start();
        let mut sent = self.before_console;
        loop {
            let arrival = wait(inbox, &clock, self.world.next_wakeup());
            let due = clock.now().saturating_since(self.world.now());
            self.world.run_for(due);
            match arrival {
                Some(Arrival::Serial { rx, .. }) => self.world.cnc_send(&Rx::cnc_bytes(&rx)),
                Some(Arrival::Failed(e)) => return e,
                _ => {}
            }
            let raw = self.world.cnc_bytes();
            if raw.len() > sent {
                let fresh = raw[sent..].to_vec();
                sent = raw.len();
                if let Err(e) = cnc.write_all(&fresh) {
                    return e;
                }
            }
            // After `CONFIG cnc_baud ...` (its reply already written at the old framing).
            if let Err(e) = cnc.set_config(self.cnc_port_config()) {
                return e;
            }
        }
    }

    /// Hand one input line (with its terminator) to the bridge. Returns the reply count to
    /// wait for, or `None` when no reply is due: a blank line, or a line that leaves a Phoenix
    /// message open (its CR LF is inside the frame; the reply comes once the frame ends).
    fn send(&mut self, line: &[u8]) -> Option<usize> {
        let awaits_reply = self.pacer.awaits_reply(line);
        let before = self.world.cnc_reply_count();
        self.world.cnc_send(line);
        awaits_reply.then_some(before + 1)
    }

    /// Print what the CNC received since the last call (stdout) and, verbose, the output
    /// transitions (stderr).
    fn flush(&mut self, out: &mut dyn Write, err: &mut dyn Write) -> io::Result<()> {
        if self.verbose {
            let units = self.world.pin_sets();
            self.transitions_printed.resize(units, 0);
            for (unit, printed) in self.transitions_printed.iter_mut().enumerate() {
                let transitions = self.world.transitions_of(unit);
                let which = match units {
                    1 => String::new(),
                    _ => format!(" @{}", unit + 1),
                };
                for t in &transitions[*printed..] {
                    writeln!(err, "[io{which}] {t}")?;
                }
                *printed = transitions.len();
            }
        }
        let records = self.world.cnc_output();
        for record in &records[self.printed..] {
            match &record.item {
                CncItem::Ack => write!(out, "<ACK>")?,
                CncItem::Nak => write!(out, "<NAK>")?,
                CncItem::Line(line) => writeln!(out, "{line}")?,
            }
        }
        self.printed = records.len();
        out.flush()?;
        err.flush()
    }
}

/// True once every unit's link is up and what the first commands need is known (a
/// Powermax's limits, an HPR's state): a console sends its first command then.
pub fn settled(bridge: &Bridge) -> bool {
    (0..bridge.unit_count()).all(|unit| {
        let status = bridge.status_of(unit);
        status.link_up && (status.limits.is_some() || status.hpr.state.is_some())
    })
}

/// Which console lines a reply is due for, so that a console sends the next line only once
/// it has come, as a well-behaved CNC does.
#[derive(Debug, Default, Clone, Copy)]
pub struct Pacer {
    /// A Phoenix message has begun (SOH/STX) and not yet ended (ETX/EOT).
    frame_open: bool,
}

impl Pacer {
    /// True when `line` (with its terminator), sent now, earns a reply: not a blank line,
    /// nor a line that leaves a Phoenix message open (its CR LF is inside the frame; the
    /// reply comes once the frame ends).
    pub fn awaits_reply(&mut self, line: &[u8]) -> bool {
        let mut content = false;
        for &b in line {
            match b {
                SOH | STX => {
                    self.frame_open = true;
                    content = true;
                }
                ETX | EOT => self.frame_open = false,
                b' ' | b'\t' | b'\r' | b'\n' => {}
                _ => content = true,
            }
        }
        content && !self.frame_open
    }
}

fn no_unit_warning(err: &mut dyn Write) -> io::Result<()> {
    writeln!(
        err,
        "pbtool sim: the simulated unit did not answer within {} s; commands go on without it",
        SETTLE_TIMEOUT.as_millis() / 1000
    )
}

/// One input line with its terminator; a last line without one gets LF (end of input ends
/// the line). `None` at end of input.
pub fn read_line(input: &mut dyn BufRead) -> io::Result<Option<Vec<u8>>> {
    let mut line = Vec::new();
    if input.read_until(b'\n', &mut line)? == 0 {
        return Ok(None);
    }
    if line.last() != Some(&b'\n') {
        line.push(b'\n');
    }
    Ok(Some(line))
}
