//! The reply lines of the commands that read what the bridge knows (HELP, ID, STATUS,
//! LIMITS, FAULT, CARTRIDGE, COUNTERS) and of the commands the link finished.

use core::fmt::{self, Display, Write};

use plasma_protocol::cnc::reply::ReplyWriter;
use plasma_protocol::cnc::{
    AllGasFlows, AllParameters, ErrorCode, Gas, HPR_GAS_FLOW_WORDS, MAXPRO_GAS_FLOW_WORDS, Pressure,
};
use plasma_protocol::hpr;

use super::describe::{
    ActionWord, FaultId, ModelName, OrDash, Text, Uid, family_word, fault_text, mode_word, on_off,
    state_name, torch_word, unit_mode,
};
use super::table::Awaiting;
use super::texts::{self, write_failure};
use super::{Context, List, ReplyLine, Session, err_line, line, no_link, ok_line};
use crate::io::{Inputs, Outputs};
use crate::link::{
    ActiveFault, CommandFailure, CommandOutput, Family, HprStatus, Limits, Model, PsLink,
    UnitStatus,
};
use crate::settings::Process;
use plasma_protocol::powermax::FaultCode;

/// The parser's [`COMMAND_WORDS`](plasma_protocol::cnc::command::COMMAND_WORDS) as HELP
/// writes them (one literal: the list joined at run time cost 180 B of flash);
/// `help_is_the_parsers_word_lists` ties the two.
const HELP_COMMANDS: &str = "HELP,ID,STATUS,LIMITS,FAULT,FAULTLOG,COUNTERS,CARTRIDGE,SET,REMOTE,\
                             GASTEST,POWER,RESTART,GASES,CORNER,RESET,CLEARWARN,EVENTS,CONFIG,HISTORY,\
                             CLOCK,CONSUMABLES,UNITS,RAW";
/// The parser's [`SET_WORDS`](plasma_protocol::cnc::command::SET_WORDS) as HELP writes them.
const HELP_SET: &str = "MODE,AMPS,PSI,PROCESS,HPR_PROCESS,HPR_PARAMETERS,HPR_GAS_FLOWS";
/// The parser's [`GASTEST_WORDS`](plasma_protocol::cnc::command::GASTEST_WORDS).
const HELP_GASTEST: &str = "ON,OFF,PREFLOW,CUTFLOW,CHECK";

pub(super) fn help(sim: bool) -> ReplyLine {
    ok_line(|w| {
        // Only words a person can type: a two-word command's second words under its first.
        w.field("commands", HELP_COMMANDS)?;
        w.field("set", HELP_SET)?;
        w.field("remote", "OFF")?;
        w.field("gastest", HELP_GASTEST)?;
        w.field("config", "SAVE")?;
        w.field("history", "CLEAR")?;
        w.field("consumables", "NEW")?;
        w.field("simulator_only", "TORCH")?;
        w.field("simulator", if sim { "YES" } else { "NO" })
    })
}

pub(super) fn link_word(status: &UnitStatus) -> &'static str {
    if status.link_up { "UP" } else { "DOWN" }
}

impl Session {
    /// `UNITS`: a `UNIT` line per unit on the line (its number, address, link, family,
    /// model, fault), then `OK units=<count>`.
    pub(super) fn units(&mut self, ctx: &Context<'_>) -> ReplyLine {
        let named = ctx.settings.units.as_slice();
        for (index, link) in ctx.units.links().enumerate() {
            let status = link.status();
            let l = line(|l| {
                let mut w = ReplyWriter::data(l, "UNIT")?;
                w.field("n", index + 1)?;
                match named.get(index) {
                    Some(unit) => w.field("address", unit)?,
                    None => w.field("address", "AUTO")?,
                }
                w.field("link", link_word(status))?;
                w.field("family", OrDash(status.family.map(family_word)))?;
                w.field("model", ModelName(status))?;
                match (status.link_up, status.active_fault) {
                    (false, _) => w.field("fault", "-")?,
                    (true, None) => w.field("fault", "none")?,
                    (true, Some(fault)) => w.field("fault", FaultId(fault))?,
                }
                w.finish().map(|_| ())
            });
            self.push(l.as_bytes());
        }
        ok_line(|w| w.field("units", ctx.units.count()))
    }
}

