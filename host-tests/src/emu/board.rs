//! The emulated board in one piece: QEMU running the firmware image, the simulated unit on its
//! PS port, the CNC port, the discrete I/O through qtest, and the firmware's log.
//!
//! A [`Board`] boots paused, sets the input pins (so a TORCH_ON held at power-up is there
//! before the first instruction), starts watching START / ARC_OK / READY, then lets the CPU
//! run. When it is dropped QEMU is killed; if the test is failing at that point, everything
//! needed to understand the failure is printed: the firmware's log, the CNC transcript, the
//! PS wire trace, QEMU's stderr. Otherwise the safety rules ([`super::safety`]) are checked on
//! what was observed, and a broken one fails the test.

use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use plasma_firmware::io::{Input, Output};
use plasma_firmware::platform::pins::USER_BUTTON;
use plasma_firmware::settings::CNC_BAUDS;

use super::cnc::CncPort;
use super::error::{Error, Result};
use super::image::firmware_elf;
use super::log::FirmwareLog;
use super::pins::{
    TestHook, UNIT_SETS, UnitSet, WATCHED_PORT, unit_input_level, unit_input_pin,
    unit_output_active, unit_output_pin,
};
use super::qemu::{Qemu, QemuOptions};
use super::qtest::Qtest;
use super::safety::{self, Observed};
use super::sim_port::{Framing, SimPort, SimPortOptions};
use super::usart::{CNC_KERNEL_CLOCK_HZ, Usart};
use plasma_protocol::serial::PortConfig;
use plasma_sim::{Model, SimOptions};

/// Boards that may run at once in one process (QEMU needs a core while the guest is busy;
/// the machine has two). `PLASMA_EMU_JOBS` overrides it.
const DEFAULT_PARALLEL_BOARDS: usize = 2;
/// How long the firmware may take to enable its CNC port after power-up.
const CNC_READY_TIMEOUT: Duration = Duration::from_secs(20);
/// How often waits look at an output.
const POLL: Duration = Duration::from_millis(2);

/// How the unit's discrete signals are wired to the board.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wiring {
    /// As in a machine: the board's START drives the unit's Start input and the unit's
    /// Motion output drives the board's MOTION input.
    Unit,
    /// The test drives MOTION itself; START reaches the unit nowhere.
    Manual,
}

/// How to boot the board.
#[derive(Debug, Clone, PartialEq)]
pub struct BoardOptions {
    /// The simulated unit.
    pub model: Model,
    /// Its options.
    pub sim: SimOptions,
    /// Further units on the same simulated line ([`SimPortOptions::more_units`]), the second
    /// wired to the board's second unit set.
    pub more_units: Vec<Model>,
    /// A fault the unit has from power-up (Powermax decimal code, HPR error number).
    pub fault_at_power_up: Option<u16>,
    /// Inputs already active when the board powers up.
    pub active_at_power_up: Vec<Input>,
    /// The discrete wiring between board and unit.
    pub wiring: Wiring,
    /// Model the PS framing from USART1's registers (a mismatch garbles the traffic); with
    /// the USART kernel clock, the baud rate too.
    pub framing_from_registers: Option<Option<u32>>,
    /// QEMU's instruction counting (`-icount shift=0,sleep=on`, see
    /// [`QemuOptions::icount`]); on by default, as the firmware side recommends.
    pub icount: bool,
    /// The image; `None` builds it ([`firmware_elf`]).
    pub elf: Option<PathBuf>,
}

impl BoardOptions {
    /// `model`, no fault, inputs inactive, the unit wired, matched framing, instruction
    /// counting on.
    pub fn new(model: Model) -> BoardOptions {
        BoardOptions {
            model,
            sim: SimOptions::default(),
            more_units: Vec::new(),
            fault_at_power_up: None,
            active_at_power_up: Vec::new(),
            wiring: Wiring::Unit,
            framing_from_registers: None,
            icount: true,
            elf: None,
        }
    }
}

/// Boards running now in this process (a counting semaphore).
static RUNNING: (Mutex<usize>, Condvar) = (Mutex::new(0), Condvar::new());

/// A place among the boards running at once; given back when dropped.
struct Slot;

impl Slot {
    fn take() -> Slot {
        let limit = std::env::var("PLASMA_EMU_JOBS")
            .ok()
            .and_then(|v| v.parse().ok())
            .filter(|&n: &usize| n > 0)
            .unwrap_or(DEFAULT_PARALLEL_BOARDS);
        let mut running = lock(&RUNNING.0);
        while *running >= limit {
            running = RUNNING.1.wait(running).unwrap_or_else(|e| e.into_inner());
        }
        *running += 1;
        Slot
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        *lock(&RUNNING.0) -= 1;
        RUNNING.1.notify_one();
    }
}

