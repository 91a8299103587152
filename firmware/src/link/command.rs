//! What the CNC session can ask of the link, and why the link may refuse before sending.

use plasma_protocol::hpr::{
    ErrorCode, GasFlows, GasPair, HprParameters, MaxProParameters, MaxProPressures, StateCode,
    SystemId,
};
use plasma_protocol::powermax::sync::PermittedModes;
use plasma_protocol::powermax::{Amps, FaultCode, OperatingMode, Pressure, Psi};

use super::status::Family;
use plasma_protocol::time::Instant;

/// Longest RAW frame accepted (a Modbus ASCII frame is at most 513 characters); the session
/// refuses a longer one before it reaches the link.
pub const RAW_CAPACITY: usize = 520;

/// An operation asked of the link; it completes with `LinkEvent::CommandDone`.
///
/// A RAW frame is borrowed: `submit` parses it into the link's own request before it
/// returns, so the command stays a few bytes instead of carrying a frame buffer through
/// every caller.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkCommand<'a> {
    /// Powermax: enter remote control with these settings. Checked against the permitted
    /// limits first; written in one request (SYNC) or as the legacy guide requires, read back,
    /// then kept and re-applied after a power cycle or a link return.
    ApplyProcess {
        /// Operating mode.
        mode: OperatingMode,
        /// Output current.
        current: Amps,
        /// Gas pressure; [`Pressure::Auto`] lets the unit choose.
        pressure: Pressure,
    },
    /// Powermax: leave remote control (zeros to all three settings) and forget the kept
    /// settings.
    ExitRemote,
    /// Powermax: start (`true`) or stop a gas test.
    GasTest {
        /// Start or stop.
        on: bool,
    },
    /// Powermax SYNC: quick restart that clears fault 0-50-0 (refused unless 0-50-0 is
    /// active); no request for 2 s afterwards.
    QuickRestart,
    /// Read the slow data again (limits, counters, cartridge, fault or error log, timers).
    RefreshSlowData,
    /// HPR / MaxPro200: set the current (058).
    HprSetNominalAmps {
        /// Amps (5 up to the unit's rating).
        amps: u16,
    },
    /// MaxPro200: 137 SET PROCESS, current and gases (the unit sets the pressures); kept and
    /// re-applied like the current.
    MaxProSetProcess {
        /// Amps, 5-200.
        amps: u16,
        /// Plasma and shield gases.
        gases: GasPair,
    },
    /// HPR (automatic gas console): 095 SET_ALL_PARAMETERS, current, corner current, gases and
    /// the six pressure set points. The unit only acknowledges it: the link reads the values
    /// back before it counts as done (`hpr::confirm`), then keeps and re-applies it.
    HprSetAllParameters(HprParameters),
    /// MaxPro200: 095 SET_ALL_PARAMETERS, current, gases and the two pressure set points; read
    /// back, kept and re-applied as the HPR's.
    MaxProSetAllParameters(MaxProParameters),
    /// HPR (automatic gas console): 078 SET_ALL_GAS_FLOWS, the six pressure set points; read
    /// back, kept and re-applied.
    HprSetAllGasFlows(GasFlows),
    /// MaxPro200: 078 SET_ALL_GAS_FLOWS, the plasma and shield pressure set points; read back,
    /// kept and re-applied.
    MaxProSetAllGasFlows(MaxProPressures),
    /// HPR (auto gas) / MaxPro200: set the inlet gases (096).
    HprSetInletGases(GasPair),
    /// HPR: corner current percent 50-100 (070).
    HprSetCornerCurrent {
        /// Percent of the cutting current.
        percent: u8,
    },
    /// HPR: clear warnings (131, error codes below 43).
    HprClearWarnings,
    /// HPR / MaxPro200: software reset (068), only when the manual allows it.
    HprSoftwareReset,
    /// HPR: start or stop the preflow (064 / 065) or cutflow (066 / 067) gas test.
    HprGasTest {
        /// The cutflow test; `false`: the preflow test.
        cutflow: bool,
        /// Start or stop.
        on: bool,
    },
    /// MaxPro200: 143 SET TEST MODE 1 "Test Gas" (start, only in state 3) or 0 "No test".
    MaxProTestGas {
        /// Start or stop.
        on: bool,
    },
    /// Powermax: read the actual gas pressure (SYNC 0x3019, legacy 0x204C) now, not at the
    /// next poll: the gas check's reading while the gas flows.
    ReadGasPressure,
    /// HPR: read the measured pressures (079) now: the gas check's reading.
    HprReadGasPressures,
    /// MaxPro200: read the measured pressures (141 GET MFG DATA1; its 079 has set points
    /// only) now: the gas check's reading.
    MaxProReadGasPressures,
    /// HPR: read the error log (134).
    HprReadErrorLog,
    /// HPR: read the timers and counters (125).
    HprReadTimers,
    /// A whole frame to forward as is (Modbus `:...\r\n` or HPR `>...<`), subject to the
    /// allow-lists; the reply frame is returned.
    Raw(&'a [u8]),
}

