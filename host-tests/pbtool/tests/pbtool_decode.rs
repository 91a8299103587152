//! `pbtool decode` on the manuals' frames. Every frame's checksum was recomputed before it was
//! used here; frames printed wrongly in the manuals are used corrected (and the printed form
//! is tested as rejected).

use std::process::Command;

use pbtool::decode::{FrameReport, Kind, Protocol, all_valid, decode_frames, lines, to_json};

fn one(frame: &str) -> FrameReport {
    decode_frames(&[frame]).remove(0)
}

/// (address, name, value, unit) of a register.
type Row<'a> = (Option<u16>, &'a str, Option<&'a str>, Option<&'a str>);

/// The registers of a report as rows, for compact assertions.
fn registers(report: &FrameReport) -> Vec<Row<'_>> {
    report
        .registers
        .iter()
        .map(|r| (r.address, r.name.as_str(), r.value.as_deref(), r.unit))
        .collect()
}

fn field<'a>(report: &'a FrameReport, name: &str) -> Option<&'a str> {
    report
        .fields
        .iter()
        .find(|f| f.name == name)
        .map(|f| f.value.as_str())
}

#[test]
fn sync_remote_mode_write_63_amps() {
    // SYNC guide: cut mode, 63 A, automatic pressure. LRC 66 recomputed.
    let r = one(":0110308000030600010FC0000066");
    assert!(r.valid, "{r:?}");
    assert_eq!(r.protocol, Some(Protocol::ModbusAscii));
    assert_eq!(r.address, Some(1));
    assert_eq!(
        r.function.as_ref().map(|f| (f.code, f.name)),
        Some((0x10, "Write Multiple Registers"))
    );
    assert_eq!(r.kind, Some(Kind::Request));
    assert!(
        r.kind_reason
            .as_deref()
            .unwrap()
            .contains("at least 8 bytes")
    );
    assert_eq!(
        registers(&r),
        [
            (Some(0x3080), "remote operating mode", Some("cut"), None),
            (Some(0x3081), "remote current", Some("63"), Some("A")),
            (Some(0x3082), "remote pressure", Some("auto"), None),
        ]
    );
    let text = lines(&r).join("\n");
    assert!(text.contains("0x3081 remote current = 63 A"), "{text}");
}

#[test]
fn remote_write_with_a_pressure_set_point() {
    // Gouge, 63 A, 72.5 psi (0x2440 = 72.5 x 128); LRC computed: 0x100 - sum = 0x00.
    let r = one(":0110308000030600030FC0244000");
    assert!(r.valid, "{r:?}");
    assert_eq!(r.registers[0].value.as_deref(), Some("gouge"));
    assert_eq!(
        (r.registers[2].value.as_deref(), r.registers[2].unit),
        (Some("72.5"), Some("psi"))
    );
}

#[test]
fn sync_fault_log_request_and_reply() {
    // The guide prints the reply as `:0104080079007900000000001` (one `0` too many: 25 hex
    // digits). With the extra digit removed the LRC 01 matches.
    let reports = decode_frames(&[":01043044000483", ":010408007900790000000001"]);
    assert!(all_valid(&reports), "{reports:?}");
    let (request, reply) = (&reports[0], &reports[1]);
    assert_eq!(request.kind, Some(Kind::Request));
    assert_eq!(request.registers.len(), 4);
    assert!(
        request
            .registers
            .iter()
            .all(|r| r.name == "fault log (newest first)" && r.raw.is_none())
    );

    assert_eq!(reply.kind, Some(Kind::Reply));
    assert_eq!(reply.answers_request, Some(true));
    assert_eq!(reply.registers[0].address, Some(0x3044));
    assert_eq!(reply.registers[3].address, Some(0x3047));
    let codes: Vec<&str> = reply.faults.iter().map(|f| f.code.as_str()).collect();
    assert_eq!(codes, ["0-12-1", "0-12-1", "0-00-0", "0-00-0"]);
    let low = &reply.faults[0];
    assert_eq!(low.text.as_deref(), Some("The gas pressure output is low."));
    assert_eq!(
        low.action_required,
        Some(false),
        "table: No, but recommended"
    );
    assert!(
        reply.registers[0]
            .value
            .as_deref()
            .unwrap()
            .starts_with("0-12-1 The gas pressure output is low.")
    );

    let printed = one(":0104080079007900000000001");
    assert!(!printed.valid);
}

