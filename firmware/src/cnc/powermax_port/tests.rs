//! The CNC port as a Powermax, byte for byte, against the simulated units behind the bridge.

extern crate std;

use std::string::String;
use std::vec::Vec;

use proptest::prelude::*;

use super::SETTLE;
use crate::cnc::rig::{Rig, mb};
use crate::settings::Settings;
use plasma_sim::powermax::DeviceIdSupport;

/// Send one Modbus frame; the reply line (without CR LF), or `None` when none came.
fn ask(rig: &mut Rig, frame: &[u8]) -> Option<String> {
    let start = rig.received.len();
    rig.bridge.handle_cnc_rx(rig.now, frame);
    rig.collect();
    let replies: Vec<String> = rig.received[start..]
        .iter()
        .filter(|t| t.starts_with(':'))
        .cloned()
        .collect();
    assert!(replies.len() <= 1, "{replies:?}");
    replies.into_iter().next()
}

fn line(frame: Vec<u8>) -> String {
    String::from_utf8(frame)
        .unwrap()
        .trim_end_matches("\r\n")
        .into()
}

fn read(rig: &mut Rig, register: u16) -> u16 {
    let [hi, lo] = register.to_be_bytes();
    let reply = ask(rig, &mb(&[0x04, hi, lo, 0x00, 0x01])).expect("a reply");
    assert_eq!(&reply[..7], ":010402", "{reply}");
    u16::from_str_radix(&reply[7..11], 16).unwrap()
}

fn write(rig: &mut Rig, register: u16, value: u16) -> Option<String> {
    let [hi, lo] = register.to_be_bytes();
    let [vh, vl] = value.to_be_bytes();
    ask(rig, &mb(&[0x06, hi, lo, vh, vl]))
}

/// pmx485's connect sequence: mode, current x 64, pressure x 128, then a read of the limits.
fn connect(rig: &mut Rig, mode: u16, amps: u16, psi: u16) -> u16 {
    for (register, value) in [(0x2093, mode), (0x2094, amps * 64), (0x2096, psi * 128)] {
        let frame = {
            let [hi, lo] = u16::to_be_bytes(register);
            let [vh, vl] = value.to_be_bytes();
            mb(&[0x06, hi, lo, vh, vl])
        };
        let echo = ask(rig, &frame).expect("echoed at once");
        assert_eq!(echo, line(frame), "a write is answered with its exact echo");
    }
    read(rig, 0x2099)
}

#[test]
fn a_read_is_answered_at_once_byte_for_byte() {
    let mut rig = Rig::sync65(Settings::default());
    // 0x2099 current min: 20 A x 64 = 0x0500.
    let reply = ask(&mut rig, b":01042099000141\r\n");
    assert_eq!(reply.as_deref(), Some(":0104020500F4"));
    // Function 03 reads the same registers.
    let reply = ask(&mut rig, &mb(&[0x03, 0x20, 0x9A, 0x00, 0x01])).unwrap();
    assert_eq!(reply, line(mb(&[0x03, 0x02, 0x10, 0x40])), "65 A x 64");
}

#[test]
fn the_legacy_block_reads_whole_with_its_gaps_as_zero() {
    let mut rig = Rig::sync65(Settings::default());
    let reply = ask(&mut rig, &mb(&[0x04, 0x20, 0x93, 0x00, 0x0D])).unwrap();
    // 13 registers: 2 + 13 * 2 bytes.
    assert_eq!(&reply[..7], ":01041A");
    let words: Vec<u16> = (0..13)
        .map(|i| u16::from_str_radix(&reply[7 + 4 * i..11 + 4 * i], 16).unwrap())
        .collect();
    assert_eq!(words[2], 0, "0x2095 is a gap");
    assert_eq!(words[6], 20 * 64, "0x2099");
    assert_eq!(words[7], 65 * 64, "0x209A");
}