/// An input the harness drove, with the number of output edges QEMU had sent before.
#[derive(Debug, Clone, Copy)]
struct Driven {
    mark: usize,
    at: Instant,
    /// The unit set (0 = the first unit).
    unit: usize,
    input: Input,
    active: bool,
}

/// A reset of the MCU the harness held and let boot ([`Board::reboot_after_reset`]), with the
/// number of output edges QEMU had sent before.
#[derive(Debug, Clone, Copy)]
struct HeldReset {
    mark: usize,
    at: Instant,
    /// Each unit set's START.
    start_on: [bool; UNIT_SETS],
}

/// The emulated board with its simulated unit. See the [module docs](self).
pub struct Board {
    // Dropped first: killing QEMU closes every socket, which ends the threads below.
    qemu: Qemu,
    qtest: Arc<Qtest>,
    sim: SimPort,
    cnc: CncPort,
    log: FirmwareLog,
    driven: Mutex<Vec<Driven>>,
    resets: Vec<HeldReset>,
    options: BoardOptions,
    elf: PathBuf,
    /// Each unit set's START at power-up.
    start_at_power_up: [bool; UNIT_SETS],
    /// The user button (B1) is held through the resets that follow.
    user_button_held: bool,
    epoch: Instant,
    _slot: Slot,
}

impl Board {
    /// Boots the board: builds the image if needed, starts QEMU paused, sets the inputs,
    /// connects the unit, and starts the CPU.
    pub fn boot(options: BoardOptions) -> Result<Board> {
        let elf = match &options.elf {
            Some(elf) => elf.clone(),
            None => firmware_elf()?,
        };
        let slot = Slot::take();
        let (mut qemu, sockets) = Qemu::start(&QemuOptions {
            elf: elf.clone(),
            icount: options.icount,
        })?;
        let qtest = Arc::new(Qtest::new(sockets.qtest)?);
        let mut driven = Vec::new();
        let epoch = Instant::now();
        for (unit, input) in every_input() {
            // Active at power-up: the first unit's inputs the options name.
            let active = unit == 0 && options.active_at_power_up.contains(&input);
            let level = unit_input_level(unit, input, active);
            let mark = qtest.set_pin(unit_input_pin(unit, input), level)?;
            driven.push(Driven {
                mark,
                at: epoch,
                unit,
                input,
                active,
            });
        }
        qtest.intercept_outputs(WATCHED_PORT)?;
        let mut start_at_power_up = [false; UNIT_SETS];
        for (unit, on) in start_at_power_up.iter_mut().enumerate() {
            let high = qtest.output_level(unit_output_pin(unit, Output::Start))?;
            *on = unit_output_active(unit, Output::Start, high);
        }

        let (on_motion, output_edges) = match options.wiring {
            Wiring::Unit => {
                let for_motion = Arc::clone(&qtest);
                let on_motion: Box<dyn FnMut(usize, bool) + Send> = Box::new(move |unit, on| {
                    // A unit with no set of the board's has no MOTION wired.
                    let Some(set) = UnitSet::new(unit) else {
                        return;
                    };
                    let motion = set.input(Input::Motion);
                    // An error means QEMU is gone: the board is being dropped.
                    let _ = for_motion.set_pin(motion.pin, motion.level(on));
                });
                (Some(on_motion), Some(qtest.subscribe()))
            }
            Wiring::Manual => (None, None),
        };
        let framing = match options.framing_from_registers {
            Some(clock_hz) => Framing::Registers {
                qtest: Arc::clone(&qtest),
                clock_hz,
            },
            None => Framing::Matched,
        };
        let sim = SimPort::start(
            sockets.ps,
            SimPortOptions {
                model: options.model,
                sim: options.sim,
                more_units: options.more_units.clone(),
                framing,
                on_motion,
                output_edges,
                seed: options.sim.seed,
            },
        )?;
        if let Some(code) = options.fault_at_power_up {
            sim.inject_fault(code)?;
        }
        let cnc = CncPort::new(sockets.cnc)?;
        let log = FirmwareLog::start(&elf, qemu.log_path())?;
        qemu.resume()?;
        match wait_cnc_port_ready(&qtest) {
            Ok(()) => {}
            // A firmware that never gets that far says why in its log (a fault at boot, a
            // reset loop); the board is dropped with this error, so it goes with it.
            Err(Error::Timeout(why)) => {
                return Err(Error::Timeout(format!(
                    "{why}; the firmware's log (last 20 lines):\n{}",
                    log.tail(20)
                )));
            }
            Err(other) => return Err(other),
        }
        Ok(Board {
            qemu,
            qtest,
            sim,
            cnc,
            log,
            driven: Mutex::new(driven),
            resets: Vec::new(),
            options,
            elf,
            start_at_power_up,
            user_button_held: false,
            epoch,
            _slot: slot,
        })
    }

