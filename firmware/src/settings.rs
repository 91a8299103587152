//! Everything the bridge keeps across a power cycle, and the `CONFIG` keys that change it.
//!
//! [`Settings`] holds the link configuration, the discrete-I/O configuration, the CNC port
//! options (events, Phoenix framing) and the last process the CNC asked for, so that it can be
//! applied again after power-up. It implements [`storage::Settings`] with a fixed-layout,
//! versioned binary record; decoding is strict (wrong length, an unknown code, a value out of
//! range, a reserved bit set: `None`, and the store falls back to the defaults).
//!
//! ```
//! use plasma_firmware::settings::Settings;
//! use plasma_firmware::storage::Settings as _;
//! use plasma_protocol::cnc::ConfigKey;
//!
//! let mut settings = Settings::default();
//! settings.set(ConfigKey::TimeoutMs, "80").unwrap();
//! let err = settings.set(ConfigKey::TimeoutMs, "30").unwrap_err();
//! assert_eq!(err.to_string(), "timeout_ms 30 outside 60..1000");
//!
//! let mut record = [0u8; 64];
//! let len = settings.encode(&mut record);
//! assert_eq!(Settings::decode(&record[..len]), Some(settings));
//! ```

use core::fmt;

use plasma_protocol::cnc::phoenix::Format;
use plasma_protocol::cnc::{
    AMPS_MAX, AMPS_MIN, Amps, ConfigKey, ErrorCode, Mode, PSI_MAX, PSI_MIN, Pressure,
};

use crate::io::{IoConfig, MIN_START_GAP};

mod wiring;
use crate::link::{LinkConfig, ProtocolChoice};
use crate::storage::{self, StoreError};
use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_protocol::time::Duration;

/// Accepted `arc_ok_debounce_ms` values.
pub const ARC_OK_DEBOUNCE_MS: (u32, u32) = (0, IoConfig::MAX_ARC_OK_DEBOUNCE.as_millis_u32());
/// Accepted `transfer_timeout_ms` values.
pub const TRANSFER_TIMEOUT_MS: (u32, u32) = (
    IoConfig::MIN_TRANSFER_TIMEOUT.as_millis_u32(),
    IoConfig::MAX_TRANSFER_TIMEOUT.as_millis_u32(),
);
/// Accepted gap between starts, ms (stored; not a `CONFIG` key).
pub const START_GAP_MS: (u32, u32) = (
    MIN_START_GAP.as_millis_u32(),
    IoConfig::MAX_START_GAP.as_millis_u32(),
);
/// The Phoenix format used until one is configured: SOH, STX, CR LF, ETX, EOT and check byte.
pub const DEFAULT_PHOENIX_FORMAT: u8 = 113;
/// Length of the version-1 record (no wiring, no CNC port block).
pub const RECORD_V1_LEN: usize = 29;
/// Length of the version-2 record: version 1, the CNC's wiring, then the CNC port block.
pub const RECORD_LEN: usize = RECORD_V1_LEN + wiring::RECORD_LEN + CNC_BLOCK_LEN;

// --- the CNC port: framing and Powermax node address (issue 13) ------------------------------

/// The baud rates `cnc_baud` accepts.
pub const CNC_BAUDS: [u32; 5] = [9_600, 19_200, 38_400, 57_600, 115_200];
const CNC_BAUD_WORDS: &str = "9600|19200|38400|57600|115200";
/// Bytes of the CNC port block in the record: address, baud (LE u32), parity, stop bits.
const CNC_BLOCK_LEN: usize = 7;

/// The CNC port: its UART framing and the node address the bridge answers at as a Powermax
/// (Modbus ASCII requests on the CNC port, see `cnc::powermax_port`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CncPort {
    /// Modbus node address the bridge answers at (1-247; 0 is the broadcast address).
    pub address: u8,
    /// UART framing (8 data bits always).
    pub framing: PortConfig,
}

impl CncPort {
    /// 115200 8N1 (the board's ST-LINK virtual COM port, the text protocol's default), node 1
    /// (the node LinuxCNC's pmx485 always addresses).
    pub const DEFAULT: CncPort = CncPort {
        address: 1,
        framing: PortConfig {
            baud: 115_200,
            parity: Parity::None,
            stop_bits: StopBits::One,
        },
    };

