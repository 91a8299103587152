//! Words the CNC sees for what the link knows: model names, modes, faults, states, settings
//! (the `ERR` texts built from them are in `texts`).

use core::fmt::{self, Display, Write};

use plasma_protocol::Text as TableText;
use plasma_protocol::cnc::Mode;
use plasma_protocol::hpr::StateCode;
use plasma_protocol::powermax::{FaultCode, OperatingMode, StepsRequired, TorchKind};

use crate::io::Interlock;
use crate::link::model_code::{model_code, model_name};
use crate::link::{
    ActiveFault, Family, PowermaxProcess, ProcessFailure, TransactionError, UnitStatus,
};

/// The family as one word: `SYNC`, `LEGACY`, `HPR`, `MAXPRO200`.
pub const fn family_word(family: Family) -> &'static str {
    match family {
        Family::PowermaxSync => "SYNC",
        Family::PowermaxLegacy => "LEGACY",
        Family::Hpr => "HPR",
        Family::MaxPro200 => "MAXPRO200",
    }
}

/// The unit's model without spaces (`Powermax65`, `Powermax65/85/105`, `HPR260XD`,
/// `MaxPro200`; `-` while none is known): the name of its model code
/// ([`model_code`](crate::link::model_code)), so `STATUS` and `HISTORY` name it alike.
pub struct ModelName<'a>(pub &'a UnitStatus);

impl Display for ModelName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(model_name(model_code(self.0)).unwrap_or("-"))
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

/// The torch kind as one word: `HAND`, `MACHINE`.
pub const fn torch_word(kind: TorchKind) -> &'static str {
    match kind {
        TorchKind::Hand => "HAND",
        TorchKind::Machine => "MACHINE",
    }
}

/// `ON` / `OFF`.
pub const fn on_off(on: bool) -> &'static str {
    if on { "ON" } else { "OFF" }
}

/// `action=` of `FAULT` and `!FAULT`: a Powermax fault's "Steps Required to Remove?" (SYNC
/// Table 6: Yes / No, but recommended / No, with the protocol crate's choice for codes the
/// table does not list); an HPR error is `required` unless it is a warning.
pub struct ActionWord(pub ActiveFault);

impl Display for ActionWord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(steps_word(steps_of(self.0)))
    }
}

/// `action=` for a fault's steps required (an HPR error's from [`steps_of`]).
pub const fn steps_word(steps: StepsRequired) -> &'static str {
    match steps {
        StepsRequired::Yes => "required",
        StepsRequired::Recommended => "recommended",
        StepsRequired::No => "none",
    }
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
pub fn powermax_fault_text(code: FaultCode, family: Option<Family>) -> Option<TableText> {
    let sync = code.info().map(|i| i.text);
    let legacy = code.legacy_info();
    match family {
        Some(Family::PowermaxLegacy) => legacy.or(sync),
        _ => sync.or(legacy),
    }
}

/// The manual's text for a fault (HPR: the error name). The tables' texts are printable
/// ASCII (their build checks it), so they go on a line as they are.
pub fn fault_text(fault: ActiveFault, family: Option<Family>) -> TableText {
    match fault {
        ActiveFault::Powermax(code) => powermax_fault_text(code, family),
        ActiveFault::Hpr(code) => code.name(),
    }
    .unwrap_or(TableText::plain("unknown fault"))
}

/// The name of an HPR / MaxPro200 state for `family`.
pub fn state_name(state: StateCode, family: Option<Family>) -> TableText {
    match family {
        Some(Family::MaxPro200) => state.maxpro200_name(),
        _ => state.hpr_name(),
    }
    .unwrap_or(TableText::plain("unknown"))
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

/// `mode=CUT amps=45 psi=AUTO` of settings as the unit reports them.
pub struct ProcessText<'a>(pub &'a PowermaxProcess, pub Option<Family>);

impl Display for ProcessText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ProcessText(s, family) = self;
        write!(
            f,
            "mode={} amps={} psi={}",
            OrDash(s.mode.map(|m| mode_word(m, *family))),
            s.current,
            s.pressure
        )
    }
}

/// One word for why settings failed (`!SETTINGS failed reason=...`).
pub fn process_failure_word(reason: &ProcessFailure) -> &'static str {
    match reason {
        ProcessFailure::Transaction(_) => "no_reply",
        ProcessFailure::ReadBackDiffers { .. } => "read_back_differs",
        ProcessFailure::RejectedByUnit { .. } => "rejected_by_unit",
        ProcessFailure::OutsideLimits => "outside_limits",
        ProcessFailure::NotAccepted => "not_accepted",
    }
}

/// A cartridge UID as text (`unreadable` when all zero).
pub struct Uid<'a>(pub &'a [u8; 16]);

impl Display for Uid<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.iter().all(|&b| b == 0) {
            return f.write_str("unreadable");
        }
        for &b in self.0.iter().take_while(|&&b| b != 0) {
            f.write_char(if b.is_ascii_graphic() { b as char } else { '?' })?;
        }
        Ok(())
    }
}

/// A fault's "steps required" (`action=` and history entries): the Powermax table's, or for
/// an HPR error whether someone must act.
pub(super) fn steps_of(fault: ActiveFault) -> StepsRequired {
    match fault {
        ActiveFault::Powermax(code) => code.steps_required(),
        ActiveFault::Hpr(_) if fault.action_required() => StepsRequired::Yes,
        ActiveFault::Hpr(_) => StepsRequired::No,
    }
}

/// `reason=` of `!START REFUSED`/`DROPPED` and of a history entry: the interlock as one word.
pub(super) fn interlock_word(interlock: Interlock) -> &'static str {
    match interlock {
        Interlock::TorchOnAtPowerUp => "torch_on_at_power_up",
        Interlock::TorchOnAtWiringChange => "torch_on_at_config",
        Interlock::LinkDown => "link_down",
        Interlock::RestartBlackout => "restart_blackout",
        Interlock::FaultRequiresAction => "fault",
        Interlock::TransferTimeout => "transfer_timeout",
        Interlock::NotReady => "not_ready",
    }
}