pub(super) fn id(ctx: &Context<'_>) -> ReplyLine {
    let status = ctx.link().status();
    ok_line(|w| {
        w.field("bridge", "plasma-bridge")?;
        w.field("version", env!("CARGO_PKG_VERSION"))?;
        w.field("reset", ctx.boot_report.unwrap_or("unknown"))?;
        w.field("link", link_word(status))?;
        w.field("model", ModelName(status))?;
        w.field("family", OrDash(status.family.map(family_word)))?;
        if let Some(Model::Powermax(model)) = status.model {
            w.field("product", model.product_code())?;
        }
        // The torch and its lead choose the cut chart: a SYNC unit's 0x3000, a legacy unit's
        // lead coils (which say nothing of the torch), a MaxPro200's 145 READ TORCH ID
        // (HPR manual line 290; `-` for "No jumper detected" and the reserved ids).
        match status.family {
            Some(family) if family.is_modbus() => {
                let torch = status.identification.and_then(|i| i.torch);
                w.field("torch", OrDash(torch.map(|t| torch_word(t.kind))))?;
                w.field("lead_ft", OrDash(status.torch_lead().map(|l| l.max_feet())))?;
            }
            Some(Family::MaxPro200) => {
                let torch = status.hpr.torch.and_then(|t| t.torch());
                w.field("torch", OrDash(torch.map(|(kind, _)| torch_word(kind))))?;
                w.field("lead_ft", OrDash(torch.map(|(_, feet)| feet)))?;
            }
            _ => {}
        }
        // An HPR's and a MaxPro200's firmware (001 VERSION, line 140): what a service call
        // asks for first.
        if status.family.is_some_and(|f| !f.is_modbus()) {
            let firmware = status.hpr.firmware;
            let power_supply = firmware.as_ref().map(|f| Text(f.power_supply.as_str()));
            w.field("firmware", OrDash(power_supply))?;
            let gas_console = firmware.as_ref().and_then(|f| f.gas_console.as_ref());
            w.field(
                "gas_firmware",
                OrDash(gas_console.map(|r| Text(r.as_str()))),
            )?;
        }
        Ok(())
    })
}

