//! The `CONFIG` text interface: each key's value as `CONFIG` shows it, the values it accepts,
//! and how a typed value changes the [`Settings`] (refused precisely, or changed).

use core::fmt;

use plasma_protocol::cnc::phoenix::Format;
use plasma_protocol::cnc::{ConfigKey, ErrorCode};
use plasma_protocol::serial::{DataBits, Parity, StopBits};
use plasma_protocol::time::Duration;

use super::{ARC_OK_DEBOUNCE_MS, CNC_BAUDS, CncPort, Settings, TRANSFER_TIMEOUT_MS, ms, wiring};
use crate::consumables::Limits;
use crate::link::{LinkConfig, NamedUnits, ProtocolChoice, UnitsError};

const CNC_BAUD_WORDS: &str = "1200|2400|4800|9600|19200|38400|57600|115200";
/// Every format value the Phoenix manual lists (a test ties it to [`Format::ALL`]).
const PHOENIX_FORMAT_WORDS: &str = "0|1|16|17|32|33|48|49|64|65|80|81|96|97|112|113";

fn parse_parity(key: ConfigKey, text: &str) -> Result<Parity, SetError<'_>> {
    [Parity::None, Parity::Even, Parity::Odd]
        .into_iter()
        .find(|p| {
            let name = parity_name(*p);
            name.eq_ignore_ascii_case(text)
                || (text.len() == 1 && name.get(..1).is_some_and(|c| c.eq_ignore_ascii_case(text)))
        })
        .ok_or(SetError::BadWord {
            key,
            expected: "NONE|EVEN|ODD",
        })
}

fn parse_stop_bits(key: ConfigKey, text: &str) -> Result<StopBits, SetError<'_>> {
    match text {
        "1" => Ok(StopBits::One),
        "2" => Ok(StopBits::Two),
        _ => Err(SetError::BadWord {
            key,
            expected: "1|2",
        }),
    }
}

/// 7 or 8. The L4 USART runs both with every parity and stop-bit setting (RM0351, USART_CR1
/// M1/M0: a 7-, 8- or 9-bit word, the parity bit included; `plasma_tasks::uart` picks it),
/// so no framing is refused.
fn parse_data_bits(key: ConfigKey, text: &str) -> Result<DataBits, SetError<'_>> {
    match text {
        "7" => Ok(DataBits::Seven),
        "8" => Ok(DataBits::Eight),
        _ => Err(SetError::BadWord {
            key,
            expected: "7|8",
        }),
    }
}

fn parse_cnc_baud(key: ConfigKey, text: &str) -> Result<u32, SetError<'_>> {
    let bad = SetError::BadWord {
        key,
        expected: CNC_BAUD_WORDS,
    };
    match parse_number(key, text, (0, u32::MAX)) {
        Ok(baud) if CNC_BAUDS.contains(&baud) => Ok(baud),
        _ => Err(bad),
    }
}

/// Why `CONFIG <key> <value>` was refused; `Display` is the text after `ERR <CODE> `.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SetError<'a> {
    /// The value should be a decimal number.
    NotANumber {
        /// The key.
        key: ConfigKey,
    },
    /// The value should be one of a few words.
    BadWord {
        /// The key.
        key: ConfigKey,
        /// The accepted words.
        expected: &'static str,
    },
    /// A number outside the key's range.
    OutOfRange {
        /// The key.
        key: ConfigKey,
        /// The value as typed (digits only).
        value: &'a str,
        /// Lowest accepted.
        min: u32,
        /// Highest accepted.
        max: u32,
    },
    /// A number that is not one of the Phoenix manual's format values.
    NotPhoenixFormat {
        /// The value as typed (digits only).
        value: &'a str,
    },
    /// Units that are not a list `CONFIG units` takes, or cannot share a line.
    Units(UnitsError),
}

impl SetError<'_> {
    /// The reply code.
    pub const fn code(&self) -> ErrorCode {
        match self {
            SetError::NotANumber { .. }
            | SetError::BadWord { .. }
            | SetError::Units(UnitsError::Syntax) => ErrorCode::Syntax,
            SetError::OutOfRange { .. } | SetError::NotPhoenixFormat { .. } => ErrorCode::Range,
            SetError::Units(UnitsError::Line(_)) => ErrorCode::Refused,
        }
    }
}

