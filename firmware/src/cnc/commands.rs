//! Carrying out one command: answered from what the bridge knows, refused, or submitted to
//! the link as the one request the command table ([`super::table`]) names for the unit on
//! the line.

use plasma_protocol::cnc::{
    AllParameters, Amps, Command, ConfigCommand, ConfigKey, ErrorCode, Gas, Mode, Pressure,
};
use plasma_protocol::hpr::{HprParameters, MaxProParameters};

use super::describe::{cnc_mode, on_off, unit_mode};
use super::replies::{cartridge, counters, fault, help, id, limits, status_line};
use super::table::{Awaiting, Route, gas_pair, route};
use super::texts::{self, UnsupportedText, write_refusal};
use super::{Context, Pending, ReplyLine, Session, SimCommand, err_line, line, no_link, ok_line};
use crate::link::command::RAW_CAPACITY;
use crate::link::{CommandFailure, CommandOutput, Family, LinkCommand};
use crate::settings::Process;
use crate::storage::history::ChangedBy;

/// The current of an HPR / MaxPro200 setting, which takes whole amps (`None`: a fraction).
// Out of line: three settings call it, and inlined it cost 144 B more flash (measured).
#[inline(never)]
fn whole_amps(amps: Amps) -> Option<u16> {
    let steps = amps.raw();
    steps
        .is_multiple_of(Amps::STEPS_PER_UNIT)
        .then_some(steps / Amps::STEPS_PER_UNIT)
}

impl Session {
    /// Carry out one command: its reply, or `None` when it waits for the link or a save.
    pub(super) fn run(&mut self, ctx: &mut Context<'_>, command: Command<'_>) -> Option<ReplyLine> {
        let status = ctx.link().status();
        let family = status.family.filter(|_| status.link_up);
        match route(&command, family) {
            Route::Send(request, awaiting) => self.submit(ctx, request, awaiting),
            Route::Settings {
                mode,
                amps,
                pressure,
            } => self.set_powermax(ctx, family, mode, amps, pressure),
            Route::HprAmps(amps) => self.set_hpr_amps(ctx, amps),
            Route::HprProcess(amps, plasma, shield) => {
                self.set_hpr_process(ctx, amps, plasma, shield)
            }
            Route::HprParameters(parameters) => self.set_hpr_parameters(ctx, parameters),
            // The table answers only CARTRIDGE (SYNC) and COUNTERS (MaxPro200, no unit)
            // locally.
            Route::Local => Some(match command {
                Command::Cartridge => cartridge(status),
                _ => counters(ctx.link()),
            }),
            Route::Unsupported(text) => Some(match family {
                Some(family) => err_line(ErrorCode::Unsupported, UnsupportedText(*text, family)),
                None => no_link(),
            }),
            Route::GasCheck(steps) => self.start_gas_check(ctx, steps),
            Route::NoLink => Some(no_link()),
            Route::Session => self.session_command(ctx, command, family),
        }
    }

    /// A command the session answers whatever unit is on the line.
    fn session_command(
        &mut self,
        ctx: &mut Context<'_>,
        command: Command<'_>,
        family: Option<Family>,
    ) -> Option<ReplyLine> {
        let status = ctx.link().status();
        // A setting refused through the Powermax-speaking port, on this unit's node.
        let refused = self.powermax.refused(ctx.unit);
        Some(match command {
            Command::Help => help(self.sim_enabled),
            Command::Id => id(ctx),
            Command::Status => status_line(ctx, refused),
            Command::Limits => limits(status, family),
            Command::Fault => fault(status, family, refused),
            Command::Events(on) => events(ctx, on),
            Command::Config(config) => return self.config(ctx, config),
            Command::Torch(on) => self.torch(on),
            Command::Power(on) => self.power(ctx, on),
            Command::Raw(frame) => return self.raw(ctx, frame),
            Command::History(history) => return self.history(history),
            Command::Clock(set) => Session::clock(ctx, set),
            Command::Consumables(command) => Session::consumables(ctx, command),
            Command::Units => self.units(ctx),
            // The table routes every other command to the unit.
            _ => no_link(),
        })
    }

    /// Submit `command`; `None` (the reply waits) when the link took it.
    fn submit(
        &mut self,
        ctx: &mut Context<'_>,
        command: LinkCommand<'_>,
        awaiting: Awaiting,
    ) -> Option<ReplyLine> {
        match ctx.submit(command) {
            Ok(ticket) => {
                self.pending = Some(Pending::Link { ticket, awaiting });
                None
            }
            Err(refusal) => {
                let family = ctx.link().status().family;
                Some(line(|l| write_refusal(l, &refusal, family, ctx.now)))
            }
        }
    }

    /// SET MODE / AMPS / PSI / PROCESS on a Powermax: missing values come from the process
    /// asked for last (or, failing that, from the unit), and all three go in one write.
    fn set_powermax(
        &mut self,
        ctx: &mut Context<'_>,
        family: Option<Family>,
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
        super::history::process_change_starts(ctx);
        let command = LinkCommand::ApplyProcess {
            mode: unit_mode(process.mode),
            current: process.amps,
            pressure: process.pressure,
        };
        self.submit(ctx, command, Awaiting::Settings(process))
    }

