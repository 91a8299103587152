//! Every command on each family, end to end on the rig: the replies `docs/cnc-protocol.md`
//! shows, byte for byte.

extern crate std;

use crate::cnc::SimCommand;
use crate::io::{Inputs, Outputs};
use crate::settings::{Process, SaveError, Settings};
use crate::storage::Persistent as _;
use plasma_protocol::time::Duration;
use plasma_sim::clock::Accumulator;
use plasma_sim::hpr::HprCounters;

use crate::cnc::rig::*;
use crate::cnc::texts::{self, UnsupportedText, unsupported};
use crate::link::{CommandFailure, Family, ProcessFailure, TransactionError};
use plasma_protocol::cnc::{ErrorCode, ParseError};

// ---------------------------------------------------------------------------------------
// a session with a SYNC unit

#[test]
fn set_process_answers_once_after_the_read_back() {
    let mut rig = Rig::sync65(Settings::default());
    let reply = rig.cmd("SET PROCESS CUT 45 AUTO");
    assert_eq!(reply, "OK mode=CUT amps=45 psi=AUTO");
    // One write of all three remote registers: cut, 45 A x 64, automatic pressure.
    assert_eq!(rig.writes(), std::vec![(0x3080, std::vec![1, 2880, 0])]);
    assert_eq!(
        rig.bridge.settings().process,
        Some(Process {
            mode: plasma_protocol::cnc::Mode::Cut,
            amps: plasma_protocol::cnc::Amps::from_raw(2880),
            pressure: plasma_protocol::cnc::Pressure::Auto,
        })
    );
    rig.run(300);
    // Automatic pressure is asked by writing 0 (SYNC manual (000_dd931256418ae627.txt) line
    // 821); 0x3012 then reads the set point the unit chose (lines 1225-1226, "Reads ... the gas
    // pressure setting"), 72 psi here, never 0: STATUS says what was asked and what was chosen.
    assert_eq!(
        rig.cmd("STATUS"),
        "OK link=UP model=Powermax65 family=SYNC remote=ON mode=CUT amps=45 psi=AUTO \
         auto_psi=72 out_amps=0 out_psi=0 fault=none start=OFF motion=OFF arc_ok=OFF ready=ON"
    );
}

#[test]
fn status_is_one_line_with_the_io_snapshot() {
    let mut rig = Rig::sync65(Settings::default());
    let inputs = Inputs {
        torch_on: true,
        motion: true,
        ..Inputs::NONE
    };
    let outputs = Outputs {
        start: true,
        arc_ok: true,
        ready: true,
        ..Outputs::OFF
    };
    rig.bridge.set_io_snapshot(inputs, outputs);
    assert_eq!(
        rig.cmd("status"),
        "OK link=UP model=Powermax65 family=SYNC remote=OFF mode=CUT amps=45 psi=76 \
         out_amps=0 out_psi=0 fault=none start=ON motion=ON arc_ok=ON ready=ON"
    );
}

#[test]
fn status_shows_the_optional_hpr_signals_while_on() {
    let mut rig = Rig::sync65(Settings::default());
    let inputs = Inputs {
        system_error: true,
        ..Inputs::NONE
    };
    let outputs = Outputs {
        remote_power: true,
        ..Outputs::OFF
    };
    rig.bridge.set_io_snapshot(inputs, outputs);
    assert_eq!(
        rig.cmd("STATUS"),
        "OK link=UP model=Powermax65 family=SYNC remote=OFF mode=CUT amps=45 psi=76 \
         out_amps=0 out_psi=0 fault=none start=OFF motion=OFF arc_ok=OFF ready=OFF \
         system_error=ON power=ON"
    );
}

#[test]
fn power_drives_remote_power_with_or_without_a_unit() {
    // HPR manual (002_72b43a5685974c77.txt) line 54: Remote Power, an input of the unit,
    // "is used to turn the power on or off". A unit that is off has no link, so POWER needs
    // none; the level reaches the I/O task as its settings do.
    let mut rig = Rig::new(Settings::default(), None);
    assert!(!rig.bridge.io_config().remote_power, "off from reset");
    assert_eq!(rig.cmd("POWER ON"), "OK power=ON");
    assert!(rig.bridge.io_config().remote_power);
    assert_eq!(
        rig.bridge.take_io_config_change().map(|c| c.remote_power),
        Some(true)
    );
    assert_eq!(rig.cmd("power on"), "OK power=ON");
    assert_eq!(
        rig.bridge.take_io_config_change(),
        None,
        "no change, nothing sent"
    );
    assert_eq!(rig.cmd("POWER OFF"), "OK power=OFF");
    assert!(!rig.bridge.io_config().remote_power);
    assert_err(&rig.cmd("POWER"), "ERR SYNTAX *POWER*");
}