impl fmt::Display for SetError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SetError::NotANumber { key } => write!(f, "{}: not a number", key.name()),
            SetError::BadWord { key, expected } => {
                write!(f, "{}: expected {expected}", key.name())
            }
            SetError::OutOfRange {
                key,
                value,
                min,
                max,
            } => write!(f, "{} {value} outside {min}..{max}", key.name()),
            SetError::NotPhoenixFormat { value } => write!(
                f,
                "phoenix_format {value} is not a Phoenix format ({PHOENIX_FORMAT_WORDS})"
            ),
            SetError::Units(error) => error.fmt(f),
        }
    }
}

/// The value of one key, as `CONFIG` prints it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigValue {
    /// A keyword (`AUTO`, `EVEN`, `ON`, ...).
    Word(&'static str),
    /// A number.
    Number(u32),
    /// The units on the line (`AUTO` or a list).
    Units(NamedUnits),
}

impl fmt::Display for ConfigValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigValue::Word(w) => f.write_str(w),
            ConfigValue::Number(n) => write!(f, "{n}"),
            ConfigValue::Units(units) => units.fmt(f),
        }
    }
}

const ON_OFF: &str = "ON|OFF";
/// A consumable limit: OFF or `1..Limits::MAX` (a test ties the two).
const LIMIT_WORDS: &str = "OFF|1..1000000";

fn limit(value: Option<u32>) -> ConfigValue {
    value.map_or(ConfigValue::Word("OFF"), ConfigValue::Number)
}

fn parse_limit(key: ConfigKey, text: &str) -> Result<Option<u32>, SetError<'_>> {
    if text.eq_ignore_ascii_case("OFF") {
        return Ok(None);
    }
    match parse_number(key, text, (1, Limits::MAX)) {
        Err(SetError::NotANumber { .. }) => Err(SetError::BadWord {
            key,
            expected: LIMIT_WORDS,
        }),
        other => other.map(Some),
    }
}

fn on_off(value: bool) -> ConfigValue {
    ConfigValue::Word(if value { "ON" } else { "OFF" })
}

fn parse_on_off(key: ConfigKey, text: &str) -> Result<bool, SetError<'_>> {
    if text.eq_ignore_ascii_case("ON") {
        Ok(true)
    } else if text.eq_ignore_ascii_case("OFF") {
        Ok(false)
    } else {
        Err(SetError::BadWord {
            key,
            expected: ON_OFF,
        })
    }
}

/// A decimal number within `min..=max`.
pub(super) fn parse_number(
    key: ConfigKey,
    text: &str,
    (min, max): (u32, u32),
) -> Result<u32, SetError<'_>> {
    if text.is_empty() || !text.bytes().all(|b| b.is_ascii_digit()) {
        return Err(SetError::NotANumber { key });
    }
    let out_of_range = SetError::OutOfRange {
        key,
        value: text,
        min,
        max,
    };
    let value = text
        .bytes()
        .try_fold(0u32, |acc, b| {
            acc.checked_mul(10)?.checked_add(u32::from(b - b'0'))
        })
        .ok_or(out_of_range)?;
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(out_of_range)
    }
}

fn protocol_name(p: ProtocolChoice) -> &'static str {
    match p {
        ProtocolChoice::Auto => "AUTO",
        ProtocolChoice::Sync => "SYNC",
        ProtocolChoice::Legacy => "LEGACY",
        ProtocolChoice::Hpr => "HPR",
    }
}

fn parity_name(p: Parity) -> &'static str {
    match p {
        Parity::None => "NONE",
        Parity::Even => "EVEN",
        Parity::Odd => "ODD",
    }
}

fn range_of(key: ConfigKey) -> (u32, u32) {
    match key {
        ConfigKey::Address => (u32::from(LinkConfig::MIN_NODE_ADDRESS), u32::from(u8::MAX)),
        ConfigKey::TimeoutMs => (
            ms(LinkConfig::MIN_RESPONSE_TIMEOUT),
            ms(LinkConfig::MAX_RESPONSE_TIMEOUT),
        ),
        ConfigKey::Retries => (0, u32::from(LinkConfig::MAX_RETRIES)),
        ConfigKey::PollMs => (
            ms(LinkConfig::MIN_POLL_INTERVAL),
            ms(LinkConfig::MAX_POLL_INTERVAL),
        ),
        ConfigKey::ArcOkDebounceMs => ARC_OK_DEBOUNCE_MS,
        ConfigKey::TransferTimeoutMs => TRANSFER_TIMEOUT_MS,
        ConfigKey::HprId => (0, u32::from(LinkConfig::MAX_HPR_ID)),
        ConfigKey::PhoenixFormat => (0, u32::from(u8::MAX)),
        ConfigKey::CncAddress => (
            u32::from(CncPort::MIN_ADDRESS),
            u32::from(CncPort::MAX_ADDRESS),
        ),
        _ => (0, 0),
    }
}

