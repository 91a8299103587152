//! End to end on the emulated board: the CNC's view. A session that sets a process, a fault
//! the unit raises reaching the CNC as an event (and holding START off), and a unit that stops
//! answering taking the link down and back, with START kept off while the rules forbid it.
//! The CNC port's framing following CONFIG at once, with the port answering Modbus after.

mod common;

use std::time::{Duration, Instant};

use common::emu::{
    EDGE, LINK_EVENT, REPLY, boot, command, event, events_mark, expect_held, expect_output,
    press_again, ready_board, set, value,
};
use host_tests::emu::{Board, BoardOptions};
use plasma_firmware::io::{Input, Interlock, IoEvent, Output};
use plasma_protocol::hpr::ErrorCode as HprError;
use plasma_protocol::serial::{DataBits, Parity, PortConfig, StopBits};
use plasma_sim::Model;
use plasma_sim::powermax::Powermax;

/// Long enough that a START the firmware wrongly allowed would have come (it follows a
/// TORCH_ON edge within a few ms, or when a 50 ms gap ends).
const STAYS_OFF: Duration = Duration::from_millis(300);

#[test]
fn a_cnc_session_sets_a_process_and_reads_status() {
    let mut board = ready_board(Model::Sync65);
    assert_eq!(command(&mut board, "EVENTS ON"), "OK events=ON");
    let mark = events_mark(&mut board);
    assert_eq!(
        command(&mut board, "SET PROCESS CUT 45 AUTO"),
        "OK mode=CUT amps=45 psi=AUTO"
    );
    event(&mut board, mark, "!REMOTE ON", EDGE);
    // The event reports the pressure the unit chose for AUTO.
    event(
        &mut board,
        mark,
        "!SETTINGS applied mode=CUT amps=45 psi=",
        EDGE,
    );

    let status = command(&mut board, "STATUS");
    for (key, expected) in [
        ("link", "UP"),
        ("family", "SYNC"),
        ("remote", "ON"),
        ("mode", "CUT"),
        ("amps", "45"),
        ("fault", "none"),
        ("start", "OFF"),
        ("ready", "ON"),
    ] {
        assert_eq!(value(&status, key), Some(expected), "{key} in {status}");
    }
    // The pressure as the unit reports it: the one it chose automatically.
    let psi = value(&status, "psi").unwrap_or("-");
    assert!(
        psi == "AUTO" || psi.parse::<f64>().is_ok(),
        "psi in {status}"
    );
    // The unit got all three in one write and is under remote control.
    let (settings, remote) = board
        .sim()
        .with_unit(|unit, _| {
            let powermax = unit
                .as_any()
                .downcast_ref::<Powermax>()
                .map(Powermax::settings);
            (powermax, unit.in_remote_mode())
        })
        .unwrap();
    let settings = settings.expect("a Powermax simulator");
    assert_eq!(
        (settings.mode, settings.current, settings.pressure),
        (1, 45 * 64, 0)
    );
    assert!(remote);

    // A refusal is one ERR line; the session goes on.
    let refused = command(&mut board, "SET PROCESS CUT 400 AUTO");
    assert!(
        refused.starts_with("ERR RANGE amps 400 outside"),
        "{refused}"
    );
    assert_eq!(command(&mut board, "REMOTE OFF"), "OK remote=OFF");
    let remote = board
        .sim()
        .with_unit(|unit, _| unit.in_remote_mode())
        .unwrap();
    assert!(!remote);
    let status = command(&mut board, "STATUS");
    assert_eq!(value(&status, "remote"), Some("OFF"), "{status}");
}

