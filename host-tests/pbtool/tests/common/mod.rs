//! What pbtool's tests share: a null-modem cable of ptys that the test can cut, tap and
//! unplug, pbtool processes driven line by line, and pbtool run once on a piped input.
#![allow(dead_code)] // each test file uses a part

use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, ExitStatus, Output, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use host_tests::emu::image;
use serialport::{SerialPort, TTYPort};

/// Generous: the machine is shared and loaded.
pub const LONG: Duration = Duration::from_secs(30);

/// Two serial devices joined like a null-modem cable: what one end writes, the other reads.
/// Each end is a pty whose master the test relays; the test keeps each slave open too, so an
/// end's user may close and reopen its port (as pyserial does) without hanging up the cable.
pub struct Cable {
    /// One end's device.
    pub a: String,
    /// The other end's device.
    pub b: String,
    /// Listening devices: with one tap it hears both directions (a 2-wire bus); with two, the
    /// first hears a -> b and the second b -> a (a 4-wire line).
    pub taps: Vec<String>,
    cut: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    relays: Vec<JoinHandle<()>>,
    _slaves: Vec<TTYPort>,
}

fn pty() -> (TTYPort, TTYPort, String) {
    let (master, slave) = TTYPort::pair().expect("a pty pair");
    close_on_exec(&master);
    close_on_exec(&slave);
    let name = slave.name().expect("the slave has a name");
    (master, slave, name)
}

/// The pair's descriptors are opened without close-on-exec: the pbtool processes the tests
/// start would inherit them and keep a master open after the test has closed it (an unplug
/// that nobody notices).
fn close_on_exec(port: &TTYPort) {
    use std::os::unix::io::AsRawFd;
    // SAFETY: fcntl on a descriptor this port owns; only the FD_CLOEXEC flag changes.
    unsafe { libc::fcntl(port.as_raw_fd(), libc::F_SETFD, libc::FD_CLOEXEC) };
}

fn clone(port: &TTYPort) -> TTYPort {
    let clone = port.try_clone_native().expect("a second handle");
    close_on_exec(&clone);
    clone
}

impl Cable {
    /// A cable without taps.
    pub fn new() -> Cable {
        Cable::with_taps(0)
    }

    /// A cable with `taps` (0, 1 or 2) listening devices.
    pub fn with_taps(taps: usize) -> Cable {
        let (master_a, slave_a, a) = pty();
        let (master_b, slave_b, b) = pty();
        let mut slaves = vec![slave_a, slave_b];
        let mut tap_masters = Vec::new();
        let mut tap_names = Vec::new();
        for _ in 0..taps {
            let (master, slave, name) = pty();
            tap_masters.push(master);
            slaves.push(slave);
            tap_names.push(name);
        }
        let (tap_ab, tap_ba): (Vec<TTYPort>, Vec<TTYPort>) = match tap_masters.as_slice() {
            [] => (vec![], vec![]),
            [one] => (vec![clone(one)], vec![clone(one)]),
            [ab, ba, ..] => (vec![clone(ab)], vec![clone(ba)]),
        };
        let cut = Arc::new(AtomicBool::new(false));
        let stop = Arc::new(AtomicBool::new(false));
        let relays = vec![
            relay(clone(&master_a), clone(&master_b), tap_ab, &cut, &stop),
            relay(master_b, master_a, tap_ba, &cut, &stop),
        ];
        Cable {
            a,
            b,
            taps: tap_names,
            cut,
            stop,
            relays,
            _slaves: slaves,
        }
    }

    /// Cut (true) or mend the cable: while cut, nothing passes either way.
    pub fn cut(&self, cut: bool) {
        self.cut.store(cut, Ordering::SeqCst);
    }

    /// Pull both ends out: the devices' users see their port go away.
    pub fn unplug(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        for relay in self.relays.drain(..) {
            let _ = relay.join();
        }
        self._slaves.clear();
    }
}

impl Drop for Cable {
    fn drop(&mut self) {
        self.unplug();
    }
}

fn relay(
    mut from: TTYPort,
    mut to: TTYPort,
    mut taps: Vec<TTYPort>,
    cut: &Arc<AtomicBool>,
    stop: &Arc<AtomicBool>,
) -> JoinHandle<()> {
    let (cut, stop) = (cut.clone(), stop.clone());
    std::thread::spawn(move || {
        let _ = from.set_timeout(Duration::from_millis(50));
        let mut buf = [0u8; 512];
        while !stop.load(Ordering::SeqCst) {
            match from.read(&mut buf) {
                Ok(n) if n > 0 && !cut.load(Ordering::SeqCst) => {
                    // The taps first: on a wire a tap hears a character no later than the
                    // receiver, which may answer at once (a reply must not reach a 4-wire
                    // sniffer after the request it provoked).
                    for tap in &mut taps {
                        let _ = tap.write_all(&buf[..n]);
                    }
                    let _ = to.write_all(&buf[..n]);
                }
                Ok(_) => {}
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                // Nobody at this end right now (a user between close and reopen).
                Err(_) => std::thread::sleep(Duration::from_millis(20)),
            }
        }
    })
}

