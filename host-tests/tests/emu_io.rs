//! End to end on the emulated board: the discrete I/O. START follows TORCH_ON within the
//! rules (a TORCH_ON held at power-up is ignored until released; 50 ms between starts), and
//! ARC_OK mirrors MOTION. The times of the 50 ms rule are the firmware's own (its log of every
//! output change); the harness's view, read through qtest, is checked too, with a tolerance.
//! Every board also checks the safety rules on what it observed when dropped.
//!
//! Two units on one line, each with its own unit set of pins: one unit's TORCH_ON starts
//! that unit only, and one unit's fault does not block another's START.
//!
//! The fault path (`plasma_tasks::safe_state::fail`) is driven through the test images' hooks:
//! a panic and a HardFault while the torch cuts make every output safe, reset the board, and
//! the next boot reports why; a TORCH_ON held through the reset does not fire the torch.

mod common;

use std::time::Duration;

use common::emu::{
    EDGE, HOLD, LINK, LINK_EVENT, boot, command, expect_held, expect_output, press_again, ready,
    ready_board, set, value, wait_logged,
};
use host_tests::emu::log::LogLine;
use host_tests::emu::safety::{GAP_TOLERANCE, START_GAP};
use host_tests::emu::{Board, BoardOptions, TestHook, Wiring};
use plasma_firmware::io::{Input, IoEvent, Output, Reason};
use plasma_firmware::platform::safe_state::ResetCause;
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

    // Released for longer than the gap: START follows the edge itself. The gap is the
    // guest's time, and a loaded host may give QEMU no CPU while the harness sleeps: a press
    // that still landed within the gap (START rises at the gap's end, "held through the gap")
    // is tried again with a longer release, up to a bound.
    let mut logged_so_far = 3;
    let mut release = Duration::from_millis(300);
    loop {
        set(&board, Input::TorchOn, false);
        expect_output(&board, Output::Start, false, EDGE);
        std::thread::sleep(release);
        set(&board, Input::TorchOn, true);
        expect_output(&board, Output::Start, true, EDGE);
        let changes = wait_logged(&board, Output::Start, logged_so_far + 2);
        let (fall, rise) = (&changes[logged_so_far], &changes[logged_so_far + 1]);
        logged_so_far += 2;
        // Not changes[0]'s reason: a first TORCH_ON within 50 ms of the I/O task's start
        // waits out the gap too, which depends on how soon the link came up.
        if rise.reason == Reason::TorchOn.as_str() {
            break;
        }
        // Only a press within the gap may wait for it: START then rose at the gap's end (as
        // late after it as the first press above may be: the I/O task's timer on a loaded host).
        assert!(
            rise.reason == Reason::StartGapElapsed.as_str()
                && rise.at_us - fall.at_us < 50_000 + 100_000,
            "{changes:?}"
        );
        assert!(release < Duration::from_secs(10), "{changes:?}");
        release *= 2;
    }
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
fn system_error_and_remote_power_are_on_their_pins() {
    let mut board = ready_board(Model::Sync65);
    // HPR manual (002_72b43a5685974c77.txt) line 51: System Error, an output of the unit,
    // "indicates that an error has occurred in the plasma system": FAULT to the CNC.
    set(&board, Input::SystemError, true);
    expect_output(&board, Output::Fault, true, EDGE);
    let status = command(&mut board, "STATUS");
    assert_eq!(value(&status, "system_error"), Some("ON"), "{status}");
    set(&board, Input::SystemError, false);
    expect_output(&board, Output::Fault, false, EDGE);
    // Line 54: Remote Power, an input of the unit, "is used to turn the power on or off".
    expect_held(
        &board,
        Output::RemotePower,
        false,
        Duration::from_millis(100),
    );
    assert_eq!(command(&mut board, "POWER ON"), "OK power=ON");
    expect_output(&board, Output::RemotePower, true, EDGE);
    assert_eq!(command(&mut board, "POWER OFF"), "OK power=OFF");
    expect_output(&board, Output::RemotePower, false, EDGE);
    board.assert_safe();
}

#[test]
fn once_a_task_stalls_the_outputs_stay_safe_until_the_reset() {
    let mut board = ready_board(Model::Sync65);
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    let mark = board.log().len();
    board.fail_on_purpose(TestHook::Stall).unwrap();
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
    // Then the watchdog resets the MCU, and the next boot says why.
    let on_at_reset = board
        .reboot_after_reset(LINK_EVENT)
        .unwrap_or_else(|e| panic!("no reset after the stall: {e}"));
    assert_eq!(on_at_reset, [], "outputs on when the MCU reset");
    assert_eq!(
        reported_reset_cause(&mut board),
        ResetCause::IndependentWatchdog.as_str()
    );
}

