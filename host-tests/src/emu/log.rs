//! The firmware's log: defmt frames that the emulated board writes by semihosting to a file,
//! decoded against the ELF's `.defmt` table while the board runs.
//!
//! Every decoded line is kept (a failing test prints them), and tests can wait for a line
//! ([`FirmwareLog::wait_for`]), e.g. the board layer's `emu-probe:` measurements.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use defmt_decoder::{DecodeError, Encoding, Table};

use super::error::{Error, Result};

/// How often the reader looks for new bytes in the log file.
const POLL: Duration = Duration::from_millis(5);

/// One decoded log line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogLine {
    /// The guest's timestamp in microseconds, when the image logs one it can be read from.
    pub guest_us: Option<u64>,
    /// The timestamp as the firmware formats it (empty without one).
    pub timestamp: String,
    /// `TRACE`, `DEBUG`, `INFO`, `WARN`, `ERROR`, or empty for a `println`.
    pub level: String,
    /// The message.
    pub text: String,
    /// When the harness decoded it (host clock).
    pub seen: Instant,
}

impl std::fmt::Display for LogLine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if !self.timestamp.is_empty() {
            write!(f, "{} ", self.timestamp)?;
        }
        if !self.level.is_empty() {
            write!(f, "{:<5} ", self.level)?;
        }
        f.write_str(&self.text)
    }
}

/// Microseconds from a defmt timestamp as displayed: `S.uuuuuu` (`:tus`), `S.mmm` (`:tms`),
/// or a plain number of ticks (taken as microseconds).
pub fn parse_timestamp_us(text: &str) -> Option<u64> {
    let text = text.trim();
    match text.split_once('.') {
        Some((seconds, fraction)) => {
            let seconds: u64 = seconds.parse().ok()?;
            let scale = match fraction.len() {
                6 => 1,
                3 => 1_000,
                _ => return None,
            };
            let fraction: u64 = fraction.parse().ok()?;
            Some(seconds * 1_000_000 + fraction * scale)
        }
        None => text.parse().ok(),
    }
}

/// An output change the I/O task logged (`I/O 69.342 ms: READY on: link up, ...`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoggedTransition {
    /// The interlocks' own time of the change, in microseconds since boot.
    pub at_us: u64,
    /// The output's name (`START`, `ARC_OK`, `READY`, `FAULT`...).
    pub output: String,
    /// The new state.
    pub on: bool,
    /// Why.
    pub reason: String,
}

/// Parses an I/O task transition line; `None` for any other line.
pub fn parse_transition(text: &str) -> Option<LoggedTransition> {
    let rest = text.strip_prefix("I/O ")?;
    let (time, rest) = rest.split_once(" ms: ")?;
    let (whole, fraction) = time.split_once('.')?;
    if fraction.len() != 3 {
        return None;
    }
    let at_us = whole.parse::<u64>().ok()? * 1000 + fraction.parse::<u64>().ok()?;
    let (change, reason) = rest.split_once(": ").unwrap_or((rest, ""));
    let (output, state) = change.split_once(' ')?;
    let on = match state {
        "on" => true,
        "off" => false,
        _ => return None,
    };
    Some(LoggedTransition {
        at_us,
        output: output.to_string(),
        on,
        reason: reason.to_string(),
    })
}

#[derive(Default)]
struct Shared {
    lines: Vec<LogLine>,
    /// Why decoding stopped or could not start.
    error: Option<String>,
    /// Undecodable frames skipped.
    malformed: u64,
}

