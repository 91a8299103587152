//! The dashboard's model: what the bridge said, fed line by line, and which commands are due.
//! No I/O and no clock of its own: every call takes `now`, the time since the monitor started.

use std::collections::VecDeque;
use std::time::Duration;

use super::parse::{ActiveFault, Fields, Line, unit_of};
use crate::history::{Row, clock_command};

/// How often STATUS (and FAULT while a fault is active) is asked.
pub const STATUS_EVERY: Duration = Duration::from_millis(250);
/// How often the link counters are read for the error rate.
pub const COUNTERS_EVERY: Duration = Duration::from_secs(10);
/// A command unanswered this long is taken as lost, so polling goes on.
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(3);
/// How far back the plot reaches.
pub const PLOT_WINDOW: Duration = Duration::from_secs(300);
/// How many events are kept.
pub const EVENTS_KEPT: usize = 100;
/// How many of the bridge's newest history entries the History panel asks for.
pub const HISTORY_SHOWN: u8 = 6;
/// The history is asked again after an event, but not more often than this.
pub const HISTORY_EVERY: Duration = Duration::from_secs(1);
/// How long `GASTEST CHECK` may take: the gas flows until the pressure settles.
pub const GAS_CHECK_TIMEOUT: Duration = Duration::from_secs(30);

/// A command the dashboard sends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// `EVENTS ON`.
    EventsOn,
    /// `STATUS`.
    Status,
    /// `FAULT`.
    Fault,
    /// `COUNTERS`: the link counters.
    Counters,
    /// `CONSUMABLES`: at connect and after each `!WARN CONSUMABLE`.
    Consumables,
    /// `HISTORY` [`HISTORY_SHOWN`]: at connect and after events.
    History,
    /// `CLOCK <time>`: the bridge's wall clock set to this one (unix seconds, UTC) at connect.
    Clock(u32),
    /// `GASTEST CHECK`: the unit's gas test, measured against its permitted range.
    GasCheck,
    /// `REMOTE OFF`.
    RemoteOff,
    /// `CLEARWARN`.
    ClearWarnings,
}

impl Command {
    /// The command line, without its line end.
    pub fn text(self) -> String {
        match self {
            Command::History => format!("HISTORY {HISTORY_SHOWN}"),
            Command::Clock(unix_seconds) => clock_command(unix_seconds),
            other => other.word().to_string(),
        }
    }

    /// The command's word(s), as the screen names it.
    pub fn word(self) -> &'static str {
        match self {
            Command::EventsOn => "EVENTS ON",
            Command::Status => "STATUS",
            Command::Fault => "FAULT",
            Command::Counters => "COUNTERS",
            Command::Consumables => "CONSUMABLES",
            Command::History => "HISTORY",
            Command::Clock(_) => "CLOCK",
            Command::GasCheck => "GASTEST CHECK",
            Command::RemoteOff => "REMOTE OFF",
            Command::ClearWarnings => "CLEARWARN",
        }
    }

    /// How long its reply may take before it is taken as lost.
    pub fn reply_timeout(self) -> Duration {
        match self {
            Command::GasCheck => GAS_CHECK_TIMEOUT,
            _ => REPLY_TIMEOUT,
        }
    }
}

/// The connection to the bridge (the port or the child process), not the bridge's link to
/// the unit.
#[derive(Debug, Clone, PartialEq)]
pub enum Connection {
    /// Not yet connected.
    Connecting,
    /// Lines can flow.
    Up,
    /// The port went away or the child exited; reconnecting.
    Lost {
        /// What happened.
        reason: String,
        /// When.
        since: Duration,
    },
}

/// Consumable life as the bridge reports it.
#[derive(Debug, Clone, PartialEq)]
pub enum Consumables {
    /// Not asked yet.
    Unknown,
    /// The bridge does not answer `CONSUMABLES`.
    NotReported,
    /// Its reply.
    Reported(Fields),
}

/// The bridge's history as the History panel shows it.
#[derive(Debug, Clone, PartialEq)]
pub enum History {
    /// Not asked yet.
    Unknown,
    /// The bridge does not answer `HISTORY` (or its history is not available): the reply.
    NotReported(String),
    /// The newest entries, newest first.
    Entries(Vec<Row>),
}