#[test]
fn pmx485s_three_writes_become_one_sync_settings_write() {
    let mut rig = Rig::sync65(Settings::default());
    write(&mut rig, 0x2093, 1).unwrap();
    write(&mut rig, 0x2094, 45 * 64).unwrap();
    rig.run(50);
    assert!(
        rig.writes().is_empty(),
        "nothing before the group is complete"
    );
    assert_eq!(connect(&mut rig, 1, 45, 0), 20 * 64);
    rig.run(300);
    assert_eq!(rig.writes(), std::vec![(0x3080, std::vec![1, 2880, 0])]);
    assert!(rig.bridge.status().remote);
    assert_eq!(read(&mut rig, 0x2094), 2880);
    assert_eq!(read(&mut rig, 0x2098), 0);
    // The process the unit confirmed is the one the settings keep (CONFIG SAVE stores it).
    assert!(rig.bridge.settings().process.is_some());
    // The text protocol sees it and still works on the same port.
    let status = rig.cmd("STATUS");
    assert!(status.contains(" amps=45 "), "{status}");
}

#[test]
fn a_group_with_nothing_after_it_completes_after_the_settle_time() {
    let mut rig = Rig::sync65(Settings::default());
    write(&mut rig, 0x3081, 40 * 64).unwrap();
    rig.run(SETTLE.as_millis() - 10);
    assert!(rig.writes().is_empty());
    rig.run(300);
    // Mode and pressure came from the unit's panel: cut, 76 psi.
    assert_eq!(
        rig.writes(),
        std::vec![(0x3080, std::vec![1, 2560, 76 * 128])]
    );
}

#[test]
fn one_0x10_write_is_a_whole_group() {
    let mut rig = Rig::sync65(Settings::default());
    let reply = ask(
        &mut rig,
        &mb(&[0x10, 0x30, 0x80, 0x00, 0x03, 0x06, 0, 1, 0x0A, 0x00, 0, 0]),
    );
    assert_eq!(reply, Some(line(mb(&[0x10, 0x30, 0x80, 0x00, 0x03]))));
    rig.run(300);
    assert_eq!(rig.writes(), std::vec![(0x3080, std::vec![1, 40 * 64, 0])]);
}

#[test]
fn a_current_the_unit_refuses_reads_as_0_11_1_and_is_an_event() {
    let settings = Settings {
        events: true,
        ..Settings::default()
    };
    let mut rig = Rig::sync65(settings);
    connect(&mut rig, 1, 100, 0);
    rig.run(300);
    assert!(rig.writes().is_empty(), "not sent");
    assert_eq!(read(&mut rig, 0x2098), 111, "0-11-1");
    // The text protocol shows it as the unit would: FAULT and STATUS.
    // SYNC guide (000_dd931256418ae627.txt) line 943: 0-11-1 "No, but recommended".
    let fault = rig.cmd("FAULT");
    assert!(
        fault.starts_with("OK fault=0-11-1 action=recommended text="),
        "{fault}"
    );
    assert!(rig.cmd("STATUS").contains(" fault=0-11-1 "));
    assert!(
        rig.received
            .iter()
            .any(|t| t == "!SETTINGS failed reason=refused fault=0-11-1"),
        "{:?}",
        rig.received
    );
    // A setting the unit takes clears it.
    connect(&mut rig, 1, 45, 0);
    rig.run(300);
    assert_eq!(read(&mut rig, 0x2098), 0);
}

#[test]
fn zeros_in_all_three_return_the_unit_to_local_control() {
    let mut rig = Rig::sync65(Settings::default());
    connect(&mut rig, 1, 45, 0);
    rig.run(300);
    assert!(rig.bridge.status().remote);
    // pmx485 on disable: three zeros, then it closes the port.
    for register in [0x2093, 0x2094, 0x2096] {
        write(&mut rig, register, 0).unwrap();
    }
    rig.run(500);
    assert_eq!(rig.writes().last(), Some(&(0x3080, std::vec![0, 0, 0])));
    assert!(!rig.bridge.status().remote);
    assert_eq!(rig.bridge.settings().process, None);
}