    fn set_hpr_amps(&mut self, ctx: &mut Context<'_>, amps: Amps) -> Option<ReplyLine> {
        let Some(amps) = whole_amps(amps) else {
            return Some(texts::whole_amps(amps));
        };
        let command = LinkCommand::HprSetNominalAmps { amps };
        self.submit(ctx, command, Awaiting::HprAmps)
    }

    /// `SET HPR_PROCESS` on a MaxPro200: 137, kept and re-applied like `SET AMPS`.
    fn set_hpr_process(
        &mut self,
        ctx: &mut Context<'_>,
        amps: Amps,
        plasma: Gas,
        shield: Gas,
    ) -> Option<ReplyLine> {
        let Some(amps) = whole_amps(amps) else {
            return Some(texts::whole_amps(amps));
        };
        let command = LinkCommand::MaxProSetProcess {
            amps,
            gases: gas_pair(plasma, shield),
        };
        self.submit(ctx, command, Awaiting::HprProcess(amps, plasma, shield))
    }

    /// `SET HPR_PARAMETERS` in the unit's form: 095, read back, kept and re-applied like
    /// `SET AMPS`.
    fn set_hpr_parameters(
        &mut self,
        ctx: &mut Context<'_>,
        parameters: AllParameters,
    ) -> Option<ReplyLine> {
        let (AllParameters::Hpr { amps, .. } | AllParameters::MaxPro200 { amps, .. }) = parameters;
        let Some(amps) = whole_amps(amps) else {
            return Some(texts::whole_amps(amps));
        };
        let command = match parameters {
            AllParameters::Hpr {
                corner,
                plasma,
                shield,
                flows,
                ..
            } => LinkCommand::HprSetAllParameters(HprParameters {
                amps,
                corner_percent: corner,
                gases: gas_pair(plasma, shield),
                flows,
            }),
            AllParameters::MaxPro200 {
                plasma,
                shield,
                pressures,
                ..
            } => LinkCommand::MaxProSetAllParameters(MaxProParameters {
                amps,
                gases: gas_pair(plasma, shield),
                pressures,
            }),
        };
        self.submit(ctx, command, Awaiting::HprParameters(parameters))
    }

    fn raw(&mut self, ctx: &mut Context<'_>, frame: &str) -> Option<ReplyLine> {
        if frame.len() > RAW_CAPACITY {
            return Some(err_line(ErrorCode::TooLong, texts::RAW_TOO_LONG));
        }
        self.submit(ctx, LinkCommand::Raw(frame.as_bytes()), Awaiting::Raw)
    }

    fn torch(&mut self, on: bool) -> ReplyLine {
        let unit = self.answering;
        if !self.sim_enabled {
            err_line(ErrorCode::Unsupported, texts::TORCH_SIMULATOR_ONLY)
        } else if self.sim.push_back(SimCommand::Torch { unit, on }).is_err() {
            err_line(ErrorCode::Busy, texts::SIMULATOR_QUEUE_FULL)
        } else {
            ok_line(|w| w.field("torch", on_off(on)))
        }
    }

    /// `POWER ON|OFF`: the REMOTE_POWER output, with or without a unit on the line (one that
    /// is off has no link). HPR manual: Remote Power "is used to turn the power on or off".
    fn power(&mut self, ctx: &mut Context<'_>, on: bool) -> ReplyLine {
        if ctx.unit != 0 {
            return err_line(ErrorCode::Unsupported, texts::POWER_EVERY_UNIT);
        }
        if ctx.settings.io.remote_power != on {
            ctx.settings.io.remote_power = on;
            self.io_config_changed = true;
        }
        ok_line(|w| w.field("power", on_off(on)))
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
        let new_units = before.units != ctx.settings.units;
        let relink = new_units || before.link.needs_redetect(&ctx.settings.link);
        if new_units {
            // Other units on the line: every link starts afresh, the kept process goes to
            // the first unit as at power-up.
            super::units::restart_units(ctx.units, ctx.settings, ctx.now);
        } else if before.link != ctx.settings.link {
            ctx.units.reconfigure(ctx.now, ctx.settings.link);
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
        awaiting: Awaiting,
        result: &Result<CommandOutput, CommandFailure>,
        by: ChangedBy,
    ) {
        // The settings persist the first unit's process; another unit's is kept by its
        // link alone (re-applied after a link loss, not after a bridge restart).
        if ctx.unit != 0 {
            return;
        }
        match (awaiting, result) {
            (Awaiting::Settings(process), Ok(CommandOutput::Process(_))) => {
                super::history::keep_process(ctx, process, by);
            }
            (Awaiting::RemoteOff, Ok(_)) => ctx.settings.process = None,
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
fn base_process(ctx: &Context<'_>, family: Option<Family>) -> Option<Process> {
    ctx.settings.process.or_else(|| {
        let known = ctx
            .link()
            .kept()
            .powermax()
            .or(ctx.link().status().settings)?;
        Some(Process {
            mode: cnc_mode(known.mode?, family),
            amps: known.current,
            pressure: known.pressure,
        })
    })
}

#[cfg(test)]
mod tests;
