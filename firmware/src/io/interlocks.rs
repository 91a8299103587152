//! The START / ARC_OK / READY / FAULT state machine.

use heapless::Deque;

use super::config::IoConfig;
use super::debounce::Debouncer;
use super::reason::{Interlock, IoEvent, Reason, Transition};
use super::signals::{Input, Inputs, Output, Outputs, SupplyState};
use plasma_protocol::time::Instant;

/// Room for the transitions of several steps (one step changes at most 7 outputs).
const TRANSITION_QUEUE: usize = 32;
/// Room for the events of several steps.
const EVENT_QUEUE: usize = 16;

/// Where the START channel is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum StartPhase {
    /// TORCH_ON inactive.
    Idle,
    /// TORCH_ON active inside the gap after the last START; START follows at `until`.
    Delayed { until: Instant },
    /// START on.
    On {
        since: Instant,
        transferred: bool,
        timeout_reported: bool,
    },
    /// TORCH_ON active but refused or dropped; waits for TORCH_ON to be released.
    Locked(Interlock),
}

/// The bridge's discrete I/O logic, sans-IO: feed it input edges, link status and time; read
/// the output levels, the transition log and events.
///
/// Every entry point takes `now`; a `now` earlier than one already seen counts as the later
/// one (time never runs backwards here, so a gap cannot be shortened by a bad clock).
/// After any call, drain [`poll_transition`](Self::poll_transition) and
/// [`poll_event`](Self::poll_event), drive the pins from [`outputs`](Self::outputs), and call
/// [`poll`](Self::poll) again no later than [`poll_at`](Self::poll_at).
#[derive(Debug, Clone)]
pub struct Interlocks {
    config: IoConfig,
    now: Instant,
    inputs: Inputs,
    supply: SupplyState,
    /// The latest blackout end ever reported: a later report cannot shorten it.
    blackout_until: Option<Instant>,
    motion: Debouncer,
    phase: StartPhase,
    /// START's last falling edge; reset counts as one (START may have been on before a
    /// watchdog reset, and the supply's relays need the same time to settle).
    last_start_fall: Instant,
    outputs: Outputs,
    transitions: Deque<Transition, TRANSITION_QUEUE>,
    events: Deque<IoEvent, EVENT_QUEUE>,
    lost_transitions: u32,
    lost_events: u32,
}

impl Interlocks {
    /// Power-up: every output off, the link assumed down until
    /// [`on_supply`](Self::on_supply) says otherwise.
    ///
    /// A TORCH_ON already active in `initial_inputs` is ignored until seen inactive
    /// ([`IoEvent::StuckTorchOnAtPowerUp`]). The pass-through outputs and FAULT take their
    /// levels at once (logged as transitions from the all-off reset state).
    pub fn new(config: IoConfig, now: Instant, initial_inputs: Inputs) -> Self {
        let mut io = Interlocks {
            config,
            now,
            inputs: initial_inputs,
            supply: SupplyState::default(),
            blackout_until: None,
            motion: Debouncer::new(now, initial_inputs.motion),
            phase: StartPhase::Idle,
            last_start_fall: now,
            outputs: Outputs::OFF,
            transitions: Deque::new(),
            events: Deque::new(),
            lost_transitions: 0,
            lost_events: 0,
        };
        if initial_inputs.torch_on {
            io.phase = StartPhase::Locked(Interlock::TorchOnAtPowerUp);
            io.push_event(IoEvent::StuckTorchOnAtPowerUp);
        }
        io.step(now);
        io
    }

    /// An input changed level (already polarity-corrected). A repeat of the current level is
    /// not an edge and changes nothing.
    pub fn on_input(&mut self, now: Instant, input: Input, active: bool) {
        let now = self.advance(now);
        let was = self.inputs.get(input);
        self.inputs.set(input, active);
        match input {
            Input::Motion => self.motion.on_level(now, active),
            Input::RampdownError if active && !was => self.push_event(IoEvent::RampdownError),
            Input::SystemError if active && !was => self.push_event(IoEvent::SystemError),
            _ => {}
        }
        self.step(now);
    }

