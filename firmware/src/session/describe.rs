//! Words and texts the CNC sees for what the link knows: model names, modes, faults, and why
//! a command was refused or failed.

use core::fmt::{self, Display, Write};

use plasma_protocol::cnc::reply::write_error;
use plasma_protocol::cnc::{ErrorCode, Mode};
use plasma_protocol::hpr::{ErrorCode as HprError, StateCode, SystemId};
use plasma_protocol::modbus_ascii::ExceptionCode;
use plasma_protocol::powermax::sync::Identification;
use plasma_protocol::powermax::{FaultCode, OperatingMode, PowerSupplyModel};

use crate::link::{
    ActiveFault, CommandFailure, Family, Model, PowermaxSettings, Refusal, SettingsFailure,
    TransactionError, UnitStatus,
};
use plasma_protocol::time::Instant;

/// The family as one word: `SYNC`, `LEGACY`, `HPR`, `MAXPRO200`.
pub const fn family_word(family: Family) -> &'static str {
    match family {
        Family::PowermaxSync => "SYNC",
        Family::PowermaxLegacy => "LEGACY",
        Family::Hpr => "HPR",
        Family::MaxPro200 => "MAXPRO200",
    }
}

/// A readable family name for error texts.
pub const fn family_name(family: Family) -> &'static str {
    family.name()
}

/// The unit's model without spaces (`Powermax65`, `Powermax65/85/105`, `HPR260XD`,
/// `MaxPro200`); a SYNC unit is named by its exact size once 0x3000 has been read.
pub struct ModelName<'a>(pub &'a UnitStatus);

impl Display for ModelName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let status = self.0;
        let size = status
            .identification
            .and_then(|Identification { model, .. }| model)
            .map(|m| m.size());
        match status.model {
            None => f.write_str("-"),
            Some(Model::Powermax(model)) => match (model, size) {
                (
                    PowerSupplyModel::Powermax65_85_105Sync | PowerSupplyModel::Powermax45Sync,
                    Some(size),
                ) => write!(f, "Powermax{size}"),
                (PowerSupplyModel::Powermax45Xp, _) => f.write_str("Powermax45XP"),
                (PowerSupplyModel::Powermax65_85_105, _)
                | (PowerSupplyModel::Powermax65_85_105Sync, _) => f.write_str("Powermax65/85/105"),
                (PowerSupplyModel::Powermax125, _) => f.write_str("Powermax125"),
                (PowerSupplyModel::Powermax45Sync, _) => f.write_str("Powermax45"),
            },
            Some(Model::PowermaxUnidentified) => f.write_str("Powermax"),
            Some(Model::Hpr(SystemId::MaxPro200)) => f.write_str("MaxPro200"),
            Some(Model::Hpr(SystemId::Hpr { rating, xd, .. })) => {
                write!(f, "HPR{}", rating.max_amps())?;
                if xd {
                    f.write_str("XD")?;
                }
                Ok(())
            }
        }
    }
}

/// The CNC word for a unit mode: expanded metal / CPA is named as the family names it.
pub const fn mode_word(mode: OperatingMode, family: Option<Family>) -> &'static str {
    match (mode, family) {
        (OperatingMode::Cut, _) => "CUT",
        (OperatingMode::Gouge, _) => "GOUGE",
        (OperatingMode::ContinuousPilotArc, Some(Family::PowermaxLegacy)) => "CPA",
        (OperatingMode::ContinuousPilotArc, _) => "EXPANDED",
    }
}

/// The unit mode for a CNC mode (`CPA` and `EXPANDED` are the same register value).
pub const fn unit_mode(mode: Mode) -> OperatingMode {
    match mode {
        Mode::Cut => OperatingMode::Cut,
        Mode::Cpa | Mode::Expanded => OperatingMode::ContinuousPilotArc,
        Mode::Gouge => OperatingMode::Gouge,
    }
}

/// The CNC mode for a unit mode, as the family names it.
pub const fn cnc_mode(mode: OperatingMode, family: Option<Family>) -> Mode {
    match (mode, family) {
        (OperatingMode::Cut, _) => Mode::Cut,
        (OperatingMode::Gouge, _) => Mode::Gouge,
        (OperatingMode::ContinuousPilotArc, Some(Family::PowermaxLegacy)) => Mode::Cpa,
        (OperatingMode::ContinuousPilotArc, _) => Mode::Expanded,
    }
}

/// `-` for an unknown value.
pub struct OrDash<T>(pub Option<T>);

impl<T: Display> Display for OrDash<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            Some(v) => v.fmt(f),
            None => f.write_str("-"),
        }
    }
}

/// `ON` / `OFF`.
pub const fn on_off(on: bool) -> &'static str {
    if on { "ON" } else { "OFF" }
}

/// A fault code as the unit shows it: `0-20-0` (Powermax) or `023` (HPR).
pub struct FaultId(pub ActiveFault);

impl Display for FaultId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            ActiveFault::Powermax(code) => code.fmt(f),
            ActiveFault::Hpr(code) => write!(f, "{:03}", code.0),
        }
    }
}