#[test]
fn fault_needing_action_says_so() {
    // Read 0x301A (`:0104301A0001B0`) answered 0x01F4 = 500 (`:01040201F404`), both from the
    // SYNC guide, LRCs recomputed.
    let reports = decode_frames(&[":0104301A0001B0", ":01040201F404"]);
    assert!(all_valid(&reports));
    let fault = &reports[1].faults[0];
    assert_eq!(fault.code, "0-50-0");
    assert_eq!(fault.action_required, Some(true));
    let value = reports[1].registers[0].value.as_deref().unwrap();
    assert!(
        value.starts_with("0-50-0 ") && value.ends_with("(action required)"),
        "{value}"
    );
}

#[test]
fn legacy_fault_read_with_the_guides_hex_crlf() {
    // Legacy guide: `:010420980001420D0A`, where `0D0A` is CR LF written in hex (LRC 42 is
    // right for 01 04 2098 0001); the response `:010402006F8A` (LRC 8A right).
    let reports = decode_frames(&[":010420980001420D0A", ":010402006F8A"]);
    assert!(all_valid(&reports), "{reports:?}");
    assert_eq!(reports[0].frame, ":01042098000142");
    assert!(reports[0].notes.iter().any(|n| n.contains("0D0A")));
    assert_eq!(reports[0].registers[0].name, "fault code");
    let reply = &reports[1];
    assert_eq!(reply.answers_request, Some(true));
    assert_eq!(reply.faults[0].code, "0-11-1");
    assert_eq!(
        reply.faults[0].text.as_deref(),
        Some("Current setting value is out of range")
    );
    assert_eq!(reply.registers[0].address, Some(0x2098));
}

#[test]
fn device_identification_names_the_model() {
    // SYNC guide: product code request and reply `081335`; LRCs C1 and 04 recomputed.
    let reports = decode_frames(&[":012B0E0401C1", ":012B0E0481000101010630383133333504"]);
    assert!(all_valid(&reports));
    assert_eq!(reports[0].kind, Some(Kind::Request));
    assert!(
        reports[0]
            .kind_reason
            .as_deref()
            .unwrap()
            .contains("4 bytes")
    );
    let reply = &reports[1];
    assert_eq!(reply.kind, Some(Kind::Reply));
    assert_eq!(field(reply, "object 01 product code"), Some("081335"));
    assert_eq!(field(reply, "model"), Some("Powermax65/85/105 SYNC"));
}

#[test]
fn cartridge_part_number_is_ascii() {
    // SYNC guide: read 0x3038 x3, reply "428936" (LRCs 90 and B5 recomputed).
    let reports = decode_frames(&[":01043038000390", ":010406343238393336B5"]);
    assert!(all_valid(&reports));
    assert_eq!(field(&reports[1], "cartridge part number"), Some("428936"));
    assert!(
        reports[1]
            .notes
            .iter()
            .any(|n| n.starts_with("cartridge 428936"))
    );
}

#[test]
fn counters_combine_low_word_first() {
    // 0x3028 = 0x0001 (low), 0x3029 = 0x0002 (high): 0x0002_0001 = 131073 starts.
    let reports = decode_frames(&[":010430280002A1", ":01040400010002F4"]);
    assert!(all_valid(&reports));
    assert_eq!(field(&reports[1], "total starts"), Some("131073"));
}

#[test]
fn bad_lrc_is_invalid_and_says_the_right_one() {
    let r = one(":01043044000484");
    assert!(!r.valid);
    let ck = r.checksum.unwrap();
    assert_eq!((ck.found, ck.expected), (0x84, 0x83));
    assert_eq!(r.error.as_deref(), Some("LRC 84 wrong, should be 83"));
    // The contents are still shown.
    assert_eq!(r.registers.len(), 4);
}

#[test]
fn line_endings_in_every_spelling() {
    let spellings = [
        ":01043044000483<CR><LF>",
        ":01043044000483<cr><lf>",
        ":01043044000483\r\n",
        ":01043044000483",
        " :01043044000483 ",
        ":0110308000030600010fc0000066",
    ];
    for s in spellings {
        let r = one(s);
        assert!(r.valid, "{s:?}: {r:?}");
        assert!(!r.frame.contains(['<', '\r', '\n', ' ']), "{s:?}");
    }
    assert!(
        one(":01043044000483<CR><LF>")
            .notes
            .iter()
            .any(|n| n.contains("<CR><LF>"))
    );
    let hpr = one(">00090<<CR><LF>");
    assert!(hpr.valid);
    assert!(hpr.notes.iter().any(|n| n.contains("lock up")));
}