#[test]
fn limits_are_refused_with_the_permitted_range_before_anything_is_sent() {
    let mut rig = Rig::sync65(Settings::default());
    assert_err(&rig.cmd("SET AMPS 120"), "ERR RANGE *120*20..65*");
    assert_err(&rig.cmd("SET PROCESS CUT 45 80"), "ERR RANGE *80*58..78*");
    assert_err(&rig.cmd("SET MODE GOUGE"), "ERR RANGE *GOUGE*CUT*EXPANDED*");
    // Beyond every unit's bounds too, the unit's own range is what the operator needs.
    assert_eq!(
        rig.cmd("SET AMPS 500"),
        "ERR RANGE amps out of range 20..65 for this cartridge"
    );
    assert_eq!(
        rig.cmd("SET PROCESS CUT 401 AUTO"),
        "ERR RANGE amps out of range 20..65 for this cartridge"
    );
    assert_err(&rig.cmd("SET AMPS 45.01"), "ERR RANGE *1/64*");
    assert!(rig.writes().is_empty(), "nothing was sent");
    assert_eq!(
        rig.cmd("LIMITS"),
        "OK modes=CUT,EXPANDED amps=20..65 psi=58..78 scope=cartridge"
    );
}

#[test]
fn a_current_beyond_every_units_bounds_quotes_the_range_limits_reports() {
    let mut rig = Rig::hpr("hpr130");
    let limits = rig.cmd("LIMITS");
    let range = limits
        .split(' ')
        .find_map(|w| w.strip_prefix("amps="))
        .unwrap()
        .to_string();
    assert_eq!(range, "5..130");
    assert_eq!(
        rig.cmd("SET AMPS 500"),
        std::format!("ERR RANGE amps out of range {range} for this unit")
    );
    // No unit on the line: the protocol's bounds, all the bridge knows.
    let mut rig = Rig::new(Settings::default(), None);
    assert_eq!(
        rig.cmd("SET AMPS 500"),
        parse_err(ParseError::OutOfRange {
            what: "amps",
            range: "5..400"
        })
    );
}

#[test]
fn set_mode_amps_and_psi_combine_with_the_other_two_values() {
    let mut rig = Rig::sync65(Settings::default());
    // Nothing asked for yet: the unit's own settings (cut, 45 A, 76 psi) fill in.
    assert_eq!(rig.cmd("SET AMPS 40"), "OK mode=CUT amps=40 psi=76");
    assert_eq!(rig.cmd("SET PSI AUTO"), "OK mode=CUT amps=40 psi=AUTO");
    assert_eq!(
        rig.cmd("SET MODE EXPANDED"),
        "OK mode=EXPANDED amps=40 psi=AUTO"
    );
    assert_eq!(rig.cmd("SET PSI 70.5"), "OK mode=EXPANDED amps=40 psi=70.5");
    assert_eq!(
        rig.writes(),
        std::vec![
            (0x3080, std::vec![1, 40 * 64, 76 * 128]),
            (0x3080, std::vec![1, 40 * 64, 0]),
            (0x3080, std::vec![2, 40 * 64, 0]),
            (0x3080, std::vec![2, 40 * 64, 141 * 64]),
        ]
    );
}

#[test]
fn settings_that_do_not_read_back_are_an_error_with_the_read_back_values() {
    let mut rig = Rig::sync65(Settings::default());
    rig.ps().powermax().config_mut().remote_settings_apply = false;
    assert_err(
        &rig.cmd("SET PROCESS CUT 50 AUTO"),
        "ERR LINK *mode=CUT*amps=45*psi=76*",
    );
    assert_eq!(rig.bridge.settings().process, None);
    rig.unplug(true);
    assert_eq!(
        rig.cmd("SET PROCESS CUT 50 AUTO"),
        failure_line(&CommandFailure::Process(ProcessFailure::Transaction(
            TransactionError::Timeout
        )))
    );
}

