//! `pbtool config`: sets the framing of the bridge's CNC port from a PC on that port, both ends
//! in step.
//!
//! A change of `cnc_baud`, `cnc_data_bits`, `cnc_parity` or `cnc_stop_bits` applies on the board right after
//! its reply, so the PC must follow each one before it sends the next: done by hand in a
//! terminal program, one missed step leaves the two ends at different framings. Here:
//!
//! 1. Find the board: `ID` at each framing the board can run ([`candidates`]: the one asked
//!    for first, then the default, then the rest) until a clean `OK bridge=` comes back. This
//!    also finds a framing saved and forgotten.
//! 2. Read the board's own CNC settings (`CONFIG`): on a pty every framing "works", and the
//!    board's word is what counts.
//! 3. Change baud, data bits, parity, stop bits one at a time ([`steps`]), the PC following each reply.
//! 4. `ID` again at the new framing; `CONFIG SAVE` when asked to.

use std::fmt;
use std::time::{Duration, Instant};

use plasma_firmware::settings::CNC_BAUDS;
use plasma_protocol::serial::{DataBits, Parity, PortConfig, StopBits};

use crate::serial::{CNC_PORT, Port, Rx, SerialError, describe};

/// How long one command waits for its reply (the board answers within milliseconds; a USB
/// serial port adds a few).
pub const REPLY_TIMEOUT: Duration = Duration::from_millis(400);
/// After a reply that changed the framing, before the next command: the board switches once
/// the reply's last stop bit has left, which the PC hears a moment later.
const SWITCH_PAUSE: Duration = Duration::from_millis(50);

/// Why the framing could not be set.
#[derive(Debug)]
pub enum ConfigError {
    /// The port could not be used.
    Port(SerialError),
    /// No framing got an answer to `ID`.
    NoBoard,
    /// The board answered, but not as expected (a refusal, or no reply after a change).
    Refused {
        /// What was sent.
        command: String,
        /// What came back (empty: nothing).
        reply: String,
    },
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::Port(e) => e.fmt(f),
            ConfigError::NoBoard => write!(
                f,
                "no bridge answered ID at any framing: is this the board's CNC port (the \
                 ST-LINK's USB serial port, /dev/ttyACM0 or /dev/serial/by-id/usb-STMicro...), \
                 is the firmware running (LD2 blinks), and does no other program (LinuxCNC, \
                 a terminal) have the port open?"
            ),
            ConfigError::Refused { command, reply } if reply.is_empty() => {
                write!(f, "no reply to {command}")
            }
            ConfigError::Refused { command, reply } => {
                write!(f, "{command} was answered {reply}")
            }
        }
    }
}

impl std::error::Error for ConfigError {}

impl From<SerialError> for ConfigError {
    fn from(e: SerialError) -> ConfigError {
        ConfigError::Port(e)
    }
}

/// Every framing the board's CNC port can run, `first` first, then the default, then the
/// others (8 data bits before 7, slow to fast, parity before none).
pub fn candidates(first: PortConfig) -> Vec<PortConfig> {
    let mut all = vec![first, CNC_PORT];
    for data_bits in [DataBits::Eight, DataBits::Seven] {
        for baud in CNC_BAUDS {
            for parity in [Parity::Even, Parity::None, Parity::Odd] {
                for stop_bits in [StopBits::One, StopBits::Two] {
                    all.push(PortConfig::new(baud, parity, stop_bits).with_data_bits(data_bits));
                }
            }
        }
    }
    let mut unique = Vec::new();
    for framing in all {
        if !unique.contains(&framing) {
            unique.push(framing);
        }
    }
    unique
}

/// The `CONFIG` commands that take the CNC port from `from` to `to`, one setting each (baud,
/// then data bits, parity, stop bits), each with the framing both ends run after its reply.
pub fn steps(from: PortConfig, to: PortConfig) -> Vec<(String, PortConfig)> {
    let mut now = from;
    let mut steps = Vec::new();
    if now.baud != to.baud {
        now.baud = to.baud;
        steps.push((format!("CONFIG cnc_baud {}", to.baud), now));
    }
    if now.data_bits != to.data_bits {
        now.data_bits = to.data_bits;
        let bits = to.data_bits.number();
        steps.push((format!("CONFIG cnc_data_bits {bits}"), now));
    }
    if now.parity != to.parity {
        now.parity = to.parity;
        let word = match to.parity {
            Parity::None => "NONE",
            Parity::Even => "EVEN",
            Parity::Odd => "ODD",
        };
        steps.push((format!("CONFIG cnc_parity {word}"), now));
    }
    if now.stop_bits != to.stop_bits {
        now.stop_bits = to.stop_bits;
        let bits = match to.stop_bits {
            StopBits::One => 1,
            StopBits::Two => 2,
        };
        steps.push((format!("CONFIG cnc_stop_bits {bits}"), now));
    }
    steps
}