#[test]
fn reply_that_does_not_answer_its_request() {
    // A 1-register reply after a 4-register read.
    let reports = decode_frames(&[":01043044000483", ":010402006F8A"]);
    let reply = &reports[1];
    assert_eq!(reply.answers_request, Some(false));
    assert!(!reply.valid);
    assert!(
        reply
            .error
            .as_deref()
            .unwrap()
            .contains("asked for 4 registers"),
        "{reply:?}"
    );
    assert!(!all_valid(&reports));
}

#[test]
fn exception_reply_is_named() {
    // 01 84 02: illegal data address; LRC 0x100 - 0x87 = 0x79.
    let reports = decode_frames(&[":01043044000483", ":01840279"]);
    assert!(all_valid(&reports));
    let reply = &reports[1];
    assert_eq!(reply.answers_request, Some(true));
    assert_eq!(field(reply, "exception"), Some("02 illegal data address"));
    assert!(
        reply
            .notes
            .iter()
            .any(|n| n.contains("refused function 04"))
    );
}

#[test]
fn reply_alone_is_recognised_by_length() {
    let r = one(":010408007900790000000001");
    assert!(r.valid);
    assert_eq!(r.kind, Some(Kind::Reply));
    assert!(r.registers.iter().all(|r| r.address.is_none()));
    assert_eq!(r.registers[0].raw, Some(0x0079));
}

#[test]
fn not_a_frame() {
    let r = one("hello");
    assert!(!r.valid);
    assert_eq!(r.protocol, None);
    assert!(!one(":0104").valid);
}

#[test]
fn hpr_hello_and_its_reply() {
    // Manual: `>00090<` (0x30 x 3 = 0x90) and the HELLO reply (checksum B5 recomputed).
    let reports = decode_frames(&[">00090<", ">000HYPERFORMANCE130MANUALB5<"]);
    assert!(all_valid(&reports), "{reports:?}");
    let request = &reports[0];
    assert_eq!(request.protocol, Some(Protocol::Hpr));
    assert_eq!(request.kind, Some(Kind::Request));
    let command = request.command.as_ref().unwrap();
    assert_eq!(
        (command.id, command.name, command.class),
        (0, Some("HELLO"), Some("normal"))
    );
    let reply = &reports[1];
    assert_eq!(reply.answers_request, Some(true));
    assert_eq!(
        field(reply, "system"),
        Some("HPR130 with manual gas console")
    );
}

#[test]
fn hpr_500_reply_is_explained() {
    // `>50095<`: '5' + '0' + '0' = 0x95.
    let r = one(">50095<");
    assert!(r.valid);
    assert_eq!(r.kind, Some(Kind::Reply));
    assert!(
        r.command
            .as_ref()
            .unwrap()
            .name
            .unwrap()
            .contains("BAD CHECKSUM")
    );
    assert!(r.notes.iter().any(|n| n.contains("checksum was wrong")));
    // 501 after a HELLO answers it (500/501 answer any request).
    let reports = decode_frames(&[">00090<", ">50196<"]);
    assert_eq!(reports[1].answers_request, Some(true));
}

#[test]
fn hpr_typed_fields_and_classes() {
    // GET_STATE reply from the crate docs: `>002000355<` = state 3.
    let state = decode_frames(&[">00292<", ">002000355<"]);
    assert!(all_valid(&state), "{state:?}");
    assert_eq!(
        field(&state[1], "state"),
        Some("3 (HPR: IDLE2; MaxPro200: READY FOR START)")
    );
    // 058 SET_NOMINAL_AMPS 130 A: `>05813031<`.
    let amps = one(">05813031<");
    assert_eq!(amps.fields[0].value, "130");
    assert_eq!(amps.fields[0].unit, Some("A"));
    // 071 MANUAL_PUMP_CONTROL is dangerous.
    let pump = one(">0711C9<");
    assert_eq!(pump.command.as_ref().unwrap().class, Some("dangerous"));
    // A bad HPR checksum says the right one.
    let bad = one(">00091<");
    assert!(!bad.valid);
    assert_eq!(
        bad.error.as_deref(),
        Some("checksum 91 wrong, should be 90")
    );
}

