//! `pbtool emu --cnc-port DEV`: the emulated board's CNC UART on a serial device (a pty, an
//! adapter), so CNC software (LinuxCNC's pmx485, a terminal) talks to the firmware itself.
//!
//! QEMU's socket carries bytes and the device carries them to the CNC; the relay between them
//! plays the wire:
//! - at start the board is told the CNC's framing (`--cnc-framing`) the way a user tells it,
//!   with `CONFIG cnc_baud`, `cnc_parity` and `cnc_stop_bits` on its CNC port, and the relay
//!   waits until USART2's registers show it; what the CNC sent meanwhile is dropped (the
//!   board was not listening yet), and the relay starts in a pause of the CNC's line;
//! - a chunk passes only if USART2's registers say the board runs the CNC's framing: when it
//!   arrives, for the CNC's characters (the board's receiver must match); for the board's,
//!   when it arrives or at a look at most [`SENT_BEFORE_A_SWITCH`] earlier. QEMU transmits
//!   in no time, so the board switches right after its reply to `CONFIG cnc_baud ...`
//!   has gone, before the relay has read all of it; on a wire the reply would take its
//!   transmission time at the old framing. After the switch the two ends no longer
//!   understand each other, as on a real line (which garbles the characters; the relay drops
//!   them and says so on stderr).

use std::fmt;
use std::io::Write;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use host_tests::emu::Board;
use plasma_firmware::settings::Settings;
use plasma_protocol::cnc::ConfigKey;
use plasma_protocol::serial::PortConfig;

use super::EmuUnit;
use super::console::{REPLY_TIMEOUT, SETTLE_TIMEOUT, settle};
use crate::realtime::{Arrival, spawn_reader};
use crate::serial::{Port, Rx, SerialError, describe};

/// How long the board may take to switch its UART after the CONFIG replies.
const SWITCH_TIMEOUT: Duration = Duration::from_secs(2);
/// How long after a look that saw the framings match the board's bytes still pass: the rest
/// of what it wrote before it switched (pmx485 gives up on a reply after 100 ms anyway).
const SENT_BEFORE_A_SWITCH: Duration = Duration::from_millis(100);
/// A pause on the CNC's line this long is taken for one between two requests.
const QUIET_GAP: Duration = Duration::from_millis(40);
/// How long stale input is dropped at most, for a CNC that never pauses.
const STALE_BOUND: Duration = Duration::from_secs(2);
/// The longest pause between two looks at the firmware's log.
const TICK: Duration = Duration::from_millis(100);

/// How `pbtool emu --cnc-port` runs.
#[derive(Debug, Clone, PartialEq)]
pub struct CncPortOptions {
    /// The simulated unit.
    pub unit: EmuUnit,
    /// The firmware's log on stderr.
    pub log: bool,
    /// The CNC's framing: the device is opened at it and the board is set to it.
    pub framing: PortConfig,
}

/// Why the relay stopped.
#[derive(Debug)]
pub enum RelayError {
    /// The serial device failed (missing, busy, gone).
    Serial(SerialError),
    /// The emulated board failed (QEMU, its sockets, a refused setting).
    Board(host_tests::emu::Error),
}

impl fmt::Display for RelayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RelayError::Serial(e) => e.fmt(f),
            RelayError::Board(e) => e.fmt(f),
        }
    }
}

impl From<SerialError> for RelayError {
    fn from(e: SerialError) -> Self {
        RelayError::Serial(e)
    }
}

impl From<host_tests::emu::Error> for RelayError {
    fn from(e: host_tests::emu::Error) -> Self {
        RelayError::Board(e)
    }
}

/// What reached the relay.
enum Relay {
    /// Characters from the CNC's device.
    FromCnc(Vec<Rx>),
    /// Bytes the board wrote.
    FromBoard(Vec<u8>),
    /// The device failed.
    CncFailed(SerialError),
    /// The board's CNC socket closed (QEMU stopped).
    BoardClosed,
}

/// Opens `device`, boots the board, sets its CNC framing and relays until the device or the
/// board fails (or the process is stopped). `err` gets the notes and, with `log`, the
/// firmware's log.
pub fn run(options: &CncPortOptions, device: &str, err: &mut dyn Write) -> RelayError {
    match relay(options, device, err) {
        Ok(never) => match never {},
        Err(e) => e,
    }
}

