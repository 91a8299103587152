//! The bridge's picture of the power supply, kept up to date by the link.

use plasma_protocol::hpr::{
    ErrorCode, GasPair, MaxProPsInfo, PsInfo, StateCode, SystemId, TimerCounter, TorchId, Version,
};
use plasma_protocol::powermax::sync::{
    Cartridge, FaultLog, Identification, PermittedModes, PsCounters,
};
use plasma_protocol::powermax::{
    Amps, CartridgeName, FaultCode, LeadLength, OperatingMode, PowerSupplyModel, Pressure, Psi,
    StepsRequired,
};

use plasma_protocol::time::Instant;

/// Protocol family of the unit on the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Family {
    /// Powermax SYNC, registers 0x3xxx.
    PowermaxSync,
    /// Older Powermax, registers 0x2xxx.
    PowermaxLegacy,
    /// HyPerformance HPR130/260/400 (XD).
    Hpr,
    /// MaxPro200.
    MaxPro200,
}

impl Family {
    /// True for the two Modbus families.
    pub const fn is_modbus(self) -> bool {
        matches!(self, Family::PowermaxSync | Family::PowermaxLegacy)
    }

    /// A readable name for error texts ("not supported by a MaxPro200").
    pub const fn name(self) -> &'static str {
        match self {
            Family::PowermaxSync => "a Powermax SYNC",
            Family::PowermaxLegacy => "a Powermax (legacy registers)",
            Family::Hpr => "an HPR",
            Family::MaxPro200 => "a MaxPro200",
        }
    }
}

/// Which unit answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Model {
    /// A Powermax identified by Read Device Identification (SYNC guide Table 2).
    Powermax(PowerSupplyModel),
    /// A Powermax that answered register reads but not (or not recognisably) device
    /// identification.
    PowermaxUnidentified,
    /// An HPR or MaxPro200, from its HELLO reply.
    Hpr(SystemId),
}

/// The fault a unit reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ActiveFault {
    /// Powermax fault code (X-YY-Z).
    Powermax(FaultCode),
    /// HPR / MaxPro200 error code (section IV).
    Hpr(ErrorCode),
}

impl ActiveFault {
    /// True when cutting cannot go on until someone acts. Powermax: the SYNC table's
    /// "Steps required: Yes" ([`FaultCode::steps_required`]: a code the table does not list
    /// counts as blocking); HPR: any
    /// error that is not a warning (codes 1-42 are warnings 131 CLEAR WARNINGS clears).
    pub fn action_required(&self) -> bool {
        match self {
            ActiveFault::Powermax(code) => code.steps_required() == StepsRequired::Yes,
            ActiveFault::Hpr(code) => code.is_error() && !code.is_warning(),
        }
    }
}

/// Mode, current and pressure of a Powermax, as written or as read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PowermaxProcess {
    /// Operating mode; `None` when the unit reports 0 or an unknown value.
    pub mode: Option<OperatingMode>,
    /// Output current.
    pub current: Amps,
    /// Gas pressure (0 = automatic).
    pub pressure: Pressure,
}

/// What the unit permits (SYNC: for the installed cartridge; legacy: for the unit).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Limits {
    /// Permitted modes (SYNC 0x3001); `None` on legacy units, which do not report them.
    pub modes: Option<PermittedModes>,
    /// Lowest current.
    pub min_current: Amps,
    /// Highest current.
    pub max_current: Amps,
    /// Lowest pressure set point.
    pub min_pressure: Psi,
    /// Highest pressure set point.
    pub max_pressure: Psi,
}

/// HPR / MaxPro200 specifics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HprStatus {
    /// System state (table V).
    pub state: Option<StateCode>,
    /// Current error (table IV).
    pub error: Option<ErrorCode>,
    /// Last GET_PS_INFO of an HPR.
    pub ps_info: Option<PsInfo>,
    /// Last GET_PS_INFO of a MaxPro200.
    pub maxpro_info: Option<MaxProPsInfo>,
    /// Last nominal current set or reported, amps.
    pub nominal_amps: Option<u16>,
    /// Output current of an HPR, amps: 028 READ_PLASMA_AMPS, read after each poll that shows
    /// the main arc on (states 6-10); 0 after a poll that shows it off.
    pub actual_amps: Option<u16>,
    /// Last error log read (134), most recent first.
    pub error_log: Option<[ErrorCode; 4]>,
    /// Last timer/counter read (125).
    pub timers: Option<TimerCounter>,
    /// A manual gas console's switch positions (122 READ_GAS_SWITCH, slow data).
    pub gases: Option<GasPair>,
    /// True after the unit accepted 004 REMOTE_MODE.
    pub remote_accepted: bool,
    /// Firmware revisions (001 VERSION, read once after detection).
    pub firmware: Option<Firmware>,
    /// A MaxPro200's torch (145 READ TORCH ID, read once after detection).
    pub torch: Option<TorchId>,
    /// The inlet gases an automatic gas console uses (098 GET_INLET_GASES, slow data).
    pub inlet_gases: Option<GasPair>,
}

/// Longest firmware revision kept: the manual's are three characters (`A.0`, line 140).
pub const REVISION_CAPACITY: usize = 12;

