//! The simulated power supply on the other end of the emulated board's PS serial port, in
//! real time.
//!
//! QEMU passes bytes only (no baud rate, parity or stop bits on the socket) and as fast as the
//! guest writes them. A thread here puts them on the same baud-accurate [`Line`] the scenario
//! harness uses, hands them to one of the same simulators ([`plasma_sim`]) with real
//! timestamps, and writes the unit's replies back to the socket character by character at the
//! moments the line delivers them (so a reply takes its real wire time at the unit's baud).
//! The line's master end takes the framing the firmware set in USART1's registers (read
//! through qtest before each frame) when [`Framing::Registers`] is asked for, so a framing
//! mismatch garbles the traffic as it would on a wire; characters the line flags with a
//! parity or framing error are dropped (QEMU cannot hand a flagged character to the guest).
//!
//! The test controls the unit while it runs ([`SimPort::with_unit`]): raise and clear faults,
//! power it off and on, or cut the cable ([`SimPort::set_connected`]) so it neither hears nor
//! answers while it keeps its state.
//!
//! Several units can share the line ([`SimPortOptions::more_units`]: a [`MultiDrop`], ids 0,
//! 1, ... as `pbtool sim` numbers them); each unit's Start follows its own unit set's START pin
//! and its Motion drives its own set's MOTION ([`SimPort::with_unit_at`] reaches each).

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixStream;
use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};

use plasma_firmware::io::Output;

use super::error::{Error, Result};
use super::pins::{UnitSet, unit_output_active};
use super::qtest::{Edge, Qtest};
use super::usart::Usart;
use crate::harness::{Direction, TraceFrame, WireTrace};
use plasma_sim::line::{End, Line, Wiring};
use plasma_sim::multidrop::{MultiDrop, units_for_one_line};
use plasma_sim::{Model, SimOptions, SimulatedUnit};

/// The longest the thread sleeps between two looks at the socket and the test's commands.
const MAX_SLEEP: Duration = Duration::from_millis(5);
/// The shortest wait worth a timed read (the timeout cannot be zero).
const MIN_SLEEP: Duration = Duration::from_micros(50);
/// A pause in the firmware's transmission longer than this starts a new frame (whose framing
/// is read again from the USART registers).
const FRAME_GAP: Duration = Duration::from_millis(2);
/// How long a write to the socket may block (QEMU stops reading while the guest does not).
const WRITE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(2);

/// Where the line's master end (the firmware's UART) takes its framing from.
#[derive(Clone)]
pub enum Framing {
    /// Always the unit's: no mismatch is modelled.
    Matched,
    /// From USART1's CR1/CR2 (parity, stop bits) and BRR (baud), read through qtest at the
    /// start of every frame the firmware sends.
    Registers {
        /// The board's qtest session.
        qtest: Arc<Qtest>,
        /// USART1's kernel clock, to turn BRR into a baud rate; `None` takes the unit's baud.
        clock_hz: Option<u32>,
    },
}

/// How to run the simulated unit.
pub struct SimPortOptions {
    /// The model.
    pub model: Model,
    /// Simulator options (seed, addresses).
    pub sim: SimOptions,
    /// Further units on the same line after the first (`model`), in order: HPRs take the ids
    /// after `sim.hpr_id`, Powermax units the nodes after `sim.modbus_address`.
    pub more_units: Vec<Model>,
    /// Where the firmware's framing comes from.
    pub framing: Framing,
    /// Called on the port's thread with the unit's index on the line whenever that unit's
    /// Motion output changes (the harness wires it to its unit set's MOTION input).
    pub on_motion: Option<Box<dyn FnMut(usize, bool) + Send>>,
    /// Edges of the board's outputs (qtest's stream): each unit set's START drives its unit's
    /// Start input.
    pub output_edges: Option<Receiver<Edge>>,
    /// Seed of the line model.
    pub seed: u64,
}