/// `pbtool ARGS` started with its standard streams piped.
fn spawn_piped(args: &[&str]) -> Child {
    spawn_with_stdin(args, Stdio::piped())
}

/// `pbtool ARGS` started with `stdin`, stdout and stderr piped.
fn spawn_with_stdin(args: &[&str], stdin: Stdio) -> Child {
    let mut command = Command::new(env!("CARGO_BIN_EXE_pbtool"));
    if may_boot_the_emulated_board(args) {
        command.env(image::ELF_ENV, emulated_board_image());
    }
    command
        .args(args)
        .stdin(stdin)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("pbtool starts")
}

/// `emu`, `--emu`, and `run` in real time (without a board it boots the emulated one).
fn may_boot_the_emulated_board(args: &[&str]) -> bool {
    let run_in_real_time =
        args.first() == Some(&"run") && !args.iter().any(|a| matches!(*a, "--fast" | "--sim"));
    args.first() == Some(&"emu") || args.contains(&"--emu") || run_in_real_time
}

/// The emulated board's image, built here (once per test process, for as long as it takes)
/// rather than by the pbtool under test: that build can outlast the time a test waits for
/// pbtool's first line.
fn emulated_board_image() -> PathBuf {
    image::firmware_elf().unwrap_or_else(|e| panic!("the emulated board's image: {e}"))
}

/// Runs `pbtool ARGS` with `input` on stdin until it exits.
pub fn pbtool_with_input(args: &[&str], input: &str) -> Output {
    let mut child = spawn_piped(args);
    child
        .stdin
        .take()
        .expect("piped")
        .write_all(input.as_bytes())
        .expect("input written");
    child.wait_with_output().expect("pbtool ends")
}

/// A pbtool process: stdin written line by line, stdout read line by line.
pub struct Pbtool {
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<String>,
    seen: Arc<Mutex<Vec<String>>>,
    stderr: Arc<Mutex<String>>,
    readers: Vec<JoinHandle<()>>,
    name: String,
}

impl Pbtool {
    /// Starts `pbtool ARGS`.
    pub fn spawn(args: &[&str]) -> Pbtool {
        Pbtool::from_child(spawn_piped(args), args)
    }

    /// Starts `pbtool ARGS` with a terminal as its stdin, as a person runs it; the returned
    /// port is the terminal's other end: what is written there is typed (end a line with
    /// `\n`; `\x04` at the start of a line is Ctrl-D). [`Pbtool::send`] is not available.
    pub fn spawn_on_terminal(args: &[&str]) -> (Pbtool, TTYPort) {
        let (keyboard, terminal) = TTYPort::pair().expect("a pty pair");
        close_on_exec(&keyboard);
        use std::os::fd::{AsRawFd, FromRawFd, IntoRawFd, OwnedFd};
        // The pair comes in raw mode; a person's terminal is line by line, with Ctrl-D as end
        // of input.
        // SAFETY: tcgetattr/tcsetattr on a descriptor the pair owns, into a zeroed termios.
        unsafe {
            let mut modes: libc::termios = std::mem::zeroed();
            assert_eq!(libc::tcgetattr(terminal.as_raw_fd(), &mut modes), 0);
            modes.c_lflag |= libc::ICANON;
            modes.c_cc[libc::VEOF] = 0x04;
            assert_eq!(
                libc::tcsetattr(terminal.as_raw_fd(), libc::TCSANOW, &modes),
                0
            );
        }
        // SAFETY: the descriptor comes from `into_raw_fd`, so it is open and owned by no one else.
        let stdin = unsafe { OwnedFd::from_raw_fd(terminal.into_raw_fd()) };
        let mut pbtool = Pbtool::from_child(spawn_with_stdin(args, Stdio::from(stdin)), args);
        pbtool.stdin = None;
        (pbtool, keyboard)
    }

