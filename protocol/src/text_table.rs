//! The long text tables (SYNC and legacy Powermax fault texts, HPR error and state names),
//! packed when the crate is built.
//!
//! Each table's rows are written once, in an `.in` file holding one macro call. The module
//! that owns the table includes it with a macro that builds the row index; the crate's build
//! script includes the same file with a macro that keeps only the texts, and packs them:
//! a dictionary of the phrases that recur across all tables (" occurred", "plasma power
//! supply", " CURRENT", ...), chosen greedily by the bytes each saves, and every text with
//! byte `0x80 + i` where it used entry `i`. The texts are printable ASCII (the build script
//! refuses others), so a byte below 0x80 is itself; each entry ends with a NUL, which the
//! texts never hold. 6.6 KB of text become 3.5 KB (2.3 KB of packed texts, 1.2 KB of
//! entries); the tests here decode every row back to its source text. The build script runs
//! only when a table's rows change (under a second), and picks the same entries on every
//! machine (ties go to the smaller phrase), so the board image stays reproducible.
//!
//! A table's packed texts lie back to back with a `(code, end)` index, 4 bytes a row instead
//! of a row with a reference. A lookup gives a [`Text`], which writes itself piece by piece
//! (no buffer): with `Display`, and with `defmt::Format` under the `defmt` feature.

use core::fmt;

include!(concat!(env!("OUT_DIR"), "/text_tables.rs"));

/// A text from one of the packed tables (or a plain one, for a fallback such as "No fault").
/// Written with `Display`; host code may call `to_string()`.
#[derive(Clone, Copy)]
pub struct Text(Repr);

#[derive(Clone, Copy)]
enum Repr {
    Packed(&'static [u8]),
    Plain(&'static str),
}

impl Text {
    /// A text that is not in a table, written as it is.
    pub const fn plain(text: &'static str) -> Text {
        Text(Repr::Plain(text))
    }

    /// The text's pieces in order: runs of plain text and dictionary entries.
    pub fn pieces(self) -> Pieces {
        Pieces(self.0)
    }

    /// The text's bytes in order.
    pub fn bytes(self) -> impl Iterator<Item = u8> {
        self.pieces().flat_map(str::bytes)
    }

    /// True when the text is empty.
    pub fn is_empty(self) -> bool {
        self.pieces().all(str::is_empty)
    }
}

/// The pieces of a [`Text`] (see [`Text::pieces`]).
pub struct Pieces(Repr);

impl Iterator for Pieces {
    type Item = &'static str;

    fn next(&mut self) -> Option<&'static str> {
        let rest = match self.0 {
            Repr::Plain(text) if !text.is_empty() => {
                self.0 = Repr::Plain("");
                return Some(text);
            }
            Repr::Plain(_) => return None,
            Repr::Packed(rest) => rest,
        };
        let (&first, after) = rest.split_first()?;
        if first >= 0x80 {
            self.0 = Repr::Packed(after);
            return dictionary_entry(first - 0x80);
        }
        let plain = rest.iter().position(|&b| b >= 0x80).unwrap_or(rest.len());
        self.0 = Repr::Packed(rest.get(plain..)?);
        // The build script checked the texts are ASCII, so the run is valid UTF-8.
        core::str::from_utf8(rest.get(..plain)?).ok()
    }
}

/// Dictionary entry `index`: the text before its NUL.
fn dictionary_entry(index: u8) -> Option<&'static str> {
    let mut start = 0;
    let mut entry = 0;
    for (at, &byte) in DICTIONARY.as_bytes().iter().enumerate() {
        if byte == 0 {
            if entry == usize::from(index) {
                return DICTIONARY.get(start..at);
            }
            entry += 1;
            start = at + 1;
        }
    }
    None
}

impl fmt::Display for Text {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.pieces().try_for_each(|piece| f.write_str(piece))
    }
}