impl LinkCommand<'_> {
    /// True when the driver of `family` carries the command out: the link refuses the others
    /// with [`Refusal::NotSupported`] before anything is sent. The CNC command table
    /// (`cnc/table.rs`) sends a family only what this accepts; a test there ties the two.
    pub const fn runs_on(&self, family: Family) -> bool {
        let powermax = family.is_modbus();
        match self {
            LinkCommand::ApplyProcess { .. }
            | LinkCommand::ExitRemote
            | LinkCommand::GasTest { .. }
            | LinkCommand::ReadGasPressure => powermax,
            // Quick restart (clears 0-50-0) exists on SYNC units only.
            LinkCommand::QuickRestart => matches!(family, Family::PowermaxSync),
            // Every family's slow data can be read again (a MaxPro200 has none: done at once).
            LinkCommand::RefreshSlowData | LinkCommand::Raw(_) => true,
            LinkCommand::HprSetNominalAmps { .. }
            | LinkCommand::HprSetInletGases(_)
            | LinkCommand::HprSoftwareReset => !powermax,
            // The MaxPro200 protocol has none of these.
            LinkCommand::HprSetCornerCurrent { .. }
            | LinkCommand::HprClearWarnings
            | LinkCommand::HprGasTest { .. }
            | LinkCommand::HprReadGasPressures
            | LinkCommand::HprReadErrorLog
            | LinkCommand::HprReadTimers
            | LinkCommand::HprSetAllParameters(_)
            | LinkCommand::HprSetAllGasFlows(_) => matches!(family, Family::Hpr),
            LinkCommand::MaxProTestGas { .. }
            | LinkCommand::MaxProSetProcess { .. }
            | LinkCommand::MaxProSetAllParameters(_)
            | LinkCommand::MaxProSetAllGasFlows(_)
            | LinkCommand::MaxProReadGasPressures => {
                matches!(family, Family::MaxPro200)
            }
        }
    }
}

/// Which HPR value was out of range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HprValue {
    /// Current in amps.
    Amps,
    /// Corner current percent.
    CornerPercent,
    /// A gas type code or pressure set point.
    GasParameter,
}

impl HprValue {
    /// The word for error texts.
    pub const fn word(self) -> &'static str {
        match self {
            HprValue::Amps => "amps",
            HprValue::CornerPercent => "percent",
            HprValue::GasParameter => "gas parameter",
        }
    }
}