/// The board keeps the history in its flash: a fault appearing and clearing and the link
/// lost and back are in `HISTORY`, and still there after a power cut, under the boot that
/// wrote them, after the new boot's reset entry. The clock is kept meanwhile.
#[test]
fn the_history_is_kept_on_the_board_across_a_power_cut() {
    let mut board = ready_board(Model::Sync65);
    assert_eq!(
        command(&mut board, "CLOCK 2026-11-26T07:30:00"),
        "OK clock=2026-11-26T07:30:00"
    );
    assert!(command(&mut board, "CLOCK").starts_with("OK clock=2026-11-26T07:3"));

    board.sim().inject_fault(500).unwrap();
    board
        .wait_status(EDGE, |s| s.contains(" fault=0-50-0 "))
        .unwrap_or_else(|e| panic!("{e}"));
    board.sim().clear_fault().unwrap();
    board
        .wait_status(EDGE, |s| s.contains(" fault=none "))
        .unwrap_or_else(|e| panic!("{e}"));
    board.sim().set_connected(false).unwrap();
    board
        .wait_status(LINK_EVENT, |s| s.contains(" link=DOWN "))
        .unwrap_or_else(|e| panic!("{e}"));
    board.sim().set_connected(true).unwrap();
    board
        .wait_status(LINK_EVENT, |s| s.contains(" link=UP "))
        .unwrap_or_else(|e| panic!("{e}"));

    let before = history(&mut board);
    let events: Vec<&str> = before.iter().map(|l| event_of(l)).collect();
    for expected in [
        "LINK_BACK",
        "LINK_LOST",
        "FAULT_CLEARED code=0-50-0",
        "FAULT code=0-50-0",
    ] {
        assert!(
            events.iter().any(|e| e.starts_with(expected)),
            "no {expected} in {before:#?}"
        );
    }
    assert!(
        events.last().is_some_and(|e| e.starts_with("RESET ")),
        "{before:#?}"
    );
    assert!(before.iter().all(|l| l.contains(" boot=0 ")), "{before:#?}");

    board.cut_power(LINK_EVENT).unwrap();
    let after = history(&mut board);
    assert!(after[0].contains(" boot=1 "), "{after:#?}");
    assert!(event_of(&after[0]).starts_with("RESET "), "{after:#?}");
    // The first boot's entries after the new boot's reset, unchanged but for the clock: the
    // running boot's entries are shown with the clock set since they were written (the reset
    // entry, written before CLOCK), an earlier boot's only with the clock they were written
    // with (the fault and the link).
    let unclocked = |lines: &[String]| -> Vec<String> {
        lines
            .iter()
            .map(|l| {
                l.split(' ')
                    .filter(|field| !field.starts_with("clock="))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect()
    };
    assert_eq!(
        unclocked(&after[1..]),
        unclocked(&before[..after.len() - 1]),
        "{before:#?}\n{after:#?}"
    );
    assert!(
        after[1..after.len() - 1]
            .iter()
            .all(|l| l.contains(" clock=2026-11-26T07:30:0")),
        "{after:#?}"
    );
    assert!(command(&mut board, "ID").starts_with("OK bridge=plasma-bridge"));
}

/// `HISTORY 16`'s entry lines, newest first, once the board answers it with its closing OK
/// line (the history task may still be scanning the flash just after a boot).
fn history(board: &mut Board) -> Vec<String> {
    let began = Instant::now();
    loop {
        let mut lines = Vec::new();
        let mut line = command(board, "HISTORY 16");
        while line.starts_with("HISTORY ") {
            lines.push(line);
            line = board
                .cnc()
                .reply(REPLY)
                .unwrap_or_else(|e| panic!("HISTORY: {e}"));
        }
        assert!(
            line.starts_with("OK history=") || line.starts_with("ERR STORAGE"),
            "{line}"
        );
        if line.starts_with("OK history=") && !lines.is_empty() {
            return lines;
        }
        assert!(began.elapsed() < LINK_EVENT, "HISTORY: {line}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// What a `HISTORY` line says happened (after ` event=`).
fn event_of(line: &str) -> &str {
    line.split(" event=").nth(1).unwrap_or(line)
}

#[test]
fn a_fault_raised_by_the_unit_reaches_the_cnc_and_holds_start_off() {
    let mut board = ready_board(Model::Sync65);
    assert_eq!(command(&mut board, "EVENTS ON"), "OK events=ON");
    let mark = events_mark(&mut board);
    let log_mark = board.log().len();
    board.sim().inject_fault(500).unwrap();
    let fault = event(&mut board, mark, "!FAULT 0-50-0", LINK_EVENT);
    // The board's log says it as the unit's panel does, not as the types are declared.
    let fault_line = "power supply fault 0-50-0 (action required)";
    logged(&board, log_mark, fault_line, |l| l == fault_line);
    assert!(fault.len() > "!FAULT 0-50-0 ".len(), "no text: {fault}");
    expect_output(&board, Output::Fault, true, EDGE);
    expect_output(&board, Output::Ready, false, EDGE);
    let status = command(&mut board, "STATUS");
    assert_eq!(value(&status, "fault"), Some("0-50-0"), "{status}");
    assert!(command(&mut board, "FAULT").starts_with("OK fault=0-50-0 action=required text="));

    // 0-50-0 requires action: TORCH_ON does not start the torch, and the CNC hears why.
    let mark = events_mark(&mut board);
    let log_mark = board.log().len();
    set(&board, Input::TorchOn, true);
    expect_held(&board, Output::Start, false, STAYS_OFF);
    event(&mut board, mark, "!START REFUSED reason=fault", EDGE);
    let refused = IoEvent::StartRefused {
        reason: Interlock::FaultRequiresAction,
    };
    let refused_line = format!(" us: {refused}");
    logged(&board, log_mark, &refused_line, |l| {
        l.starts_with("I/O event @1 at ") && l.ends_with(&refused_line)
    });

    // Cleared: the fault is gone, but the refused TORCH_ON stays refused until released.
    let mark = events_mark(&mut board);
    board.sim().clear_fault().unwrap();
    event(&mut board, mark, "!FAULT CLEARED code=0-50-0", LINK_EVENT);
    expect_output(&board, Output::Ready, true, EDGE);
    expect_output(&board, Output::Fault, false, EDGE);
    expect_held(&board, Output::Start, false, STAYS_OFF);
    press_again(&board);
    expect_output(&board, Output::Start, true, EDGE);

    // A fault during the cut drops START.
    let mark = events_mark(&mut board);
    board.sim().inject_fault(500).unwrap();
    event(&mut board, mark, "!FAULT 0-50-0", LINK_EVENT);
    expect_output(&board, Output::Start, false, EDGE);
    event(&mut board, mark, "!START DROPPED reason=fault", EDGE);
    set(&board, Input::TorchOn, false);
}

/// An HPR error's name (a packed table row) reaches the board's log through its
/// `defmt::Format` and the CNC through its `Display`: both say the table's row as written.
#[test]
fn an_hpr_errors_name_reaches_the_log_and_the_cnc_as_the_table_writes_it() {
    let mut board = ready_board(Model::Hpr260);
    assert_eq!(command(&mut board, "EVENTS ON"), "OK events=ON");
    let name = HprError(134)
        .name()
        .expect("134 is in the table")
        .to_string();
    assert_eq!(name, "CHOPPER 1 OVERCURRENT");
    let mark = events_mark(&mut board);
    let log_mark = board.log().len();
    board.sim().inject_fault(134).unwrap();
    let raised = event(&mut board, mark, "!FAULT 134", LINK_EVENT);
    assert_eq!(raised, format!("!FAULT 134 action=required text={name}"));
    let fault_line = format!("power supply fault error 134 {name} (action required)");
    logged(&board, log_mark, &fault_line, |l| l == fault_line);
    assert_eq!(
        command(&mut board, "FAULT"),
        format!("OK fault=134 action=required text={name}")
    );
}

#[test]
fn a_unit_that_stops_answering_takes_the_link_down_and_back() {
    let mut board = ready_board(Model::Pm65);
    assert_eq!(command(&mut board, "EVENTS ON"), "OK events=ON");
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);

    // The cable is cut: the link goes down and takes START with it.
    let mark = events_mark(&mut board);
    board.sim().set_connected(false).unwrap();
    let down = event(&mut board, mark, "!LINK DOWN", LINK_EVENT);
    assert!(
        down.starts_with("!LINK DOWN reason=no_answer failures="),
        "{down}"
    );
    assert!(down.ends_with("last=timeout"), "{down}");
    expect_output(&board, Output::Start, false, EDGE);
    event(&mut board, mark, "!START DROPPED reason=link_down", EDGE);
    expect_output(&board, Output::Fault, true, EDGE);
    expect_output(&board, Output::Ready, false, EDGE);
    let status = command(&mut board, "STATUS");
    assert_eq!(value(&status, "link"), Some("DOWN"), "{status}");

    // No start while the link is down, even from a fresh TORCH_ON.
    let mark = events_mark(&mut board);
    press_again(&board);
    expect_held(&board, Output::Start, false, STAYS_OFF);
    event(&mut board, mark, "!START REFUSED reason=link_down", EDGE);

    // Connected again: found again; the held TORCH_ON does not fire the torch by itself.
    let mark = events_mark(&mut board);
    board.sim().set_connected(true).unwrap();
    let up = event(&mut board, mark, "!LINK UP", LINK_EVENT);
    assert!(
        up.starts_with("!LINK UP model=Powermax") && up.ends_with(" LEGACY"),
        "{up}"
    );
    expect_output(&board, Output::Ready, true, LINK_EVENT);
    expect_output(&board, Output::Fault, false, EDGE);
    expect_held(&board, Output::Start, false, STAYS_OFF);
    press_again(&board);
    expect_output(&board, Output::Start, true, EDGE);
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
}

/// Waits until the board's CNC UART runs `wanted` (it switches once the CONFIG reply has
/// left); panics with what it runs otherwise.
fn expect_cnc_framing(board: &Board, wanted: PortConfig) {
    let deadline = std::time::Instant::now() + EDGE;
    loop {
        let now = board.cnc_framing(wanted.baud).unwrap();
        if now == Some(wanted) {
            return;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the CNC UART runs {now:?}, not {wanted:?}\n{}",
            board.log().tail(10)
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn the_cnc_framing_follows_config_at_once_and_the_port_answers_modbus_after() {
    let mut board = ready_board(Model::Sync65);
    let mut framing = PortConfig::new(115_200, Parity::None, StopBits::One);
    expect_cnc_framing(&board, framing);
    let mark = board.log().len();
    // Each reply comes at the old framing; the UART switches after it (pmx485's 19200 8E1).
    assert_eq!(
        command(&mut board, "CONFIG cnc_baud 19200"),
        "OK cnc_baud=19200"
    );
    framing.baud = 19_200;
    expect_cnc_framing(&board, framing);
    assert_eq!(
        command(&mut board, "CONFIG cnc_parity EVEN"),
        "OK cnc_parity=EVEN"
    );
    framing.parity = Parity::Even;
    expect_cnc_framing(&board, framing);
    board
        .log()
        .wait_for(mark, EDGE, |l| l.text == "CNC UART: 19200 baud 8E1")
        .unwrap_or_else(|e| panic!("{e}\n{}", board.log().tail(10)));
    // pmx485's first read, the minimum current (0x2099, function 04): 20 A x 64.
    assert_eq!(command(&mut board, ":01042099000141"), ":0104020500F4");
    assert_eq!(
        command(&mut board, "CONFIG cnc_stop_bits 2"),
        "OK cnc_stop_bits=2"
    );
    framing.stop_bits = StopBits::Two;
    expect_cnc_framing(&board, framing);
    // A Phoenix messaging port's 7 data bits (Phoenix manual, 003_610fea73110d789e.txt line
    // 7043): with parity the USART's word is 8 bits, the parity bit its top one; the port
    // still answers (QEMU carries bytes, the firmware keeps the 7 data bits of each).
    assert_eq!(
        command(&mut board, "CONFIG cnc_data_bits 7"),
        "OK cnc_data_bits=7"
    );
    framing.data_bits = DataBits::Seven;
    expect_cnc_framing(&board, framing);
    logged(&board, mark, "CNC UART at 7E2", |l| {
        l == "CNC UART: 19200 baud 7E2"
    });
    assert_eq!(command(&mut board, ":01042099000141"), ":0104020500F4");
    board.assert_safe();
}

#[test]
fn holding_b1_at_reset_restores_the_cnc_ports_default_framing_and_nothing_else() {
    let mut board = ready_board(Model::Sync65);
    let default = PortConfig::new(115_200, Parity::None, StopBits::One);
    let saved = PortConfig::new(19_200, Parity::Even, StopBits::One);
    for (line, reply) in [
        (
            "CONFIG timeout_ms 250",
            "OK timeout_ms=250 link=redetecting",
        ),
        ("CONFIG cnc_baud 19200", "OK cnc_baud=19200"),
        ("CONFIG cnc_parity EVEN", "OK cnc_parity=EVEN"),
        ("CONFIG SAVE", "OK config=saved"),
    ] {
        assert_eq!(command(&mut board, line), reply);
    }
    board.cut_power(LINK_EVENT).unwrap();
    expect_cnc_framing(&board, saved);

    // Held through a reset: the default framing, logged, and the other settings as saved.
    board.hold_user_button(true).unwrap();
    let mark = board.log().len();
    board.cut_power(LINK_EVENT).unwrap();
    expect_cnc_framing(&board, default);
    logged(&board, mark, "B1 held", |l| {
        l.starts_with("B1 held at reset")
    });
    board.hold_user_button(false).unwrap();
    assert_eq!(
        command(&mut board, "CONFIG timeout_ms"),
        "OK timeout_ms=250"
    );
    assert_eq!(command(&mut board, "CONFIG cnc_baud"), "OK cnc_baud=115200");

    // Nothing was written: without B1 the saved framing comes back.
    board.cut_power(LINK_EVENT).unwrap();
    expect_cnc_framing(&board, saved);
    board.assert_safe();
}

/// Waits for a firmware log line since `mark` for which `matches` holds (`what` names it).
fn logged(board: &Board, mark: usize, what: &str, matches: impl Fn(&str) -> bool) {
    board
        .log()
        .wait_for(mark, EDGE, |l| matches(&l.text))
        .unwrap_or_else(|e| panic!("no log line {what:?}: {e}\n{}", board.log().tail(20)));
}

/// Power cuts at random instants during `CONFIG SAVE`: the emulated board's settings flash
/// outlives the reset as flash outlives a power cut (and takes the L4's time to program and
/// erase), so each cut leaves the save done, not begun, or anywhere in between. Every boot
/// must load the settings of the last save or of the one cut, both keys of the same one,
/// never a mix and never the defaults.
#[test]
fn a_power_cut_during_config_save_leaves_the_old_or_the_new_settings() {
    const CUTS: u32 = 40;
    let mut board = boot(BoardOptions::new(Model::Sync65));
    // Two keys per version, changed together: a mix shows.
    let version = |i: u32| (10 + i, 60 + i);
    configure(&mut board, version(0));
    let began = Instant::now();
    assert_eq!(command(&mut board, "CONFIG SAVE"), "OK config=saved");
    let save_took = began.elapsed();
    assert_eq!(stored(&mut board), version(0));

    // Cut instants from a fixed seed, so a failure repeats.
    let mut noise: u32 = 0x2545_F491;
    let mut saved = version(0);
    let (mut old, mut new) = (0, 0);
    for i in 1..=CUTS {
        configure(&mut board, version(i));
        noise ^= noise << 13;
        noise ^= noise >> 17;
        noise ^= noise << 5;
        // Anywhere from before the save starts (the line takes a while to arrive) to its end
        // (the cut itself lands a few ms after the harness asks for it).
        let delay = save_took.mul_f64(f64::from(noise % 1000) / 1000.0);
        board.cnc().send("CONFIG SAVE").unwrap();
        std::thread::sleep(delay);
        board
            .cut_power(LINK_EVENT)
            .unwrap_or_else(|e| panic!("cut {i}: no boot after it: {e}"));
        let now = stored(&mut board);
        assert!(
            now == saved || now == version(i),
            "cut {i} {delay:?} into a {save_took:?} save: {now:?} loaded, expected {saved:?} or {:?}",
            version(i)
        );
        if now == saved {
            old += 1
        } else {
            new += 1
        }
        saved = now;
    }
    eprintln!(
        "{CUTS} cuts: {old} kept the old settings, {new} the new (a save takes {save_took:?})"
    );
}

/// Sets the two keys of a version.
fn configure(board: &mut Board, (arc_ok, hold): (u32, u32)) {
    assert_eq!(
        command(board, &format!("CONFIG arc_ok_debounce_ms {arc_ok}")),
        format!("OK arc_ok_debounce_ms={arc_ok}")
    );
    assert_eq!(
        command(board, &format!("CONFIG hold_debounce_ms {hold}")),
        format!("OK hold_debounce_ms={hold}")
    );
}

/// The two keys as the board has them, after a boot. Replies from before the cut (a `CONFIG
/// SAVE` answered just before it, a line cut short) may still be queued: skipped.
fn stored(board: &mut Board) -> (u32, u32) {
    let mut read = |key: &str| -> u32 {
        board.cnc().send(&format!("CONFIG {key}")).unwrap();
        loop {
            let reply = board
                .cnc()
                .reply(REPLY)
                .unwrap_or_else(|e| panic!("CONFIG {key}: {e}"));
            if let Some(v) = value(&reply, key) {
                return v.parse().unwrap_or_else(|e| panic!("{reply}: {e}"));
            }
        }
    };
    (read("arc_ok_debounce_ms"), read("hold_debounce_ms"))
}

/// The consumable record is kept in the board's settings flash: a cut the bridge counted
/// (legacy Powermax: the bridge's own count) is there after a power cut.
#[test]
fn the_consumable_count_is_kept_on_the_board_across_a_power_cut() {
    let mut board = common::emu::ready(boot(BoardOptions {
        wiring: host_tests::emu::Wiring::Manual,
        ..BoardOptions::new(Model::Pm65)
    }));
    let first = command(&mut board, "CONSUMABLES");
    assert!(
        first.starts_with("OK source=bridge starts=0 arc_s=0 "),
        "{first}"
    );
    set(&board, Input::TorchOn, true);
    expect_output(&board, Output::Start, true, EDGE);
    set(&board, Input::Motion, true);
    expect_output(&board, Output::ArcOk, true, EDGE);
    set(&board, Input::Motion, false);
    expect_output(&board, Output::ArcOk, false, EDGE);
    set(&board, Input::TorchOn, false);
    expect_output(&board, Output::Start, false, EDGE);
    board
        .wait_status(EDGE, |s| s.contains(" start=OFF motion=OFF "))
        .unwrap_or_else(|e| panic!("{e}"));
    // The first count is stored at its arc-off. A CONFIG SAVE waits for a store under way,
    // and a second one for a store taken between the two: after both it is in flash.
    for _ in 0..2 {
        assert_eq!(command(&mut board, "CONFIG SAVE"), "OK config=saved");
    }
    let counted = command(&mut board, "CONSUMABLES");
    assert!(
        counted.starts_with("OK source=bridge starts=1 "),
        "{counted}"
    );

    board.cut_power(LINK_EVENT).unwrap();
    board = common::emu::ready(board);
    let kept = command(&mut board, "CONSUMABLES");
    assert!(kept.starts_with("OK source=bridge starts=1 "), "{kept}");
    board.assert_safe();
}
