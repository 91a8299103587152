//! HPR / MaxPro200 frames: checksum, command and class, typed request and reply fields.

use plasma_protocol::Error;
use plasma_protocol::hpr::command::id;
use plasma_protocol::hpr::{
    Acceptance, Class, ControlData, DiagnosticReply, ErrorCode, Frame, GasCode, GasConsole,
    GasFlows, GasPair, GasPressures, HprRating, LeakCheckMode, MfgData1, MfgData2, Reply, Request,
    StateCode, SystemId, TestMode, checksum, command_info,
};

use super::{Command, Fault, FrameReport, Kind};

/// Decodes one HPR frame into `report`; returns the request it is, for the next frame to be
/// matched against.
pub(super) fn decode(
    text: &str,
    previous: Option<&Request>,
    report: &mut FrameReport,
) -> Option<Request> {
    let bytes = text.as_bytes();
    let frame = match Frame::parse(bytes) {
        Ok(frame) => {
            let sum = checksum(frame.id, frame.data);
            report.checksum = Some(super::Checksum {
                found: sum,
                expected: sum,
            });
            frame
        }
        Err(Error::BadChecksum { expected, found }) => {
            report.checksum = Some(super::Checksum { found, expected });
            report.fail(format!(
                "checksum {found:02X} wrong, should be {expected:02X}"
            ));
            // Frame::parse checked the id digits and the checksum's hex before the sum.
            let inner = &bytes[1..bytes.len() - 1];
            let id = std::str::from_utf8(&inner[..3]).ok()?.parse().ok()?;
            report.note("the contents below are decoded despite the bad checksum");
            Frame::new(id, &inner[3..inner.len() - 2])
        }
        Err(e) => {
            report.fail(format!("not a valid HPR frame: {e}"));
            return None;
        }
    };
    report.command = Some(command(frame.id));
    if let Some(c) = report.command.as_ref().filter(|c| c.name.is_none()) {
        report.note(format!(
            "command {:03} is not in the manual's command table",
            c.id
        ));
    }
    if let Some(class @ ("dangerous" | "factory testing only")) =
        report.command.as_ref().and_then(|c| c.class)
    {
        report.note(format!(
            "{class} command: the bridge never sends it on its own"
        ));
    }

    if let Some(request) = previous {
        match Reply::parse_for(request, &frame) {
            Ok(reply) => {
                report.kind = Some(Kind::Reply);
                report.kind_reason = Some("answers the request before it".into());
                report.answers_request = Some(true);
                describe_reply(&reply, report);
                return None;
            }
            Err(Error::Mismatch) => {
                if request_of(&frame).is_err() && Reply::parse(&frame).is_ok() {
                    report.answers_request = Some(false);
                    let why = if !request.expects_reply() {
                        format!("command {:03} gets no reply", request.id())
                    } else {
                        format!("id {:03}, the request was {:03}", frame.id, request.id())
                    };
                    report.fail(format!(
                        "reply does not answer the request before it: {why}"
                    ));
                }
            }
            Err(e) => {
                report.kind = Some(Kind::Reply);
                report.answers_request = Some(true);
                report.fail(format!(
                    "reply to the request before it, but its data is malformed: {e}"
                ));
                return None;
            }
        }
    }

    match (request_of(&frame), Reply::parse(&frame)) {
        (Ok(request), reply) => {
            report.kind = Some(Kind::Request);
            report.kind_reason = Some(if reply.is_ok() {
                "taken as the request: its data fits the request and the reply format".to_owned()
            } else {
                "its data fits the request format, not the reply's".to_owned()
            });
            describe_request(&request, report);
            Some(request)
        }
        (Err(_), Ok(reply)) => {
            report.kind = Some(Kind::Reply);
            report.kind_reason = Some(match frame.id {
                id::BAD_CHECKSUM | id::UNKNOWN_COMMAND => {
                    "500/501 are only ever replies".to_owned()
                }
                _ => "its data fits the reply format, not the request's".to_owned(),
            });
            describe_reply(&reply, report);
            None
        }
        (Err(request), Err(reply)) => {
            untyped(&frame, request, reply, report);
            None
        }
    }
}

/// The request a frame is, with 500/501 never requests.
fn request_of(frame: &Frame<'_>) -> plasma_protocol::Result<Request> {
    match frame.id {
        id::BAD_CHECKSUM | id::UNKNOWN_COMMAND => Err(Error::Unsupported),
        _ => Request::parse(frame),
    }
}

