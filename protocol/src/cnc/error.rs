//! Why a command was refused: a stable code word and a precise, allocation-free text.

use core::fmt;

use super::line::{LineError, MAX_LINE_LEN};

/// The stable word after `ERR` in a reply. CNC programs may match on it; never rename one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ErrorCode {
    /// Unknown command, wrong number of arguments, bad keyword or number.
    Syntax,
    /// A number outside the absolute bounds of the protocol (e.g. amps above 400).
    Range,
    /// The line was longer than 128 characters.
    TooLong,
    /// The line held a non-printable byte.
    Binary,
    /// Not possible in the current state (e.g. gases changed while cutting).
    State,
    /// The power supply did not answer, or answered with an error.
    Link,
    /// The connected power supply has no such function.
    Unsupported,
    /// Refused by a safety interlock or because the command is locked.
    Denied,
    /// Too many commands are waiting, or the unit is in a quiet period; send it again later.
    Busy,
    /// Refused by the bridge's allow-list (a RAW frame the bridge never forwards), or by the
    /// unit itself (a setting it will not take).
    Refused,
    /// The settings could not be stored (`CONFIG SAVE`).
    Storage,
}

impl ErrorCode {
    /// Every code.
    pub const ALL: [ErrorCode; 11] = [
        ErrorCode::Syntax,
        ErrorCode::Range,
        ErrorCode::TooLong,
        ErrorCode::Binary,
        ErrorCode::State,
        ErrorCode::Link,
        ErrorCode::Unsupported,
        ErrorCode::Denied,
        ErrorCode::Busy,
        ErrorCode::Refused,
        ErrorCode::Storage,
    ];

    /// The word as sent: `SYNTAX`, `RANGE`, `TOOLONG`, `BINARY`, `STATE`, `LINK`,
    /// `UNSUPPORTED`, `DENIED`, `BUSY`, `REFUSED`, `STORAGE`.
    pub const fn as_str(self) -> &'static str {
        match self {
            ErrorCode::Syntax => "SYNTAX",
            ErrorCode::Range => "RANGE",
            ErrorCode::TooLong => "TOOLONG",
            ErrorCode::Binary => "BINARY",
            ErrorCode::State => "STATE",
            ErrorCode::Link => "LINK",
            ErrorCode::Unsupported => "UNSUPPORTED",
            ErrorCode::Denied => "DENIED",
            ErrorCode::Busy => "BUSY",
            ErrorCode::Refused => "REFUSED",
            ErrorCode::Storage => "STORAGE",
        }
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Why a line is not a valid command.
///
/// `Display` writes the text that follows `ERR <CODE> ` in the reply, e.g.
/// `ERR RANGE amps out of range 5..400` or `ERR SYNTAX mode: expected CUT|CPA|EXPANDED|GOUGE`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParseError {
    /// The line holds no command word.
    Empty,
    /// The first word is not a command.
    UnknownCommand,
    /// An argument is missing.
    MissingArgument {
        /// What was expected there (`amps`, `mode`, ...).
        what: &'static str,
    },
    /// More arguments than the command takes.
    UnexpectedArgument,
    /// A word that should be one of a fixed set of keywords.
    BadKeyword {
        /// Which argument.
        what: &'static str,
        /// The accepted words.
        expected: &'static str,
    },
    /// An argument that should be a number is not a (non-negative, decimal) number.
    BadNumber {
        /// Which argument.
        what: &'static str,
    },
    /// A number outside its absolute bounds.
    OutOfRange {
        /// Which argument.
        what: &'static str,
        /// The accepted range, as written in the reply.
        range: &'static str,
    },
    /// A number finer than the step the power supply stores (1/64 A, 1/128 psi).
    NotMultiple {
        /// Which argument.
        what: &'static str,
        /// The step.
        step: &'static str,
    },
    /// The line was too long (from the [`LineAssembler`](super::line::LineAssembler)).
    TooLong,
    /// The line held a non-printable byte.
    Binary,
}

impl ParseError {
    /// The code word for the reply.
    pub const fn code(&self) -> ErrorCode {
        match self {
            ParseError::OutOfRange { .. } | ParseError::NotMultiple { .. } => ErrorCode::Range,
            ParseError::TooLong => ErrorCode::TooLong,
            ParseError::Binary => ErrorCode::Binary,
            _ => ErrorCode::Syntax,
        }
    }
}

impl From<LineError> for ParseError {
    fn from(error: LineError) -> Self {
        match error {
            LineError::TooLong => ParseError::TooLong,
            LineError::Binary => ParseError::Binary,
        }
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParseError::Empty => f.write_str("empty line"),
            ParseError::UnknownCommand => f.write_str("unknown command (HELP lists the commands)"),
            ParseError::MissingArgument { what } => write!(f, "missing {what}"),
            ParseError::UnexpectedArgument => f.write_str("too many arguments"),
            ParseError::BadKeyword { what, expected } => write!(f, "{what}: expected {expected}"),
            ParseError::BadNumber { what } => write!(f, "{what}: not a number"),
            ParseError::OutOfRange { what, range } => write!(f, "{what} out of range {range}"),
            ParseError::NotMultiple { what, step } => {
                write!(f, "{what} must be a multiple of {step}")
            }
            ParseError::TooLong => write!(f, "line longer than {MAX_LINE_LEN} characters"),
            ParseError::Binary => f.write_str("non-printable byte in line"),
        }
    }
}

impl core::error::Error for ParseError {}

impl From<LineError> for ErrorCode {
    fn from(error: LineError) -> Self {
        ParseError::from(error).code()
    }
}
