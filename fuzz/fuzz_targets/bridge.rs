//! The whole bridge as a board runs it: the sans-IO [`Bridge`] (link, CNC session, settings)
//! and the discrete I/O ([`DiscreteIo`]: input filter and interlocks), exchanged in the order
//! of `supervisor::Supervisor::turn` and the I/O task, in virtual time.
//!
//! The input is a power-up (stored settings, input pins, optionally a simulated unit of
//! `plasma-sim` wired to the power-supply port) and a sequence of steps: CNC bytes or command lines,
//! Modbus ASCII requests from the CNC with a valid LRC (the CNC port answers as a Powermax;
//! [`cnc_master`]: any node, functions, registers from the protocol's tables, pmx485's
//! sequence), power-supply bytes (raw, or framed with a valid checksum so that they reach the
//! link's logic), a character the UART flagged, time passing, input edges, and things done to
//! the unit (faults, power, line noise).
//!
//! Checked on every step:
//! - the independent [`SafetyMonitor`], fed only the input edges at the pins and the START
//!   output, stays clean (so no Modbus request from the CNC ever gives a START);
//! - every frame the bridge transmits to the power supply decodes (Modbus ASCII or HPR) and
//!   is on the allow-list, judged by the protocol's own tables for the family of the unit on
//!   the line; while the link speaks to a SYNC unit, settings go as one whole 0x10 write
//!   ([`supply_rules`]);
//! - every CNC output line that starts with `:` is a Modbus ASCII response, never to node 0;
//!   a request the board knows arrived whole between lines is answered exactly when it is
//!   for the bridge's `cnc_address` and the link is up, and the answer is a response to it
//!   from that address (`modbus_ascii::validate_reply`), or an exception for a PDU that does
//!   not parse;
//! - buffers stay bounded: a frame fits the link's transmit buffer, a piece of CNC output
//!   fits the session's output buffer, no line is longer than `MAX_REPLY_LEN`, and the
//!   output drains;
//! - the bridge does not ask again and again for an instant already processed (on the board
//!   that is a busy loop);
//! - settings that `CONFIG SAVE` hands over encode within the record and load back equal;
//! - nothing panics.
#![no_main]

#[path = "bridge/cnc_master.rs"]
mod cnc_master;
#[path = "bridge/supply_rules.rs"]
mod supply_rules;

use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

use plasma_firmware::bridge::{Bridge, SaveRequest};
use plasma_firmware::consumables::ConsumableSet;
use plasma_firmware::bridge::{FRAME_IDLE_TIMEOUT, MAX_REPLY_LEN, OUTPUT_CAPACITY};
use plasma_firmware::io::{DiscreteIo, Input, InputConfig, PinLevels, SafetyMonitor, SupplyState};
// The board's own figures: the supervisor's and the PS port's read sizes, frames per turn and
// longest wait, so that the target turns as the board does.
use plasma_firmware::platform::runner::{MAX_FRAMES_PER_TURN, MAX_WAIT, PS_RX_CHUNK};
use plasma_firmware::platform::supervisor::CNC_RX_CHUNK;
use plasma_firmware::settings::{SaveError, Settings};
use plasma_firmware::storage::{MAX_PAYLOAD, Persistent as _};
use plasma_protocol::cnc::command::COMMAND_WORDS;
use plasma_protocol::cnc::phoenix::{self, ACK, NAK};
use plasma_protocol::cnc::{ConfigKey, Gas, Mode};
use plasma_protocol::hpr;
use plasma_protocol::modbus_ascii::{self, Request, Response};
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::{Model, SimOptions, SimulatedUnit};

use cnc_master::{MasterRequest, Node, Pmx485};
use supply_rules::Judge;

/// Times one instant may be processed again because the bridge still asks for it, as the
/// host harness allows; more is a busy loop on the board.
const MAX_REPEATS_AT_ONE_INSTANT: u32 = 2;
/// Pieces of CNC output one drain may take before it counts as never draining.
const MAX_OUTPUT_PIECES: usize = 1024;