    /// The link's view of the supply changed.
    pub fn on_supply(&mut self, now: Instant, supply: SupplyState) {
        let now = self.advance(now);
        self.blackout_until = match (self.blackout_until, supply.restart_blackout_until) {
            (Some(known), Some(new)) => Some(known.max(new)),
            (known, new) => known.or(new),
        };
        self.supply = supply;
        self.step(now);
    }

    /// Let time pass: debounce, the gap between starts, the transfer time-out, blackout end.
    pub fn poll(&mut self, now: Instant) {
        let now = self.advance(now);
        self.step(now);
    }

    /// The next instant at which [`poll`](Self::poll) has something to do, if any.
    pub fn poll_at(&self) -> Option<Instant> {
        let mut next: Option<Instant> = None;
        let mut consider = |t: Instant| next = Some(next.map_or(t, |n| n.min(t)));
        if let Some(t) = self.motion.settles_at(self.config.arc_ok_debounce) {
            consider(t);
        }
        match self.phase {
            StartPhase::Delayed { until } => consider(until),
            StartPhase::On {
                since,
                transferred: false,
                timeout_reported: false,
            } => consider(since + self.config.transfer_timeout),
            _ => {}
        }
        if let Some(until) = self.blackout_until.filter(|&u| u > self.now) {
            consider(until);
        }
        next
    }

    /// The current output levels.
    pub fn outputs(&self) -> Outputs {
        self.outputs
    }

    /// The next logged output change, oldest first.
    pub fn poll_transition(&mut self) -> Option<Transition> {
        self.transitions.pop_front()
    }

    /// The next event, oldest first.
    pub fn poll_event(&mut self) -> Option<IoEvent> {
        self.events.pop_front()
    }

    /// The input levels as last reported.
    pub fn inputs(&self) -> Inputs {
        self.inputs
    }

    /// The supply state as last reported.
    pub fn supply(&self) -> SupplyState {
        self.supply
    }

    /// Apply new settings while running (a `CONFIG` change from the CNC).
    ///
    /// Nothing here can fire the torch: a stricter setting takes effect at once (an interlock
    /// switched on drops START in this call if it applies), a looser one only affects the next
    /// TORCH_ON, since every refusal latches until TORCH_ON is released.
    pub fn set_config(&mut self, now: Instant, config: IoConfig) {
        let now = self.advance(now);
        self.config = config;
        self.step(now);
    }

    /// TORCH_ON's meaning changed (its active level or debounce): `active` is its level under
    /// the new setting. Like power-up, an active TORCH_ON is ignored until seen inactive, so
    /// no change can fire the torch: a START that is on drops in this call.
    pub fn rearm_torch_on(&mut self, now: Instant, active: bool) {
        let now = self.advance(now);
        self.inputs.torch_on = active;
        if active {
            let interlock = Interlock::TorchOnAtWiringChange;
            if matches!(self.phase, StartPhase::On { .. }) {
                self.drop_start(interlock);
            } else {
                self.refuse(interlock);
            }
        }
        self.step(now);
    }

    /// The settings in use.
    pub fn config(&self) -> &IoConfig {
        &self.config
    }

    /// The interlock holding START off while TORCH_ON is active, if any.
    pub fn start_locked_by(&self) -> Option<Interlock> {
        match self.phase {
            StartPhase::Locked(interlock) => Some(interlock),
            _ => None,
        }
    }

    /// Transitions dropped (oldest first) because nobody drained the log in time.
    pub fn lost_transitions(&self) -> u32 {
        self.lost_transitions
    }

    /// Events dropped (oldest first) because nobody drained them in time.
    pub fn lost_events(&self) -> u32 {
        self.lost_events
    }

    fn advance(&mut self, now: Instant) -> Instant {
        self.now = self.now.max(now);
        self.now
    }

    fn in_blackout(&self, now: Instant) -> bool {
        self.blackout_until.is_some_and(|until| now < until)
    }

    /// The first interlock that forbids START now (the gap between starts is not one: it
    /// delays, it does not refuse).
    fn interlock(&self, now: Instant) -> Result<(), Interlock> {
        if self.config.link_required && !self.supply.link_up {
            return Err(Interlock::LinkDown);
        }
        if self.in_blackout(now) {
            return Err(Interlock::RestartBlackout);
        }
        if self.config.refuse_start_on_fault && self.supply.fault_requires_action {
            return Err(Interlock::FaultRequiresAction);
        }
        Ok(())
    }