impl SimPortOptions {
    /// `model` with default options, matched framing and no Motion wiring.
    pub fn new(model: Model) -> SimPortOptions {
        SimPortOptions {
            model,
            sim: SimOptions::default(),
            more_units: Vec::new(),
            framing: Framing::Matched,
            on_motion: None,
            output_edges: None,
            seed: 1,
        }
    }
}

/// What the port's thread publishes.
#[derive(Debug, Default)]
struct Published {
    trace: WireTrace,
    dropped: u64,
    /// Set when the thread stopped on an error (the socket failed).
    stopped: Option<String>,
}

type Job = Box<dyn FnOnce(&mut Station) + Send>;

/// A simulated unit answering on the board's PS socket. Stops when dropped or when QEMU closes
/// the socket.
pub struct SimPort {
    jobs: Option<Sender<Job>>,
    published: Arc<Mutex<Published>>,
    epoch: std::time::Instant,
    thread: Option<JoinHandle<()>>,
    model: Model,
}

impl SimPort {
    /// Starts the unit on `stream` (time zero is now).
    pub fn start(stream: UnixStream, options: SimPortOptions) -> Result<SimPort> {
        let epoch = std::time::Instant::now();
        let published = Arc::new(Mutex::new(Published::default()));
        let (jobs, inbox) = mpsc::channel::<Job>();
        stream
            .set_write_timeout(Some(WRITE_TIMEOUT))
            .map_err(|e| Error::io("PS socket", e))?;
        let model = options.model;
        let models: Vec<Model> = std::iter::once(model)
            .chain(options.more_units.iter().copied())
            .collect();
        // Checked here, where the error can be returned (the units are built on the thread).
        units_for_one_line(&models, &options.sim)
            .map_err(|e| Error::Protocol(format!("the simulated line: {e}")))?;
        let for_thread = Arc::clone(&published);
        let thread = std::thread::Builder::new()
            .name(format!("sim-{model}"))
            .spawn(move || {
                // The unit is built on its own thread: simulators need not be Send.
                let unit = match build_line(&models, &options.sim) {
                    Ok(unit) => unit,
                    Err(e) => {
                        lock(&for_thread).stopped = Some(e);
                        return;
                    }
                };
                let port = unit.port();
                let mut station = Station {
                    line: Line::new(port, port, Wiring::FourWire, options.seed),
                    unit,
                    framing: options.framing,
                    on_motion: options.on_motion,
                    output_edges: options.output_edges,
                    motion: vec![false; models.len()],
                    last_rx: None,
                    epoch,
                    published: for_thread,
                };
                let result = station.run(stream, &inbox);
                if let Err(e) = result {
                    lock(&station.published).stopped = Some(e.to_string());
                }
            })
            .map_err(|e| Error::io("simulator thread", e))?;
        Ok(SimPort {
            jobs: Some(jobs),
            published,
            epoch,
            thread: Some(thread),
            model,
        })
    }

    /// The simulated model.
    pub fn model(&self) -> Model {
        self.model
    }

    /// The simulator's clock now.
    pub fn now(&self) -> Instant {
        instant_since(self.epoch)
    }