/// What a key asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyAction {
    /// Leave the monitor.
    Quit,
    /// Send this command.
    Send(Command),
    /// Not a key the dashboard uses (or no connection to send on).
    Ignored,
}

/// One point of the plot: actual current and pressure at a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// When STATUS said it.
    pub at: Duration,
    /// `out_amps`.
    pub amps: Option<f64>,
    /// `out_psi`.
    pub psi: Option<f64>,
}

/// Everything the dashboard shows.
#[derive(Debug, Clone)]
pub struct Dashboard {
    /// What the monitor is attached to (`sim sync65`, `/dev/ttyACM0`).
    pub source: String,
    /// The port's framing (`--port` only).
    pub framing: Option<String>,
    /// Seconds since the Unix epoch at `now` = 0, for the events' times of day (UTC).
    pub wall_origin_s: u64,
    /// The connection.
    pub connection: Connection,
    /// The latest STATUS reply.
    pub status: Option<Fields>,
    /// The active fault (from FAULT, or a `!FAULT` event until FAULT answers).
    pub fault: Option<ActiveFault>,
    /// Consumable life.
    pub consumables: Consumables,
    /// The last `!WARN CONSUMABLE` event (the text after `!`), until a CONSUMABLES reply
    /// says the set was changed (less used than at the warning).
    pub consumable_warning: Option<String>,
    /// The bridge's newest history entries.
    pub history: History,
    /// The last `GASTEST CHECK` reply (the text after `OK `/`ERR `), until the next.
    pub gas_check: Option<String>,
    /// The latest events and the monitor's own notes, newest last, with their times.
    pub events: VecDeque<(Duration, String)>,
    /// The plot's points, oldest first, within [`PLOT_WINDOW`].
    pub samples: VecDeque<Sample>,
    /// The reply to the last key's command (`REMOTE OFF: OK remote=OFF`).
    pub last_action: Option<String>,
    counters: VecDeque<(Duration, f64)>,
    /// `HISTORY` lines of the reply under way.
    history_lines: Vec<Row>,
    history_wanted: bool,
    history_asked: Option<Duration>,
    consumables_wanted: bool,
    pending: VecDeque<Command>,
    pending_since: Duration,
    next_status: Duration,
    next_counters: Duration,
}

impl Dashboard {
    /// A dashboard for `source`, not yet connected.
    pub fn new(source: &str, framing: Option<String>, wall_origin_s: u64) -> Dashboard {
        Dashboard {
            source: source.to_string(),
            framing,
            wall_origin_s,
            connection: Connection::Connecting,
            status: None,
            fault: None,
            consumables: Consumables::Unknown,
            consumable_warning: None,
            history: History::Unknown,
            gas_check: None,
            events: VecDeque::new(),
            samples: VecDeque::new(),
            last_action: None,
            counters: VecDeque::new(),
            history_lines: Vec::new(),
            history_wanted: false,
            history_asked: None,
            consumables_wanted: false,
            pending: VecDeque::new(),
            pending_since: Duration::ZERO,
            next_status: Duration::ZERO,
            next_counters: Duration::ZERO,
        }
    }

    /// The connection is up: what to send first (events on, the bridge's clock set to this
    /// one, the consumables and the history).
    pub fn connected(&mut self, now: Duration) -> Vec<Command> {
        self.connection = Connection::Up;
        self.pending.clear();
        self.counters.clear();
        self.history_lines.clear();
        self.note(now, format!("connected to {}", self.source));
        self.next_status = now;
        self.next_counters = now;
        self.history_wanted = false;
        self.history_asked = Some(now);
        self.consumables_wanted = false;
        let first = vec![
            Command::EventsOn,
            Command::Clock(self.wall_seconds(now)),
            Command::Consumables,
            Command::History,
        ];
        self.sent(now, &first);
        first
    }

    /// Unix seconds (UTC) at `now`.
    pub fn wall_seconds(&self, now: Duration) -> u32 {
        let seconds = self.wall_origin_s.saturating_add(now.as_secs());
        u32::try_from(seconds).unwrap_or(u32::MAX)
    }

    /// The port went away or the child exited.
    pub fn lost(&mut self, now: Duration, reason: &str) {
        if matches!(self.connection, Connection::Lost { .. }) {
            return;
        }
        self.connection = Connection::Lost {
            reason: reason.to_string(),
            since: now,
        };
        self.pending.clear();
        self.note(now, format!("connection lost: {reason}"));
    }

