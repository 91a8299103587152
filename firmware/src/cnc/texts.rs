//! The texts of the CNC side's `ERR` replies, in one place: the session writes them and the
//! tests read them from here, so a reworded text changes one line and no test. (Two kinds
//! come from elsewhere: a line that does not parse, from the protocol crate's
//! `write_parse_error`, and a `CONFIG` value refused, from the settings' `SetError`.)
//!
//! Texts that carry values (limits, fault codes, check bytes) are built here from the typed
//! reason (a link `Refusal` or `CommandFailure`, a frame error); tests match those by their
//! `ERR` code and the values.

use core::fmt::{self, Display, Write};

use plasma_protocol::Text as TableText;
use plasma_protocol::cnc::reply::write_error;
use plasma_protocol::cnc::{AMPS_ARGUMENT, Amps, ErrorCode, phoenix};
use plasma_protocol::hpr::ErrorCode as HprError;
use plasma_protocol::hpr::{GasConsole, SystemId};
use plasma_protocol::modbus_ascii::ExceptionCode;
use plasma_protocol::powermax::OperatingMode;
use plasma_protocol::time::{Decimal, Instant};

use super::describe::{OrDash, ProcessText, mode_word, powermax_fault_text, state_name};
use super::{ReplyLine, err_line};
use crate::link::{CommandFailure, Family, ProcessFailure, Refusal, TransactionError};
use crate::settings::SaveError;

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

/// `SET AMPS` with a fraction on a unit that takes whole amps: its `ERR` line.
pub fn whole_amps(amps: Amps) -> ReplyLine {
    err_line(
        ErrorCode::Range,
        format_args!("amps {amps}: this unit takes whole amps"),
    )
}

/// `CONFIG SAVE` failed: its `ERR` line.
pub fn not_saved(error: SaveError) -> ReplyLine {
    err_line(
        ErrorCode::Storage,
        format_args!("settings not saved: {error}"),
    )
}

/// `GASTEST CHECK` while TORCH_ON, START or MOTION is on.
pub const GAS_CHECK_TORCH_ON: &str =
    "GASTEST CHECK refused: the torch is on (TORCH_ON, START or MOTION)";
/// `GASTEST CHECK` with a fault that requires action (its code follows).
pub const GAS_CHECK_FAULTED: &str =
    "GASTEST CHECK refused: the unit has a fault that requires action,";
/// TORCH_ON or START came on during `GASTEST CHECK`.
pub const GAS_CHECK_STOPPED_TORCH: &str =
    "GASTEST CHECK stopped: the torch came on; the gas test was ended";
/// The link was lost during `GASTEST CHECK`.
pub const GAS_CHECK_LINK_LOST: &str =
    "GASTEST CHECK stopped: the link was lost; the gas test is ended when the unit answers again";
/// `GASTEST CHECK` ended without a reading.
pub const GAS_CHECK_NO_READING: &str = "GASTEST CHECK: the unit gave no pressure reading";

/// `HISTORY` when the history's flash could not be read or erased (or the board keeps none).
pub const HISTORY_UNAVAILABLE: &str = "history not available";

/// `POWER` with `@N`: one setting drives every unit's REMOTE_POWER output.
pub const POWER_EVERY_UNIT: &str =
    "POWER switches every unit's REMOTE_POWER output: send it without @N";

/// `CONSUMABLES` for a unit beyond the first.
pub const CONSUMABLES_FIRST_UNIT: &str =
    "consumable life is kept for unit 1 only (the unit without @N)";

/// `@N` for a unit the bridge does not drive (0-based `unit`, `count` units configured).
pub struct NoSuchUnit {
    /// The unit named, 0-based.
    pub unit: usize,
    /// How many units `CONFIG units` names.
    pub count: usize,
}

impl fmt::Display for NoSuchUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unit {}: the bridge drives {} unit{} (CONFIG units)",
            self.unit + 1,
            self.count,
            if self.count == 1 { "" } else { "s" }
        )
    }
}

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

/// Why a command does not exist on a family: the words before and after the family's name
/// in its `ERR UNSUPPORTED` text. The command table (`table.rs`) says which one a command
/// gets on which family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unsupported {
    before: &'static str,
    after: &'static str,
}

const SETTINGS_HINT: &str = " takes SET AMPS and GASES";

/// The `ERR UNSUPPORTED` texts, one per command the table refuses on some family.
pub mod unsupported {
    use super::{SETTINGS_HINT, Unsupported};

