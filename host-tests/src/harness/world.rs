//! The discrete-event loop: bridge endpoint <-> [`Line`] <-> [`SimulatedUnit`], plus the
//! discrete I/O and the safety monitor, in virtual time.

use std::fmt;

use plasma_firmware::io::{Input, Interlocks, IoConfig, IoEvent, SafetyMonitor, Transition};
use plasma_firmware::link::{
    CommandFailure, CommandOutput, LinkCommand, LinkEvent, PsLink, Refusal, Ticket,
};
use plasma_firmware::platform::runner::MAX_FRAMES_PER_TURN;
use plasma_protocol::time::{Duration, Instant};

use super::endpoint::WorldEndpoint;
use super::options::{RxErrors, WorldOptions};
use super::pins::UnitPins;
use super::trace::{Direction, TraceFrame, WireTrace};
use plasma_sim::hpr::Hpr;
use plasma_sim::line::{End, Line};
use plasma_sim::multidrop::MultiDrop;
use plasma_sim::{Model, SimulatedUnit};

/// Times the loop processes one instant again because something still asks for it; beyond
/// this the request is stale and the loop moves on (and counts it).
const MAX_REPEATS_AT_ONE_INSTANT: u32 = 2;

/// While the endpoint keeps asking for an instant already processed, a board's task loop
/// would spin; the loop models that spin as a call every millisecond, so whatever the
/// endpoint does when time passes still happens (at most this late).
const BUSY_LOOP_TICK: Duration = Duration::from_millis(1);

/// A wait ran out of virtual time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timeout {
    /// Virtual time when the wait gave up.
    pub at: Instant,
    /// How long it waited.
    pub waited: Duration,
}

impl fmt::Display for Timeout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "gave up at {} ms after waiting {} ms",
            self.at.as_millis(),
            self.waited.as_millis()
        )
    }
}

impl std::error::Error for Timeout {}

/// Counters of the event loop itself.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WorldStats {
    /// Instants processed.
    pub steps: u64,
    /// Steps taken because a wake-up time at or before the current instant was still asked
    /// for after the instant had been processed: on a board, a busy loop. Each counts one
    /// millisecond of spinning. A world whose count is not 0 panics when dropped.
    pub stale_wakeups: u64,
}

/// One simulated installation. See the [module docs](super).
pub struct World<E: WorldEndpoint = PsLink> {
    now: Instant,
    endpoint: E,
    unit: Box<dyn SimulatedUnit>,
    line: Line,
    /// Each simulated unit's discrete I/O (one set per unit of a [`MultiDrop`]), the first
    /// unit's first.
    pins: Vec<UnitPins>,
    rx_errors: RxErrors,
    events: Vec<(Instant, LinkEvent)>,
    trace: WireTrace,
    heard: Vec<(Instant, u8)>,
    noise_bursts: Vec<(Instant, Duration)>,
    scratch: Vec<LinkEvent>,
    repeats: u32,
    stats: WorldStats,
}

impl World<PsLink> {
    /// A bare [`PsLink`] (configured by `options.link`) against a simulated `model`.
    pub fn new(model: Model, options: WorldOptions) -> Self {
        let unit = model.build(&options.sim);
        Self::with_unit(unit, options)
    }

    /// A bare [`PsLink`] against a simulator built by the caller (custom configuration).
    pub fn with_unit(unit: Box<dyn SimulatedUnit>, options: WorldOptions) -> Self {
        let link = PsLink::new(options.link, Instant::ZERO);
        Self::with_endpoint(link, unit, options)
    }

    /// The link.
    pub fn link(&self) -> &PsLink {
        &self.endpoint
    }

    /// Submit a command to the link now.
    pub fn submit(&mut self, command: LinkCommand<'_>) -> Result<Ticket, Refusal> {
        let now = self.now;
        let ticket = self.endpoint.submit(now, command)?;
        // Events of the submit (e.g. an immediate answer) belong to this instant.
        self.process();
        Ok(ticket)
    }