/// Command words for [`Step::CncLine`]: the parser's own list (the one source HELP prints),
/// and `TORCH`, which the simulator runs and the fuzzed bridge answers too.
const SIMULATOR_VERB: &str = "TORCH";
const WORDS: [&str; 8] = [
    "MODE", "AMPS", "PSI", "PROCESS", "SAVE", "ON", "OFF", "AUTO",
];

#[derive(Arbitrary, Debug)]
struct Scenario {
    /// A stored settings record payload (decoded as at boot; the defaults if invalid).
    stored: Option<Vec<u8>>,
    /// Input pins at power-up, one bit per input in [`Input::ALL`] order (1 = high).
    pins: u8,
    /// A simulated unit on the line: index into [`Model::ALL`].
    unit: Option<u8>,
    /// `set_boot_report` at power-up.
    boot_report: bool,
    steps: Vec<Step>,
}

#[derive(Arbitrary, Debug)]
enum Step {
    /// Bytes from the CNC.
    CncBytes(Vec<u8>),
    /// A command line from the CNC (CR LF appended).
    CncLine(Verb, Vec<Arg>),
    /// A Modbus ASCII request from the CNC with a correct LRC.
    CncModbus(MasterRequest),
    /// LinuxCNC's pmx485: three force-register writes, then reads.
    Pmx485(Pmx485),
    /// Bytes from the power supply's port, as received.
    PsBytes(Vec<u8>),
    /// A Modbus ASCII frame with a correct LRC, as received.
    PsModbus { address: u8, pdu: Vec<u8> },
    /// An HPR frame with a correct checksum, as received.
    PsHpr { id: u16, data: Vec<u8> },
    /// A character the UART flagged (parity, framing, noise).
    PsFlagged,
    /// Time passes (in units of 64 us, up to about 4.2 s).
    Wait(u16),
    /// An edge at an input pin: the input goes active or inactive.
    Input { input: u8, active: bool },
    /// The next `CONFIG SAVE` fails with this error (index into [`SAVE_ERRORS`]).
    FailNextSave(u8),
    /// The unit raises a fault (Powermax decimal code, HPR error id).
    UnitFault(u16),
    /// The unit clears its fault.
    UnitClearFault,
    /// The unit is switched off (false) or on (true).
    UnitPower(bool),
    /// Noise on the line for this many microseconds.
    Noise(u16),
}

#[derive(Arbitrary, Debug)]
struct Verb(u8);

#[derive(Arbitrary, Debug)]
enum Arg {
    Word(u8),
    Mode(u8),
    Gas(u8),
    Key(u8),
    Number(u16),
    Decimal(u16, u8),
    Text(Vec<u8>),
    RawModbus { address: u8, pdu: Vec<u8> },
    RawHpr { id: u16, data: Vec<u8> },
}

const SAVE_ERRORS: [SaveError; 4] = [
    SaveError::Flash,
    SaveError::Corrupted,
    SaveError::TooLarge,
    SaveError::Storage,
];

fn pick<T: Copy>(items: &[T], index: u8) -> T {
    items[usize::from(index) % items.len()]
}

impl Verb {
    fn write(&self, line: &mut Vec<u8>) {
        let verb = COMMAND_WORDS
            .get(usize::from(self.0) % (COMMAND_WORDS.len() + 1))
            .unwrap_or(&SIMULATOR_VERB);
        line.extend_from_slice(verb.as_bytes());
    }
}

impl Arg {
    fn write(&self, line: &mut Vec<u8>) {
        line.push(b' ');
        match self {
            Arg::Word(i) => line.extend_from_slice(pick(&WORDS, *i).as_bytes()),
            Arg::Mode(i) => line.extend_from_slice(pick(&Mode::ALL, *i).name().as_bytes()),
            Arg::Gas(i) => line.extend_from_slice(pick(&Gas::ALL, *i).name().as_bytes()),
            Arg::Key(i) => line.extend_from_slice(pick(&ConfigKey::ALL, *i).name().as_bytes()),
            Arg::Number(n) => line.extend_from_slice(n.to_string().as_bytes()),
            Arg::Decimal(n, f) => line.extend_from_slice(format!("{n}.{f}").as_bytes()),
            Arg::Text(bytes) => line.extend(bytes.iter().filter(|b| !matches!(b, b'\r' | b'\n'))),
            Arg::RawModbus { address, pdu } => line.extend(modbus_frame(*address, pdu)),
            Arg::RawHpr { id, data } => line.extend(hpr_frame(*id, data)),
        }
    }
}

