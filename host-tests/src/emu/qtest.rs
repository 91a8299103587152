//! A client of QEMU's qtest protocol: drive GPIO inputs, read registers, and receive the output
//! edges QEMU streams once a port is intercepted.
//!
//! The protocol is line based: the client sends `command args\n`; QEMU answers each command
//! with one line, `OK [values]`, `FAIL reason` or `ERR reason`. After `irq_intercept_out`, QEMU
//! also sends `IRQ raise <n>` / `IRQ lower <n>` lines whenever output line `n` of the
//! intercepted device changes, at any moment, between replies too. A reader thread sorts the
//! two: replies go to the command waiting for them, edges to [`Qtest::edges`] and the
//! subscribers.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::error::{Error, Result};
use super::pins::{Pin, Port, QemuPort};

/// How long a command may wait for its reply (QEMU answers in microseconds; a loaded machine
/// and a busy main loop can take far longer, but not this long).
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(10);

/// One line from QEMU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Line {
    /// `OK` and the words after it.
    Ok(Vec<String>),
    /// `FAIL ...` or `ERR ...`: the command was refused.
    Fail(String),
    /// An output line of the intercepted device changed.
    Irq {
        /// Output line number (for a GPIO port: the pin number).
        line: u8,
        /// The new level.
        high: bool,
    },
}

/// Parses one line QEMU sent (without its newline).
pub fn parse_line(text: &str) -> Result<Line> {
    let mut words = text.split_ascii_whitespace();
    match words.next() {
        Some("OK") => Ok(Line::Ok(words.map(str::to_string).collect())),
        Some("FAIL" | "ERR") => Ok(Line::Fail(text.trim().to_string())),
        Some("IRQ") => {
            let high = match words.next() {
                Some("raise") => true,
                Some("lower") => false,
                _ => return Err(Error::Protocol(format!("bad IRQ line {text:?}"))),
            };
            let line = words
                .next()
                .and_then(|n| n.parse::<u8>().ok())
                .ok_or_else(|| Error::Protocol(format!("bad IRQ line {text:?}")))?;
            Ok(Line::Irq { line, high })
        }
        _ => Err(Error::Protocol(format!("unexpected line {text:?}"))),
    }
}

/// Parses the value of a `readl`/`readw`/`readb` reply (`OK 0x00000001`).
pub fn parse_value(words: &[String]) -> Result<u64> {
    let text = words
        .first()
        .ok_or_else(|| Error::Protocol("read reply without a value".to_string()))?;
    let digits = text
        .strip_prefix("0x")
        .or_else(|| text.strip_prefix("0X"))
        .ok_or_else(|| Error::Protocol(format!("read value {text:?} is not hexadecimal")))?;
    u64::from_str_radix(digits, 16)
        .map_err(|_| Error::Protocol(format!("read value {text:?} is not hexadecimal")))
}

/// An output edge QEMU reported, with the host time the harness read it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    /// When the line was read (host clock; the edge happened a little earlier).
    pub at: Instant,
    /// The pin (on the intercepted port).
    pub pin: Pin,
    /// The new level.
    pub high: bool,
}

/// Everything the reader thread shares with the client.
struct Shared {
    edges: Vec<Edge>,
    subscribers: Vec<Sender<Edge>>,
    intercepted: Option<Port>,
    /// The level last driven on each input pin.
    driven: HashMap<Pin, bool>,
}

/// A qtest session. Cheap to share (`&Qtest` from several threads): commands are serialised.
pub struct Qtest {
    /// The socket to write on, and the channel of replies; locked for one command's round
    /// trip.
    session: Mutex<(UnixStream, Receiver<(Line, usize)>)>,
    shared: Arc<Mutex<Shared>>,
}

impl Qtest {
    /// A session on a connected socket (QEMU's `-qtest` chardev).
    pub fn new(stream: UnixStream) -> Result<Qtest> {
        let reader = stream
            .try_clone()
            .map_err(|e| Error::io("qtest socket", e))?;
        let shared = Arc::new(Mutex::new(Shared {
            edges: Vec::new(),
            subscribers: Vec::new(),
            intercepted: None,
            driven: HashMap::new(),
        }));
        let (replies_tx, replies_rx) = mpsc::channel();
        let for_reader = Arc::clone(&shared);
        std::thread::Builder::new()
            .name("qtest-reader".to_string())
            .spawn(move || read_lines(reader, &replies_tx, &for_reader))
            .map_err(|e| Error::io("qtest reader thread", e))?;
        Ok(Qtest {
            session: Mutex::new((stream, replies_rx)),
            shared,
        })
    }

    /// Sends one command and returns the words after its `OK`.
    pub fn command(&self, command: &str) -> Result<Vec<String>> {
        self.command_marked(command).map(|(words, _)| words)
    }