/// The reset cause the boot report gives on the CNC port. The tests save no settings, so
/// the boot runs the defaults (events off) and the report is `ID`'s `reset=<cause>,...`.
fn reported_reset_cause(board: &mut Board) -> String {
    let id = command(board, "ID");
    let reset = value(&id, "reset").unwrap_or_else(|| panic!("no reset= in {id}"));
    reset.split(',').next().unwrap_or_default().to_string()
}

/// Fails on purpose with `hook` while the torch cuts, with TORCH_ON held through the reset,
/// and checks the fault path end to end: every output safe when the MCU resets, the reset and
/// the boot that follows by themselves, the boot report on the CNC port, `fault_logged` in
/// the firmware's log, and no START until TORCH_ON is pressed again.
fn a_fault_while_cutting(hook: TestHook, fault_logged: impl Fn(&LogLine) -> bool) {
    let mut board = ready_board(Model::Sync65);
    // FAULT inverted: its pin is high while no fault is active, so the safe state's write on
    // the other port (GPIOC) shows too.
    assert_eq!(
        command(&mut board, "CONFIG fault_active LOW"),
        "OK fault_active=LOW"
    );
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    expect_output(&board, Output::ArcOk, true, EDGE);
    expect_output(&board, Output::Fault, true, EDGE);
    let mark = board.log().len();

    board.fail_on_purpose(hook).unwrap();
    let on_at_reset = board
        .reboot_after_reset(LINK_EVENT)
        .unwrap_or_else(|e| panic!("no reset after the {hook:?}: {e}"));
    assert_eq!(on_at_reset, [], "outputs on when the MCU reset");
    board
        .log()
        .wait_for(mark, EDGE, |l| l.level == "ERROR" && fault_logged(l))
        .unwrap_or_else(|e| panic!("the fault path's log line: {e}"));

    // The next boot says why on the CNC port.
    assert_eq!(reported_reset_cause(&mut board), ResetCause::Panic.as_str());

    // The firmware found TORCH_ON active as it started: held through the reset. The link
    // comes back, and that TORCH_ON does not fire the torch.
    let held = IoEvent::StuckTorchOnAtPowerUp.to_string();
    board
        .log()
        .wait_for(mark, LINK_EVENT, |l| l.text.ends_with(&held))
        .unwrap_or_else(|e| panic!("TORCH_ON not seen held at the boot: {e}"));
    let board = ready(board);
    expect_held(&board, Output::Start, false, Duration::from_millis(300));
    press_again(&board);
    expect_output(&board, Output::Start, true, EDGE);
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    board.assert_safe();
}

#[test]
fn a_panic_makes_the_outputs_safe_resets_and_is_reported_at_the_next_boot() {
    a_fault_while_cutting(TestHook::Panic, |l| {
        // The emulated image always logs the message and where it was raised.
        l.text.starts_with("panic: ") && l.text.contains("test_hooks.rs")
    });
}

#[test]
fn a_hard_fault_makes_the_outputs_safe_resets_and_is_reported_at_the_next_boot() {
    a_fault_while_cutting(TestHook::HardFault, |l| {
        // The faulting instruction's address: in the image's flash.
        l.text
            .strip_prefix("hard fault at pc 0x")
            .and_then(|pc| u32::from_str_radix(pc, 16).ok())
            .is_some_and(|pc| (0x0800_0000..0x0810_0000).contains(&pc))
    });
}

/// The stack runs off the bottom of SRAM2 (unmapped): the HardFault's own frame cannot be
/// stacked either, so a handler that pushed on entry would fault again at HardFault priority:
/// lockup with START on, which the silicon holds until the IWDG resets it and QEMU ends
/// itself ("qemu: fatal: Lockup: can't escalate 3 to HardFault (current priority -1)"; this
/// test then fails with "no reset after the StackOverflow", as it did with cortex-m-rt's
/// `#[exception]` handler).
#[test]
fn a_stack_overflow_makes_the_outputs_safe_resets_and_is_reported_at_the_next_boot() {
    a_fault_while_cutting(TestHook::StackOverflow, |l| {
        l.text.starts_with("hard fault: stack overflow (sp 0x0fff")
    });
}