/// `pdu` as a Modbus ASCII frame with a correct LRC (empty if it does not fit).
fn modbus_frame(address: u8, pdu: &[u8]) -> Vec<u8> {
    let mut out = [0u8; modbus_ascii::MAX_FRAME_CHARS];
    match modbus_ascii::encode(address, pdu, &mut out) {
        Ok(n) => out[..n].to_vec(),
        Err(_) => Vec::new(),
    }
}

/// An HPR frame with a correct checksum (empty if it cannot be written).
fn hpr_frame(id: u16, data: &[u8]) -> Vec<u8> {
    let mut out = [0u8; hpr::MAX_FRAME_LEN];
    match hpr::Frame::new(id, data).emit(&mut out) {
        Ok(n) => out[..n].to_vec(),
        Err(_) => Vec::new(),
    }
}

/// Every `:` line to the CNC is a Modbus ASCII response, and none goes to node 0 (a broadcast
/// is never answered).
fn check_modbus_line(line: &[u8]) {
    let text = String::from_utf8_lossy(line);
    let mut buf = [0u8; modbus_ascii::MAX_FRAME_BYTES];
    let frame = modbus_ascii::decode(line, &mut buf)
        .unwrap_or_else(|e| panic!("CNC line {text:?} is no Modbus frame: {e:?}"));
    assert_ne!(frame.address, 0, "{text:?} answers a broadcast");
    if let Err(e) = Response::parse(frame.pdu) {
        panic!("CNC line {text:?} is no Modbus response: {e:?}");
    }
}

/// `reply` answers `pdu` sent to `address`: a response to the request, or an exception for
/// its function when the PDU does not parse.
fn check_reply(reply: &[u8], address: u8, pdu: &[u8]) {
    let text = String::from_utf8_lossy(reply);
    let mut buf = [0u8; modbus_ascii::MAX_FRAME_BYTES];
    let frame = modbus_ascii::decode(reply, &mut buf)
        .unwrap_or_else(|e| panic!("{text:?} is no Modbus frame: {e:?}"));
    match Request::parse(pdu) {
        Ok(request) => {
            if let Err(e) = modbus_ascii::validate_reply(&request, address, &frame) {
                panic!("{text:?} does not answer {request:?} to node {address}: {e:?}");
            }
        }
        Err(_) => {
            let function = pdu.first().map_or(0, |f| f & 0x7F);
            assert_eq!(frame.address, address, "{text:?} from another node");
            assert!(
                matches!(Response::parse(frame.pdu),
                    Ok(Response::Exception { function: f, .. }) if f == function),
                "{text:?} is no exception to the PDU {pdu:02X?}"
            );
        }
    }
}

/// A simulated unit wired straight to the bridge's port: what one sends, the other hears at
/// once, whole, if both use the same line settings and no noise is on the line; otherwise
/// every character arrives flagged. (The scenario tests run the baud-accurate line; here it
/// would cost most of the time, and the steps damage the traffic themselves.)
struct Unit {
    model: Model,
    unit: Box<dyn SimulatedUnit>,
    start_given: bool,
    noisy_until: Instant,
}

impl Unit {
    fn clean(&self, now: Instant, port: PortConfig) -> bool {
        now >= self.noisy_until && port == self.unit.port()
    }
}