    /// Runs `act` on unit `index` of the line (0 = the first; on its thread, between two
    /// steps) and returns its result; `None` for no such unit.
    pub fn with_unit_at<R: Send + 'static>(
        &self,
        index: usize,
        act: impl FnOnce(&mut dyn SimulatedUnit, Instant) -> R + Send + 'static,
    ) -> Result<Option<R>> {
        self.with_station(move |station, now| station.line_unit(index).map(|u| act(u, now)))
    }

    /// Raises a fault on unit `index` of the line (as [`SimPort::inject_fault`]).
    pub fn inject_fault_at(&self, index: usize, code: u16) -> Result<()> {
        self.with_unit_at(index, move |unit, now| unit.inject_fault(now, code))?
            .ok_or_else(|| Error::Protocol(format!("no unit {index} on the simulated line")))
    }

    /// Runs `act` on the unit (on its thread, between two steps) and returns its result.
    pub fn with_unit<R: Send + 'static>(
        &self,
        act: impl FnOnce(&mut dyn SimulatedUnit, Instant) -> R + Send + 'static,
    ) -> Result<R> {
        self.with_station(move |station, now| act(&mut *station.unit, now))
    }

    fn with_station<R: Send + 'static>(
        &self,
        act: impl FnOnce(&mut Station, Instant) -> R + Send + 'static,
    ) -> Result<R> {
        let (reply, result) = mpsc::channel();
        let job: Job = Box::new(move |station: &mut Station| {
            let now = instant_since(station.epoch);
            let _ = reply.send(act(station, now));
        });
        let stopped = || {
            let why = lock(&self.published).stopped.clone();
            Error::Exited(format!(
                "the simulated unit has stopped ({})",
                why.as_deref().unwrap_or("the PS socket closed")
            ))
        };
        self.jobs
            .as_ref()
            .and_then(|jobs| jobs.send(job).ok())
            .ok_or_else(stopped)?;
        result
            .recv_timeout(std::time::Duration::from_secs(10))
            .map_err(|_| stopped())
    }

    /// Raises a fault (Powermax decimal code such as 500 for 0-50-0, HPR error number).
    pub fn inject_fault(&self, code: u16) -> Result<()> {
        self.with_unit(move |unit, now| unit.inject_fault(now, code))
    }

    /// Clears the unit's fault.
    pub fn clear_fault(&self) -> Result<()> {
        self.with_unit(|unit, now| unit.clear_fault(now))
    }

    /// Switches the unit off (it forgets its volatile settings; neither hears nor sends).
    pub fn power_off(&self) -> Result<()> {
        self.with_station(|station, now| {
            station.unit.power_off(now);
            station.line.set_unit_powered(now, false);
        })
    }

    /// Switches the unit on.
    pub fn power_on(&self) -> Result<()> {
        self.with_station(|station, now| {
            station.line.set_unit_powered(now, true);
            station.unit.power_on(now);
        })
    }

    /// Connects or cuts the cable: while cut the unit hears nothing and nothing it sends
    /// arrives, but it stays on and keeps its state.
    pub fn set_connected(&self, connected: bool) -> Result<()> {
        self.with_station(move |station, now| station.line.set_unit_powered(now, connected))
    }

    /// Drives the unit's Start input (the board's START output).
    pub fn set_start(&self, on: bool) -> Result<()> {
        self.with_unit(move |unit, now| unit.set_start(now, on))
    }

    /// The unit's Motion output.
    pub fn motion(&self) -> Result<bool> {
        self.with_unit(|unit, _| unit.motion())
    }

    /// What went over the line so far (frames as sent, with their line timing).
    pub fn trace(&self) -> WireTrace {
        lock(&self.published).trace.clone()
    }

    /// Characters from the firmware that the line flagged (dropped), so far.
    pub fn dropped(&self) -> u64 {
        lock(&self.published).dropped
    }

    /// Why the port's thread stopped, if it did on an error.
    pub fn stopped(&self) -> Option<String> {
        lock(&self.published).stopped.clone()
    }
}