#[test]
fn json_has_the_documented_fields() {
    let reports = decode_frames(&[":0110308000030600010FC0000066", ">50095<"]);
    let modbus = to_json(&reports[0]);
    assert_eq!(modbus["protocol"], "modbus_ascii");
    assert_eq!(modbus["valid"], true);
    assert_eq!(modbus["checksum"]["found"], "66");
    assert_eq!(modbus["checksum"]["expected"], "66");
    assert_eq!(modbus["address"], 1);
    assert_eq!(modbus["function"]["code"], 0x10);
    assert_eq!(modbus["kind"], "request");
    assert_eq!(modbus["registers"][1]["address"], 0x3081);
    assert_eq!(modbus["registers"][1]["name"], "remote current");
    assert_eq!(modbus["registers"][1]["raw"], 0x0FC0);
    assert_eq!(modbus["registers"][1]["value"], "63");
    assert_eq!(modbus["registers"][1]["unit"], "A");
    assert!(modbus["text"].is_array());
    assert!(modbus["error"].is_null());
    let hpr = to_json(&reports[1]);
    assert_eq!(hpr["protocol"], "hpr");
    assert_eq!(hpr["kind"], "reply");
    assert_eq!(hpr["command"]["id"], 500);

    let faults = decode_frames(&[":01043044000483", ":010408007900790000000001"]);
    let reply = to_json(&faults[1]);
    assert_eq!(reply["fault"][0]["code"], "0-12-1");
    assert_eq!(reply["fault"][0]["action_required"], false);
    let bad = to_json(&one(":01043044000484"));
    assert_eq!(bad["valid"], false);
    assert_eq!(bad["checksum"]["expected"], "83");
    assert_eq!(bad["error"], "LRC 84 wrong, should be 83");
}

fn pbtool(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_pbtool"))
        .args(args)
        .output()
        .unwrap();
    (out.status.code(), String::from_utf8(out.stdout).unwrap())
}

#[test]
fn binary_decodes_the_remote_write() {
    let (code, out) = pbtool(&["decode", ":0110308000030600010FC0000066<CR><LF>"]);
    assert_eq!(code, Some(0), "{out}");
    assert!(out.contains("0x3080 remote operating mode = cut"), "{out}");
    assert!(out.contains("0x3081 remote current = 63 A"), "{out}");
    assert!(out.contains("0x3082 remote pressure = auto"), "{out}");
}

#[test]
fn binary_exits_1_on_a_bad_lrc_and_names_the_right_one() {
    let (code, out) = pbtool(&["decode", ":01043044000483", ":01043044000484"]);
    assert_eq!(code, Some(1));
    assert!(out.contains("LRC 84 WRONG, should be 83"), "{out}");
}

#[test]
fn binary_json_is_one_object_per_line() {
    let (code, out) = pbtool(&[
        "decode",
        "--json",
        ":012B0E0401C1",
        ":012B0E0481000101010630383133333504",
        ">50095<",
    ]);
    assert_eq!(code, Some(0));
    let objects: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(objects.len(), 3);
    assert_eq!(objects[1]["kind"], "reply");
    assert!(
        objects[1]["fields"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f["value"] == "Powermax65/85/105 SYNC")
    );
    assert_eq!(objects[2]["protocol"], "hpr");
}

#[test]
fn binary_usage_error_exits_2() {
    assert_eq!(pbtool(&["decode"]).0, Some(2));
    assert_eq!(pbtool(&["frobnicate"]).0, Some(2));
}