    /// Run until `ticket` completes (or has completed), returning its result.
    pub fn wait_command(
        &mut self,
        ticket: Ticket,
        timeout: Duration,
    ) -> Result<Result<CommandOutput, CommandFailure>, Timeout> {
        let find = |w: &World<PsLink>| {
            w.events.iter().find_map(|(_, e)| match e {
                LinkEvent::CommandDone { ticket: t, result } if *t == ticket => Some(*result),
                _ => None,
            })
        };
        self.run_until(|w| find(w).is_some(), timeout)?;
        Ok(find(self).expect("found by run_until"))
    }

    /// Submit and wait for the result; panics on a refusal or a time-out.
    pub fn command(
        &mut self,
        command: LinkCommand<'_>,
        timeout: Duration,
    ) -> Result<CommandOutput, CommandFailure> {
        let ticket = self
            .submit(command)
            .unwrap_or_else(|r| panic!("{command:?} refused: {r:?}"));
        self.wait_command(ticket, timeout).unwrap_or_else(|t| {
            panic!("{command:?} did not complete: {t}\n{}", self.trace.tail(20))
        })
    }
}

impl<E: WorldEndpoint> World<E> {
    /// Any endpoint against a simulator; the world starts at time zero.
    pub fn with_endpoint(endpoint: E, unit: Box<dyn SimulatedUnit>, options: WorldOptions) -> Self {
        let master_port = endpoint.ps_port_config();
        let mut line = Line::new(master_port, unit.port(), options.wiring, options.seed);
        line.set_corrupt_probability(options.corrupt_probability);
        line.set_drop_probability(options.drop_probability);
        if let Some(density) = options.noise_density {
            line.set_noise_density(density);
        }
        let units = unit
            .as_any()
            .downcast_ref::<MultiDrop>()
            .map_or(1, MultiDrop::len);
        let mut world = World {
            now: Instant::ZERO,
            endpoint,
            unit,
            line,
            pins: (0..units).map(|_| UnitPins::new(options.io)).collect(),
            rx_errors: options.rx_errors,
            events: Vec::new(),
            trace: WireTrace::default(),
            heard: Vec::new(),
            noise_bursts: Vec::new(),
            scratch: Vec::new(),
            repeats: 0,
            stats: WorldStats::default(),
        };
        world.process();
        world
    }

    // --- time ----------------------------------------------------------------------------

    /// Virtual time now.
    pub fn now(&self) -> Instant {
        self.now
    }

    /// Run for `duration` of virtual time.
    pub fn run_for(&mut self, duration: Duration) {
        let target = self.now + duration;
        while self.step(target) {}
        self.assert_safe();
    }

    /// Run until `pred` holds (checked now and after every step), at most `timeout`.
    pub fn run_until(
        &mut self,
        mut pred: impl FnMut(&Self) -> bool,
        timeout: Duration,
    ) -> Result<Instant, Timeout> {
        let began = self.now;
        let deadline = self.now + timeout;
        if pred(self) {
            return Ok(self.now);
        }
        loop {
            let more = self.step(deadline);
            if pred(self) {
                self.assert_safe();
                return Ok(self.now);
            }
            if !more {
                self.assert_safe();
                return Err(Timeout {
                    at: self.now,
                    waited: self.now.saturating_since(began),
                });
            }
        }
    }

    /// Act on the endpoint at the current instant (e.g. hand it CNC bytes), then let the
    /// world react at this instant.
    pub fn drive<R>(&mut self, act: impl FnOnce(&mut E, Instant) -> R) -> R {
        let now = self.now;
        let result = act(&mut self.endpoint, now);
        self.process();
        result
    }

    /// The earliest instant at which something is due (a real-time driver sleeps until
    /// then).
    pub fn next_wakeup(&self) -> Option<Instant> {
        self.wakeups().min()
    }

