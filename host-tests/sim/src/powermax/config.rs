//! What makes one simulated Powermax (model, address, serial settings, the behaviours the
//! manuals leave open) and the values it reports: settings, counters, arc state, limits.

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Duration;

use crate::clock::Accumulator;
use crate::{Family, Model, legacy, sync};

/// What a block read does with an undocumented address inside a documented block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UndocumentedAddresses {
    /// Reads as 0.
    Accept,
    /// The whole read is refused with exception 02 (illegal data address).
    Refuse,
}

/// What a write of an out-of-range setting does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutOfRange {
    /// Acknowledged; the setting is not applied and fault 0-11-0/1/2 is raised.
    Fault,
    /// Refused with exception 03 (illegal data value).
    Exception,
}

/// How a unit treats Read Device Identification (0x2B / 0x0E).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeviceIdSupport {
    /// Answers with its product code (SYNC guide Table 2) and this conformity level (0x81 in
    /// the guide's sample reply).
    Answers {
        /// Conformity level in the reply header.
        conformity: u8,
    },
    /// Refuses with exception 01.
    IllegalFunction,
    /// Does not answer at all.
    Silent,
}

/// Timing of the arc sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ArcTimings {
    /// Pilot arc to transfer (torch reaching the plate); `None`: never transfers.
    pub transfer_delay: Option<Duration>,
    /// A pilot arc that has not transferred goes out after this long.
    pub pilot_timeout: Duration,
    /// Gas keeps flowing this long after the arc.
    pub postflow: Duration,
}

impl Default for ArcTimings {
    fn default() -> Self {
        ArcTimings {
            transfer_delay: Some(Duration::from_millis(100)),
            pilot_timeout: Duration::from_secs(5),
            postflow: Duration::from_secs(10),
        }
    }
}

/// Everything that makes one simulated Powermax.
#[derive(Debug, Clone, PartialEq)]
pub struct PowermaxConfig {
    /// The model.
    pub model: Model,
    /// Node address setting, 0 = learn from the first valid request after power-up.
    pub address: u8,
    /// Serial settings (SYNC units can be set to odd / no parity and 2 stop bits).
    pub port: PortConfig,
    /// Time from the end of a request to the start of the reply.
    pub latency: Duration,
    /// Random extra latency, up to this much.
    pub latency_jitter: Duration,
    /// Block reads over undocumented addresses.
    pub undocumented: UndocumentedAddresses,
    /// Out-of-range setting writes.
    pub out_of_range: OutOfRange,
    /// Read Device Identification.
    pub device_id: DeviceIdSupport,
    /// Holding / input registers the unit refuses to read (a read touching one is refused
    /// whole with exception 02), as a unit might for write-only or unsupported registers.
    pub refused_registers: Vec<u16>,
    /// Remote settings take effect. `false` models a faulty unit that acknowledges the
    /// writes but keeps cutting with its panel settings, so that a read-back differs.
    pub remote_settings_apply: bool,
    /// Arc sequence timing.
    pub timings: ArcTimings,
    /// After power-on the unit ignores the line this long.
    pub boot_time: Duration,
    /// After a quick restart the unit ignores the line this long.
    pub quick_restart_time: Duration,
    /// Torch type / lead length id (SYNC guide Table 3): high byte of 0x3000, and the legacy
    /// lead-length coils.
    pub torch_id: u8,
    /// Power supply type id (SYNC guide Table 4): low byte of 0x3000.
    pub type_id: u8,
    /// Output current range of the power supply, amps.
    pub amps: (u16, u16),
    /// Permitted gas pressure, psi (legacy units; SYNC units take it from the cartridge).
    pub psi: (u16, u16),
    /// Pressure the unit picks in automatic mode, psi (legacy units).
    pub auto_psi: u16,
    /// PRNG seed (latency jitter).
    pub seed: u64,
}

impl PowermaxConfig {
    /// Defaults for `model` (a Powermax SYNC or legacy model).
    pub fn for_model(model: Model) -> PowermaxConfig {
        let sync = model.family() == Family::Sync;
        PowermaxConfig {
            model,
            address: 0,
            port: PortConfig::MODBUS_DEFAULT,
            latency: Duration::from_millis(3),
            latency_jitter: Duration::ZERO,
            undocumented: UndocumentedAddresses::Accept,
            out_of_range: OutOfRange::Fault,
            device_id: DeviceIdSupport::Answers {
                conformity: plasma_protocol::powermax::device_id::CONFORMITY_LEVEL,
            },
            refused_registers: Vec::new(),
            remote_settings_apply: true,
            timings: ArcTimings::default(),
            boot_time: Duration::ZERO,
            quick_restart_time: Duration::from_secs(2),
            torch_id: 0x04,
            type_id: if sync { sync::type_id(model) } else { 0 },
            amps: if sync {
                sync::current_range(model)
            } else {
                legacy::current_range(model)
            },
            psi: (63, 78),
            auto_psi: 70,
            seed: 1,
        }
    }
}

/// Operating settings: mode, current (amps x 64), pressure (psi x 128, 0 = automatic).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Process {
    /// Operating mode (SYNC: 1 cut, 2 expanded metal, 3 gouge; legacy: 1 normal, 2 CPA,
    /// 3 gouge).
    pub mode: u16,
    /// Current, amps x 64.
    pub current: u16,
    /// Pressure, psi x 128; 0 = automatic.
    pub pressure: u16,
}

/// Power supply life counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counters {
    /// Pilot arc starts.
    pub starts: u32,
    /// Pilot arc time.
    pub pilot: Accumulator,
    /// Arc transfers.
    pub transfers: u32,
    /// Transferred arc time.
    pub transfer: Accumulator,
}

/// Where the arc sequence is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArcState {
    /// No gas, no arc.
    Idle,
    /// Pilot arc.
    Pilot,
    /// Arc transferred to the work; Motion is on.
    Transferred,
    /// Gas postflow after the arc.
    Postflow,
}

/// Permitted settings, as the unit reports them (0x3001-0x3005, 0x2099-0x209D).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Lowest and highest permitted mode.
    pub modes: (u16, u16),
    /// Current range, amps x 64.
    pub current: (u16, u16),
    /// Pressure range, psi x 128.
    pub pressure: (u16, u16),
    /// Automatic pressure, psi x 128.
    pub auto_pressure: u16,
}
