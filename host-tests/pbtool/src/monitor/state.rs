//! The dashboard's model: what the bridge said, fed line by line, and which commands are due.
//! No I/O and no clock of its own: every call takes `now`, the time since the monitor started.

use std::collections::VecDeque;
use std::time::Duration;

use super::parse::{ActiveFault, Fields, Line};

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
    /// `CONSUMABLES`, asked once per connection.
    Consumables,
    /// `GASTEST ON` / `GASTEST OFF`.
    GasTest(bool),
    /// `REMOTE OFF`.
    RemoteOff,
    /// `CLEARWARN`.
    ClearWarnings,
}

impl Command {
    /// The command line, without its line end.
    pub fn text(self) -> &'static str {
        match self {
            Command::EventsOn => "EVENTS ON",
            Command::Status => "STATUS",
            Command::Fault => "FAULT",
            Command::Counters => "COUNTERS",
            Command::Consumables => "CONSUMABLES",
            Command::GasTest(true) => "GASTEST ON",
            Command::GasTest(false) => "GASTEST OFF",
            Command::RemoteOff => "REMOTE OFF",
            Command::ClearWarnings => "CLEARWARN",
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
    /// Whether the gas test is on (as the last GASTEST reply said).
    pub gas_test: bool,
    /// The latest events and the monitor's own notes, newest last, with their times.
    pub events: VecDeque<(Duration, String)>,
    /// The plot's points, oldest first, within [`PLOT_WINDOW`].
    pub samples: VecDeque<Sample>,
    /// The reply to the last key's command (`REMOTE OFF: OK remote=OFF`).
    pub last_action: Option<String>,
    counters: VecDeque<(Duration, f64)>,
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
            gas_test: false,
            events: VecDeque::new(),
            samples: VecDeque::new(),
            last_action: None,
            counters: VecDeque::new(),
            pending: VecDeque::new(),
            pending_since: Duration::ZERO,
            next_status: Duration::ZERO,
            next_counters: Duration::ZERO,
        }
    }

    /// The connection is up: what to send first (events on, whether consumables are reported).
    pub fn connected(&mut self, now: Duration) -> Vec<Command> {
        self.connection = Connection::Up;
        self.pending.clear();
        self.counters.clear();
        self.note(now, format!("connected to {}", self.source));
        self.next_status = now;
        self.next_counters = now;
        let first = vec![Command::EventsOn, Command::Consumables];
        self.sent(now, &first);
        first
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
        if !self.pending.is_empty() {
            if now.saturating_sub(self.pending_since) < REPLY_TIMEOUT {
                return Vec::new();
            }
            self.note(now, format!("no reply to {}", self.pending[0].text()));
            self.pending.clear();
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
        self.sent(now, &due);
        due
    }

    /// A key pressed: `q` quits, `g` gas test on/off, `r` remote off, `c` clear warnings.
    pub fn key(&mut self, now: Duration, key: char) -> KeyAction {
        let command = match key {
            'q' | 'Q' => return KeyAction::Quit,
            'g' | 'G' => Command::GasTest(!self.gas_test),
            'r' | 'R' => Command::RemoteOff,
            'c' | 'C' => Command::ClearWarnings,
            _ => return KeyAction::Ignored,
        };
        if self.connection != Connection::Up {
            self.last_action = Some(format!("{}: not connected", command.text()));
            return KeyAction::Ignored;
        }
        self.sent(now, &[command]);
        self.last_action = Some(format!("{}: sent", command.text()));
        KeyAction::Send(command)
    }

    /// One line from the bridge.
    pub fn apply_line(&mut self, now: Duration, line: &str) {
        match Line::parse(line) {
            Line::Event(event) => self.event(now, event),
            Line::Other(_) => {}
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
                self.consumables = Consumables::Reported(fields);
            }
            (Command::Consumables, _) => self.consumables = Consumables::NotReported,
            (Command::Status | Command::Fault | Command::Counters | Command::EventsOn, _) => {}
            (action, reply) => {
                if let (Command::GasTest(_), Line::Ok(fields)) = (action, &reply)
                    && let Some(state) = fields.get("gastest")
                {
                    self.gas_test = state == "ON";
                }
                let answer = match reply {
                    Line::Ok(fields) => {
                        let words: Vec<String> =
                            fields.iter().map(|(k, v)| format!("{k}={v}")).collect();
                        format!("OK {}", words.join(" "))
                    }
                    Line::Err(text) => format!("ERR {text}"),
                    Line::Event(text) | Line::Other(text) => text,
                };
                self.last_action = Some(format!("{}: {answer}", action.text()));
            }
        }
    }

    fn event(&mut self, now: Duration, event: String) {
        if let Some(code) = event.strip_prefix("FAULT CLEARED code=") {
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

/// The command an `OK` reply answers, where its first field says so.
fn answered_by(reply: &Line) -> Option<Command> {
    let Line::Ok(fields) = reply else {
        return None;
    };
    let (first, value) = fields.iter().next()?;
    match first {
        "link" => Some(Command::Status),
        "fault" => Some(Command::Fault),
        "events" => Some(Command::EventsOn),
        "gastest" => Some(Command::GasTest(value == "ON")),
        _ if fields.get("link_ok").is_some() => Some(Command::Counters),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Duration = Duration::from_secs(1);

    fn up() -> Dashboard {
        let mut dash = Dashboard::new("sim sync65", None, 0);
        assert_eq!(
            dash.connected(Duration::ZERO),
            [Command::EventsOn, Command::Consumables]
        );
        dash.apply_line(Duration::ZERO, "OK events=ON");
        dash.apply_line(
            Duration::ZERO,
            "ERR SYNTAX unknown command (HELP lists the commands)",
        );
        dash
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
        assert_eq!(dash.key(S, 'g'), KeyAction::Send(Command::GasTest(true)));
        dash.apply_line(S, "OK gastest=ON");
        assert!(dash.gas_test);
        assert_eq!(dash.key(S, 'g'), KeyAction::Send(Command::GasTest(false)));
        dash.apply_line(S, "OK gastest=OFF");
        assert!(!dash.gas_test);
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