#[test]
fn an_hpr_takes_the_current_only_and_refuses_another_mode() {
    let mut rig = Rig::hpr("hpr260");
    assert_eq!(read(&mut rig, 0x209A), 260 * 64, "limits from the rating");
    assert_eq!(read(&mut rig, 0x2099), 5 * 64);
    assert_eq!(read(&mut rig, 0x209D), 0, "pressure automatic");
    let before = rig.hpr_commands().len();
    connect(&mut rig, 1, 45, 0);
    rig.run(500);
    let sent = rig.hpr_commands()[before..].to_vec();
    assert!(sent.contains(&58), "058 set current: {sent:?}");
    assert_eq!(rig.bridge.status().hpr.nominal_amps, Some(45));
    connect(&mut rig, 3, 45, 0);
    rig.run(300);
    assert_eq!(read(&mut rig, 0x2098), 110, "gouge: 0-11-0");
    connect(&mut rig, 1, 45, 80);
    rig.run(300);
    assert_eq!(read(&mut rig, 0x2098), 112, "a pressure: 0-11-2");
}

#[test]
fn an_hpr_error_never_reads_as_no_fault() {
    let mut rig = Rig::hpr("hpr260");
    rig.fault(44);
    rig.run(500);
    assert_ne!(read(&mut rig, 0x2098), 0);
}

#[test]
fn the_link_lost_means_no_reply() {
    let mut rig = Rig::sync65(Settings::default());
    assert!(ask(&mut rig, &mb(&[0x04, 0x20, 0x98, 0x00, 0x01])).is_some());
    rig.unplug(true);
    rig.run(5000);
    assert!(!rig.bridge.status().link_up);
    assert_eq!(ask(&mut rig, &mb(&[0x04, 0x20, 0x98, 0x00, 0x01])), None);
    assert_eq!(write(&mut rig, 0x2093, 1), None);
    // The text protocol answers and says why.
    assert!(rig.cmd("ID").contains(" link=DOWN "));
}

#[test]
fn other_nodes_and_broadcasts_get_no_reply() {
    let mut rig = Rig::sync65(Settings::default());
    let mut out = [0u8; 64];
    let n = plasma_protocol::modbus_ascii::encode(2, &[0x04, 0x20, 0x98, 0x00, 0x01], &mut out)
        .unwrap();
    assert_eq!(ask(&mut rig, &out[..n]), None, "node 2");
    let n = plasma_protocol::modbus_ascii::encode(
        0,
        &[0x10, 0x30, 0x80, 0x00, 0x03, 0x06, 0, 1, 0x0A, 0x00, 0, 0],
        &mut out,
    )
    .unwrap();
    assert_eq!(ask(&mut rig, &out[..n]), None, "broadcast");
    rig.run(300);
    assert_eq!(rig.writes(), std::vec![(0x3080, std::vec![1, 40 * 64, 0])]);
    // cnc_address moves the node.
    assert!(rig.cmd("CONFIG cnc_address 2").starts_with("OK"));
    let n = plasma_protocol::modbus_ascii::encode(2, &[0x04, 0x20, 0x98, 0x00, 0x01], &mut out)
        .unwrap();
    assert!(ask(&mut rig, &out[..n]).is_some());
}

#[test]
fn a_broadcast_that_ends_a_refused_group_gets_no_reply() {
    let mut rig = Rig::sync65(Settings::default());
    // A reply went out before; then a group the unit refuses (100 A on a 65 A unit), ended
    // by a broadcast read: silence, not the earlier reply sent again.
    read(&mut rig, 0x2098);
    write(&mut rig, 0x2094, 100 * 64).unwrap();
    let mut out = [0u8; 64];
    let n = plasma_protocol::modbus_ascii::encode(0, &[0x04, 0x20, 0x98, 0x00, 0x01], &mut out)
        .unwrap();
    assert_eq!(ask(&mut rig, &out[..n]), None);
    assert_eq!(read(&mut rig, 0x2098), 111, "refused all the same: 0-11-1");
}

#[test]
fn exceptions_as_a_unit_gives_them() {
    let mut rig = Rig::sync65(Settings::default());
    let cases: [(&[u8], &[u8]); 6] = [
        (&[0x08, 0x00, 0x00, 0x00, 0x00], &[0x88, 0x01]),
        (&[0x04, 0x20, 0x00, 0x00, 0x01], &[0x84, 0x02]),
        (&[0x04, 0x20, 0x9F, 0x00, 0x02], &[0x84, 0x02]),
        (&[0x04, 0x20, 0x98, 0x00, 0x00], &[0x84, 0x03]),
        (&[0x06, 0x20, 0x98, 0x00, 0x01], &[0x86, 0x02]),
        (&[0x06, 0x20, 0x93, 0x00, 0x07], &[0x86, 0x03]),
    ];
    for (request, exception) in cases {
        assert_eq!(
            ask(&mut rig, &mb(request)),
            Some(line(mb(exception))),
            "{request:02X?}"
        );
    }
    assert_eq!(
        ask(&mut rig, &mb(&[0x05, 0x31, 0x00, 0xFF, 0x00])),
        Some(line(mb(&[0x85, 0x02]))),
        "the Start coil is read only: Modbus never starts the torch"
    );
    rig.run(300);
    assert!(rig.writes().is_empty());
}