/// Why a command was refused; nothing was sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// No unit is connected (detection running or link down).
    LinkNotUp,
    /// The command does not exist for this family.
    NotSupported {
        /// The family on the line.
        family: Family,
    },
    /// The permitted limits have not been read yet.
    LimitsUnknown,
    /// The mode is not permitted for the installed cartridge.
    ModeNotPermitted {
        /// Mode asked for.
        mode: OperatingMode,
        /// Modes permitted (0x3001).
        permitted: PermittedModes,
    },
    /// Current outside the permitted range.
    CurrentOutOfRange {
        /// Asked for.
        requested: Amps,
        /// Lowest permitted.
        min: Amps,
        /// Highest permitted.
        max: Amps,
    },
    /// Pressure set point outside the permitted range.
    PressureOutOfRange {
        /// Asked for.
        requested: Psi,
        /// Lowest permitted.
        min: Psi,
        /// Highest permitted.
        max: Psi,
    },
    /// A quick restart only clears 0-50-0, which is not active.
    QuickRestartNeeds050 {
        /// The fault that is active instead, if any.
        active: Option<FaultCode>,
    },
    /// Within the 2 s after a quick restart.
    Blackout {
        /// End of the blackout.
        until: Instant,
    },
    /// Too many commands waiting.
    QueueFull,
    /// An HPR value outside the manual's range (or the unit's rating).
    HprValueOutOfRange {
        /// Which value.
        value: HprValue,
        /// Asked for.
        requested: u16,
        /// Lowest allowed.
        min: u16,
        /// Highest allowed.
        max: u16,
    },
    /// The unit's state does not allow the command (HPR software reset: only in a shutdown
    /// error, state 14 with error > 79; MaxPro200: not while cutting, states 4-10).
    StateForbids {
        /// Current state, if known.
        state: Option<StateCode>,
        /// Current error, if known.
        error: Option<ErrorCode>,
    },
    /// The manual's "System" column does not name the unit's system for this HPR command
    /// (058 SET_NOMINAL_AMPS on a manual gas console HPR: "Auto Gas System MaxPro200").
    NotOnThisSystem {
        /// Command id.
        id: u16,
        /// The unit, as HELLO named it.
        system: SystemId,
    },
    /// The RAW frame could not be parsed (framing, checksum, PDU).
    RawMalformed(plasma_protocol::Error),
    /// The RAW Modbus frame names another node.
    RawWrongAddress {
        /// Node address of the link.
        expected: u8,
        /// Address in the frame.
        found: u8,
    },
    /// The RAW Modbus function is neither a read nor an allowed write.
    RawFunctionNotAllowed {
        /// Function code.
        function: u8,
    },
    /// The RAW Modbus write targets a register or coil not documented as writable.
    RawWriteNotAllowed {
        /// First address written.
        address: u16,
    },
    /// The RAW HPR command is not on the allow-list (factory-only, dangerous or unknown),
    /// or is line control the link owns (SLEEP/WAKE/BROADCAST).
    RawCommandNotAllowed {
        /// Command id.
        id: u16,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_family_runs_the_requests_its_driver_has_and_nothing_else() {
        use Family::{Hpr, MaxPro200, PowermaxLegacy, PowermaxSync};
        assert!(LinkCommand::HprSetCornerCurrent { percent: 80 }.runs_on(Hpr));
        assert!(!LinkCommand::HprSetCornerCurrent { percent: 80 }.runs_on(MaxPro200));
        let cutflow_test = LinkCommand::HprGasTest {
            cutflow: true,
            on: true,
        };
        assert!(!cutflow_test.runs_on(MaxPro200));
        assert!(LinkCommand::MaxProTestGas { on: true }.runs_on(MaxPro200));
        assert!(!LinkCommand::MaxProTestGas { on: true }.runs_on(Hpr));
        // 095 and 078 take another form on each (HPR manual lines 165 and 180).
        let hpr_flows = LinkCommand::HprSetAllGasFlows(GasFlows::default());
        let maxpro_flows = LinkCommand::MaxProSetAllGasFlows(MaxProPressures::default());
        assert!(hpr_flows.runs_on(Hpr) && !hpr_flows.runs_on(MaxPro200));
        assert!(maxpro_flows.runs_on(MaxPro200) && !maxpro_flows.runs_on(Hpr));
        assert!(LinkCommand::QuickRestart.runs_on(PowermaxSync));
        assert!(!LinkCommand::QuickRestart.runs_on(PowermaxLegacy));
        assert!(LinkCommand::RefreshSlowData.runs_on(PowermaxLegacy));
        assert!(LinkCommand::RefreshSlowData.runs_on(MaxPro200));
        assert!(LinkCommand::RefreshSlowData.runs_on(Hpr));
        let settings = LinkCommand::ApplyProcess {
            mode: OperatingMode::Cut,
            current: Amps::from_raw(45 * Amps::STEPS_PER_UNIT),
            pressure: Pressure::Auto,
        };
        assert!(!settings.runs_on(Hpr));
        for family in [PowermaxSync, PowermaxLegacy, Hpr, MaxPro200] {
            assert!(LinkCommand::Raw(b">0020D<").runs_on(family));
            // A Powermax request never goes to an HPR or MaxPro200, an HPR request never to a
            // Powermax.
            assert_eq!(settings.runs_on(family), family.is_modbus());
            let hpr_requests = [
                LinkCommand::HprSetNominalAmps { amps: 100 },
                LinkCommand::HprSetCornerCurrent { percent: 80 },
                LinkCommand::HprClearWarnings,
                LinkCommand::HprSoftwareReset,
                cutflow_test,
                LinkCommand::MaxProTestGas { on: false },
                LinkCommand::HprReadErrorLog,
                LinkCommand::HprReadTimers,
            ];
            for request in hpr_requests {
                assert!(
                    !(request.runs_on(family) && family.is_modbus()),
                    "{request:?}"
                );
            }
        }
    }
}
