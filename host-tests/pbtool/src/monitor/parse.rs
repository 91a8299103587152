//! The bridge's CNC text lines as the dashboard reads them: `OK`/`ERR` replies split into
//! `key=value` fields, and `!` events (docs/cnc-protocol.md sections 1, 3 and 6).

/// One line from the bridge.
#[derive(Debug, Clone, PartialEq)]
pub enum Line {
    /// `OK key=value ...`: a reply that succeeded.
    Ok(Fields),
    /// `ERR CODE message`: a reply that failed; the text after `ERR `.
    Err(String),
    /// `!...`: an event; the text after `!`.
    Event(String),
    /// Anything else (a blank line, a banner): kept as it came.
    Other(String),
}

impl Line {
    /// Reads one line (without its line end; a trailing CR is dropped).
    pub fn parse(line: &str) -> Line {
        let line = line.trim_end_matches(['\r', '\n']);
        if let Some(rest) = line.strip_prefix('!') {
            Line::Event(rest.to_string())
        } else if line == "OK" {
            Line::Ok(Fields::default())
        } else if let Some(rest) = line.strip_prefix("OK ") {
            Line::Ok(Fields::parse(rest))
        } else if let Some(rest) = line.strip_prefix("ERR ") {
            Line::Err(rest.to_string())
        } else {
            Line::Other(line.to_string())
        }
    }
}

/// The unit a reply or event is about: `unit=N` (N = 1-4) before any free-text field (`text=`,
/// `reply=`, which run to the end of the line); 1 without it (docs/cnc-protocol.md section 10).
/// An `ERR` line carries it right after the code, which this finds as well.
pub fn unit_of(line: &str) -> u8 {
    line.split(' ')
        .take_while(|word| !word.starts_with("text=") && !word.starts_with("reply="))
        .find_map(|word| word.strip_prefix("unit=")?.parse().ok())
        .filter(|unit| (1..=4).contains(unit))
        .unwrap_or(1)
}

/// The `key=value` fields of a reply, in order. `text=` runs to the end of the line, as the
/// protocol says, so a fault's text keeps its spaces.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Fields(Vec<(String, String)>);

impl Fields {
    /// Splits `key=value key=value ... [text=free text]`; a word without `=` is a key with an
    /// empty value.
    pub fn parse(text: &str) -> Fields {
        let mut fields = Vec::new();
        let mut rest = text.trim_start();
        while !rest.is_empty() {
            if let Some(free) = rest.strip_prefix("text=") {
                fields.push(("text".to_string(), free.to_string()));
                break;
            }
            let (word, after) = rest.split_once(' ').unwrap_or((rest, ""));
            let (key, value) = word.split_once('=').unwrap_or((word, ""));
            fields.push((key.to_string(), value.to_string()));
            rest = after.trim_start();
        }
        Fields(fields)
    }

    /// The value of `key`, if the reply has it.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.0
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// The value of `key` as a number; `None` when absent or unknown (`-`, `AUTO`).
    pub fn number(&self, key: &str) -> Option<f64> {
        self.get(key)?.parse().ok()
    }

    /// Whether `key` reads `ON`.
    pub fn is_on(&self, key: &str) -> bool {
        self.get(key) == Some("ON")
    }

    /// Every field, in the order of the line.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &str)> {
        self.0.iter().map(|(k, v)| (k.as_str(), v.as_str()))
    }
}

/// The active fault as `FAULT` answers it.
#[derive(Debug, Clone, PartialEq)]
pub struct ActiveFault {
    /// `0-50-0`, HPR `044`.
    pub code: String,
    /// `required`, `recommended` or `none`: the steps to remove it.
    pub action: String,
    /// The manual's text.
    pub text: String,
}

