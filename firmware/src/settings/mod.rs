//! Everything the bridge keeps across a power cycle.
//!
//! [`Settings`] holds the link configuration, the discrete-I/O configuration, the CNC port
//! options (events, Phoenix framing) and the last process the CNC asked for, so that it can be
//! applied again after power-up. The `CONFIG` keys that show and change it are in `config`
//! ([`Settings::get`], [`Settings::set`], [`Settings::accepted`]); the record the store keeps
//! is in `record`: it implements [`storage::Persistent`] with a fixed-layout, versioned binary
//! record; decoding is strict (wrong length, an unknown code, a value out of range, a reserved
//! bit set: `None`, and the store falls back to the defaults).
//!
//! ```
//! use plasma_firmware::settings::Settings;
//! use plasma_firmware::storage::Persistent as _;
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
use plasma_protocol::cnc::{AMPS_MAX, AMPS_MIN, Amps, Mode, PSI_MAX, PSI_MIN, Pressure};
use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_protocol::time::Duration;

use crate::io::{IoConfig, MIN_START_GAP};
use crate::link::LinkConfig;
#[cfg(doc)]
use crate::storage;
use crate::storage::StoreError;

mod config;
mod record;
mod wiring;

use config::parse_number;
pub use config::{Accepted, ConfigValue, SetError};
pub use record::{RECORD_LEN, RECORD_V1_LEN};

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

// --- the CNC port: framing and Powermax node address (issue 13) ------------------------------

/// The baud rates `cnc_baud` accepts: Phoenix's messaging ports from 1200 up (Phoenix manual,
/// "Baud Rate": 1200 to 115200; the rates between are the common ones).
pub const CNC_BAUDS: [u32; 8] = [1_200, 2_400, 4_800, 9_600, 19_200, 38_400, 57_600, 115_200];

/// The CNC port: its UART framing and the node address the bridge answers at as a Powermax
/// (Modbus ASCII requests on the CNC port, see `cnc::powermax_port`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CncPort {
    /// Modbus node address the bridge answers at, [`CncPort::MIN_ADDRESS`] to
    /// [`CncPort::MAX_ADDRESS`].
    pub address: u8,
    /// UART framing.
    pub framing: PortConfig,
}

impl CncPort {
    /// 115200 8N1 (the board's ST-LINK virtual COM port, the text protocol's default), node 1
    /// (the node LinuxCNC's pmx485 always addresses).
    pub const DEFAULT: CncPort = CncPort {
        address: 1,
        framing: PortConfig::new(115_200, Parity::None, StopBits::One),
    };

    /// Lowest node address accepted (0 is the broadcast address).
    pub const MIN_ADDRESS: u8 = 1;
    /// Highest node address accepted (Modbus reserves 248-255).
    pub const MAX_ADDRESS: u8 = 247;

    fn is_valid(&self) -> bool {
        (Self::MIN_ADDRESS..=Self::MAX_ADDRESS).contains(&self.address)
            && CNC_BAUDS.contains(&self.framing.baud)
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
    /// How the Phoenix CNC frames serial messages (any of the manual's sixteen formats).
    pub phoenix_format: Format,
    /// The last process the unit confirmed (`None` after `REMOTE OFF`).
    pub process: Option<Process>,
    /// The CNC port's framing and Powermax node address.
    pub cnc: CncPort,
    /// The limits of a consumable set (OFF by default: no manual gives a figure).
    pub consumable_limits: crate::consumables::Limits,
    /// The units on the power-supply line (`CONFIG units`; one, auto-detected, by default).
    pub units: crate::link::NamedUnits,
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
            consumable_limits: crate::consumables::Limits::default(),
            units: crate::link::NamedUnits::AUTO,
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

fn ms(duration: Duration) -> u32 {
    u32::try_from(duration.as_millis()).unwrap_or(u32::MAX)
}

impl Settings {
    /// The CNC port's UART framing (`cnc_baud`, `cnc_parity`, `cnc_stop_bits`,
    /// `cnc_data_bits`).
    pub fn cnc_port_config(&self) -> PortConfig {
        self.cnc.framing
    }

    /// The settings a boot runs with: as loaded, except that with the user button (B1) held
    /// at reset the CNC port takes its default framing ([`CncPort::DEFAULT`]), the way back
    /// to a board whose saved framing is forgotten. Everything else stays, the CNC port's
    /// node address among it, and nothing is written: `CONFIG SAVE` keeps the default framing.
    pub fn at_boot(self, user_button_held: bool) -> Settings {
        if !user_button_held {
            return self;
        }
        Settings {
            cnc: CncPort {
                framing: CncPort::DEFAULT.framing,
                ..self.cnc
            },
            ..self
        }
    }

    /// True when every field is one this firmware accepts (what [`decode`] insists on).
    ///
    /// [`decode`]: storage::Persistent::decode
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
            && self.cnc.is_valid()
            && crate::link::NamedUnits::new(self.link, self.units.as_slice()).is_ok()
            && process_ok
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::cnc::ConfigKey;

    #[test]
    fn save_errors_from_the_store() {
        assert_eq!(
            SaveError::from(StoreError::<()>::TooLarge),
            SaveError::TooLarge
        );
        assert_eq!(SaveError::from(StoreError::Flash(7)), SaveError::Flash);
    }

    #[test]
    fn the_user_button_at_boot_restores_the_cnc_framing_only() {
        let mut saved = Settings::default();
        for (key, value) in [
            (ConfigKey::CncBaud, "19200"),
            (ConfigKey::CncParity, "EVEN"),
            (ConfigKey::CncStopBits, "2"),
            (ConfigKey::CncDataBits, "7"),
            (ConfigKey::CncAddress, "7"),
            (ConfigKey::TimeoutMs, "250"),
            (ConfigKey::InterlockReady, "OFF"),
        ] {
            saved.set(key, value).unwrap();
        }
        assert_eq!(saved.at_boot(false), saved, "not held: as saved");
        let booted = saved.at_boot(true);
        assert_eq!(booted.cnc_port_config(), CncPort::DEFAULT.framing);
        assert_ne!(booted.cnc_port_config(), saved.cnc_port_config());
        assert_eq!(booted.cnc.address, 7, "the node address stays");
        assert_eq!(
            Settings {
                cnc: saved.cnc,
                ..booted
            },
            saved,
            "nothing else changes"
        );
    }
}