/// `STATUS`; `refused`: the 0-11-x fault of a setting the unit refused through the Powermax
/// registers, shown while the unit itself has no fault (as 0x2098 shows it).
pub(super) fn status_line(ctx: &Context<'_>, refused: Option<FaultCode>) -> ReplyLine {
    let status = ctx.link().status();
    let active_fault = status.active_fault.or(refused.map(ActiveFault::Powermax));
    let family = status.family;
    let hpr = matches!(family, Some(Family::Hpr | Family::MaxPro200));
    let (inputs, outputs) = ctx.io().unwrap_or((Inputs::NONE, Outputs::OFF));
    let ready = match ctx.io() {
        Some((_, outputs)) => outputs.ready,
        None => status.ready,
    };
    ok_line(|w| {
        w.field("link", link_word(status))?;
        w.field("model", ModelName(status))?;
        w.field("family", OrDash(family.map(family_word)))?;
        w.field("remote", on_off(status.remote))?;
        if hpr {
            // What 079 GET_PS_INFO and 028 READ_PLASMA_AMPS report (HPR manual lines 148,
            // 168): an HPR's 079 has measured pressures, a MaxPro200's the set points.
            let hpr = &status.hpr;
            let maxpro = hpr.maxpro_info;
            w.field("mode", "-")?;
            w.field("amps", OrDash(hpr.nominal_amps))?;
            w.field("psi", OrDash(maxpro.map(|m| m.plasma_setpoint)))?;
            w.field("out_amps", OrDash(hpr.actual_amps))?;
            let pressures = hpr.ps_info.map(|p| p.pressures);
            w.field("out_psi", OrDash(pressures.map(|p| p.plasma_cutflow)))?;
        } else {
            let settings = status.settings;
            w.field(
                "mode",
                OrDash(settings.and_then(|s| s.mode).map(|m| mode_word(m, family))),
            )?;
            w.field("amps", OrDash(settings.map(|s| s.current)))?;
            // Asked for automatic pressure, the unit reads back the set point it chose (SYNC
            // 0x3012 "gas pressure setting"): the request is AUTO, as SET answered, and the
            // choice is shown beside it.
            let unit_psi = settings.map(|s| s.pressure);
            if status.remote && kept_auto_pressure(ctx.link()) {
                w.field("psi", "AUTO")?;
                w.field("auto_psi", OrDash(unit_psi.and_then(Pressure::psi)))?;
            } else {
                w.field("psi", OrDash(unit_psi))?;
            }
            w.field("out_amps", OrDash(status.actual_current))?;
            w.field("out_psi", OrDash(status.actual_pressure))?;
        }
        match active_fault {
            Some(fault) => w.field("fault", FaultId(fault))?,
            None => w.field("fault", "none")?,
        }
        w.field("start", on_off(outputs.start))?;
        w.field("motion", on_off(inputs.motion))?;
        w.field("arc_ok", on_off(outputs.arc_ok))?;
        w.field("ready", on_off(ready))?;
        // The optional HPR signals, only while on: an installation without them wired sees
        // the line it always did.
        if inputs.system_error {
            w.field("system_error", "ON")?;
        }
        if outputs.remote_power {
            w.field("power", "ON")?;
        }
        // Only with a limit set: without one there is no share of life to show.
        if let Some(used) = super::consumables::used_percent(ctx) {
            w.field("consumables", format_args!("{used}%"))?;
        }
        if let Some(state) = status.hpr.state.filter(|_| hpr) {
            w.field("state", state.0)?;
            w.field("state_name", state_name(state, family))?;
        }
        if hpr {
            hpr_status(w, &status.hpr, status.model)?;
        }
        Ok(())
    })
}

/// The process the unit confirmed, and the link re-applies, asks for automatic pressure.
fn kept_auto_pressure(link: &PsLink) -> bool {
    link.kept()
        .powermax()
        .is_some_and(|p| p.pressure == Pressure::Auto)
}

/// STATUS's HPR / MaxPro200 fields from the last 079 GET_PS_INFO: the HPR's four measured
/// pressures, the MaxPro200's shield set point and gases.
fn hpr_status(
    w: &mut ReplyWriter<&mut ReplyLine>,
    hpr: &HprStatus,
    model: Option<Model>,
) -> fmt::Result {
    if let Some(Model::Hpr(system)) = model
        && let Some(console) = console_word(system)
    {
        w.field("console", console)?;
    }
    // Named as the set points of SET HPR_GAS_FLOWS.
    let [
        plasma_cutflow,
        plasma_preflow,
        shield_cutflow,
        shield_preflow,
        ..,
    ] = HPR_GAS_FLOW_WORDS;
    if let Some(p) = hpr.ps_info.map(|i| i.pressures) {
        w.field(plasma_cutflow, p.plasma_cutflow)?;
        w.field(plasma_preflow, p.plasma_preflow)?;
        w.field(shield_cutflow, p.shield_cutflow)?;
        w.field(shield_preflow, p.shield_preflow)?;
    }
    if let Some(m) = hpr.maxpro_info {
        // Display mode 3 is "Test Mode" (line 168): the 143 test gas is on.
        w.field("gastest", on_off(m.display_mode == 3))?;
        w.field(MAXPRO_GAS_FLOW_WORDS[1], m.shield_setpoint)?;
        w.field("plasma", GasName(m.plasma_gas))?;
        w.field("shield", GasName(m.shield_gas))?;
    }
    // A manual gas console's switch positions (slow data, 122); an automatic one's inlet gases
    // (slow data, 098).
    if let Some(gases) = hpr.gases.or(hpr.inlet_gases) {
        w.field("plasma", GasName(gases.plasma))?;
        w.field("shield", GasName(gases.shield))?;
    }
    Ok(())
}