fn command(id: u16) -> Command {
    let info = command_info(id);
    let name = match id {
        id::BAD_CHECKSUM => Some("BAD CHECKSUM (error reply)"),
        id::UNKNOWN_COMMAND => Some("UNKNOWN COMMAND (error reply)"),
        _ => info.map(|c| c.name),
    };
    Command {
        id,
        name,
        class: info.map(|c| match c.class {
            Class::Normal => "normal",
            Class::FactoryTestingOnly => "factory testing only",
            Class::Dangerous => "dangerous",
        }),
    }
}

/// A frame whose command has no typed format here (factory and diagnostic commands).
fn untyped(frame: &Frame<'_>, request: Error, reply: Error, report: &mut FrameReport) {
    let data = String::from_utf8_lossy(frame.data);
    if request == Error::Unsupported && reply == Error::Unsupported {
        report.kind_reason =
            Some("request and reply of this command are not typed; data shown raw".into());
        if frame.data.is_empty() {
            report.kind = Some(Kind::Request);
            report.kind_reason = Some("no data: a request (data format not typed here)".into());
        } else {
            report.field("data", data, None);
        }
    } else {
        report.field("data", data, None);
        report.fail(format!(
            "data fits neither the request ({request}) nor the reply ({reply}) format of command {:03}",
            frame.id
        ));
    }
}

fn describe_request(request: &Request, report: &mut FrameReport) {
    match *request {
        Request::SetNominalAmps { amps } => report.field("current setpoint", amps, Some("A")),
        Request::SetCornerCurrent { percent } => report.field("corner current", percent, Some("%")),
        Request::SetAllGasFlows(flows) => gas_flows(&flows, report),
        Request::SetAllGasFlowsMaxPro200(p) => {
            report.field("plasma pressure setpoint", p.plasma, Some("psi"));
            report.field("shield pressure setpoint", p.shield, Some("psi"));
        }
        Request::Wake { system_id } => report.field("system id", system_id, None),
        Request::SetAllParameters(p) => {
            report.field("current setpoint", p.amps, Some("A"));
            report.field("corner current", p.corner_percent, Some("%"));
            gases(&p.gases, report);
            gas_flows(&p.flows, report);
        }
        Request::SetAllParametersMaxPro200(p) => {
            report.field("current setpoint", p.amps, Some("A"));
            gases(&p.gases, report);
            report.field("plasma pressure setpoint", p.pressures.plasma, Some("psi"));
            report.field("shield pressure setpoint", p.pressures.shield, Some("psi"));
        }
        Request::SetInletGases(pair) => gases(&pair, report),
        Request::LeakCheckMode(mode) => report.field("mode", leak_check_name(mode), None),
        Request::SerialResponseDelay { enabled } => report.field(
            "response delay",
            if enabled { "on (about 1 ms)" } else { "off" },
            None,
        ),
        Request::SetProcess { amps, gases: pair } => {
            report.field("current setpoint", amps, Some("A"));
            gases(&pair, report);
        }
        Request::SetTestMode(mode) => report.field("test mode", test_mode_name(mode), None),
        Request::Sleep | Request::BroadcastMode => {
            report.note("no system replies to this command");
        }
        _ => {}
    }
}