/// The CNC framing in a `CONFIG` reply (`... cnc_baud=19200 cnc_parity=EVEN cnc_stop_bits=1
/// cnc_data_bits=8`; 8 data bits from firmware that has no `cnc_data_bits`).
pub fn framing_in(config_reply: &str) -> Option<PortConfig> {
    let value = |key: &str| {
        config_reply
            .split_whitespace()
            .find_map(|word| word.strip_prefix(key)?.strip_prefix('='))
    };
    let baud = value("cnc_baud")?.parse().ok()?;
    let parity = match value("cnc_parity")? {
        "NONE" => Parity::None,
        "EVEN" => Parity::Even,
        "ODD" => Parity::Odd,
        _ => return None,
    };
    let stop_bits = match value("cnc_stop_bits")? {
        "1" => StopBits::One,
        "2" => StopBits::Two,
        _ => return None,
    };
    let data_bits = match value("cnc_data_bits") {
        None | Some("8") => DataBits::Eight,
        Some("7") => DataBits::Seven,
        Some(_) => return None,
    };
    Some(PortConfig::new(baud, parity, stop_bits).with_data_bits(data_bits))
}

/// What [`set_cnc_framing`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Outcome {
    /// The framing the board's CNC port ran when found.
    pub found: PortConfig,
    /// The framing it runs now.
    pub now: PortConfig,
    /// Whether `CONFIG SAVE` stored it.
    pub saved: bool,
}

/// Sets the CNC port of the board on `port` to `target` (and saves it when `save`), telling
/// `progress` each step.
pub fn set_cnc_framing(
    port: &str,
    target: PortConfig,
    save: bool,
    progress: &mut dyn FnMut(&str),
) -> Result<Outcome, ConfigError> {
    let mut line = LineEnd::new(Port::open(port, target)?);
    let answered_at = find_board(&mut line, target, progress)?;
    let config = line.command("CONFIG", "OK ")?;
    let found = framing_in(&config).ok_or_else(|| ConfigError::Refused {
        command: "CONFIG".to_string(),
        reply: config.clone(),
    })?;
    if found != answered_at {
        // A pty carries every framing; the board knows its own.
        line.port.set_config(found)?;
    }
    progress(&format!("the board's CNC port runs {}", describe(found)));
    for (command, framing) in steps(found, target) {
        let wanted = command
            .strip_prefix("CONFIG ")
            .unwrap_or(&command)
            .replacen(' ', "=", 1);
        line.command(&command, &format!("OK {wanted}"))?;
        line.port.set_config(framing)?;
        progress(&format!("{command}: both ends now {}", describe(framing)));
        std::thread::sleep(SWITCH_PAUSE);
    }
    line.command("ID", "OK bridge=")?;
    if save {
        line.command("CONFIG SAVE", "OK config=saved")?;
    }
    Ok(Outcome {
        found,
        now: target,
        saved: save,
    })
}

/// The first of [`candidates`] at which `ID` gets a clean answer.
fn find_board(
    line: &mut LineEnd,
    target: PortConfig,
    progress: &mut dyn FnMut(&str),
) -> Result<PortConfig, ConfigError> {
    for framing in candidates(target) {
        line.port.set_config(framing)?;
        // A partial line left by an earlier try ends here (the board answers it or not).
        line.send("")?;
        match line.command("ID", "OK bridge=") {
            Ok(_) => {
                progress(&format!("found the bridge at {}", describe(framing)));
                return Ok(framing);
            }
            Err(ConfigError::Refused { .. }) => {
                progress(&format!("no answer at {}", describe(framing)));
            }
            Err(e) => return Err(e),
        }
    }
    Err(ConfigError::NoBoard)
}

/// Lines to and from the board's CNC port.
struct LineEnd {
    port: Port,
    received: Vec<Rx>,
}

impl LineEnd {
    fn new(port: Port) -> LineEnd {
        LineEnd {
            port,
            received: Vec::new(),
        }
    }

    fn send(&mut self, text: &str) -> Result<(), SerialError> {
        self.port.write_all(format!("{text}\r\n").as_bytes())
    }

