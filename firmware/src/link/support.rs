//! Which unit family supports which CNC command, and which link command it becomes.
//!
//! One table, read by both sides: the session looks up what a CNC command becomes on the unit
//! on the line (submit it, answer it from what the bridge knows, or refuse it), and the link
//! accepts exactly the link commands the table routes to on its family (plus the few that no
//! CNC command becomes, [`link_only`]). It lives in the link layer because the session sits on
//! the link: the link cannot read the session, the session can read the link.

use super::command::LinkCommand;
use super::status::Family;

/// A CNC command whose support depends on the unit's family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum UnitCommand {
    /// `SET MODE`.
    SetMode,
    /// `SET PSI`.
    SetPsi,
    /// `SET PROCESS`.
    SetProcess,
    /// `SET AMPS`.
    SetAmps,
    /// `REMOTE OFF`.
    RemoteOff,
    /// `GASTEST ON|OFF`.
    GasTest,
    /// `RESTART`.
    Restart,
    /// `GASES`.
    Gases,
    /// `CORNER`.
    Corner,
    /// `RESET`.
    Reset,
    /// `CLEARWARN`.
    ClearWarn,
    /// `FAULTLOG`.
    FaultLog,
    /// `COUNTERS`.
    Counters,
    /// `CARTRIDGE`.
    Cartridge,
    /// `RAW`.
    Raw,
}

impl UnitCommand {
    /// Every row of the table.
    pub const ALL: [UnitCommand; 15] = [
        UnitCommand::SetMode,
        UnitCommand::SetPsi,
        UnitCommand::SetProcess,
        UnitCommand::SetAmps,
        UnitCommand::RemoteOff,
        UnitCommand::GasTest,
        UnitCommand::Restart,
        UnitCommand::Gases,
        UnitCommand::Corner,
        UnitCommand::Reset,
        UnitCommand::ClearWarn,
        UnitCommand::FaultLog,
        UnitCommand::Counters,
        UnitCommand::Cartridge,
        UnitCommand::Raw,
    ];
}

/// A link command without its arguments.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[allow(missing_docs)] // Each names the `LinkCommand` variant of the same name.
pub enum LinkOp {
    ApplySettings,
    ExitRemote,
    GasTest,
    QuickRestart,
    RefreshSlowData,
    HprSetNominalAmps,
    HprSetProcess,
    HprSetInletGases,
    HprSetCornerCurrent,
    HprClearWarnings,
    HprSoftwareReset,
    HprGasTest,
    HprReadErrorLog,
    HprReadTimers,
    Raw,
}

impl LinkCommand<'_> {
    /// The command without its arguments: the key into the support table.
    pub const fn op(&self) -> LinkOp {
        match self {
            LinkCommand::ApplySettings { .. } => LinkOp::ApplySettings,
            LinkCommand::ExitRemote => LinkOp::ExitRemote,
            LinkCommand::GasTest { .. } => LinkOp::GasTest,
            LinkCommand::QuickRestart => LinkOp::QuickRestart,
            LinkCommand::RefreshSlowData => LinkOp::RefreshSlowData,
            LinkCommand::HprSetNominalAmps { .. } => LinkOp::HprSetNominalAmps,
            LinkCommand::HprSetProcess { .. } => LinkOp::HprSetProcess,
            LinkCommand::HprSetInletGases(_) => LinkOp::HprSetInletGases,
            LinkCommand::HprSetCornerCurrent { .. } => LinkOp::HprSetCornerCurrent,
            LinkCommand::HprClearWarnings => LinkOp::HprClearWarnings,
            LinkCommand::HprSoftwareReset => LinkOp::HprSoftwareReset,
            LinkCommand::HprGasTest { .. } => LinkOp::HprGasTest,
            LinkCommand::HprReadErrorLog => LinkOp::HprReadErrorLog,
            LinkCommand::HprReadTimers => LinkOp::HprReadTimers,
            LinkCommand::Raw(_) => LinkOp::Raw,
        }
    }
}

/// What a CNC command becomes on a family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Route {
    /// Submitted to the link as this command.
    Link(LinkOp),
    /// Answered from what the bridge already knows; nothing is sent.
    Local,
    /// The family has no such function.
    Unsupported,
}

