//! `pbtool emu`: the firmware image on the emulated board with simulated units, and the CNC
//! port on stdin/stdout, like `pbtool sim` (whose rules it follows: the first command once
//! every unit's link is up and its limits are read, one command at a time, every line the
//! board writes printed as it arrives; `@N` addresses unit N). `TORCH ON` / `TORCH OFF` (`@N
//! TORCH ON`: unit N's) are not sent to the board: they drive its TORCH_ON input pin (unit
//! N's set's), as the CNC's output would. With `log`, the firmware's own log goes to stderr.

use std::collections::VecDeque;
use std::io::{self, Write};
use std::sync::mpsc::Receiver;
use std::time::{Duration, Instant};

use plasma_firmware::io::{Input, Output};

use host_tests::emu::pins::UNIT_SETS;
use host_tests::emu::{Board, Error, Result};

use super::EmuUnit;
use crate::realtime::receive_lines;

/// The longest wait for the link (and the unit's limits) before the first command.
pub(crate) const SETTLE_TIMEOUT: Duration = Duration::from_secs(10);
/// The longest wait for one reply.
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(10);
/// How long `TORCH ON|OFF` waits for START to follow before it answers anyway.
const TORCH_SETTLE: Duration = Duration::from_millis(200);
/// How long the console keeps printing after the last reply at the end of input.
const LINGER: Duration = Duration::from_millis(200);
/// The longest pause between two looks at the CNC port, stdin and the log.
const TICK: Duration = Duration::from_millis(10);

/// Why TORCH works here although the board's HELP says `simulator=NO`.
pub const TORCH_NOTE: &str = "pbtool emu: TORCH ON|OFF also work here: pbtool, not the board, \
    takes them and drives the board's TORCH_ON input pin as the CNC's output would \
    (the board's HELP lists TORCH as simulator_only, and the board is no simulator)";

/// How `pbtool emu` runs.
#[derive(Debug, Clone, PartialEq)]
pub struct EmuConsoleOptions {
    /// The simulated unit.
    pub unit: EmuUnit,
    /// Event lines on from the start.
    pub events: bool,
    /// The firmware's log on stderr.
    pub log: bool,
    /// Set the board's wall clock to this (unix seconds, UTC) at start (`pbtool run`).
    pub clock: Option<u32>,
}

/// What a console input line asks for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ConsoleLine {
    /// Nothing (a blank line).
    Blank,
    /// Drive unit `unit`'s TORCH_ON (0 = the first; `@N TORCH ON|OFF` is unit N's).
    Torch {
        /// The unit, from 0.
        unit: usize,
        /// The level: the CNC asks for the arc.
        on: bool,
    },
    /// Send to the board's CNC port.
    Cnc(String),
}

/// Sorts an input line (terminator included or not).
pub fn classify(line: &[u8]) -> ConsoleLine {
    let text = String::from_utf8_lossy(line);
    let text = text.trim_end_matches(['\r', '\n']);
    let words: Vec<String> = text
        .split_ascii_whitespace()
        .map(str::to_ascii_uppercase)
        .collect();
    let words: Vec<&str> = words.iter().map(String::as_str).collect();
    // `@N ` in front addresses unit N (N from 1), as on the CNC port.
    let (unit, command) = match words.split_first() {
        Some((first, rest)) => match first.strip_prefix('@').map(str::parse::<usize>) {
            Some(Ok(n)) if n >= 1 => (n - 1, rest),
            _ => (0, words.as_slice()),
        },
        None => return ConsoleLine::Blank,
    };
    match command {
        ["TORCH", "ON"] => ConsoleLine::Torch { unit, on: true },
        ["TORCH", "OFF"] => ConsoleLine::Torch { unit, on: false },
        _ => ConsoleLine::Cnc(text.to_string()),
    }
}

