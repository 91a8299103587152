//! The whole bridge as a board runs it: the sans-IO [`Bridge`] (link, CNC session, settings)
//! and the discrete I/O ([`DiscreteIo`]: input filter and interlocks), exchanged in the order
//! of `supervisor::Supervisor::turn` and the I/O task, in virtual time.
//!
//! The input is a power-up (stored settings, input pins, optionally a simulated unit of
//! `plasma-sim` wired to the power-supply port) and a sequence of steps: CNC bytes or command lines,
//! power-supply bytes (raw, or framed with a valid checksum so that they reach the link's
//! logic), a character the UART flagged, time passing, input edges, and things done to the
//! unit (faults, power, line noise).
//!
//! Checked on every step:
//! - the independent [`SafetyMonitor`], fed only the input edges at the pins and the START
//!   output, stays clean;
//! - every frame the bridge transmits to the power supply decodes (Modbus ASCII or HPR) and
//!   is on the allow-list, judged by the protocol's own tables: a Modbus write reaches only
//!   registers or coils `powermax::registers` documents as writable, an HPR command is
//!   [`Class::Normal`] in `hpr::command` (not factory-only, not dangerous, not unknown);
//! - buffers stay bounded: a frame fits the link's transmit buffer, a piece of CNC output
//!   fits the session's output buffer, no line is longer than `MAX_REPLY_LEN`, and the
//!   output drains;
//! - the bridge does not ask again and again for an instant already processed (on the board
//!   that is a busy loop);
//! - settings that `CONFIG SAVE` hands over encode within the record and load back equal;
//! - nothing panics.
#![no_main]

use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

use plasma_firmware::bridge::Bridge;
use plasma_firmware::discrete::DiscreteIo;
use plasma_firmware::inputs::{InputConfig, PinLevels};
use plasma_firmware::io::{Input, SafetyMonitor, SupplyState};
use plasma_firmware::link::TX_CAPACITY;
use plasma_firmware::bridge::{MAX_REPLY_LEN, OUTPUT_CAPACITY};
use plasma_firmware::settings::{SaveError, Settings};
use plasma_firmware::storage::{MAX_PAYLOAD, Settings as _};
use plasma_protocol::cnc::phoenix::{ACK, NAK};
use plasma_protocol::cnc::{ConfigKey, Gas, Mode};
use plasma_protocol::hpr::{self, Class};
use plasma_protocol::modbus_ascii::{self, Request};
use plasma_protocol::powermax::registers;
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::{Model, SimOptions, SimulatedUnit};

/// Frames the board writes per turn at most (`runner::MAX_FRAMES_PER_TURN`).
const FRAMES_PER_TURN: usize = 4;
/// Bytes per CNC read on the board (`supervisor::CNC_RX_CHUNK`).
const CNC_RX_CHUNK: usize = 64;
/// Bytes per power-supply read on the board (`supervisor::PS_RX_CHUNK`).
const PS_RX_CHUNK: usize = 64;
/// The board's task waits at most this long (`runner::MAX_WAIT`).
const MAX_WAIT: Duration = Duration::from_millis(100);
/// Times one instant may be processed again because the bridge still asks for it, as the
/// host harness allows; more is a busy loop on the board.
const MAX_REPEATS_AT_ONE_INSTANT: u32 = 2;
/// Pieces of CNC output one drain may take before it counts as never draining.
const MAX_OUTPUT_PIECES: usize = 1024;

/// Command words for [`Step::CncLine`]: a seed for the search, not a specification (the
/// parser is the one source; a word missing here only costs coverage).
const VERBS: [&str; 20] = [
    "HELP",
    "ID",
    "STATUS",
    "LIMITS",
    "FAULT",
    "FAULTLOG",
    "COUNTERS",
    "CARTRIDGE",
    "RESTART",
    "RESET",
    "CLEARWARN",
    "SET",
    "REMOTE",
    "GASTEST",
    "EVENTS",
    "TORCH",
    "GASES",
    "CORNER",
    "CONFIG",
    "RAW",
];
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
        line.extend_from_slice(pick(&VERBS, self.0).as_bytes());
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