/// SYNC manual (000_dd931256418ae627.txt) lines 1700-1744: the Start and Motion coils read one
/// (`:010131000001CC` -> `:01010100FD`, both off) and both at once (`:010131000002CB` ->
/// `:01010103FA`, both on); Table 1 (lines 452-453): 0x0810/0x0811 are their old addresses.
#[test]
fn the_start_and_motion_coils_are_the_manuals_samples() {
    use crate::io::{Inputs, Outputs};
    let mut rig = Rig::sync65(Settings::default());
    rig.bridge.set_io_snapshot(Inputs::NONE, Outputs::OFF);
    assert_eq!(
        ask(&mut rig, b":010131000001CC\r\n").as_deref(),
        Some(":01010100FD")
    );
    // The unit's Start input is the bridge's START output; its Motion output the MOTION input.
    let motion = Inputs {
        motion: true,
        ..Inputs::NONE
    };
    let start = Outputs {
        start: true,
        ..Outputs::OFF
    };
    rig.bridge.set_io_snapshot(motion, start);
    assert_eq!(
        ask(&mut rig, b":010131000002CB\r\n").as_deref(),
        Some(":01010103FA")
    );
    assert_eq!(
        ask(&mut rig, &mb(&[0x01, 0x08, 0x10, 0x00, 0x02])),
        Some(line(mb(&[0x01, 0x01, 0x03])))
    );
    assert_eq!(
        ask(&mut rig, &mb(&[0x01, 0x31, 0x00, 0x00, 0x03])),
        Some(line(mb(&[0x81, 0x02]))),
        "0x3102 is not a coil"
    );
}

/// The torch-lead coils (Powermax65/85 protocol, 001_0bf4bbd6620a48c8.txt lines 258-271: read 2
/// coils from 0x0808, `:01010101FC` for a 35-50 ft lead): a legacy unit's own, read by the
/// link; a SYNC unit's from 0x3000 (SYNC manual, 000_dd931256418ae627.txt, line 618: 0x04 is a
/// machine torch with a 15-25 ft lead, coils 00).
#[test]
fn the_torch_lead_coils_behind_legacy_and_sync_units() {
    let mut legacy = Rig::new(Settings::default(), Some("pm65"));
    legacy.ps().powermax().config_mut().torch_id = 0x05;
    legacy.run(1500);
    assert_eq!(
        ask(&mut legacy, &mb(&[0x01, 0x08, 0x08, 0x00, 0x02])).as_deref(),
        Some(":01010101FC")
    );
    assert_eq!(
        ask(&mut legacy, &mb(&[0x01, 0x31, 0x00, 0x00, 0x01])),
        Some(line(mb(&[0x81, 0x02]))),
        "the SYNC coils only behind a SYNC unit"
    );
    let mut sync = Rig::sync65(Settings::default());
    assert_eq!(
        ask(&mut sync, &mb(&[0x01, 0x08, 0x08, 0x00, 0x02])).as_deref(),
        Some(":01010100FD")
    );
    let mut hpr = Rig::hpr("hpr130");
    assert_eq!(
        ask(&mut hpr, &mb(&[0x01, 0x08, 0x08, 0x00, 0x02])),
        Some(line(mb(&[0x81, 0x02])))
    );
}