fn describe_reply(reply: &Reply<'_>, report: &mut FrameReport) {
    match *reply {
        Reply::Hello(system) => report.field("system", system_name(&system), None),
        Reply::Version(v) => {
            report.field("power supply firmware", v.power_supply, None);
            if let Some(g) = v.gas_console {
                report.field("gas console firmware", g, None);
            }
        }
        Reply::State(state) => state_field("state", state, report),
        Reply::CurrentError(code) => error_code(code, report),
        Reply::Ack { result, .. } => report.field("result", acceptance(result), None),
        Reply::PlasmaAmps(a) => report.field("actual current", a, Some("A")),
        Reply::NominalAmps(a) => report.field("current setpoint now", a, Some("A")),
        Reply::CornerCurrentSet(p) => report.field("corner current set", p, Some("%")),
        Reply::ControlVoltage(tenths) => {
            report.field("control voltage", format!("{}.{}", tenths / 10, tenths % 10), Some("V"))
        }
        Reply::IoStatus(io) => {
            let mut on = Vec::new();
            for (port, bits) in ["A", "B", "C", "D", "E", "F"].iter().zip(io.ports) {
                report.field(format!("port {port} (bit 7..0)"), format!("{bits:08b}"), None);
                on.extend((0..8).rev().filter(|b| bits >> b & 1 == 1).map(|b| format!("P{port}{b}")));
            }
            report.field("bits on", if on.is_empty() { "none".to_owned() } else { on.join(" ") }, None);
            // HPR manual (002_72b43a5685974c77.txt) line 162: "Refer to IO listing for
            // description of each bit"; the manual has no such listing.
            report.note("the manual names no bit of ports A-F (its IO listing is not printed)");
        }
        Reply::Diagnostic(d) => diagnostic(&d, report),
        Reply::PsInfo(info) => {
            pressures(&info.pressures, report);
            report.field("current setpoint", info.current_setpoint, Some("A"));
            let name = info.state.hpr_name().map_or("not in the HPR state table".into(), |n| n.to_string());
            report.field("state", format!("{} {name}", info.state.0), None);
            error_code(info.error, report);
        }
        Reply::MaxProPsInfo(info) => {
            let name = info.state.maxpro200_name().map_or("not in the MaxPro200 state table".into(), |n| n.to_string());
            report.field("state", format!("{} {name}", info.state.0), None);
            error_code(info.error, report);
            report.field("plasma gas", gas_name(info.plasma_gas), None);
            report.field("plasma pressure setpoint", info.plasma_setpoint, Some("psi"));
            report.field("shield gas", gas_name(info.shield_gas), None);
            report.field("shield pressure setpoint", info.shield_setpoint, Some("psi"));
            report.field("current setpoint", info.current_setpoint, Some("A"));
            let mode = match info.display_mode {
                0 => "current",
                1 => "error/status",
                2 => "coolant flow",
                3 => "test mode",
                _ => "unknown",
            };
            report.field("display mode", format!("{} {mode}", info.display_mode), None);
            report.field("display", if info.locked { "locked" } else { "unlocked" }, None);
        }
        Reply::Wake(system_id) => report.field("woken system id", system_id, None),
        Reply::GasPressures(p) => pressures(&p, report),
        Reply::CornerCurrent(p) => report.field("corner current", p, Some("%")),
        Reply::InletGases(pair) => gases(&pair, report),
        Reply::GasFlows(flows) => gas_flows(&flows, report),
        Reply::LeakCheck(0) => report.field("result", "not accepted", None),
        Reply::LeakCheck(seconds) => report.field("test duration", seconds, Some("s")),
        Reply::GasSwitch(pair) => gases(&pair, report),
        Reply::TimerCounter(t) => {
            report.field("arc on time", t.arc_on_seconds, Some("s"));
            report.field("system on time", t.system_on_minutes, Some("min"));
            report.field("starts", t.starts, None);
            report.field("start errors", t.start_errors, None);
            report.field("rampdown errors", t.rampdown_errors, None);
            report.field("memory block writes", t.write_counter, None);
            report.field("memory block", t.memory_block, None);
        }
        Reply::ErrorLog(log) => {
            for code in log {
                error_code(code, report);
            }
            report.note("error log: most recent first");
        }
        Reply::ReadyForStart(ready) => report.field("ready for start", if ready { "yes" } else { "no" }, None),
        Reply::SetTestMode(v) => report.field("reply", v, None),
        Reply::TorchId(torch) => {
            report.field("torch", format!("{} {}", torch.0, torch.description().unwrap_or("not in the table")), None)
        }
        Reply::BadChecksum => report.note(
            "500: the supply received a command whose checksum was wrong and ignored it; \
             check that the sender sums the id and data characters, and the RS-422 wiring and noise",
        ),
        Reply::UnknownCommand => report.note(
            "501: the supply does not know the command id it received (or not on this system); \
             check the id and the supply's firmware revision",
        ),
    }
}

