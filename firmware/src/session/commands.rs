//! Carrying out one command: answered from what the bridge knows, refused, or submitted to
//! the link (the support table, [`crate::link::support`], says which on the unit on the line).

use plasma_protocol::cnc::{Amps, Command, ConfigCommand, ConfigKey, ErrorCode, Mode, Pressure};
use plasma_protocol::hpr::{GasCode, GasPair};

use super::describe::{cnc_mode, on_off, unit_mode, write_refusal};
use super::replies::{cartridge, counters, fault, help, id, limits, status_line};
use super::texts::{self, UnsupportedText};
use super::{Context, Pending, ReplyLine, Session, SimCommand, err_line, line, no_link, ok_line};
use crate::link::command::RAW_CAPACITY;
use crate::link::support::{LinkOp, Route, UnitCommand, route};
use crate::link::{CommandFailure, CommandOutput, Family, HprGasFlow, LinkCommand};
use crate::settings::Process;

/// What a command sent to the link waits for, and how to answer when it is done.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Op {
    Settings(Process),
    RemoteOff,
    GasTest(bool),
    Restart,
    HprAmps,
    Gases(plasma_protocol::cnc::Gas, plasma_protocol::cnc::Gas),
    Corner,
    Reset,
    ClearWarn,
    Raw,
    FaultLog,
    Counters,
}

impl Session {
    /// Carry out one command: its reply, or `None` when it waits for the link or a save.
    pub(super) fn run(&mut self, ctx: &mut Context<'_>, command: Command<'_>) -> Option<ReplyLine> {
        use UnitCommand as U;
        let status = ctx.link.status();
        let family = status.family.filter(|_| status.link_up);
        let unit = match command {
            Command::Help => return Some(help(self.sim_enabled)),
            Command::Id => return Some(id(ctx)),
            Command::Status => return Some(status_line(ctx, self.powermax.refused())),
            Command::Limits => return Some(limits(status, family)),
            Command::Fault => return Some(fault(status, family, self.powermax.refused())),
            Command::Events(on) => return Some(events(ctx, on)),
            Command::Config(config) => return self.config(ctx, config),
            Command::Torch(on) => return Some(self.torch(on)),
            Command::Raw(frame) => return self.raw(ctx, frame),
            Command::FaultLog => U::FaultLog,
            Command::Counters => U::Counters,
            Command::Cartridge => U::Cartridge,
            Command::SetMode(_) => U::SetMode,
            Command::SetAmps(_) => U::SetAmps,
            Command::SetPsi(_) => U::SetPsi,
            Command::SetProcess { .. } => U::SetProcess,
            Command::RemoteOff => U::RemoteOff,
            Command::GasTest(_) => U::GasTest,
            Command::Restart => U::Restart,
            Command::Gases { .. } => U::Gases,
            Command::Corner(_) => U::Corner,
            Command::Reset => U::Reset,
            Command::ClearWarn => U::ClearWarn,
        };
        self.unit_command(ctx, unit, command)
    }

    /// A command whose support depends on the unit's family: the table decides.
    fn unit_command(
        &mut self,
        ctx: &mut Context<'_>,
        unit: UnitCommand,
        command: Command<'_>,
    ) -> Option<ReplyLine> {
        let status = ctx.link.status();
        let family = status.family.filter(|_| status.link_up);
        let route = match family {
            Some(family) => route(unit, family),
            // Without a unit, COUNTERS still has the link's own counters.
            None if unit == UnitCommand::Counters => Route::Local,
            None => return Some(no_link()),
        };
        match (route, family) {
            // The table answers only CARTRIDGE (SYNC) and COUNTERS (MaxPro200) locally.
            (Route::Local, _) => Some(match unit {
                UnitCommand::Cartridge => cartridge(status),
                _ => counters(ctx.link),
            }),
            (Route::Link(op), Some(family)) => self.submit_unit(ctx, family, unit, op, command),
            (_, Some(family)) => Some(unsupported(unit, family)),
            (_, None) => Some(no_link()),
        }
    }

