//! The way to the bridge's CNC text protocol: a serial port, or a `pbtool sim` / `pbtool emu`
//! child over pipes. Lines come from a reader thread on a channel; the end of the connection
//! comes as [`Incoming::Closed`].

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, Command as Process, Stdio};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Duration;

use plasma_protocol::serial::PortConfig;

use crate::serial::{Port, Rx};

/// What the monitor attaches to.
#[derive(Debug, Clone)]
pub enum Source {
    /// A board's CNC port.
    Port {
        /// The device (`/dev/ttyACM0`, `COM3`).
        device: String,
        /// Its framing.
        framing: PortConfig,
    },
    /// A pbtool child with the CNC protocol on its stdin/stdout: `sim ...` or `emu ...`.
    Child {
        /// Its arguments after `pbtool`.
        args: Vec<String>,
    },
}

impl Source {
    /// `pbtool SUBCOMMAND --ps MODEL --events [--fault CODE]`: the simulator (`sim`) or the
    /// emulated board (`emu`).
    pub fn child(subcommand: &str, model: &str, fault: Option<&str>) -> Source {
        let mut args: Vec<String> = [subcommand, "--ps", model, "--events"]
            .map(String::from)
            .into();
        if let Some(code) = fault {
            args.extend(["--fault".to_string(), code.to_string()]);
        }
        Source::Child { args }
    }

    /// How the screen names it.
    pub fn label(&self) -> String {
        match self {
            Source::Port { device, .. } => device.clone(),
            // `sim sync65`, `emu hpr130 --fault 044`.
            Source::Child { args } => args
                .iter()
                .filter(|a| !matches!(a.as_str(), "--ps" | "--events"))
                .cloned()
                .collect::<Vec<_>>()
                .join(" "),
        }
    }
}

/// What the reader thread passes on.
#[derive(Debug, Clone, PartialEq)]
pub enum Incoming {
    /// One line, without its line end.
    Line(String),
    /// The port went away or the child exited.
    Closed(String),
}

enum Writer {
    Port(Port),
    Child(ChildStdin),
}

/// An open connection; dropping it closes the port or ends the child.
pub struct Connection {
    writer: Writer,
    child: Option<Child>,
}

/// How long the port reader waits per read, so that its thread notices a dropped receiver.
const READ_TICK: Duration = Duration::from_millis(100);

impl Connection {
    /// Opens `source` (a child is `exe` run with the source's arguments); its lines arrive on
    /// the receiver.
    pub fn open(source: &Source, exe: &Path) -> Result<(Connection, Receiver<Incoming>), String> {
        let (inbox, lines) = channel();
        let connection = match source {
            Source::Port { device, framing } => {
                let port = Port::open(device, *framing).map_err(|e| e.to_string())?;
                let reader = port.try_clone().map_err(|e| e.to_string())?;
                read_port(reader, inbox);
                Connection {
                    writer: Writer::Port(port),
                    child: None,
                }
            }
            Source::Child { args } => {
                let mut child = Process::new(exe)
                    .args(args)
                    .stdin(Stdio::piped())
                    .stdout(Stdio::piped())
                    // The child's banner and log would tear the screen.
                    .stderr(Stdio::null())
                    .spawn()
                    .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
                let (Some(stdin), Some(stdout)) = (child.stdin.take(), child.stdout.take()) else {
                    let _ = child.kill();
                    let _ = child.wait();
                    return Err("child without pipes".to_string());
                };
                read_child(BufReader::new(stdout), inbox);
                Connection {
                    writer: Writer::Child(stdin),
                    child: Some(child),
                }
            }
        };
        Ok((connection, lines))
    }

    /// Sends one command line.
    pub fn send(&mut self, line: &str) -> Result<(), String> {
        let bytes = format!("{line}\r\n");
        match &mut self.writer {
            Writer::Port(port) => port.write_all(bytes.as_bytes()).map_err(|e| e.to_string()),
            Writer::Child(stdin) => stdin
                .write_all(bytes.as_bytes())
                .and_then(|()| stdin.flush())
                .map_err(|e| format!("child's input: {e}")),
        }
    }
}

impl Drop for Connection {
    fn drop(&mut self) {
        if let Some(child) = &mut self.child {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

fn read_child(mut stdout: BufReader<std::process::ChildStdout>, inbox: Sender<Incoming>) {
    std::thread::spawn(move || {
        let mut line = String::new();
        loop {
            line.clear();
            match stdout.read_line(&mut line) {
                Ok(0) => {
                    let _ = inbox.send(Incoming::Closed("the child exited".to_string()));
                    return;
                }
                Ok(_) => {
                    let text = line.trim_end_matches(['\r', '\n']).to_string();
                    if inbox.send(Incoming::Line(text)).is_err() {
                        return;
                    }
                }
                Err(e) => {
                    let _ = inbox.send(Incoming::Closed(format!("the child's output: {e}")));
                    return;
                }
            }
        }
    });
}

fn read_port(mut port: Port, inbox: Sender<Incoming>) {
    std::thread::spawn(move || {
        let mut received = Vec::new();
        let mut line = Vec::new();
        loop {
            if let Err(e) = port.read(READ_TICK, &mut received) {
                let _ = inbox.send(Incoming::Closed(e.to_string()));
                return;
            }
            for byte in Rx::cnc_bytes(&received) {
                if byte == b'\n' {
                    let text = String::from_utf8_lossy(&line)
                        .trim_end_matches('\r')
                        .to_string();
                    line.clear();
                    if inbox.send(Incoming::Line(text)).is_err() {
                        return;
                    }
                } else {
                    line.push(byte);
                }
            }
            received.clear();
        }
    });
}
