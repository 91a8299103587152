//! The command table: what a CNC command that needs the unit becomes on each family. Each
//! row names the one link request the command is sent as (and what its reply waits for), an
//! answer from what the bridge already knows, or the `ERR UNSUPPORTED` text of a family
//! without the function. This is the only place that maps CNC commands to link requests; the
//! link checks each request against the family once ([`LinkCommand::runs_on`]).

use plasma_protocol::cnc::{Amps, Command, Gas, Mode, Pressure};
use plasma_protocol::hpr::{GasCode, GasPair};

use super::texts::{Unsupported, unsupported};
use crate::link::{Family, LinkCommand};
use crate::settings::Process;

/// What a command sent to the link waits for: how its reply is written when the link is done.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Awaiting {
    /// `SET ...` on a Powermax: the whole process asked for (kept once the unit confirms it).
    Settings(Process),
    RemoteOff,
    GasTest(bool),
    Restart,
    HprAmps,
    Gases(Gas, Gas),
    Corner,
    Reset,
    ClearWarn,
    Raw,
    FaultLog,
    Counters,
}

/// What a command becomes with the unit on the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Route<'a> {
    /// Sent to the link as this request.
    Send(LinkCommand<'a>, Awaiting),
    /// A Powermax `SET`: the values not given come from the process asked for last (or the
    /// unit's), then all three are sent as one `ApplySettings`.
    Settings {
        mode: Option<Mode>,
        amps: Option<Amps>,
        pressure: Option<Pressure>,
    },
    /// `SET AMPS` on an HPR or MaxPro200: sent as `HprSetNominalAmps` when it is whole amps.
    HprAmps(Amps),
    /// Answered from what the bridge knows; nothing is sent.
    Local,
    /// The family has no such function.
    Unsupported(Unsupported),
    /// The command needs a unit and none is connected.
    NoLink,
    /// Answered by the session whatever is on the line (`HELP`, `CONFIG`, `RAW`, ...).
    Session,
}

/// The table: what `command` becomes on `family` (`None`: no unit connected).
pub(super) fn route<'a>(command: &Command<'a>, family: Option<Family>) -> Route<'a> {
    use LinkCommand as L;
    use Route::{Local, Send, Unsupported as No};
    use unsupported as text;
    let settings = |mode, amps, pressure| Route::Settings {
        mode,
        amps,
        pressure,
    };
    // Each row: [SYNC, LEGACY, HPR, MAXPRO200].
    let row = match *command {
        Command::SetMode(mode) => {
            let set = settings(Some(mode), None, None);
            [set, set, No(text::SET_MODE), No(text::SET_MODE)]
        }
        Command::SetPsi(pressure) => {
            let set = settings(None, None, Some(pressure));
            [set, set, No(text::SET_PSI), No(text::SET_PSI)]
        }
        Command::SetProcess {
            mode,
            amps,
            pressure,
        } => {
            let set = settings(Some(mode), Some(amps), Some(pressure));
            [set, set, No(text::SET_PROCESS), No(text::SET_PROCESS)]
        }
        Command::SetAmps(amps) => {
            let set = settings(None, Some(amps), None);
            [set, set, Route::HprAmps(amps), Route::HprAmps(amps)]
        }
        Command::RemoteOff => {
            let exit = Send(L::ExitRemote, Awaiting::RemoteOff);
            [exit, exit, No(text::REMOTE_OFF), No(text::REMOTE_OFF)]
        }
        // The MaxPro200 protocol has no gas test.
        Command::GasTest(on) => [
            Send(L::GasTest { on }, Awaiting::GasTest(on)),
            Send(L::GasTest { on }, Awaiting::GasTest(on)),
            Send(L::HprGasTest { on }, Awaiting::GasTest(on)),
            No(text::NOT_SUPPORTED),
        ],
        // Quick restart (clears 0-50-0) exists on SYNC units only.
        Command::Restart => [
            Send(L::QuickRestart, Awaiting::Restart),
            No(text::RESTART),
            No(text::RESTART),
            No(text::RESTART),
        ],
        Command::Gases { plasma, shield } => {
            let set = Send(
                L::HprSetInletGases(gas_pair(plasma, shield)),
                Awaiting::Gases(plasma, shield),
            );
            [No(text::GASES), No(text::GASES), set, set]
        }
        Command::Corner(percent) => [
            No(text::CORNER),
            No(text::CORNER),
            Send(L::HprSetCornerCurrent { percent }, Awaiting::Corner),
            No(text::CORNER),
        ],
        Command::Reset => {
            let reset = Send(L::HprSoftwareReset, Awaiting::Reset);
            [No(text::RESET), No(text::RESET), reset, reset]
        }
        Command::ClearWarn => [
            No(text::CLEAR_WARN),
            No(text::CLEAR_WARN),
            Send(L::HprClearWarnings, Awaiting::ClearWarn),
            No(text::CLEAR_WARN),
        ],
        // A SYNC cartridge keeps a fault log (read with the slow data); legacy units and the
        // MaxPro200 keep none the bridge can read.
        Command::FaultLog => [
            Send(L::RefreshSlowData, Awaiting::FaultLog),
            No(text::FAULT_LOG),
            Send(L::HprReadErrorLog, Awaiting::FaultLog),
            No(text::FAULT_LOG),
        ],
        // The MaxPro200 has no timer read: its COUNTERS are the link's own.
        Command::Counters => [
            Send(L::RefreshSlowData, Awaiting::Counters),
            Send(L::RefreshSlowData, Awaiting::Counters),
            Send(L::HprReadTimers, Awaiting::Counters),
            Local,
        ],
        Command::Cartridge => [
            Local,
            No(text::CARTRIDGE),
            No(text::CARTRIDGE),
            No(text::CARTRIDGE),
        ],
        Command::Help
        | Command::Id
        | Command::Status
        | Command::Limits
        | Command::Fault
        | Command::Events(_)
        | Command::Config(_)
        | Command::Torch(_)
        | Command::Raw(_) => return Route::Session,
    };
    let [sync, legacy, hpr, maxpro200] = row;
    match family {
        Some(Family::PowermaxSync) => sync,
        Some(Family::PowermaxLegacy) => legacy,
        Some(Family::Hpr) => hpr,
        Some(Family::MaxPro200) => maxpro200,
        // Without a unit, COUNTERS still has the link's own counters.
        None if matches!(command, Command::Counters) => Local,
        None => Route::NoLink,
    }
}