impl ActiveFault {
    /// The fault of a `FAULT` reply; `None` for `fault=none` or another reply.
    pub fn from_reply(fields: &Fields) -> Option<ActiveFault> {
        let code = fields.get("fault")?;
        if code == "none" {
            return None;
        }
        Some(ActiveFault {
            code: code.to_string(),
            action: fields.get("action").unwrap_or("-").to_string(),
            text: fields.get("text").unwrap_or("").to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Lines as `pbtool sim --fast --ps sync65 --fault 0-50-0` answers EVENTS ON, STATUS,
    // FAULT, CONSUMABLES and COUNTERS.
    const EVENTS_ON: &str = "OK events=ON";
    const STATUS: &str = "OK link=UP model=Powermax65 family=SYNC remote=OFF mode=CUT amps=65 psi=72 out_amps=0 out_psi=0 fault=0-50-0 start=OFF motion=OFF arc_ok=OFF ready=OFF";
    const FAULT: &str = "OK fault=0-50-0 action=required text=The cartridge is off, the torch was disconnected when you set the plasma power supply to ON (I), or the torch was in the yellow lock (X) position during a restart.";
    const UNKNOWN: &str = "ERR SYNTAX unknown command (HELP lists the commands)";
    const COUNTERS: &str = "OK starts=0 pilot_arc_s=0 transfers=0 transfer_s=0 link_ok=21 link_failed=0 retries=0 timeouts=0 bad_checksums=0 link_downs=0";

    #[test]
    fn status_fields() {
        let Line::Ok(fields) = Line::parse(STATUS) else {
            panic!("not an OK line");
        };
        assert_eq!(fields.get("link"), Some("UP"));
        assert_eq!(fields.get("model"), Some("Powermax65"));
        assert_eq!(fields.number("amps"), Some(65.0));
        assert_eq!(fields.number("out_psi"), Some(0.0));
        assert_eq!(fields.get("fault"), Some("0-50-0"));
        assert!(!fields.is_on("ready"));
        assert_eq!(fields.get("state"), None);
    }

    #[test]
    fn unknown_values_are_not_numbers() {
        let Line::Ok(fields) = Line::parse(
            "OK link=DOWN model=- family=- remote=OFF mode=- amps=- psi=AUTO out_amps=- out_psi=-",
        ) else {
            panic!("not an OK line");
        };
        assert_eq!(fields.number("amps"), None);
        assert_eq!(fields.number("psi"), None);
        assert_eq!(fields.get("psi"), Some("AUTO"));
    }

    #[test]
    fn fault_text_keeps_its_spaces() {
        let Line::Ok(fields) = Line::parse(FAULT) else {
            panic!("not an OK line");
        };
        let fault = ActiveFault::from_reply(&fields).expect("a fault");
        assert_eq!(fault.code, "0-50-0");
        assert_eq!(fault.action, "required");
        assert!(fault.text.starts_with("The cartridge is off, the torch"));
        assert!(fault.text.ends_with("during a restart."));
    }

    // Lines of `pbtool sim --ps hpr260 --ps hpr130` and docs/cnc-protocol.md section 10.
    #[test]
    fn the_unit_a_line_is_about() {
        assert_eq!(unit_of("OK fault=none unit=2"), 2);
        assert_eq!(
            unit_of("!FAULT 044 action=required unit=2 text=LOW PLASMA GAS PRESSURE"),
            2
        );
        assert_eq!(
            unit_of("ERR SYNTAX unit=3 unknown command (HELP lists the commands)"),
            3
        );
        assert_eq!(unit_of("!LINK UP model=HPR130 HPR unit=2"), 2);
        assert_eq!(
            unit_of("!FAULT 044 action=required text=LOW PLASMA GAS PRESSURE"),
            1
        );
        // A unit named inside free text is not the line's.
        assert_eq!(unit_of("OK fault=044 action=required text=see unit=2"), 1);
        assert_eq!(unit_of("OK raw reply=>01 unit=4 00<"), 1);
        assert_eq!(unit_of("OK unit=9"), 1);
    }

    #[test]
    fn no_fault() {
        let Line::Ok(fields) = Line::parse("OK fault=none") else {
            panic!("not an OK line");
        };
        assert_eq!(ActiveFault::from_reply(&fields), None);
    }

    #[test]
    fn other_kinds() {
        assert_eq!(
            Line::parse(UNKNOWN),
            Line::Err("SYNTAX unknown command (HELP lists the commands)".into())
        );
        assert_eq!(
            Line::parse("!FAULT CLEARED code=0-50-0\r"),
            Line::Event("FAULT CLEARED code=0-50-0".into())
        );
        assert_eq!(Line::parse("OK"), Line::Ok(Fields::default()));
        let Line::Ok(fields) = Line::parse(EVENTS_ON) else {
            panic!("not an OK line");
        };
        assert!(fields.is_on("events"));
        let Line::Ok(fields) = Line::parse(COUNTERS) else {
            panic!("not an OK line");
        };
        assert_eq!(fields.number("link_failed"), Some(0.0));
        assert_eq!(fields.number("link_ok"), Some(21.0));
    }
}