    /// Whether the unit takes a start now, asked only before START rises: an HPR leaves
    /// IDLE2 for PREFLOW as soon as it sees START, so a START that is on is never dropped
    /// for it. The link's report counts only while the link is up (with it down the link
    /// interlock decides); the NOT_READY signal counts always.
    fn ready_for_start(&self) -> Result<(), Interlock> {
        let link_says_not_ready = self.supply.link_up && !self.supply.unit_ready;
        if self.config.ready_required && (link_says_not_ready || self.inputs.not_ready) {
            return Err(Interlock::NotReady);
        }
        Ok(())
    }

    /// Recompute every output at `now` (`now` already advanced).
    fn step(&mut self, now: Instant) {
        let motion_changed = match self.motion.poll(now, self.config.arc_ok_debounce) {
            Some(true) => {
                self.push_event(IoEvent::ArcOn);
                true
            }
            Some(false) => {
                self.push_event(IoEvent::ArcOff);
                true
            }
            None => false,
        };

        let start_reason = self.step_start(now);
        let start = matches!(self.phase, StartPhase::On { .. });
        if start != self.outputs.start {
            if !start {
                self.last_start_fall = now;
            }
            self.set_output(now, Output::Start, start, start_reason);
        }

        let motion = self.motion.stable();
        let arc_ok = motion && (start || !self.config.arc_ok_requires_start);
        if arc_ok != self.outputs.arc_ok {
            let reason = match (arc_ok, motion_changed, motion) {
                (true, true, _) => Reason::ArcTransferred,
                (true, false, _) => Reason::StartOn,
                (false, _, false) => Reason::ArcLost,
                (false, _, true) => Reason::StartOff,
            };
            self.set_output(now, Output::ArcOk, arc_ok, reason);
        }

        // Pass-throughs, never gated: none of them can fire an arc. HOLD only delays ignition
        // (the HPR stays in preflow), PIERCE_COMPLETE only selects shield preflow or cutflow
        // gas, CORNER_CURRENT only lowers the current to the set corner percentage.
        let pass_through = [
            (Output::Hold, self.inputs.hold),
            (Output::PierceComplete, self.inputs.pierce_complete),
            (Output::CornerCurrent, self.inputs.corner_current),
        ];
        for (output, level) in pass_through {
            if self.outputs.get(output) != level {
                self.set_output(now, output, level, Reason::CncInput);
            }
        }
        // The CNC's POWER command: powering the unit on or off cannot fire an arc either.
        if self.outputs.remote_power != self.config.remote_power {
            let level = self.config.remote_power;
            self.set_output(now, Output::RemotePower, level, Reason::CncCommand);
        }

        let not_ready = self.ready_blocker(now);
        let ready = not_ready.is_none();
        if ready != self.outputs.ready {
            self.set_output(
                now,
                Output::Ready,
                ready,
                not_ready.unwrap_or(Reason::SupplyReady),
            );
        }

        let fault = self.fault_cause();
        let faulted = fault.is_some();
        if faulted != self.outputs.fault {
            self.set_output(
                now,
                Output::Fault,
                faulted,
                fault.unwrap_or(Reason::FaultCleared),
            );
        }
    }

    /// Advance the START channel; returns the reason for a START change, if one happens.
    fn step_start(&mut self, now: Instant) -> Reason {
        if !self.inputs.torch_on {
            // Releasing TORCH_ON ends every phase, including the power-up lock.
            self.phase = StartPhase::Idle;
            return Reason::TorchOff;
        }
        match self.phase {
            StartPhase::Idle => match self.interlock(now).and_then(|()| self.ready_for_start()) {
                Err(interlock) => self.refuse(interlock),
                Ok(()) => {
                    let until = self.last_start_fall + self.config.effective_start_gap();
                    if now >= until {
                        return self.start_on(now, Reason::TorchOn);
                    }
                    self.phase = StartPhase::Delayed { until };
                    self.push_event(IoEvent::StartDelayed { until });
                    Reason::TorchOn
                }
            },
            StartPhase::Delayed { until } => {
                match self.interlock(now).and_then(|()| self.ready_for_start()) {
                    Err(interlock) => self.refuse(interlock),
                    Ok(()) => {
                        if now >= until {
                            return self.start_on(now, Reason::StartGapElapsed);
                        }
                        Reason::StartGapElapsed
                    }
                }
            }
            StartPhase::On {
                since,
                transferred,
                timeout_reported,
            } => {
                if let Err(interlock) = self.interlock(now) {
                    return self.drop_start(interlock);
                }
                self.keep_on(now, since, transferred, timeout_reported, Reason::TorchOn)
            }
            StartPhase::Locked(interlock) => Reason::Interlock(interlock),
        }
    }