#[test]
fn hpr_diagnostic_reads_are_typed() {
    // HPR manual (002_72b43a5685974c77.txt) line 266: 132 READ COOLANT PRESSURE, `>13296<`
    // answered `>13280FE<` (80 counts; "83 counts = 225 psi 73 counts = 200 psi").
    let coolant = decode_frames(&[">13296<", ">13280FE<"]);
    assert!(all_valid(&coolant), "{coolant:?}");
    assert_eq!(coolant[1].answers_request, Some(true));
    assert_eq!(field(&coolant[1], "coolant pressure (raw A/D)"), Some("80"));
    assert_eq!(field(&coolant[1], "coolant pressure"), Some("217.5"));
    // Line 200: 100 GET_CONTROL_DATA, HPR form.
    let control = decode_frames(&[
        ">10091<",
        ">100CAT0482 CBT0021 LVO0118 CFL0009 CTP0481 TTP0481 CAC0001 CBC0014 WLC0005 CAS0000 CBS0534 PWMA0000 PWMB00000B<",
    ]);
    assert!(all_valid(&control), "{control:?}");
    assert_eq!(control[0].kind, Some(Kind::Request));
    assert_eq!(field(&control[1], "line voltage"), Some("11.8"));
    assert_eq!(field(&control[1], "coolant flow"), Some("0.09"));
    assert_eq!(field(&control[1], "chopper B setpoint"), Some("534"));
    // Line 239: 117 READ_GAS_INPUTS_FROM_PS, seven inputs (the manual console's list).
    let inputs = one(">1170000000E9<");
    assert!(inputs.valid, "{inputs:?}");
    assert_eq!(field(&inputs, "error select"), Some("off"));
    assert_eq!(field(&inputs, "serial ID bit 2"), Some("off"));
    // Line 269: 133 GET CONTROL DATA3.
    let data3 = one(">133CCT0482 CDT0021 CCC0000 CDC000050<");
    assert!(data3.valid, "{data3:?}");
    assert_eq!(
        field(&data3, "chopper C temperature (raw A/D)"),
        Some("482")
    );
    // Line 162: 074's bits, listed by port and bit (the manual names none).
    let io = one(">074PA00000100 PB00000000 PC00010101 PD00100000 PE00010000 PF10000000B7<");
    assert_eq!(field(&io, "bits on"), Some("PA2 PC4 PC2 PC0 PD5 PE4 PF7"));
}

#[test]
fn manual_typos_are_invalid_and_show_what_was_meant() {
    // SYNC guide (000_dd931256418ae627.txt) line 1154: exit remote mode, one `0` too many;
    // its reply (line 1173) answers the corrected request.
    let reports = decode_frames(&[":01103080000306000000000000036<CR><LF>", ":0110308000033C"]);
    let printed = &reports[0];
    assert!(!printed.valid);
    assert!(printed.error.as_deref().unwrap().contains("odd number"));
    let meant = printed.meant.as_deref().unwrap();
    assert_eq!(meant.frame, ":0110308000030600000000000036");
    assert!(meant.valid, "{meant:?}");
    assert_eq!(meant.kind, Some(Kind::Request));
    assert_eq!(
        meant.registers[0].value.as_deref(),
        Some("0 (with current and pressure 0: leave remote control)")
    );
    assert!(
        printed
            .notes
            .iter()
            .any(|n| n.contains("printed with a typo"))
    );
    assert_eq!(reports[1].answers_request, Some(true), "{:?}", reports[1]);
    let text = lines(printed).join("\n");
    assert!(
        text.contains("the manual meant :0110308000030600000000000036:"),
        "{text}"
    );
    // Line 1589: the fault log reply, after its request (line 1574).
    let log = decode_frames(&[":01043044000483", ":0104080079007900000000001"]).remove(1);
    assert!(!log.valid);
    let meant = log.meant.as_deref().unwrap();
    assert!(meant.valid, "{meant:?}");
    assert_eq!(meant.faults[0].code, "0-12-1");
    // Line 1662: the cartridge name reply.
    let name = one(":01040C43204D45434800000000000006F");
    assert!(!name.valid);
    assert!(name.meant.as_deref().unwrap().valid);
    // HPR manual (002_72b43a5685974c77.txt) line 139: HELLO, "HYPERPERFORMANCE".
    let hello = one(">000HYPERPERFORMANCE130MANUALB5<");
    assert!(!hello.valid);
    assert_eq!(
        hello.error.as_deref(),
        Some("checksum B5 wrong, should be 9C")
    );
    let meant = hello.meant.as_deref().unwrap();
    assert!(meant.valid);
    assert_eq!(
        field(meant, "system"),
        Some("HPR130 with manual gas console")
    );
    // A frame that is not a listed typo has nothing meant.
    assert!(one(">00091<").meant.is_none());
    let json = to_json(&hello);
    assert_eq!(json["meant"]["valid"], true);
}