    /// Submit the link command `op` the table chose, with the CNC command's arguments.
    fn submit_unit(
        &mut self,
        ctx: &mut Context<'_>,
        family: Family,
        unit: UnitCommand,
        op: LinkOp,
        command: Command<'_>,
    ) -> Option<ReplyLine> {
        let (link_command, op) = match (op, command) {
            (LinkOp::ApplySettings, Command::SetMode(mode)) => {
                return self.set_powermax(ctx, family, Some(mode), None, None);
            }
            (LinkOp::ApplySettings, Command::SetAmps(amps)) => {
                return self.set_powermax(ctx, family, None, Some(amps), None);
            }
            (LinkOp::ApplySettings, Command::SetPsi(pressure)) => {
                return self.set_powermax(ctx, family, None, None, Some(pressure));
            }
            (
                LinkOp::ApplySettings,
                Command::SetProcess {
                    mode,
                    amps,
                    pressure,
                },
            ) => return self.set_powermax(ctx, family, Some(mode), Some(amps), Some(pressure)),
            (LinkOp::HprSetNominalAmps, Command::SetAmps(amps)) => {
                return self.set_hpr_amps(ctx, amps);
            }
            (LinkOp::ExitRemote, _) => (LinkCommand::ExitRemote, Op::RemoteOff),
            (LinkOp::GasTest, Command::GasTest(on)) => {
                (LinkCommand::GasTest { on }, Op::GasTest(on))
            }
            (LinkOp::HprGasTest, Command::GasTest(on)) => {
                let flow = HprGasFlow::Preflow;
                (LinkCommand::HprGasTest { flow, on }, Op::GasTest(on))
            }
            (LinkOp::QuickRestart, _) => (LinkCommand::QuickRestart, Op::Restart),
            (LinkOp::HprSetInletGases, Command::Gases { plasma, shield }) => {
                let gases = GasPair {
                    plasma: GasCode(u16::from(plasma.hpr_code())),
                    shield: GasCode(u16::from(shield.hpr_code())),
                };
                (
                    LinkCommand::HprSetInletGases(gases),
                    Op::Gases(plasma, shield),
                )
            }
            (LinkOp::HprSetCornerCurrent, Command::Corner(percent)) => {
                (LinkCommand::HprSetCornerCurrent { percent }, Op::Corner)
            }
            (LinkOp::HprSoftwareReset, _) => (LinkCommand::HprSoftwareReset, Op::Reset),
            (LinkOp::HprClearWarnings, _) => (LinkCommand::HprClearWarnings, Op::ClearWarn),
            (LinkOp::RefreshSlowData, Command::FaultLog) => {
                (LinkCommand::RefreshSlowData, Op::FaultLog)
            }
            (LinkOp::HprReadErrorLog, _) => (LinkCommand::HprReadErrorLog, Op::FaultLog),
            (LinkOp::RefreshSlowData, _) => (LinkCommand::RefreshSlowData, Op::Counters),
            (LinkOp::HprReadTimers, _) => (LinkCommand::HprReadTimers, Op::Counters),
            // The table routes no other pair.
            _ => return Some(unsupported(unit, family)),
        };
        self.submit(ctx, link_command, op)
    }

    /// Submit `command`; `None` (the reply waits) when the link took it.
    fn submit(
        &mut self,
        ctx: &mut Context<'_>,
        command: LinkCommand<'_>,
        op: Op,
    ) -> Option<ReplyLine> {
        match ctx.link.submit(ctx.now, command) {
            Ok(ticket) => {
                self.pending = Some(Pending::Link { ticket, op });
                None
            }
            Err(refusal) => {
                let family = ctx.link.status().family;
                Some(line(|l| write_refusal(l, &refusal, family, ctx.now)))
            }
        }
    }

    /// SET MODE / AMPS / PSI / PROCESS on a Powermax: missing values come from the process
    /// asked for last (or, failing that, from the unit), and all three go in one write.
    fn set_powermax(
        &mut self,
        ctx: &mut Context<'_>,
        family: Family,
        mode: Option<Mode>,
        amps: Option<Amps>,
        pressure: Option<Pressure>,
    ) -> Option<ReplyLine> {
        let process = match (mode, amps, pressure) {
            (Some(mode), Some(amps), Some(pressure)) => Process {
                mode,
                amps,
                pressure,
            },
            _ => match base_process(ctx, family) {
                Some(base) => Process {
                    mode: mode.unwrap_or(base.mode),
                    amps: amps.unwrap_or(base.amps),
                    pressure: pressure.unwrap_or(base.pressure),
                },
                None => return Some(err_line(ErrorCode::State, texts::SETTINGS_UNKNOWN)),
            },
        };
        let command = LinkCommand::ApplySettings {
            mode: unit_mode(process.mode),
            current: process.amps,
            pressure: process.pressure,
        };
        self.submit(ctx, command, Op::Settings(process))
    }