    /// The commands due at `now` (none while a reply is awaited or without a connection).
    pub fn poll(&mut self, now: Duration) -> Vec<Command> {
        if self.connection != Connection::Up {
            return Vec::new();
        }
        if let Some(&awaited) = self.pending.front() {
            if now.saturating_sub(self.pending_since) < awaited.reply_timeout() {
                return Vec::new();
            }
            self.note(now, format!("no reply to {}", awaited.word()));
            self.pending.clear();
            self.history_lines.clear();
        }
        let mut due = Vec::new();
        if now >= self.next_status {
            due.push(Command::Status);
            if self.fault.is_some() {
                due.push(Command::Fault);
            }
            self.next_status = now + STATUS_EVERY;
        }
        if now >= self.next_counters {
            due.push(Command::Counters);
            self.next_counters = now + COUNTERS_EVERY;
        }
        if self.consumables_wanted {
            due.push(Command::Consumables);
            self.consumables_wanted = false;
        }
        let history_due = self
            .history_asked
            .is_none_or(|at| now.saturating_sub(at) >= HISTORY_EVERY);
        if self.history_wanted && history_due {
            due.push(Command::History);
            self.history_wanted = false;
            self.history_asked = Some(now);
        }
        self.sent(now, &due);
        due
    }

    /// A key pressed: `q` quits, `g` gas check, `r` remote off, `c` clear warnings.
    pub fn key(&mut self, now: Duration, key: char) -> KeyAction {
        let command = match key {
            'q' | 'Q' => return KeyAction::Quit,
            'g' | 'G' => Command::GasCheck,
            'r' | 'R' => Command::RemoteOff,
            'c' | 'C' => Command::ClearWarnings,
            _ => return KeyAction::Ignored,
        };
        if self.connection != Connection::Up {
            self.last_action = Some(format!("{}: not connected", command.word()));
            return KeyAction::Ignored;
        }
        self.sent(now, &[command]);
        self.last_action = Some(format!("{}: sent", command.word()));
        KeyAction::Send(command)
    }

    /// One line from the bridge.
    pub fn apply_line(&mut self, now: Duration, line: &str) {
        // The dashboard shows unit 1 and asks without `@N`: another unit's event is logged
        // only, and its reply answers nothing asked (docs/cnc-protocol.md section 10).
        let first_unit = unit_of(line) == 1;
        match Line::parse(line) {
            Line::Event(event) if !first_unit => self.note(now, event),
            Line::Event(event) => self.event(now, event),
            Line::Ok(_) | Line::Err(_) if !first_unit => {}
            Line::Other(other) => {
                if let Some(row) = Row::parse(&other) {
                    self.history_lines.push(row);
                }
            }
            reply => {
                // Replies come in order. One that names its command drops the commands
                // before it (their replies were lost), and one that names a command not
                // awaited is a late reply to one given up on: the pairing recovers either way.
                let command = match answered_by(&reply) {
                    Some(named) => match self.pending.iter().position(|&p| p == named) {
                        Some(at) => self.pending.drain(..=at).next_back(),
                        None => None,
                    },
                    None => self.pending.pop_front(),
                };
                if let Some(command) = command {
                    self.pending_since = now;
                    self.reply(now, command, reply);
                }
            }
        }
    }

    /// Link errors per minute from the link counters read over the last minute; `None` until
    /// two readings are apart.
    pub fn errors_per_minute(&self) -> Option<f64> {
        let (last_at, last) = *self.counters.back()?;
        let (first_at, first) = *self.counters.front()?;
        let span = last_at.checked_sub(first_at)?.as_secs_f64();
        (span > 0.0).then(|| (last - first) * 60.0 / span)
    }

    fn sent(&mut self, now: Duration, commands: &[Command]) {
        if self.pending.is_empty() {
            self.pending_since = now;
        }
        self.pending.extend(commands.iter().copied());
    }

