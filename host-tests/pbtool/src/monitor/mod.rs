//! `pbtool monitor`: a live dashboard of a bridge, through its CNC text protocol.
//!
//! - [`parse`]: the reply and event lines, split into fields.
//! - [`state`]: the [`Dashboard`] model, fed line by line; it says which commands are due.
//! - [`view`]: [`view::render`] draws it with ratatui (full and compact layouts).
//! - [`transport`]: the serial port or the `pbtool sim` / `emu` child, lines on a channel.
//!
//! [`run`] is the terminal loop around them, [`snapshot`] one frame as text.

pub mod parse;
pub mod state;
pub mod transport;
pub mod view;

use std::io;
use std::path::Path;
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use ratatui::Terminal;
use ratatui::backend::{Backend, TestBackend};
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};

pub use state::Dashboard;
use state::{Connection as Link, Consumables, History, KeyAction};
use transport::{Connection, Incoming, Source};

/// How long to wait between attempts to reopen a port or restart a child.
pub const RECONNECT_EVERY: Duration = Duration::from_secs(1);
/// The screen's refresh tick: also how long a key or a line may wait.
const TICK: Duration = Duration::from_millis(100);

/// A monitor session: the dashboard and its connection, without a terminal.
pub struct Session {
    source: Source,
    exe: std::path::PathBuf,
    started: Instant,
    /// The model.
    pub dashboard: Dashboard,
    connection: Option<(Connection, Receiver<Incoming>)>,
    next_attempt: Duration,
}

impl Session {
    /// A session on `source`; children are `exe` (pbtool itself) run with its arguments.
    pub fn new(source: Source, exe: &Path, framing: Option<String>) -> Session {
        let wall_origin_s = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        Session {
            dashboard: Dashboard::new(&source.label(), framing, wall_origin_s),
            source,
            exe: exe.to_path_buf(),
            started: Instant::now(),
            connection: None,
            next_attempt: Duration::ZERO,
        }
    }

    /// The time since the session started.
    pub fn now(&self) -> Duration {
        self.started.elapsed()
    }

    /// Connects when due, takes the lines that came within `wait`, sends what is due.
    pub fn step(&mut self, wait: Duration) {
        let now = self.now();
        if self.connection.is_none() && now >= self.next_attempt {
            self.next_attempt = now + RECONNECT_EVERY;
            match Connection::open(&self.source, &self.exe) {
                Ok(connection) => {
                    self.connection = Some(connection);
                    let first = self.dashboard.connected(now);
                    self.send(&first);
                }
                Err(e) => self.dashboard.lost(now, &e),
            }
        }
        let Some((_, lines)) = &self.connection else {
            std::thread::sleep(wait);
            return;
        };
        let mut closed = None;
        match lines.recv_timeout(wait) {
            Ok(incoming) => {
                let mut next = Some(incoming);
                while let Some(incoming) = next {
                    match incoming {
                        Incoming::Line(line) => self.dashboard.apply_line(self.now(), &line),
                        Incoming::Closed(reason) => {
                            closed = Some(reason);
                            break;
                        }
                    }
                    next = lines.try_recv().ok();
                }
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => closed = Some("the reader stopped".into()),
        }
        if let Some(reason) = closed {
            self.close(&reason);
            return;
        }
        let due = self.dashboard.poll(self.now());
        self.send(&due);
    }

    /// A key: `false` to quit.
    pub fn key(&mut self, key: char) -> bool {
        match self.dashboard.key(self.now(), key) {
            KeyAction::Quit => false,
            KeyAction::Send(command) => {
                self.send(&[command]);
                true
            }
            KeyAction::Ignored => true,
        }
    }

    fn send(&mut self, commands: &[state::Command]) {
        let Some((connection, _)) = &mut self.connection else {
            return;
        };
        for command in commands {
            if let Err(e) = connection.send(&command.text()) {
                self.close(&e);
                return;
            }
        }
    }

    fn close(&mut self, reason: &str) {
        self.connection = None;
        let now = self.now();
        self.dashboard.lost(now, reason);
        self.next_attempt = now + RECONNECT_EVERY;
    }

    /// Whether the dashboard has a complete picture: STATUS, the fault's steps (if any), the
    /// consumables' and the history's answers.
    pub fn settled(&self) -> bool {
        let dash = &self.dashboard;
        dash.connection == Link::Up
            && dash.status.is_some()
            && dash.consumables != Consumables::Unknown
            && dash.history != History::Unknown
            && dash.fault.as_ref().is_none_or(|f| f.action != "-")
    }
}

/// Runs the dashboard on `terminal` until `q` (or Ctrl-C).
pub fn run<B: Backend>(terminal: &mut Terminal<B>, session: &mut Session) -> io::Result<()>
where
    B::Error: Into<io::Error>,
{
    loop {
        let now = session.now();
        terminal
            .draw(|frame| view::render(frame, &session.dashboard, now))
            .map_err(Into::into)?;
        if event::poll(Duration::ZERO)? {
            match event::read()? {
                Event::Key(key) if key.kind == KeyEventKind::Press => {
                    let quit = key.modifiers.contains(KeyModifiers::CONTROL)
                        && key.code == KeyCode::Char('c');
                    if quit {
                        return Ok(());
                    }
                    if let KeyCode::Char(c) = key.code
                        && !session.key(c)
                    {
                        return Ok(());
                    }
                }
                // A resize is redrawn at the next turn; other events change nothing.
                _ => {}
            }
            continue;
        }
        session.step(TICK);
    }
}

/// Connects, waits (up to `limit`) until the dashboard has a complete picture, and returns
/// one frame of `width` x `height` as text, and whether the picture was complete.
pub fn snapshot(session: &mut Session, width: u16, height: u16, limit: Duration) -> (String, bool) {
    let deadline = Instant::now() + limit;
    while !session.settled() && Instant::now() < deadline {
        session.step(TICK);
    }
    let text = screen_text(&session.dashboard, session.now(), width, height);
    (text, session.settled())
}

/// `dash` drawn at `now` on a `width` x `height` screen, as lines of text (trailing blanks
/// trimmed).
pub fn screen_text(dash: &Dashboard, now: Duration, width: u16, height: u16) -> String {
    let mut terminal = match Terminal::new(TestBackend::new(width, height)) {
        Ok(terminal) => terminal,
        Err(e) => match e {},
    };
    if let Err(e) = terminal.draw(|frame| view::render(frame, dash, now)) {
        match e {}
    }
    let buffer = terminal.backend().buffer();
    let mut text = String::new();
    for y in 0..buffer.area.height {
        let mut line = String::new();
        for x in 0..buffer.area.width {
            line.push_str(buffer[(x, y)].symbol());
        }
        text.push_str(line.trim_end());
        text.push('\n');
    }
    text
}