    /// As [`Qtest::command`], with the number of edges QEMU had sent before its reply: QEMU
    /// writes an edge the moment the guest makes it and answers a command once it has run, on
    /// one socket, so edges `..mark` happened before the command took effect and the rest
    /// after.
    pub fn command_marked(&self, command: &str) -> Result<(Vec<String>, usize)> {
        let session = self.session.lock().unwrap_or_else(|e| e.into_inner());
        let (stream, replies) = &*session;
        let mut writer = stream;
        writer
            .write_all(format!("{command}\n").as_bytes())
            .map_err(|e| Error::Exited(format!("qtest {command:?}: {e}")))?;
        match replies.recv_timeout(REPLY_TIMEOUT) {
            Ok((Line::Ok(words), mark)) => Ok((words, mark)),
            Ok((Line::Fail(text), _)) => Err(Error::Protocol(format!("qtest {command:?}: {text}"))),
            Ok((Line::Irq { .. }, _)) => unreachable!("the reader keeps IRQ lines apart"),
            Err(RecvTimeoutError::Timeout) => Err(Error::Timeout(format!(
                "qtest {command:?}: no reply in {} s",
                REPLY_TIMEOUT.as_secs()
            ))),
            Err(RecvTimeoutError::Disconnected) => Err(Error::Exited(format!(
                "qtest {command:?}: the socket closed"
            ))),
        }
    }

    /// Drives a GPIO input pin to `high`; returns the number of edges that came before the
    /// change (see [`Qtest::command_marked`]).
    pub fn set_pin(&self, pin: Pin, high: bool) -> Result<usize> {
        let (_, mark) = self.command_marked(&set_irq_in_command(pin, high))?;
        lock(&self.shared).driven.insert(pin, high);
        Ok(mark)
    }

    /// The level last driven on `pin` by [`Qtest::set_pin`], if any. A reset of the machine
    /// makes QEMU's GPIO forget it (every pin reads its pull again), not this.
    pub fn driven_level(&self, pin: Pin) -> Option<bool> {
        lock(&self.shared).driven.get(&pin).copied()
    }

    /// Reads a 32-bit register.
    pub fn readl(&self, address: u64) -> Result<u32> {
        let words = self.command(&format!("readl 0x{address:x}"))?;
        let value = parse_value(&words)?;
        u32::try_from(value)
            .map_err(|_| Error::Protocol(format!("readl 0x{address:x}: {value:#x} too wide")))
    }

    /// Writes a 32-bit register.
    pub fn writel(&self, address: u64, value: u32) -> Result<()> {
        self.command(&format!("writel 0x{address:x} 0x{value:x}"))
            .map(drop)
    }

    /// The level of an output pin (its ODR bit).
    pub fn output_level(&self, pin: Pin) -> Result<bool> {
        Ok(self.readl(pin.port.odr_address())? & pin.mask() != 0)
    }

    /// Streams the output edges of `port` from now on ([`Qtest::edges`], [`Qtest::subscribe`]).
    /// QEMU allows one intercepted device per session.
    pub fn intercept_outputs(&self, port: Port) -> Result<()> {
        self.command(&format!("irq_intercept_out {}", port.qom_path()))?;
        lock(&self.shared).intercepted = Some(port);
        Ok(())
    }

    /// Every edge received so far.
    pub fn edges(&self) -> Vec<Edge> {
        lock(&self.shared).edges.clone()
    }

    /// Edges from now on, as they arrive.
    pub fn subscribe(&self) -> Receiver<Edge> {
        let (tx, rx) = mpsc::channel();
        lock(&self.shared).subscribers.push(tx);
        rx
    }
}

impl Drop for Qtest {
    fn drop(&mut self) {
        // Ends the reader thread (it holds a clone of the socket).
        let session = self.session.lock().unwrap_or_else(|e| e.into_inner());
        let _ = session.0.shutdown(std::net::Shutdown::Both);
    }
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|e| e.into_inner())
}

/// The `set_irq_in` command that drives `pin` (a GPIO port's unnamed input line n is pin n).
pub fn set_irq_in_command(pin: Pin, high: bool) -> String {
    format!(
        "set_irq_in {} unnamed-gpio-in {} {}",
        pin.port.qom_path(),
        pin.number,
        u8::from(high)
    )
}