/// Waits until unit `unit`'s `STATUS` (`@N STATUS`) shows its link up and the unit ready, then
/// its READY output.
fn wait_unit_ready(board: &mut Board, unit: usize) {
    let status = if unit == 0 {
        "STATUS".to_string()
    } else {
        format!("@{} STATUS", unit + 1)
    };
    let began = std::time::Instant::now();
    loop {
        let reply = command(board, &status);
        if reply.contains(" link=UP ") && reply.contains(" ready=ON") {
            break;
        }
        assert!(
            began.elapsed() < LINK,
            "unit {} never ready: {reply}",
            unit + 1
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    board
        .wait_unit_output(unit, Output::Ready, true, EDGE)
        .unwrap_or_else(|e| panic!("{e}"));
}

/// Drives unit `unit`'s input.
fn set_unit(board: &Board, unit: usize, input: Input, active: bool) {
    board
        .set_unit_input(unit, input, active)
        .unwrap_or_else(|e| panic!("unit {} {} {active}: {e}", unit + 1, input.as_str()));
}

/// Waits for unit `unit`'s output.
fn expect_unit_output(board: &Board, unit: usize, output: Output, on: bool) {
    board
        .wait_unit_output(unit, output, on, EDGE)
        .unwrap_or_else(|e| panic!("{e}"));
}

/// The first unit's START never came on (its edges, the boot's safe-state write included,
/// are all off).
fn assert_first_start_never_on(board: &Board) {
    let first_start = board.edges(Output::Start);
    assert!(
        first_start.iter().all(|e| !e.1),
        "the first START never came on: {first_start:?}"
    );
}

/// Two HPR260s (ids 0 and 1) on one simulated multi-drop line, each wired to its own unit set
/// of the pin table (its START to the unit's Start, the unit's Machine Motion to its MOTION):
/// the second unit's TORCH_ON starts the second unit only, and a fault on the first unit (HPR
/// error 044, which refuses a start) does not block the second's START. Every unit's START is
/// under the safety rules when the board is dropped.
#[test]
fn two_units_on_one_line_each_torch_on_starts_its_own_unit_only() {
    let options = BoardOptions {
        more_units: vec![Model::Hpr260],
        ..BoardOptions::new(Model::Hpr260)
    };
    let mut board = boot(options);
    let reply = command(&mut board, "CONFIG units HPR:0,HPR:1");
    assert!(reply.starts_with("OK units=HPR:0,HPR:1"), "{reply}");
    wait_unit_ready(&mut board, 0);
    wait_unit_ready(&mut board, 1);

    set_unit(&board, 1, Input::TorchOn, true);
    expect_unit_output(&board, 1, Output::Start, true);
    // The second unit's arc transfers: its own MOTION, its own ARC_OK.
    expect_unit_output(&board, 1, Output::ArcOk, true);
    expect_held(&board, Output::Start, false, HOLD);
    assert!(!board.output(Output::ArcOk).unwrap());
    set_unit(&board, 1, Input::TorchOn, false);
    expect_unit_output(&board, 1, Output::Start, false);
    assert_first_start_never_on(&board);

    // A fault on the first unit: its FAULT on, its START refused; the second starts.
    board.sim().inject_fault_at(0, 44).unwrap();
    board
        .wait_unit_output(0, Output::Fault, true, LINK_EVENT)
        .unwrap_or_else(|e| panic!("{e}"));
    set(&board, Input::TorchOn, true);
    std::thread::sleep(Duration::from_millis(300));
    // The second unit is ready again after its first cut's postflow (a TORCH_ON it refused
    // would stay refused until released).
    board
        .wait_unit_output(1, Output::Ready, true, LINK)
        .unwrap_or_else(|e| panic!("{e}"));
    set_unit(&board, 1, Input::TorchOn, true);
    expect_unit_output(&board, 1, Output::Start, true);
    board
        .expect_held(Output::Start, false, HOLD)
        .unwrap_or_else(|e| panic!("{e}"));
    // Each unit's fault is its own: the first's 044; the second shows at most its own warning
    // (031 START LOST: its first cut's TORCH_ON was released while the arc was on).
    let first_fault = command(&mut board, "FAULT");
    assert!(first_fault.starts_with("OK fault=044 "), "{first_fault}");
    let second_fault = command(&mut board, "@2 FAULT");
    assert!(
        second_fault.contains(" action=none ") || second_fault.starts_with("OK fault=none"),
        "{second_fault}"
    );
    set(&board, Input::TorchOn, false);
    set_unit(&board, 1, Input::TorchOn, false);
    expect_unit_output(&board, 1, Output::Start, false);
    assert_first_start_never_on(&board);
    board.assert_safe();
}