    fn from_child(mut child: Child, args: &[&str]) -> Pbtool {
        let stdout = child.stdout.take().expect("piped");
        let mut stderr_pipe = child.stderr.take().expect("piped");
        let (tx, lines) = channel();
        let seen = Arc::new(Mutex::new(Vec::new()));
        let seen_by_reader = seen.clone();
        let stdout_reader = std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { return };
                seen_by_reader.lock().unwrap().push(line.clone());
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        let stderr = Arc::new(Mutex::new(String::new()));
        let stderr_by_reader = stderr.clone();
        let stderr_reader = std::thread::spawn(move || {
            let mut buf = [0u8; 1024];
            while let Ok(n) = stderr_pipe.read(&mut buf) {
                if n == 0 {
                    return;
                }
                stderr_by_reader
                    .lock()
                    .unwrap()
                    .push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        Pbtool {
            stdin: child.stdin.take(),
            child,
            lines,
            seen,
            stderr,
            readers: vec![stdout_reader, stderr_reader],
            name: format!("pbtool {}", args.join(" ")),
        }
    }

    /// Writes `line` and a newline to its stdin.
    pub fn send(&mut self, line: &str) {
        let stdin = self.stdin.as_mut().expect("stdin still open");
        writeln!(stdin, "{line}").expect("pbtool reads its stdin");
        stdin.flush().expect("flushed");
    }

    /// Ends its input.
    pub fn close_stdin(&mut self) {
        self.stdin = None;
    }

    /// The next stdout line that `wanted` accepts (lines before it are skipped); panics with
    /// everything seen when none comes within [`LONG`].
    pub fn expect(&self, what: &str, wanted: impl Fn(&str) -> bool) -> String {
        let deadline = Instant::now() + LONG;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) if wanted(&line) => return line,
                Ok(_) => {}
                Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => {
                    panic!("{}: no {what}\n{}", self.name, self.transcript())
                }
            }
        }
    }

    /// The next line starting with `prefix`.
    pub fn expect_prefix(&self, prefix: &str) -> String {
        self.expect(prefix, |l| l.starts_with(prefix))
    }

    /// Stdout so far and stderr, for failure messages.
    pub fn transcript(&self) -> String {
        format!(
            "--- stdout\n{}\n--- stderr\n{}",
            self.seen.lock().unwrap().join("\n"),
            self.stderr.lock().unwrap()
        )
    }

    /// Stderr so far.
    pub fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// Waits until its stderr contains `text` (it may come after a stdout line that was
    /// written later: the two pipes are read by two threads); panics with everything seen when
    /// it has not come within [`LONG`]. Returns stderr so far.
    pub fn expect_stderr(&self, text: &str) -> String {
        let deadline = Instant::now() + LONG;
        loop {
            let stderr = self.stderr();
            if stderr.contains(text) {
                return stderr;
            }
            if Instant::now() > deadline {
                panic!(
                    "{}: stderr never said {text:?}\n{}",
                    self.name,
                    self.transcript()
                );
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Waits for it to exit (panics after [`LONG`]); its stdin stays as it is. Returns once
    /// everything it wrote to stdout and stderr has been read.
    pub fn wait(&mut self) -> ExitStatus {
        let deadline = Instant::now() + LONG;
        let status = loop {
            if let Some(status) = self.child.try_wait().expect("waitable") {
                break status;
            }
            if Instant::now() > deadline {
                panic!("{} did not exit\n{}", self.name, self.transcript());
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        self.drain_readers(deadline);
        status
    }

    /// Ends it (SIGKILL) and returns everything it wrote to stderr.
    pub fn kill(mut self) -> String {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.drain_readers(Instant::now() + LONG);
        self.stderr()
    }

    /// Waits until both readers have met the end of their pipe. A process it started that
    /// still holds a pipe (QEMU under `pbtool emu`) keeps a reader going: after `deadline` the
    /// output read so far is what there is.
    fn drain_readers(&mut self, deadline: Instant) {
        while self.readers.iter().any(|r| !r.is_finished()) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

impl Drop for Pbtool {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The CNC's end of a CNC port: commands out, reply lines back.
pub struct CncEnd {
    port: Box<dyn SerialPort>,
    pending: Vec<u8>,
}

impl CncEnd {
    /// Opens `device` at the CNC port's 115200 8N1.
    pub fn open(device: &str) -> CncEnd {
        let port = serialport::new(device, 115_200)
            .timeout(Duration::from_millis(100))
            .open()
            .expect("the CNC end opens");
        CncEnd {
            port,
            pending: Vec::new(),
        }
    }

    /// Sends `line` with CR LF and returns the next reply line (`OK`/`ERR`; event lines are
    /// skipped); `None` when none came within [`LONG`].
    pub fn command(&mut self, line: &str) -> Option<String> {
        self.command_within(line, LONG)
    }

    /// As [`CncEnd::command`], waiting at most `timeout`.
    pub fn command_within(&mut self, line: &str, timeout: Duration) -> Option<String> {
        self.port
            .write_all(format!("{line}\r\n").as_bytes())
            .expect("written");
        let deadline = Instant::now() + timeout;
        while Instant::now() < deadline {
            while let Some(end) = self.pending.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.pending.drain(..=end).collect();
                let text = String::from_utf8_lossy(&line).trim().to_string();
                if text.starts_with("OK") || text.starts_with("ERR") {
                    return Some(text);
                }
            }
            let mut buf = [0u8; 256];
            if let Ok(n) = self.port.read(&mut buf) {
                self.pending.extend_from_slice(&buf[..n]);
            }
        }
        None
    }
}