    /// START comes on now (the interlocks were just checked).
    fn start_on(&mut self, now: Instant, reason: Reason) -> Reason {
        // Checked at once, so a zero time-out never leaves a deadline in the past.
        self.keep_on(now, now, false, false, reason)
    }

    /// START stays on unless the arc is overdue and the configuration drops it.
    fn keep_on(
        &mut self,
        now: Instant,
        since: Instant,
        transferred: bool,
        timeout_reported: bool,
        reason: Reason,
    ) -> Reason {
        let transferred = transferred || self.motion.stable();
        let overdue = now >= since + self.config.transfer_timeout;
        if !transferred && !timeout_reported && overdue {
            self.push_event(IoEvent::TransferTimeout);
            if self.config.drop_start_on_transfer_timeout {
                // A zero time-out is overdue before START ever rose: that is a refusal.
                return if self.outputs.start {
                    self.drop_start(Interlock::TransferTimeout)
                } else {
                    self.refuse(Interlock::TransferTimeout)
                };
            }
        }
        self.phase = StartPhase::On {
            since,
            transferred,
            timeout_reported: timeout_reported || (!transferred && overdue),
        };
        reason
    }

    fn refuse(&mut self, interlock: Interlock) -> Reason {
        self.phase = StartPhase::Locked(interlock);
        self.push_event(IoEvent::StartRefused { reason: interlock });
        Reason::Interlock(interlock)
    }

    fn drop_start(&mut self, interlock: Interlock) -> Reason {
        self.phase = StartPhase::Locked(interlock);
        self.push_event(IoEvent::StartDropped { reason: interlock });
        Reason::Interlock(interlock)
    }

    /// Why READY is off, or `None` when it is on.
    fn ready_blocker(&self, now: Instant) -> Option<Reason> {
        if self.config.link_required && !self.supply.link_up {
            Some(Reason::LinkDown)
        } else if self.supply.fault_requires_action {
            Some(Reason::FaultRequiresAction)
        } else if self.in_blackout(now) {
            Some(Reason::RestartBlackout)
        } else if !self.supply.unit_ready {
            Some(Reason::UnitNotReady)
        } else if self.inputs.not_ready {
            Some(Reason::NotReadySignal)
        } else {
            None
        }
    }

    /// Why FAULT is on, or `None` when it is off. With the link down the supply's last
    /// fault report is stale, so the lost link is the reason given.
    fn fault_cause(&self) -> Option<Reason> {
        if self.config.link_required && !self.supply.link_up {
            Some(Reason::LinkDown)
        } else if self.supply.fault_active || self.supply.fault_requires_action {
            Some(Reason::FaultActive)
        } else if self.inputs.system_error {
            Some(Reason::SystemErrorSignal)
        } else {
            None
        }
    }

    fn set_output(&mut self, now: Instant, output: Output, level: bool, reason: Reason) {
        self.outputs.set(output, level);
        let transition = Transition {
            output,
            level,
            reason,
            at: now,
        };
        if self.transitions.is_full() {
            self.transitions.pop_front();
            self.lost_transitions = self.lost_transitions.saturating_add(1);
        }
        let _ = self.transitions.push_back(transition);
    }

    fn push_event(&mut self, event: IoEvent) {
        if self.events.is_full() {
            self.events.pop_front();
            self.lost_events = self.lost_events.saturating_add(1);
        }
        let _ = self.events.push_back(event);
    }
}

#[cfg(test)]
mod tests;
