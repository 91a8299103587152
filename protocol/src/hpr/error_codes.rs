//! Error codes (manual section IV), as returned by 003 CURRENT_ERROR, 079 GET_PS_INFO and
//! 134 READ ERROR LOG.
//!
//! The table is complete as printed in the manual, including the codes revision N added for
//! the HPR400 (028, 034, 073-076, 095, 107, 146, 147, 154, 155, 157-160). Names and
//! descriptions are kept as printed.

use crate::text_table::Text;

/// An error code as the supply reports it (0 = no error).
///
/// Kept as a number so an unknown code from newer firmware still parses; [`name`](Self::name)
/// says whether the manual knows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorCode(pub u16);

impl ErrorCode {
    /// 000 NO ERROR.
    pub const NONE: ErrorCode = ErrorCode(0);

    /// Name from section IV, if the manual lists this code.
    pub fn name(self) -> Option<Text> {
        error_name(self.0)
    }

    /// Description from section IV, if the manual lists this code.
    #[cfg(feature = "descriptions")]
    pub fn description(self) -> Option<&'static str> {
        error_info(self.0).map(|e| e.description)
    }

    /// True for a code other than 0.
    pub fn is_error(self) -> bool {
        self.0 != 0
    }

    /// Codes 1-42: the ones 131 CLEAR WARNINGS clears ("error codes less than #43").
    pub fn is_warning(self) -> bool {
        (1..43).contains(&self.0)
    }

    /// Codes above 79: with state 14 (SHUTDOWN) this is the "shutdown error condition" in
    /// which an HPR accepts 068 SOFTWARE_RESET.
    pub fn is_shutdown_error(self) -> bool {
        self.0 > 79
    }
}

/// One row of the error table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ErrorInfo {
    /// Code number.
    pub code: u16,
    /// Name as printed.
    pub name: &'static str,
    /// Description as printed. Only host tools print it: the board shows the name, so its
    /// image leaves the ~5 KB of descriptions out (feature `descriptions`).
    #[cfg(feature = "descriptions")]
    pub description: &'static str,
}

/// A row; without the `descriptions` feature the text is dropped at compile time.
const fn row(code: u16, name: &'static str, description: &'static str) -> ErrorInfo {
    #[cfg(not(feature = "descriptions"))]
    let _ = description;
    ErrorInfo {
        code,
        name,
        #[cfg(feature = "descriptions")]
        description,
    }
}

/// The table, written once (`error_table.in`): the full rows ([`ERROR_CODES`], host tools)
/// and a compact name index for [`error_name`]. The board image keeps only the index, 4 bytes
/// a row, and the names packed by the build script (see [`crate::text_table`]).
macro_rules! error_table {
    ($(($code:literal, $name:literal, $description:literal $(,)?)),* $(,)?) => {
        /// Section IV, in the manual's order (ascending code).
        pub const ERROR_CODES: &[ErrorInfo] = &[$(row($code, $name, $description)),*];

        /// Each code with the end of its packed name (the start is the row before's end).
        static NAME_ENDS: [(u16, u16); ERROR_CODES.len()] =
            crate::text_table::code_ends([$($code),*], crate::text_table::ERROR_NAME_ENDS);
    };
}

include!("error_table.in");

/// The table row for `code`, if the manual lists it.
pub fn error_info(code: u16) -> Option<&'static ErrorInfo> {
    ERROR_CODES
        .binary_search_by_key(&code, |e| e.code)
        .ok()
        .and_then(|i| ERROR_CODES.get(i))
}

/// Name of error `code`, if the manual lists it (from the compact index, see [`error_table`]).
pub fn error_name(code: u16) -> Option<Text> {
    crate::text_table::text_of(&crate::text_table::ERROR_NAME_TEXTS, &NAME_ENDS, code)
}

/// Description of error `code`, if the manual lists it.
#[cfg(feature = "descriptions")]
pub fn error_description(code: u16) -> Option<&'static str> {
    error_info(code).map(|e| e.description)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_sorted_and_complete() {
        assert!(ERROR_CODES.windows(2).all(|w| w[0].code < w[1].code));
        assert_eq!(ERROR_CODES.len(), 88);
        // Codes added in revision N (HPR400) are all present.
        for code in [
            28, 34, 73, 74, 75, 76, 95, 107, 146, 147, 154, 155, 157, 158, 159, 160,
        ] {
            assert!(error_name(code).is_some(), "{code}");
        }
    }

    #[test]
    fn name_index_matches_the_rows() {
        assert_eq!(NAME_ENDS.len(), ERROR_CODES.len());
        for info in ERROR_CODES {
            assert_eq!(error_name(info.code).unwrap(), info.name, "{}", info.code);
        }
    }

    #[test]
    fn lookups() {
        assert_eq!(error_name(0).unwrap(), "NO ERROR");
        assert_eq!(ErrorCode(116).name().unwrap(), "WATCHDOG INTERLOCK");
        assert_eq!(error_name(50).unwrap(), "START ON AT INIT");
        #[cfg(feature = "descriptions")]
        assert_eq!(
            error_description(190),
            Some("Chopper B current signal is invalid")
        );
        assert!(error_name(1).is_none());
        assert!(error_name(999).is_none());
        assert!(ErrorCode(42).is_warning() && !ErrorCode(43).is_warning());
        assert!(!ErrorCode(0).is_warning() && !ErrorCode(0).is_error());
        assert!(ErrorCode(80).is_shutdown_error() && !ErrorCode(79).is_shutdown_error());
    }
}
