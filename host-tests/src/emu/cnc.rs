//! The CNC's side of the emulated board's CNC serial port (USART2): send command lines, read
//! reply lines, collect `!` event lines (docs/cnc-protocol.md). Or, once [`CncPort::tap`]ped,
//! the board's bytes as they come, for a relay to real CNC software (`pbtool emu --cnc-port`).

use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use plasma_protocol::cnc::phoenix::{ACK, NAK};

use super::error::{Error, Result};

/// One item the board sent: a line (without its CR LF), or a Phoenix ACK / NAK byte.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Received {
    /// When the harness read it.
    pub at: Instant,
    /// The line, or `<ACK>` / `<NAK>`.
    pub text: String,
}

impl Received {
    /// True for an event line (`!...`).
    pub fn is_event(&self) -> bool {
        self.text.starts_with('!')
    }
}

/// Splits the board's output into lines (CR LF, CR or LF end a line) and ACK/NAK bytes.
#[derive(Debug, Default)]
pub struct LineSplitter {
    partial: Vec<u8>,
}

impl LineSplitter {
    /// Feeds `bytes`; returns the items they complete.
    pub fn push(&mut self, bytes: &[u8]) -> Vec<String> {
        let mut items = Vec::new();
        for &b in bytes {
            match b {
                b'\r' | b'\n' => {
                    if !self.partial.is_empty() {
                        items.push(String::from_utf8_lossy(&self.partial).into_owned());
                        self.partial.clear();
                    }
                }
                ACK => items.push("<ACK>".to_string()),
                NAK => items.push("<NAK>".to_string()),
                _ => self.partial.push(b),
            }
        }
        items
    }
}

/// Where the reader thread puts the board's raw bytes once the port is tapped.
type Tap = Arc<Mutex<Option<Sender<Vec<u8>>>>>;

/// The CNC end of the board's CNC port.
pub struct CncPort {
    writer: UnixStream,
    incoming: Receiver<Received>,
    tap: Tap,
    /// Every item received, in order (what the tests have read and what they have not).
    transcript: Arc<Mutex<Vec<(Instant, String)>>>,
    events: Vec<Received>,
}

impl CncPort {
    /// The CNC end on a connected socket (QEMU's serial1).
    pub fn new(stream: UnixStream) -> Result<CncPort> {
        let mut reader = stream.try_clone().map_err(|e| Error::io("CNC socket", e))?;
        let (tx, incoming) = mpsc::channel();
        let transcript = Arc::new(Mutex::new(Vec::new()));
        let log = Arc::clone(&transcript);
        let tap: Tap = Arc::default();
        let tapped = Arc::clone(&tap);
        std::thread::Builder::new()
            .name("cnc-reader".to_string())
            .spawn(move || {
                let mut splitter = LineSplitter::default();
                let mut buf = [0u8; 256];
                while let Ok(n) = reader.read(&mut buf) {
                    if n == 0 {
                        break;
                    }
                    if relayed(&tapped, &buf[..n]) {
                        continue;
                    }
                    let at = Instant::now();
                    for text in splitter.push(&buf[..n]) {
                        lock(&log).push((at, format!("< {text}")));
                        if tx.send(Received { at, text }).is_err() {
                            return;
                        }
                    }
                }
                // The board's port closed: so does the tap's receiver.
                lock(&tapped).take();
            })
            .map_err(|e| Error::io("CNC reader thread", e))?;
        Ok(CncPort {
            writer: stream,
            incoming,
            tap,
            transcript,
            events: Vec::new(),
        })
    }

    /// From now on every chunk the board writes goes to the returned receiver as it arrives,
    /// and no longer to [`CncPort::reply`], the events or the transcript (a relay to CNC
    /// software runs for hours: nothing accumulates). The receiver closes when the board's
    /// port does.
    pub fn tap(&mut self) -> Receiver<Vec<u8>> {
        let (tx, rx) = mpsc::channel();
        *lock(&self.tap) = Some(tx);
        rx
    }

