//! Which unit a command line is for: `@N ` before the command (N = 1-4) names unit N of the
//! units on the bridge's power-supply line; a line without it is for unit 1, so everything
//! written for one unit works unchanged.
//!
//! ```
//! use plasma_protocol::cnc::{Command, split_unit};
//!
//! assert_eq!(split_unit("@2 SET AMPS 45"), Ok((2, "SET AMPS 45")));
//! assert_eq!(split_unit("STATUS"), Ok((1, "STATUS")));
//! let (_, command) = split_unit("@3   FAULT").unwrap();
//! assert_eq!(Command::parse(command), Ok(Command::Fault));
//! ```

use super::ParseError;

/// The most units one line carries (HPR ids 0-3; the bridge drives four Powermax at most).
pub const MAX_UNIT: u8 = 4;

/// What the reply names when `@N` is wrong.
pub const UNIT_ARGUMENT: &str = "unit";

/// The unit (1-[`MAX_UNIT`]) a line addresses and the command after its `@N ` prefix.
/// Refused: `@` without a number, a number outside 1-4, nothing after it.
pub fn split_unit(line: &str) -> Result<(u8, &str), ParseError> {
    let line = line.trim_ascii_start();
    let Some(rest) = line.strip_prefix('@') else {
        return Ok((1, line));
    };
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let (number, command) = rest.split_at_checked(digits).unwrap_or((rest, ""));
    let separated = matches!(command.bytes().next(), None | Some(b' ' | b'\t'));
    if number.is_empty() || !separated {
        return Err(ParseError::BadNumber {
            what: UNIT_ARGUMENT,
        });
    }
    // At most one digit is a unit: longer numbers are out of range without parsing them.
    let unit = match number.as_bytes() {
        &[digit] => digit - b'0',
        _ => 0,
    };
    if !(1..=MAX_UNIT).contains(&unit) {
        return Err(ParseError::OutOfRange {
            what: UNIT_ARGUMENT,
            range: "1..4",
        });
    }
    let command = command.trim_ascii_start();
    if command.is_empty() {
        return Err(ParseError::Empty);
    }
    Ok((unit, command))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prefix_names_a_unit_and_leaves_the_command() {
        assert_eq!(split_unit("@1 ID"), Ok((1, "ID")));
        assert_eq!(split_unit("  @4\tSTATUS"), Ok((4, "STATUS")));
        assert_eq!(split_unit("SET AMPS 45"), Ok((1, "SET AMPS 45")));
        // `@` only at the start: elsewhere it is the command's own text.
        assert_eq!(split_unit("RAW @1"), Ok((1, "RAW @1")));
    }

    #[test]
    fn a_wrong_prefix_is_refused_precisely() {
        let bad_number = Err(ParseError::BadNumber {
            what: UNIT_ARGUMENT,
        });
        assert_eq!(split_unit("@ ID"), bad_number);
        assert_eq!(split_unit("@x ID"), bad_number);
        assert_eq!(split_unit("@2ID"), bad_number);
        let out_of_range = Err(ParseError::OutOfRange {
            what: UNIT_ARGUMENT,
            range: "1..4",
        });
        assert_eq!(split_unit("@0 ID"), out_of_range);
        assert_eq!(split_unit("@5 ID"), out_of_range);
        assert_eq!(split_unit("@99999999999 ID"), out_of_range);
        assert_eq!(split_unit("@2"), Err(ParseError::Empty));
        assert_eq!(split_unit("@2   "), Err(ParseError::Empty));
    }
}