/// One firmware revision as the unit wrote it, kept without borrowing the reply.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Revision {
    bytes: [u8; REVISION_CAPACITY],
    len: u8,
}

impl Revision {
    /// `text`, or `None` when it is longer than [`REVISION_CAPACITY`].
    pub fn new(text: &str) -> Option<Revision> {
        let mut bytes = [0u8; REVISION_CAPACITY];
        bytes
            .get_mut(..text.len())?
            .copy_from_slice(text.as_bytes());
        Some(Revision {
            bytes,
            len: u8::try_from(text.len()).ok()?,
        })
    }

    /// The revision's text.
    pub fn as_str(&self) -> &str {
        let bytes = self.bytes.get(..usize::from(self.len)).unwrap_or_default();
        core::str::from_utf8(bytes).unwrap_or_default()
    }
}

/// The 001 VERSION reply kept: power supply firmware, then gas console firmware (line 140).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Firmware {
    /// Power supply firmware.
    pub power_supply: Revision,
    /// Gas console firmware, when the reply has one.
    pub gas_console: Option<Revision>,
}

impl Firmware {
    /// The reply kept; `None` when a revision is longer than [`REVISION_CAPACITY`].
    pub fn new(version: &Version<'_>) -> Option<Firmware> {
        let gas_console = match version.gas_console {
            Some(text) => Some(Revision::new(text)?),
            None => None,
        };
        Some(Firmware {
            power_supply: Revision::new(version.power_supply)?,
            gas_console,
        })
    }
}

/// Snapshot of what the bridge knows about the unit.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UnitStatus {
    /// Family of the unit, once detected.
    pub family: Option<Family>,
    /// Model of the unit, once detected.
    pub model: Option<Model>,
    /// True while the unit answers.
    pub link_up: bool,
    /// True while the bridge holds the unit in remote control.
    pub remote: bool,
    /// Settings as the unit reports them (SYNC 0x3010-0x3012, legacy force registers read
    /// back when the unit allows it).
    pub settings: Option<PowermaxProcess>,
    /// Actual output current (SYNC).
    pub actual_current: Option<Amps>,
    /// Actual gas pressure (SYNC).
    pub actual_pressure: Option<Psi>,
    /// Active fault; `None` = no fault (or not known while the link is down).
    pub active_fault: Option<ActiveFault>,
    /// Permitted settings.
    pub limits: Option<Limits>,
    /// SYNC 0x3000: torch and power-supply type.
    pub identification: Option<Identification>,
    /// The conformity level the unit gave in its Read Device Identification reply
    /// (0x2B/0x0E) when it identified itself; `None` when it answered none.
    pub device_id_conformity: Option<u8>,
    /// Legacy torch-lead coils 0x0808/0x0809 (slow data); a SYNC unit has its lead in
    /// [`UnitStatus::identification`].
    pub legacy_lead: Option<LeadLength>,
    /// SYNC power-supply counters (0x3028-0x302F).
    pub ps_counters: Option<PsCounters>,
    /// Legacy arc-on time in seconds (0x209E-0x209F).
    pub arc_seconds: Option<u32>,
    /// SYNC cartridge: UID, part number, revision, nominal current, counters.
    pub cartridge: Option<Cartridge>,
    /// SYNC cartridge name (0x3048-0x304D).
    pub cartridge_name: Option<CartridgeName>,
    /// SYNC cartridge fault log (0x3044-0x3047).
    pub fault_log: Option<FaultLog>,
    /// HPR / MaxPro200 data.
    pub hpr: HprStatus,
    /// After a quick restart: no request (and no START) before this time.
    pub restart_blackout_until: Option<Instant>,
    /// True when the unit can take a start: link up, no blocking fault, no blackout, and
    /// (HPR) in its ready state.
    pub ready: bool,
}

impl UnitStatus {
    /// Forget everything learned from the unit (after link-down); what the link re-applies
    /// is not part of the status ([`Kept`](crate::link::Kept)).
    pub(crate) fn forget_unit(&mut self) {
        *self = UnitStatus::default();
    }

    /// The torch lead: a SYNC unit's from 0x3000 (Table 3), a legacy unit's from its coils.
    pub fn torch_lead(&self) -> Option<LeadLength> {
        match self.family {
            Some(Family::PowermaxSync) => self.identification.and_then(|i| i.torch).map(|t| t.lead),
            _ => self.legacy_lead,
        }
    }

    /// The unit's own state allows a start: an HPR or MaxPro200 in state 03 (Table V: IDLE2 /
    /// READY FOR START); a Powermax reports no such state, so always.
    pub fn state_ready(&self) -> bool {
        match self.family {
            Some(Family::Hpr) | Some(Family::MaxPro200) => self.hpr.state == Some(StateCode(3)),
            _ => true,
        }
    }

    /// Recompute [`UnitStatus::ready`] for time `now`.
    pub(crate) fn update_ready(&mut self, now: Instant) {
        let blackout = self.restart_blackout_until.is_some_and(|until| now < until);
        let fault_blocks = self.active_fault.is_some_and(|f| f.action_required());
        self.ready = self.link_up && !blackout && !fault_blocks && self.state_ready();
    }
}
