//! Why an output changed, why a start was refused, and what the I/O logic reports.

use core::fmt;

use super::signals::Output;
use plasma_protocol::time::{Decimal, Instant};

/// A condition that keeps START off although the CNC asks for it.
///
/// Each of these latches: START stays off until TORCH_ON has been released and asserted
/// again, so clearing a condition never fires the torch by itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Interlock {
    /// TORCH_ON was already active at power-up and has not been seen inactive since.
    TorchOnAtPowerUp,
    /// TORCH_ON read active when its active level or debounce changed, and has not been seen
    /// inactive since (the power-up rule, for a change of what the pin means).
    TorchOnAtWiringChange,
    /// The link to the power supply is down.
    LinkDown,
    /// The supply is restarting after a SYNC quick restart.
    RestartBlackout,
    /// The supply reports a fault that requires action.
    FaultRequiresAction,
    /// The arc did not transfer within the configured time after START.
    TransferTimeout,
    /// The unit is not ready for a start: an HPR or MaxPro200 outside state 03 (IDLE2 /
    /// READY FOR START: purging, gas test, powering up) or its NOT_READY signal active. Only
    /// refuses: once START is on the unit leaves that state by design (PREFLOW and on).
    NotReady,
}

log_texts!(Interlock {
    Interlock::TorchOnAtPowerUp => "torch-on active at power-up",
    Interlock::TorchOnAtWiringChange => "torch-on active when its wiring setting changed",
    Interlock::LinkDown => "link to power supply down",
    Interlock::RestartBlackout => "quick-restart blackout",
    Interlock::FaultRequiresAction => "power supply fault requires action",
    Interlock::TransferTimeout => "arc did not transfer in time",
    Interlock::NotReady => "power supply not ready for start",
});

impl fmt::Display for Interlock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Why an output took its new level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reason {
    /// START on: the CNC asserted TORCH_ON and every interlock allows it.
    TorchOn,
    /// START on: a TORCH_ON held through the 50 ms gap between starts.
    StartGapElapsed,
    /// START off: the CNC released TORCH_ON.
    TorchOff,
    /// START off: an interlock became false while START was on.
    Interlock(Interlock),
    /// ARC_OK on: MOTION has been active for the debounce time.
    ArcTransferred,
    /// ARC_OK off: MOTION has been inactive for the debounce time.
    ArcLost,
    /// ARC_OK on: START came on while MOTION was already (debounced) active.
    StartOn,
    /// ARC_OK off: START went off.
    StartOff,
    /// A pass-through output follows its CNC input.
    CncInput,
    /// READY on: link up, no fault requiring action, no blackout, supply ready.
    SupplyReady,
    /// READY off: the link is down (also FAULT on: the link is lost).
    LinkDown,
    /// READY off: the supply has a fault that requires action.
    FaultRequiresAction,
    /// READY off: quick-restart blackout.
    RestartBlackout,
    /// READY off: the supply reports over the link that it is not ready.
    UnitNotReady,
    /// READY off: the HPR NOT_READY signal is active.
    NotReadySignal,
    /// FAULT on: the supply reports a fault.
    FaultActive,
    /// FAULT on: the HPR / MaxPro200 SYSTEM_ERROR signal is active.
    SystemErrorSignal,
    /// FAULT off: no fault and the link is up.
    FaultCleared,
    /// REMOTE_POWER: the CNC's `POWER ON|OFF`.
    CncCommand,
}

log_texts!(Reason, delegate Reason::Interlock(interlock) => interlock {
    Reason::TorchOn => "torch-on from CNC",
    Reason::StartGapElapsed => "torch-on held through the gap between starts",
    Reason::TorchOff => "torch-on released by CNC",
    Reason::ArcTransferred => "arc transferred (MOTION stable)",
    Reason::ArcLost => "arc lost (MOTION off, stable)",
    Reason::StartOn => "START on with arc already transferred",
    Reason::StartOff => "START off",
    Reason::CncInput => "follows CNC input",
    Reason::SupplyReady => "link up, no fault, supply ready",
    Reason::LinkDown => "link to power supply down",
    Reason::FaultRequiresAction => "power supply fault requires action",
    Reason::RestartBlackout => "quick-restart blackout",
    Reason::UnitNotReady => "power supply reports not ready",
    Reason::NotReadySignal => "NOT_READY signal active",
    Reason::FaultActive => "power supply fault active",
    Reason::SystemErrorSignal => "SYSTEM_ERROR signal active",
    Reason::FaultCleared => "no fault, link up",
    Reason::CncCommand => "POWER command from CNC",
});