/// ID names the torch and its lead, so a CNC loads the cut chart for them: a SYNC unit's from
/// 0x3000 (SYNC manual, 000_dd931256418ae627.txt, lines 618-620: 0x04 machine torch 15-25 ft,
/// 0x06 75 ft), a legacy unit's lead from its coils (Powermax65/85 protocol,
/// 001_0bf4bbd6620a48c8.txt, lines 258-271: 01 is 35-50 ft), which say nothing of the torch,
/// a MaxPro200's from 145; an HPR has no torch id.
#[test]
fn id_names_the_torch_and_its_lead() {
    let mut sync = Rig::new(Settings::default(), Some("sync85"));
    sync.ps().powermax().config_mut().torch_id = 0x06;
    sync.run(1500);
    let id = sync.cmd("ID");
    assert!(
        id.ends_with(" family=SYNC product=081335 torch=MACHINE lead_ft=75"),
        "{id}"
    );
    let mut legacy = Rig::new(Settings::default(), Some("pm65"));
    legacy.ps().powermax().config_mut().torch_id = 0x05;
    legacy.run(1500);
    let id = legacy.cmd("ID");
    assert!(
        id.ends_with(" family=LEGACY product=081223 torch=- lead_ft=50"),
        "{id}"
    );
    let mut hpr = Rig::hpr("hpr130");
    let id = hpr.cmd("ID");
    assert!(!id.contains("torch=") && !id.contains("lead_ft="), "{id}");
    // A MaxPro200's from 145 READ TORCH ID (HPR manual, 002_72b43a5685974c77.txt, line 290:
    // the simulator answers the sample, `>14500025C<`, id 2 "25 Ft mechanized torch"), with
    // its firmware from 001 VERSION (line 140).
    let mut maxpro = Rig::hpr("maxpro200");
    let id = maxpro.cmd("ID");
    assert!(
        id.ends_with(" family=MAXPRO200 torch=MACHINE lead_ft=25 firmware=A.0 gas_firmware=A.2"),
        "{id}"
    );
}