    /// Sends `line` with CR LF.
    pub fn send(&mut self, line: &str) -> Result<()> {
        lock(&self.transcript).push((Instant::now(), format!("> {line}")));
        self.send_bytes(format!("{line}\r\n").as_bytes())
    }

    /// Sends raw bytes.
    pub fn send_bytes(&mut self, bytes: &[u8]) -> Result<()> {
        self.writer
            .write_all(bytes)
            .map_err(|e| Error::Exited(format!("writing the CNC port: {e}")))
    }

    /// The next item the board sends (event or not), within `timeout`.
    pub fn next(&mut self, timeout: Duration) -> Result<Received> {
        match self.incoming.recv_timeout(timeout) {
            Ok(item) => Ok(item),
            Err(RecvTimeoutError::Timeout) => Err(Error::Timeout(format!(
                "nothing on the CNC port in {} ms",
                timeout.as_millis()
            ))),
            Err(RecvTimeoutError::Disconnected) => {
                Err(Error::Exited("the CNC port closed".to_string()))
            }
        }
    }

    /// The next line that is not an event (events met on the way are kept, see
    /// [`CncPort::events`]).
    pub fn reply(&mut self, timeout: Duration) -> Result<String> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let item = self.next(left).map_err(|e| match e {
                Error::Timeout(_) => Error::Timeout(format!(
                    "no reply on the CNC port in {} ms",
                    timeout.as_millis()
                )),
                e => e,
            })?;
            if item.is_event() {
                self.events.push(item);
            } else {
                return Ok(item.text);
            }
        }
    }

    /// Sends `line` and returns its reply.
    pub fn command(&mut self, line: &str, timeout: Duration) -> Result<String> {
        self.send(line)?;
        self.reply(timeout).map_err(|e| match e {
            Error::Timeout(_) => Error::Timeout(format!(
                "no reply to {line:?} in {} ms",
                timeout.as_millis()
            )),
            e => e,
        })
    }

    /// Waits for an event line starting with `prefix` that arrives after index `mark` of
    /// [`CncPort::events`]; returns it. A reply line met meanwhile is an error (a command's
    /// reply should have been read by then).
    pub fn wait_event(&mut self, mark: usize, prefix: &str, timeout: Duration) -> Result<String> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(found) = self
                .events
                .get(mark..)
                .unwrap_or(&[])
                .iter()
                .find(|e| e.text.starts_with(prefix))
            {
                return Ok(found.text.clone());
            }
            let left = deadline.saturating_duration_since(Instant::now());
            match self.next(left) {
                Ok(item) if item.is_event() => self.events.push(item),
                Ok(item) => {
                    return Err(Error::Protocol(format!(
                        "waiting for {prefix:?}, got the reply {:?}",
                        item.text
                    )));
                }
                Err(Error::Timeout(_)) => {
                    return Err(Error::Timeout(format!(
                        "no {prefix:?} event in {} ms",
                        timeout.as_millis()
                    )));
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// Takes the events that have already arrived (without waiting) into [`CncPort::events`].
    pub fn collect_events(&mut self) -> Result<()> {
        while let Ok(item) = self.incoming.try_recv() {
            if item.is_event() {
                self.events.push(item);
            } else {
                return Err(Error::Protocol(format!(
                    "unexpected reply {:?} on the CNC port",
                    item.text
                )));
            }
        }
        Ok(())
    }

    /// Event lines received so far (in order).
    pub fn events(&self) -> &[Received] {
        &self.events
    }

    /// Everything sent (`> `) and received (`< `), with times relative to `epoch`.
    pub fn transcript(&self, epoch: Instant) -> String {
        lock(&self.transcript)
            .iter()
            .map(|(at, text)| {
                format!(
                    "{:>10.3} ms {text}\n",
                    at.saturating_duration_since(epoch).as_secs_f64() * 1000.0
                )
            })
            .collect()
    }
}

impl Drop for CncPort {
    fn drop(&mut self) {
        // Ends the reader thread (it holds a clone of the socket).
        let _ = self.writer.shutdown(std::net::Shutdown::Both);
    }
}

/// Hands `bytes` to the tap, if there is one; false when there is none (or its receiver has
/// gone: the port goes back to lines).
fn relayed(tap: &Tap, bytes: &[u8]) -> bool {
    let mut tap = lock(tap);
    let Some(relay) = tap.as_ref() else {
        return false;
    };
    if relay.send(bytes.to_vec()).is_ok() {
        return true;
    }
    *tap = None;
    false
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{BufRead, BufReader};

    #[test]
    fn lines_end_at_cr_lf_and_ack_nak_stand_alone() {
        let mut s = LineSplitter::default();
        assert_eq!(s.push(b"OK ev"), Vec::<String>::new());
        assert_eq!(s.push(b"ents=ON\r\n!LINK UP"), ["OK events=ON"]);
        assert_eq!(
            s.push(b"\r\n\x06\x15ERR X\n"),
            ["!LINK UP", "<ACK>", "<NAK>", "ERR X"]
        );
    }

    #[test]
    fn a_tapped_port_hands_over_raw_bytes_and_keeps_no_lines() {
        let (ours, mut theirs) = UnixStream::pair().unwrap();
        let mut cnc = CncPort::new(ours).unwrap();
        theirs.write_all(b"OK before\r\n").unwrap();
        assert_eq!(cnc.reply(Duration::from_secs(5)).unwrap(), "OK before");
        let raw = cnc.tap();
        theirs.write_all(b":010600011234B4\r\n\x06").unwrap();
        let mut got = Vec::new();
        while got.len() < 18 {
            got.extend(raw.recv_timeout(Duration::from_secs(5)).unwrap());
        }
        assert_eq!(got, b":010600011234B4\r\n\x06");
        assert!(cnc.next(Duration::from_millis(50)).is_err());
        let transcript = cnc.transcript(Instant::now());
        assert!(!transcript.contains("0106"), "{transcript}");
        cnc.send_bytes(b"ID\r\n").unwrap();
        let mut echo = [0u8; 4];
        theirs.read_exact(&mut echo).unwrap();
        assert_eq!(&echo, b"ID\r\n");
        drop(theirs);
        assert!(raw.recv_timeout(Duration::from_secs(5)).is_err());
    }

    #[test]
    fn a_command_gets_its_reply_and_events_on_the_way_are_kept() {
        let (ours, theirs) = UnixStream::pair().unwrap();
        let board = std::thread::spawn(move || {
            let mut writer = theirs.try_clone().unwrap();
            let mut lines = BufReader::new(theirs).lines();
            assert_eq!(lines.next().unwrap().unwrap(), "STATUS");
            writer
                .write_all(
                    b"!FAULT 0-50-0 cartridge\r\nOK link=UP\r\n!LINK DOWN reason=no_answer\r\n",
                )
                .unwrap();
            assert_eq!(lines.next().unwrap().unwrap(), "ID");
            // No reply: the client times out.
            let _ = lines.next();
        });
        let mut cnc = CncPort::new(ours).unwrap();
        let timeout = Duration::from_secs(5);
        assert_eq!(cnc.command("STATUS", timeout).unwrap(), "OK link=UP");
        assert_eq!(cnc.events().len(), 1);
        assert_eq!(
            cnc.wait_event(0, "!LINK DOWN", timeout).unwrap(),
            "!LINK DOWN reason=no_answer"
        );
        assert_eq!(
            cnc.wait_event(0, "!FAULT", timeout).unwrap(),
            "!FAULT 0-50-0 cartridge"
        );
        assert!(matches!(
            cnc.command("ID", Duration::from_millis(50)),
            Err(Error::Timeout(text)) if text.contains("\"ID\"")
        ));
        let transcript = cnc.transcript(Instant::now() - Duration::from_secs(1));
        assert!(transcript.contains("> STATUS\n"), "{transcript}");
        assert!(transcript.contains("< OK link=UP\n"), "{transcript}");
        drop(cnc);
        board.join().unwrap();
    }
}