    fn is_valid(&self) -> bool {
        (1..=247).contains(&self.address) && CNC_BAUDS.contains(&self.framing.baud)
    }

    fn encode(&self) -> [u8; CNC_BLOCK_LEN] {
        let b = self.framing.baud.to_le_bytes();
        [
            self.address,
            b[0],
            b[1],
            b[2],
            b[3],
            index_of(&PARITIES, &self.framing.parity),
            stop_bits_number(self.framing.stop_bits),
        ]
    }

    fn decode(r: &[u8]) -> Option<CncPort> {
        let &[address, b0, b1, b2, b3, parity, stop] = r else {
            return None;
        };
        let port = CncPort {
            address,
            framing: PortConfig {
                baud: u32::from_le_bytes([b0, b1, b2, b3]),
                parity: *PARITIES.get(usize::from(parity))?,
                stop_bits: stop_bits_from(stop)?,
            },
        };
        port.is_valid().then_some(port)
    }
}

fn stop_bits_number(stop_bits: StopBits) -> u8 {
    match stop_bits {
        StopBits::One => 1,
        StopBits::Two => 2,
    }
}

fn stop_bits_from(number: u8) -> Option<StopBits> {
    match number {
        1 => Some(StopBits::One),
        2 => Some(StopBits::Two),
        _ => None,
    }
}

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

/// The process (mode, current, pressure) the CNC asked for last, re-applied after power-up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Process {
    /// Operating mode as the CNC named it (`CPA` and `EXPANDED` are the same unit mode).
    pub mode: Mode,
    /// Output current.
    pub amps: Amps,
    /// Gas pressure, or automatic.
    pub pressure: Pressure,
}

/// Everything that survives a power cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// Power-supply link.
    pub link: LinkConfig,
    /// Discrete I/O interlocks.
    pub io: IoConfig,
    /// `!` event lines on the CNC port.
    pub events: bool,
    /// How the Phoenix CNC frames serial messages (a format with SOH or STX).
    pub phoenix_format: Format,
    /// The last process the unit confirmed (`None` after `REMOTE OFF`).
    pub process: Option<Process>,
    /// The CNC port's framing and Powermax node address.
    pub cnc: CncPort,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            link: LinkConfig::default(),
            io: IoConfig::default(),
            events: false,
            phoenix_format: Format::from_value(DEFAULT_PHOENIX_FORMAT).unwrap_or(Format::PLAIN),
            process: None,
            cnc: CncPort::DEFAULT,
        }
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
    /// A Phoenix format value that is not one of the framed formats.
    NotFramedFormat {
        /// The value as typed (digits only).
        value: &'a str,
    },
}

impl SetError<'_> {
    /// The reply code.
    pub const fn code(&self) -> ErrorCode {
        match self {
            SetError::NotANumber { .. } | SetError::BadWord { .. } => ErrorCode::Syntax,
            SetError::OutOfRange { .. } | SetError::NotFramedFormat { .. } => ErrorCode::Range,
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
            SetError::NotFramedFormat { value } => write!(
                f,
                "phoenix_format {value} is not a framed format (32 33 48 49 64 65 80 81 96 97 \
                 112 113; without SOH or STX a message is a plain text line)"
            ),
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
}

impl fmt::Display for ConfigValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigValue::Word(w) => f.write_str(w),
            ConfigValue::Number(n) => write!(f, "{n}"),
        }
    }
}

/// Why the board could not store the settings (`CONFIG SAVE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SaveError {
    /// The flash driver failed.
    Flash,
    /// The store is damaged beyond repair.
    Corrupted,
    /// The record does not fit.
    TooLarge,
    /// Anything else the storage layer reports.
    Storage,
}

impl fmt::Display for SaveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SaveError::Flash => "flash write failed",
            SaveError::Corrupted => "settings store corrupted",
            SaveError::TooLarge => "settings record too large",
            SaveError::Storage => "storage layer error",
        })
    }
}