    /// The bridge's board restarts now: `reset` rebuilds the endpoint (keeping whatever
    /// survives a power cycle), every unit's interlocks start again from reset with `io` and
    /// the input levels of this moment (a TORCH_ON held through the reset is ignored until
    /// released), and the power-up safety rules are checked again from here.
    pub fn reset_bridge(&mut self, io: IoConfig, reset: impl FnOnce(&mut E, Instant)) {
        let now = self.now;
        reset(&mut self.endpoint, now);
        for pins in &mut self.pins {
            pins.reset(now, io);
        }
        self.process();
    }

    /// Run until an event after this call matches `pred`; returns it with its time.
    pub fn wait_event(
        &mut self,
        mut pred: impl FnMut(&LinkEvent) -> bool,
        timeout: Duration,
    ) -> Result<(Instant, LinkEvent), Timeout> {
        let mark = self.events.len();
        let found = |w: &Self, pred: &mut dyn FnMut(&LinkEvent) -> bool| {
            w.events[mark..].iter().find(|(_, e)| pred(e)).copied()
        };
        self.run_until(|w| found(w, &mut pred).is_some(), timeout)?;
        Ok(found(self, &mut pred).expect("found by run_until"))
    }

    /// Run until the link reports itself up.
    pub fn wait_link_up(&mut self, timeout: Duration) -> Result<Instant, Timeout> {
        self.run_until(|w| w.endpoint.status().link_up, timeout)
    }

    // --- the discrete I/O -------------------------------------------------------------------

    /// Drive the CNC's TORCH_ON input (the first unit's).
    pub fn set_torch(&mut self, on: bool) {
        self.set_torch_of(0, on);
    }

    /// Drive unit `unit`'s TORCH_ON input (0 = the first unit).
    pub fn set_torch_of(&mut self, unit: usize, on: bool) {
        self.set_input_of(unit, Input::TorchOn, on);
    }

    /// Drive another CNC input (HOLD, CORNER_CURRENT...) of the first unit.
    pub fn set_input(&mut self, input: Input, on: bool) {
        self.set_input_of(0, input, on);
    }

    /// Drive an input of unit `unit`'s set.
    pub fn set_input_of(&mut self, unit: usize, input: Input, on: bool) {
        self.drive_input(unit, input, on);
        self.process();
    }

    /// An edge at unit `unit`'s input pin now (ignored for a unit the world does not have).
    fn drive_input(&mut self, unit: usize, input: Input, on: bool) {
        let now = self.now;
        if let Some(pins) = self.pins.get_mut(unit) {
            pins.drive_input(now, input, on);
        }
    }

    /// How many sets of discrete I/O the world has: one per simulated unit.
    pub fn pin_sets(&self) -> usize {
        self.pins.len()
    }

    fn pins(&self, unit: usize) -> &UnitPins {
        self.pins
            .get(unit)
            .unwrap_or_else(|| panic!("no unit {unit}: the world has {}", self.pins.len()))
    }

    /// The interlocks (the first unit's).
    pub fn io(&self) -> &Interlocks {
        self.io_of(0)
    }

    /// Unit `unit`'s interlocks.
    pub fn io_of(&self, unit: usize) -> &Interlocks {
        &self.pins(unit).io
    }

    /// Every output change of the (first unit's) interlocks so far.
    pub fn transitions(&self) -> &[Transition] {
        self.transitions_of(0)
    }

    /// Every output change of unit `unit`'s interlocks so far.
    pub fn transitions_of(&self, unit: usize) -> &[Transition] {
        &self.pins(unit).transitions
    }

    /// Every discrete I/O event (of the first unit) so far.
    pub fn io_events(&self) -> &[(Instant, IoEvent)] {
        self.io_events_of(0)
    }

    /// Every discrete I/O event of unit `unit` so far.
    pub fn io_events_of(&self, unit: usize) -> &[(Instant, IoEvent)] {
        &self.pins(unit).io_events
    }

