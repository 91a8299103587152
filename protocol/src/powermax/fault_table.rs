//! The fault tables, transcribed row by row.
//!
//! Texts are kept ASCII (they may be forwarded to a CNC terminal): typographic quotes and
//! dashes became ASCII, the check-mark symbol is spelled out. A model restriction printed as a
//! leading "(Powermax65/85/105 SYNC)" is moved to [`SyncModels`].

use super::fault::{StepsRequired, SyncModels};

pub(super) use crate::text_table::{LEGACY_FAULT_TEXTS, SYNC_FAULT_TEXTS};

/// A row of the SYNC table as the image stores it: the text is a span of the packed
/// [`SYNC_FAULT_TEXTS`] ending at `end` (starting where the row before ends). Six bytes a row
/// instead of a 12-byte row with a reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct SyncRow {
    pub code: u16,
    pub end: u16,
    pub steps: StepsRequired,
    pub models: SyncModels,
}

/// The SYNC table, written once (`sync_faults.in`): the row index here, the texts packed by
/// the build script (see [`crate::text_table`]).
macro_rules! sync_faults {
    ($(($code:literal, $models:expr, $steps:expr, $text:literal $(,)?)),* $(,)?) => {
        /// SYNC guide, Table 6 "Fault codes and descriptions": all 66 rows, in table order.
        pub(super) static SYNC_FAULTS: [SyncRow; 66] = sync_rows(
            [$(($code, $models, $steps)),*],
            crate::text_table::SYNC_FAULT_ENDS,
        );
    };
}

/// The rows with their packed text ends (`(code, models, steps)` and the ends in row order).
const fn sync_rows<const N: usize>(
    rows: [(u16, SyncModels, StepsRequired); N],
    ends: [u16; N],
) -> [SyncRow; N] {
    let mut out = [SyncRow {
        code: 0,
        end: 0,
        steps: StepsRequired::No,
        models: SyncModels::All,
    }; N];
    let mut i = 0;
    while i < N {
        // Const evaluation only (the table), never input: an index out of range would fail
        // the build, not the bridge.
        #[allow(clippy::indexing_slicing)]
        {
            let (code, models, steps) = rows[i];
            out[i] = SyncRow {
                code,
                end: ends[i],
                steps,
                models,
            };
        }
        i += 1;
    }
    out
}

use StepsRequired::{No, Recommended, Yes};
use SyncModels::{All, Powermax45, Powermax65_85_105};

include!("sync_faults.in");

/// The legacy list, written once (`legacy_faults.in`): a (code, end) index here, the texts
/// packed by the build script, 4 bytes a row instead of a 12-byte (code, text) pair.
macro_rules! legacy_faults {
    ($(($code:literal, $text:literal)),* $(,)?) => {
        /// Legacy Powermax65/85 guide (807220), "Fault Codes": all 18 rows, in table order,
        /// each code with the end of its text in [`LEGACY_FAULT_TEXTS`]. The guide calls the
        /// list partial ("summarizes some fault codes") and has no action column.
        pub(super) static LEGACY_FAULTS: [(u16, u16); 18] =
            crate::text_table::code_ends([$($code),*], crate::text_table::LEGACY_FAULT_ENDS);
    };
}

include!("legacy_faults.in");
