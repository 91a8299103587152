//! The discrete signals the bridge reads and drives, and the power-supply status the link
//! reports. Levels are logical (`true` = active): the board corrects polarity (the HPR's
//! opto-isolated inputs are active low) before anything reaches this module.

use core::fmt;

use plasma_protocol::time::Instant;

/// A discrete input of the bridge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Input {
    /// CNC: torch on (the CNC's plasma start request).
    TorchOn,
    /// CNC (HPR): hold ignition; the supply stays in preflow while it is active.
    Hold,
    /// CNC (HPR): pierce complete; the supply switches from shield preflow to cutflow gas.
    PierceComplete,
    /// CNC (HPR): corner current; the supply drops to its corner-current percentage.
    CornerCurrent,
    /// Power supply: machine motion / transfer (the arc has transferred to the plate).
    Motion,
    /// Power supply (HPR): not ready for start (purging, gas test mode, ...).
    NotReady,
    /// Power supply (HPR): the last arc did not ramp down properly.
    RampdownError,
    /// Power supply (HPR, MaxPro200): an error has occurred in the plasma system (its code
    /// is read over the serial link). Optional: an open input reads inactive.
    SystemError,
}

impl Input {
    /// Every input, in declaration order.
    pub const ALL: [Input; 8] = [
        Input::TorchOn,
        Input::Hold,
        Input::PierceComplete,
        Input::CornerCurrent,
        Input::Motion,
        Input::NotReady,
        Input::RampdownError,
        Input::SystemError,
    ];

    /// Signal name as printed in logs.
    pub const fn as_str(self) -> &'static str {
        match self {
            Input::TorchOn => "TORCH_ON",
            Input::Hold => "HOLD",
            Input::PierceComplete => "PIERCE_COMPLETE",
            Input::CornerCurrent => "CORNER_CURRENT",
            Input::Motion => "MOTION",
            Input::NotReady => "NOT_READY",
            Input::RampdownError => "RAMPDOWN_ERROR",
            Input::SystemError => "SYSTEM_ERROR",
        }
    }
}

impl fmt::Display for Input {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A discrete output of the bridge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Output {
    /// To the power supply: plasma start.
    Start,
    /// To the power supply (HPR): hold ignition, passed through from the CNC.
    Hold,
    /// To the power supply (HPR): pierce complete, passed through from the CNC.
    PierceComplete,
    /// To the power supply (HPR): corner current, passed through from the CNC.
    CornerCurrent,
    /// To the CNC: the arc has transferred (debounced MOTION).
    ArcOk,
    /// To the CNC: the bridge and the supply would accept a start.
    Ready,
    /// To the CNC: the supply has a fault, or the link to it is lost.
    Fault,
    /// To the power supply (HPR): remote power on, as the CNC last asked with `POWER ON|OFF`;
    /// off from reset until it asks. Optional: a unit without it wired ignores it.
    RemotePower,
}

impl Output {
    /// Every output, in declaration order.
    pub const ALL: [Output; 8] = [
        Output::Start,
        Output::Hold,
        Output::PierceComplete,
        Output::CornerCurrent,
        Output::ArcOk,
        Output::Ready,
        Output::Fault,
        Output::RemotePower,
    ];

    /// Signal name as printed in logs.
    pub const fn as_str(self) -> &'static str {
        match self {
            Output::Start => "START",
            Output::Hold => "HOLD",
            Output::PierceComplete => "PIERCE_COMPLETE",
            Output::CornerCurrent => "CORNER_CURRENT",
            Output::ArcOk => "ARC_OK",
            Output::Ready => "READY",
            Output::Fault => "FAULT",
            Output::RemotePower => "REMOTE_POWER",
        }
    }
}

impl fmt::Display for Output {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The level of every input at one moment (logical levels, `true` = active).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Inputs {
    /// See [`Input::TorchOn`].
    pub torch_on: bool,
    /// See [`Input::Hold`].
    pub hold: bool,
    /// See [`Input::PierceComplete`].
    pub pierce_complete: bool,
    /// See [`Input::CornerCurrent`].
    pub corner_current: bool,
    /// See [`Input::Motion`].
    pub motion: bool,
    /// See [`Input::NotReady`].
    pub not_ready: bool,
    /// See [`Input::RampdownError`].
    pub rampdown_error: bool,
    /// See [`Input::SystemError`].
    pub system_error: bool,
}

impl Inputs {
    /// Every input inactive.
    pub const NONE: Inputs = Inputs {
        torch_on: false,
        hold: false,
        pierce_complete: false,
        corner_current: false,
        motion: false,
        not_ready: false,
        rampdown_error: false,
        system_error: false,
    };

