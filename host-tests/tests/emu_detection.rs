//! End to end on the emulated board: the firmware image finds each family of unit on its PS
//! port by itself. The line's framing is the one the firmware programs into USART1 (parity,
//! stop bits, and the baud rate from BRR at the board's 80 MHz), so a Modbus probe at 8E1
//! reaches an HPR (8N1) garbled, as on a wire, and only a real switch of the port finds it.

mod common;

use common::emu::{EDGE, LINK, boot, command, expect_output, value};
use host_tests::emu::usart::KERNEL_CLOCK_HZ as USART_CLOCK_HZ;
use host_tests::emu::{Board, BoardOptions};
use plasma_firmware::io::Output;
use plasma_protocol::powermax::PowerSupplyModel;
use plasma_protocol::serial::PortConfig;
use plasma_sim::Model;

/// Boots against `model`, waits for the link, and returns the board with the settled STATUS
/// and ID replies.
fn detect(model: Model, expect_model: &str) -> (Board, String, String) {
    let mut board = boot(BoardOptions {
        framing_from_registers: Some(Some(USART_CLOCK_HZ)),
        ..BoardOptions::new(model)
    });
    let status = board
        .wait_status(LINK, |s| {
            value(s, "model") == Some(expect_model) && value(s, "ready") == Some("ON")
        })
        .unwrap_or_else(|e| panic!("{model} not detected as {expect_model}: {e}"));
    expect_output(&board, Output::Ready, true, EDGE);
    expect_output(&board, Output::Fault, false, EDGE);
    let id = command(&mut board, "ID");
    (board, status, id)
}

#[test]
fn a_powermax_sync_unit_is_detected() {
    let (board, status, id) = detect(Model::Sync65, "Powermax65");
    // The log names the unit as the guide does, not as the types are declared.
    let link_up = format!(
        "link up: {}",
        PowerSupplyModel::Powermax65_85_105Sync.name()
    );
    board
        .log()
        .wait_for(0, EDGE, |l| l.text == link_up)
        .unwrap_or_else(|e| panic!("no {link_up:?} in the log: {e}\n{}", board.log().tail(20)));
    assert_eq!(value(&status, "link"), Some("UP"), "{status}");
    assert_eq!(value(&status, "family"), Some("SYNC"), "{status}");
    assert_eq!(value(&status, "fault"), Some("none"), "{status}");
    assert!(
        id.starts_with("OK bridge=plasma-bridge version=0.1.0 reset=power-on"),
        "{id}"
    );
    assert!(
        id.ends_with("model=Powermax65 family=SYNC product=081335 torch=MACHINE lead_ft=25"),
        "{id}"
    );
}

#[test]
fn a_legacy_powermax_unit_is_detected() {
    let (_board, status, id) = detect(Model::Pm125, "Powermax125");
    assert_eq!(value(&status, "family"), Some("LEGACY"), "{status}");
    assert_eq!(value(&id, "link"), Some("UP"), "{id}");
    assert_eq!(value(&id, "family"), Some("LEGACY"), "{id}");
}

#[test]
fn an_hpr_unit_is_detected_after_the_port_switches_to_8n1() {
    let (board, status, id) = detect(Model::Hpr260, "HPR260");
    assert_eq!(value(&status, "family"), Some("HPR"), "{status}");
    // IDLE2 (3): ready for a start.
    assert_eq!(value(&status, "state"), Some("3"), "{status}");
    assert_eq!(value(&id, "family"), Some("HPR"), "{id}");
    // The firmware asked in Modbus at 8E1 first (unanswered), then said HELLO at 8N1.
    let trace = board.sim().trace();
    let port_of = |start: &[u8]| {
        trace
            .requests()
            .find(|f| f.bytes.starts_with(start))
            .map(|f| f.port)
            .unwrap_or_else(|| panic!("no {start:?} request:\n{}", trace.tail(20)))
    };
    assert_eq!(port_of(b":01"), PortConfig::MODBUS_DEFAULT);
    assert_eq!(port_of(b">000"), PortConfig::HPR);
}