fn relay(
    options: &CncPortOptions,
    device: &str,
    err: &mut dyn Write,
) -> Result<std::convert::Infallible, RelayError> {
    // The device first: a missing port is reported before QEMU starts.
    let mut port = Port::open(device, options.framing)?;
    let reader = port.try_clone()?;
    let mut board = options.unit.boot()?;
    if !settle(&mut board, options.unit.count())? {
        note(
            err,
            &format!(
                "the simulated units were not all found within {} s; relaying without them",
                SETTLE_TIMEOUT.as_secs()
            ),
        );
    }
    set_cnc_framing(&mut board, options.framing)?;
    note(
        err,
        &format!(
            "the firmware on the emulated board against a simulated {}; its CNC port on {device} \
             at {}. Ctrl-C quits.",
            options.unit.model,
            describe(options.framing)
        ),
    );

    let stale = drop_stale_input(&mut port)?;
    if stale > 0 {
        note(
            err,
            &format!("dropped {stale} characters the CNC sent while the board was booting"),
        );
    }
    let (relay_tx, inbox) = mpsc::channel();
    forward_device(reader, relay_tx.clone());
    forward_board(board.cnc().tap(), relay_tx);
    let mut printed = 0;
    // The last look at USART2 (what the board ran), and the last that saw the CNC's framing.
    let mut board_ran = Some(options.framing);
    let mut matched_at = Instant::now();
    loop {
        if options.log {
            // A closed stderr only loses the log.
            let _ = super::print_log(&board, &mut printed, err);
        }
        let arrival = match inbox.recv_timeout(TICK) {
            Ok(arrival) => arrival,
            Err(RecvTimeoutError::Timeout) => {
                if look(&board, options.framing, &mut board_ran, err)? {
                    matched_at = Instant::now();
                }
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => return Err(board_closed()),
        };
        let (bytes, to_board) = match arrival {
            Relay::FromCnc(rx) => (
                // A flagged character cannot be handed to QEMU's USART; a pty never flags one.
                rx.into_iter()
                    .filter_map(|r| match r {
                        Rx::Byte(b) => Some(b),
                        Rx::Error => None,
                    })
                    .collect::<Vec<u8>>(),
                true,
            ),
            Relay::FromBoard(bytes) => (bytes, false),
            Relay::CncFailed(e) => return Err(e.into()),
            Relay::BoardClosed => return Err(board_closed()),
        };
        let passes = if look(&board, options.framing, &mut board_ran, err)? {
            matched_at = Instant::now();
            true
        } else {
            !to_board && matched_at.elapsed() <= SENT_BEFORE_A_SWITCH
        };
        if !passes || bytes.is_empty() {
            continue;
        }
        if to_board {
            board.cnc().send_bytes(&bytes)?;
        } else {
            port.write_all(&bytes)?;
        }
    }
}

/// Drops what the CNC sent while the board booted, and starts between two of its requests;
/// the number of characters dropped.
///
/// A master that polled all along (pmx485) would otherwise have its old requests answered
/// late, take each reply for the next request's and fall behind (it catches up only when it
/// reopens its port). A board powered up now would not have heard them either. What the
/// port's queue and any cable or relay before it still hold arrives at once: the CNC's
/// characters are dropped until the line has been quiet for [`QUIET_GAP`] (pmx485 waits
/// 100 ms for each reply), or for at most [`STALE_BOUND`].
fn drop_stale_input(port: &mut Port) -> Result<usize, SerialError> {
    let began = Instant::now();
    let mut dropped = Vec::new();
    loop {
        let before = dropped.len();
        port.read(QUIET_GAP, &mut dropped)?;
        if dropped.len() == before || began.elapsed() > STALE_BOUND {
            return Ok(dropped.len());
        }
    }
}

/// The board's CNC port runs `framing` once its CONFIG replies are OK and USART2 shows it.
fn set_cnc_framing(board: &mut Board, framing: PortConfig) -> Result<(), RelayError> {
    let mut wanted = Settings::default();
    wanted.cnc.framing = framing;
    for key in [
        ConfigKey::CncBaud,
        ConfigKey::CncDataBits,
        ConfigKey::CncParity,
        ConfigKey::CncStopBits,
    ] {
        let line = format!("CONFIG {} {}", key.name(), wanted.get(key));
        let reply = board.command(&line, REPLY_TIMEOUT)?;
        if !reply.starts_with("OK ") {
            return Err(host_tests::emu::Error::Protocol(format!(
                "the board answered {line:?} with {reply:?}"
            ))
            .into());
        }
    }
    let began = Instant::now();
    loop {
        let runs = board.cnc_framing(framing.baud)?;
        if runs == Some(framing) {
            return Ok(());
        }
        if began.elapsed() > SWITCH_TIMEOUT {
            return Err(host_tests::emu::Error::Protocol(format!(
                "the board's CNC UART runs {}, not {}, {} s after the CONFIG",
                runs.map_or("nothing".to_string(), describe),
                describe(framing),
                SWITCH_TIMEOUT.as_secs()
            ))
            .into());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Whether the board's CNC UART runs `cnc` now. Each change from `board_ran` (the last look)
/// is noted on `err`: a CONFIG passes through "nothing" (the UART off while it is set up), so
/// the framing it ends at gets its own note.
fn look(
    board: &Board,
    cnc: PortConfig,
    board_ran: &mut Option<PortConfig>,
    err: &mut dyn Write,
) -> Result<bool, RelayError> {
    let board_runs = board.cnc_framing(cnc.baud)?;
    let now = board_runs == Some(cnc);
    if board_runs != *board_ran {
        note(err, &mismatch_note(now, board_runs, cnc));
        *board_ran = board_runs;
    }
    Ok(now)
}

fn mismatch_note(matched: bool, board_runs: Option<PortConfig>, cnc: PortConfig) -> String {
    if matched {
        return format!(
            "the board's CNC UART runs {} again: relaying",
            describe(cnc)
        );
    }
    format!(
        "the board's CNC UART now runs {}, the CNC's line {}: characters are lost until they \
         match (set --cnc-framing to the board's, or CONFIG it back)",
        board_runs.map_or("nothing".to_string(), describe),
        describe(cnc)
    )
}

fn board_closed() -> RelayError {
    RelayError::Board(host_tests::emu::Error::Exited(
        "the emulated board's CNC port closed".to_string(),
    ))
}

fn note(err: &mut dyn Write, text: &str) {
    let _ = writeln!(err, "pbtool emu: {text}");
}

/// The device's characters (its reader thread's arrivals) as relay events.
fn forward_device(reader: Port, relay: Sender<Relay>) {
    let (inbox, arrivals) = mpsc::channel();
    spawn_reader(reader, 0, inbox);
    std::thread::spawn(move || {
        for arrival in arrivals {
            let event = match arrival {
                Arrival::Serial { rx, .. } => Relay::FromCnc(rx),
                Arrival::Failed(e) => Relay::CncFailed(e),
                Arrival::Line(_) | Arrival::EndOfInput => continue,
            };
            if relay.send(event).is_err() {
                return;
            }
        }
    });
}

/// The board's bytes (the CNC port's tap) as relay events; [`Relay::BoardClosed`] at the end.
fn forward_board(tap: Receiver<Vec<u8>>, relay: Sender<Relay>) {
    std::thread::spawn(move || {
        for bytes in tap {
            if relay.send(Relay::FromBoard(bytes)).is_err() {
                return;
            }
        }
        let _ = relay.send(Relay::BoardClosed);
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::serial::{Parity, StopBits};

    #[test]
    fn a_mismatch_says_both_framings_and_what_to_do() {
        let cnc = PortConfig::MODBUS_DEFAULT;
        let board = PortConfig::new(9600, Parity::None, StopBits::One);
        let text = mismatch_note(false, Some(board), cnc);
        assert!(text.contains(&describe(board)), "{text}");
        assert!(text.contains(&describe(cnc)), "{text}");
        assert!(text.contains("--cnc-framing"), "{text}");
        assert!(mismatch_note(true, Some(cnc), cnc).ends_with("again: relaying"));
    }
}