impl<E> From<StoreError<E>> for SaveError {
    fn from(e: StoreError<E>) -> Self {
        match e {
            StoreError::Flash(_) => SaveError::Flash,
            StoreError::Corrupted => SaveError::Corrupted,
            StoreError::TooLarge => SaveError::TooLarge,
            StoreError::BadRegion | StoreError::Internal => SaveError::Storage,
        }
    }
}

const ON_OFF: &str = "ON|OFF";

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
fn parse_number(key: ConfigKey, text: &str, (min, max): (u32, u32)) -> Result<u32, SetError<'_>> {
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

fn ms(duration: Duration) -> u32 {
    u32::try_from(duration.as_millis()).unwrap_or(u32::MAX)
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
    let ms = |d: Duration| u32::try_from(d.as_millis()).unwrap_or(u32::MAX);
    match key {
        ConfigKey::Address => (1, 255),
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
        ConfigKey::PhoenixFormat => (0, 255),
        ConfigKey::CncAddress => (1, 247),
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
            ConfigKey::InterlockFault => on_off(io.refuse_start_on_fault),
            ConfigKey::InterlockLink => on_off(io.link_required),
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
                ConfigValue::Number(u32::from(stop_bits_number(self.cnc.framing.stop_bits)))
            }
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
            ConfigKey::InterlockFault
            | ConfigKey::InterlockLink
            | ConfigKey::TransferTimeoutDropsStart
            | ConfigKey::Events => Accepted::Words(ON_OFF),
            ConfigKey::PhoenixFormat => Accepted::Words("32|33|48|49|64|65|80|81|96|97|112|113"),
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
            ConfigKey::InterlockFault => io.refuse_start_on_fault = parse_on_off(key, text)?,
            ConfigKey::InterlockLink => io.link_required = parse_on_off(key, text)?,
            ConfigKey::ArcOkDebounceMs => io.arc_ok_debounce = millis(text)?,
            ConfigKey::TransferTimeoutMs => io.transfer_timeout = millis(text)?,
            ConfigKey::TransferTimeoutDropsStart => {
                io.drop_start_on_transfer_timeout = parse_on_off(key, text)?;
            }
            ConfigKey::Events => self.events = parse_on_off(key, text)?,
            ConfigKey::HprId => link.hpr_id = number(text)? as u8,
            ConfigKey::PhoenixFormat => {
                let not_framed = SetError::NotFramedFormat { value: text };
                let value = number(text).map_err(|e| match e {
                    SetError::OutOfRange { .. } => not_framed,
                    other => other,
                })?;
                self.phoenix_format = u8::try_from(value)
                    .ok()
                    .and_then(|v| Format::from_value(v).ok())
                    .filter(|f| f.start_byte().is_some())
                    .ok_or(not_framed)?;
            }
            ConfigKey::CncAddress => self.cnc.address = number(text)? as u8,
            ConfigKey::CncBaud => self.cnc.framing.baud = parse_cnc_baud(key, text)?,
            ConfigKey::CncParity => self.cnc.framing.parity = parse_parity(key, text)?,
            ConfigKey::CncStopBits => self.cnc.framing.stop_bits = parse_stop_bits(key, text)?,
            // The wiring keys (`wiring::KEYS`); every other key has its arm above.
            other => return wiring::set(io, other, text).unwrap_or(Ok(())),
        }
        Ok(())
    }

    /// The CNC port's UART framing (`cnc_baud`, `cnc_parity`, `cnc_stop_bits`).
    pub fn cnc_port_config(&self) -> PortConfig {
        self.cnc.framing
    }

    /// True when every field is one this firmware accepts (what [`decode`] insists on).
    ///
    /// [`decode`]: storage::Settings::decode
    pub fn is_valid(&self) -> bool {
        let within = |d: Duration, (min, max): (u32, u32)| {
            d.as_millis() >= u64::from(min) && d.as_millis() <= u64::from(max)
        };
        let process_ok = self.process.is_none_or(|p| {
            p.amps >= AMPS_MIN
                && p.amps <= AMPS_MAX
                && p.pressure
                    .psi()
                    .is_none_or(|psi| psi >= PSI_MIN && psi <= PSI_MAX)
        });
        self.link.validate().is_ok()
            && within(self.io.start_gap, START_GAP_MS)
            && within(self.io.arc_ok_debounce, ARC_OK_DEBOUNCE_MS)
            && within(self.io.transfer_timeout, TRANSFER_TIMEOUT_MS)
            && self.phoenix_format.start_byte().is_some()
            && self.cnc.is_valid()
            && process_ok
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

// --- record layout, version 2 (version 1 is its first 29 bytes) ----------------------------
// 0 protocol | 1 node address | 2 parity | 3 stop bits | 4-5 response time-out ms (LE)
// 6 retries | 7-8 poll ms | 9-12 slow-data ms | 13 HPR id | 14 failures before down
// 15-16 start gap ms | 17-18 ARC_OK debounce ms | 19-20 transfer time-out ms | 21 flags
// 22 Phoenix format | 23 process present | 24 mode | 25-26 amps raw | 27-28 pressure raw
// 29 active-high inputs (bit per input) | 30-36 input debounce ms | 37 inverted outputs
// 38 CNC address | 39-42 CNC baud (LE) | 43 CNC parity | 44 CNC stop bits

const FLAG_ARC_OK_REQUIRES_START: u8 = 1 << 0;
const FLAG_DROP_START_ON_TRANSFER_TIMEOUT: u8 = 1 << 1;
const FLAG_REFUSE_START_ON_FAULT: u8 = 1 << 2;
const FLAG_LINK_REQUIRED: u8 = 1 << 3;
const FLAG_EVENTS: u8 = 1 << 4;
const FLAGS_KNOWN: u8 = 0x1F;

const PROTOCOLS: [ProtocolChoice; 4] = [
    ProtocolChoice::Auto,
    ProtocolChoice::Sync,
    ProtocolChoice::Legacy,
    ProtocolChoice::Hpr,
];
const PARITIES: [Parity; 3] = [Parity::None, Parity::Even, Parity::Odd];

fn index_of<T: PartialEq>(items: &[T], item: &T) -> u8 {
    items.iter().position(|i| i == item).unwrap_or(0) as u8
}

fn u16_ms(d: Duration) -> [u8; 2] {
    u16::try_from(d.as_millis())
        .unwrap_or(u16::MAX)
        .to_le_bytes()
}

impl storage::Settings for Settings {
    const VERSION: u8 = 2;

    fn encode(&self, out: &mut [u8]) -> usize {
        let mut r = [0u8; RECORD_LEN];
        let link = &self.link;
        let io = &self.io;
        r[0] = index_of(&PROTOCOLS, &link.protocol);
        r[1] = link.node_address;
        r[2] = index_of(&PARITIES, &link.modbus_parity);
        r[3] = stop_bits_number(link.modbus_stop_bits);
        r[4..6].copy_from_slice(&u16_ms(link.response_timeout));
        r[6] = link.retries;
        r[7..9].copy_from_slice(&u16_ms(link.poll_interval));
        r[9..13].copy_from_slice(&ms(link.slow_data_interval).to_le_bytes());
        r[13] = link.hpr_id;
        r[14] = link.failures_before_down;
        r[15..17].copy_from_slice(&u16_ms(io.start_gap));
        r[17..19].copy_from_slice(&u16_ms(io.arc_ok_debounce));
        r[19..21].copy_from_slice(&u16_ms(io.transfer_timeout));
        let flag = |on: bool, bit: u8| if on { bit } else { 0 };
        r[21] = flag(io.arc_ok_requires_start, FLAG_ARC_OK_REQUIRES_START)
            | flag(
                io.drop_start_on_transfer_timeout,
                FLAG_DROP_START_ON_TRANSFER_TIMEOUT,
            )
            | flag(io.refuse_start_on_fault, FLAG_REFUSE_START_ON_FAULT)
            | flag(io.link_required, FLAG_LINK_REQUIRED)
            | flag(self.events, FLAG_EVENTS);
        r[22] = self.phoenix_format.value();
        if let Some(process) = self.process {
            r[23] = 1;
            r[24] = index_of(&Mode::ALL, &process.mode);
            r[25..27].copy_from_slice(&process.amps.raw().to_le_bytes());
            r[27..29].copy_from_slice(&process.pressure.raw().to_le_bytes());
        }
        let (wiring_bytes, cnc) = r[RECORD_V1_LEN..].split_at_mut(wiring::RECORD_LEN);
        wiring_bytes.copy_from_slice(&wiring::encode(io));
        cnc.copy_from_slice(&self.cnc.encode());
        match out.get_mut(..RECORD_LEN) {
            Some(slot) => {
                slot.copy_from_slice(&r);
                RECORD_LEN
            }
            // Too small a buffer: report a length the store refuses.
            None => out.len().saturating_add(1),
        }
    }

    fn decode(payload: &[u8]) -> Option<Self> {
        let (v1, rest) = payload.split_at_checked(RECORD_V1_LEN)?;
        let (wiring_bytes, cnc) = rest.split_at_checked(wiring::RECORD_LEN)?;
        let (inputs, outputs) = wiring::decode(wiring_bytes.try_into().ok()?)?;
        let mut settings = Settings {
            cnc: CncPort::decode(cnc)?,
            ..decode_v1(v1)?
        };
        settings.io.inputs = inputs;
        settings.io.outputs = outputs;
        settings.is_valid().then_some(settings)
    }

    /// Version 1 had neither the wiring nor the CNC port block: both keep their defaults.
    fn migrate(version: u8, payload: &[u8]) -> Option<Self> {
        match version {
            1 => decode_v1(payload),
            _ => None,
        }
    }
}

/// The version-1 record (also the first part of version 2), the CNC port at its defaults.
fn decode_v1(payload: &[u8]) -> Option<Settings> {
    let r: &[u8; RECORD_V1_LEN] = payload.try_into().ok()?;
    // Offsets are constants inside the fixed-length record.
    let u16_at = |i: usize| {
        r.get(i..i + 2)
            .and_then(|b| b.try_into().ok())
            .map_or(0, u16::from_le_bytes)
    };
    let millis = |i: usize| Duration::from_millis(u64::from(u16_at(i)));
    let flags = r[21];
    if flags & !FLAGS_KNOWN != 0 {
        return None;
    }
    let link = LinkConfig {
        protocol: *PROTOCOLS.get(usize::from(r[0]))?,
        node_address: r[1],
        modbus_parity: *PARITIES.get(usize::from(r[2]))?,
        modbus_stop_bits: stop_bits_from(r[3])?,
        response_timeout: millis(4),
        retries: r[6],
        poll_interval: millis(7),
        slow_data_interval: Duration::from_millis(u64::from(u32::from_le_bytes([
            r[9], r[10], r[11], r[12],
        ]))),
        hpr_id: r[13],
        failures_before_down: r[14],
    };
    let io = IoConfig {
        start_gap: millis(15).max(MIN_START_GAP),
        arc_ok_debounce: millis(17),
        arc_ok_requires_start: flags & FLAG_ARC_OK_REQUIRES_START != 0,
        transfer_timeout: millis(19),
        drop_start_on_transfer_timeout: flags & FLAG_DROP_START_ON_TRANSFER_TIMEOUT != 0,
        refuse_start_on_fault: flags & FLAG_REFUSE_START_ON_FAULT != 0,
        link_required: flags & FLAG_LINK_REQUIRED != 0,
        // Version 1 has no wiring: the reference board's (version 2 overwrites it).
        ..IoConfig::default()
    };
    let process = match r[23] {
        0 if r[24..].iter().all(|&b| b == 0) => None,
        1 => Some(Process {
            mode: *Mode::ALL.get(usize::from(r[24]))?,
            amps: Amps::from_raw(u16_at(25)),
            pressure: Pressure::from_raw(u16_at(27)),
        }),
        _ => return None,
    };
    let settings = Settings {
        link,
        io,
        events: flags & FLAG_EVENTS != 0,
        phoenix_format: Format::from_value(r[22]).ok()?,
        process,
        cnc: CncPort::DEFAULT,
    };
    settings.is_valid().then_some(settings)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use super::*;
    use crate::storage::Settings as _;

    fn round_trip(settings: &Settings) -> Option<Settings> {
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = settings.encode(&mut out);
        assert_eq!(len, RECORD_LEN);
        Settings::decode(&out[..len])
    }

    #[test]
    fn defaults_are_valid_and_round_trip() {
        let defaults = Settings::default();
        assert!(defaults.is_valid());
        assert_eq!(round_trip(&defaults), Some(defaults));
        assert_eq!(defaults.phoenix_format.value(), 113);
        assert!(!defaults.events);
    }

    #[test]
    fn every_field_round_trips() {
        let mut s = Settings::default();
        for (key, value) in [
            (ConfigKey::Protocol, "hpr"),
            (ConfigKey::Address, "17"),
            (ConfigKey::Parity, "o"),
            (ConfigKey::StopBits, "2"),
            (ConfigKey::TimeoutMs, "250"),
            (ConfigKey::Retries, "5"),
            (ConfigKey::PollMs, "500"),
            (ConfigKey::InterlockFault, "off"),
            (ConfigKey::InterlockLink, "OFF"),
            (ConfigKey::ArcOkDebounceMs, "10"),
            (ConfigKey::TransferTimeoutMs, "5000"),
            (ConfigKey::TransferTimeoutDropsStart, "off"),
            (ConfigKey::Events, "on"),
            (ConfigKey::HprId, "3"),
            (ConfigKey::PhoenixFormat, "49"),
            (ConfigKey::CncAddress, "7"),
            (ConfigKey::CncBaud, "19200"),
            (ConfigKey::CncParity, "even"),
            (ConfigKey::CncStopBits, "2"),
        ] {
            s.set(key, value).unwrap();
        }
        s.process = Some(Process {
            mode: Mode::Expanded,
            amps: Amps::from_raw(45 * 64 + 32),
            pressure: Pressure::Set(plasma_protocol::units::Psi::from_raw(70 * 128)),
        });
        let back = round_trip(&s).unwrap();
        assert_eq!(back, s);
        assert_eq!(back.get(ConfigKey::Parity), ConfigValue::Word("ODD"));
        assert_eq!(back.get(ConfigKey::TimeoutMs), ConfigValue::Number(250));
        assert_eq!(back.link.protocol, ProtocolChoice::Hpr);
        assert!(!back.io.link_required);
    }

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
            "cnc_baud: expected 9600|19200|38400|57600|115200"
        );
        let err = s.set(ConfigKey::CncAddress, "0").unwrap_err();
        assert_eq!(err.to_string(), "cnc_address 0 outside 1..247");
        assert!(s.set(ConfigKey::CncStopBits, "3").is_err());
        assert_eq!(s.cnc_port_config(), PortConfig::MODBUS_DEFAULT);
    }

    #[test]
    fn a_version_1_record_loads_with_the_default_cnc_port() {
        let mut s = Settings::default();
        s.set(ConfigKey::HprId, "2").unwrap();
        s.set(ConfigKey::CncBaud, "19200").unwrap();
        let mut out = [0u8; storage::MAX_PAYLOAD];
        let len = s.encode(&mut out);
        assert_eq!(len, RECORD_LEN);
        let v1 = &out[..RECORD_V1_LEN];
        assert_eq!(Settings::decode(v1), None, "a v1 record is not a v2 one");
        let migrated = Settings::migrate(1, v1).unwrap();
        assert_eq!(migrated.link.hpr_id, 2);
        assert_eq!(migrated.cnc, crate::settings::CncPort::DEFAULT);
        assert_eq!(Settings::migrate(3, v1), None);
    }

    #[test]
    fn decode_is_strict() {
        let mut out = [0u8; 64];
        let len = Settings::default().encode(&mut out);
        let good = out;
        assert!(Settings::decode(&good[..len]).is_some());
        assert_eq!(Settings::decode(&good[..len - 1]), None, "short");
        assert_eq!(Settings::decode(&good[..len + 1]), None, "long");
        let corrupt = |i: usize, v: u8| {
            let mut r = good;
            r[i] = v;
            Settings::decode(&r[..len])
        };
        assert_eq!(corrupt(0, 4), None, "unknown protocol");
        assert_eq!(corrupt(1, 0), None, "node address 0");
        assert_eq!(corrupt(2, 3), None, "unknown parity");
        assert_eq!(corrupt(3, 3), None, "three stop bits");
        assert_eq!(corrupt(4, 10), None, "10 ms time-out");
        assert_eq!(corrupt(6, 6), None, "six retries");
        assert_eq!(corrupt(13, 4), None, "HPR id 4");
        assert_eq!(corrupt(14, 0), None, "no failures before down");
        assert_eq!(corrupt(21, 0x20), None, "reserved flag");
        assert_eq!(corrupt(22, 17), None, "unframed Phoenix format");
        assert_eq!(corrupt(22, 2), None, "no such Phoenix format");
        assert_eq!(corrupt(23, 2), None, "bad process tag");
        assert_eq!(corrupt(24, 1), None, "process bytes without a process");
        assert_eq!(corrupt(29, 0x80), None, "an eighth input active high");
        assert_eq!(corrupt(30, 101), None, "TORCH_ON debounce above 100 ms");
        assert_eq!(corrupt(37, 1), None, "START inverted");
        assert_eq!(corrupt(38, 0), None, "CNC node address 0 (broadcast)");
        assert_eq!(corrupt(39, 0x81), None, "CNC baud not one of the five");
        assert_eq!(corrupt(43, 3), None, "unknown CNC parity");
        assert_eq!(corrupt(44, 3), None, "three CNC stop bits");
        let with_process = Settings {
            process: Some(Process {
                mode: Mode::Cut,
                amps: Amps::from_raw(45 * 64),
                pressure: Pressure::Auto,
            }),
            ..Settings::default()
        };
        let len = with_process.encode(&mut out);
        let mut r = out;
        r[24] = 4;
        assert_eq!(Settings::decode(&r[..len]), None, "unknown mode");
        let mut r = out;
        r[25..27].copy_from_slice(&(401u16 * 64).to_le_bytes());
        assert_eq!(Settings::decode(&r[..len]), None, "amps above 400");
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
        assert!(
            text(s.set(ConfigKey::PhoenixFormat, "17").unwrap_err())
                .starts_with("RANGE phoenix_format 17 is not a framed format")
        );
        assert!(s.set(ConfigKey::PhoenixFormat, "300").is_err());
        assert_eq!(s, before);
        assert_eq!(
            Settings::accepted(ConfigKey::PollMs).to_string(),
            "20..1000"
        );
    }

    #[test]
    fn a_version_1_record_still_loads_with_the_reference_wiring() {
        let mut s = Settings::default();
        s.set(ConfigKey::TimeoutMs, "250").unwrap();
        s.set(ConfigKey::TorchOnActive, "HIGH").unwrap();
        let mut out = [0u8; 64];
        let len = s.encode(&mut out);
        assert_eq!(len, RECORD_LEN);
        // A version-1 record is the first 29 bytes of a version-2 one.
        let v1 = &out[..RECORD_V1_LEN];
        assert_eq!(Settings::decode(v1), None, "not a version-2 record");
        let migrated = Settings::migrate(1, v1).unwrap();
        assert_eq!(migrated.link, s.link);
        assert_eq!(migrated.io.inputs, crate::io::InputConfig::default());
        assert_eq!(
            migrated.get(ConfigKey::TorchOnActive),
            ConfigValue::Word("LOW")
        );
        assert_eq!(Settings::migrate(3, v1), None);
        // And the wiring round-trips in version 2.
        assert_eq!(Settings::decode(&out[..len]), Some(s));
    }

    #[test]
    fn save_errors_from_the_store() {
        assert_eq!(
            SaveError::from(StoreError::<()>::TooLarge),
            SaveError::TooLarge
        );
        assert_eq!(SaveError::from(StoreError::Flash(7)), SaveError::Flash);
    }
}