/// An HPR's gas console as HELLO names it.
fn console_word(system: hpr::SystemId) -> Option<&'static str> {
    match system {
        hpr::SystemId::Hpr {
            console: Some(console),
            ..
        } => Some(match console {
            hpr::GasConsole::Manual => "MANUAL",
            hpr::GasConsole::Auto => "AUTO",
            hpr::GasConsole::AutoMix => "AUTOMIX",
        }),
        _ => None,
    }
}

/// A table VI gas code as the word `GASES` takes, or its number (codes a CNC does not select).
struct GasName(hpr::GasCode);

impl Display for GasName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let gas = u8::try_from(self.0.0).ok().and_then(Gas::from_hpr_code);
        match gas {
            Some(gas) => f.write_str(gas.name()),
            None => write!(f, "{}", self.0.0),
        }
    }
}

pub(super) fn limits(status: &UnitStatus, family: Option<Family>) -> ReplyLine {
    match (family, status.model) {
        (None, _) => no_link(),
        (Some(Family::Hpr | Family::MaxPro200), Some(Model::Hpr(system))) => hpr_limits(system),
        (Some(family), _) => match status.limits {
            None => err_line(ErrorCode::State, texts::LIMITS_NOT_READ),
            Some(limits) => powermax_limits(&limits, family),
        },
    }
}

/// The current range the unit on the line accepts, as LIMITS shows it (`20..65`).
#[derive(Debug, Clone, Copy)]
pub(super) enum AmpsRange {
    /// An HPR's or MaxPro200's: the manual's least current up to the unit's rating.
    Hpr(hpr::SystemId),
    /// A Powermax's, as it reported them (SYNC: for the installed cartridge).
    Powermax(Limits),
}

impl AmpsRange {
    /// The range of the unit on the line, if the link knows it.
    pub(super) fn of(status: &UnitStatus, family: Option<Family>) -> Option<AmpsRange> {
        match (family?, status.model) {
            (Family::Hpr | Family::MaxPro200, Some(Model::Hpr(system))) => {
                Some(AmpsRange::Hpr(system))
            }
            _ => status.limits.map(AmpsRange::Powermax),
        }
    }
}

impl Display for AmpsRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AmpsRange::Hpr(system) => {
                let max = match system {
                    hpr::SystemId::Hpr { rating, .. } => rating.max_amps(),
                    hpr::SystemId::MaxPro200 => hpr::MAX_MAXPRO_AMPS,
                };
                write!(f, "{}..{max}", hpr::MIN_AMPS)
            }
            AmpsRange::Powermax(limits) => {
                write!(f, "{}..{}", limits.min_current, limits.max_current)
            }
        }
    }
}

/// An HPR's or MaxPro200's ranges: from the manual and the unit's rating, for what its
/// system takes (a manual gas console sets the current at its knobs: `amps=-`).
fn hpr_limits(system: hpr::SystemId) -> ReplyLine {
    use hpr::command::id;
    let amps = hpr::accepts(id::SET_NOMINAL_AMPS, &system).then_some(AmpsRange::Hpr(system));
    ok_line(|w| {
        w.field("amps", OrDash(amps))?;
        if hpr::accepts(id::SET_CORNER_CURRENT, &system) {
            let (low, high) = (hpr::CORNER_PERCENT.start(), hpr::CORNER_PERCENT.end());
            w.field("corner", format_args!("{low}..{high}"))?;
        }
        if let Some(console) = console_word(system) {
            w.field("console", console)?;
        }
        Ok(())
    })
}

