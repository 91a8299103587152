//! The command table: what a CNC command that needs the unit becomes on each family. Each
//! row names the one link request the command is sent as (and what its reply waits for), an
//! answer from what the bridge already knows, or the `ERR UNSUPPORTED` text of a family
//! without the function. This is the only place that maps CNC commands to link requests; the
//! link checks each request against the family once ([`LinkCommand::runs_on`]).

use plasma_protocol::cnc::{
    AllGasFlows, AllParameters, Amps, Command, ConsumablesCommand, Gas, GasFlow, Mode, Pressure,
};
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
    GasFlowTest(GasFlow, bool),
    Restart,
    HprAmps,
    HprProcess(u16, Gas, Gas),
    HprParameters(AllParameters),
    HprGasFlows(AllGasFlows),
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
    /// unit's), then all three are sent as one `ApplyProcess`.
    Settings {
        mode: Option<Mode>,
        amps: Option<Amps>,
        pressure: Option<Pressure>,
    },
    /// `SET AMPS` on an HPR or MaxPro200: sent as `HprSetNominalAmps` when it is whole amps.
    HprAmps(Amps),
    /// `SET HPR_PROCESS` on a MaxPro200: sent as `MaxProSetProcess` when it is whole amps.
    HprProcess(Amps, Gas, Gas),
    /// `SET HPR_PARAMETERS` in the form of the unit's family: sent as `HprSetAllParameters`
    /// or `MaxProSetAllParameters` when it is whole amps.
    HprParameters(AllParameters),
    /// Answered from what the bridge knows; nothing is sent.
    Local,
    /// The family has no such function.
    Unsupported(&'static Unsupported),
    /// `GASTEST CHECK`: these requests, one after the other (see `gas_check`).
    GasCheck(GasCheckSteps),
    /// The command needs a unit and none is connected.
    NoLink,
    /// Answered by the session whatever is on the line (`HELP`, `CONFIG`, `RAW`, ...).
    Session,
}

/// The link requests of a `GASTEST CHECK`: start the gas test, read the pressure while the
/// gas flows, end the test.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct GasCheckSteps {
    pub start: LinkCommand<'static>,
    pub read: LinkCommand<'static>,
    pub stop: LinkCommand<'static>,
}