impl Settings {
    /// The value of `key`.
    pub fn get(&self, key: ConfigKey) -> ConfigValue {
        let link = &self.link;
        let io = &self.io;
        match key {
            ConfigKey::Protocol => ConfigValue::Word(protocol_name(link.protocol)),
            ConfigKey::Address => ConfigValue::Number(u32::from(link.node_address)),
            ConfigKey::Parity => ConfigValue::Word(parity_name(link.modbus_parity)),
            ConfigKey::StopBits => ConfigValue::Number(match link.modbus_stop_bits {
                StopBits::One => 1,
                StopBits::Two => 2,
            }),
            ConfigKey::TimeoutMs => ConfigValue::Number(ms(link.response_timeout)),
            ConfigKey::Retries => ConfigValue::Number(u32::from(link.retries)),
            ConfigKey::PollMs => ConfigValue::Number(ms(link.poll_interval)),
            ConfigKey::ReapplyAfterPowerCycle => on_off(link.reapply_after_power_cycle),
            ConfigKey::InterlockFault => on_off(io.refuse_start_on_fault),
            ConfigKey::InterlockLink => on_off(io.link_required),
            ConfigKey::InterlockReady => on_off(io.ready_required),
            ConfigKey::ArcOkDebounceMs => ConfigValue::Number(ms(io.arc_ok_debounce)),
            ConfigKey::TransferTimeoutMs => ConfigValue::Number(ms(io.transfer_timeout)),
            ConfigKey::TransferTimeoutDropsStart => on_off(io.drop_start_on_transfer_timeout),
            ConfigKey::Events => on_off(self.events),
            ConfigKey::HprId => ConfigValue::Number(u32::from(link.hpr_id)),
            ConfigKey::PhoenixFormat => ConfigValue::Number(u32::from(self.phoenix_format.value())),
            ConfigKey::CncAddress => ConfigValue::Number(u32::from(self.cnc.address)),
            ConfigKey::CncBaud => ConfigValue::Number(self.cnc.framing.baud),
            ConfigKey::CncParity => ConfigValue::Word(parity_name(self.cnc.framing.parity)),
            ConfigKey::CncStopBits => {
                ConfigValue::Number(u32::from(self.cnc.framing.stop_bits.number()))
            }
            ConfigKey::CncDataBits => {
                ConfigValue::Number(u32::from(self.cnc.framing.data_bits.number()))
            }
            ConfigKey::ConsumableStartLimit => limit(self.consumable_limits.starts),
            ConfigKey::ConsumableArcLimitS => limit(self.consumable_limits.arc_seconds),
            ConfigKey::Units => ConfigValue::Units(self.units),
            // The wiring keys (`wiring::KEYS`); every other key has its arm above.
            other => wiring::get(io, other).unwrap_or(ConfigValue::Number(0)),
        }
    }

    /// The accepted values of `key`, as `HELP`-style text (`60..1000`, `ON|OFF`, ...).
    pub fn accepted(key: ConfigKey) -> Accepted {
        match key {
            ConfigKey::Protocol => Accepted::Words("AUTO|SYNC|LEGACY|HPR"),
            ConfigKey::Parity | ConfigKey::CncParity => Accepted::Words("NONE|EVEN|ODD"),
            ConfigKey::StopBits | ConfigKey::CncStopBits => Accepted::Words("1|2"),
            ConfigKey::CncBaud => Accepted::Words(CNC_BAUD_WORDS),
            ConfigKey::CncDataBits => Accepted::Words("7|8"),
            ConfigKey::InterlockFault
            | ConfigKey::InterlockLink
            | ConfigKey::InterlockReady
            | ConfigKey::TransferTimeoutDropsStart
            | ConfigKey::ReapplyAfterPowerCycle
            | ConfigKey::Events => Accepted::Words(ON_OFF),
            ConfigKey::PhoenixFormat => Accepted::Words(PHOENIX_FORMAT_WORDS),
            ConfigKey::ConsumableStartLimit | ConfigKey::ConsumableArcLimitS => {
                Accepted::Words(LIMIT_WORDS)
            }
            ConfigKey::Units => Accepted::Words(NamedUnits::WORDS),
            other => wiring::accepted(other).unwrap_or_else(|| {
                let (min, max) = range_of(other);
                Accepted::Range(min, max)
            }),
        }
    }