    /// The options it was booted with.
    pub fn options(&self) -> &BoardOptions {
        &self.options
    }

    /// The image it runs.
    pub fn elf(&self) -> &std::path::Path {
        &self.elf
    }

    /// When it was powered up (host clock).
    pub fn epoch(&self) -> Instant {
        self.epoch
    }

    /// The qtest session.
    pub fn qtest(&self) -> &Qtest {
        &self.qtest
    }

    /// The simulated unit.
    pub fn sim(&self) -> &SimPort {
        &self.sim
    }

    /// The CNC port.
    pub fn cnc(&mut self) -> &mut CncPort {
        &mut self.cnc
    }

    /// The framing the firmware runs its CNC UART (USART2) at, read from the registers now;
    /// a baud rate within 2 % of `nominal_baud`, else of one `cnc_baud` accepts, reads as that
    /// rate (BRR rounds: 9600 baud from 16 MHz is BRR 1667, 9598 baud). `None` while the USART
    /// is off.
    pub fn cnc_framing(&self, nominal_baud: u32) -> Result<Option<PortConfig>> {
        let framing = Usart::CNC.framing(&self.qtest, Some(CNC_KERNEL_CLOCK_HZ), nominal_baud)?;
        Ok(framing.map(|mut framing| {
            let near = |b: u32| framing.baud.abs_diff(b) * 50 <= b;
            if let Some(&baud) = CNC_BAUDS.iter().find(|&&b| near(b)) {
                framing.baud = baud;
            }
            framing
        }))
    }

    /// The firmware's log.
    pub fn log(&self) -> &FirmwareLog {
        &self.log
    }

    /// Drives an input signal of the first unit (`active` = the opto-coupler conducts: the
    /// pin is low).
    pub fn set_input(&self, input: Input, active: bool) -> Result<()> {
        self.set_unit_input(0, input, active)
    }

    /// Drives unit `unit`'s input signal (0 = the first unit; a board-wide input's one pin
    /// for every unit).
    pub fn set_unit_input(&self, unit: usize, input: Input, active: bool) -> Result<()> {
        let level = unit_input_level(unit, input, active);
        let mark = self.qtest.set_pin(unit_input_pin(unit, input), level)?;
        lock(&self.driven).push(Driven {
            mark,
            at: Instant::now(),
            unit,
            input,
            active,
        });
        Ok(())
    }

    /// Holds the user button (B1, PC13) down, or lets it go: the firmware reads it once at
    /// boot, so a hold counts from the next reset ([`Board::cut_power`]), through which it is
    /// held as a person holds it.
    pub fn hold_user_button(&mut self, held: bool) -> Result<()> {
        self.user_button_held = held;
        let level = USER_BUTTON.level(held);
        self.qtest.set_pin(USER_BUTTON.pin, level).map(drop)
    }

    /// Makes the firmware fail on purpose: the test images' `hook`, its pin pulled low. The
    /// reset that follows (the fault path's, the watchdog's) is held, QEMU stopped, until
    /// [`Board::reboot_after_reset`].
    pub fn fail_on_purpose(&mut self, hook: TestHook) -> Result<()> {
        self.qemu.qmp().hold_guest_resets(true)?;
        self.qtest.set_pin(hook.pin(), false).map(drop)
    }

    /// Waits up to `timeout` for the reset held since [`Board::fail_on_purpose`], then boots
    /// the board again as a reset does on the real one: QEMU's reset forgets the levels
    /// driven on its pins, so the inputs get theirs back before the first instruction (a
    /// TORCH_ON held through the reset is still held), while the hook's pin is let go.
    /// Returns the outputs that were on when the MCU reset (by the pin table: the levels the
    /// firmware left, before QEMU's reset clears them) once the firmware has enabled its CNC
    /// port again. The safety rules treat the reset as a power-up.
    pub fn reboot_after_reset(&mut self, timeout: Duration) -> Result<Vec<Output>> {
        self.qemu.qmp().wait_status("shutdown", timeout)?;
        self.restart_stopped(timeout)
    }