/// A Powermax's limits as it reports them (SYNC: for the installed cartridge).
fn powermax_limits(limits: &Limits, family: Family) -> ReplyLine {
    ok_line(|w| {
        match limits.modes {
            Some(modes) => {
                let low = modes.low_mode();
                let high = modes.high_mode().filter(|h| Some(*h) != low);
                let words = low
                    .into_iter()
                    .chain(high)
                    .map(|m| mode_word(m, Some(family)));
                w.field("modes", List(words))?;
            }
            None => w.field("modes", "CUT,CPA,GOUGE")?,
        }
        w.field("amps", AmpsRange::Powermax(*limits))?;
        let (min, max) = (limits.min_pressure, limits.max_pressure);
        w.field("psi", format_args!("{min}..{max}"))?;
        let scope = match family {
            Family::PowermaxSync => "cartridge",
            _ => "unit",
        };
        w.field("scope", scope)
    })
}

pub(super) fn fault(
    status: &UnitStatus,
    family: Option<Family>,
    refused: Option<FaultCode>,
) -> ReplyLine {
    if family.is_none() {
        return no_link();
    }
    match status.active_fault.or(refused.map(ActiveFault::Powermax)) {
        None => ok_line(|w| w.field("fault", "none")),
        // `text=` is the last field and runs to the end of the line: the manual's words.
        Some(fault) => line(|l| {
            write!(
                l,
                "OK fault={} action={} text={}\r\n",
                FaultId(fault),
                ActionWord(fault),
                fault_text(fault, family)
            )
        }),
    }
}

/// `CARTRIDGE` on a SYNC unit (the command table refuses it elsewhere).
pub(super) fn cartridge(status: &UnitStatus) -> ReplyLine {
    match status.cartridge {
        None => err_line(ErrorCode::State, texts::CARTRIDGE_NOT_READ),
        Some(c) => ok_line(|w| {
            w.field("uid", Uid(&c.uid.0))?;
            w.field("part", OrDash(c.part_number.as_str()))?;
            w.field("rev", c.revision)?;
            w.field("nominal_amps", c.nominal_current())?;
            if let Some(name) = status
                .cartridge_name
                .as_ref()
                .and_then(|n| n.as_str())
                .filter(|n| !n.is_empty())
            {
                w.field("name", name)?;
            }
            w.field("starts", c.counters.starts)?;
            w.field("pilot_arc_s", c.counters.pilot_arc_seconds)?;
            w.field("transfers", c.counters.transfers)?;
            w.field("transfer_s", c.counters.transfer_seconds())
        }),
    }
}

pub(super) fn counters(link: &PsLink) -> ReplyLine {
    counters_with(link, |_| Ok(()))
}

/// The unit's counters (written by `unit`) followed by the link's.
pub(super) fn counters_with(
    link: &PsLink,
    unit: impl FnOnce(&mut ReplyWriter<&mut ReplyLine>) -> fmt::Result,
) -> ReplyLine {
    let d = link.diagnostics();
    ok_line(|w| {
        unit(w)?;
        w.field("link_ok", d.transactions_ok)?;
        w.field("link_failed", d.transactions_failed)?;
        w.field("retries", d.retries)?;
        w.field("timeouts", d.timeouts)?;
        w.field("bad_checksums", d.bad_checksums)?;
        w.field("link_downs", d.link_downs)
    })
}