    /// The level of one input.
    pub const fn get(&self, input: Input) -> bool {
        match input {
            Input::TorchOn => self.torch_on,
            Input::Hold => self.hold,
            Input::PierceComplete => self.pierce_complete,
            Input::CornerCurrent => self.corner_current,
            Input::Motion => self.motion,
            Input::NotReady => self.not_ready,
            Input::RampdownError => self.rampdown_error,
            Input::SystemError => self.system_error,
        }
    }

    /// Set the level of one input.
    pub fn set(&mut self, input: Input, active: bool) {
        let slot = match input {
            Input::TorchOn => &mut self.torch_on,
            Input::Hold => &mut self.hold,
            Input::PierceComplete => &mut self.pierce_complete,
            Input::CornerCurrent => &mut self.corner_current,
            Input::Motion => &mut self.motion,
            Input::NotReady => &mut self.not_ready,
            Input::RampdownError => &mut self.rampdown_error,
            Input::SystemError => &mut self.system_error,
        };
        *slot = active;
    }
}

/// The level of every output at one moment (logical levels, `true` = active).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Outputs {
    /// See [`Output::Start`].
    pub start: bool,
    /// See [`Output::Hold`].
    pub hold: bool,
    /// See [`Output::PierceComplete`].
    pub pierce_complete: bool,
    /// See [`Output::CornerCurrent`].
    pub corner_current: bool,
    /// See [`Output::ArcOk`].
    pub arc_ok: bool,
    /// See [`Output::Ready`].
    pub ready: bool,
    /// See [`Output::Fault`].
    pub fault: bool,
    /// See [`Output::RemotePower`].
    pub remote_power: bool,
}

impl Outputs {
    /// Every output off: the level at reset.
    pub const OFF: Outputs = Outputs {
        start: false,
        hold: false,
        pierce_complete: false,
        corner_current: false,
        arc_ok: false,
        ready: false,
        fault: false,
        remote_power: false,
    };

    /// The level of one output.
    pub const fn get(&self, output: Output) -> bool {
        match output {
            Output::Start => self.start,
            Output::Hold => self.hold,
            Output::PierceComplete => self.pierce_complete,
            Output::CornerCurrent => self.corner_current,
            Output::ArcOk => self.arc_ok,
            Output::Ready => self.ready,
            Output::Fault => self.fault,
            Output::RemotePower => self.remote_power,
        }
    }

    pub(crate) fn set(&mut self, output: Output, active: bool) {
        let slot = match output {
            Output::Start => &mut self.start,
            Output::Hold => &mut self.hold,
            Output::PierceComplete => &mut self.pierce_complete,
            Output::CornerCurrent => &mut self.corner_current,
            Output::ArcOk => &mut self.arc_ok,
            Output::Ready => &mut self.ready,
            Output::Fault => &mut self.fault,
            Output::RemotePower => &mut self.remote_power,
        };
        *slot = active;
    }
}

/// What the link to the power supply currently knows, as far as the discrete I/O cares.
///
/// The link owns the meaning of each field (for example `link_up` is its verdict after its
/// own retries, so a single frame lost to HF-ignition noise does not flip it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SupplyState {
    /// The link gets answers from the supply.
    pub link_up: bool,
    /// The supply reports a fault that needs an operator (not a warning).
    pub fault_requires_action: bool,
    /// The supply reports any fault (including warnings).
    pub fault_active: bool,
    /// After a SYNC quick restart: no request and no Start before this instant.
    pub restart_blackout_until: Option<Instant>,
    /// The unit's own readiness for a start, as the link last read it: an HPR or MaxPro200
    /// in state 03 (IDLE2 / READY FOR START); a Powermax has no such state (its faults say
    /// why it cannot cut), so it is ready while the link is up. False with the link down.
    /// Faults and the blackout are the fields above, not part of this one.
    pub unit_ready: bool,
}

impl SupplyState {
    /// Link up, no fault, no blackout, ready.
    pub const HEALTHY: SupplyState = SupplyState {
        link_up: true,
        fault_requires_action: false,
        fault_active: false,
        restart_blackout_until: None,
        unit_ready: true,
    };
}
