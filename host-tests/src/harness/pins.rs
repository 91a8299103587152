//! One unit's discrete I/O in the [`World`](super::World): its interlocks, the levels at its
//! input pins as the harness drives them, and its own independent safety monitors.
//!
//! A world has one set per simulated unit (several on a multi-drop line): each set hears only
//! what concerns its unit (its TORCH_ON, its unit's MOTION, its unit's supply state) and its
//! monitors check only its START, so unit 2's TORCH_ON starting unit 1, or one unit's fault
//! blocking another's START, is a broken rule of that unit.

use plasma_firmware::io::{
    Input, Inputs, Interlocks, IoConfig, IoEvent, SafetyMonitor, SupplyState, Transition,
};
use plasma_protocol::time::Instant;

/// One unit's discrete I/O. See the [module docs](self).
pub(super) struct UnitPins {
    pub(super) io: Interlocks,
    /// The input levels at the board's pins, as driven: what the monitors and a reset see,
    /// kept apart from the interlocks' own view.
    pub(super) pins_in: Inputs,
    pub(super) monitor: SafetyMonitor,
    /// A second monitor started at the last bridge reset: the power-up rules (START off at
    /// reset, a held TORCH_ON ignored) apply again from there.
    pub(super) reset_monitor: Option<SafetyMonitor>,
    pub(super) transitions: Vec<Transition>,
    pub(super) io_events: Vec<(Instant, IoEvent)>,
    pub(super) start_given: bool,
    /// HOLD and CORNER_CURRENT as last given to an HPR simulator.
    pub(super) hpr_inputs_given: (bool, bool),
    /// REMOTE_POWER as last seen, and whether its falling edge switched the unit off.
    pub(super) remote_power_given: bool,
    pub(super) off_by_remote_power: bool,
    pub(super) last_supply: SupplyState,
}

impl UnitPins {
    /// A set from power-up at time zero, every input low.
    pub(super) fn new(config: IoConfig) -> Self {
        UnitPins {
            io: Interlocks::new(config, Instant::ZERO, Inputs::NONE),
            pins_in: Inputs::NONE,
            monitor: power_up_monitor(&config, Inputs::NONE),
            reset_monitor: None,
            transitions: Vec::new(),
            io_events: Vec::new(),
            start_given: false,
            hpr_inputs_given: (false, false),
            remote_power_given: false,
            off_by_remote_power: false,
            last_supply: SupplyState::default(),
        }
    }

    /// An edge at one of this unit's input pins at `now`: the monitors see it as it arrives,
    /// then the interlocks get it.
    pub(super) fn drive_input(&mut self, now: Instant, input: Input, on: bool) {
        self.pins_in.set(input, on);
        self.each_monitor(|m| m.input(input, on));
        self.io.on_input(now, input, on);
    }

    /// The bridge's board restarts at `now`: the interlocks from reset with `config` and the
    /// levels at the pins, a fresh power-up monitor beside the one that watched from the start.
    pub(super) fn reset(&mut self, now: Instant, config: IoConfig) {
        while let Some(t) = self.io.poll_transition() {
            self.transitions.push(t);
        }
        self.io = Interlocks::new(config, now, self.pins_in);
        self.last_supply = SupplyState::default();
        self.reset_monitor = Some(power_up_monitor(&config, self.pins_in));
    }

    /// A new interlock configuration at `now` (after `CONFIG <io key>`). The world's pins are
    /// the CNC's meaning: a change of TORCH_ON's wiring keeps the level and re-arms the
    /// power-up rule, as DiscreteIo does on the board.
    pub(super) fn reconfigure(&mut self, now: Instant, config: IoConfig) {
        let torch_on = |c: &IoConfig| c.inputs.get(Input::TorchOn);
        let level = self.pins_in.torch_on;
        if torch_on(self.io.config()) != torch_on(&config) {
            self.io.rearm_torch_on(now, level);
            self.each_monitor(|m| m.torch_on_redefined(level));
        }
        self.each_monitor(|m| m.ready_interlock(config.ready_required));
        self.io.set_config(now, config);
    }

    /// The unit's supply as its link sees it at `now`: to the monitors always, to the
    /// interlocks when it changed.
    pub(super) fn supply(&mut self, now: Instant, supply: SupplyState) {
        self.each_monitor(|m| m.link_reports(supply.link_up, supply.unit_ready));
        if supply != self.last_supply {
            self.io.on_supply(now, supply);
            self.last_supply = supply;
        }
    }

    /// The monitors check START (as given to the unit) at `now`.
    pub(super) fn check(&mut self, now: Instant) {
        let start = self.start_given;
        let blackout = self.last_supply.restart_blackout_until;
        self.each_monitor(|m| m.check(now, start, blackout));
    }

    /// The first broken rule of this unit's monitors, described.
    pub(super) fn violation(&self) -> Option<String> {
        if let Some(monitor) = self.reset_monitor.as_ref().filter(|m| !m.is_clean()) {
            return Some(format!(
                "safety rule broken after the bridge reset ({} times): {:?}",
                monitor.count(),
                monitor.violations()
            ));
        }
        (!self.monitor.is_clean()).then(|| {
            format!(
                "safety rule broken ({} times): {:?}",
                self.monitor.count(),
                self.monitor.violations()
            )
        })
    }

    fn each_monitor(&mut self, mut f: impl FnMut(&mut SafetyMonitor)) {
        f(&mut self.monitor);
        if let Some(monitor) = &mut self.reset_monitor {
            f(monitor);
        }
    }
}

/// A monitor watching from a power-up with these settings and input levels: the operator's
/// ready interlock as saved, NOT_READY as it reads at the pin.
fn power_up_monitor(io: &IoConfig, pins_in: Inputs) -> SafetyMonitor {
    let mut monitor = SafetyMonitor::new(pins_in.torch_on);
    monitor.ready_interlock(io.ready_required);
    monitor.input(Input::NotReady, pins_in.not_ready);
    monitor
}