/// Boots the board and runs the console until the end of `input` (a reader thread's
/// channel, closed at end of input) and the last reply.
pub fn run(
    options: &EmuConsoleOptions,
    input: Receiver<Vec<u8>>,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> Result<()> {
    let io = |e: io::Error| Error::io("writing the console", e);
    let mut board = options.unit.boot()?;
    let mut log_printed = 0;
    let mut print_log = |board: &Board, err: &mut dyn Write| -> Result<()> {
        if options.log {
            super::print_log(board, &mut log_printed, err).map_err(io)?;
        }
        Ok(())
    };
    // Events on before the link comes up, so that `!LINK UP` is among them.
    if options.events {
        board.command("EVENTS ON", REPLY_TIMEOUT)?;
    }
    if let Some(unix_seconds) = options.clock {
        let command = crate::history::clock_command(unix_seconds);
        board.command(&command, REPLY_TIMEOUT)?;
    }
    if !settle(&mut board, options.unit.count())? {
        writeln!(
            err,
            "pbtool emu: the simulated units were not all found within {} s; commands go on \
             without them",
            SETTLE_TIMEOUT.as_secs()
        )
        .map_err(io)?;
    }
    // The events that came while waiting for the link, in order.
    for event in board.cnc().events() {
        writeln!(out, "{}", event.text).map_err(io)?;
    }
    print_log(&board, err)?;

    let mut lines: VecDeque<Vec<u8>> = VecDeque::new();
    let mut waiting: Option<Instant> = None;
    let mut ended = false;
    let mut ended_at: Option<Instant> = None;
    loop {
        // What the board said.
        loop {
            match board.cnc().next(Duration::ZERO) {
                Ok(item) => {
                    // As `pbtool sim`: ACK/NAK in front of the reply line that follows.
                    if matches!(item.text.as_str(), "<ACK>" | "<NAK>") {
                        write!(out, "{}", item.text).map_err(io)?;
                        continue;
                    }
                    writeln!(out, "{}", item.text).map_err(io)?;
                    if !item.is_event() {
                        waiting = None;
                    }
                }
                Err(Error::Timeout(_)) => break,
                Err(e) => return Err(e),
            }
        }
        out.flush().map_err(io)?;
        print_log(&board, err)?;
        if waiting.is_some_and(|since| since.elapsed() > REPLY_TIMEOUT) {
            writeln!(
                err,
                "pbtool emu: no reply within {} s",
                REPLY_TIMEOUT.as_secs()
            )
            .map_err(io)?;
            waiting = None;
        }
        // The next command, once the board is free.
        while waiting.is_none() {
            let Some(line) = lines.pop_front() else { break };
            match classify(&line) {
                ConsoleLine::Blank => {}
                // A unit the board does not drive: the board says so (`ERR RANGE`).
                ConsoleLine::Torch { unit, .. } if unit >= options.unit.count() => {
                    board.cnc().send_bytes(&line)?;
                    waiting = Some(Instant::now());
                }
                ConsoleLine::Torch { unit, .. } if unit >= UNIT_SETS => {
                    writeln!(
                        out,
                        "ERR UNSUPPORTED unit={n} the emulated board has {UNIT_SETS} unit sets: \
                         unit {n} has no TORCH_ON pin",
                        n = unit + 1
                    )
                    .map_err(io)?;
                }
                ConsoleLine::Torch { unit, on } => {
                    board.set_unit_input(unit, Input::TorchOn, on)?;
                    // Like the simulator's TORCH command, answer once the interlocks have
                    // acted: START follows at once unless a rule holds it (the 50 ms gap at
                    // most delays it).
                    let _ = board.wait_unit_output(unit, Output::Start, on, TORCH_SETTLE);
                    // As the simulator tags a reply about a unit beyond the first.
                    let tag = match unit {
                        0 => String::new(),
                        _ => format!(" unit={}", unit + 1),
                    };
                    writeln!(out, "OK torch={}{tag}", if on { "ON" } else { "OFF" }).map_err(io)?;
                }
                ConsoleLine::Cnc(command) => {
                    board.cnc().send_bytes(&line)?;
                    waiting = Some(Instant::now());
                    if command.eq_ignore_ascii_case("HELP") {
                        // The board is no simulator and says so; TORCH is this console's.
                        writeln!(err, "{TORCH_NOTE}").map_err(io)?;
                    }
                }
            }
        }
        if ended && lines.is_empty() && waiting.is_none() {
            let since = *ended_at.get_or_insert_with(Instant::now);
            if since.elapsed() >= LINGER {
                out.flush().map_err(io)?;
                return Ok(());
            }
            std::thread::sleep(TICK);
            continue;
        }
        if ended {
            std::thread::sleep(TICK);
            continue;
        }
        ended = !receive_lines(&input, TICK, &mut lines);
    }
}

/// Waits until each of the `units` has its link up and its limits (or an HPR's state) read;
/// false when that did not happen within [`SETTLE_TIMEOUT`].
pub fn settle(board: &mut Board, units: usize) -> Result<bool> {
    let began = Instant::now();
    let mut settled = 0;
    while began.elapsed() < SETTLE_TIMEOUT {
        if settled == units {
            return Ok(true);
        }
        let at = match settled {
            0 => String::new(),
            unit => format!("@{} ", unit + 1),
        };
        let status = board.command(&format!("{at}STATUS"), REPLY_TIMEOUT)?;
        if status.contains(" link=UP ")
            && board
                .command(&format!("{at}LIMITS"), REPLY_TIMEOUT)?
                .starts_with("OK ")
        {
            settled += 1;
            continue;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    Ok(settled == units)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torch_lines_drive_the_pin_and_the_rest_goes_to_the_board() {
        assert_eq!(
            classify(b"torch on\n"),
            ConsoleLine::Torch { unit: 0, on: true }
        );
        assert_eq!(
            classify(b"  TORCH   OFF \r\n"),
            ConsoleLine::Torch { unit: 0, on: false }
        );
        assert_eq!(classify(b"\r\n"), ConsoleLine::Blank);
        assert_eq!(
            classify(b"SET PROCESS CUT 45 AUTO\n"),
            ConsoleLine::Cnc("SET PROCESS CUT 45 AUTO".to_string())
        );
        assert_eq!(classify(b"TORCH\n"), ConsoleLine::Cnc("TORCH".to_string()));
    }

    #[test]
    fn an_at_n_torch_line_drives_unit_ns_pin_and_other_at_lines_go_to_the_board() {
        assert_eq!(
            classify(b"@2 TORCH ON\n"),
            ConsoleLine::Torch { unit: 1, on: true }
        );
        assert_eq!(
            classify(b"@4 torch off\n"),
            ConsoleLine::Torch { unit: 3, on: false }
        );
        // The board answers what is no unit: `@0`, `@x`, and `@N` alone.
        for line in ["@0 TORCH ON", "@x TORCH ON", "@2", "@2 ID"] {
            assert_eq!(
                classify(format!("{line}\n").as_bytes()),
                ConsoleLine::Cnc(line.to_string())
            );
        }
    }
}