    /// Cuts the power now and brings it back: QEMU stops at once (a reset the harness asks
    /// for, held), then boots again as [`Board::reboot_after_reset`] does. RAM stays, so the
    /// emulated settings flash keeps what the cut left, as flash would. Returns the outputs
    /// that were on at the cut once the firmware has enabled its CNC port again.
    pub fn cut_power(&mut self, timeout: Duration) -> Result<Vec<Output>> {
        self.qemu.qmp().hold_guest_resets(true)?;
        self.qemu.qmp().execute("system_reset")?;
        self.qemu.qmp().wait_status("shutdown", timeout)?;
        self.restart_stopped(timeout)
    }

    /// From a stop at a reset: notes the outputs, resets the machine paused, drives the
    /// inputs again and starts the core.
    fn restart_stopped(&mut self, timeout: Duration) -> Result<Vec<Output>> {
        let mut on_at_reset = Vec::new();
        for output in Output::ALL {
            if self.output(output)? {
                on_at_reset.push(output);
            }
        }
        let mut start_on = [false; UNIT_SETS];
        for (unit, on) in start_on.iter_mut().enumerate() {
            *on = self.unit_output(unit, Output::Start)?;
        }
        self.resets.push(HeldReset {
            mark: self.qtest.edges().len(),
            at: Instant::now(),
            start_on,
        });
        self.qemu.qmp().reset_stopped(timeout)?;
        for pin in every_input().map(|(unit, input)| unit_input_pin(unit, input)) {
            if let Some(high) = self.qtest.driven_level(pin) {
                self.qtest.set_pin(pin, high)?;
            }
        }
        if self.user_button_held {
            self.qtest
                .set_pin(USER_BUTTON.pin, USER_BUTTON.level(true))?;
        }
        self.qemu.resume()?;
        wait_cnc_port_ready(&self.qtest)?;
        Ok(on_at_reset)
    }

    /// An output signal of the first unit now.
    pub fn output(&self, output: Output) -> Result<bool> {
        self.unit_output(0, output)
    }

    /// Unit `unit`'s output signal now.
    pub fn unit_output(&self, unit: usize, output: Output) -> Result<bool> {
        let high = self.qtest.output_level(unit_output_pin(unit, output))?;
        Ok(unit_output_active(unit, output, high))
    }

    /// Waits until the first unit's `output` is `on`; returns how long that took.
    pub fn wait_output(&self, output: Output, on: bool, timeout: Duration) -> Result<Duration> {
        self.wait_unit_output(0, output, on, timeout)
    }

    /// Waits until unit `unit`'s `output` is `on`; returns how long that took.
    pub fn wait_unit_output(
        &self,
        unit: usize,
        output: Output,
        on: bool,
        timeout: Duration,
    ) -> Result<Duration> {
        let began = Instant::now();
        loop {
            if self.unit_output(unit, output)? == on {
                return Ok(began.elapsed());
            }
            if began.elapsed() > timeout {
                return Err(Error::Timeout(format!(
                    "unit {}'s {} still {} after {} ms",
                    unit + 1,
                    output.as_str(),
                    if on { "off" } else { "on" },
                    timeout.as_millis()
                )));
            }
            std::thread::sleep(POLL);
        }
    }

    /// Waits `duration` and checks that the first unit's `output` was `on` all along: its
    /// level at both ends and, for an output on the watched port, no edge in between.
    pub fn expect_held(&self, output: Output, on: bool, duration: Duration) -> Result<()> {
        self.expect_unit_held(0, output, on, duration)
    }

    /// [`Board::expect_held`] for unit `unit`'s `output`.
    pub fn expect_unit_held(
        &self,
        unit: usize,
        output: Output,
        on: bool,
        duration: Duration,
    ) -> Result<()> {
        let pin = unit_output_pin(unit, output);
        let mark = self.qtest.edges().len();
        let state = |now: bool| if now { "on" } else { "off" };
        if self.unit_output(unit, output)? != on {
            return Err(Error::Protocol(format!(
                "{} is {} (expected {} for {} ms)",
                output.as_str(),
                state(!on),
                state(on),
                duration.as_millis()
            )));
        }
        let began = Instant::now();
        std::thread::sleep(duration);
        let level = self.unit_output(unit, output)?;
        let edges = self.qtest.edges();
        let changed = edges
            .get(mark..)
            .unwrap_or(&[])
            .iter()
            .find(|e| e.pin == pin);
        if level != on || changed.is_some() {
            return Err(Error::Protocol(format!(
                "{} did not stay {} for {} ms (changed {} ms into it)",
                output.as_str(),
                state(on),
                duration.as_millis(),
                changed.map_or(duration.as_millis(), |e| {
                    e.at.saturating_duration_since(began).as_millis()
                })
            )));
        }
        Ok(())
    }