impl From<Interlock> for Reason {
    fn from(interlock: Interlock) -> Self {
        Reason::Interlock(interlock)
    }
}

impl fmt::Display for Reason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One output changing level, for the board's log and the simulator's trace.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Transition {
    /// The output that changed.
    pub output: Output,
    /// Its new level.
    pub level: bool,
    /// Why.
    pub reason: Reason,
    /// When (the `now` of the call that changed it).
    pub at: Instant,
}

impl fmt::Display for Transition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let us = self.at.as_micros();
        write!(
            f,
            "{}.{:03} ms {} {}: {}",
            us / 1000,
            us % 1000,
            self.output,
            if self.level { "on" } else { "off" },
            self.reason
        )
    }
}

/// Something the supervisor or the CNC session may want to know about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IoEvent {
    /// MOTION became active (debounced): the arc transferred.
    ArcOn,
    /// MOTION became inactive (debounced): the arc is gone.
    ArcOff,
    /// START has been on for the transfer time-out and MOTION never came.
    TransferTimeout,
    /// A new TORCH_ON was refused; START stays off until TORCH_ON is released.
    StartRefused {
        /// The interlock that refused it.
        reason: Interlock,
    },
    /// START was on and an interlock dropped it; it stays off until TORCH_ON is released.
    StartDropped {
        /// The interlock that dropped it.
        reason: Interlock,
    },
    /// A new TORCH_ON arrived inside the gap between starts; START follows at `until`
    /// if TORCH_ON is still active then.
    StartDelayed {
        /// When the gap ends.
        until: Instant,
    },
    /// TORCH_ON was active at power-up; it is ignored until seen inactive.
    StuckTorchOnAtPowerUp,
    /// The HPR reports that the last arc did not ramp down properly (consumable wear).
    RampdownError,
    /// The HPR / MaxPro200 SYSTEM_ERROR signal came on: an error occurred in the plasma
    /// system (its code is read over the serial link).
    SystemError,
}

impl fmt::Display for IoEvent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IoEvent::ArcOn => f.write_str("arc on"),
            IoEvent::ArcOff => f.write_str("arc off"),
            IoEvent::TransferTimeout => f.write_str("arc transfer time-out"),
            IoEvent::StartRefused { reason } => write!(f, "start refused: {reason}"),
            IoEvent::StartDropped { reason } => write!(f, "start dropped: {reason}"),
            IoEvent::StartDelayed { until } => {
                write!(f, "start delayed until {} us", Decimal(until.as_micros()))
            }
            IoEvent::StuckTorchOnAtPowerUp => {
                f.write_str("torch-on active at power-up, ignored until released")
            }
            IoEvent::RampdownError => f.write_str("rampdown error"),
            IoEvent::SystemError => f.write_str("system error signal"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn us(v: u64) -> Instant {
        Instant::from_micros(v)
    }

    #[test]
    fn every_reason_and_transition_has_text() {
        let t = Transition {
            output: Output::Start,
            level: false,
            reason: Reason::Interlock(Interlock::RestartBlackout),
            at: us(2_100_250),
        };
        assert_eq!(
            t.to_string(),
            "2100.250 ms START off: quick-restart blackout"
        );
        assert_eq!(
            IoEvent::StartRefused {
                reason: Interlock::LinkDown
            }
            .to_string(),
            "start refused: link to power supply down"
        );
        assert_eq!(Reason::TorchOff.as_str(), "torch-on released by CNC");
    }
}