/// The board: the bridge, the discrete I/O, the pins, and the monitor watching them.
struct Board {
    now: Instant,
    bridge: Bridge,
    io: DiscreteIo,
    inputs: InputConfig,
    pins: PinLevels,
    monitor: SafetyMonitor,
    supply_sent: Option<SupplyState>,
    next_save: Result<(), SaveError>,
    /// The CNC output line under way (ACK and NAK come between lines).
    cnc_line: Vec<u8>,
    /// CNC output lines that start with `:` since the last request step.
    modbus_replies: Vec<Vec<u8>>,
    /// The CNC port's input is known to stand between lines, no frame under way.
    cnc_between_lines: bool,
    /// The last CNC input bytes, to spot a `RAW` command across steps.
    cnc_tail: Vec<u8>,
    raw_possible: bool,
    /// Steps injected bytes on the power-supply port.
    impersonated: bool,
    unit: Option<Unit>,
    repeats: u32,
}

impl Board {
    fn power_up(scenario: &Scenario) -> Board {
        let now = Instant::ZERO;
        let settings = scenario
            .stored
            .as_deref()
            .and_then(Settings::decode)
            .unwrap_or_default();
        let inputs = settings.io.inputs;
        let mut pins = PinLevels::ALL_LOW;
        for (bit, input) in Input::ALL.into_iter().enumerate() {
            pins = pins.with(input, scenario.pins & (1 << bit) != 0);
        }
        let torch_on = inputs
            .get(Input::TorchOn)
            .polarity
            .is_active(pins.is_high(Input::TorchOn));
        let mut bridge = Bridge::new(settings, now);
        if scenario.boot_report {
            bridge.set_boot_report(now, "power-on");
        }
        let io = DiscreteIo::new(bridge.io_config(), now, pins);
        let unit = scenario.unit.map(|index| {
            let model = pick(&Model::ALL, index);
            Unit {
                model,
                unit: model.build(&SimOptions::default()),
                start_given: false,
                noisy_until: now,
            }
        });
        let mut board = Board {
            now,
            bridge,
            io,
            inputs,
            pins,
            monitor: SafetyMonitor::new(torch_on),
            supply_sent: None,
            next_save: Ok(()),
            cnc_line: Vec::new(),
            modbus_replies: Vec::new(),
            cnc_between_lines: true,
            cnc_tail: Vec::new(),
            raw_possible: false,
            impersonated: false,
            unit,
            repeats: 0,
        };
        board.turn();
        board
    }

    /// An edge at an input pin: the monitor sees it as it arrives, then the I/O task.
    fn drive_input(&mut self, input: Input, active: bool) {
        let high = self.inputs.get(input).polarity.is_active(true) == active;
        self.pins = self.pins.with(input, high);
        self.monitor.input(input, active);
        self.io.on_pins(self.now, self.pins);
    }

    /// Whether `input` is active at its pin.
    fn pin_active(&self, input: Input) -> bool {
        self.inputs
            .get(input)
            .polarity
            .is_active(self.pins.is_high(input))
    }

    /// Characters arrived from the power supply now.
    fn ps_rx(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(PS_RX_CHUNK) {
            self.bridge.handle_ps_rx(self.now, chunk);
        }
        self.turn();
    }

    fn cnc_rx(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(CNC_RX_CHUNK) {
            self.bridge.handle_cnc_rx(self.now, chunk);
        }
        self.turn();
    }

    /// Let `duration` pass, processing every instant something is due.
    fn wait(&mut self, duration: Duration) {
        let target = self.now + duration;
        loop {
            let wakeups = [
                ("bridge", self.bridge.poll_at()),
                ("I/O", self.io.poll_at()),
                (
                    "unit",
                    self.unit.as_ref().and_then(|u| u.unit.next_wakeup()),
                ),
                // The board's tasks wake at least this often.
                ("task", Some(self.now + MAX_WAIT)),
            ];
            let next = wakeups
                .iter()
                .filter_map(|&(_, at)| at)
                .min()
                .unwrap_or(target);
            if next <= self.now {
                self.repeats += 1;
                assert!(
                    self.repeats <= MAX_REPEATS_AT_ONE_INSTANT,
                    "busy loop at {} us: {wakeups:?}",
                    self.now.as_micros()
                );
            } else if next > target {
                if self.now < target {
                    self.move_to(target);
                    self.turn();
                }
                return;
            } else {
                self.move_to(next);
            }
            self.turn();
        }
    }