impl fmt::Debug for Text {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use fmt::Write;
        f.write_char('"')?;
        for piece in self.pieces() {
            write!(f, "{}", piece.escape_debug())?;
        }
        f.write_char('"')
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for Text {
    fn format(&self, f: defmt::Formatter<'_>) {
        for piece in self.pieces() {
            defmt::write!(f, "{=str}", piece);
        }
    }
}

/// Same text, however stored.
impl PartialEq for Text {
    fn eq(&self, other: &Text) -> bool {
        self.bytes().eq(other.bytes())
    }
}

impl Eq for Text {}

impl PartialEq<str> for Text {
    fn eq(&self, other: &str) -> bool {
        self.bytes().eq(other.bytes())
    }
}

impl PartialEq<&str> for Text {
    fn eq(&self, other: &&str) -> bool {
        self.bytes().eq(other.bytes())
    }
}

/// Each code with the packed end of its text (`codes` and `ends` in row order).
pub(crate) const fn code_ends<const N: usize>(codes: [u16; N], ends: [u16; N]) -> [(u16, u16); N] {
    let mut out = [(0, 0); N];
    let mut i = 0;
    while i < N {
        // Const evaluation only (the tables), never input.
        #[allow(clippy::indexing_slicing)]
        {
            out[i] = (codes[i], ends[i]);
        }
        i += 1;
    }
    out
}

/// The span of `texts` that ends at `row`'s end and starts where the row before ends.
pub(crate) fn span(
    texts: &'static [u8],
    ends: impl Fn(usize) -> Option<u16>,
    row: usize,
) -> Option<Text> {
    let end = ends(row)?;
    let start = match row.checked_sub(1) {
        Some(before) => ends(before)?,
        None => 0,
    };
    texts
        .get(usize::from(start)..usize::from(end))
        .map(|packed| Text(Repr::Packed(packed)))
}

/// The text of `code` in a table with a `(code, end)` index.
pub(crate) fn text_of(texts: &'static [u8], index: &[(u16, u16)], code: u16) -> Option<Text> {
    let row = index.iter().position(|&(c, _)| c == code)?;
    span(texts, |row| index.get(row).map(|&(_, end)| end), row)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::{String, ToString};
    use std::vec::Vec;

    use super::*;

    #[test]
    fn spans_follow_each_other() {
        static TEXTS: [u8; 11] = *b"onetwothree";
        static INDEX: [(u16, u16); 3] = code_ends([7, 2, 40], [3, 6, 11]);
        assert_eq!(INDEX, [(7, 3), (2, 6), (40, 11)]);
        assert_eq!(text_of(&TEXTS, &INDEX, 7).unwrap(), "one");
        assert_eq!(text_of(&TEXTS, &INDEX, 2).unwrap(), "two");
        assert_eq!(text_of(&TEXTS, &INDEX, 40).unwrap(), "three");
        assert!(text_of(&TEXTS, &INDEX, 3).is_none());
    }

    #[test]
    fn entries_expand_between_plain_runs() {
        static TEXTS: [u8; 5] = [b'<', 0x80, b'|', 0x81, b'>'];
        let text = span(&TEXTS, |row| (row == 0).then_some(5), 0).unwrap();
        let first = dictionary_entry(0).unwrap();
        let second = dictionary_entry(1).unwrap();
        let expected = std::format!("<{first}|{second}>");
        assert_eq!(text.to_string(), expected);
        assert_eq!(
            text.pieces().collect::<Vec<_>>(),
            ["<", first, "|", second, ">"]
        );
        assert_eq!(std::format!("{text:?}"), std::format!("{expected:?}"));
        assert!(text == expected.as_str() && text != "<");
        // A code past the dictionary (none is written) ends the text rather than panic.
        assert_eq!(
            dictionary_entry(0xFF - 0x80).is_some(),
            DICTIONARY.matches('\0').count() == 0x80
        );
        assert_eq!(dictionary_entry(200), None);
    }

    #[test]
    fn plain_texts_are_written_as_they_are() {
        let text = Text::plain("No fault");
        assert_eq!(text.to_string(), "No fault");
        assert!(!text.is_empty() && Text::plain("").is_empty());
        assert_eq!(text, Text::plain("No fault"));
    }

    /// The packed tables, texts and dictionary together, are smaller than the plain texts.
    #[test]
    fn packing_saves_bytes() {
        let plain: usize = all_plain_texts().iter().map(String::len).sum();
        let packed = SYNC_FAULT_TEXTS.len()
            + LEGACY_FAULT_TEXTS.len()
            + ERROR_NAME_TEXTS.len()
            + STATE_NAME_TEXTS.len()
            + DICTIONARY.len();
        assert!(
            packed * 10 < plain * 6,
            "packed {packed} B, plain {plain} B"
        );
    }

    /// Every row of every table (expanded from the same `.in` files into plain strings)
    /// decodes to its source text.
    #[test]
    fn every_row_decodes_to_its_source_text() {
        let tables: [(&[u8], &[u16], Vec<String>); 4] = [
            (&SYNC_FAULT_TEXTS, &SYNC_FAULT_ENDS, plain::sync()),
            (&LEGACY_FAULT_TEXTS, &LEGACY_FAULT_ENDS, plain::legacy()),
            (&ERROR_NAME_TEXTS, &ERROR_NAME_ENDS, plain::error_names()),
            (&STATE_NAME_TEXTS, &STATE_NAME_ENDS, plain::state_names()),
        ];
        for (texts, ends, plain) in tables {
            assert_eq!(ends.len(), plain.len());
            assert_eq!(ends.last().map(|&end| usize::from(end)), Some(texts.len()));
            for (row, source) in plain.iter().enumerate() {
                let text = span(texts, |row| ends.get(row).copied(), row).unwrap();
                assert_eq!(text.to_string(), *source, "row {row}");
                assert!(text == source.as_str());
            }
        }
    }

    fn all_plain_texts() -> Vec<String> {
        [
            plain::sync(),
            plain::legacy(),
            plain::error_names(),
            plain::state_names(),
        ]
        .concat()
    }

    /// The `.in` files expanded into plain strings.
    mod plain {
        extern crate std;
        use std::string::{String, ToString};
        use std::vec::Vec;

        macro_rules! sync_faults {
            ($(($code:literal, $models:expr, $steps:expr, $text:literal $(,)?)),* $(,)?) => {
                pub fn sync() -> Vec<String> {
                    [$($text),*].iter().map(|t| t.to_string()).collect()
                }
            };
        }
        macro_rules! legacy_faults {
            ($(($code:literal, $text:literal)),* $(,)?) => {
                pub fn legacy() -> Vec<String> {
                    [$($text),*].iter().map(|t| t.to_string()).collect()
                }
            };
        }
        macro_rules! error_table {
            ($(($code:literal, $name:literal, $description:literal $(,)?)),* $(,)?) => {
                pub fn error_names() -> Vec<String> {
                    [$($name),*].iter().map(|t| t.to_string()).collect()
                }
            };
        }
        macro_rules! state_table {
            ($(($code:literal, $maxpro200:literal, $hpr:literal)),* $(,)?) => {
                pub fn state_names() -> Vec<String> {
                    [$($maxpro200, $hpr),*].iter().map(|t| t.to_string()).collect()
                }
            };
        }
        include!("powermax/sync_faults.in");
        include!("powermax/legacy_faults.in");
        include!("hpr/error_table.in");
        include!("hpr/state_table.in");
    }
}
