//! Real time for the sans-IO pieces (the firmware's Bridge, a simulated unit): a wall clock in
//! their [`Instant`]s, and one inbox for everything that arrives (serial characters from
//! reader threads, stdin lines), waited on with a time-out up to the next instant the piece
//! asked to be woken. Every wait blocks in the kernel: nothing spins.

use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender};

use plasma_protocol::time::Instant;

use crate::serial::{Port, Rx, SerialError};

/// The longest wait without a look at the clock (a piece that asks for no wake-up still
/// gets polled this often).
pub const MAX_WAIT: std::time::Duration = std::time::Duration::from_millis(100);
/// How long a reader thread blocks in one read (it then simply reads again).
const READ_TICK: std::time::Duration = std::time::Duration::from_millis(200);

/// Waits up to `wait` for a line of `input` (stdin's, from a reader thread), then takes whatever
/// else has arrived (a paste, a pipe) in one go; all go to the back of `lines`. False once the
/// input has ended.
pub fn receive_lines(
    input: &Receiver<Vec<u8>>,
    wait: std::time::Duration,
    lines: &mut VecDeque<Vec<u8>>,
) -> bool {
    match input.recv_timeout(wait) {
        Ok(line) => lines.push_back(line),
        Err(RecvTimeoutError::Timeout) => {}
        Err(RecvTimeoutError::Disconnected) => return false,
    }
    lines.extend(input.try_iter());
    true
}

/// The wall clock, from zero at [`Clock::start`].
#[derive(Debug, Clone, Copy)]
pub struct Clock {
    epoch: std::time::Instant,
}

impl Clock {
    /// Time zero is now.
    pub fn start() -> Clock {
        Clock {
            epoch: std::time::Instant::now(),
        }
    }

    /// Now.
    pub fn now(&self) -> Instant {
        let micros = u64::try_from(self.epoch.elapsed().as_micros()).unwrap_or(u64::MAX);
        Instant::from_micros(micros)
    }

    /// The host instant `when` on this clock (zero if before the start).
    pub fn at(&self, when: std::time::Instant) -> Instant {
        let since = when.saturating_duration_since(self.epoch);
        Instant::from_micros(u64::try_from(since.as_micros()).unwrap_or(u64::MAX))
    }

    /// Seconds since the start, for logs.
    pub fn seconds(&self, at: Instant) -> f64 {
        at.as_micros() as f64 / 1e6
    }
}

/// Something that arrived.
#[derive(Debug)]
pub enum Arrival {
    /// Characters from serial port number `port` (in the order the reader threads were
    /// started).
    Serial {
        /// Which port.
        port: usize,
        /// What came.
        rx: Vec<Rx>,
        /// When the reader had it (before it waited its turn in the inbox): a tap with two
        /// ports orders the two directions by it.
        read_at: std::time::Instant,
    },
    /// A line from stdin (with its terminator).
    Line(Vec<u8>),
    /// Stdin ended.
    EndOfInput,
    /// A port failed (went away); its reader has stopped.
    Failed(SerialError),
}

/// Starts a thread that reads `port` and sends what comes as [`Arrival::Serial`] tagged
/// `index`; it stops when the port fails (after sending [`Arrival::Failed`]) or, once the
/// inbox is dropped, with the next characters (or the process).
pub fn spawn_reader(mut port: Port, index: usize, inbox: Sender<Arrival>) {
    std::thread::spawn(move || {
        let mut rx = Vec::new();
        loop {
            match port.read(READ_TICK, &mut rx) {
                Ok(()) if rx.is_empty() => {}
                Ok(()) => {
                    let arrival = Arrival::Serial {
                        port: index,
                        rx: std::mem::take(&mut rx),
                        read_at: std::time::Instant::now(),
                    };
                    if inbox.send(arrival).is_err() {
                        return;
                    }
                }
                Err(e) => {
                    let _ = inbox.send(Arrival::Failed(e));
                    return;
                }
            }
        }
    });
}

/// Starts a thread that sends stdin's lines, then [`Arrival::EndOfInput`].
pub fn spawn_stdin(inbox: Sender<Arrival>) {
    std::thread::spawn(move || {
        let mut stdin = std::io::stdin().lock();
        while let Ok(Some(line)) = crate::sim::read_line(&mut stdin) {
            if inbox.send(Arrival::Line(line)).is_err() {
                return;
            }
        }
        let _ = inbox.send(Arrival::EndOfInput);
    });
}

/// Waits for the next arrival until `wake` (at most [`MAX_WAIT`]); `None` when the time came
/// first (or every sender has gone).
pub fn wait(inbox: &Receiver<Arrival>, clock: &Clock, wake: Option<Instant>) -> Option<Arrival> {
    let now = clock.now();
    let timeout = wake
        .map(|at| std::time::Duration::from_micros(at.saturating_since(now).as_micros()))
        .unwrap_or(MAX_WAIT)
        .min(MAX_WAIT);
    match inbox.recv_timeout(timeout) {
        Ok(arrival) => Some(arrival),
        Err(RecvTimeoutError::Timeout) => None,
        Err(RecvTimeoutError::Disconnected) => {
            std::thread::sleep(timeout);
            None
        }
    }
}