/// SYNC manual (000_dd931256418ae627.txt) lines 1038-1077: `:01053180FF004A` starts a gas test,
/// `:01053180000049` stops it, each echoed; Table 1 (line 454): 0x0832 is the old address.
#[test]
fn the_gas_test_coil_starts_and_stops_a_gas_test() {
    let mut rig = Rig::sync65(Settings::default());
    for frame in [":01053180FF004A", ":01053180000049"] {
        let request = std::format!("{frame}\r\n");
        assert_eq!(ask(&mut rig, request.as_bytes()).as_deref(), Some(frame));
        rig.run(300);
    }
    assert_eq!(
        rig.writes(),
        [(0x3180, std::vec![1]), (0x3180, std::vec![0])],
        "the link wrote the unit's coil"
    );
    let mut legacy = Rig::new(Settings::default(), Some("pm65"));
    legacy.run(1500);
    let on = mb(&[0x05, 0x08, 0x32, 0xFF, 0x00]);
    assert_eq!(ask(&mut legacy, &on), Some(line(on.clone())));
    assert_eq!(
        ask(&mut legacy, b":01053180FF004A\r\n"),
        Some(line(mb(&[0x85, 0x02])))
    );
    legacy.run(300);
    assert_eq!(legacy.writes(), [(0x0832, std::vec![1])]);
}

/// SYNC manual (000_dd931256418ae627.txt) lines 1114 and 1130: the quick restart request and
/// its echo; line 1101: it stops 0-50-0 only.
#[test]
fn the_quick_restart_registers_restart_a_sync_unit_in_0_50_0() {
    let mut rig = Rig::sync65(Settings::default());
    let restart = b":0110308E0002040404061805\r\n";
    // No 0-50-0: echoed, and nothing is sent (it would stop no fault).
    assert_eq!(ask(&mut rig, restart).as_deref(), Some(":0110308E00022F"));
    rig.run(300);
    assert!(rig.writes().is_empty(), "{:?}", rig.writes());
    rig.fault(500);
    rig.run(300);
    assert_eq!(ask(&mut rig, restart).as_deref(), Some(":0110308E00022F"));
    rig.run(300);
    assert_eq!(rig.writes(), [(0x308E, std::vec![0x0404, 0x0618])]);
    // Other values, one register alone, or function 06: exception 03.
    let cases: [&[u8]; 3] = [
        &[0x10, 0x30, 0x8E, 0x00, 0x02, 0x04, 0x04, 0x04, 0x06, 0x19],
        &[0x10, 0x30, 0x8E, 0x00, 0x01, 0x02, 0x04, 0x04],
        &[0x06, 0x30, 0x8F, 0x06, 0x18],
    ];
    for request in cases {
        let reply = ask(&mut rig, &mb(request)).unwrap();
        assert_eq!(
            reply,
            line(mb(&[request[0] | 0x80, 0x03])),
            "{request:02X?}"
        );
    }
    // Not served behind a legacy unit.
    let mut legacy = Rig::new(Settings::default(), Some("pm65"));
    legacy.run(1500);
    assert_eq!(ask(&mut legacy, restart), Some(line(mb(&[0x90, 0x02]))));
}

#[test]
fn the_sync_map_is_served_only_behind_a_sync_unit() {
    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(read(&mut rig, 0x3003), 65 * 64);
    let mut hpr = Rig::hpr("hpr130");
    assert_eq!(
        ask(&mut hpr, &mb(&[0x04, 0x30, 0x03, 0x00, 0x01])),
        Some(line(mb(&[0x84, 0x02])))
    );
}