/// The table: what `command` becomes on `family`. (One copy in the image: the session and
/// the link both call it.)
#[inline(never)]
pub fn route(command: UnitCommand, family: Family) -> Route {
    use LinkOp as L;
    use Route::{Link, Local, Unsupported as No};
    use UnitCommand as C;
    // Each row: [SYNC, LEGACY, HPR, MAXPRO200].
    let row = match command {
        C::SetMode => [Link(L::ApplySettings), Link(L::ApplySettings), No, No],
        C::SetPsi => [Link(L::ApplySettings), Link(L::ApplySettings), No, No],
        C::SetProcess => [Link(L::ApplySettings), Link(L::ApplySettings), No, No],
        C::SetAmps => [
            Link(L::ApplySettings),
            Link(L::ApplySettings),
            Link(L::HprSetNominalAmps),
            Link(L::HprSetNominalAmps),
        ],
        C::RemoteOff => [Link(L::ExitRemote), Link(L::ExitRemote), No, No],
        // The MaxPro200 protocol has no gas test.
        C::GasTest => [Link(L::GasTest), Link(L::GasTest), Link(L::HprGasTest), No],
        // Quick restart (clears 0-50-0) exists on SYNC units only.
        C::Restart => [Link(L::QuickRestart), No, No, No],
        C::Gases => [No, No, Link(L::HprSetInletGases), Link(L::HprSetInletGases)],
        C::Corner => [No, No, Link(L::HprSetCornerCurrent), No],
        C::Reset => [No, No, Link(L::HprSoftwareReset), Link(L::HprSoftwareReset)],
        C::ClearWarn => [No, No, Link(L::HprClearWarnings), No],
        // A SYNC cartridge keeps a fault log (read with the slow data); legacy units and the
        // MaxPro200 keep none the bridge can read.
        C::FaultLog => [Link(L::RefreshSlowData), No, Link(L::HprReadErrorLog), No],
        // The MaxPro200 has no timer read: its COUNTERS are the link's own.
        C::Counters => [
            Link(L::RefreshSlowData),
            Link(L::RefreshSlowData),
            Link(L::HprReadTimers),
            Local,
        ],
        C::Cartridge => [Local, No, No, No],
        C::Raw => [Link(L::Raw), Link(L::Raw), Link(L::Raw), Link(L::Raw)],
    };
    let [sync, legacy, hpr, maxpro200] = row;
    match family {
        Family::PowermaxSync => sync,
        Family::PowermaxLegacy => legacy,
        Family::Hpr => hpr,
        Family::MaxPro200 => maxpro200,
    }
}

/// Link commands no CNC command becomes (host tools and tests submit them directly), and
/// the families that take them.
pub const fn link_only(op: LinkOp, family: Family) -> bool {
    matches!(
        (op, family),
        (LinkOp::HprSetProcess, Family::MaxPro200)
            // Every family's slow data can be read again (a MaxPro200 has none: done at once).
            | (LinkOp::RefreshSlowData, _)
    )
}

/// True when the link takes `op` on `family`: a CNC command becomes it there, or it is
/// [`link_only`].
pub fn accepts(family: Family, op: LinkOp) -> bool {
    link_only(op, family)
        || UnitCommand::ALL
            .iter()
            .any(|&command| matches!(route(command, family), Route::Link(o) if o == op))
}

#[cfg(test)]
mod tests {
    use super::*;

    const FAMILIES: [Family; 4] = [
        Family::PowermaxSync,
        Family::PowermaxLegacy,
        Family::Hpr,
        Family::MaxPro200,
    ];

    #[test]
    fn powermax_commands_stay_on_the_modbus_families_and_hpr_commands_on_the_others() {
        for family in FAMILIES {
            for command in UnitCommand::ALL {
                let Route::Link(op) = route(command, family) else {
                    continue;
                };
                let hpr_op = matches!(
                    op,
                    LinkOp::HprSetNominalAmps
                        | LinkOp::HprSetInletGases
                        | LinkOp::HprSetCornerCurrent
                        | LinkOp::HprClearWarnings
                        | LinkOp::HprSoftwareReset
                        | LinkOp::HprGasTest
                        | LinkOp::HprReadErrorLog
                        | LinkOp::HprReadTimers
                );
                let shared = matches!(op, LinkOp::Raw | LinkOp::RefreshSlowData);
                assert!(
                    shared || hpr_op != family.is_modbus(),
                    "{command:?} on {family:?} becomes {op:?}"
                );
            }
        }
    }

    #[test]
    fn the_link_accepts_what_the_table_routes_to_and_nothing_else() {
        assert!(accepts(Family::Hpr, LinkOp::HprSetCornerCurrent));
        assert!(!accepts(Family::MaxPro200, LinkOp::HprSetCornerCurrent));
        assert!(!accepts(Family::MaxPro200, LinkOp::HprGasTest));
        assert!(accepts(Family::PowermaxSync, LinkOp::QuickRestart));
        assert!(!accepts(Family::PowermaxLegacy, LinkOp::QuickRestart));
        assert!(accepts(Family::PowermaxLegacy, LinkOp::RefreshSlowData));
        assert!(accepts(Family::MaxPro200, LinkOp::RefreshSlowData));
        assert!(accepts(Family::Hpr, LinkOp::RefreshSlowData));
        assert!(!accepts(Family::PowermaxSync, LinkOp::HprSetProcess));
        assert!(!accepts(Family::Hpr, LinkOp::ApplySettings));
        for family in FAMILIES {
            assert!(accepts(family, LinkOp::Raw));
        }
    }
}