fn diagnostic(reply: &DiagnosticReply, report: &mut FrameReport) {
    match *reply {
        DiagnosticReply::ControlData(d) => control_data(&d, report),
        DiagnosticReply::MaxProControlData(d) => {
            mfg_data1(&d.first, report);
            mfg_data2(&d.second, report);
        }
        DiagnosticReply::MfgData1(d) => mfg_data1(&d, report),
        DiagnosticReply::MfgData2(d) => mfg_data2(&d, report),
        DiagnosticReply::GasConsoleInputs(inputs) => {
            let console = if inputs.count() == 7 {
                "manual"
            } else {
                "automatic"
            };
            report.note(format!(
                "{} inputs: named from the manual's {console} gas console list",
                inputs.count()
            ));
            for (index, name) in inputs.names().iter().enumerate() {
                let on = inputs.input(index).unwrap_or(false);
                report.field(*name, if on { "on" } else { "off" }, None);
            }
        }
        DiagnosticReply::CoolantPressure(counts) => {
            report.field("coolant pressure (raw A/D)", counts.0, Some("counts"));
            let tenths = counts.psi_tenths();
            report.field(
                "coolant pressure",
                format!("{}.{}", tenths / 10, tenths % 10),
                Some("psi"),
            );
            report.note(
                "psi on the line through the manual's 83 counts = 225 psi and 73 counts = 200 psi",
            );
        }
        DiagnosticReply::ControlData3(d) => {
            report.field(
                "chopper C temperature (raw A/D)",
                d.chopper_c_temp,
                Some("counts"),
            );
            report.field(
                "chopper D temperature (raw A/D)",
                d.chopper_d_temp,
                Some("counts"),
            );
            report.field("chopper C current", d.chopper_c_current, Some("A"));
            report.field("chopper D current", d.chopper_d_current, Some("A"));
        }
    }
}

/// `value` hundredths as `1.00`.
fn hundredths(value: u16) -> String {
    format!("{}.{:02}", value / 100, value % 100)
}

fn control_data(d: &ControlData, report: &mut FrameReport) {
    report.field(
        "chopper A temperature (raw A/D)",
        d.chopper_a_temp,
        Some("counts"),
    );
    report.field(
        "chopper B temperature (raw A/D)",
        d.chopper_b_temp,
        Some("counts"),
    );
    let volts = d.line_voltage;
    report.field(
        "line voltage",
        format!("{}.{}", volts / 10, volts % 10),
        Some("V"),
    );
    report.field("coolant flow", hundredths(d.coolant_flow), Some("gpm"));
    report.field(
        "coolant temperature (raw A/D)",
        d.coolant_temp,
        Some("counts"),
    );
    report.field(
        "transformer temperature (raw A/D)",
        d.transformer_temp,
        Some("counts"),
    );
    report.field("chopper A current", d.chopper_a_current, Some("A"));
    report.field("chopper B current", d.chopper_b_current, Some("A"));
    report.field("work lead current", d.work_lead_current, Some("A"));
    report.field("chopper A setpoint", d.chopper_a_setpoint, Some("A"));
    report.field("chopper B setpoint", d.chopper_b_setpoint, Some("A"));
    // 1070 = 100 %, shown in tenths of a percent.
    let percent = |pwm: u16| {
        let tenths = u32::from(pwm) * 1000 / 1070;
        format!("{} ({}.{} %)", pwm, tenths / 10, tenths % 10)
    };
    report.field("chopper A PWM", percent(d.pwm_chopper_a), None);
    report.field("chopper B PWM", percent(d.pwm_chopper_b), None);
}

fn mfg_data1(d: &MfgData1, report: &mut FrameReport) {
    report.field("plasma pressure", d.plasma_pressure, Some("psi"));
    report.field("shield pressure", d.shield_pressure, Some("psi"));
    report.field(
        "inlet pressure (psi in the 100 list, ADC counts in 141's)",
        d.inlet_pressure,
        None,
    );
    report.field("coolant temperature (ADC)", d.coolant_temp, Some("counts"));
    report.field("chopper temperature (ADC)", d.chopper_temp, Some("counts"));
    report.field("channel A current", d.channel_a_current, Some("A"));
}

fn mfg_data2(d: &MfgData2, report: &mut FrameReport) {
    report.field("channel B current", d.channel_b_current, Some("A"));
    report.field(
        "transformer temperature",
        d.transformer_temp,
        Some("counts"),
    );
    report.field(
        "inductor A temperature (ADC)",
        d.inductor_a_temp,
        Some("counts"),
    );
    report.field(
        "inductor B temperature (ADC)",
        d.inductor_b_temp,
        Some("counts"),
    );
    report.field("bus voltage", d.bus_voltage, Some("V"));
    report.field("coolant flow", hundredths(d.coolant_flow), Some("gpm"));
}