    fn move_to(&mut self, at: Instant) {
        if at > self.now {
            self.now = at;
            self.repeats = 0;
        }
    }

    /// Everything due now: the unit hears and answers, then one supervisor turn (bytes in,
    /// frames out (asking for them polls), poll, CNC output, exchange with the I/O task, save),
    /// then the I/O task, then the monitor's sample.
    fn turn(&mut self) {
        let now = self.now;
        self.unit_side();

        // Supervisor: the I/O task's levels and events in.
        self.bridge
            .set_io_snapshot(self.io.inputs(), self.io.outputs());
        while let Some(event) = self.io.poll_event() {
            self.bridge.on_io_event(now, event);
        }
        while self.io.poll_transition().is_some() {}

        for _ in 0..MAX_FRAMES_PER_TURN {
            let Some(frame) = self.bridge.poll_ps_transmit(now) else {
                break;
            };
            let frame = frame.to_vec();
            self.judge().check(&frame);
            // The port takes the settings the bridge reports after handing out the frame.
            let port = self.bridge.ps_port_config();
            if let Some(unit) = &mut self.unit {
                let clean = unit.clean(now, port);
                for &byte in &frame {
                    if clean {
                        unit.unit.receive(now, byte);
                    } else {
                        unit.unit.receive_error(now);
                    }
                }
            }
        }
        self.bridge.poll(now);
        self.drain_cnc_output();

        // Supervisor: supply state and settings out, a save.
        let supply = self.bridge.supply_state();
        if self.supply_sent != Some(supply) {
            self.io.on_supply(now, supply);
            self.supply_sent = Some(supply);
        }
        if let Some(config) = self.bridge.take_io_config_change() {
            // A new wiring of TORCH_ON is an operator's command the monitor observes: the pin
            // keeps its level, its meaning may change, and the power-up rule applies again.
            let torch_on_rewired =
                config.inputs.get(Input::TorchOn) != self.inputs.get(Input::TorchOn);
            self.io.reconfigure(now, config, self.pins);
            self.inputs = config.inputs;
            if torch_on_rewired {
                let active = self
                    .inputs
                    .get(Input::TorchOn)
                    .polarity
                    .is_active(self.pins.is_high(Input::TorchOn));
                self.monitor.torch_on_redefined(active);
            }
        }
        match self.bridge.take_save_request() {
            Some(SaveRequest::Settings(settings)) => {
                let mut payload = [0u8; MAX_PAYLOAD];
                let len = settings.encode(&mut payload);
                assert!(
                    len <= MAX_PAYLOAD,
                    "settings record over {MAX_PAYLOAD} bytes"
                );
                assert_eq!(
                    Settings::decode(&payload[..len]),
                    Some(settings),
                    "saved settings load back different"
                );
                let result = core::mem::replace(&mut self.next_save, Ok(()));
                self.bridge.save_finished(now, result);
                self.drain_cnc_output();
            }
            Some(SaveRequest::Consumables(set)) => {
                let mut payload = [0u8; MAX_PAYLOAD];
                let len = set.encode(&mut payload);
                assert_eq!(
                    ConsumableSet::decode(&payload[..len]),
                    Some(set),
                    "saved consumable record loads back different"
                );
                self.bridge.save_finished(now, Ok(()));
            }
            None => {}
        }

        // The I/O task.
        self.io.poll(now);
        let start = self.io.outputs().start;
        if let Some(unit) = &mut self.unit
            && start != unit.start_given
        {
            unit.unit.set_start(now, start);
            unit.start_given = start;
        }
        self.monitor
            .check(now, start, supply.restart_blackout_until);
        assert!(
            self.monitor.is_clean(),
            "safety rule broken: {:?}",
            self.monitor.violations()
        );
    }