    const fn words(before: &'static str, after: &'static str) -> Unsupported {
        Unsupported { before, after }
    }

    /// `SET MODE` on an HPR or MaxPro200.
    pub const SET_MODE: Unsupported = words("SET MODE is a Powermax command; ", SETTINGS_HINT);
    /// `SET PSI` on an HPR or MaxPro200.
    pub const SET_PSI: Unsupported = words("SET PSI is a Powermax command; ", SETTINGS_HINT);
    /// `SET PROCESS` on an HPR or MaxPro200.
    pub const SET_PROCESS: Unsupported =
        words("SET PROCESS is a Powermax command; ", SETTINGS_HINT);
    /// `REMOTE OFF` on an HPR or MaxPro200.
    pub const REMOTE_OFF: Unsupported = words(
        "REMOTE OFF is a Powermax command; ",
        " stays in remote mode while the bridge talks to it",
    );
    /// `SET HPR_PROCESS` on anything but a MaxPro200.
    pub const HPR_PROCESS: Unsupported = words(
        "SET HPR_PROCESS is a MaxPro200 command (137 set process), not available on ",
        "; an HPR takes SET AMPS, GASES and CORNER",
    );
    /// `SET HPR_PARAMETERS` on a Powermax.
    pub const HPR_PARAMETERS: Unsupported = words(
        "SET HPR_PARAMETERS is an HPR/MaxPro200 command (095 set all parameters), not available on ",
        "; a Powermax takes SET PROCESS",
    );
    /// `SET HPR_PARAMETERS` in the other family's form (095 takes other fields on each).
    pub const HPR_PARAMETERS_FORM: Unsupported = words(
        "SET HPR_PARAMETERS in this form is not taken by ",
        ": an HPR takes <A> <corner> <plasma> <shield> and six psi, a MaxPro200 \
         <A> <plasma> <shield> and two psi",
    );
    /// `SET HPR_GAS_FLOWS` on a Powermax.
    pub const HPR_GAS_FLOWS: Unsupported = words(
        "SET HPR_GAS_FLOWS is an HPR/MaxPro200 command (078 set all gas flows), not available on ",
        "; a Powermax takes SET PSI",
    );
    /// `SET HPR_GAS_FLOWS` in the other family's form (078 takes other fields on each).
    pub const HPR_GAS_FLOWS_FORM: Unsupported = words(
        "SET HPR_GAS_FLOWS in this form is not taken by ",
        ": an HPR takes six psi, a MaxPro200 two",
    );
    /// `RESTART` on anything but a Powermax SYNC.
    pub const RESTART: Unsupported = words(
        "RESTART (quick restart, clears 0-50-0) is a Powermax SYNC function, not available on ",
        "",
    );
    /// `GASES` on a Powermax.
    pub const GASES: Unsupported = words(
        "GASES is an HPR/MaxPro200 command; ",
        " runs on air and sets no gases",
    );
    /// `CORNER` on anything but an HPR.
    pub const CORNER: Unsupported = words(
        "CORNER is an HPR command (070 corner current), not available on ",
        "",
    );
    /// `RESET` on a Powermax.
    pub const RESET: Unsupported = words(
        "RESET is an HPR/MaxPro200 command (068 software reset), not available on ",
        "; a Powermax SYNC clears 0-50-0 with RESTART",
    );
    /// `GASTEST PREFLOW|CUTFLOW` on anything but an HPR.
    pub const GAS_FLOW_TEST: Unsupported = words(
        "GASTEST PREFLOW|CUTFLOW is an HPR command (064-067 gas tests), not available on ",
        "; GASTEST ON|OFF runs the unit's gas test",
    );
    /// `CLEARWARN` on anything but an HPR.
    pub const CLEAR_WARN: Unsupported = words(
        "CLEARWARN is an HPR command (131 clear warnings), not available on ",
        "",
    );
    /// `FAULTLOG` on a family that keeps no log the bridge can read.
    pub const FAULT_LOG: Unsupported = words(
        "FAULTLOG: ",
        " keeps no fault log the bridge can read; FAULT shows the active fault",
    );
    /// `CARTRIDGE` on anything but a Powermax SYNC.
    pub const CARTRIDGE: Unsupported = words(
        "CARTRIDGE is a Powermax SYNC function; ",
        " has no cartridge data",
    );
    /// `CONSUMABLES NEW` on a SYNC.
    pub const CONSUMABLES_NEW: Unsupported = words(
        "CONSUMABLES NEW is not taken on ",
        ": its cartridge keeps its own counts and another cartridge starts a new record by itself",
    );
    /// Any other command a family lacks, and a request the link
    /// refuses for the family (`Refusal::NotSupported`).
    pub const NOT_SUPPORTED: Unsupported = words("not supported by ", "");
}

