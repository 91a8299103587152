//! What makes one simulated HPR / MaxPro200 (model, gas console, timing) and the values it
//! reports: the phases of its sequence and its counters.

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Duration;

use crate::Model;
use crate::clock::Accumulator;

/// Gas console of an HPR.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GasConsole {
    /// Manual gas console: gases and pressures set by knobs.
    Manual,
    /// Automatic gas console: the CNC sets gases and pressures.
    Auto,
}

/// Durations of the sequence steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HprTimings {
    /// Power-up checks before the purge (MaxPro200: initial checks too).
    pub power_up: Duration,
    /// Gas purge after power-up or a gas change.
    pub purge: Duration,
    /// Preflow before ignition.
    pub preflow: Duration,
    /// Pilot arc to transfer; `None`: never transfers.
    pub transfer_delay: Option<Duration>,
    /// A pilot arc that has not transferred by then fails with error 021.
    pub pilot_timeout: Duration,
    /// Transfer to steady state (ramp-up).
    pub rampup: Duration,
    /// Ramp-down after Start goes off.
    pub rampdown: Duration,
    /// Gas flow after the arc (auto off / end of cycle).
    pub postflow: Duration,
    /// Longest HF ignition burst.
    pub hf_max: Duration,
}

impl Default for HprTimings {
    fn default() -> Self {
        HprTimings {
            power_up: Duration::from_millis(500),
            purge: Duration::from_secs(2),
            preflow: Duration::from_millis(500),
            transfer_delay: Some(Duration::from_millis(50)),
            pilot_timeout: Duration::from_millis(300),
            rampup: Duration::from_millis(50),
            rampdown: Duration::from_millis(100),
            postflow: Duration::from_secs(2),
            hf_max: Duration::from_secs(1),
        }
    }
}

/// Everything that makes one simulated HPR / MaxPro200.
#[derive(Debug, Clone, PartialEq)]
pub struct HprConfig {
    /// The model.
    pub model: Model,
    /// Dip-switch id, 0-3.
    pub id: u8,
    /// Gas console (ignored on the MaxPro200).
    pub console: GasConsole,
    /// Serial settings.
    pub port: PortConfig,
    /// Sequence timing.
    pub timings: HprTimings,
    /// Firmware versions reported by 001: power supply, then gas console, space delimited.
    pub version: String,
    /// Torch id reported by 145 (MaxPro200), one of the manual's table (line 290).
    pub torch_id: u16,
    /// Settings commands are refused until 004 REMOTE_MODE.
    pub require_remote_mode: bool,
    /// PRNG seed (response time).
    pub seed: u64,
}

impl HprConfig {
    /// Defaults for `model` (an HPR model or the MaxPro200).
    pub fn for_model(model: Model) -> HprConfig {
        HprConfig {
            model,
            id: 0,
            console: GasConsole::Auto,
            port: PortConfig::HPR,
            timings: HprTimings::default(),
            // "ps rev A, gas rev A" (line 140); the sample frame `>001A.0 A.25<` fails its
            // checksum, and `A.0 A.2` is the reading whose text matches the note.
            version: "A.0 A.2".into(),
            // The manual's sample, `>14500025C<`: id 2, 25 Ft mechanized torch.
            torch_id: 2,
            require_remote_mode: true,
            seed: 1,
        }
    }
}

/// Where the sequence is (mapped to the section V state codes by
/// [`Hpr::state_code`](super::Hpr::state_code)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Power-up (HPR 0 idle, MaxPro 0 power up).
    PowerUp,
    /// MaxPro 1 initial checks.
    InitialChecks,
    /// 2 purge.
    Purge,
    /// 3 idle2 / ready for start.
    Ready,
    /// 4 preflow.
    Preflow,
    /// MaxPro 5 preflow hold (HPR stays in 4).
    PreflowHold,
    /// MaxPro 6 ignite.
    Ignite,
    /// Pilot arc (HPR 5, MaxPro 7).
    Pilot,
    /// HPR 6 transfer.
    Transfer,
    /// Ramp-up (HPR 7, MaxPro 8).
    Rampup,
    /// Steady state / main arc (HPR 8, MaxPro 9).
    Steady,
    /// Ramp-down (HPR 9, MaxPro 10).
    Rampdown,
    /// HPR 10 final ramp-down.
    FinalRampdown,
    /// HPR 11 auto off / MaxPro 11 ramp-down complete.
    AutoOff,
    /// MaxPro 12 end of cycle.
    EndOfCycle,
    /// 14 shutdown.
    Shutdown,
    /// HPR 12 test cutflow.
    TestCutflow,
    /// HPR 20 test preflow.
    TestPreflow,
}

/// Counters reported by 125 GET_TIMER_COUNTER.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct HprCounters {
    /// Arc on time.
    pub arc_on: Accumulator,
    /// Powered time.
    pub system_on: Accumulator,
    /// Arc transfers.
    pub starts: u32,
    /// Failed to transfer.
    pub start_errors: u32,
    /// Failed to ramp down.
    pub rampdown_errors: u32,
}