    /// The unit's side at this instant: its timers, its reply, its MOTION output.
    fn unit_side(&mut self) {
        let now = self.now;
        let Some(unit) = &mut self.unit else {
            return;
        };
        unit.unit.advance(now);
        for (start, length) in unit.unit.take_noise_bursts() {
            unit.noisy_until = unit.noisy_until.max(start + length);
        }
        while let Some(bytes) = unit.unit.poll_transmit(now) {
            if unit.clean(now, self.bridge.ps_port_config()) {
                self.bridge.handle_ps_rx(now, &bytes);
            } else {
                for _ in &bytes {
                    self.bridge.handle_ps_rx_error(now);
                }
            }
        }
        // MOTION is the unit's output, wired to the board's input.
        let motion = unit.unit.motion();
        if motion != self.pin_active(Input::Motion) {
            self.drive_input(Input::Motion, motion);
        }
    }

    fn drain_cnc_output(&mut self) {
        for _ in 0..MAX_OUTPUT_PIECES {
            let Some(piece) = self.bridge.poll_cnc_output() else {
                return;
            };
            assert!(!piece.is_empty(), "an empty piece of CNC output");
            assert!(piece.len() <= OUTPUT_CAPACITY, "CNC output over its buffer");
            for &byte in piece {
                match byte {
                    b'\n' => {
                        let mut line = core::mem::take(&mut self.cnc_line);
                        if line.first() == Some(&b':') {
                            line.push(byte);
                            check_modbus_line(&line);
                            self.modbus_replies.push(line);
                        }
                    }
                    ACK | NAK if self.cnc_line.is_empty() => {}
                    _ => {
                        self.cnc_line.push(byte);
                        assert!(
                            self.cnc_line.len() < MAX_REPLY_LEN,
                            "a CNC line over {MAX_REPLY_LEN} bytes"
                        );
                    }
                }
            }
        }
        panic!("CNC output does not drain");
    }

    fn step(&mut self, step: &Step) {
        match step {
            Step::CncBytes(bytes) => {
                self.note_cnc_text(bytes);
                self.cnc_between_lines &= bytes.is_empty();
                self.cnc_rx(bytes);
            }
            Step::CncLine(verb, args) => {
                let mut line = Vec::new();
                verb.write(&mut line);
                for arg in args {
                    arg.write(&mut line);
                }
                line.extend_from_slice(b"\r\n");
                self.note_cnc_text(&line);
                // A line of text ends between lines, unless SOH or STX opened a Phoenix frame.
                self.cnc_between_lines &= !line.iter().any(|&b| phoenix::is_frame_start(b));
                self.cnc_rx(&line);
            }
            Step::CncModbus(request) => {
                self.settle_cnc_input(request.resync);
                let pdu = request.pdu.bytes(self.bridge.status());
                if let Some(pdu) = pdu {
                    self.cnc_request(request.node, &pdu);
                }
            }
            Step::Pmx485(pmx) => {
                self.settle_cnc_input(pmx.resync);
                for exchange in pmx.exchanges() {
                    if exchange.gap_ms > 0 {
                        self.wait(Duration::from_millis(u64::from(exchange.gap_ms)));
                    }
                    if let Some(active) = exchange.torch_on {
                        self.drive_input(Input::TorchOn, active);
                        self.turn();
                    }
                    if let Some(pdu) = exchange.pdu.bytes(self.bridge.status()) {
                        self.cnc_request(Node::Bridge, &pdu);
                    }
                }
            }
            Step::PsBytes(bytes) => {
                self.impersonated |= !bytes.is_empty();
                self.ps_rx(bytes);
            }
            Step::PsModbus { address, pdu } => {
                self.impersonated = true;
                self.ps_rx(&modbus_frame(*address, pdu));
            }
            Step::PsHpr { id, data } => {
                self.impersonated = true;
                self.ps_rx(&hpr_frame(*id, data));
            }
            Step::PsFlagged => {
                self.bridge.handle_ps_rx_error(self.now);
                self.turn();
            }
            Step::Wait(units) => self.wait(Duration::from_micros(u64::from(*units) * 64)),
            Step::Input { input, active } => {
                self.drive_input(pick(&Input::ALL, *input), *active);
                self.turn();
            }
            Step::FailNextSave(i) => self.next_save = Err(pick(&SAVE_ERRORS, *i)),
            Step::UnitFault(code) => self.on_unit(|u, now| u.unit.inject_fault(now, *code)),
            Step::UnitClearFault => self.on_unit(|u, now| u.unit.clear_fault(now)),
            Step::UnitPower(on) => self.on_unit(|u, now| {
                if *on {
                    u.unit.power_on(now);
                } else {
                    u.unit.power_off(now);
                }
            }),
            Step::Noise(us) => self.on_unit(|u, now| {
                u.noisy_until = u
                    .noisy_until
                    .max(now + Duration::from_micros(u64::from(*us)));
            }),
        }
    }