/// The text of `ERR UNSUPPORTED` for a command the family does not have.
pub struct UnsupportedText(pub Unsupported, pub Family);

impl Display for UnsupportedText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let UnsupportedText(Unsupported { before, after }, family) = *self;
        f.write_str(before)?;
        f.write_str(family.name())?;
        f.write_str(after)
    }
}

/// What happened to a transaction, as a sentence.
pub struct TransactionText(pub TransactionError);

impl Display for TransactionText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            TransactionError::Timeout => f.write_str("the unit did not answer in time"),
            TransactionError::BadChecksum => f.write_str("the replies had bad checksums"),
            TransactionError::Exception(code) => {
                write!(
                    f,
                    "the unit answered with exception {:02X} ({})",
                    code.to_u8(),
                    ExceptionName(code)
                )
            }
            TransactionError::Mismatch => f.write_str("the reply did not answer the request"),
            TransactionError::HprBadChecksum500 => {
                f.write_str("the unit saw a bad checksum in the request (500)")
            }
            TransactionError::HprUnknownCommand501 => {
                f.write_str("the unit does not know the command (501)")
            }
            TransactionError::Malformed => f.write_str("the reply could not be parsed"),
        }
    }
}

struct ExceptionName(ExceptionCode);

impl Display for ExceptionName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// The word naming what a limit applies to.
pub(super) fn limit_scope(family: Option<Family>) -> &'static str {
    match family {
        Some(Family::PowermaxSync) => "for this cartridge",
        _ => "for this unit",
    }
}

/// A current outside every unit's bounds: the range of the unit on the line (what LIMITS
/// shows), where the parser's own text quotes the bounds.
pub(super) fn amps_out_of_range(range: impl Display, family: Option<Family>) -> ReplyLine {
    err_line(
        ErrorCode::Range,
        format_args!(
            "{AMPS_ARGUMENT} out of range {range} {}",
            limit_scope(family)
        ),
    )
}

/// Write the `ERR` line for a command the link refused (nothing was sent).
pub fn write_refusal<W: Write>(
    out: &mut W,
    refusal: &Refusal,
    family: Option<Family>,
    now: Instant,
) -> fmt::Result {
    match refusal {
        Refusal::ModeNotPermitted { .. }
        | Refusal::CurrentOutOfRange { .. }
        | Refusal::PressureOutOfRange { .. }
        | Refusal::HprValueOutOfRange { .. } => write_range_refusal(out, refusal, family),
        Refusal::LinkNotUp => write_error(out, ErrorCode::Link, "no power supply connected"),
        Refusal::NotSupported { family } => write_error(
            out,
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::NOT_SUPPORTED, *family),
        ),
        Refusal::LimitsUnknown => write_error(out, ErrorCode::State, LIMITS_NOT_READ),
        Refusal::NotOnThisSystem { .. } => {
            write_error(out, ErrorCode::Unsupported, RefusalText(refusal))
        }
        Refusal::QuickRestartNeeds050 { .. } => {
            write_error(out, ErrorCode::State, RefusalText(refusal))
        }
        Refusal::Blackout { until } => write_error(
            out,
            ErrorCode::Busy,
            format_args!(
                "the unit restarts: quiet for another {} ms",
                until.saturating_since(now).as_millis_u32()
            ),
        ),
        Refusal::QueueFull => write_error(out, ErrorCode::Busy, "the link's command queue is full"),
        Refusal::StateForbids { state, error } => write_error(
            out,
            ErrorCode::State,
            format_args!(
                "not allowed in state {} ({}) with error {} ({})",
                OrDash(state.map(|s| s.0)),
                state.map_or(TableText::plain("unknown"), |s| state_name(s, family)),
                OrDash(error.map(HprCode)),
                error
                    .and_then(|e| e.name())
                    .unwrap_or(TableText::plain("unknown")),
            ),
        ),
        Refusal::RawMalformed(_)
        | Refusal::RawWrongAddress { .. }
        | Refusal::RawFunctionNotAllowed { .. }
        | Refusal::RawWriteNotAllowed { .. }
        | Refusal::RawCommandNotAllowed { .. } => {
            write_error(out, ErrorCode::Refused, RefusalText(refusal))
        }
    }
}