    /// Edges of the first unit's `output` (on the watched port) so far, with the host time
    /// they were read.
    pub fn edges(&self, output: Output) -> Vec<(Instant, bool)> {
        self.unit_edges(0, output)
    }

    /// Edges of unit `unit`'s `output` (on the watched port) so far.
    pub fn unit_edges(&self, unit: usize, output: Output) -> Vec<(Instant, bool)> {
        let pin = unit_output_pin(unit, output);
        self.qtest
            .edges()
            .into_iter()
            .filter(|e| e.pin == pin)
            .map(|e| (e.at, unit_output_active(unit, output, e.high)))
            .collect()
    }

    /// Sends a CNC command and returns its reply (events on the way are kept).
    pub fn command(&mut self, line: &str, timeout: Duration) -> Result<String> {
        self.cnc.command(line, timeout)
    }

    /// Asks `STATUS` every 100 ms until `pred` holds for its reply; returns that reply.
    pub fn wait_status(
        &mut self,
        timeout: Duration,
        mut pred: impl FnMut(&str) -> bool,
    ) -> Result<String> {
        let began = Instant::now();
        loop {
            let reply = self.cnc.command("STATUS", timeout)?;
            if pred(&reply) {
                return Ok(reply);
            }
            if began.elapsed() > timeout {
                return Err(Error::Timeout(format!(
                    "STATUS never matched in {} ms; last: {reply}",
                    timeout.as_millis()
                )));
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// The safety rules broken so far by any unit (see [`super::safety`]; each unit set's
    /// START against its own TORCH_ON), a unit beyond the first named.
    pub fn safety_violations(&self) -> Vec<String> {
        let mut broken = self.unit_safety_violations(0);
        for unit in 1..UNIT_SETS {
            let of_unit = self.unit_safety_violations(unit);
            broken.extend(
                of_unit
                    .into_iter()
                    .map(|v| format!("unit {}: {v}", unit + 1)),
            );
        }
        broken
    }

    /// The safety rules unit `unit`'s set broke so far.
    fn unit_safety_violations(&self, unit: usize) -> Vec<String> {
        let driven: Vec<Driven> = lock(&self.driven)
            .iter()
            .filter(|d| d.unit == unit)
            .copied()
            .collect();
        let start = unit_output_pin(unit, Output::Start);
        let edges = self.qtest.edges();
        let torch_at_power_up = driven
            .iter()
            .find(|d| d.input == Input::TorchOn)
            .is_some_and(|d| d.active);
        let mut observed = Vec::new();
        // TORCH_ON changes and resets, each before the edges QEMU sent after it.
        let mut between: Vec<(usize, Observed)> = driven
            .iter()
            .filter(|d| d.input == Input::TorchOn)
            .skip(1)
            .map(|d| {
                let torch = Observed::TorchOn {
                    at: d.at,
                    active: d.active,
                };
                (d.mark, torch)
            })
            .chain(self.resets.iter().map(|r| {
                let reset = Observed::Reset {
                    at: r.at,
                    start_on: r.start_on.get(unit).copied().unwrap_or(false),
                };
                (r.mark, reset)
            }))
            .collect();
        between.sort_by_key(|&(mark, o)| (mark, o.at()));
        let mut inputs = between.into_iter().peekable();
        for (index, edge) in edges.iter().enumerate() {
            while let Some((_, o)) = inputs.next_if(|&(mark, _)| mark <= index) {
                observed.push(o);
            }
            if edge.pin == start {
                observed.push(Observed::Start {
                    at: edge.at,
                    on: unit_output_active(unit, Output::Start, edge.high),
                });
            }
        }
        observed.extend(inputs.map(|(_, o)| o));
        safety::check(
            self.epoch,
            torch_at_power_up,
            self.start_at_power_up.get(unit).copied().unwrap_or(false),
            &observed,
        )
    }

    /// Fails (with the diagnostics) when a safety rule was broken.
    pub fn assert_safe(&self) {
        let broken = self.safety_violations();
        assert!(
            broken.is_empty(),
            "safety rules broken:\n{}\n{}",
            broken.join("\n"),
            self.diagnostics()
        );
    }

    /// Everything that explains a failure: the firmware log, the CNC transcript, the PS
    /// traffic, the discrete I/O, QEMU's stderr.
    pub fn diagnostics(&self) -> String {
        let mut text = String::new();
        text.push_str(&format!(
            "==== emulated board against a simulated {} (image {})\n",
            self.options.model,
            self.elf.display()
        ));
        text.push_str("---- firmware log (last 80 lines)\n");
        text.push_str(&self.log.tail(80));
        text.push_str("---- CNC port\n");
        text.push_str(&self.cnc.transcript(self.epoch));
        text.push_str("---- PS port (last 30 frames, times from the unit's start)\n");
        text.push_str(&self.sim.trace().tail(30));
        if let Some(why) = self.sim.stopped() {
            text.push_str(&format!("(the simulated unit stopped: {why})\n"));
        }
        text.push_str("---- discrete I/O (host ms)\n");
        let ms = |at: Instant| at.saturating_duration_since(self.epoch).as_secs_f64() * 1000.0;
        for d in lock(&self.driven).iter().filter(|d| d.at > self.epoch) {
            text.push_str(&format!(
                "{:>10.3} ms {}{} {}\n",
                ms(d.at),
                unit_prefix(d.unit),
                d.input.as_str(),
                if d.active { "active" } else { "inactive" }
            ));
        }
        for r in &self.resets {
            text.push_str(&format!(
                "{:>10.3} ms the MCU reset (after {} output edges), START {:?}\n",
                ms(r.at),
                r.mark,
                r.start_on
            ));
        }
        for e in self.qtest.edges() {
            let name = UnitSet::ALL
                .into_iter()
                .flat_map(|set| Output::ALL.map(|o| (set, o)))
                .find(|&(set, o)| set.output(o).pin == e.pin)
                .map_or_else(
                    || e.pin.to_string(),
                    |(set, o)| format!("{}{}", unit_prefix(set.index()), o.as_str()),
                );
            text.push_str(&format!(
                "{:>10.3} ms {name} -> {}\n",
                ms(e.at),
                if e.high { "high" } else { "low" }
            ));
        }
        let stderr = self.qemu.stderr();
        if !stderr.trim().is_empty() {
            text.push_str("---- QEMU stderr\n");
            text.push_str(&stderr);
        }
        text
    }
}

impl Drop for Board {
    fn drop(&mut self) {
        if std::thread::panicking() {
            // libtest shows a failing test's captured output: the whole story.
            eprintln!("{}", self.diagnostics());
            return;
        }
        let broken = self.safety_violations();
        if !broken.is_empty() {
            panic!(
                "safety rules broken:\n{}\n{}",
                broken.join("\n"),
                self.diagnostics()
            );
        }
    }
}

/// Waits until the firmware has enabled USART2's receiver and its interrupt: bytes sent to
/// the CNC port before that are lost, as on a board.
fn wait_cnc_port_ready(qtest: &Qtest) -> Result<()> {
    const USART2_CR1: u64 = 0x4000_4400;
    const READY: u32 = 1 << 0 | 1 << 2 | 1 << 5; // UE, RE, RXNEIE
    let began = Instant::now();
    while qtest.readl(USART2_CR1)? & READY != READY {
        if began.elapsed() > CNC_READY_TIMEOUT {
            return Err(Error::Timeout(format!(
                "the firmware did not enable its CNC port (USART2) in {} s",
                CNC_READY_TIMEOUT.as_secs()
            )));
        }
        std::thread::sleep(POLL);
    }
    Ok(())
}

/// Every unit set's input signals, a board-wide one once (with the first unit).
fn every_input() -> impl Iterator<Item = (usize, Input)> {
    UnitSet::ALL.into_iter().flat_map(|set| {
        Input::ALL
            .into_iter()
            .filter(move |&i| {
                set.index() == 0 || !plasma_firmware::platform::pins::is_board_wide(i)
            })
            .map(move |i| (set.index(), i))
    })
}

/// How the diagnostics name a signal's unit: nothing for the first, `@N ` for another (as the
/// CNC port addresses it).
fn unit_prefix(unit: usize) -> String {
    if unit == 0 {
        String::new()
    } else {
        format!("@{} ", unit + 1)
    }
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}