    fn set_hpr_amps(&mut self, ctx: &mut Context<'_>, amps: Amps) -> Option<ReplyLine> {
        let steps = amps.raw();
        if !steps.is_multiple_of(Amps::STEPS_PER_UNIT) {
            return Some(err_line(
                ErrorCode::Range,
                format_args!("amps {amps}: this unit takes whole amps"),
            ));
        }
        let command = LinkCommand::HprSetNominalAmps {
            amps: steps / Amps::STEPS_PER_UNIT,
        };
        self.submit(ctx, command, Op::HprAmps)
    }

    fn raw(&mut self, ctx: &mut Context<'_>, frame: &str) -> Option<ReplyLine> {
        if frame.len() > RAW_CAPACITY {
            return Some(err_line(ErrorCode::TooLong, texts::RAW_TOO_LONG));
        }
        self.submit(ctx, LinkCommand::Raw(frame.as_bytes()), Op::Raw)
    }

    fn torch(&mut self, on: bool) -> ReplyLine {
        if !self.sim_enabled {
            err_line(ErrorCode::Unsupported, texts::TORCH_SIMULATOR_ONLY)
        } else if self.sim.push_back(SimCommand::Torch(on)).is_err() {
            err_line(ErrorCode::Busy, texts::SIMULATOR_QUEUE_FULL)
        } else {
            ok_line(|w| w.field("torch", on_off(on)))
        }
    }

    fn config(&mut self, ctx: &mut Context<'_>, config: ConfigCommand<'_>) -> Option<ReplyLine> {
        Some(match config {
            ConfigCommand::Show => {
                let settings = &*ctx.settings;
                ok_line(|w| {
                    for key in ConfigKey::ALL {
                        w.field(key.name(), settings.get(key))?;
                    }
                    Ok(())
                })
            }
            ConfigCommand::Get(key) => {
                let value = ctx.settings.get(key);
                ok_line(|w| w.field(key.name(), value))
            }
            ConfigCommand::Set { key, value } => self.config_set(ctx, key, value),
            ConfigCommand::Save => {
                self.pending = Some(Pending::Save { taken: false });
                return None;
            }
        })
    }

    /// `CONFIG <key> <value>`: a link key starts detection again, an I/O key goes to the
    /// interlocks.
    fn config_set(&mut self, ctx: &mut Context<'_>, key: ConfigKey, value: &str) -> ReplyLine {
        let before = *ctx.settings;
        if let Err(e) = ctx.settings.set(key, value) {
            return err_line(e.code(), e);
        }
        let relink = before.link != ctx.settings.link;
        if relink {
            ctx.link.reconfigure(ctx.now, ctx.settings.link);
        }
        if before.io != ctx.settings.io {
            self.io_config_changed = true;
        }
        // Setting the Phoenix format overrides the one recognised on the port.
        if key == ConfigKey::PhoenixFormat {
            self.recognised = None;
        }
        let value = ctx.settings.get(key);
        ok_line(|w| {
            w.field(key.name(), value)?;
            if relink {
                w.field("link", "redetecting")?;
            }
            Ok(())
        })
    }

    /// What a finished command changes besides its reply: the process the unit confirmed
    /// becomes the one the settings keep (and `CONFIG SAVE` stores); `REMOTE OFF` forgets it.
    pub(super) fn keep_outcome(
        ctx: &mut Context<'_>,
        op: Op,
        result: &Result<CommandOutput, CommandFailure>,
    ) {
        match (op, result) {
            (Op::Settings(process), Ok(CommandOutput::Settings(_))) => {
                ctx.settings.process = Some(process);
            }
            (Op::RemoteOff, Ok(_)) => ctx.settings.process = None,
            _ => {}
        }
    }
}

/// `EVENTS ON|OFF`.
fn events(ctx: &mut Context<'_>, on: bool) -> ReplyLine {
    ctx.settings.events = on;
    ok_line(|w| w.field("events", on_off(on)))
}

/// The process a partial `SET` starts from: the one asked for last (its persisted copy), or
/// failing that the unit's (as the link keeps or reads it).
fn base_process(ctx: &Context<'_>, family: Family) -> Option<Process> {
    ctx.settings.process.or_else(|| {
        let known = ctx.link.kept().powermax().or(ctx.link.status().settings)?;
        Some(Process {
            mode: cnc_mode(known.mode?, Some(family)),
            amps: known.current,
            pressure: known.pressure,
        })
    })
}

/// `ERR UNSUPPORTED` for a command `family` lacks.
fn unsupported(unit: UnitCommand, family: Family) -> ReplyLine {
    err_line(ErrorCode::Unsupported, UnsupportedText(unit, family))
}