    fn reply(&mut self, now: Duration, command: Command, reply: Line) {
        match (command, reply) {
            (Command::Status, Line::Ok(fields)) => {
                if fields.get("fault") == Some("none") {
                    self.fault = None;
                } else if self.fault.is_none()
                    && let Some(code) = fields.get("fault")
                {
                    self.fault = Some(ActiveFault {
                        code: code.to_string(),
                        action: "-".to_string(),
                        text: String::new(),
                    });
                }
                self.sample(now, &fields);
                self.status = Some(fields);
            }
            (Command::Fault, Line::Ok(fields)) => self.fault = ActiveFault::from_reply(&fields),
            (Command::Counters, Line::Ok(fields)) => {
                if let Some(failed) = fields.number("link_failed") {
                    self.count(now, failed);
                }
            }
            (Command::Consumables, Line::Ok(fields)) => {
                // A set less used than at the warning is a new one: the warning is over.
                let warned_at = self
                    .consumable_warning
                    .as_deref()
                    .and_then(|w| used_percent(&Fields::parse(w)));
                if warned_at.is_some_and(|warned| used_percent(&fields).is_none_or(|u| u < warned))
                {
                    self.consumable_warning = None;
                }
                self.consumables = Consumables::Reported(fields);
            }
            (Command::Consumables, _) => self.consumables = Consumables::NotReported,
            (Command::History, Line::Ok(_)) => {
                self.history = History::Entries(std::mem::take(&mut self.history_lines));
            }
            (Command::History, reply) => {
                self.history_lines.clear();
                self.history = History::NotReported(answer_text(reply));
            }
            // A bridge without CLOCK: its entries carry no wall-clock time, nothing else changes.
            (
                Command::Status
                | Command::Fault
                | Command::Counters
                | Command::EventsOn
                | Command::Clock(_),
                _,
            ) => {}
            (action, reply) => {
                let answer = answer_text(reply);
                if action == Command::GasCheck {
                    self.gas_check = Some(answer.clone());
                }
                self.last_action = Some(format!("{}: {answer}", action.word()));
            }
        }
    }

    fn event(&mut self, now: Duration, event: String) {
        // What happened is in the history now (or soon): the panel asks again.
        self.history_wanted = true;
        if event.starts_with("WARN CONSUMABLE") {
            self.consumable_warning = Some(event.clone());
            self.consumables_wanted = true;
        } else if let Some(code) = event.strip_prefix("FAULT CLEARED code=") {
            if self.fault.as_ref().is_some_and(|f| f.code == code) {
                self.fault = None;
            }
        } else if let Some(rest) = event.strip_prefix("FAULT ") {
            // `!FAULT <code> action=<a> text=<text>`: as FAULT answers it.
            let (code, rest) = rest.split_once(' ').unwrap_or((rest, ""));
            let (action, text) = match rest.strip_prefix("action=") {
                Some(fields) => fields.split_once(' ').unwrap_or((fields, "")),
                None => ("-", rest),
            };
            self.fault = Some(ActiveFault {
                code: code.to_string(),
                action: action.to_string(),
                text: text.strip_prefix("text=").unwrap_or(text).to_string(),
            });
        }
        self.note(now, event);
    }

    fn note(&mut self, now: Duration, text: String) {
        self.events.push_back((now, text));
        while self.events.len() > EVENTS_KEPT {
            self.events.pop_front();
        }
    }

    fn sample(&mut self, now: Duration, fields: &Fields) {
        self.samples.push_back(Sample {
            at: now,
            amps: fields.number("out_amps"),
            psi: fields.number("out_psi"),
        });
        while self
            .samples
            .front()
            .is_some_and(|s| now.saturating_sub(s.at) > PLOT_WINDOW)
        {
            self.samples.pop_front();
        }
    }

    fn count(&mut self, now: Duration, failed: f64) {
        // A count that went down is a bridge that restarted: its rate starts again.
        if self.counters.back().is_some_and(|&(_, last)| failed < last) {
            self.counters.clear();
        }
        self.counters.push_back((now, failed));
        while self.counters.len() > 2
            && self
                .counters
                .get(1)
                .is_some_and(|&(at, _)| now.saturating_sub(at) >= Duration::from_secs(60))
        {
            self.counters.pop_front();
        }
    }
}

/// The share of consumable life used (`used=NN%`); `None` for `OFF` (no limit set) or none.
pub fn used_percent(fields: &Fields) -> Option<f64> {
    fields.get("used")?.strip_suffix('%')?.parse().ok()
}