#[test]
fn every_command_on_a_sync_unit() {
    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(
        rig.cmd("HELP"),
        "OK commands=HELP,ID,STATUS,LIMITS,FAULT,FAULTLOG,COUNTERS,CARTRIDGE,SET,REMOTE,\
         GASTEST,POWER,RESTART,GASES,CORNER,RESET,CLEARWARN,EVENTS,CONFIG,HISTORY,CLOCK,CONSUMABLES,UNITS,RAW \
         set=MODE,AMPS,PSI,PROCESS,HPR_PROCESS,HPR_PARAMETERS,HPR_GAS_FLOWS remote=OFF \
         gastest=ON,OFF,PREFLOW,CUTFLOW,CHECK config=SAVE history=CLEAR consumables=NEW simulator_only=TORCH simulator=NO"
    );
    assert!(rig.cmd("help").starts_with("OK commands=HELP,ID,STATUS,"));
    assert_eq!(
        rig.cmd("ID"),
        "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=Powermax65 \
         family=SYNC product=081335 torch=MACHINE lead_ft=25"
    );
    assert_eq!(rig.cmd("ID now"), parse_err(ParseError::UnexpectedArgument));
    assert!(
        rig.cmd("STATUS")
            .starts_with("OK link=UP model=Powermax65 family=SYNC remote=OFF ")
    );
    assert_eq!(
        rig.cmd("LIMITS"),
        "OK modes=CUT,EXPANDED amps=20..65 psi=58..78 scope=cartridge"
    );
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    assert_eq!(rig.cmd("FAULTLOG"), "OK log=0-20-0,0-50-0");
    assert_eq!(
        rig.cmd("COUNTERS"),
        std::format!(
            "OK starts=1200 pilot_arc_s=300 transfers=1100 transfer_s=5000 link_ok={} \
             link_failed=0 retries=0 timeouts={} bad_checksums=0 link_downs=0",
            rig.bridge.diagnostics().transactions_ok,
            rig.bridge.diagnostics().timeouts
        )
    );
    assert_eq!(
        rig.cmd("CARTRIDGE"),
        "OK uid=E00401D0036FB25D part=428930 rev=1 nominal_amps=65 name=C_MECH starts=17 \
         pilot_arc_s=40 transfers=15 transfer_s=40"
    );
    assert_eq!(rig.cmd("GASTEST ON"), "OK gastest=ON");
    assert_eq!(rig.cmd("GASTEST OFF"), "OK gastest=OFF");
    assert_err(&rig.cmd("GASTEST MAYBE"), "ERR SYNTAX *");
    assert_err(&rig.cmd("RESTART"), "ERR STATE *0-50-0*");
    rig.fault(500);
    rig.run(300);
    assert_eq!(
        rig.cmd("FAULT"),
        "OK fault=0-50-0 action=required text=The cartridge is off, the torch was disconnected \
         when you set the plasma power supply to ON (I), or the torch was in the yellow lock (X) \
         position during a restart."
    );
    let restart = rig.cmd("RESTART");
    assert_eq!(restart, "OK restart=done quiet_ms=2000");
    assert_eq!(rig.cmd("SET AMPS 40").split(' ').next(), Some("ERR"));
    rig.run(2500);
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    assert_eq!(
        rig.cmd("GASES O2 AIR"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::GASES, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("CORNER 80"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::CORNER, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("RESET"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::RESET, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("CLEARWARN"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::CLEAR_WARN, Family::PowermaxSync)
        )
    );
    assert_err(
        &rig.cmd("SET PROCESS GOUGE 45 AUTO"),
        "ERR RANGE *GOUGE*CUT*EXPANDED*",
    );
    assert_err(
        &rig.cmd("SET PROCESS CUT 120 AUTO"),
        "ERR RANGE *120*20..65*",
    );
    assert_err(&rig.cmd("SET PROCESS CUT 45 80"), "ERR RANGE *80*58..78*");
    assert_eq!(
        rig.cmd("SET PROCESS CUT 500 AUTO"),
        "ERR RANGE amps out of range 20..65 for this cartridge"
    );
    assert_err(&rig.cmd("SET PROCESS CUT 45.01 AUTO"), "ERR RANGE *1/64*");
    assert_err(
        &rig.cmd("SET PROCESS FLY 45 AUTO"),
        "ERR SYNTAX *CUT|CPA|EXPANDED|GOUGE*",
    );
    assert_err(&rig.cmd("SET PROCESS CUT 45"), "ERR SYNTAX missing *");
    assert_eq!(
        rig.cmd("SET PROCESS CUT 45 AUTO"),
        "OK mode=CUT amps=45 psi=AUTO"
    );
    assert_eq!(rig.cmd("SET AMPS 40"), "OK mode=CUT amps=40 psi=AUTO");
    assert_err(&rig.cmd("SET AMPS 66"), "ERR RANGE *66*20..65*");
    assert_err(&rig.cmd("SET AMPS"), "ERR SYNTAX missing *");
    assert_err(&rig.cmd("SET AMPS forty"), "ERR SYNTAX *");
    assert_eq!(rig.cmd("SET PSI 70.5"), "OK mode=CUT amps=40 psi=70.5");
    assert_eq!(rig.cmd("SET PSI AUTO"), "OK mode=CUT amps=40 psi=AUTO");
    assert_err(&rig.cmd("SET PSI 10"), "ERR RANGE *10*58..78*");
    assert_eq!(
        rig.cmd("SET MODE EXPANDED"),
        "OK mode=EXPANDED amps=40 psi=AUTO"
    );
    assert_err(
        &rig.cmd("SET MODE GOUGE"),
        "ERR RANGE mode GOUGE not permitted *",
    );
    assert_err(&rig.cmd("SET MODE"), "ERR SYNTAX missing *");
    assert_err(&rig.cmd("SET"), "ERR SYNTAX missing *");
    assert_eq!(rig.cmd("EVENTS ON"), "OK events=ON");
    assert_eq!(rig.cmd("EVENTS OFF"), "OK events=OFF");
    assert_err(&rig.cmd("EVENTS MAYBE"), "ERR SYNTAX *EVENTS*ON|OFF*");
    assert_eq!(rig.cmd("REMOTE OFF"), "OK remote=OFF");
    assert_eq!(rig.writes().last(), Some(&(0x3080, std::vec![0, 0, 0])));
    assert_eq!(rig.bridge.settings().process, None);
    assert_eq!(
        rig.cmd("TORCH ON"),
        err(ErrorCode::Unsupported, texts::TORCH_SIMULATOR_ONLY)
    );
    assert_err(&rig.cmd("TORCH MAYBE"), "ERR SYNTAX *");
    assert_err(&rig.cmd("REMOTE ON"), "ERR SYNTAX *REMOTE*OFF*");
    assert_eq!(rig.cmd("FLY"), parse_err(ParseError::UnknownCommand));
    // The failing commands sent nothing: the unit is as REMOTE OFF left it.
    assert_eq!(rig.writes().last(), Some(&(0x3080, std::vec![0, 0, 0])));
    assert_eq!(rig.ps().powermax().force_registers().current, 0);
}

/// What RAW answers: the unit's reply, or why the allow-list refused the frame. That refused
/// frames never reach the unit or the wire, on each family, is the harness's scenario
/// (`raw_refuses_*` in host-tests/tests/cnc_scenarios.rs).
#[test]
fn raw_replies_carry_the_units_answer_or_say_why_the_frame_is_refused() {
    let mut rig = Rig::sync65(Settings::default());
    // Read the active fault register 0x301A.
    let read = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    let read = core::str::from_utf8(&read).unwrap().trim_end();
    assert_eq!(read, ":0104301A0001B0");
    assert_eq!(
        rig.cmd(&std::format!("RAW {read}")),
        "OK reply=:0104020000F9"
    );
    // A write to a register not documented as writable.
    let write = mb(&[0x06, 0x30, 0x10, 0x00, 0x01]);
    let write = core::str::from_utf8(&write).unwrap().trim_end();
    assert_err(&rig.cmd(&std::format!("RAW {write}")), "ERR REFUSED *3010*");
    assert_err(&rig.cmd("RAW :0104301A0001B1"), "ERR REFUSED *B0*B1*");
    assert_eq!(
        rig.cmd("RAW"),
        parse_err(ParseError::MissingArgument { what: "frame" })
    );
    assert!(rig.writes().is_empty());
}

// ---------------------------------------------------------------------------------------
// HPR and MaxPro200

#[test]
fn every_command_on_an_hpr() {
    let mut rig = Rig::hpr("hpr130");
    assert_eq!(
        rig.cmd("ID"),
        "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=HPR130 family=HPR \
         firmware=A.0 gas_firmware=A.2"
    );
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    assert_eq!(rig.cmd("FAULTLOG"), "OK log=none");
    assert_eq!(
        rig.cmd("STATUS"),
        "OK link=UP model=HPR130 family=HPR remote=OFF mode=- amps=130 psi=- out_amps=0 \
         out_psi=55 fault=none start=OFF motion=OFF arc_ok=OFF ready=ON state=3 \
         state_name=IDLE2 console=AUTO plasma_cutflow_psi=55 plasma_preflow_psi=45 \
         shield_cutflow_psi=35 shield_preflow_psi=25 plasma=O2 shield=AIR"
    );
    assert_eq!(
        rig.cmd("LIMITS"),
        "OK amps=5..130 corner=50..100 console=AUTO"
    );
    assert_eq!(rig.cmd("SET AMPS 100"), "OK amps=100");
    assert_eq!(rig.ps().hpr().nominal_amps(), 100);
    let requests = rig.hpr_commands();
    let set = requests.iter().position(|&id| id == 58).unwrap();
    assert_eq!(requests[set - 1], 4, "REMOTE_MODE before the first setting");
    assert_err(&rig.cmd("SET AMPS 131"), "ERR RANGE *131*5..130*");
    assert_err(&rig.cmd("SET AMPS 45.5"), "ERR RANGE *45.5*");
    assert_eq!(
        rig.cmd("SET PROCESS CUT 45 AUTO"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::SET_PROCESS, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("SET MODE CUT"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::SET_MODE, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("SET PSI 60"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::SET_PSI, Family::Hpr)
        )
    );
    assert_eq!(rig.cmd("GASES O2 AIR"), "OK plasma=O2 shield=AIR");
    assert_eq!(rig.cmd("CORNER 80"), "OK corner=80");
    assert_err(&rig.cmd("CORNER 40"), "ERR RANGE *50..100*");
    assert_err(&rig.cmd("CORNER 120"), "ERR RANGE *50..100*");
    assert_err(&rig.cmd("CORNER"), "ERR SYNTAX missing *");
    assert_err(&rig.cmd("GASES O2"), "ERR SYNTAX missing *");
    assert_err(
        &rig.cmd("GASES XE AIR"),
        "ERR SYNTAX *O2|CH4|H35|H5|AIR|N2|AR|N95|F5*",
    );
    assert_eq!(
        rig.cmd("SET HPR_PROCESS 100 O2 AIR"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::HPR_PROCESS, Family::Hpr)
        )
    );
    assert_eq!(rig.cmd("CLEARWARN"), "OK clearwarn=done");
    assert_eq!(rig.cmd("GASTEST ON"), "OK gastest=ON");
    assert_eq!(rig.cmd("GASTEST OFF"), "OK gastest=OFF");
    assert_eq!(rig.cmd("GASTEST CUTFLOW ON"), "OK gastest=ON flow=CUTFLOW");
    assert_eq!(
        rig.cmd("GASTEST CUTFLOW OFF"),
        "OK gastest=OFF flow=CUTFLOW"
    );
    let tests: std::vec::Vec<u16> = rig
        .hpr_commands()
        .into_iter()
        .filter(|id| (64..=67).contains(id))
        .collect();
    assert_eq!(tests, [64, 65, 66, 67]);
    assert_eq!(rig.cmd("GASTEST PREFLOW ON"), "OK gastest=ON flow=PREFLOW");
    assert_eq!(
        rig.cmd("GASTEST PREFLOW OFF"),
        "OK gastest=OFF flow=PREFLOW"
    );
    assert_eq!(
        rig.cmd("GASTEST CUTFLOW"),
        "ERR SYNTAX missing GASTEST argument"
    );
    // The next poll sees the unit back in IDLE2.
    rig.run(300);
    assert_err(&rig.cmd("RESET"), "ERR STATE *3*IDLE2*000*NO*ERROR*");
    // Two errors come and go before the bridge polls: only the log keeps them.
    rig.fault(20);
    rig.fault(44);
    rig.fault(0);
    assert_eq!(rig.cmd("FAULTLOG"), "OK log=044,020");
    rig.ps().hpr().set_counters(HprCounters {
        arc_on: Accumulator::from_secs(3600),
        system_on: Accumulator::from_secs(900 * 60),
        starts: 420,
        start_errors: 3,
        rampdown_errors: 1,
    });
    assert!(rig.cmd("COUNTERS").starts_with(
        "OK arc_s=3600 system_min=900 starts=420 start_errors=3 rampdown_errors=1 link_ok="
    ));
    assert_eq!(
        rig.cmd("CARTRIDGE"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::CARTRIDGE, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("RESTART"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::RESTART, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("REMOTE OFF"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::REMOTE_OFF, Family::Hpr)
        )
    );
    assert_eq!(rig.cmd("RAW >00292<"), "OK reply=>002000355<");
    assert_err(&rig.cmd("RAW >12093<"), "ERR REFUSED *120*");
    assert_err(
        &rig.cmd("RAW >00293<"),
        "ERR REFUSED raw frame rejected: bad checksum*",
    );
    rig.fault(44);
    rig.run(300);
    assert_eq!(
        rig.cmd("FAULT"),
        "OK fault=044 action=required text=LOW PLASMA GAS PRESSURE"
    );
}

/// `SET HPR_PARAMETERS` (095) and `SET HPR_GAS_FLOWS` (078) in each family's form, with the
/// HPR manual's sample values (002_72b43a5685974c77.txt lines 165 and 180), answered once the
/// unit read them back; the other family's form and a Powermax are refused.
#[test]
fn hpr_parameters_and_gas_flows_in_each_familys_form() {
    let mut rig = Rig::hpr("hpr130");
    assert_eq!(
        rig.cmd("SET HPR_PARAMETERS 100 75 O2 N2 55 45 35 25 0 0"),
        "OK amps=100 corner=75 plasma=O2 shield=N2 plasma_cutflow_psi=55 plasma_preflow_psi=45 \
         shield_cutflow_psi=35 shield_preflow_psi=25 n2_mix_psi=0 gas2_mix_psi=0"
    );
    assert_eq!(rig.ps().hpr().nominal_amps(), 100);
    assert_eq!(
        rig.cmd("SET HPR_GAS_FLOWS 55 45 35 25 50 50"),
        "OK plasma_cutflow_psi=55 plasma_preflow_psi=45 shield_cutflow_psi=35 \
         shield_preflow_psi=25 n2_mix_psi=50 gas2_mix_psi=50"
    );
    let sent: std::vec::Vec<u16> = rig
        .hpr_commands()
        .into_iter()
        .filter(|id| [78, 95, 97, 98, 99].contains(id))
        .collect();
    assert_eq!(&sent[sent.len() - 6..], [95, 99, 97, 98, 78, 99]);
    assert_err(
        &rig.cmd("SET HPR_PARAMETERS 131 75 O2 N2 55 45 35 25 0 0"),
        "ERR RANGE *131*130*",
    );
    assert_err(
        &rig.cmd("SET HPR_PARAMETERS 100.5 75 O2 N2 55 45 35 25 0 0"),
        "ERR RANGE *100.5*whole amps",
    );
    assert_eq!(
        rig.cmd("SET HPR_GAS_FLOWS 50 58"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::HPR_GAS_FLOWS_FORM, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("SET HPR_PARAMETERS 150 O2 AIR 50 58"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::HPR_PARAMETERS_FORM, Family::Hpr)
        )
    );

    let mut rig = Rig::hpr("maxpro200");
    assert_eq!(
        rig.cmd("SET HPR_PARAMETERS 150 O2 AIR 60 40"),
        "OK amps=150 plasma=O2 shield=AIR plasma_psi=60 shield_psi=40"
    );
    assert_eq!(
        rig.cmd("SET HPR_GAS_FLOWS 50 58"),
        "OK plasma_psi=50 shield_psi=58"
    );
    assert_eq!(rig.ps().hpr().nominal_amps(), 150);
    assert_eq!(
        rig.cmd("SET HPR_GAS_FLOWS 55 45 35 25 50 50"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::HPR_GAS_FLOWS_FORM, Family::MaxPro200)
        )
    );

    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(
        rig.cmd("SET HPR_PARAMETERS 150 O2 AIR 50 58"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::HPR_PARAMETERS, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("SET HPR_GAS_FLOWS 50 58"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::HPR_GAS_FLOWS, Family::PowermaxSync)
        )
    );
}

// ---------------------------------------------------------------------------------------
// CONFIG

/// The CONFIG text interface and the save: every key's reply, the errors, which change
/// redetects or reaches the I/O, SAVE's queueing, and the record decoding to the same settings.
#[test]
fn config_get_set_and_save_round_trip_through_the_settings_record() {
    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(
        rig.cmd("CONFIG"),
        "OK protocol=AUTO address=1 parity=EVEN stop_bits=1 timeout_ms=100 retries=2 \
         poll_ms=100 reapply_after_power_cycle=OFF interlock_fault=ON interlock_link=ON \
         interlock_ready=ON \
         arc_ok_debounce_ms=2 transfer_timeout_ms=3000 transfer_timeout_drops_start=ON \
         events=OFF hpr_id=0 phoenix_format=113 torch_on_active=LOW torch_on_debounce_ms=1 \
         hold_active=LOW \
         hold_debounce_ms=5 pierce_complete_active=LOW pierce_complete_debounce_ms=5 \
         corner_current_active=LOW corner_current_debounce_ms=5 motion_active=LOW \
         motion_debounce_ms=0 not_ready_active=LOW not_ready_debounce_ms=5 \
         rampdown_error_active=LOW rampdown_error_debounce_ms=5 system_error_active=LOW system_error_debounce_ms=5 ps_hold_active=HIGH \
         fault_active=HIGH cnc_address=1 cnc_baud=115200 cnc_parity=NONE \
         cnc_stop_bits=1 cnc_data_bits=8 consumable_start_limit=OFF consumable_arc_limit_s=OFF \
         units=AUTO"
    );
    assert_eq!(rig.cmd("CONFIG timeout_ms"), "OK timeout_ms=100");
    assert_err(&rig.cmd("CONFIG timeout_ms 30"), "ERR RANGE *30*60..1000*");
    assert_err(&rig.cmd("CONFIG parity mark"), "ERR SYNTAX *NONE|EVEN|ODD*");
    assert_err(&rig.cmd("CONFIG baud 9600"), "ERR SYNTAX *SAVE*CONFIG*");
    assert_eq!(
        rig.cmd("CONFIG timeout_ms 80"),
        "OK timeout_ms=80 link=redetecting"
    );
    assert_eq!(
        rig.bridge.link().config().response_timeout,
        Duration::from_millis(80)
    );
    assert!(!rig.bridge.status().link_up, "the link detects again");
    assert_eq!(rig.bridge.take_io_config_change(), None);
    assert_eq!(
        rig.cmd("CONFIG arc_ok_debounce_ms 5"),
        "OK arc_ok_debounce_ms=5"
    );
    assert_eq!(
        rig.bridge
            .take_io_config_change()
            .map(|c| c.arc_ok_debounce),
        Some(Duration::from_millis(5))
    );
    assert_eq!(rig.cmd("CONFIG events on"), "OK events=ON");
    // The re-apply policy is a link key that needs no detection.
    rig.run(2000);
    assert!(rig.bridge.status().link_up);
    assert_eq!(
        rig.cmd("CONFIG reapply_after_power_cycle on"),
        "OK reapply_after_power_cycle=ON"
    );
    assert!(rig.bridge.status().link_up, "no detection for the policy");
    assert!(rig.bridge.link().config().reapply_after_power_cycle);
    // SAVE waits for the store; a line sent meanwhile waits behind it.
    rig.save_result = None;
    let tokens = rig.send_bytes(b"CONFIG SAVE\r\nCONFIG hpr_id\r\n", 0);
    assert!(tokens.iter().all(|t| !is_reply(t)), "{tokens:?}");
    let Some(crate::bridge::SaveRequest::Settings(settings)) = rig.bridge.take_save_request()
    else {
        panic!("a settings save")
    };
    assert_eq!(rig.bridge.take_save_request(), None, "once");
    let mut record = [0u8; 64];
    let len = settings.encode(&mut record);
    let restored = Settings::decode(&record[..len]).unwrap();
    assert_eq!(restored, *rig.bridge.settings());
    rig.bridge.save_finished(rig.now, Ok(()));
    rig.collect();
    let n = rig.received.len();
    assert_eq!(rig.received[n - 2..], ["OK config=saved", "OK hpr_id=0"]);
    // A failed store.
    rig.save_result = Some(Err(SaveError::Flash));
    assert_err(&rig.cmd("CONFIG SAVE"), "ERR STORAGE *");
    // That a power cycle brings these keys back is the harness's scenario
    // (`config_save_and_a_power_cycle_keep_the_config_and_reapply_the_process`).
}

// ---------------------------------------------------------------------------------------
// simulator commands

#[test]
fn torch_is_handed_to_the_simulator_driver() {
    let mut rig = Rig::new(Settings::default(), None);
    assert_eq!(
        rig.cmd("TORCH ON"),
        err(ErrorCode::Unsupported, texts::TORCH_SIMULATOR_ONLY)
    );
    assert_eq!(rig.bridge.poll_sim_command(), None);
    rig.bridge.enable_sim_commands();
    assert_eq!(rig.cmd("TORCH ON"), "OK torch=ON");
    assert_eq!(rig.cmd("torch off"), "OK torch=OFF");
    assert_eq!(
        rig.bridge.poll_sim_command(),
        Some(SimCommand::Torch { unit: 0, on: true })
    );
    assert_eq!(
        rig.bridge.poll_sim_command(),
        Some(SimCommand::Torch { unit: 0, on: false })
    );
    assert_eq!(rig.bridge.poll_sim_command(), None);
    assert!(
        rig.cmd("HELP")
            .ends_with("simulator_only=TORCH simulator=YES")
    );
}

// ---------------------------------------------------------------------------------------
// the remaining replies docs/cnc-protocol.md shows

#[test]
fn documented_replies_not_covered_above() {
    let mut rig = Rig::sync65(Settings::default());
    assert_err(
        &rig.cmd("SET MODE PLASMA"),
        "ERR SYNTAX *CUT|CPA|EXPANDED|GOUGE*",
    );
    assert_err(
        &rig.cmd("GASES XENON AIR"),
        "ERR SYNTAX *O2|CH4|H35|H5|AIR|N2|AR|N95|F5*",
    );
    assert_err(&rig.cmd("EVENTS MAYBE"), "ERR SYNTAX *EVENTS*ON|OFF*");
    rig.fault(500);
    rig.run(300);
    assert_eq!(rig.cmd("RESTART"), "OK restart=done quiet_ms=2000");
    assert!(
        rig.cmd("SET AMPS 40")
            .starts_with("ERR BUSY the unit restarts: quiet for another "),
    );

    let mut rig = Rig::hpr("hpr400xd");
    // RESET only in a shutdown error (state 14, error above 79).
    rig.fault(80);
    rig.run(300);
    assert_eq!(rig.cmd("RESET"), "OK reset=done");
    assert!(rig.cmd("STATUS").contains(" model=HPR400XD family=HPR "));
}