/// Write the `ERR RANGE` line of a value outside what the unit permits.
fn write_range_refusal<W: Write>(
    out: &mut W,
    refusal: &Refusal,
    family: Option<Family>,
) -> fmt::Result {
    let scope = limit_scope(family);
    match refusal {
        Refusal::ModeNotPermitted { mode, permitted } => {
            let low = permitted.low_mode().map(|m| mode_word(m, family));
            let high = permitted.high_mode().map(|m| mode_word(m, family));
            let second = if high == low { None } else { high };
            write_error(
                out,
                ErrorCode::Range,
                format_args!(
                    "mode {} not permitted {scope} (permitted: {}{}{})",
                    mode_word(*mode, family),
                    OrDash(low),
                    if second.is_some() { " " } else { "" },
                    second.unwrap_or("")
                ),
            )
        }
        Refusal::CurrentOutOfRange {
            requested,
            min,
            max,
        } => write_error(
            out,
            ErrorCode::Range,
            format_args!("amps {requested} outside {min}..{max} {scope}"),
        ),
        Refusal::PressureOutOfRange {
            requested,
            min,
            max,
        } => write_error(
            out,
            ErrorCode::Range,
            format_args!("psi {requested} outside {min}..{max} {scope}"),
        ),
        Refusal::HprValueOutOfRange {
            value,
            requested,
            min,
            max,
        } => write_error(
            out,
            ErrorCode::Range,
            format_args!("{} {requested} outside {min}..{max} {scope}", value.word()),
        ),
        // `write_refusal` sends only the four above here.
        _ => Ok(()),
    }
}

/// The system a command is refused for, with what to do instead.
struct SystemText(SystemId);

impl Display for SystemText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self.0 {
            SystemId::MaxPro200 => "a MaxPro200",
            SystemId::Hpr {
                console: Some(GasConsole::Manual),
                ..
            } => "an HPR with a manual gas console: its knobs set the current and gases",
            SystemId::Hpr { .. } => "an HPR with an automatic gas console",
        })
    }
}

struct HprCode(HprError);

impl Display for HprCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:03}", self.0.0)
    }
}

/// Write the `ERR` line for a command that was sent and failed.
pub fn write_failure<W: Write>(
    out: &mut W,
    failure: &CommandFailure,
    family: Option<Family>,
) -> fmt::Result {
    match failure {
        CommandFailure::Transaction(e) => write_error(out, ErrorCode::Link, TransactionText(*e)),
        CommandFailure::Process(ProcessFailure::Transaction(e)) => write_error(
            out,
            ErrorCode::Link,
            format_args!("settings not applied: {}", TransactionText(*e)),
        ),
        CommandFailure::Process(ProcessFailure::ReadBackDiffers { read_back, .. }) => write_error(
            out,
            ErrorCode::Link,
            format_args!(
                "settings not confirmed: the unit reads back {}",
                ProcessText(read_back, family)
            ),
        ),
        CommandFailure::Process(ProcessFailure::RejectedByUnit { fault }) => write_error(
            out,
            ErrorCode::Refused,
            format_args!(
                "the unit rejected the settings with fault {fault} ({})",
                powermax_fault_text(*fault, family).unwrap_or(TableText::plain("unknown fault"))
            ),
        ),
        CommandFailure::Process(ProcessFailure::OutsideLimits) => write_error(
            out,
            ErrorCode::Range,
            "settings outside the unit's permitted limits",
        ),
        CommandFailure::Process(ProcessFailure::NotAccepted) | CommandFailure::NotAccepted => {
            write_error(
                out,
                ErrorCode::Refused,
                "the unit did not accept the command",
            )
        }
        CommandFailure::LinkDown => write_error(
            out,
            ErrorCode::Link,
            "the link went down before the command completed",
        ),
    }
}

/// A link refusal in plain words: the text of some `ERR` lines (RAW checks, quick restart)
/// and of `!SETTINGS failed reason=refused why=...`. It uses no `Debug` formatting, which
/// would bring core's `Debug` machinery (~1 KB) into the image.
pub struct RefusalText<'a>(pub &'a Refusal);