/// The HPR gas codes of a `GASES` command.
fn gas_pair(plasma: Gas, shield: Gas) -> GasPair {
    GasPair {
        plasma: GasCode(u16::from(plasma.hpr_code())),
        shield: GasCode(u16::from(shield.hpr_code())),
    }
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

    /// One command of each kind the table routes to the unit.
    fn unit_commands() -> [Command<'static>; 15] {
        let amps = Amps::from_raw(45 * Amps::STEPS_PER_UNIT);
        [
            Command::SetMode(Mode::Cut),
            Command::SetPsi(Pressure::Auto),
            Command::SetProcess {
                mode: Mode::Cut,
                amps,
                pressure: Pressure::Auto,
            },
            Command::SetAmps(amps),
            Command::RemoteOff,
            Command::GasTest(true),
            Command::Restart,
            Command::Gases {
                plasma: Gas::Air,
                shield: Gas::Air,
            },
            Command::Corner(80),
            Command::Reset,
            Command::ClearWarn,
            Command::FaultLog,
            Command::Counters,
            Command::Cartridge,
            Command::Raw(":010300000001FB\r\n"),
        ]
    }

    #[test]
    fn the_table_sends_a_family_only_requests_its_driver_runs() {
        for family in FAMILIES {
            for command in unit_commands() {
                if let Route::Send(request, _) = route(&command, Some(family)) {
                    assert!(
                        request.runs_on(family),
                        "{command:?} on {family:?} becomes {request:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn settings_go_to_a_powermax_whole_and_to_an_hpr_as_amps() {
        let amps = Amps::from_raw(45 * Amps::STEPS_PER_UNIT);
        for family in FAMILIES {
            let route = route(&Command::SetAmps(amps), Some(family));
            if family.is_modbus() {
                assert!(matches!(route, Route::Settings { amps: Some(a), .. } if a == amps));
            } else {
                assert_eq!(route, Route::HprAmps(amps));
            }
        }
    }

    #[test]
    fn without_a_unit_only_counters_are_answered() {
        for command in unit_commands() {
            let expected = match command {
                Command::Counters => Route::Local,
                Command::Raw(_) => Route::Session,
                _ => Route::NoLink,
            };
            assert_eq!(route(&command, None), expected, "{command:?}");
        }
        assert_eq!(route(&Command::Help, None), Route::Session);
    }
}