    /// Change `key` to the value typed as `text` (keywords in any case). Nothing changes
    /// when the value is refused.
    pub fn set<'a>(&mut self, key: ConfigKey, text: &'a str) -> Result<(), SetError<'a>> {
        let number = |text: &'a str| parse_number(key, text, range_of(key));
        let millis = |text: &'a str| number(text).map(|v| Duration::from_millis(u64::from(v)));
        let link = &mut self.link;
        let io = &mut self.io;
        match key {
            ConfigKey::Protocol => {
                link.protocol = [
                    ProtocolChoice::Auto,
                    ProtocolChoice::Sync,
                    ProtocolChoice::Legacy,
                    ProtocolChoice::Hpr,
                ]
                .into_iter()
                .find(|p| protocol_name(*p).eq_ignore_ascii_case(text))
                .ok_or(SetError::BadWord {
                    key,
                    expected: "AUTO|SYNC|LEGACY|HPR",
                })?;
            }
            ConfigKey::Address => link.node_address = number(text)? as u8,
            ConfigKey::Parity => link.modbus_parity = parse_parity(key, text)?,
            ConfigKey::StopBits => link.modbus_stop_bits = parse_stop_bits(key, text)?,
            ConfigKey::TimeoutMs => link.response_timeout = millis(text)?,
            ConfigKey::Retries => link.retries = number(text)? as u8,
            ConfigKey::PollMs => link.poll_interval = millis(text)?,
            ConfigKey::ReapplyAfterPowerCycle => {
                link.reapply_after_power_cycle = parse_on_off(key, text)?;
            }
            ConfigKey::InterlockFault => io.refuse_start_on_fault = parse_on_off(key, text)?,
            ConfigKey::InterlockLink => io.link_required = parse_on_off(key, text)?,
            ConfigKey::InterlockReady => io.ready_required = parse_on_off(key, text)?,
            ConfigKey::ArcOkDebounceMs => io.arc_ok_debounce = millis(text)?,
            ConfigKey::TransferTimeoutMs => io.transfer_timeout = millis(text)?,
            ConfigKey::TransferTimeoutDropsStart => {
                io.drop_start_on_transfer_timeout = parse_on_off(key, text)?;
            }
            ConfigKey::Events => self.events = parse_on_off(key, text)?,
            ConfigKey::HprId => link.hpr_id = number(text)? as u8,
            ConfigKey::PhoenixFormat => {
                let not_a_format = SetError::NotPhoenixFormat { value: text };
                let value = number(text).map_err(|e| match e {
                    SetError::OutOfRange { .. } => not_a_format,
                    other => other,
                })?;
                self.phoenix_format = u8::try_from(value)
                    .ok()
                    .and_then(|v| Format::from_value(v).ok())
                    .ok_or(not_a_format)?;
            }
            ConfigKey::CncAddress => self.cnc.address = number(text)? as u8,
            ConfigKey::CncBaud => self.cnc.framing.baud = parse_cnc_baud(key, text)?,
            ConfigKey::CncParity => self.cnc.framing.parity = parse_parity(key, text)?,
            ConfigKey::CncStopBits => self.cnc.framing.stop_bits = parse_stop_bits(key, text)?,
            ConfigKey::CncDataBits => self.cnc.framing.data_bits = parse_data_bits(key, text)?,
            ConfigKey::ConsumableStartLimit => {
                self.consumable_limits.starts = parse_limit(key, text)?;
            }
            ConfigKey::ConsumableArcLimitS => {
                self.consumable_limits.arc_seconds = parse_limit(key, text)?;
            }
            ConfigKey::Units => {
                self.units = NamedUnits::parse(self.link, text).map_err(SetError::Units)?;
            }
            // The wiring keys (`wiring::KEYS`); every other key has its arm above.
            other => return wiring::set(io, other, text).unwrap_or(Ok(())),
        }
        Ok(())
    }
}