    /// Sends `command` and returns the first reply line that starts with `OK`/`ERR` and has no
    /// flagged character (others are noise from a wrong framing or event lines); a refusal
    /// when it does not start with `wanted` or none came within [`REPLY_TIMEOUT`].
    fn command(&mut self, command: &str, wanted: &str) -> Result<String, ConfigError> {
        self.drain()?;
        self.send(command)?;
        let deadline = Instant::now() + REPLY_TIMEOUT;
        let mut reply = String::new();
        while reply.is_empty() {
            let now = Instant::now();
            if now >= deadline {
                break;
            }
            self.port.read(deadline - now, &mut self.received)?;
            while let Some(end) = self.received.iter().position(|&r| r == Rx::Byte(b'\n')) {
                let line: Vec<Rx> = self.received.drain(..=end).collect();
                if line.contains(&Rx::Error) {
                    continue;
                }
                let text = String::from_utf8_lossy(&Rx::cnc_bytes(&line))
                    .trim()
                    .to_string();
                if text.starts_with("OK") || text.starts_with("ERR") {
                    reply = text;
                    break;
                }
            }
        }
        if reply.starts_with(wanted) {
            Ok(reply)
        } else {
            Err(ConfigError::Refused {
                command: command.to_string(),
                reply,
            })
        }
    }

    /// Drops what arrived before a command (an answer to an earlier try, events).
    fn drain(&mut self) -> Result<(), SerialError> {
        self.received.clear();
        let mut stale = Vec::new();
        loop {
            self.port.read(Duration::from_millis(20), &mut stale)?;
            if stale.is_empty() {
                return Ok(());
            }
            stale.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PMX485: PortConfig = PortConfig::MODBUS_DEFAULT;

    #[test]
    fn the_framing_asked_for_is_tried_first_then_the_default_then_every_other_once() {
        let all = candidates(PMX485);
        assert_eq!(all[..2], [PMX485, CNC_PORT]);
        assert_eq!(all.len(), 2 * CNC_BAUDS.len() * 3 * 2);
        assert!(all.iter().any(|f| f.data_bits == DataBits::Seven));
        assert!(all.iter().enumerate().all(|(i, f)| !all[..i].contains(f)));
    }

    #[test]
    fn baud_changes_first_then_parity_then_stop_bits() {
        let to = PortConfig {
            stop_bits: StopBits::Two,
            ..PMX485
        };
        let steps = steps(CNC_PORT, to);
        let commands: Vec<&str> = steps.iter().map(|(c, _)| c.as_str()).collect();
        assert_eq!(
            commands,
            [
                "CONFIG cnc_baud 19200",
                "CONFIG cnc_parity EVEN",
                "CONFIG cnc_stop_bits 2"
            ]
        );
        assert_eq!(steps[0].1, PortConfig::HPR);
        assert_eq!(steps[1].1, PMX485);
        assert_eq!(steps[2].1, to);
    }

    #[test]
    fn nothing_to_change_is_no_step() {
        assert!(steps(PMX485, PMX485).is_empty());
        assert_eq!(steps(PortConfig::HPR, PMX485).len(), 1);
    }

    #[test]
    fn the_cnc_framing_is_read_from_a_config_reply() {
        let reply = "OK protocol=AUTO address=1 parity=EVEN cnc_address=1 cnc_baud=19200 \
                     cnc_parity=EVEN cnc_stop_bits=1";
        assert_eq!(framing_in(reply), Some(PMX485));
        // `parity=` (the power supply's) is not `cnc_parity=`.
        assert_eq!(framing_in("OK parity=EVEN cnc_baud=9600"), None);
        assert_eq!(
            framing_in("OK cnc_baud=9600 cnc_parity=ODD cnc_stop_bits=2"),
            Some(PortConfig::new(9_600, Parity::Odd, StopBits::Two))
        );
        assert_eq!(
            framing_in("OK cnc_baud=4800 cnc_parity=EVEN cnc_stop_bits=1 cnc_data_bits=7"),
            PortConfig::from_framing(4800, "7E1")
        );
        assert_eq!(
            framing_in("OK cnc_baud=4800 cnc_parity=EVEN cnc_stop_bits=1 cnc_data_bits=9"),
            None
        );
    }

    #[test]
    fn seven_data_bits_are_a_step_of_their_own() {
        let phoenix = PortConfig::from_framing(4800, "7E1").unwrap();
        let steps = steps(CNC_PORT, phoenix);
        let commands: Vec<&str> = steps.iter().map(|(c, _)| c.as_str()).collect();
        assert_eq!(
            commands,
            [
                "CONFIG cnc_baud 4800",
                "CONFIG cnc_data_bits 7",
                "CONFIG cnc_parity EVEN"
            ]
        );
        assert_eq!(steps[2].1, phoenix);
    }
}
