//! End to end on the emulated board: the discrete I/O. START follows TORCH_ON within the
//! rules (a TORCH_ON held at power-up is ignored until released; 50 ms between starts), and
//! ARC_OK mirrors MOTION. The times of the 50 ms rule are the firmware's own (its log of every
//! output change); the harness's view, read through qtest, is checked too, with a tolerance.
//! Every board also checks the safety rules on what it observed when dropped.

mod common;

use std::time::Duration;

use common::emu::{
    EDGE, HOLD, LINK_EVENT, boot, command, expect_held, expect_output, press_again, ready,
    ready_board, set, wait_logged,
};
use host_tests::emu::safety::{GAP_TOLERANCE, START_GAP};
use host_tests::emu::{BoardOptions, Wiring};
use plasma_firmware::io::{Input, Output};
use plasma_sim::Model;

#[test]
fn start_follows_torch_on_and_keeps_50_ms_between_starts() {
    let board = ready_board(Model::Sync65);
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    // The unit is wired: its arc transfers, MOTION comes, ARC_OK follows.
    expect_output(&board, Output::ArcOk, true, EDGE);
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    expect_output(&board, Output::ArcOk, false, EDGE);

    // At once again: START waits for the end of the 50 ms gap, then follows.
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    let changes = wait_logged(&board, Output::Start, 3);
    let (fall, rise) = (&changes[1], &changes[2]);
    assert!(!fall.on && rise.on, "{changes:?}");
    let gap_us = rise.at_us - fall.at_us;
    assert!(
        gap_us >= 50_000,
        "START rose {gap_us} us after it fell: {changes:?}"
    );
    // ...and not much later than the gap: it was delayed, not refused.
    assert!(gap_us < 50_000 + 100_000, "{changes:?}");
    // The harness saw the same edges (its times carry the host's scheduling jitter).
    let edges = board.edges(Output::Start);
    assert_eq!(
        edges.iter().map(|e| e.1).collect::<Vec<_>>(),
        [true, false, true]
    );
    let seen = edges[2].0.duration_since(edges[1].0);
    assert!(seen + GAP_TOLERANCE >= START_GAP, "{seen:?}");

    // Released for longer than the gap: START follows the edge itself.
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    // Well over 50 ms of the guest's clock, which may run slower than the host's.
    std::thread::sleep(Duration::from_millis(300));
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    let changes = wait_logged(&board, Output::Start, 5);
    assert_eq!(changes[4].reason, changes[0].reason, "{changes:?}");
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    board.assert_safe();
}

#[test]
fn a_torch_on_held_at_power_up_is_ignored_until_released() {
    let board = ready(boot(BoardOptions {
        active_at_power_up: vec![Input::TorchOn],
        ..BoardOptions::new(Model::Sync65)
    }));
    // The link is up and the unit ready, and still no START.
    expect_held(&board, Output::Start, false, Duration::from_millis(300));
    press_again(&board);
    expect_output(&board, Output::Start, true, EDGE);
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    // The firmware's log: one START on, one off, nothing before the release.
    let changes = wait_logged(&board, Output::Start, 2);
    assert_eq!(
        changes.iter().map(|c| c.on).collect::<Vec<_>>(),
        [true, false]
    );
    board.assert_safe();
}

#[test]
fn arc_ok_mirrors_motion() {
    let board = ready(boot(BoardOptions {
        wiring: Wiring::Manual,
        ..BoardOptions::new(Model::Sync65)
    }));
    // MOTION without our START is not our arc.
    set(&board, Input::Motion, true);
    expect_held(&board, Output::ArcOk, false, Duration::from_millis(100));
    set(&board, Input::Motion, false);
    std::thread::sleep(HOLD);

    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    for _ in 0..3 {
        set(&board, Input::Motion, true);
        expect_output(&board, Output::ArcOk, true, EDGE);
        set(&board, Input::Motion, false);
        expect_output(&board, Output::ArcOk, false, EDGE);
    }
    // ARC_OK drops with START.
    set(&board, Input::Motion, true);
    expect_output(&board, Output::ArcOk, true, EDGE);
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    expect_output(&board, Output::ArcOk, false, EDGE);
    // The firmware logged exactly these changes: four on, four off, alternating.
    let changes = wait_logged(&board, Output::ArcOk, 8);
    let levels: Vec<bool> = changes.iter().map(|c| c.on).collect();
    assert_eq!(levels, [true, false].repeat(4), "{changes:?}");
    set(&board, Input::Motion, false);
    board.assert_safe();
}

#[test]
fn wiring_changes_on_the_running_board_never_fire_and_never_touch_start() {
    let mut board = ready_board(Model::Sync65);
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    // TORCH_ON's debounce changes during the cut: START drops, the held press is ignored.
    assert_eq!(
        command(&mut board, "CONFIG torch_on_debounce_ms 3"),
        "OK torch_on_debounce_ms=3"
    );
    expect_output(&board, Output::Start, false, EDGE);
    expect_held(&board, Output::Start, false, Duration::from_millis(200));
    press_again(&board);
    expect_output(&board, Output::Start, true, EDGE);
    // FAULT inverted while cutting: its pin goes high (the harness reads pins by the table,
    // so "on"), START stays as it is.
    assert_eq!(
        command(&mut board, "CONFIG fault_active LOW"),
        "OK fault_active=LOW"
    );
    expect_output(&board, Output::Fault, true, EDGE);
    expect_held(&board, Output::Start, true, Duration::from_millis(100));
    assert!(command(&mut board, "CONFIG start_active LOW").starts_with("ERR SYNTAX"));
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    board.assert_safe();
}

#[test]
fn once_a_task_stalls_the_outputs_stay_safe_until_the_reset() {
    let board = ready_board(Model::Sync65);
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    let mark = board.log().len();
    board.stall_thread_mode().unwrap();
    // The bridge task stops reporting: the watchdog makes the outputs safe at once...
    board
        .log()
        .wait_for(mark, LINK_EVENT, |l| l.text.contains("silent for"))
        .unwrap_or_else(|e| panic!("{e}\n{}", board.log().tail(20)));
    expect_output(&board, Output::Start, false, EDGE);
    // ...and they stay safe until the reset, although the I/O task runs on (its own
    // executor) with TORCH_ON active, released and pressed again. The reset comes about a
    // second of guest time after the trip; the checks below take less host time than that,
    // and the guest's clock never runs faster than the host's.
    expect_held(&board, Output::Start, false, Duration::from_millis(200));
    set(&board, Input::TorchOn, false);
    expect_held(&board, Output::Start, false, Duration::from_millis(100));
    set(&board, Input::TorchOn, true);
    expect_held(&board, Output::Start, false, Duration::from_millis(200));
}
