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
        names(self.0).1
    }

    /// Meaning on a MaxPro200, if the manual gives one.
    pub fn maxpro200_name(self) -> Option<&'static str> {
        names(self.0).0
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

/// The table, written once (`""` for a blank cell): the full rows ([`STATE_CODES`], host
/// tools) and a compact name index for the lookups. The board image keeps only the index:
/// 6 bytes a row and the names back to back, instead of a 20-byte row with two references.
macro_rules! state_table {
    ($(($code:literal, $maxpro200:literal, $hpr:literal)),* $(,)?) => {
        /// Section V, ascending code.
        pub const STATE_CODES: &[StateInfo] = &[$(row($code, cell($maxpro200), cell($hpr))),*];

        /// Each row's MaxPro200 name then its HPR name, in table order.
        const NAMES: &str = concat!($($maxpro200, $hpr),*);

        /// Each code with the ends of its two names in [`NAMES`].
        static NAME_ENDS: [(u16, u16, u16); STATE_CODES.len()] =
            name_ends([$(($code, $maxpro200.len(), $hpr.len())),*]);
    };
}

/// A table cell: blank is `None`.
const fn cell(name: &'static str) -> Option<&'static str> {
    if name.is_empty() { None } else { Some(name) }
}

/// Running ends of the names (`(code, MaxPro200 length, HPR length)` in).
const fn name_ends<const N: usize>(rows: [(u16, usize, usize); N]) -> [(u16, u16, u16); N] {
    let mut ends = [(0, 0, 0); N];
    let mut end = 0;
    let mut i = 0;
    while i < N {
        // Const evaluation only (the table), never input: an index out of range would fail
        // the build, not the bridge.
        #[allow(clippy::indexing_slicing)]
        {
            let (code, maxpro200, hpr) = rows[i];
            let maxpro200_end = end + maxpro200;
            end = maxpro200_end + hpr;
            ends[i] = (code, maxpro200_end as u16, end as u16);
        }
        i += 1;
    }
    ends
}

/// The (MaxPro200, HPR) names of `code`: spans of [`NAMES`], blank cells as `None`.
fn names(code: u16) -> (Option<&'static str>, Option<&'static str>) {
    let Ok(row) = NAME_ENDS.binary_search_by_key(&code, |&(c, _, _)| c) else {
        return (None, None);
    };
    let start = match row.checked_sub(1).and_then(|before| NAME_ENDS.get(before)) {
        Some(&(_, _, end)) => end,
        None => 0,
    };
    let Some(&(_, maxpro200_end, hpr_end)) = NAME_ENDS.get(row) else {
        return (None, None);
    };
    let name = |from: u16, to: u16| {
        NAMES
            .get(usize::from(from)..usize::from(to))
            .filter(|name| !name.is_empty())
    };
    (name(start, maxpro200_end), name(maxpro200_end, hpr_end))
}

state_table![
    (0, "POWER UP", "IDLE"),
    (1, "INITIAL CHECKS", ""),
    (2, "GAS PURGE", "PURGE"),
    (3, "READY FOR START", "IDLE2"),
    (4, "PREFLOW", "PREFLOW"),
    (5, "PREFLOW HOLD", "PILOT ARC"),
    (6, "IGNITE", "TRANSFER"),
    (7, "PILOT ARC", "RAMPUP"),
    (8, "RAMPUP", "STEADY STATE"),
    (9, "MAIN ARC", "RAMPDOWN"),
    (10, "RAMPDOWN", "FINAL RAMPDOWN"),
    (11, "RAMPDOWN COMPLETE", "AUTO OFF"),
    (12, "END OF CYCLE", "TEST CUTFLOW"),
    (14, "SHUTDOWN", "SHUTDOWN"),
    (15, "RESET", "RESET"),
    (16, "MAINTENANCE", "MAINTENANCE"),
    // Printed "STANBY": a typo in the manual for STANDBY.
    (17, "STANDBY", ""),
    (20, "", "TEST PREFLOW"),
    (22, "", "MANUAL PUMP CONTROL"),
    (23, "", "INLET LEAK CHECK"),
    (24, "", "SYSTEM LEAK CHECK"),
    (25, "", "BURKERT FLOW CHECK"),
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

    #[test]
    fn name_index_matches_the_rows() {
        assert_eq!(NAME_ENDS.len(), STATE_CODES.len());
        for info in STATE_CODES {
            let state = StateCode(info.code);
            assert_eq!(state.maxpro200_name(), info.maxpro200, "{}", info.code);
            assert_eq!(state.hpr_name(), info.hpr, "{}", info.code);
        }
        assert_eq!(STATE_CODES.len(), 22);
        assert_eq!(state_info(17).and_then(|s| s.hpr), None);
        assert_eq!(StateCode(17).maxpro200_name(), Some("STANDBY"));
    }
}
