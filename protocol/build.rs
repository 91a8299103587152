//! Packs the long text tables (SYNC and legacy Powermax fault texts, HPR error and state names)
//! into `$OUT_DIR/text_tables.rs`, which `src/text_table.rs` includes.
//!
//! The rows are read from the same `.in` files the library includes, with `macro_rules!`
//! definitions here that keep only the texts. One dictionary serves every table: greedy, each
//! round taking the phrase that saves the most bytes, until the 128 codes above ASCII are
//! used or no phrase saves anything. Ties go to the smaller phrase, so the output is the same
//! bytes on every machine (the board image is reproducible).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::{env, fs};

mod rows {
    macro_rules! sync_faults {
        ($(($code:literal, $models:expr, $steps:expr, $text:literal $(,)?)),* $(,)?) => {
            pub const SYNC_FAULTS: &[&str] = &[$($text),*];
        };
    }
    macro_rules! legacy_faults {
        ($(($code:literal, $text:literal)),* $(,)?) => {
            pub const LEGACY_FAULTS: &[&str] = &[$($text),*];
        };
    }
    macro_rules! error_table {
        ($(($code:literal, $name:literal, $description:literal $(,)?)),* $(,)?) => {
            pub const ERROR_NAMES: &[&str] = &[$($name),*];
        };
    }
    macro_rules! state_table {
        ($(($code:literal, $maxpro200:literal, $hpr:literal)),* $(,)?) => {
            /// Each row's MaxPro200 cell then its HPR cell.
            pub const STATE_NAMES: &[&str] = &[$($maxpro200, $hpr),*];
        };
    }
    include!("src/powermax/sync_faults.in");
    include!("src/powermax/legacy_faults.in");
    include!("src/hpr/error_table.in");
    include!("src/hpr/state_table.in");
}

/// The tables in output order: the constant names the library uses, and their texts.
const TABLES: [(&str, &[&str]); 4] = [
    ("SYNC_FAULT", rows::SYNC_FAULTS),
    ("LEGACY_FAULT", rows::LEGACY_FAULTS),
    ("ERROR_NAME", rows::ERROR_NAMES),
    ("STATE_NAME", rows::STATE_NAMES),
];

/// The first byte that names a dictionary entry (bytes below it are ASCII text).
const FIRST_CODE: usize = 0x80;
/// Longest phrase considered: longer ones recur too rarely to matter, and the search stays
/// quick in an unoptimised build script.
const LONGEST_PHRASE: usize = 48;

/// A text while it is packed: plain runs and dictionary codes.
#[derive(Clone)]
enum Piece {
    Plain(Vec<u8>),
    Entry(u8),
}

fn main() {
    for path in [
        "src/powermax/sync_faults.in",
        "src/powermax/legacy_faults.in",
        "src/hpr/error_table.in",
        "src/hpr/state_table.in",
    ] {
        println!("cargo::rerun-if-changed={path}");
    }
    println!("cargo::rerun-if-changed=build.rs");

    let mut texts: Vec<Vec<Piece>> = Vec::new();
    for (name, table) in TABLES {
        for text in table {
            assert!(
                text.bytes()
                    .all(|b| b.is_ascii() && b != 0x7F && !b.is_ascii_control()),
                "{name}: {text:?} is not printable ASCII"
            );
            texts.push(vec![Piece::Plain(text.as_bytes().to_vec())]);
        }
    }

    let mut dictionary: Vec<Vec<u8>> = Vec::new();
    while dictionary.len() < 0x100 - FIRST_CODE {
        let Some(phrase) = best_phrase(&texts) else {
            break;
        };
        let code = (FIRST_CODE + dictionary.len()) as u8;
        for text in &mut texts {
            *text = replace(text, &phrase, code);
        }
        dictionary.push(phrase);
    }

    let mut out = String::new();
    out.push_str("// Written by build.rs from the tables' rows; see text_table.rs.\n\n");
    let entries: Vec<u8> = dictionary
        .iter()
        .flat_map(|entry| entry.iter().chain(b"\0"))
        .copied()
        .collect();
    let _ = writeln!(
        out,
        "/// The dictionary entries, each ended by a NUL (byte 0x80 + i names entry i).\n\
         pub(crate) static DICTIONARY: &str = \"{}\";",
        escape(&entries)
    );
    let mut packed_texts = texts.into_iter();
    for (name, table) in TABLES {
        let packed: Vec<Vec<u8>> = packed_texts
            .by_ref()
            .take(table.len())
            .map(encode)
            .collect();
        let ends = running_ends(packed.iter().map(Vec::len));
        let bytes = packed.concat();
        let _ = writeln!(
            out,
            "/// The packed texts back to back ({} B plain).\n\
             pub(crate) static {name}_TEXTS: [u8; {}] = *b\"{}\";",
            table.iter().map(|t| t.len()).sum::<usize>(),
            bytes.len(),
            escape(&bytes)
        );
        let _ = writeln!(
            out,
            "/// The end of each packed text in [`{name}_TEXTS`], in row order.\n\
             pub(crate) const {name}_ENDS: [u16; {}] = {:?};",
            ends.len(),
            ends
        );
    }
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(out_dir.join("text_tables.rs"), out).expect("OUT_DIR is writable");
}