/// The manual's description of a Powermax fault for `family`.
pub fn powermax_fault_text(code: FaultCode, family: Option<Family>) -> Option<&'static str> {
    let sync = code.info().map(|i| i.text);
    let legacy = code.legacy_info();
    match family {
        Some(Family::PowermaxLegacy) => legacy.or(sync),
        _ => sync.or(legacy),
    }
}

/// The manual's text for a fault (HPR: the error name).
pub fn fault_text(fault: ActiveFault, family: Option<Family>) -> &'static str {
    match fault {
        ActiveFault::Powermax(code) => powermax_fault_text(code, family),
        ActiveFault::Hpr(code) => code.name(),
    }
    .unwrap_or("unknown fault")
}

/// The name of an HPR / MaxPro200 state for `family`.
pub fn state_name(state: StateCode, family: Option<Family>) -> &'static str {
    match family {
        Some(Family::MaxPro200) => state.maxpro200_name(),
        _ => state.hpr_name(),
    }
    .unwrap_or("unknown")
}

/// Free text that cannot break a line: control and non-ASCII characters become `?`.
pub struct Text<'a>(pub &'a str);

impl Display for Text<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for c in self.0.chars() {
            f.write_char(if c == ' ' || c.is_ascii_graphic() {
                c
            } else {
                '?'
            })?;
        }
        Ok(())
    }
}

/// One word for a failed transaction (events: `last=timeout`).
pub const fn transaction_word(error: TransactionError) -> &'static str {
    match error {
        TransactionError::Timeout => "timeout",
        TransactionError::BadChecksum => "bad_checksum",
        TransactionError::Exception(_) => "exception",
        TransactionError::Mismatch => "mismatch",
        TransactionError::HprBadChecksum500 => "hpr_500",
        TransactionError::HprUnknownCommand501 => "hpr_501",
        TransactionError::Malformed => "malformed",
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
                    crate::link::diagnostics::exception_code_byte(code),
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

/// `mode=CUT amps=45 psi=AUTO` of settings as the unit reports them.
pub struct SettingsText<'a>(pub &'a PowermaxSettings, pub Option<Family>);

impl Display for SettingsText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let SettingsText(s, family) = self;
        write!(
            f,
            "mode={} amps={} psi={}",
            OrDash(s.mode.map(|m| mode_word(m, *family))),
            s.current,
            s.pressure
        )
    }
}

/// The word naming what a limit applies to.
fn limit_scope(family: Option<Family>) -> &'static str {
    match family {
        Some(Family::PowermaxSync) => "for this cartridge",
        _ => "for this unit",
    }
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
            format_args!("not supported by {}", family_name(*family)),
        ),
        Refusal::LimitsUnknown => write_error(out, ErrorCode::State, super::texts::LIMITS_NOT_READ),
        Refusal::QuickRestartNeeds050 { .. } => write_error(out, ErrorCode::State, refusal),
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
                state.map_or("unknown", |s| state_name(s, family)),
                OrDash(error.map(HprCode)),
                error.and_then(|e| e.name()).unwrap_or("unknown"),
            ),
        ),
        Refusal::RawMalformed(_)
        | Refusal::RawWrongAddress { .. }
        | Refusal::RawFunctionNotAllowed { .. }
        | Refusal::RawWriteNotAllowed { .. }
        | Refusal::RawCommandNotAllowed { .. } => write_error(out, ErrorCode::Refused, refusal),
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
        CommandFailure::Settings(SettingsFailure::Transaction(e)) => write_error(
            out,
            ErrorCode::Link,
            format_args!("settings not applied: {}", TransactionText(*e)),
        ),
        CommandFailure::Settings(SettingsFailure::ReadBackDiffers { read_back, .. }) => {
            write_error(
                out,
                ErrorCode::Link,
                format_args!(
                    "settings not confirmed: the unit reads back {}",
                    SettingsText(read_back, family)
                ),
            )
        }
        CommandFailure::Settings(SettingsFailure::RejectedByUnit { fault }) => write_error(
            out,
            ErrorCode::Refused,
            format_args!(
                "the unit rejected the settings with fault {fault} ({})",
                powermax_fault_text(*fault, family).unwrap_or("unknown fault")
            ),
        ),
        CommandFailure::Settings(SettingsFailure::OutsideLimits) => write_error(
            out,
            ErrorCode::Range,
            "settings outside the unit's permitted limits",
        ),
        CommandFailure::Settings(SettingsFailure::NotAccepted) | CommandFailure::NotAccepted => {
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

/// One word for why settings failed (`!SETTINGS failed reason=...`).
pub fn settings_failure_word(reason: &SettingsFailure) -> &'static str {
    match reason {
        SettingsFailure::Transaction(_) => "no_reply",
        SettingsFailure::ReadBackDiffers { .. } => "read_back_differs",
        SettingsFailure::RejectedByUnit { .. } => "rejected_by_unit",
        SettingsFailure::OutsideLimits => "outside_limits",
        SettingsFailure::NotAccepted => "not_accepted",
    }
}
