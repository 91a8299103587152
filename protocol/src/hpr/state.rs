//! State codes (manual section V), as returned by 002 GET_STATE and 079 GET_PS_INFO.
//!
//! The same number means different things on an HPR and a MaxPro200 (the table has one
//! column for each); "-----", "N/A" and blank cells are stored as `None`. Row 13 is blank in
//! both columns and so is absent.

/// A state code as the supply reports it. Meaning depends on the system family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StateCode(pub u16);

impl StateCode {
    /// HPR state 3, IDLE2 (MaxPro200: READY FOR START): the state 121 LEAK_CHECK_MODE and
    /// 137 SET PROCESS require.
    pub const READY: StateCode = StateCode(3);
    /// HPR state 5, PILOT ARC: HF ignition is active, serial traffic may be corrupted for up
    /// to 1 s (section VII.2 suggests pausing serial traffic while in it).
    pub const HPR_PILOT_ARC: StateCode = StateCode(5);
    /// MaxPro200 state 7, PILOT ARC.
    pub const MAXPRO_PILOT_ARC: StateCode = StateCode(7);
    /// State 14, SHUTDOWN (both families).
    pub const SHUTDOWN: StateCode = StateCode(14);

    /// Meaning on an HPR, if the manual gives one.
    pub fn hpr_name(self) -> Option<&'static str> {
        state_info(self.0).and_then(|s| s.hpr)
    }

    /// Meaning on a MaxPro200, if the manual gives one.
    pub fn maxpro200_name(self) -> Option<&'static str> {
        state_info(self.0).and_then(|s| s.maxpro200)
    }
}

/// One row of the state table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateInfo {
    /// Code number.
    pub code: u16,
    /// MaxPro200 column.
    pub maxpro200: Option<&'static str>,
    /// HPR column.
    pub hpr: Option<&'static str>,
}

const fn row(code: u16, maxpro200: Option<&'static str>, hpr: Option<&'static str>) -> StateInfo {
    StateInfo {
        code,
        maxpro200,
        hpr,
    }
}

/// Section V, ascending code.
pub const STATE_CODES: &[StateInfo] = &[
    row(0, Some("POWER UP"), Some("IDLE")),
    row(1, Some("INITIAL CHECKS"), None),
    row(2, Some("GAS PURGE"), Some("PURGE")),
    row(3, Some("READY FOR START"), Some("IDLE2")),
    row(4, Some("PREFLOW"), Some("PREFLOW")),
    row(5, Some("PREFLOW HOLD"), Some("PILOT ARC")),
    row(6, Some("IGNITE"), Some("TRANSFER")),
    row(7, Some("PILOT ARC"), Some("RAMPUP")),
    row(8, Some("RAMPUP"), Some("STEADY STATE")),
    row(9, Some("MAIN ARC"), Some("RAMPDOWN")),
    row(10, Some("RAMPDOWN"), Some("FINAL RAMPDOWN")),
    row(11, Some("RAMPDOWN COMPLETE"), Some("AUTO OFF")),
    row(12, Some("END OF CYCLE"), Some("TEST CUTFLOW")),
    row(14, Some("SHUTDOWN"), Some("SHUTDOWN")),
    row(15, Some("RESET"), Some("RESET")),
    row(16, Some("MAINTENANCE"), Some("MAINTENANCE")),
    // Printed "STANBY": a typo in the manual for STANDBY.
    row(17, Some("STANDBY"), None),
    row(20, None, Some("TEST PREFLOW")),
    row(22, None, Some("MANUAL PUMP CONTROL")),
    row(23, None, Some("INLET LEAK CHECK")),
    row(24, None, Some("SYSTEM LEAK CHECK")),
    row(25, None, Some("BURKERT FLOW CHECK")),
];

/// The table row for `code`, if the manual lists it.
pub fn state_info(code: u16) -> Option<&'static StateInfo> {
    STATE_CODES
        .binary_search_by_key(&code, |s| s.code)
        .ok()
        .and_then(|i| STATE_CODES.get(i))
}

/// HPR meaning of state `code`.
pub fn hpr_state_name(code: u16) -> Option<&'static str> {
    StateCode(code).hpr_name()
}

/// MaxPro200 meaning of state `code`.
pub fn maxpro200_state_name(code: u16) -> Option<&'static str> {
    StateCode(code).maxpro200_name()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_differ() {
        assert!(STATE_CODES.windows(2).all(|w| w[0].code < w[1].code));
        assert_eq!(hpr_state_name(5), Some("PILOT ARC"));
        assert_eq!(maxpro200_state_name(5), Some("PREFLOW HOLD"));
        assert_eq!(maxpro200_state_name(7), Some("PILOT ARC"));
        assert_eq!(hpr_state_name(1), None);
        assert_eq!(maxpro200_state_name(1), Some("INITIAL CHECKS"));
        assert_eq!(hpr_state_name(13), None);
        assert_eq!(maxpro200_state_name(13), None);
        assert_eq!(maxpro200_state_name(20), None);
        assert_eq!(hpr_state_name(20), Some("TEST PREFLOW"));
        assert_eq!(StateCode::SHUTDOWN.hpr_name(), Some("SHUTDOWN"));
        assert_eq!(hpr_state_name(26), None);
    }
}