/// The phrase whose entry saves the most bytes, if any saves some. A phrase starts at a word
/// (or a space) and ends at one, which keeps the search small and loses little.
fn best_phrase(texts: &[Vec<Piece>]) -> Option<Vec<u8>> {
    let mut counts: HashMap<&[u8], usize> = HashMap::new();
    for run in texts.iter().flatten().filter_map(|piece| match piece {
        Piece::Plain(run) => Some(run),
        Piece::Entry(_) => None,
    }) {
        for start in 0..run.len() {
            if !(start == 0 || run[start - 1] == b' ' || run[start] == b' ') {
                continue;
            }
            for end in start + 2..=run.len().min(start + LONGEST_PHRASE) {
                if end == run.len() || b" .,-/#()".contains(&run[end]) || run[end - 1] == b' ' {
                    *counts.entry(&run[start..end]).or_default() += 1;
                }
            }
        }
    }
    // Each use saves all but one byte; the entry costs its bytes and its NUL end, reckoned
    // at two bytes (one of margin).
    let saving =
        |phrase: &[u8], count: usize| (count * (phrase.len() - 1)) as i64 - phrase.len() as i64 - 2;
    counts
        .into_iter()
        .map(|(phrase, count)| (saving(phrase, count), phrase))
        .filter(|&(saved, _)| saved > 0)
        .max_by(|a, b| a.0.cmp(&b.0).then_with(|| b.1.cmp(a.1)))
        .map(|(_, phrase)| phrase.to_vec())
}

/// `text` with every use of `phrase` in its plain runs (left to right) replaced by `code`.
fn replace(text: &[Piece], phrase: &[u8], code: u8) -> Vec<Piece> {
    let mut out = Vec::new();
    for piece in text {
        let Piece::Plain(run) = piece else {
            out.push(piece.clone());
            continue;
        };
        let mut rest = &run[..];
        while let Some(at) = rest.windows(phrase.len()).position(|w| w == phrase) {
            if at > 0 {
                out.push(Piece::Plain(rest[..at].to_vec()));
            }
            out.push(Piece::Entry(code));
            rest = &rest[at + phrase.len()..];
        }
        if !rest.is_empty() {
            out.push(Piece::Plain(rest.to_vec()));
        }
    }
    out
}

fn encode(text: Vec<Piece>) -> Vec<u8> {
    let mut bytes = Vec::new();
    for piece in text {
        match piece {
            Piece::Plain(run) => bytes.extend(run),
            Piece::Entry(code) => bytes.push(code),
        }
    }
    bytes
}

fn running_ends(lengths: impl Iterator<Item = usize>) -> Vec<u16> {
    let mut end = 0;
    lengths
        .map(|len| {
            end += len;
            u16::try_from(end).expect("a table's packed texts fit in 64 KiB")
        })
        .collect()
}

/// The bytes as the inside of a Rust (byte) string literal.
fn escape(bytes: &[u8]) -> String {
    bytes
        .iter()
        .flat_map(|&b| std::ascii::escape_default(b))
        .map(char::from)
        .collect()
}