#[test]
fn fault_steps_keep_the_tables_three_values() {
    // SYNC guide (000_dd931256418ae627.txt) line 945: 0-12-1 "No, but recommended"; the
    // fault log sample of lines 1574 and 1589 (corrected) holds it.
    let reports = decode_frames(&[":01043044000483", ":010408007900790000000001"]);
    let low = &reports[1].faults[0];
    assert_eq!(low.steps_required, Some("no, but recommended"));
    // Legacy guide (001_0bf4bbd6620a48c8.txt) line 281: 0-12-0 is only in the legacy list
    // (no action column): taken as required. Read of 0x2098 answered 0x0078 (LRC computed).
    let reports = decode_frames(&[":01042098000142", ":010402007881"]);
    assert!(all_valid(&reports), "{reports:?}");
    let legacy = &reports[1].faults[0];
    assert_eq!(legacy.code, "0-12-0");
    assert_eq!(legacy.text.as_deref(), Some("Low input gas pressure"));
    assert_eq!(
        (legacy.steps_required, legacy.action_required),
        (Some("yes"), Some(true))
    );
    let value = reports[1].registers[0].value.as_deref().unwrap();
    assert!(value.ends_with("taken as required)"), "{value}");
    assert_eq!(to_json(&reports[1])["fault"][0]["steps_required"], "yes");
}

#[test]
fn torch_lead_length_of_the_legacy_coils_and_sync_0x3000() {
    // Legacy guide (001_0bf4bbd6620a48c8.txt) lines 258-271: read 2 coils from 0x0808
    // (`:010108080002EC`, the OCR'd sample rebuilt with its LRC) and the three responses.
    for (reply, length) in [
        (":01010100FD", "15-25 ft (up to 7.6 m)"),
        (":01010101FC", "35-50 ft (up to 15 m)"),
        (":01010102FB", "75 ft (up to 23 m)"),
    ] {
        let reports = decode_frames(&[":010108080002EC", reply]);
        assert!(all_valid(&reports), "{reports:?}");
        assert_eq!(
            field(&reports[1], "torch lead length"),
            Some(length),
            "{reply}"
        );
    }
    // Bits 11 are not in the guide's table (LRC computed).
    let reports = decode_frames(&[":010108080002EC", ":01010103FA"]);
    assert_eq!(
        field(&reports[1], "torch lead length"),
        Some("bits 11: not a length the legacy guide lists")
    );
    // A read that covers the two coils among others (16 coils from 0x0800, LRCs computed):
    // 0x0808 on, 0x0809 off in the second byte's bits 0 and 1.
    let reports = decode_frames(&[":010108000010E6", ":0101020001FB"]);
    assert!(all_valid(&reports), "{reports:?}");
    assert_eq!(
        field(&reports[1], "torch lead length"),
        Some("35-50 ft (up to 15 m)")
    );
    // A read that covers one of them only: no length.
    let reports = decode_frames(&[":010108090001EC", ":01010101FC"]);
    assert!(all_valid(&reports), "{reports:?}");
    assert_eq!(field(&reports[1], "torch lead length"), None);
    // The guide's reply alone (line 270): the coils are unknown, what it means if it answers
    // the lead read is said.
    let bare = one(":01010101FC");
    assert!(
        bare.notes
            .iter()
            .any(|n| n.contains("torch-lead read") && n.contains("35-50 ft (up to 15 m)")),
        "{bare:?}"
    );
    assert_eq!(field(&bare, "torch lead length"), None);
    // Two coil bytes cannot answer a two-coil read: no lead is suggested.
    let bare = one(":0101020001FB");
    assert!(
        !bare.notes.iter().any(|n| n.contains("torch-lead read")),
        "{bare:?}"
    );
    // SYNC guide (000_dd931256418ae627.txt) line 607: 0x3000 = 0x0508, machine torch with a
    // 35-50 ft lead (Table 3) on a Powermax105 SYNC CSA 200-600 V (Table 4); LRCs computed.
    let reports = decode_frames(&[":010430000001CA", ":0104020508EC"]);
    assert!(all_valid(&reports), "{reports:?}");
    let value = reports[1].registers[0].value.as_deref().unwrap();
    assert!(value.contains("35") && value.contains("50"), "{value}");
    assert!(
        value.contains("Powermax105") && value.contains("600"),
        "{value}"
    );
}