/// The reply of a command the link finished. It only formats: what the outcome changes is
/// the command handler's (`Session::keep_outcome`).
// Kept out of the link-event loop it is called from: a smaller image.
#[inline(never)]
pub(super) fn complete(
    ctx: &Context<'_>,
    awaiting: Awaiting,
    result: &Result<CommandOutput, CommandFailure>,
) -> ReplyLine {
    let family = ctx.link().status().family;
    let output = match result {
        Err(failure) => return line(|l| write_failure(l, failure, family)),
        Ok(output) => *output,
    };
    match awaiting {
        Awaiting::Settings(process) => process_done(process, output, family),
        Awaiting::RemoteOff => ok_line(|w| w.field("remote", "OFF")),
        Awaiting::GasTest(on) => ok_line(|w| w.field("gastest", on_off(on))),
        Awaiting::GasFlowTest(flow, on) => ok_line(|w| {
            w.field("gastest", on_off(on))?;
            w.field("flow", flow.name())
        }),
        Awaiting::Restart => restart_done(ctx),
        Awaiting::HprAmps => match output {
            CommandOutput::Value(amps) => ok_line(|w| w.field("amps", amps)),
            _ => ok_line(|w| w.field("amps", "set")),
        },
        Awaiting::HprProcess(amps, plasma, shield) => ok_line(|w| {
            w.field("amps", amps)?;
            w.field("plasma", plasma.name())?;
            w.field("shield", shield.name())
        }),
        Awaiting::HprParameters(parameters) => ok_line(|w| all_parameters(w, &parameters)),
        Awaiting::HprGasFlows(flows) => ok_line(|w| all_gas_flows(w, &flows)),
        Awaiting::Gases(plasma, shield) => ok_line(|w| {
            w.field("plasma", plasma.name())?;
            w.field("shield", shield.name())
        }),
        Awaiting::Corner => match output {
            CommandOutput::Value(percent) => ok_line(|w| w.field("corner", percent)),
            _ => ok_line(|w| w.field("corner", "set")),
        },
        Awaiting::Reset => ok_line(|w| w.field("reset", "done")),
        Awaiting::ClearWarn => ok_line(|w| w.field("clearwarn", "done")),
        Awaiting::Raw => raw_done(ctx, output),
        Awaiting::FaultLog => fault_log_done(ctx, output),
        Awaiting::Counters => counters_done(ctx),
    }
}

/// `SET HPR_PARAMETERS` confirmed: the values sent, which the unit read back (the link's
/// `hpr::confirm`).
fn all_parameters(w: &mut ReplyWriter<&mut ReplyLine>, parameters: &AllParameters) -> fmt::Result {
    let (plasma, shield, flows) = match *parameters {
        AllParameters::Hpr {
            amps,
            corner,
            plasma,
            shield,
            flows,
        } => {
            w.field("amps", amps)?;
            w.field("corner", corner)?;
            (plasma, shield, AllGasFlows::Hpr(flows))
        }
        AllParameters::MaxPro200 {
            amps,
            plasma,
            shield,
            pressures,
        } => {
            w.field("amps", amps)?;
            (plasma, shield, AllGasFlows::MaxPro200(pressures))
        }
    };
    w.field("plasma", plasma.name())?;
    w.field("shield", shield.name())?;
    all_gas_flows(w, &flows)
}

/// `SET HPR_GAS_FLOWS` confirmed: the set points sent, which the unit read back.
fn all_gas_flows(w: &mut ReplyWriter<&mut ReplyLine>, flows: &AllGasFlows) -> fmt::Result {
    let (names, pressures): (&[&str], [u16; 6]) = match *flows {
        AllGasFlows::Hpr(flows) => (&HPR_GAS_FLOW_WORDS, flows.to_array()),
        AllGasFlows::MaxPro200(p) => (&MAXPRO_GAS_FLOW_WORDS, [p.plasma, p.shield, 0, 0, 0, 0]),
    };
    names
        .iter()
        .zip(pressures)
        .try_for_each(|(name, psi)| w.field(name, psi))
}

