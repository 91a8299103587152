//! Settings of the discrete I/O logic.

use super::input_config::InputConfig;
use super::output_levels::OutputConfig;
use plasma_protocol::time::Duration;

/// The Powermax manuals' minimum delay between Start signals ("to give sufficient time for
/// the relay circuits to complete switching").
pub const MIN_START_GAP: Duration = Duration::from_millis(50);

/// Settings of the discrete I/O: the CNC's wiring ([`inputs`](Self::inputs),
/// [`outputs`](Self::outputs)), read by [`DiscreteIo`](super::DiscreteIo), and the
/// rules of [`Interlocks`](super::Interlocks). [`IoConfig::default`] is the safe choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IoConfig {
    /// Least time from a START falling edge to the next rising edge. Values below
    /// [`MIN_START_GAP`] are raised to it.
    pub start_gap: Duration,
    /// How long MOTION must hold a level before ARC_OK takes it (both edges).
    pub arc_ok_debounce: Duration,
    /// ARC_OK only while START is on (a MOTION without our START is not our arc).
    pub arc_ok_requires_start: bool,
    /// Time after START's rising edge within which MOTION must come.
    pub transfer_timeout: Duration,
    /// On a transfer time-out, drop START (it then stays off until TORCH_ON is released).
    pub drop_start_on_transfer_timeout: bool,
    /// Refuse (and drop) START while the supply has a fault that requires action.
    pub refuse_start_on_fault: bool,
    /// The installation has a serial link to the supply: refuse (and drop) START while it is
    /// down, hold READY off and FAULT on while it is down. Clear it only for a discrete-only
    /// installation.
    pub link_required: bool,
    /// Refuse START while the unit is not ready for a start (HPR / MaxPro200 outside state
    /// 03, or the NOT_READY signal active). Refuses only: a unit leaves its ready state once
    /// it takes a start, so this never drops a START that is on.
    pub ready_required: bool,
    /// Active level and debounce of every input (the CNC's wiring).
    pub inputs: InputConfig,
    /// Active level of the outputs a table may need inverted.
    pub outputs: OutputConfig,
    /// REMOTE_POWER on: what the CNC last asked with `POWER ON|OFF`. Not stored: off after
    /// every reset of the bridge, like every output (the safe state).
    pub remote_power: bool,
}

impl IoConfig {
    /// Longest [`start_gap`](Self::start_gap) a setting may hold.
    pub const MAX_START_GAP: Duration = Duration::from_millis(1000);
    /// Longest [`arc_ok_debounce`](Self::arc_ok_debounce) a setting may hold.
    pub const MAX_ARC_OK_DEBOUNCE: Duration = Duration::from_millis(100);
    /// Shortest [`transfer_timeout`](Self::transfer_timeout) a setting may hold.
    pub const MIN_TRANSFER_TIMEOUT: Duration = Duration::from_millis(100);
    /// Longest [`transfer_timeout`](Self::transfer_timeout) a setting may hold.
    pub const MAX_TRANSFER_TIMEOUT: Duration = Duration::from_secs(10);

    /// The gap actually enforced: `start_gap`, but never less than [`MIN_START_GAP`].
    pub fn effective_start_gap(&self) -> Duration {
        if self.start_gap < MIN_START_GAP {
            MIN_START_GAP
        } else {
            self.start_gap
        }
    }
}

impl Default for IoConfig {
    fn default() -> Self {
        IoConfig {
            start_gap: MIN_START_GAP,
            arc_ok_debounce: Duration::from_millis(2),
            arc_ok_requires_start: true,
            transfer_timeout: Duration::from_secs(3),
            drop_start_on_transfer_timeout: true,
            refuse_start_on_fault: true,
            link_required: true,
            ready_required: true,
            inputs: InputConfig::default(),
            outputs: OutputConfig::default(),
            remote_power: false,
        }
    }
}
