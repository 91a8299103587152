//! Texts stored back to back with a `(code, end)` index: 4 bytes a row instead of a row with
//! a string reference (12 bytes with its code). Built at compile time from the one table a
//! module writes (see the `ERROR_CODES` and fault tables).

/// Running ends of the texts (`(code, length)` in, `(code, end)` out).
pub(crate) const fn text_ends<const N: usize>(rows: [(u16, usize); N]) -> [(u16, u16); N] {
    let mut ends = [(0, 0); N];
    let mut end = 0;
    let mut i = 0;
    while i < N {
        // Const evaluation only (the tables), never input: an index out of range would fail
        // the build, not the bridge.
        #[allow(clippy::indexing_slicing)]
        {
            end += rows[i].1;
            ends[i] = (rows[i].0, end as u16);
        }
        i += 1;
    }
    ends
}

/// The text of `code`: the span of `texts` that ends at its row's end and starts where the
/// row before ends.
pub(crate) fn text_of(
    texts: &'static str,
    index: &[(u16, u16)],
    code: u16,
) -> Option<&'static str> {
    let row = index.iter().position(|&(c, _)| c == code)?;
    let end = index.get(row)?.1;
    let start = match row.checked_sub(1) {
        Some(before) => index.get(before)?.1,
        None => 0,
    };
    texts.get(usize::from(start)..usize::from(end))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_follow_each_other() {
        const TEXTS: &str = "onetwothree";
        static INDEX: [(u16, u16); 3] = text_ends([(7, 3), (2, 3), (40, 5)]);
        assert_eq!(INDEX, [(7, 3), (2, 6), (40, 11)]);
        assert_eq!(text_of(TEXTS, &INDEX, 7), Some("one"));
        assert_eq!(text_of(TEXTS, &INDEX, 2), Some("two"));
        assert_eq!(text_of(TEXTS, &INDEX, 40), Some("three"));
        assert_eq!(text_of(TEXTS, &INDEX, 3), None);
    }
}