/// The reader thread: replies to the waiting command, edges to the log and the subscribers.
/// Ends when QEMU closes the socket (dropping `replies`, which fails any waiting command).
fn read_lines(stream: UnixStream, replies: &Sender<(Line, usize)>, shared: &Mutex<Shared>) {
    for text in BufReader::new(stream).lines() {
        let Ok(text) = text else { break };
        if text.trim().is_empty() {
            continue;
        }
        match parse_line(&text) {
            Ok(Line::Irq { line, high }) => {
                let mut shared = lock(shared);
                let Some(port) = shared.intercepted else {
                    continue;
                };
                let edge = Edge {
                    at: Instant::now(),
                    pin: Pin { port, number: line },
                    high,
                };
                shared.edges.push(edge);
                shared.subscribers.retain(|s| s.send(edge).is_ok());
            }
            Ok(reply) => {
                let mark = lock(shared).edges.len();
                if replies.send((reply, mark)).is_err() {
                    break;
                }
            }
            // A line that is neither (a QEMU warning?) fails the command waiting for a reply.
            Err(e) => {
                let mark = lock(shared).edges.len();
                if replies.send((Line::Fail(e.to_string()), mark)).is_err() {
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emu::pins::{input_pin, output_pin};
    use plasma_firmware::io::{Input, Output};

    #[test]
    fn replies_and_edges_are_parsed() {
        assert_eq!(parse_line("OK").unwrap(), Line::Ok(vec![]));
        assert_eq!(
            parse_line("OK 0x00000201").unwrap(),
            Line::Ok(vec!["0x00000201".to_string()])
        );
        assert_eq!(parse_value(&["0x00000201".to_string()]).unwrap(), 0x201);
        assert_eq!(
            parse_line("IRQ raise 9").unwrap(),
            Line::Irq {
                line: 9,
                high: true
            }
        );
        assert_eq!(
            parse_line("IRQ lower 0").unwrap(),
            Line::Irq {
                line: 0,
                high: false
            }
        );
        assert_eq!(
            parse_line("FAIL Unknown device").unwrap(),
            Line::Fail("FAIL Unknown device".to_string())
        );
        assert!(matches!(parse_line("IRQ up 3"), Err(Error::Protocol(_))));
        assert!(matches!(parse_line("IRQ raise x"), Err(Error::Protocol(_))));
        assert!(matches!(parse_line("hello"), Err(Error::Protocol(_))));
        assert!(parse_value(&["201".to_string()]).is_err());
        assert!(parse_value(&[]).is_err());
    }

    #[test]
    fn inputs_are_driven_by_port_and_pin() {
        assert_eq!(
            set_irq_in_command(input_pin(Input::TorchOn), false),
            "set_irq_in /machine/soc/gpioa unnamed-gpio-in 0 0"
        );
        assert_eq!(
            set_irq_in_command(input_pin(Input::RampdownError), true),
            "set_irq_in /machine/soc/gpiob unnamed-gpio-in 10 1"
        );
    }

    /// A fake QEMU on the other end of a socket pair: answers each command from `script`
    /// (an IRQ line is sent before the reply when the script says so).
    fn fake_qemu(script: Vec<(&'static str, Vec<&'static str>)>) -> Qtest {
        let (ours, theirs) = UnixStream::pair().unwrap();
        std::thread::spawn(move || {
            let mut writer = theirs.try_clone().unwrap();
            let mut lines = BufReader::new(theirs).lines();
            for (expected, answer) in script {
                let got = lines.next().unwrap().unwrap();
                assert_eq!(got, expected);
                for line in answer {
                    writer.write_all(format!("{line}\n").as_bytes()).unwrap();
                }
            }
        });
        Qtest::new(ours).unwrap()
    }

    #[test]
    fn a_session_reads_registers_and_collects_edges_between_replies() {
        let qtest = fake_qemu(vec![
            ("irq_intercept_out /machine/soc/gpiob", vec!["OK"]),
            ("readl 0x48000414", vec!["IRQ raise 0", "OK 0x00000041"]),
            ("readl 0x48000414", vec!["OK 0x00000041"]),
            ("readl 0x48000414", vec!["OK 0x00000041"]),
            (
                "set_irq_in /machine/soc/gpioa unnamed-gpio-in 0 0",
                vec!["OK", "IRQ lower 0"],
            ),
            ("readl 0x48000814", vec!["FAIL no such register"]),
        ]);
        let edges = qtest.subscribe();
        qtest.intercept_outputs(Port::B).unwrap();
        assert!(qtest.output_level(output_pin(Output::Start)).unwrap());
        assert!(qtest.output_level(output_pin(Output::Ready)).unwrap());
        assert!(!qtest.output_level(output_pin(Output::ArcOk)).unwrap());
        // One edge came before the input changed, one after.
        assert_eq!(qtest.set_pin(input_pin(Input::TorchOn), false).unwrap(), 1);
        let first = edges.recv_timeout(Duration::from_secs(5)).unwrap();
        let second = edges.recv_timeout(Duration::from_secs(5)).unwrap();
        assert_eq!((first.pin, first.high), (output_pin(Output::Start), true));
        assert_eq!(
            (second.pin, second.high),
            (output_pin(Output::Start), false)
        );
        assert_eq!(qtest.edges().len(), 2);
        assert!(matches!(
            qtest.readl(0x4800_0814),
            Err(Error::Protocol(text)) if text.contains("no such register")
        ));
        // The fake has hung up: the next command fails at once, it does not hang.
        assert!(matches!(qtest.readl(0x4800_0814), Err(Error::Exited(_))));
    }
}