/// What a key accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Accepted {
    /// One of these words (`|`-separated).
    Words(&'static str),
    /// A number in this inclusive range.
    Range(u32, u32),
}

impl fmt::Display for Accepted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Accepted::Words(w) => f.write_str(w),
            Accepted::Range(min, max) => write!(f, "{min}..{max}"),
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use plasma_protocol::serial::PortConfig;

    use super::*;

    #[test]
    fn the_cnc_port_keys_give_the_port_config() {
        let mut s = Settings::default();
        assert_eq!(
            s.cnc_port_config(),
            crate::settings::CncPort::DEFAULT.framing
        );
        s.set(ConfigKey::CncBaud, "19200").unwrap();
        s.set(ConfigKey::CncParity, "E").unwrap();
        assert_eq!(s.cnc_port_config(), PortConfig::MODBUS_DEFAULT);
        let err = s.set(ConfigKey::CncBaud, "14400").unwrap_err();
        assert_eq!(
            err.to_string(),
            "cnc_baud: expected 1200|2400|4800|9600|19200|38400|57600|115200"
        );
        let err = s.set(ConfigKey::CncAddress, "0").unwrap_err();
        assert_eq!(err.to_string(), "cnc_address 0 outside 1..247");
        assert!(s.set(ConfigKey::CncStopBits, "3").is_err());
        assert_eq!(s.cnc_port_config(), PortConfig::MODBUS_DEFAULT);
    }

    #[test]
    fn the_consumable_limits_are_off_or_a_number() {
        let mut s = Settings::default();
        let key = ConfigKey::ConsumableStartLimit;
        assert_eq!(s.get(key).to_string(), "OFF");
        s.set(key, "500").unwrap();
        s.set(ConfigKey::ConsumableArcLimitS, "7200").unwrap();
        assert_eq!(s.get(key).to_string(), "500");
        assert_eq!(s.consumable_limits.arc_seconds, Some(7200));
        let err = s.set(key, "lots").unwrap_err();
        assert_eq!(
            err.to_string(),
            "consumable_start_limit: expected OFF|1..1000000"
        );
        let err = s.set(key, "0").unwrap_err();
        assert_eq!(
            err.to_string(),
            "consumable_start_limit 0 outside 1..1000000"
        );
        s.set(key, "off").unwrap();
        assert_eq!(s.consumable_limits.starts, None);
        let mut words = std::string::String::new();
        core::fmt::Write::write_fmt(&mut words, format_args!("OFF|1..{}", Limits::MAX)).unwrap();
        assert_eq!(words, LIMIT_WORDS);
    }

    #[test]
    fn the_accepted_words_are_exactly_what_set_takes() {
        // `cnc_baud` and `phoenix_format` list their values as text beside the table that
        // decides: the two must agree.
        let words = |key| match Settings::accepted(key) {
            Accepted::Words(w) => w.split('|').collect::<std::vec::Vec<_>>(),
            Accepted::Range(..) => std::vec::Vec::new(),
        };
        let bauds: std::vec::Vec<u32> = words(ConfigKey::CncBaud)
            .iter()
            .map(|w| w.parse().unwrap())
            .collect();
        assert_eq!(bauds, CNC_BAUDS);
        let taken: std::vec::Vec<std::string::String> = (0..=255u32)
            .map(|v| v.to_string())
            .filter(|v| Settings::default().set(ConfigKey::PhoenixFormat, v).is_ok())
            .collect();
        assert_eq!(words(ConfigKey::PhoenixFormat), taken);
        let all: std::vec::Vec<std::string::String> =
            Format::ALL.iter().map(|f| f.value().to_string()).collect();
        assert_eq!(taken, all);
    }

    /// Phoenix manual (003_610fea73110d789e.txt) line 7012: a messaging port's "Baud Rate:
    /// Select a communication speed from 1200 to 115200 Baud."
    #[test]
    fn cnc_baud_covers_a_phoenix_ports_range() {
        for baud in [
            "1200", "2400", "4800", "9600", "19200", "38400", "57600", "115200",
        ] {
            let mut s = Settings::default();
            assert_eq!(s.set(ConfigKey::CncBaud, baud), Ok(()), "{baud}");
            assert_eq!(s.get(ConfigKey::CncBaud).to_string(), baud);
        }
        assert!(Settings::default().set(ConfigKey::CncBaud, "600").is_err());
    }

    /// Phoenix manual (003_610fea73110d789e.txt) lines 7037-7043, a messaging port's settings:
    /// "Parity: Select None, Odd or Even." and "Data Bits: Select 7 or 8 Data Bits." Every
    /// combination, with 1 or 2 stop bits, is a CNC port framing.
    #[test]
    fn the_cnc_framing_covers_a_phoenix_ports_parity_and_data_bits() {
        for data_bits in ["7", "8"] {
            for parity in ["NONE", "ODD", "EVEN"] {
                for stop_bits in ["1", "2"] {
                    let mut s = Settings::default();
                    s.set(ConfigKey::CncBaud, "4800").unwrap();
                    s.set(ConfigKey::CncDataBits, data_bits).unwrap();
                    s.set(ConfigKey::CncParity, parity).unwrap();
                    s.set(ConfigKey::CncStopBits, stop_bits).unwrap();
                    assert!(s.is_valid());
                    assert_eq!(s.get(ConfigKey::CncDataBits).to_string(), data_bits);
                    let framing = [data_bits, &parity[..1], stop_bits].concat();
                    assert_eq!(
                        s.cnc_port_config().to_string(),
                        ["4800 ", &framing].concat()
                    );
                }
            }
        }
        let mut s = Settings::default();
        let err = s.set(ConfigKey::CncDataBits, "9").unwrap_err();
        assert_eq!(err.to_string(), "cnc_data_bits: expected 7|8");
        assert_eq!(s, Settings::default(), "nothing changed");
        assert_eq!(
            Settings::accepted(ConfigKey::CncDataBits).to_string(),
            "7|8"
        );
    }

    /// Phoenix manual (003_610fea73110d789e.txt) line 7075: "0,1,16,17,32,33,48,49,64,
    /// 65,80,81,96,97,112,113 are supported"; every one is a `phoenix_format`, the unframed
    /// 0, 1, 16 and 17 included.
    #[test]
    fn phoenix_format_takes_every_value_the_manual_lists() {
        let listed = "0,1,16,17,32,33,48,49,64,65,80,81,96,97,112,113";
        for value in listed.split(',') {
            let mut s = Settings::default();
            assert_eq!(s.set(ConfigKey::PhoenixFormat, value), Ok(()), "{value}");
            assert_eq!(s.get(ConfigKey::PhoenixFormat).to_string(), value);
            assert!(s.is_valid(), "{value}");
        }
    }

    #[test]
    fn set_refuses_precisely_and_changes_nothing() {
        let mut s = Settings::default();
        let before = s;
        let text = |e: SetError<'_>| std::format!("{} {}", e.code(), e);
        assert_eq!(
            text(s.set(ConfigKey::TimeoutMs, "30").unwrap_err()),
            "RANGE timeout_ms 30 outside 60..1000"
        );
        assert_eq!(
            text(s.set(ConfigKey::TimeoutMs, "99999999999").unwrap_err()),
            "RANGE timeout_ms 99999999999 outside 60..1000"
        );
        assert_eq!(
            text(s.set(ConfigKey::Retries, "-1").unwrap_err()),
            "SYNTAX retries: not a number"
        );
        assert_eq!(
            text(s.set(ConfigKey::Parity, "mark").unwrap_err()),
            "SYNTAX parity: expected NONE|EVEN|ODD"
        );
        assert_eq!(
            text(s.set(ConfigKey::Events, "yes").unwrap_err()),
            "SYNTAX events: expected ON|OFF"
        );
        assert_eq!(
            text(s.set(ConfigKey::Address, "0").unwrap_err()),
            "RANGE address 0 outside 1..255"
        );
        assert_eq!(
            text(s.set(ConfigKey::PhoenixFormat, "2").unwrap_err()),
            "RANGE phoenix_format 2 is not a Phoenix format \
             (0|1|16|17|32|33|48|49|64|65|80|81|96|97|112|113)"
        );
        assert!(s.set(ConfigKey::PhoenixFormat, "300").is_err());
        assert_eq!(s, before);
        assert_eq!(
            Settings::accepted(ConfigKey::PollMs).to_string(),
            "20..1000"
        );
    }
}
