//! The texts of the session's own `ERR` replies, in one place: the session writes them and
//! the tests read them from here, so a reworded text changes one line and no test.
//!
//! Texts that carry values (limits, fault codes, check bytes) are built by the types here or
//! in `describe` from the typed reason; tests match those by their `ERR` code and the values.

use core::fmt::{self, Display};

use plasma_protocol::cnc::ErrorCode;
use plasma_protocol::cnc::phoenix;

use super::{ReplyLine, err_line};

use crate::link::Family;
use crate::link::support::UnitCommand;

/// No unit on the line.
pub const NO_LINK: &str = "no power supply connected (the bridge is looking for one)";
/// `SET MODE|AMPS|PSI` on a Powermax before any process is known.
pub const SETTINGS_UNKNOWN: &str =
    "the unit's settings are not known yet: use SET PROCESS <mode> <A> <psi|AUTO>";
/// `LIMITS` (or a setting the link checks) before the slow data was read.
pub const LIMITS_NOT_READ: &str = "the unit's permitted limits have not been read yet, try again";
/// `CARTRIDGE` before the cartridge was read.
pub const CARTRIDGE_NOT_READ: &str = "cartridge data not read yet, try again";
/// `FAULTLOG` when neither log could be read.
pub const FAULT_LOG_UNREADABLE: &str = "the fault log could not be read";
/// `TORCH` on the board.
pub const TORCH_SIMULATOR_ONLY: &str = "TORCH is a simulator command";
/// `TORCH` while the driver has not taken the earlier ones.
pub const SIMULATOR_QUEUE_FULL: &str = "simulator commands are waiting";
/// `RAW` with a frame longer than the link takes.
pub const RAW_TOO_LONG: &str = "frame too long";
/// A reply that did not fit its line.
pub const REPLY_TOO_LONG: &str = "reply longer than the line buffer";
/// A text line cut short by a Phoenix frame start.
pub const LINE_INTERRUPTED: &str =
    "incomplete line dropped: a Phoenix message (SOH/STX) began before its CR/LF";
/// A Phoenix message cut short.
pub const PHOENIX_TRUNCATED: &str =
    "Phoenix message incomplete: the next one began or the line went quiet (NAK sent)";
/// A Phoenix message with a framing byte missing or out of place.
pub const PHOENIX_FRAMING: &str =
    "Phoenix message framing: a framing byte is missing or out of place (NAK sent)";

/// A line that found the queue of [`QUEUE_CAPACITY`](super::QUEUE_CAPACITY) full (a test ties the number).
pub const QUEUE_FULL: &str = "4 commands are already waiting, line dropped";

/// Why a Phoenix message was refused (NAK): its `ERR` line.
pub fn frame_error(error: plasma_protocol::Error) -> ReplyLine {
    use plasma_protocol::Error as E;
    match error {
        E::BadChecksum { expected, found } => err_line(
            ErrorCode::Syntax,
            format_args!(
                "Phoenix message check byte {found:02X}, expected {expected:02X} (NAK sent)"
            ),
        ),
        E::Overlong => err_line(
            ErrorCode::TooLong,
            format_args!(
                "Phoenix message longer than {} bytes (NAK sent)",
                phoenix::MAX_MESSAGE_LEN
            ),
        ),
        E::Truncated => err_line(ErrorCode::Syntax, PHOENIX_TRUNCATED),
        _ => err_line(ErrorCode::Syntax, PHOENIX_FRAMING),
    }
}

/// Why `command` does not exist on a family (the text of its `ERR UNSUPPORTED`): the words
/// before and after the family's name.
const fn unsupported_words(command: UnitCommand) -> (&'static str, &'static str) {
    const SETTINGS_HINT: &str = " takes SET AMPS and GASES";
    match command {
        UnitCommand::SetMode => ("SET MODE is a Powermax command; ", SETTINGS_HINT),
        UnitCommand::SetPsi => ("SET PSI is a Powermax command; ", SETTINGS_HINT),
        UnitCommand::SetProcess => ("SET PROCESS is a Powermax command; ", SETTINGS_HINT),
        UnitCommand::RemoteOff => (
            "REMOTE OFF is a Powermax command; ",
            " stays in remote mode while the bridge talks to it",
        ),
        UnitCommand::Restart => (
            "RESTART (quick restart, clears 0-50-0) is a Powermax SYNC function, not available on ",
            "",
        ),
        UnitCommand::Gases => (
            "GASES is an HPR/MaxPro200 command; ",
            " runs on air and sets no gases",
        ),
        UnitCommand::Corner => (
            "CORNER is an HPR command (070 corner current), not available on ",
            "",
        ),
        UnitCommand::Reset => (
            "RESET is an HPR/MaxPro200 command (068 software reset), not available on ",
            "; a Powermax SYNC clears 0-50-0 with RESTART",
        ),
        UnitCommand::ClearWarn => (
            "CLEARWARN is an HPR command (131 clear warnings), not available on ",
            "",
        ),
        UnitCommand::FaultLog => (
            "FAULTLOG: ",
            " keeps no fault log the bridge can read; FAULT shows the active fault",
        ),
        UnitCommand::Cartridge => (
            "CARTRIDGE is a Powermax SYNC function; ",
            " has no cartridge data",
        ),
        // The link's own words (`Refusal::NotSupported`).
        UnitCommand::GasTest | UnitCommand::SetAmps | UnitCommand::Counters | UnitCommand::Raw => {
            ("not supported by ", "")
        }
    }
}

/// The text of `ERR UNSUPPORTED` for a command the family does not have.
pub struct UnsupportedText(pub UnitCommand, pub Family);

impl Display for UnsupportedText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (before, after) = unsupported_words(self.0);
        f.write_str(before)?;
        f.write_str(self.1.name())?;
        f.write_str(after)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_queue_full_text_names_the_queue_capacity() {
        let count = QUEUE_FULL.split(' ').next();
        assert_eq!(
            count,
            Some(std::format!("{}", super::super::QUEUE_CAPACITY).as_str())
        );
    }
}