    /// What the board knows when a frame leaves for the power supply.
    fn judge(&self) -> Judge {
        Judge {
            unit: self.unit.as_ref().map(|u| u.model.family()),
            link: self.bridge.status().family,
            impersonated: self.impersonated,
            raw_possible: self.raw_possible,
        }
    }

    /// Watches the CNC's text for a `RAW` command (any case, across steps): it may write
    /// one settings register on purpose.
    fn note_cnc_text(&mut self, bytes: &[u8]) {
        self.cnc_tail
            .extend(bytes.iter().map(u8::to_ascii_uppercase));
        if self.cnc_tail.windows(3).any(|w| w == b"RAW") {
            self.raw_possible = true;
        }
        let keep_from = self.cnc_tail.len().saturating_sub(2);
        self.cnc_tail.drain(..keep_from);
    }

    /// Before a request, when the port's input is unknown and `resync`: let a frame under way
    /// lapse and end the line, so the request arrives between lines.
    fn settle_cnc_input(&mut self, resync: bool) {
        if self.cnc_between_lines || !resync {
            return;
        }
        self.wait(FRAME_IDLE_TIMEOUT);
        self.cnc_rx(b"\r\n");
        self.cnc_between_lines = true;
    }

    /// The CNC port answers as a Powermax only while the link is up with a unit it knows.
    fn link_serves(&self) -> bool {
        let status = self.bridge.status();
        status.link_up && status.family.is_some()
    }

    /// `pdu` from the CNC to `node` with a correct LRC, and the answer checked: when the
    /// request arrived between lines, exactly one reply if it is for the bridge and the link
    /// is up (before and after; either way if it changed), none otherwise.
    fn cnc_request(&mut self, node: Node, pdu: &[u8]) {
        let cnc_address = self.bridge.settings().cnc.address;
        let address = node.address(cnc_address);
        let frame = modbus_frame(address, pdu);
        if frame.is_empty() {
            return;
        }
        let between_lines = self.cnc_between_lines;
        let served_before = self.link_serves();
        self.modbus_replies.clear();
        self.cnc_rx(&frame);
        let replies = core::mem::take(&mut self.modbus_replies);
        assert!(replies.len() <= 1, "one request, replies {replies:?}");
        // A queued `CONFIG cnc_address` may have run meanwhile: then either node was right.
        if !between_lines || self.bridge.settings().cnc.address != cnc_address {
            return;
        }
        let served_after = self.link_serves();
        let for_bridge = address != 0 && address == cnc_address;
        let request = String::from_utf8_lossy(&frame);
        match replies.first() {
            Some(reply) => {
                let reply = String::from_utf8_lossy(reply);
                assert!(
                    for_bridge,
                    "{request:?} to node {address} answered {reply:?} (the bridge is node {cnc_address})"
                );
                assert!(
                    served_before || served_after,
                    "{request:?} answered {reply:?} while the link is down"
                );
                check_reply(reply.as_bytes(), address, pdu);
            }
            None => assert!(
                !(for_bridge && served_before && served_after),
                "{request:?} not answered with the link up"
            ),
        }
    }

    fn on_unit(&mut self, act: impl FnOnce(&mut Unit, Instant)) {
        let now = self.now;
        if let Some(unit) = &mut self.unit {
            act(unit, now);
        }
        self.turn();
    }
}

fuzz_target!(|scenario: Scenario| {
    let mut board = Board::power_up(&scenario);
    for step in &scenario.steps {
        board.step(step);
    }
});