    /// The (first unit's) safety monitor (checked after every step).
    pub fn monitor(&self) -> &SafetyMonitor {
        self.monitor_of(0)
    }

    /// Unit `unit`'s own safety monitor, fed only that unit's pins and supply state.
    pub fn monitor_of(&self, unit: usize) -> &SafetyMonitor {
        &self.pins(unit).monitor
    }

    /// Panics when a safety rule was broken, of any unit.
    pub fn assert_safe(&self) {
        for (unit, pins) in self.pins.iter().enumerate() {
            if let Some(violation) = pins.violation() {
                let which = match self.pins.len() {
                    1 => String::new(),
                    _ => format!("unit {}: ", unit + 1),
                };
                panic!("{which}{violation}\nlast frames:\n{}", self.trace.tail(20));
            }
        }
    }

    // --- the unit and the line ------------------------------------------------------------

    /// The simulated unit.
    pub fn unit(&mut self) -> &mut dyn SimulatedUnit {
        &mut *self.unit
    }

    /// The simulated unit, read-only.
    pub fn unit_ref(&self) -> &dyn SimulatedUnit {
        &*self.unit
    }

    /// The concrete simulator (e.g. [`plasma_sim::powermax::Powermax`]).
    pub fn sim<T: 'static>(&mut self) -> &mut T {
        self.unit
            .as_any_mut()
            .downcast_mut::<T>()
            .expect("the simulator is not of this type")
    }

    /// The concrete simulator, read-only.
    pub fn sim_ref<T: 'static>(&self) -> &T {
        self.unit
            .as_any()
            .downcast_ref::<T>()
            .expect("the simulator is not of this type")
    }

    /// The unit's gas supply delivers at most `psi` from now on (`None`: ample): a Powermax's
    /// actual pressure, an HPR's measured pressures stay below it.
    pub fn set_gas_supply(&mut self, psi: Option<u16>) {
        let unit = self.unit.as_any_mut();
        if let Some(powermax) = unit.downcast_mut::<plasma_sim::powermax::Powermax>() {
            powermax.set_supply_psi(psi);
        } else if let Some(hpr) = unit.downcast_mut::<plasma_sim::hpr::Hpr>() {
            hpr.set_supply_psi(psi);
        } else {
            panic!("the simulator has no gas supply");
        }
    }

    /// Raise a fault on the unit now (Powermax decimal code, HPR error id).
    pub fn inject_fault(&mut self, code: u16) {
        let now = self.now;
        self.unit.inject_fault(now, code);
        self.process();
    }

    /// Clear the unit's fault now.
    pub fn clear_fault(&mut self) {
        let now = self.now;
        self.unit.clear_fault(now);
        self.process();
    }

    /// Switch the unit off now (it neither hears nor sends).
    pub fn power_off(&mut self) {
        let now = self.now;
        self.unit.power_off(now);
        self.line.set_unit_powered(now, false);
        self.process();
    }

    /// Switch the unit on now.
    pub fn power_on(&mut self) {
        let now = self.now;
        self.line.set_unit_powered(now, true);
        self.unit.power_on(now);
        self.process();
    }

    /// Pull the unit's serial cable now (`true`) or plug it back: the unit stays powered and
    /// keeps its state (remote control, settings), it only neither hears nor is heard. Unlike
    /// [`World::power_off`], which the unit forgets its state through.
    pub fn pull_cable(&mut self, pulled: bool) {
        let now = self.now;
        self.line.set_unit_powered(now, !pulled);
        self.process();
    }

    /// Electrical noise on the line from now on (independent of the unit's own bursts).
    pub fn add_noise(&mut self, length: Duration) {
        let now = self.now;
        self.line.add_noise_burst(now, length);
        self.noise_bursts.push((now, length));
        self.process();
    }

    /// The line.
    pub fn line(&self) -> &Line {
        &self.line
    }

    /// The line, to change fault injection mid-run.
    pub fn line_mut(&mut self) -> &mut Line {
        &mut self.line
    }

    /// Noise bursts so far (the unit's HF ignition and [`World::add_noise`]).
    pub fn noise_bursts(&self) -> &[(Instant, Duration)] {
        &self.noise_bursts
    }

    // --- the bridge side ------------------------------------------------------------------

    /// The endpoint.
    pub fn endpoint(&self) -> &E {
        &self.endpoint
    }

    /// The endpoint, mutable (commands through its own API).
    pub fn endpoint_mut(&mut self) -> &mut E {
        &mut self.endpoint
    }

    /// Link events so far, with the instant they were drained.
    pub fn events(&self) -> &[(Instant, LinkEvent)] {
        &self.events
    }

    /// The wire trace.
    pub fn trace(&self) -> &WireTrace {
        &self.trace
    }

    /// Every character the endpoint was handed, with the instant (what the bridge actually
    /// heard, after the line's damage; the trace holds what was sent).
    pub fn heard(&self) -> &[(Instant, u8)] {
        &self.heard
    }

    /// The characters the endpoint was handed in `[from, to)`.
    pub fn heard_between(&self, from: Instant, to: Instant) -> Vec<u8> {
        self.heard
            .iter()
            .filter(|(t, _)| *t >= from && *t < to)
            .map(|&(_, b)| b)
            .collect()
    }

    /// Loop counters.
    pub fn stats(&self) -> WorldStats {
        self.stats
    }

    // --- the loop -------------------------------------------------------------------------

    /// Every instant something asked to be called at: the endpoint, the line, the
    /// simulator, each unit's interlocks.
    fn wakeups(&self) -> impl Iterator<Item = Instant> + '_ {
        [
            self.endpoint.poll_at(),
            self.line.next_delivery(),
            self.unit.next_wakeup(),
        ]
        .into_iter()
        .chain(self.pins.iter().map(|p| p.io.poll_at()))
        .flatten()
    }

    /// Process the next instant at which something happens, if it is not after `limit`;
    /// otherwise move to `limit`, process it and return false.
    fn step(&mut self, limit: Instant) -> bool {
        let mut next = self.wakeups().min();
        if next.is_some_and(|t| t <= self.now) {
            if self.repeats >= MAX_REPEATS_AT_ONE_INSTANT {
                self.stats.stale_wakeups += 1;
                let spin = self
                    .endpoint
                    .poll_at()
                    .filter(|&t| t <= self.now)
                    .map(|_| self.now + BUSY_LOOP_TICK);
                next = self.wakeups().filter(|&t| t > self.now).chain(spin).min();
            } else {
                self.repeats += 1;
            }
        }
        match next {
            Some(t) if t <= limit => {
                self.move_to(t);
                self.process();
                true
            }
            _ => {
                self.move_to(limit);
                self.process();
                false
            }
        }
    }

    fn move_to(&mut self, t: Instant) {
        if t > self.now {
            self.now = t;
            self.repeats = 0;
        }
    }

    /// Everything due at `self.now`, in causal order: the unit hears and answers, the bridge
    /// hears and transmits, the discrete I/O follows, the safety rules are checked.
    fn process(&mut self) {
        let now = self.now;
        self.stats.steps += 1;

        // The unit side.
        self.unit.advance(now);
        self.take_unit_noise();
        for b in self.line.receive(End::Unit, now) {
            match b.error {
                None => self.unit.receive(b.at, b.byte),
                Some(_) => self.unit.receive_error(b.at),
            }
        }
        if let Some(bytes) = self.unit.poll_transmit(now) {
            self.send(End::Unit, &bytes);
        }
        self.take_unit_noise();
        // Each unit's Motion output to its own set's MOTION input.
        for index in 0..self.pins.len() {
            let motion = unit_on_line(&mut *self.unit, index).is_some_and(|u| u.motion());
            if motion != self.pins[index].pins_in.motion {
                self.drive_input(index, Input::Motion, motion);
            }
        }

        // The bridge side.
        // In order: runs of characters, and (when reported) the flagged ones in their place.
        let mut chunk: Vec<u8> = Vec::new();
        for b in self.line.receive(End::Master, now) {
            let byte = match (b.error, self.rx_errors) {
                (None, _) | (Some(_), RxErrors::Deliver) => Some(b.byte),
                (Some(_), RxErrors::Drop) => None,
                (Some(_), RxErrors::Substitute) => Some(0),
                (Some(_), RxErrors::Report) => {
                    self.hand_over(now, &mut chunk);
                    self.endpoint.handle_ps_rx_error(now);
                    None
                }
            };
            chunk.extend(byte);
        }
        self.hand_over(now, &mut chunk);
        // Asking for a frame polls the endpoint; its events are drained after the frames.
        for _ in 0..MAX_FRAMES_PER_TURN {
            self.apply_master_port();
            let Some(frame) = self.endpoint.poll_ps_transmit(now).map(<[u8]>::to_vec) else {
                break;
            };
            // The link may switch the port while choosing the frame (auto-detection).
            self.apply_master_port();
            let end = self.send(End::Master, &frame);
            // The line model knows when the last stop bit leaves: the reply time-out runs
            // from there, as on the board (the runner reports the end of its flush).
            self.endpoint.ps_transmitted(end);
        }
        self.drain_endpoint();

        // What the endpoint asks of the machine: a simulator-only TORCH_ON level, a new
        // interlock configuration (one for every unit's set).
        while let Some((unit, on)) = self.endpoint.poll_torch_request() {
            self.drive_input(unit, Input::TorchOn, on);
        }
        if let Some(config) = self.endpoint.take_io_config_change() {
            for pins in &mut self.pins {
                pins.reconfigure(now, config);
            }
        }

        // Each unit's discrete I/O, from its link's view at this instant.
        for index in 0..self.pins.len() {
            self.step_unit_io(index);
        }
        self.assert_safe();
    }

    /// Unit `index`'s interlocks follow its supply state; its START drives that unit alone,
    /// its events and levels go back to the endpoint as that unit's, its monitors check it.
    fn step_unit_io(&mut self, index: usize) {
        let now = self.now;
        let supply = self.endpoint.supply_state_of(index);
        let pins = &mut self.pins[index];
        pins.supply(now, supply);
        pins.io.poll(now);
        let start = pins.io.outputs().start;
        if start != pins.start_given {
            if let Some(unit) = unit_on_line(&mut *self.unit, index) {
                unit.set_start(now, start);
            }
            pins.start_given = start;
        }
        self.pass_through_to_hpr(index);
        self.follow_remote_power(index);
        let pins = &mut self.pins[index];
        while let Some(t) = pins.io.poll_transition() {
            pins.transitions.push(t);
        }
        while let Some(e) = pins.io.poll_event() {
            self.endpoint.on_io_event_of(index, now, e);
            pins.io_events.push((now, e));
        }
        self.endpoint
            .set_io_snapshot_of(index, pins.io.inputs(), pins.io.outputs());
        pins.check(now);
    }

    /// Hand the characters in `chunk` to the endpoint (and log them as heard).
    fn hand_over(&mut self, now: Instant, chunk: &mut Vec<u8>) {
        if chunk.is_empty() {
            return;
        }
        self.heard.extend(chunk.iter().map(|&b| (now, b)));
        self.endpoint.handle_ps_rx(now, chunk);
        chunk.clear();
    }

    fn apply_master_port(&mut self) {
        let port = self.endpoint.ps_port_config();
        if self.line.port(End::Master) != port {
            self.line.set_port(End::Master, port);
        }
    }

    /// Puts `bytes` on the line from `from`; returns when its last stop bit has left.
    fn send(&mut self, from: End, bytes: &[u8]) -> Instant {
        let start = self.now.max(self.line.busy_until(from));
        let port = self.line.port(from);
        let end = self.line.transmit(from, self.now, bytes);
        let direction = match from {
            End::Master => Direction::ToUnit,
            End::Unit => Direction::ToBridge,
        };
        self.trace.push(TraceFrame {
            direction,
            start,
            end,
            port,
            bytes: bytes.to_vec(),
        });
        end
    }

    fn take_unit_noise(&mut self) {
        for (start, length) in self.unit.take_noise_bursts() {
            self.line.add_noise_burst(start, length);
            self.noise_bursts.push((start, length));
        }
    }

    fn drain_endpoint(&mut self) {
        let now = self.now;
        self.endpoint.poll(now, &mut self.scratch);
        for e in self.scratch.drain(..) {
            self.events.push((now, e));
        }
    }

    /// Unit `index`'s HOLD and CORNER_CURRENT to its HPR simulator (it has no
    /// PIERCE_COMPLETE input).
    fn pass_through_to_hpr(&mut self, index: usize) {
        let pins = &mut self.pins[index];
        let outputs = pins.io.outputs();
        let levels = (outputs.hold, outputs.corner_current);
        let given = pins.hpr_inputs_given;
        if levels == given {
            return;
        }
        pins.hpr_inputs_given = levels;
        let now = self.now;
        let hpr =
            unit_on_line(&mut *self.unit, index).and_then(|u| u.as_any_mut().downcast_mut::<Hpr>());
        if let Some(hpr) = hpr {
            if levels.0 != given.0 {
                hpr.set_hold(now, levels.0);
            }
            if levels.1 != given.1 {
                hpr.set_corner(now, levels.1);
            }
        }
    }

    /// Unit `index`'s Remote Power input wired to its REMOTE_POWER, edge by edge: the unit
    /// starts switched on by its operator (REMOTE_POWER is off from the bridge's reset), a
    /// falling edge switches it off and the next rising edge back on. A unit alone takes its
    /// end of the line with it; a unit on a multi-drop line falls silent by itself.
    fn follow_remote_power(&mut self, index: usize) {
        let pins = &mut self.pins[index];
        let on = pins.io.outputs().remote_power;
        if on == pins.remote_power_given {
            return;
        }
        pins.remote_power_given = on;
        let now = self.now;
        let alone = !self.unit.as_any().is::<MultiDrop>();
        if !on {
            pins.off_by_remote_power = true;
            if let Some(unit) = unit_on_line(&mut *self.unit, index) {
                unit.power_off(now);
            }
            if alone {
                self.line.set_unit_powered(now, false);
            }
        } else if core::mem::take(&mut pins.off_by_remote_power) {
            if alone {
                self.line.set_unit_powered(now, true);
            }
            if let Some(unit) = unit_on_line(&mut *self.unit, index) {
                unit.power_on(now);
            }
        }
    }
}

/// Simulated unit `index` of `unit`: a unit of a [`MultiDrop`], or a lone unit as unit 0.
fn unit_on_line(unit: &mut dyn SimulatedUnit, index: usize) -> Option<&mut dyn SimulatedUnit> {
    if unit.as_any().is::<MultiDrop>() {
        let line = unit.as_any_mut().downcast_mut::<MultiDrop>()?;
        return line.unit_mut(index).map(|u| u as &mut dyn SimulatedUnit);
    }
    (index == 0).then_some(unit)
}

impl<E: WorldEndpoint> Drop for World<E> {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            self.assert_safe();
            // On a board, a wake-up time that stays in the past is a busy loop.
            assert_eq!(
                self.stats.stale_wakeups,
                0,
                "the endpoint kept asking for a time already processed (busy loop)\n{}",
                self.trace.tail(10)
            );
        }
    }
}