/// Decodes the firmware's log file while the board runs. Stops when dropped.
pub struct FirmwareLog {
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FirmwareLog {
    /// Reads the `.defmt` table of `elf` and starts following `log` (which may not exist
    /// yet).
    pub fn start(elf: &Path, log: &Path) -> Result<FirmwareLog> {
        let bytes = std::fs::read(elf)
            .map_err(|e| Error::io(format!("reading the image {}", elf.display()), e))?;
        let table = Table::parse(&bytes)
            .map_err(|e| Error::Image(format!("{}: bad defmt table: {e}", elf.display())))?
            .ok_or_else(|| {
                Error::Image(format!("{} has no .defmt section (no logs)", elf.display()))
            })?;
        let shared = Arc::new(Mutex::new(Shared::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (for_thread, stop_flag, path) =
            (Arc::clone(&shared), Arc::clone(&stop), log.to_owned());
        let thread = std::thread::Builder::new()
            .name("defmt-log".to_string())
            .spawn(move || follow(&table, &path, &stop_flag, &for_thread))
            .map_err(|e| Error::io("log thread", e))?;
        Ok(FirmwareLog {
            shared,
            stop,
            thread: Some(thread),
        })
    }

    /// Every line decoded so far.
    pub fn lines(&self) -> Vec<LogLine> {
        lock(&self.shared).lines.clone()
    }

    /// Number of lines decoded so far (a mark for [`FirmwareLog::since`]).
    pub fn len(&self) -> usize {
        lock(&self.shared).lines.len()
    }

    /// True while nothing was decoded.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Lines from index `mark` on.
    pub fn since(&self, mark: usize) -> Vec<LogLine> {
        lock(&self.shared)
            .lines
            .get(mark..)
            .map(<[LogLine]>::to_vec)
            .unwrap_or_default()
    }

    /// Waits until a line from index `mark` on satisfies `pred`; returns it.
    pub fn wait_for(
        &self,
        mark: usize,
        timeout: Duration,
        mut pred: impl FnMut(&LogLine) -> bool,
    ) -> Result<LogLine> {
        let deadline = Instant::now() + timeout;
        let mut checked = mark;
        loop {
            {
                let shared = lock(&self.shared);
                if let Some(line) = shared.lines.iter().skip(checked).find(|l| pred(l)) {
                    return Ok(line.clone());
                }
                checked = checked.max(shared.lines.len());
                if let Some(error) = &shared.error {
                    return Err(Error::Protocol(format!("firmware log: {error}")));
                }
            }
            if Instant::now() >= deadline {
                return Err(Error::Timeout(format!(
                    "no such firmware log line in {} ms",
                    timeout.as_millis()
                )));
            }
            std::thread::sleep(POLL);
        }
    }

    /// The last `n` lines, one per line of text (for failure messages).
    pub fn tail(&self, n: usize) -> String {
        let shared = lock(&self.shared);
        let skip = shared.lines.len().saturating_sub(n);
        let mut text: String = shared
            .lines
            .iter()
            .skip(skip)
            .map(|l| format!("{l}\n"))
            .collect();
        if shared.malformed > 0 {
            text.push_str(&format!(
                "({} undecodable frames skipped)\n",
                shared.malformed
            ));
        }
        if let Some(error) = &shared.error {
            text.push_str(&format!("(log decoding stopped: {error})\n"));
        }
        text
    }
}

impl Drop for FirmwareLog {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

/// The reader thread: new bytes of the file into the stream decoder, frames into lines. After
/// the stop flag, one last read (QEMU has exited: everything it wrote is in the file).
fn follow(table: &Table, path: &PathBuf, stop: &AtomicBool, shared: &Mutex<Shared>) {
    let raw = matches!(table.encoding(), Encoding::Raw);
    let mut decoder = table.new_stream_decoder();
    let mut file: Option<File> = None;
    let mut buf = vec![0u8; 4096];
    loop {
        let stopping = stop.load(Ordering::Relaxed);
        if file.is_none() {
            file = File::open(path).ok();
        }
        let mut got_any = false;
        if let Some(f) = &mut file {
            loop {
                match f.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => {
                        got_any = true;
                        decoder.received(&buf[..n]);
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        lock(shared).error = Some(format!("reading {}: {e}", path.display()));
                        return;
                    }
                }
            }
        }
        if got_any {
            loop {
                match decoder.decode() {
                    Ok(frame) => {
                        let timestamp = frame
                            .display_timestamp()
                            .map(|t| t.to_string())
                            .unwrap_or_default();
                        let line = LogLine {
                            guest_us: parse_timestamp_us(&timestamp),
                            level: frame
                                .level()
                                .map(|l| l.as_str().to_ascii_uppercase())
                                .unwrap_or_default(),
                            text: frame.display_message().to_string(),
                            timestamp,
                            seen: Instant::now(),
                        };
                        lock(shared).lines.push(line);
                    }
                    Err(DecodeError::UnexpectedEof) => break,
                    // rzCOBS resynchronises at the next frame; a raw stream cannot.
                    Err(DecodeError::Malformed) => {
                        let mut shared = lock(shared);
                        shared.malformed += 1;
                        if raw {
                            shared.error = Some("raw defmt stream out of sync".to_string());
                            return;
                        }
                    }
                }
            }
        }
        if stopping {
            return;
        }
        if !got_any {
            std::thread::sleep(POLL);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timestamps_are_read_in_microseconds() {
        assert_eq!(parse_timestamp_us("1.000250"), Some(1_000_250));
        assert_eq!(parse_timestamp_us("12.345"), Some(12_345_000));
        assert_eq!(parse_timestamp_us("7710"), Some(7_710));
        assert_eq!(parse_timestamp_us(""), None);
        assert_eq!(parse_timestamp_us("00:00:01.000250"), None);
    }

    #[test]
    fn transitions_are_read_from_the_io_log() {
        assert_eq!(
            parse_transition("I/O 69.342 ms: READY on: link up, no fault, supply ready"),
            Some(LoggedTransition {
                at_us: 69_342,
                output: "READY".to_string(),
                on: true,
                reason: "link up, no fault, supply ready".to_string()
            })
        );
        let off = parse_transition("I/O 1203.007 ms: START off: torch-on released").unwrap();
        assert_eq!(
            (off.at_us, off.output.as_str(), off.on),
            (1_203_007, "START", false)
        );
        assert_eq!(parse_transition("link up: Some(Powermax)"), None);
        assert_eq!(parse_transition("I/O 1.5 ms: START on: x"), None);
        assert_eq!(parse_transition("I/O 1.500 ms: START maybe: x"), None);
    }

    #[test]
    fn an_image_without_a_defmt_table_is_refused_clearly() {
        // Any ELF without .defmt: the test binary itself.
        let me = std::env::current_exe().unwrap();
        let err = FirmwareLog::start(&me, Path::new("/nonexistent.defmt"))
            .err()
            .expect("refused")
            .to_string();
        assert!(
            err.contains("no .defmt section") || err.contains("bad defmt table"),
            "{err}"
        );
    }
}