/// `SET ...` confirmed: the settings as the unit reads them back.
fn process_done(process: Process, output: CommandOutput, family: Option<Family>) -> ReplyLine {
    let CommandOutput::Process(read) = output else {
        return ok_line(|w| w.field("mode", mode_word(unit_mode(process.mode), family)));
    };
    // The unit's word for the mode read back (SYNC: EXPANDED, legacy: CPA).
    let mode = read.mode.map_or("-", |m| mode_word(m, family));
    ok_line(|w| {
        w.field("mode", mode)?;
        w.field("amps", read.current)?;
        match process.pressure {
            Pressure::Auto => w.field("psi", "AUTO"),
            Pressure::Set(_) => w.field("psi", read.pressure),
        }
    })
}

/// `RESTART` done: how long the unit stays quiet.
fn restart_done(ctx: &Context<'_>) -> ReplyLine {
    let quiet = ctx
        .link()
        .status()
        .restart_blackout_until
        .map(|until| until.saturating_since(ctx.now).as_millis_u32());
    ok_line(|w| {
        w.field("restart", "done")?;
        w.field("quiet_ms", OrDash(quiet))
    })
}

/// `RAW` answered: the unit's reply frame.
fn raw_done(ctx: &Context<'_>, output: CommandOutput) -> ReplyLine {
    let len = match output {
        CommandOutput::Raw { len } => len,
        _ => 0,
    };
    let reply = ctx.link().raw_reply();
    let reply = reply.get(..len).unwrap_or(reply).trim_ascii_end();
    let text = core::str::from_utf8(reply).unwrap_or("?");
    // `reply=` is the last field and runs to the end of the line: an HPR reply may hold
    // spaces.
    line(|l| write!(l, "OK reply={}\r\n", Text(text)))
}

/// `FAULTLOG` read: the HPR error log or the SYNC cartridge's fault log.
fn fault_log_done(ctx: &Context<'_>, output: CommandOutput) -> ReplyLine {
    let status = ctx.link().status();
    match (output, status.fault_log, status.hpr.error_log) {
        (CommandOutput::ErrorLog(log), _, _) | (_, None, Some(log)) => ok_line(|w| {
            let codes = log.iter().filter(|e| e.0 != 0).map(|e| HprId(e.0));
            w.field("log", List(codes))
        }),
        (_, Some(log), _) => ok_line(|w| {
            let codes = log.0.iter().copied().filter(|c| !c.is_none());
            w.field("log", List(codes))
        }),
        _ => err_line(ErrorCode::Link, texts::FAULT_LOG_UNREADABLE),
    }
}

/// `COUNTERS` read: the unit's counters, then the link's.
fn counters_done(ctx: &Context<'_>) -> ReplyLine {
    let status = ctx.link().status().clone();
    counters_with(ctx.link(), |w| {
        if let Some(c) = status.ps_counters {
            w.field("starts", c.starts)?;
            w.field("pilot_arc_s", c.pilot_arc_seconds)?;
            w.field("transfers", c.transfers)?;
            w.field("transfer_s", c.transfer_seconds)?;
        }
        if let Some(s) = status.arc_seconds {
            w.field("arc_s", s)?;
        }
        if let Some(t) = status.hpr.timers {
            w.field("arc_s", t.arc_on_seconds)?;
            w.field("system_min", t.system_on_minutes)?;
            w.field("starts", t.starts)?;
            w.field("start_errors", t.start_errors)?;
            w.field("rampdown_errors", t.rampdown_errors)?;
        }
        Ok(())
    })
}

/// An HPR error code in the manual's three digits.
pub(super) struct HprId(pub(super) u16);

impl Display for HprId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:03}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::{HELP_COMMANDS, HELP_GASTEST, HELP_SET};
    use plasma_protocol::cnc::command::{COMMAND_WORDS, GASTEST_WORDS, SET_WORDS};

    #[test]
    fn help_is_the_parsers_word_lists() {
        assert!(HELP_COMMANDS.split(',').eq(COMMAND_WORDS));
        assert!(HELP_SET.split(',').eq(SET_WORDS));
        assert!(HELP_GASTEST.split(',').eq(GASTEST_WORDS));
    }
}