/// The table: what `command` becomes on `family` (`None`: no unit connected).
pub(super) fn route<'a>(command: &Command<'a>, family: Option<Family>) -> Route<'a> {
    use Family::{Hpr, MaxPro200, PowermaxLegacy as Legacy, PowermaxSync as Sync};
    use LinkCommand as L;
    use Route::{Local, Send, Unsupported as No};
    use unsupported as text;
    let settings = |mode, amps, pressure| Route::Settings {
        mode,
        amps,
        pressure,
    };
    match (*command, family) {
        (
            Command::Help
            | Command::Id
            | Command::Status
            | Command::Limits
            | Command::Fault
            | Command::Events(_)
            | Command::Config(_)
            | Command::Torch(_)
            | Command::History(_)
            | Command::Clock(_)
            | Command::Consumables(ConsumablesCommand::Show)
            | Command::Units
            | Command::Power(_)
            | Command::Raw(_),
            _,
        ) => Route::Session,
        // A SYNC cartridge names its set: another cartridge is a new set by itself.
        (Command::Consumables(ConsumablesCommand::New), Some(Sync)) => No(&text::CONSUMABLES_NEW),
        // Without a unit the operator may still have fitted new consumables.
        (Command::Consumables(_), _) => Route::Session,
        // Without a unit, COUNTERS still has the link's own counters.
        (Command::Counters, None) => Local,
        (_, None) => Route::NoLink,
        (Command::SetMode(mode), Some(Sync | Legacy)) => settings(Some(mode), None, None),
        (Command::SetMode(_), _) => No(&text::SET_MODE),
        (Command::SetPsi(pressure), Some(Sync | Legacy)) => settings(None, None, Some(pressure)),
        (Command::SetPsi(_), _) => No(&text::SET_PSI),
        (
            Command::SetProcess {
                mode,
                amps,
                pressure,
            },
            Some(Sync | Legacy),
        ) => settings(Some(mode), Some(amps), Some(pressure)),
        (Command::SetProcess { .. }, _) => No(&text::SET_PROCESS),
        (Command::SetAmps(amps), Some(Sync | Legacy)) => settings(None, Some(amps), None),
        (Command::SetAmps(amps), Some(Hpr | MaxPro200)) => Route::HprAmps(amps),
        (
            Command::SetHprProcess {
                amps,
                plasma,
                shield,
            },
            Some(MaxPro200),
        ) => Route::HprProcess(amps, plasma, shield),
        (Command::SetHprProcess { .. }, _) => No(&text::HPR_PROCESS),
        // 095 and 078 take other fields on an HPR and on a MaxPro200 (HPR manual lines 165,
        // 180): each family only its own form.
        (Command::SetHprParameters(p @ AllParameters::Hpr { .. }), Some(Hpr))
        | (Command::SetHprParameters(p @ AllParameters::MaxPro200 { .. }), Some(MaxPro200)) => {
            Route::HprParameters(p)
        }
        (Command::SetHprParameters(_), Some(Hpr | MaxPro200)) => No(&text::HPR_PARAMETERS_FORM),
        (Command::SetHprParameters(_), _) => No(&text::HPR_PARAMETERS),
        (Command::SetHprGasFlows(f @ AllGasFlows::Hpr(flows)), Some(Hpr)) => {
            Send(L::HprSetAllGasFlows(flows), Awaiting::HprGasFlows(f))
        }
        (Command::SetHprGasFlows(f @ AllGasFlows::MaxPro200(pressures)), Some(MaxPro200)) => {
            Send(L::MaxProSetAllGasFlows(pressures), Awaiting::HprGasFlows(f))
        }
        (Command::SetHprGasFlows(_), Some(Hpr | MaxPro200)) => No(&text::HPR_GAS_FLOWS_FORM),
        (Command::SetHprGasFlows(_), _) => No(&text::HPR_GAS_FLOWS),
        (Command::RemoteOff, Some(Sync | Legacy)) => Send(L::ExitRemote, Awaiting::RemoteOff),
        (Command::RemoteOff, _) => No(&text::REMOTE_OFF),
        (Command::GasTest(on), Some(Sync | Legacy)) => {
            Send(L::GasTest { on }, Awaiting::GasTest(on))
        }
        (Command::GasTest(on), Some(Hpr)) => {
            Send(L::HprGasTest { cutflow: false, on }, Awaiting::GasTest(on))
        }
        (Command::GasTest(on), Some(MaxPro200)) => {
            Send(L::MaxProTestGas { on }, Awaiting::GasTest(on))
        }
        (Command::GasFlowTest { flow, on }, Some(Hpr)) => Send(
            L::HprGasTest {
                cutflow: flow == GasFlow::Cutflow,
                on,
            },
            Awaiting::GasFlowTest(flow, on),
        ),
        (Command::GasFlowTest { .. }, _) => No(&text::GAS_FLOW_TEST),
        (Command::GasCheck, Some(Sync | Legacy)) => Route::GasCheck(GasCheckSteps {
            start: L::GasTest { on: true },
            read: L::ReadGasPressure,
            stop: L::GasTest { on: false },
        }),
        // The cutflow test: the larger flow, the one that shows a supply that cannot keep up.
        (Command::GasCheck, Some(Hpr)) => Route::GasCheck(GasCheckSteps {
            start: L::HprGasTest {
                cutflow: true,
                on: true,
            },
            read: L::HprReadGasPressures,
            stop: L::HprGasTest {
                cutflow: true,
                on: false,
            },
        }),
        // 143 test gas: "plasma and shield gases flow at set value" (HPR manual line 283).
        (Command::GasCheck, Some(MaxPro200)) => Route::GasCheck(GasCheckSteps {
            start: L::MaxProTestGas { on: true },
            read: L::MaxProReadGasPressures,
            stop: L::MaxProTestGas { on: false },
        }),
        // Quick restart (clears 0-50-0) exists on SYNC units only.
        (Command::Restart, Some(Sync)) => Send(L::QuickRestart, Awaiting::Restart),
        (Command::Restart, _) => No(&text::RESTART),
        (Command::Gases { plasma, shield }, Some(Hpr | MaxPro200)) => Send(
            L::HprSetInletGases(gas_pair(plasma, shield)),
            Awaiting::Gases(plasma, shield),
        ),
        (Command::Gases { .. }, _) => No(&text::GASES),
        (Command::Corner(percent), Some(Hpr)) => {
            Send(L::HprSetCornerCurrent { percent }, Awaiting::Corner)
        }
        (Command::Corner(_), _) => No(&text::CORNER),
        (Command::Reset, Some(Hpr | MaxPro200)) => Send(L::HprSoftwareReset, Awaiting::Reset),
        (Command::Reset, _) => No(&text::RESET),
        (Command::ClearWarn, Some(Hpr)) => Send(L::HprClearWarnings, Awaiting::ClearWarn),
        (Command::ClearWarn, _) => No(&text::CLEAR_WARN),
        // A SYNC cartridge keeps a fault log (read with the slow data); legacy units and the
        // MaxPro200 keep none the bridge can read.
        (Command::FaultLog, Some(Sync)) => Send(L::RefreshSlowData, Awaiting::FaultLog),
        (Command::FaultLog, Some(Hpr)) => Send(L::HprReadErrorLog, Awaiting::FaultLog),
        (Command::FaultLog, _) => No(&text::FAULT_LOG),
        (Command::Counters, Some(Sync | Legacy)) => Send(L::RefreshSlowData, Awaiting::Counters),
        (Command::Counters, Some(Hpr)) => Send(L::HprReadTimers, Awaiting::Counters),
        // The MaxPro200 has no timer read: its COUNTERS are the link's own.
        (Command::Counters, Some(MaxPro200)) => Local,
        (Command::Cartridge, Some(Sync)) => Local,
        (Command::Cartridge, _) => No(&text::CARTRIDGE),
    }
}