impl Drop for SimPort {
    fn drop(&mut self) {
        // Closing the job channel ends the thread at its next look (at most MAX_SLEEP).
        self.jobs = None;
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

fn instant_since(epoch: std::time::Instant) -> Instant {
    Instant::from_micros(u64::try_from(epoch.elapsed().as_micros()).unwrap_or(u64::MAX))
}

fn std_duration(d: Duration) -> std::time::Duration {
    std::time::Duration::from_micros(d.as_micros())
}

/// The units of `models` on one line: one unit as it is, more in a [`MultiDrop`].
fn build_line(
    models: &[Model],
    options: &SimOptions,
) -> std::result::Result<Box<dyn SimulatedUnit>, String> {
    let mut units = units_for_one_line(models, options).map_err(|e| e.to_string())?;
    if units.len() == 1
        && let Some(unit) = units.pop()
    {
        return Ok(unit);
    }
    Ok(Box::new(MultiDrop::new(units).map_err(|e| e.to_string())?))
}

/// The unit, its line and the socket's bookkeeping, owned by the port's thread.
struct Station {
    /// The unit, or a [`MultiDrop`] of several.
    unit: Box<dyn SimulatedUnit>,
    line: Line,
    framing: Framing,
    on_motion: Option<Box<dyn FnMut(usize, bool) + Send>>,
    output_edges: Option<Receiver<Edge>>,
    /// Each unit's Motion as last passed on.
    motion: Vec<bool>,
    /// When the firmware's last character arrived.
    last_rx: Option<Instant>,
    epoch: std::time::Instant,
    published: Arc<Mutex<Published>>,
}

impl Station {
    fn now(&self) -> Instant {
        instant_since(self.epoch)
    }

    /// Unit `index` of the line.
    fn line_unit(&mut self, index: usize) -> Option<&mut (dyn SimulatedUnit + 'static)> {
        if self.unit.as_any().is::<MultiDrop>() {
            let line = self.unit.as_any_mut().downcast_mut::<MultiDrop>()?;
            return line.unit_mut(index);
        }
        (index == 0).then_some(&mut *self.unit)
    }

    /// The loop: jobs, the socket, the unit and the line, until the socket or the job channel
    /// closes.
    fn run(&mut self, mut stream: UnixStream, jobs: &Receiver<Job>) -> Result<()> {
        let mut buf = [0u8; 256];
        loop {
            loop {
                match jobs.try_recv() {
                    Ok(job) => job(self),
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => return Ok(()),
                }
            }
            self.take_output_edges();
            self.step(&mut stream)?;
            let now = self.now();
            let wait = [self.line.next_delivery(), self.unit.next_wakeup()]
                .into_iter()
                .flatten()
                .min()
                .map_or(MAX_SLEEP, |t| t.saturating_since(now))
                .min(MAX_SLEEP)
                .max(MIN_SLEEP);
            stream
                .set_read_timeout(Some(std_duration(wait)))
                .map_err(|e| Error::io("PS socket", e))?;
            match stream.read(&mut buf) {
                Ok(0) => return Ok(()),
                Ok(n) => {
                    let now = self.now();
                    self.heard_from_firmware(now, &buf[..n]);
                }
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {}
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(Error::io("reading the PS socket", e)),
            }
        }
    }

    /// Each unit set's START edges from the board to its unit's Start input.
    fn take_output_edges(&mut self) {
        let Some(edges) = &self.output_edges else {
            return;
        };
        let changes: Vec<(usize, bool)> = edges
            .try_iter()
            .filter_map(|e| {
                let set = UnitSet::ALL
                    .into_iter()
                    .find(|set| set.output(Output::Start).pin == e.pin)?;
                let on = unit_output_active(set.index(), Output::Start, e.high);
                Some((set.index(), on))
            })
            .collect();
        for (index, on) in changes {
            let now = self.now();
            if let Some(unit) = self.line_unit(index) {
                unit.set_start(now, on);
            }
        }
    }

    /// Characters the firmware wrote: onto the line from the master end.
    fn heard_from_firmware(&mut self, now: Instant, bytes: &[u8]) {
        let new_frame = self
            .last_rx
            .is_none_or(|t| now.saturating_since(t) > FRAME_GAP);
        self.last_rx = Some(now);
        if new_frame && let Some(port) = self.firmware_port() {
            self.line.set_port(End::Master, port);
        }
        let start = now.max(self.line.busy_until(End::Master));
        let port = self.line.port(End::Master);
        let end = self.line.transmit(End::Master, now, bytes);
        self.record(Direction::ToUnit, start, end, port, bytes);
    }

    /// The framing the firmware has set, if it is to be modelled and can be read.
    fn firmware_port(&self) -> Option<PortConfig> {
        let Framing::Registers { qtest, clock_hz } = &self.framing else {
            return None;
        };
        Usart::PS
            .framing(qtest, *clock_hz, self.unit.port().baud)
            .ok()
            .flatten()
    }

    /// Everything due now: the unit hears, runs and answers; its characters go to the socket.
    fn step(&mut self, stream: &mut UnixStream) -> Result<()> {
        let now = self.now();
        self.unit.advance(now);
        self.take_noise();
        for b in self.line.receive(End::Unit, now) {
            match b.error {
                None => self.unit.receive(b.at, b.byte),
                Some(_) => self.unit.receive_error(b.at),
            }
        }
        if let Some(reply) = self.unit.poll_transmit(now) {
            let start = now.max(self.line.busy_until(End::Unit));
            let port = self.line.port(End::Unit);
            let end = self.line.transmit(End::Unit, now, &reply);
            self.record(Direction::ToBridge, start, end, port, &reply);
        }
        self.take_noise();
        let mut out = Vec::new();
        for b in self.line.receive(End::Master, now) {
            match b.error {
                None => out.push(b.byte),
                Some(_) => lock(&self.published).dropped += 1,
            }
        }
        if !out.is_empty() {
            stream
                .write_all(&out)
                .map_err(|e| Error::io("writing the PS socket", e))?;
        }
        for index in 0..self.motion.len() {
            let Some(motion) = self.line_unit(index).map(|u| u.motion()) else {
                continue;
            };
            if self.motion.get(index) != Some(&motion) {
                if let Some(seen) = self.motion.get_mut(index) {
                    *seen = motion;
                }
                if let Some(on_motion) = &mut self.on_motion {
                    on_motion(index, motion);
                }
            }
        }
        Ok(())
    }

    fn take_noise(&mut self) {
        for (start, length) in self.unit.take_noise_bursts() {
            self.line.add_noise_burst(start, length);
        }
    }

    /// Adds a transmission to the trace, extending the last frame when it continues it: the
    /// firmware's writes reach the socket in pieces whenever QEMU runs, any time apart on a
    /// loaded host, so pieces are joined until the frame's end (`\n` or `<`) or a piece that
    /// starts a frame (`:` or `>`, after a frame the firmware cut short).
    fn record(
        &self,
        direction: Direction,
        start: Instant,
        end: Instant,
        port: PortConfig,
        bytes: &[u8],
    ) {
        let mut published = lock(&self.published);
        if let Some(last) = published.trace.last_mut()
            && last.direction == direction
            && !matches!(bytes.first(), Some(b':' | b'>'))
            && !last.bytes.ends_with(b"\n")
            && !last.bytes.ends_with(b"<")
        {
            last.bytes.extend_from_slice(bytes);
            last.end = end;
            return;
        }
        published.trace.push(TraceFrame {
            direction,
            start,
            end,
            port,
            bytes: bytes.to_vec(),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::pins::unit_output_pin;
    use std::io::Read;

    fn read_until(stream: &mut UnixStream, end: &[u8]) -> (Vec<u8>, std::time::Duration) {
        let began = std::time::Instant::now();
        stream
            .set_read_timeout(Some(std::time::Duration::from_secs(5)))
            .unwrap();
        let mut got = Vec::new();
        let mut byte = [0u8];
        while !got.ends_with(end) {
            stream.read_exact(&mut byte).unwrap();
            got.push(byte[0]);
        }
        (got, began.elapsed())
    }

    #[test]
    fn a_request_on_the_socket_gets_the_units_reply_at_its_baud() {
        let (mut firmware, theirs) = UnixStream::pair().unwrap();
        let port = SimPort::start(theirs, SimPortOptions::new(Model::Sync65)).unwrap();
        firmware.write_all(b":010430000001CA\r\n").unwrap();
        let (reply, took) = read_until(&mut firmware, b"\r\n");
        assert_eq!(reply, b":0104020400F5\r\n");
        // 17 + 15 characters of 572.9 us on the wire and 3 ms in the unit: 21.3 ms at least.
        assert!(took >= std::time::Duration::from_micros(21_000), "{took:?}");
        let trace = port.trace();
        let frames: Vec<String> = trace.frames().iter().map(|f| f.text()).collect();
        assert_eq!(frames, [":010430000001CA\\r\\n", ":0104020400F5\\r\\n"]);
        assert!(trace.frames()[1].start >= trace.frames()[0].end);
    }

    #[test]
    fn a_request_in_pieces_is_one_frame() {
        let (mut firmware, theirs) = UnixStream::pair().unwrap();
        let port = SimPort::start(theirs, SimPortOptions::new(Model::Sync65)).unwrap();
        // A loaded host: the pieces come any time apart (here 5 ms and 120 ms).
        for (piece, after_ms) in [(&b":0104300"[..], 5), (b"00001CA", 120), (b"\r\n", 0)] {
            firmware.write_all(piece).unwrap();
            std::thread::sleep(std::time::Duration::from_millis(after_ms));
        }
        let (reply, _) = read_until(&mut firmware, b"\r\n");
        assert_eq!(reply, b":0104020400F5\r\n");
        assert_eq!(port.trace().frames()[0].bytes, b":010430000001CA\r\n");
    }

    #[test]
    fn a_cut_cable_silences_the_unit_until_it_is_connected_again() {
        let (mut firmware, theirs) = UnixStream::pair().unwrap();
        let port = SimPort::start(theirs, SimPortOptions::new(Model::Sync65)).unwrap();
        port.set_connected(false).unwrap();
        firmware.write_all(b":010430000001CA\r\n").unwrap();
        firmware
            .set_read_timeout(Some(std::time::Duration::from_millis(100)))
            .unwrap();
        let mut byte = [0u8];
        assert!(firmware.read(&mut byte).is_err(), "the unit answered");
        port.set_connected(true).unwrap();
        firmware.write_all(b":010430000001CA\r\n").unwrap();
        let (reply, _) = read_until(&mut firmware, b"\r\n");
        assert_eq!(reply, b":0104020400F5\r\n");
    }

    #[test]
    fn an_injected_fault_is_reported_and_cleared() {
        let (mut firmware, theirs) = UnixStream::pair().unwrap();
        let port = SimPort::start(theirs, SimPortOptions::new(Model::Sync65)).unwrap();
        port.inject_fault(500).unwrap();
        assert_eq!(port.with_unit(|u, _| u.active_fault()).unwrap(), 500);
        // The active fault register (0x301A): 500 = 0x01F4.
        firmware.write_all(b":0104301A0001B0\r\n").unwrap();
        let (reply, _) = read_until(&mut firmware, b"\r\n");
        assert_eq!(reply, b":01040201F404\r\n");
        port.clear_fault().unwrap();
        firmware.write_all(b":0104301A0001B0\r\n").unwrap();
        let (reply, _) = read_until(&mut firmware, b"\r\n");
        assert_eq!(reply, b":0104020000F9\r\n");
    }

    #[test]
    fn motion_follows_start_and_reaches_the_wiring() {
        let (_firmware, theirs) = UnixStream::pair().unwrap();
        let (tx, rx) = mpsc::channel();
        let options = SimPortOptions {
            on_motion: Some(Box::new(move |_, on| tx.send(on).unwrap())),
            ..SimPortOptions::new(Model::Sync65)
        };
        let port = SimPort::start(theirs, options).unwrap();
        port.set_start(true).unwrap();
        let timeout = std::time::Duration::from_secs(5);
        assert_eq!(rx.recv_timeout(timeout), Ok(true));
        assert!(port.motion().unwrap());
        port.set_start(false).unwrap();
        assert_eq!(rx.recv_timeout(timeout), Ok(false));
    }

    #[test]
    fn start_edges_reach_the_units_start_input() {
        let (_firmware, theirs) = UnixStream::pair().unwrap();
        let (edges, output_edges) = mpsc::channel();
        let options = SimPortOptions {
            output_edges: Some(output_edges),
            ..SimPortOptions::new(Model::Sync65)
        };
        let port = SimPort::start(theirs, options).unwrap();
        let edge = |pin, high| Edge {
            at: std::time::Instant::now(),
            pin,
            high,
        };
        // Another pin of the port changes nothing, nor another unit set's START.
        edges
            .send(edge(unit_output_pin(0, Output::Ready), true))
            .unwrap();
        edges
            .send(edge(unit_output_pin(1, Output::Start), true))
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(300));
        assert!(!port.motion().unwrap());
        edges
            .send(edge(unit_output_pin(0, Output::Start), true))
            .unwrap();
        let began = std::time::Instant::now();
        while !port.motion().unwrap() {
            assert!(
                began.elapsed() < std::time::Duration::from_secs(5),
                "no arc"
            );
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }

    #[test]
    fn each_unit_sets_start_drives_its_own_unit_on_a_shared_line() {
        let (_firmware, theirs) = UnixStream::pair().unwrap();
        let (edges, output_edges) = mpsc::channel();
        let (tx, rx) = mpsc::channel();
        // Two Powermax units at nodes 1 and 2 (an HPR would purge for seconds before a start).
        let options = SimPortOptions {
            sim: SimOptions {
                modbus_address: 1,
                ..SimOptions::default()
            },
            more_units: vec![Model::Sync65],
            output_edges: Some(output_edges),
            on_motion: Some(Box::new(move |unit, on| tx.send((unit, on)).unwrap())),
            ..SimPortOptions::new(Model::Sync65)
        };
        let port = SimPort::start(theirs, options).unwrap();
        let motion_of = |index| port.with_unit_at(index, |u, _| u.motion()).unwrap();
        assert_eq!(port.with_unit_at(2, |_, _| ()).unwrap(), None, "two units");
        let edge = |pin, high| Edge {
            at: std::time::Instant::now(),
            pin,
            high,
        };
        edges
            .send(edge(unit_output_pin(1, Output::Start), true))
            .unwrap();
        let timeout = std::time::Duration::from_secs(5);
        assert_eq!(
            rx.recv_timeout(timeout),
            Ok((1, true)),
            "the second unit's arc"
        );
        assert_eq!((motion_of(0), motion_of(1)), (Some(false), Some(true)));
        port.inject_fault_at(0, 44).unwrap();
        assert_eq!(
            port.with_unit_at(0, |u, _| u.active_fault()).unwrap(),
            Some(44)
        );
        assert_eq!(
            port.with_unit_at(1, |u, _| u.active_fault()).unwrap(),
            Some(0)
        );
    }

    #[test]
    fn a_line_units_cannot_share_is_refused() {
        let (_firmware, theirs) = UnixStream::pair().unwrap();
        let options = SimPortOptions {
            more_units: vec![Model::Sync65],
            ..SimPortOptions::new(Model::Hpr260)
        };
        assert!(matches!(
            SimPort::start(theirs, options),
            Err(Error::Protocol(_))
        ));
    }

    #[test]
    fn the_port_stops_when_the_socket_closes() {
        let (firmware, theirs) = UnixStream::pair().unwrap();
        let port = SimPort::start(theirs, SimPortOptions::new(Model::Hpr260)).unwrap();
        drop(firmware);
        let began = std::time::Instant::now();
        while port.inject_fault(44).is_ok() {
            assert!(began.elapsed() < std::time::Duration::from_secs(5));
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert!(matches!(port.clear_fault(), Err(Error::Exited(_))));
    }
}