/// Panics unless `frame` is one whole frame the bridge may send: a Modbus ASCII request
/// whose writes reach only documented writable registers and coils, or an HPR command of
/// class Normal.
fn check_allowed(frame: &[u8]) {
    assert!(frame.len() <= TX_CAPACITY, "frame over the transmit buffer");
    match frame.first() {
        Some(b':') => {
            let mut buf = [0u8; modbus_ascii::MAX_FRAME_BYTES];
            let decoded = modbus_ascii::decode(frame, &mut buf)
                .unwrap_or_else(|e| panic!("sent a Modbus frame that does not decode: {e:?}"));
            let request = decoded
                .request()
                .unwrap_or_else(|e| panic!("sent a Modbus PDU that does not parse: {e:?}"));
            let allowed = match request {
                Request::ReadCoils { .. }
                | Request::ReadHoldingRegisters { .. }
                | Request::ReadInputRegisters { .. }
                | Request::ReadDeviceIdentification { .. } => true,
                Request::WriteSingleCoil { address, .. } => registers::coil_writable(address),
                Request::WriteSingleRegister { address, .. } => {
                    registers::registers_writable(address, 1)
                }
                Request::WriteMultipleRegisters { start, values } => u16::try_from(values.len())
                    .is_ok_and(|n| registers::registers_writable(start, n)),
            };
            assert!(allowed, "sent a write off the allow-list: {request:?}");
        }
        Some(&hpr::frame::START) => {
            let parsed = hpr::Frame::parse(frame)
                .unwrap_or_else(|e| panic!("sent an HPR frame that does not parse: {e:?}"));
            assert_eq!(
                hpr::classify(parsed.id),
                Some(Class::Normal),
                "sent HPR command {:03} off the allow-list",
                parsed.id
            );
        }
        _ => panic!("sent something that is no frame: {frame:?}"),
    }
}

/// A simulated unit wired straight to the bridge's port: what one sends, the other hears at
/// once, whole, if both use the same line settings and no noise is on the line; otherwise
/// every character arrives flagged. (The scenario tests run the baud-accurate line; here it
/// would cost most of the time, and the steps damage the traffic themselves.)
struct Unit {
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
    /// Characters of the CNC output line under way (ACK and NAK come between lines).
    cnc_line_len: usize,
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
            let unit = pick(&Model::ALL, index).build(&SimOptions::default());
            Unit {
                unit,
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
            cnc_line_len: 0,
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
    /// poll, frames out, poll, CNC output, exchange with the I/O task, save), then the I/O
    /// task, then the monitor's sample.
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

        self.bridge.poll(now);
        for _ in 0..FRAMES_PER_TURN {
            let Some(frame) = self.bridge.poll_ps_transmit(now) else {
                break;
            };
            check_allowed(frame);
            let frame = frame.to_vec();
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
        if let Some(settings) = self.bridge.take_save_request() {
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
                    b'\n' => self.cnc_line_len = 0,
                    ACK | NAK if self.cnc_line_len == 0 => {}
                    _ => {
                        self.cnc_line_len += 1;
                        assert!(
                            self.cnc_line_len < MAX_REPLY_LEN,
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
            Step::CncBytes(bytes) => self.cnc_rx(bytes),
            Step::CncLine(verb, args) => {
                let mut line = Vec::new();
                verb.write(&mut line);
                for arg in args {
                    arg.write(&mut line);
                }
                line.extend_from_slice(b"\r\n");
                self.cnc_rx(&line);
            }
            Step::PsBytes(bytes) => self.ps_rx(bytes),
            Step::PsModbus { address, pdu } => self.ps_rx(&modbus_frame(*address, pdu)),
            Step::PsHpr { id, data } => self.ps_rx(&hpr_frame(*id, data)),
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