impl Display for RefusalText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mode_name = |mode: Option<OperatingMode>| mode.map_or("-", OperatingMode::sync_name);
        match self.0 {
            Refusal::LinkNotUp => f.write_str("no power supply connected"),
            Refusal::NotSupported { family } => write!(f, "not supported by {}", family.name()),
            Refusal::LimitsUnknown => f.write_str("permitted limits not read yet"),
            Refusal::ModeNotPermitted { mode, permitted } => write!(
                f,
                "mode {} not permitted (permitted: {}, {})",
                mode.sync_name(),
                mode_name(permitted.low_mode()),
                mode_name(permitted.high_mode())
            ),
            Refusal::CurrentOutOfRange {
                requested,
                min,
                max,
            } => {
                write!(f, "current {requested} A outside {min}-{max} A")
            }
            Refusal::PressureOutOfRange {
                requested,
                min,
                max,
            } => {
                write!(f, "pressure {requested} psi outside {min}-{max} psi")
            }
            Refusal::QuickRestartNeeds050 { active } => match active {
                Some(code) => write!(f, "quick restart needs fault 0-50-0, active is {code}"),
                None => f.write_str("quick restart needs fault 0-50-0, no fault active"),
            },
            Refusal::Blackout { until } => {
                // (Decimal: no 64-bit division in the board image.)
                let until = Decimal(until.as_millis());
                write!(f, "quiet after quick restart until {until} ms")
            }
            Refusal::QueueFull => f.write_str("too many commands waiting"),
            Refusal::NotOnThisSystem { id, system } => {
                write!(
                    f,
                    "HPR command {id:03} is not taken by {}",
                    SystemText(*system)
                )
            }
            Refusal::HprValueOutOfRange {
                value,
                requested,
                min,
                max,
            } => {
                write!(f, "{} {requested} outside {min}-{max}", value.word())
            }
            Refusal::StateForbids { state, error } => {
                f.write_str("not allowed in state ")?;
                match state {
                    Some(state) => write!(f, "{}", state.0)?,
                    None => f.write_str("unknown")?,
                }
                match error {
                    Some(error) => write!(f, " with error {:03}", error.0),
                    None => f.write_str(" with error unknown"),
                }
            }
            Refusal::RawMalformed(e) => write!(f, "raw frame rejected: {e}"),
            Refusal::RawWrongAddress { expected, found } => {
                write!(
                    f,
                    "raw frame for node {found}, link talks to node {expected}"
                )
            }
            Refusal::RawFunctionNotAllowed { function } => {
                write!(f, "raw function {function:02X} not allowed")
            }
            Refusal::RawWriteNotAllowed { address } => {
                write!(f, "raw write to {address:04X} not allowed")
            }
            Refusal::RawCommandNotAllowed { id } => write!(f, "raw command {id:03} not allowed"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::HprValue;
    use plasma_protocol::hpr::StateCode;
    use plasma_protocol::powermax::sync::PermittedModes;
    use std::string::ToString;

    #[test]
    fn the_queue_full_text_names_the_queue_capacity() {
        let count = QUEUE_FULL.split(' ').next();
        assert_eq!(
            count,
            Some(std::format!("{}", super::super::QUEUE_CAPACITY).as_str())
        );
    }

    #[test]
    fn refusal_texts_name_things_without_debug_output() {
        let texts = [
            (
                Refusal::NotSupported {
                    family: Family::MaxPro200,
                },
                "not supported by a MaxPro200",
            ),
            (
                Refusal::ModeNotPermitted {
                    mode: OperatingMode::Gouge,
                    permitted: PermittedModes { high: 2, low: 9 },
                },
                "mode gouge not permitted (permitted: -, expanded metal)",
            ),
            (
                Refusal::HprValueOutOfRange {
                    value: HprValue::CornerPercent,
                    requested: 40,
                    min: 50,
                    max: 100,
                },
                "percent 40 outside 50-100",
            ),
            (
                Refusal::StateForbids {
                    state: Some(StateCode(14)),
                    error: Some(HprError(7)),
                },
                "not allowed in state 14 with error 007",
            ),
            (
                Refusal::StateForbids {
                    state: None,
                    error: None,
                },
                "not allowed in state unknown with error unknown",
            ),
            (
                Refusal::Blackout {
                    until: Instant::from_millis(12_345_678_901),
                },
                "quiet after quick restart until 12345678901 ms",
            ),
        ];
        for (refusal, text) in texts {
            assert_eq!(RefusalText(&refusal).to_string(), text);
        }
    }
}