/// A reply as the screen shows it: `OK key=value ...` or `ERR CODE text`.
fn answer_text(reply: Line) -> String {
    match reply {
        Line::Ok(fields) => {
            let words: Vec<String> = fields
                .iter()
                .map(|(k, v)| {
                    if v.is_empty() {
                        k.to_string()
                    } else {
                        format!("{k}={v}")
                    }
                })
                .collect();
            format!("OK {}", words.join(" ")).trim_end().to_string()
        }
        Line::Err(text) => format!("ERR {text}"),
        Line::Event(text) | Line::Other(text) => text,
    }
}

/// The command an `OK` reply answers, where its first field says so. Commands that share a
/// first field with another's reply are not named (they pair in order).
fn answered_by(reply: &Line) -> Option<Command> {
    let Line::Ok(fields) = reply else {
        return None;
    };
    let (first, _) = fields.iter().next()?;
    match first {
        "link" => Some(Command::Status),
        "fault" => Some(Command::Fault),
        "events" => Some(Command::EventsOn),
        "history" => Some(Command::History),
        "GASTEST" => Some(Command::GasCheck),
        _ if fields.get("link_ok").is_some() => Some(Command::Counters),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Duration = Duration::from_secs(1);

    /// 2026-11-26T07:30:00 UTC.
    const WALL_ORIGIN: u64 = 1_795_678_200;

    fn up() -> Dashboard {
        let mut dash = Dashboard::new("sim sync65", None, WALL_ORIGIN);
        let first = dash.connected(Duration::ZERO);
        assert_eq!(
            first,
            [
                Command::EventsOn,
                Command::Clock(1_795_678_200),
                Command::Consumables,
                Command::History
            ]
        );
        assert_eq!(first[1].text(), "CLOCK 2026-11-26T07:30:00");
        assert_eq!(first[3].text(), "HISTORY 6");
        dash.apply_line(Duration::ZERO, "OK events=ON");
        dash.apply_line(Duration::ZERO, "OK clock=2026-11-26T07:30:00");
        dash.apply_line(
            Duration::ZERO,
            "ERR SYNTAX unknown command (HELP lists the commands)",
        );
        dash.apply_line(
            Duration::ZERO,
            "HISTORY seq=2 boot=1 uptime_ms=800 clock=2026-11-26T07:29:59 family=- event=RESET cause=power-on",
        );
        dash.apply_line(Duration::ZERO, "OK history=1 skipped=0");
        dash
    }

    #[test]
    fn the_history_at_connect() {
        let dash = up();
        let History::Entries(rows) = &dash.history else {
            panic!("{:?}", dash.history);
        };
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].get("event"), "RESET");
        assert!(dash.pending.is_empty(), "{:?}", dash.pending);
    }

    #[test]
    fn the_history_again_after_events_at_most_once_a_second() {
        let mut dash = up();
        dash.apply_line(
            S / 2,
            "!FAULT 0-50-0 action=required text=The cartridge is off.",
        );
        // Half a second after the last ask: not yet.
        assert_eq!(
            dash.poll(S / 2),
            [Command::Status, Command::Fault, Command::Counters]
        );
        dash.apply_line(S / 2, "OK link=UP fault=0-50-0 out_amps=0 out_psi=0");
        dash.apply_line(
            S / 2,
            "OK fault=0-50-0 action=required text=The cartridge is off.",
        );
        dash.apply_line(S / 2, "OK link_ok=3 link_failed=0");
        assert_eq!(
            dash.poll(S),
            [Command::Status, Command::Fault, Command::History]
        );
        dash.apply_line(S, "OK link=UP fault=0-50-0 out_amps=0 out_psi=0");
        dash.apply_line(
            S,
            "OK fault=0-50-0 action=required text=The cartridge is off.",
        );
        dash.apply_line(
            S,
            "HISTORY seq=3 boot=1 uptime_ms=1400 clock=2026-11-26T07:30:01 family=SYNC event=FAULT code=0-50-0 action=required",
        );
        // An event while the history's reply comes: asked again, a second later.
        dash.apply_line(S, "!ARC OFF");
        dash.apply_line(
            S,
            "HISTORY seq=2 boot=1 uptime_ms=800 clock=2026-11-26T07:29:59 family=- event=RESET cause=power-on",
        );
        dash.apply_line(S, "OK history=2 skipped=0");
        let History::Entries(rows) = &dash.history else {
            panic!("{:?}", dash.history);
        };
        assert_eq!(
            rows.iter().map(|r| r.get("seq")).collect::<Vec<_>>(),
            ["3", "2"]
        );
        assert_eq!(dash.poll(S + S / 2), [Command::Status, Command::Fault]);
        dash.apply_line(S + S / 2, "OK link=UP fault=0-50-0 out_amps=0 out_psi=0");
        dash.apply_line(
            S + S / 2,
            "OK fault=0-50-0 action=required text=The cartridge is off.",
        );
        assert_eq!(
            dash.poll(2 * S),
            [Command::Status, Command::Fault, Command::History]
        );
    }

    #[test]
    fn a_bridge_without_history_says_so() {
        let mut dash = Dashboard::new("/dev/ttyACM0", None, 0);
        dash.connected(Duration::ZERO);
        dash.apply_line(Duration::ZERO, "OK events=ON");
        dash.apply_line(
            Duration::ZERO,
            "ERR SYNTAX unknown command (HELP lists the commands)",
        );
        dash.apply_line(
            Duration::ZERO,
            "ERR SYNTAX unknown command (HELP lists the commands)",
        );
        dash.apply_line(Duration::ZERO, "ERR STORAGE history not available");
        assert_eq!(
            dash.history,
            History::NotReported("ERR STORAGE history not available".into())
        );
        assert!(dash.pending.is_empty(), "{:?}", dash.pending);
    }

    #[test]
    fn a_consumable_warning_asks_again_and_stays_until_a_new_set() {
        let mut dash = Dashboard::new("sim pm65", None, 0);
        dash.connected(Duration::ZERO);
        for line in [
            "OK events=ON",
            "OK clock=1970-01-01T00:00:00",
            "OK consumables source=COUNTED starts=120 arc_s=3400 start_limit=150 arc_limit_s=OFF used=80% wear_faults=0",
            "OK history=0 skipped=0",
        ] {
            dash.apply_line(Duration::ZERO, line);
        }
        assert!(matches!(dash.consumables, Consumables::Reported(_)));
        dash.apply_line(S, "!WARN CONSUMABLE used=90% starts=135 arc_s=3700");
        assert_eq!(
            dash.consumable_warning.as_deref(),
            Some("WARN CONSUMABLE used=90% starts=135 arc_s=3700")
        );
        assert_eq!(
            dash.poll(S),
            [
                Command::Status,
                Command::Counters,
                Command::Consumables,
                Command::History
            ]
        );
        dash.apply_line(S, "OK link=UP fault=none out_amps=0 out_psi=0");
        dash.apply_line(S, "OK link_ok=3 link_failed=0");
        dash.apply_line(S, "OK consumables source=COUNTED starts=135 arc_s=3700 start_limit=150 arc_limit_s=OFF used=90% wear_faults=0");
        dash.apply_line(S, "OK history=0 skipped=0");
        let Consumables::Reported(fields) = &dash.consumables else {
            panic!("{:?}", dash.consumables);
        };
        assert_eq!(used_percent(fields), Some(90.0));
        assert!(dash.consumable_warning.is_some());
        // CONSUMABLES NEW: the next answer is a fresh set, the warning goes.
        dash.apply_line(2 * S, "!CONSUMABLES NEW");
        dash.poll(2 * S);
        dash.apply_line(2 * S, "OK link=UP fault=none out_amps=0 out_psi=0");
        dash.apply_line(2 * S, "OK history=0 skipped=0");
        dash.apply_line(3 * S, "!WARN CONSUMABLE used=90% starts=135 arc_s=3700");
        dash.poll(3 * S);
        dash.apply_line(3 * S, "OK link=UP fault=none out_amps=0 out_psi=0");
        dash.apply_line(3 * S, "OK consumables source=COUNTED starts=0 arc_s=0 start_limit=150 arc_limit_s=OFF used=0% wear_faults=0");
        assert_eq!(dash.consumable_warning, None);
    }

    #[test]
    fn used_share() {
        assert_eq!(
            used_percent(&Fields::parse("starts=3 used=45%")),
            Some(45.0)
        );
        assert_eq!(used_percent(&Fields::parse("starts=3 used=OFF")), None);
        assert_eq!(used_percent(&Fields::parse("starts=3")), None);
    }

    #[test]
    fn consumables_not_reported_when_unknown_command() {
        let dash = up();
        assert_eq!(dash.consumables, Consumables::NotReported);
    }

    #[test]
    fn polls_status_then_fault_while_a_fault_is_active() {
        let mut dash = up();
        assert_eq!(dash.poll(S), [Command::Status, Command::Counters]);
        // Nothing more until the replies came.
        assert_eq!(dash.poll(2 * S), []);
        dash.apply_line(2 * S, "OK link=UP model=Powermax65 family=SYNC remote=OFF mode=CUT amps=65 psi=72 out_amps=0 out_psi=0 fault=0-50-0 start=OFF motion=OFF arc_ok=OFF ready=OFF");
        dash.apply_line(2 * S, "OK link_ok=21 link_failed=0");
        assert_eq!(dash.fault.as_ref().map(|f| f.code.as_str()), Some("0-50-0"));
        assert_eq!(dash.poll(3 * S), [Command::Status, Command::Fault]);
        dash.apply_line(3 * S, "OK link=UP fault=0-50-0 out_amps=0 out_psi=0");
        dash.apply_line(
            3 * S,
            "OK fault=0-50-0 action=required text=The cartridge is off.",
        );
        let fault = dash.fault.clone().expect("fault");
        assert_eq!(fault.action, "required");
        assert_eq!(fault.text, "The cartridge is off.");
        dash.apply_line(4 * S, "!FAULT CLEARED code=0-50-0");
        assert_eq!(dash.fault, None);
        assert_eq!(
            dash.events.back(),
            Some(&(4 * S, "FAULT CLEARED code=0-50-0".to_string()))
        );
    }

    /// Two HPRs on the line, as `pbtool sim --ps hpr260 --ps hpr130 --fault 044` says it:
    /// unit 2's events and replies leave unit 1's picture as it was.
    #[test]
    fn another_units_lines_do_not_change_the_first_units() {
        let mut dash = up();
        assert_eq!(dash.poll(S), [Command::Status, Command::Counters]);
        dash.apply_line(S, "!LINK UP model=HPR130 HPR unit=2");
        dash.apply_line(
            S,
            "!FAULT 044 action=required unit=2 text=LOW PLASMA GAS PRESSURE",
        );
        assert_eq!(dash.fault, None);
        // Logged as they came, the unit named.
        assert_eq!(
            dash.events.back(),
            Some(&(
                S,
                "FAULT 044 action=required unit=2 text=LOW PLASMA GAS PRESSURE".to_string()
            ))
        );
        // A reply of unit 2 pairs with none of unit 1's commands.
        dash.apply_line(
            S,
            "OK link=UP model=HPR130 family=HPR out_amps=0 out_psi=55 fault=044 unit=2",
        );
        dash.apply_line(S, "OK link_ok=8 link_failed=5 unit=2");
        assert_eq!(dash.status, None);
        assert_eq!(dash.pending, [Command::Status, Command::Counters]);
        dash.apply_line(
            S,
            "OK link=UP model=HPR260 family=HPR out_amps=0 out_psi=55 fault=none",
        );
        dash.apply_line(S, "OK link_ok=8 link_failed=0");
        assert!(dash.pending.is_empty(), "{:?}", dash.pending);
        assert_eq!(
            dash.status.as_ref().and_then(|s| s.get("model")),
            Some("HPR260")
        );
        assert_eq!(dash.fault, None);
        // Unit 1's fault and its clearing still count; unit 2's clearing does not touch it.
        dash.apply_line(
            2 * S,
            "!FAULT 044 action=required text=LOW PLASMA GAS PRESSURE",
        );
        dash.apply_line(2 * S, "!FAULT CLEARED code=044 unit=2");
        assert_eq!(dash.fault.as_ref().map(|f| f.code.as_str()), Some("044"));
        dash.apply_line(2 * S, "!FAULT CLEARED code=044");
        assert_eq!(dash.fault, None);
    }

    #[test]
    fn a_fault_event_gives_the_action_and_text() {
        let mut dash = up();
        dash.apply_line(
            S,
            "!FAULT 0-12-1 action=recommended text=The gas pressure output is low.",
        );
        let fault = dash.fault.clone().expect("fault");
        assert_eq!(
            (
                fault.code.as_str(),
                fault.action.as_str(),
                fault.text.as_str()
            ),
            ("0-12-1", "recommended", "The gas pressure output is low.")
        );
    }

    #[test]
    fn a_lost_reply_does_not_stop_polling() {
        let mut dash = up();
        assert!(!dash.poll(S).is_empty());
        assert_eq!(dash.poll(S + REPLY_TIMEOUT - Duration::from_millis(1)), []);
        assert_eq!(dash.poll(S + REPLY_TIMEOUT), [Command::Status]);
    }

    #[test]
    fn late_replies_pair_again() {
        let mut dash = Dashboard::new("emu sync65", None, 0);
        dash.connected(Duration::ZERO);
        // The board is slow to come up: the first commands time out.
        assert_eq!(
            dash.poll(REPLY_TIMEOUT),
            [Command::Status, Command::Counters]
        );
        // Their late replies come, then the STATUS reply.
        dash.apply_line(4 * S, "OK events=ON");
        dash.apply_line(
            4 * S,
            "ERR SYNTAX unknown command (HELP lists the commands)",
        );
        dash.apply_line(
            4 * S,
            "OK link=UP model=Powermax65 fault=none out_amps=0 out_psi=0",
        );
        dash.apply_line(4 * S, "OK link_ok=3 link_failed=0");
        // At most a round is lost: the next STATUS pairs.
        assert_eq!(dash.poll(5 * S), [Command::Status]);
        dash.apply_line(
            5 * S,
            "OK link=UP model=Powermax65 fault=none out_amps=0 out_psi=0",
        );
        assert_eq!(
            dash.status.as_ref().and_then(|s| s.get("model")),
            Some("Powermax65")
        );
        assert_eq!(dash.poll(6 * S), [Command::Status]);
    }

    #[test]
    fn errors_per_minute_from_link_failed() {
        let mut dash = up();
        dash.poll(S);
        dash.apply_line(S, "OK link=UP out_amps=0 out_psi=0 fault=none");
        dash.apply_line(S, "OK link_failed=4");
        assert_eq!(dash.errors_per_minute(), None);
        dash.poll(11 * S);
        dash.apply_line(11 * S, "OK link=UP out_amps=0 out_psi=0 fault=none");
        dash.apply_line(11 * S, "OK link_failed=6");
        assert_eq!(dash.errors_per_minute(), Some(12.0));
    }

    #[test]
    fn keys_send_and_show_the_reply() {
        let mut dash = up();
        assert_eq!(dash.key(S, 'g'), KeyAction::Send(Command::GasCheck));
        // The gas flows for a while: no "no reply" within the usual time.
        assert_eq!(dash.poll(S + REPLY_TIMEOUT), []);
        dash.apply_line(
            S + REPLY_TIMEOUT,
            "OK GASTEST CHECK result=PASS measured_psi=72 min_psi=65 max_psi=80",
        );
        assert_eq!(
            dash.gas_check.as_deref(),
            Some("OK GASTEST CHECK result=PASS measured_psi=72 min_psi=65 max_psi=80")
        );
        // It stays until the next check, whatever else is sent.
        assert_eq!(dash.key(S, 'r'), KeyAction::Send(Command::RemoteOff));
        dash.apply_line(S, "OK remote=OFF");
        assert!(dash.gas_check.is_some());
        assert_eq!(dash.key(S, 'g'), KeyAction::Send(Command::GasCheck));
        dash.apply_line(S, "ERR BUSY the arc is on");
        assert_eq!(dash.gas_check.as_deref(), Some("ERR BUSY the arc is on"));
        assert_eq!(dash.key(S, 'c'), KeyAction::Send(Command::ClearWarnings));
        dash.apply_line(S, "ERR UNSUPPORTED CLEARWARN is an HPR command");
        assert_eq!(
            dash.last_action.as_deref(),
            Some("CLEARWARN: ERR UNSUPPORTED CLEARWARN is an HPR command")
        );
        assert_eq!(dash.key(S, 'q'), KeyAction::Quit);
        assert_eq!(dash.key(S, 'x'), KeyAction::Ignored);
    }

    #[test]
    fn lost_connection_sends_nothing() {
        let mut dash = up();
        dash.lost(S, "child exited");
        assert_eq!(dash.poll(2 * S), []);
        assert_eq!(dash.key(2 * S, 'r'), KeyAction::Ignored);
        assert!(matches!(dash.connection, Connection::Lost { .. }));
    }
}