/// The HPR gas codes of a `GASES`, `SET HPR_PROCESS` or `SET HPR_PARAMETERS` command.
pub(super) fn gas_pair(plasma: Gas, shield: Gas) -> GasPair {
    GasPair {
        plasma: GasCode(u16::from(plasma.hpr_code())),
        shield: GasCode(u16::from(shield.hpr_code())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::hpr::{GasFlows, MaxProPressures};

    const FAMILIES: [Family; 4] = [
        Family::PowermaxSync,
        Family::PowermaxLegacy,
        Family::Hpr,
        Family::MaxPro200,
    ];

    /// One command of each kind the table routes to the unit.
    fn unit_commands() -> [Command<'static>; 22] {
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
            Command::SetHprProcess {
                amps,
                plasma: Gas::O2,
                shield: Gas::Air,
            },
            Command::SetHprParameters(AllParameters::Hpr {
                amps,
                corner: 80,
                plasma: Gas::O2,
                shield: Gas::Air,
                flows: GasFlows::from_array([55, 45, 35, 25, 0, 0]),
            }),
            Command::SetHprParameters(AllParameters::MaxPro200 {
                amps,
                plasma: Gas::O2,
                shield: Gas::Air,
                pressures: MaxProPressures {
                    plasma: 50,
                    shield: 58,
                },
            }),
            Command::SetHprGasFlows(AllGasFlows::Hpr(GasFlows::from_array([
                55, 45, 35, 25, 0, 0,
            ]))),
            Command::SetHprGasFlows(AllGasFlows::MaxPro200(MaxProPressures {
                plasma: 50,
                shield: 58,
            })),
            Command::RemoteOff,
            Command::GasTest(true),
            Command::GasCheck,
            Command::GasFlowTest {
                flow: GasFlow::Cutflow,
                on: true,
            },
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
                let requests = match route(&command, Some(family)) {
                    Route::Send(request, _) => [Some(request), None, None],
                    Route::GasCheck(steps) => {
                        [Some(steps.start), Some(steps.read), Some(steps.stop)]
                    }
                    _ => [None; 3],
                };
                for request in requests.into_iter().flatten() {
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
    fn set_hpr_parameters_goes_out_only_in_the_units_own_form() {
        let commands = unit_commands();
        let [hpr_form, maxpro_form] = [commands[5], commands[6]];
        for family in FAMILIES {
            for (command, own) in [(hpr_form, Family::Hpr), (maxpro_form, Family::MaxPro200)] {
                let Command::SetHprParameters(parameters) = command else {
                    panic!("{command:?}");
                };
                let routed = route(&command, Some(family));
                assert_eq!(
                    routed == Route::HprParameters(parameters),
                    family == own,
                    "{command:?} on {family:?}"
                );
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