fn state_field(name: &str, state: StateCode, report: &mut FrameReport) {
    let hpr = state.hpr_name().map_or("-".into(), |n| n.to_string());
    let maxpro = state.maxpro200_name().map_or("-".into(), |n| n.to_string());
    report.field(
        name,
        format!("{} (HPR: {hpr}; MaxPro200: {maxpro})", state.0),
        None,
    );
}

fn error_code(code: ErrorCode, report: &mut FrameReport) {
    let text = match (code.name(), code.description()) {
        (Some(name), Some(description)) if !description.is_empty() => {
            Some(format!("{name}: {description}"))
        }
        (Some(name), _) => Some(name.to_string()),
        _ => None,
    };
    report.faults.push(Fault {
        address: None,
        code: format!("{:03}", code.0),
        raw: code.0,
        text,
        action_required: None,
        steps_required: None,
    });
}

fn gases(pair: &GasPair, report: &mut FrameReport) {
    report.field("plasma gas", gas_name(pair.plasma), None);
    report.field("shield gas", gas_name(pair.shield), None);
}

fn gas_name(gas: GasCode) -> String {
    format!(
        "{} {}",
        gas.0,
        gas.name().unwrap_or("(not in the gas table)")
    )
}

fn gas_flows(f: &GasFlows, report: &mut FrameReport) {
    report.field("plasma cutflow setpoint", f.plasma_cutflow, Some("psi"));
    report.field("plasma preflow setpoint", f.plasma_preflow, Some("psi"));
    report.field("shield cutflow setpoint", f.shield_cutflow, Some("psi"));
    report.field("shield preflow setpoint", f.shield_preflow, Some("psi"));
    report.field("N2 mix setpoint", f.n2_mix, Some("psi"));
    report.field("gas 2 mix setpoint", f.gas2_mix, Some("psi"));
}

fn pressures(p: &GasPressures, report: &mut FrameReport) {
    report.field("plasma cutflow pressure", p.plasma_cutflow, Some("psi"));
    report.field("plasma preflow pressure", p.plasma_preflow, Some("psi"));
    report.field("shield cutflow pressure", p.shield_cutflow, Some("psi"));
    report.field("shield preflow pressure", p.shield_preflow, Some("psi"));
    report.field("cut gas 1 pressure", p.cut_gas_1, Some("psi"));
    report.field("cut gas 2 pressure", p.cut_gas_2, Some("psi"));
    report.field("N2 mix inlet pressure", p.n2_mix_inlet, Some("psi"));
    report.field("gas 2 mix inlet pressure", p.gas2_mix_inlet, Some("psi"));
}

fn system_name(system: &SystemId) -> String {
    match system {
        SystemId::MaxPro200 => "MaxPro200".to_owned(),
        SystemId::Hpr {
            rating,
            xd,
            console,
        } => {
            let rating = match rating {
                HprRating::Hpr130 => "HPR130",
                HprRating::Hpr260 => "HPR260",
                HprRating::Hpr400 => "HPR400",
            };
            let xd = if *xd { "XD" } else { "" };
            let console = match console {
                Some(GasConsole::Manual) => " with manual gas console",
                Some(GasConsole::Auto) => " with automatic gas console",
                Some(GasConsole::AutoMix) => " with automatic mixing gas console",
                None => "",
            };
            format!("{rating}{xd}{console}")
        }
    }
}

fn acceptance(result: Acceptance) -> &'static str {
    match result {
        Acceptance::Accepted => "1 accepted",
        Acceptance::NotAccepted => "0 not accepted",
        Acceptance::Invalid => "2 data invalid, or the system is not in state 2 or 3",
    }
}

fn leak_check_name(mode: LeakCheckMode) -> &'static str {
    match mode {
        LeakCheckMode::Run => "0 back to normal operation",
        LeakCheckMode::InletLeak => "1 inlet leak check",
        LeakCheckMode::SystemLeak => "2 system leak check",
        LeakCheckMode::BurkertFlow => "3 Burkert valve flow check",
    }
}

fn test_mode_name(mode: TestMode) -> &'static str {
    match mode {
        TestMode::None => "0 no test (gases stop)",
        TestMode::TestGas => "1 test gas at set value",
        TestMode::ShowSoftwareRevision => "2 show software revision",
        TestMode::PlasmaLeakCheck => "3 plasma leak check",
        TestMode::TestGasFullPressure => "4 test gas at full pressure",
        TestMode::ShowTorchId => "5 show torch id",
        TestMode::InlineValveTest => "6 in-line valve test",
    }
}
