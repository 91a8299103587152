//! State codes (manual section V), as returned by 002 GET_STATE and 079 GET_PS_INFO.
//!
//! The same number means different things on an HPR and a MaxPro200 (the table has one
//! column for each); "-----", "N/A" and blank cells are stored as `None`. Row 13 is blank in
//! both columns and so is absent.

use crate::text_table::Text;

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
    pub fn hpr_name(self) -> Option<Text> {
        names(self.0).1
    }

    /// Meaning on a MaxPro200, if the manual gives one.
    pub fn maxpro200_name(self) -> Option<Text> {
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

/// The table, written once (`state_table.in`, `""` for a blank cell): the full rows
/// ([`STATE_CODES`], host tools) and a compact name index for the lookups. The board image
/// keeps only the index, 6 bytes a row, and the names packed by the build script (see
/// [`crate::text_table`]).
macro_rules! state_table {
    ($(($code:literal, $maxpro200:literal, $hpr:literal)),* $(,)?) => {
        /// Section V, ascending code.
        pub const STATE_CODES: &[StateInfo] = &[$(row($code, cell($maxpro200), cell($hpr))),*];

        /// Each code with the packed ends of its two names.
        static NAME_ENDS: [(u16, u16, u16); STATE_CODES.len()] =
            name_ends([$($code),*], crate::text_table::STATE_NAME_ENDS);
    };
}

/// A table cell: blank is `None`.
const fn cell(name: &'static str) -> Option<&'static str> {
    if name.is_empty() { None } else { Some(name) }
}

/// Each code with the ends of its two names (`ends`: each row's MaxPro200 end then its HPR
/// end).
const fn name_ends<const N: usize, const CELLS: usize>(
    codes: [u16; N],
    ends: [u16; CELLS],
) -> [(u16, u16, u16); N] {
    let mut out = [(0, 0, 0); N];
    let mut i = 0;
    while i < N {
        // Const evaluation only (the table), never input: an index out of range (a cell
        // count other than two a row) would fail the build, not the bridge.
        #[allow(clippy::indexing_slicing)]
        {
            out[i] = (codes[i], ends[2 * i], ends[2 * i + 1]);
        }
        i += 1;
    }
    out
}

/// The (MaxPro200, HPR) names of `code`: spans of the packed names, blank cells as `None`.
fn names(code: u16) -> (Option<Text>, Option<Text>) {
    let Ok(row) = NAME_ENDS.binary_search_by_key(&code, |&(c, _, _)| c) else {
        return (None, None);
    };
    // Cell `2 * row` is the row's MaxPro200 name, `2 * row + 1` its HPR name.
    let cell = |cell: usize| {
        let ends = |cell: usize| {
            let &(_, maxpro200, hpr) = NAME_ENDS.get(cell / 2)?;
            Some(if cell.is_multiple_of(2) {
                maxpro200
            } else {
                hpr
            })
        };
        crate::text_table::span(&crate::text_table::STATE_NAME_TEXTS, ends, cell)
            .filter(|name| !name.is_empty())
    };
    (cell(2 * row), cell(2 * row + 1))
}

include!("state_table.in");

/// The table row for `code`, if the manual lists it.
pub fn state_info(code: u16) -> Option<&'static StateInfo> {
    STATE_CODES
        .binary_search_by_key(&code, |s| s.code)
        .ok()
        .and_then(|i| STATE_CODES.get(i))
}

/// HPR meaning of state `code`.
pub fn hpr_state_name(code: u16) -> Option<Text> {
    StateCode(code).hpr_name()
}

/// MaxPro200 meaning of state `code`.
pub fn maxpro200_state_name(code: u16) -> Option<Text> {
    StateCode(code).maxpro200_name()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The packed name is the row's name (both blank, or the same text).
    fn same(packed: Option<Text>, row: Option<&str>) -> bool {
        match (packed, row) {
            (Some(packed), Some(row)) => packed == row,
            (packed, row) => packed.is_none() && row.is_none(),
        }
    }

    #[test]
    fn columns_differ() {
        assert!(STATE_CODES.windows(2).all(|w| w[0].code < w[1].code));
        assert_eq!(hpr_state_name(5).unwrap(), "PILOT ARC");
        assert_eq!(maxpro200_state_name(5).unwrap(), "PREFLOW HOLD");
        assert_eq!(maxpro200_state_name(7).unwrap(), "PILOT ARC");
        assert!(hpr_state_name(1).is_none());
        assert_eq!(maxpro200_state_name(1).unwrap(), "INITIAL CHECKS");
        assert!(hpr_state_name(13).is_none());
        assert!(maxpro200_state_name(13).is_none());
        assert!(maxpro200_state_name(20).is_none());
        assert_eq!(hpr_state_name(20).unwrap(), "TEST PREFLOW");
        assert_eq!(StateCode::SHUTDOWN.hpr_name().unwrap(), "SHUTDOWN");
        assert!(hpr_state_name(26).is_none());
    }

    #[test]
    fn name_index_matches_the_rows() {
        assert_eq!(NAME_ENDS.len(), STATE_CODES.len());
        for info in STATE_CODES {
            let state = StateCode(info.code);
            assert!(
                same(state.maxpro200_name(), info.maxpro200),
                "{}",
                info.code
            );
            assert!(same(state.hpr_name(), info.hpr), "{}", info.code);
        }
        assert_eq!(STATE_CODES.len(), 22);
        assert_eq!(state_info(17).and_then(|s| s.hpr), None);
        assert_eq!(StateCode(17).maxpro200_name().unwrap(), "STANDBY");
    }
}