/// The bytes of a hex string as the manual prints them (`303831333335`).
fn hex_bytes(hex: &str) -> Vec<u8> {
    (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect()
}

/// SYNC manual (000_dd931256418ae627.txt) lines 572 and 587: the request and the reply, byte
/// for byte, of a Powermax65/85/105 SYNC (line 564: 081335).
#[test]
fn identification_is_the_manuals_sample_behind_a_sync_unit() {
    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(
        ask(&mut rig, b":012B0E0401C1\r\n").as_deref(),
        Some(":012B0E0481000101010630383133333504")
    );
    // Only object 0x01 is held: another one asked for individually is exception 02.
    assert_eq!(
        ask(&mut rig, &mb(&[0x2B, 0x0E, 0x04, 0x00])),
        Some(line(mb(&[0xAB, 0x02])))
    );
    // Stream access (basic, regular, extended) from any object: the product code in one
    // reply, the code asked for echoed, no more follows, next object id 0.
    for (code, object) in [(0x01, 0x00), (0x01, 0x02), (0x02, 0x00), (0x03, 0x80)] {
        let mut reply = std::vec![0x2B, 0x0E, code, 0x81, 0x00, 0x00, 0x01, 0x01, 0x06];
        reply.extend(hex_bytes("303831333335"));
        assert_eq!(
            ask(&mut rig, &mb(&[0x2B, 0x0E, code, object])),
            Some(line(mb(&reply))),
            "code {code:02X} object {object:02X}"
        );
    }
    // An access code Modbus does not define: exception 03.
    assert_eq!(
        ask(&mut rig, &mb(&[0x2B, 0x0E, 0x05, 0x01])),
        Some(line(mb(&[0xAB, 0x03])))
    );
}

/// A legacy unit behind the bridge is identified with the product code SYNC manual
/// (000_dd931256418ae627.txt) Table 2 lists for it (lines 561-563), in the sample's header
/// (line 587), so a SYNC-aware CNC picks the 0x2xxx map; an HPR has none: exception 01.
#[test]
fn identification_of_legacy_units_and_none_for_an_hpr() {
    for (model, hex) in [
        ("pm45xp", "303831323838"),
        ("pm65", "303831323233"),
        ("pm125", "303831323531"),
    ] {
        let mut rig = Rig::new(Settings::default(), Some(model));
        rig.run(600);
        assert!(rig.bridge.status().link_up, "{model}");
        let mut reply = std::vec![0x2B, 0x0E, 0x04, 0x81, 0x00, 0x01, 0x01, 0x01, 0x06];
        reply.extend(hex_bytes(hex));
        assert_eq!(
            ask(&mut rig, b":012B0E0401C1\r\n"),
            Some(line(mb(&reply))),
            "{model}"
        );
    }
    let mut hpr = Rig::hpr("hpr130");
    assert_eq!(
        ask(&mut hpr, b":012B0E0401C1\r\n"),
        Some(line(mb(&[0xAB, 0x01])))
    );
}

/// The conformity level is the one the unit gave at detection, not the sample's 0x81 (SYNC
/// manual (000_dd931256418ae627.txt) line 587): a unit that reports 0x83 (basic and regular
/// identification, stream and individual access, in the Modbus reading) is answered with 0x83,
/// the rest of the sample's reply unchanged, behind a SYNC and a legacy unit.
#[test]
fn identification_gives_the_conformity_level_the_unit_gave() {
    for (model, hex) in [("sync65", "303831333335"), ("pm125", "303831323531")] {
        let mut rig = Rig::new(Settings::default(), Some(model));
        rig.ps().powermax().config_mut().device_id = DeviceIdSupport::Answers { conformity: 0x83 };
        rig.run(600);
        assert_eq!(
            rig.bridge.status().device_id_conformity,
            Some(0x83),
            "{model}"
        );
        let mut reply = std::vec![0x2B, 0x0E, 0x04, 0x83, 0x00, 0x01, 0x01, 0x01, 0x06];
        reply.extend(hex_bytes(hex));
        assert_eq!(
            ask(&mut rig, b":012B0E0401C1\r\n"),
            Some(line(mb(&reply))),
            "{model}"
        );
    }
}

#[test]
fn text_commands_keep_working_between_modbus_requests() {
    let mut rig = Rig::sync65(Settings::default());
    read(&mut rig, 0x2098);
    assert!(rig.cmd("ID").starts_with("OK bridge="));
    // A request that stops arriving does not swallow the next text line.
    rig.bridge.handle_cnc_rx(rig.now, b":010420");
    rig.run(100);
    assert!(rig.cmd("ID").starts_with("OK bridge="));
    read(&mut rig, 0x2098);
}

/// One step of a Modbus master: a write anywhere near the force registers, a read, or a pause.
#[derive(Debug, Clone)]
enum MasterStep {
    Write(u16, u16),
    WriteMany(u16, Vec<u16>),
    Read(u16),
    Pause(u64),
}

fn master_step() -> impl Strategy<Value = MasterStep> {
    let register = prop_oneof![
        Just(0x2093u16),
        Just(0x2094),
        Just(0x2096),
        Just(0x3080),
        Just(0x3081),
        Just(0x3082),
        Just(0x3100),
        Just(0x0810),
        0x2090u16..0x20A0,
    ];
    let value = prop_oneof![0u16..4, Just(0), 0u16..0x2000, any::<u16>()];
    prop_oneof![
        (register.clone(), value.clone()).prop_map(|(r, v)| MasterStep::Write(r, v)),
        (register.clone(), proptest::collection::vec(value, 1..4))
            .prop_map(|(r, v)| MasterStep::WriteMany(r, v)),
        register.prop_map(MasterStep::Read),
        (0u64..250).prop_map(MasterStep::Pause),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Whatever a Modbus master writes, the unit gets only whole settings writes (all three
    /// registers in one request) and never a START or any other coil.
    #[test]
    fn no_sequence_of_modbus_writes_makes_a_partial_settings_write_or_a_start(
        steps in proptest::collection::vec(master_step(), 1..24)
    ) {
        let mut rig = Rig::sync65(Settings::default());
        for step in steps {
            let frame = match step {
                MasterStep::Write(r, v) => {
                    let ([hi, lo], [vh, vl]) = (r.to_be_bytes(), v.to_be_bytes());
                    mb(&[0x06, hi, lo, vh, vl])
                }
                MasterStep::WriteMany(r, values) => {
                    let [hi, lo] = r.to_be_bytes();
                    let mut pdu = std::vec![0x10, hi, lo, 0, values.len() as u8, 2 * values.len() as u8];
                    for v in values {
                        pdu.extend_from_slice(&v.to_be_bytes());
                    }
                    mb(&pdu)
                }
                MasterStep::Read(r) => {
                    let [hi, lo] = r.to_be_bytes();
                    mb(&[0x04, hi, lo, 0, 1])
                }
                MasterStep::Pause(ms) => {
                    rig.run(ms);
                    continue;
                }
            };
            rig.bridge.handle_cnc_rx(rig.now, &frame);
            rig.collect();
            rig.run(20);
        }
        rig.run(SETTLE.as_millis() + 500);
        // `writes` lists every 0x10 write and every coil write (START is coil 0x3100).
        for (address, values) in rig.writes() {
            prop_assert_eq!(address, 0x3080, "only the settings registers, no coil");
            prop_assert_eq!(values.len(), 3, "all three at once");
        }
    }
}

#[test]
fn a_text_set_after_modbus_writes_shows_in_the_force_registers() {
    let mut rig = Rig::sync65(Settings::default());
    connect(&mut rig, 1, 45, 0);
    rig.run(300);
    assert!(rig.cmd("SET AMPS 30").starts_with("OK"));
    assert_eq!(read(&mut rig, 0x2094), 30 * 64);
}

#[test]
fn a_colon_inside_a_refused_line_is_text() {
    let mut rig = Rig::sync65(Settings::default());
    // A control byte makes the line assembler drop the rest of the line; the `:` in it must
    // not open a Modbus request.
    rig.bridge
        .handle_cnc_rx(rig.now, b"\x03RAW :0104301A0001B0\r\n");
    rig.run(100);
    assert!(
        rig.received.iter().all(|t| !t.starts_with(':')),
        "{:?}",
        rig.received
    );
    assert_eq!(read(&mut rig, 0x2098), 0);
}

/// Reads `quantity` registers from `start` in one function 04 request.
fn read_block(rig: &mut Rig, start: u16, quantity: u16) -> Vec<u16> {
    let [hi, lo] = start.to_be_bytes();
    let [qh, ql] = quantity.to_be_bytes();
    let reply = ask(rig, &mb(&[0x04, hi, lo, qh, ql])).expect("a reply");
    assert_eq!(&reply[..5], ":0104", "{reply}");
    let words = &reply[7..reply.len() - 2];
    (0..usize::from(quantity))
        .map(|i| u16::from_str_radix(&words[i * 4..i * 4 + 4], 16).unwrap())
        .collect()
}

/// SYNC manual (000_dd931256418ae627.txt) lines 454-533: 0x3000 identification, 0x3030-0x3037
/// UID, 0x3038-0x303B part number and revision, 0x303C nominal current, 0x3040-0x3043 cartridge
/// counters, 0x3044-0x3047 fault log, 0x3048-0x304D name. A SYNC-aware CNC reads them through
/// the bridge as from the unit.
#[test]
fn a_sync_units_identification_and_cartridge_read_through_the_bridge() {
    let mut rig = Rig::sync65(Settings::default());
    let (uid, revision) = {
        let cartridge = rig.ps().powermax().cartridge().expect("a cartridge");
        (cartridge.uid, cartridge.revision)
    };
    let status = rig.bridge.link().status().clone();
    let identification = status.identification.expect("the link read 0x3000").raw;
    assert_eq!(read(&mut rig, 0x3000), identification);
    let block = read_block(&mut rig, 0x3030, 30);
    let text = |words: &[u16]| -> Vec<u8> { words.iter().flat_map(|w| w.to_be_bytes()).collect() };
    assert_eq!(text(&block[..8]), uid, "UID, bytes 0 and 1 first");
    assert_eq!(block[11], revision);
    assert_eq!(
        &block[13..16],
        &[0, 0, 0],
        "0x303D-0x303F lie between documented registers"
    );
    assert_eq!(
        &block[16..20],
        &[17, 40, 15, 20],
        "starts, pilot s, transfers, 2 s counts"
    );
    assert_eq!(&block[20..24], &[200, 500, 0, 0], "fault log, newest first");
    let cartridge = status.cartridge.expect("the link read the cartridge");
    assert_eq!(text(&block[8..11]), cartridge.part_number.0);
    assert_eq!(block[12], cartridge.nominal_current_raw);
    let name = status.cartridge_name.expect("the link read the name");
    assert_eq!(text(&block[24..30]), name.0);
    assert_eq!(
        ask(&mut rig, &mb(&[0x04, 0x30, 0x4E, 0x00, 0x01])),
        Some(line(mb(&[0x84, 0x02]))),
        "0x304E is past the map"
    );
}

/// A Modbus frame for `node`.
fn at_node(node: u8, pdu: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 600];
    let n = plasma_protocol::modbus_ascii::encode(node, pdu, &mut out).unwrap();
    out[..n].to_vec()
}

#[test]
fn each_unit_on_the_line_answers_at_its_own_node_from_cnc_address_on() {
    // A SYNC 65 (node 1 on the supply line) and a SYNC 45 (node 2); the CNC port's nodes 5
    // and 6.
    let mut rig = Rig::on_line(
        Settings::default(),
        "POWERMAX:1,POWERMAX:2",
        &["sync65", "sync45"],
    );
    assert_eq!(rig.cmd("CONFIG cnc_address 5"), "OK cnc_address=5");
    // Both units' limits read (slow data, in turns on the shared line).
    rig.run(3000);
    assert!((0..2).all(|u| rig.bridge.status_of(u).limits.is_some()));
    // 0x209A, the maximum current: 65 A and 45 A, x 64.
    let max = |rig: &mut Rig, node: u8| {
        let reply = ask(rig, &at_node(node, &[0x04, 0x20, 0x9A, 0x00, 0x01]))?;
        Some(u16::from_str_radix(&reply[7..11], 16).unwrap() / 64)
    };
    assert_eq!(max(&mut rig, 5), Some(65));
    assert_eq!(max(&mut rig, 6), Some(45));
    assert_eq!(max(&mut rig, 7), None, "no third unit: no answer");
    assert_eq!(max(&mut rig, 4), None);
    // A write to node 6 sets unit 2 only, and its reply is node 6's.
    for (register, value) in [(0x2093u16, 1u16), (0x2094, 30 * 64), (0x2096, 0)] {
        let [hi, lo] = register.to_be_bytes();
        let [vh, vl] = value.to_be_bytes();
        let frame = at_node(6, &[0x06, hi, lo, vh, vl]);
        assert_eq!(ask(&mut rig, &frame), Some(line(frame)));
    }
    rig.run(1500);
    let second = rig.cmd("@2 STATUS");
    assert!(second.contains(" amps=30"), "{second}");
    let first = rig.cmd("STATUS");
    assert!(!first.contains(" amps=30"), "{first}");
    // The settings persist the first unit's process only.
    assert_eq!(rig.bridge.settings().process, None);
}
