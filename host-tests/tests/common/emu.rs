//! Helpers of the end-to-end tests on the emulated board (tests/emu_*.rs).
//!
//! Waits are "until the condition or a generous time-out": the emulated board runs slower
//! than a real one on a loaded machine, and a test must not depend on that.

use std::time::Duration;

use host_tests::emu::log::{LoggedTransition, parse_transition};
use host_tests::emu::pins::input_pin;
use host_tests::emu::{Board, BoardOptions};
use plasma_firmware::io::{Input, Output};
use plasma_sim::Model;

// Bounds on host time for what the firmware does on its own clock: generous, because on a
// loaded 2-core machine QEMU may get no CPU for seconds (a 3 s EDGE and a 15 s LINK_EVENT were
// each overrun once by a run at low priority beside other builds). A passing test never waits
// them out.
/// Link detection: a few hundred ms on an idle machine.
pub const LINK: Duration = Duration::from_secs(60);
/// One CNC reply (SET commands wait for the unit).
pub const REPLY: Duration = Duration::from_secs(30);
/// One output change the firmware makes at once (an edge, an interrupt, a GPIO write).
pub const EDGE: Duration = Duration::from_secs(20);
/// A poll cycle of the link and what follows from it (a fault seen, a link lost, a reset).
pub const LINK_EVENT: Duration = Duration::from_secs(60);

/// Boots the board; a missing QEMU or image fails the test with the reason (and how to
/// install QEMU).
pub fn boot(options: BoardOptions) -> Board {
    Board::boot(options).unwrap_or_else(|e| panic!("cannot run the emulated board: {e}"))
}

/// Boots with `model` (unit wired) and waits until the link is up and the unit ready.
pub fn ready_board(model: Model) -> Board {
    ready(boot(BoardOptions::new(model)))
}

/// Waits until the link is up and READY is on; returns the board.
pub fn ready(mut board: Board) -> Board {
    board
        .wait_status(LINK, |s| s.contains(" link=UP ") && s.contains(" ready=ON"))
        .unwrap_or_else(|e| panic!("the unit never became ready: {e}"));
    board
        .wait_output(Output::Ready, true, EDGE)
        .unwrap_or_else(|e| panic!("{e}"));
    // The unit's limits (or an HPR's state) are read just after the link comes up.
    let began = std::time::Instant::now();
    while !command(&mut board, "LIMITS").starts_with("OK ") {
        assert!(began.elapsed() < LINK, "the unit's limits were never read");
        std::thread::sleep(Duration::from_millis(50));
    }
    board
}

/// Sends `line` and returns its reply.
pub fn command(board: &mut Board, line: &str) -> String {
    board
        .command(line, REPLY)
        .unwrap_or_else(|e| panic!("{line}: {e}"))
}

/// Waits for an event line starting with `prefix` after event index `mark`.
pub fn event(board: &mut Board, mark: usize, prefix: &str, timeout: Duration) -> String {
    board
        .cnc()
        .wait_event(mark, prefix, timeout)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The number of events received so far (a mark for [`event`]).
pub fn events_mark(board: &mut Board) -> usize {
    board
        .cnc()
        .collect_events()
        .unwrap_or_else(|e| panic!("{e}"));
    board.cnc().events().len()
}

/// Drives an input.
pub fn set(board: &Board, input: Input, active: bool) {
    board
        .set_input(input, active)
        .unwrap_or_else(|e| panic!("{} {active}: {e}", input.as_str()));
}

/// How long the harness holds an input level it wants the firmware to see: well above the
/// inputs' debounce (about 1 ms on TORCH_ON, 2 ms on MOTION). A stimulus, not an assertion.
pub const HOLD: Duration = Duration::from_millis(20);

/// Releases TORCH_ON and presses it again, each level held for [`HOLD`]. The firmware must
/// see the release: a host-time sleep alone does not promise that (on a loaded machine QEMU
/// may get no CPU for those 20 ms, and then meets both levels at once), so first the
/// release's edge must have been taken (its EXTI handler clears the line's pending bit).
pub fn press_again(board: &Board) {
    set(board, Input::TorchOn, false);
    wait_edge_taken(board, Input::TorchOn);
    std::thread::sleep(HOLD);
    set(board, Input::TorchOn, true);
}

/// Waits until the firmware's EXTI handler has taken the last edge of `input` (EXTI_PR1's
/// bit for the pin is clear; the harness's pin change set it).
fn wait_edge_taken(board: &Board, input: Input) {
    const EXTI_PR1: u64 = 0x4001_0414;
    let line = 1u32 << input_pin(input).number;
    let began = std::time::Instant::now();
    while board.qtest().readl(EXTI_PR1).unwrap() & line != 0 {
        assert!(began.elapsed() < EDGE, "the {input:?} edge was never taken");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Waits for an output to reach `on`.
pub fn expect_output(board: &Board, output: Output, on: bool, timeout: Duration) {
    board
        .wait_output(output, on, timeout)
        .unwrap_or_else(|e| panic!("{e}"));
}

/// Checks that an output stays `on` for `duration`.
pub fn expect_held(board: &Board, output: Output, on: bool, duration: Duration) {
    board
        .expect_held(output, on, duration)
        .unwrap_or_else(|e| panic!("{e}"));
}

/// The output changes the firmware logged so far, for `output`.
pub fn logged(board: &Board, output: Output) -> Vec<LoggedTransition> {
    board
        .log()
        .lines()
        .iter()
        .filter_map(|l| parse_transition(&l.text))
        .filter(|t| t.output == output.as_str())
        .collect()
}

/// Waits until the firmware has logged at least `count` changes of `output`.
pub fn wait_logged(board: &Board, output: Output, count: usize) -> Vec<LoggedTransition> {
    let began = std::time::Instant::now();
    loop {
        let changes = logged(board, output);
        if changes.len() >= count {
            return changes;
        }
        assert!(
            began.elapsed() < EDGE,
            "only {} changes of {} logged, expected {count}",
            changes.len(),
            output.as_str()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The value of `key=` in a reply line (up to the next space).
pub fn value<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    line.split(' ')
        .find_map(|word| word.strip_prefix(key)?.strip_prefix('='))
}
