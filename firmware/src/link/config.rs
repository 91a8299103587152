//! What the installer chooses about the power-supply link, checked before the link starts.

use core::fmt;

use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_protocol::time::{Decimal, Duration};

/// Which protocol family the link speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ProtocolChoice {
    /// Find out: Modbus device identification, then a legacy register read, then HPR HELLO.
    #[default]
    Auto,
    /// Powermax SYNC (registers 0x3xxx) only.
    Sync,
    /// Older Powermax (registers 0x2xxx) only.
    Legacy,
    /// HyPerformance HPR / MaxPro200 (`>ID data CK<`) only.
    Hpr,
}

/// Link settings. Build with [`LinkConfig::default`] and adjust; [`LinkConfig::validate`]
/// says precisely what is wrong. Each field's range is written once, as the `MIN_`/`MAX_`
/// constants below, beside the two functions that enforce them ([`LinkConfig::validate`]
/// refuses, [`LinkConfig::clamped`] clamps); the `CONFIG` keys read the same constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkConfig {
    /// Protocol family (default: auto-detect).
    pub protocol: ProtocolChoice,
    /// Modbus node address, [`LinkConfig::MIN_NODE_ADDRESS`] up (default 1). A unit set to 0
    /// learns it from the first request.
    pub node_address: u8,
    /// Modbus parity (default even; SYNC units can be set to odd or none).
    pub modbus_parity: Parity,
    /// Modbus stop bits (default 1).
    pub modbus_stop_bits: StopBits,
    /// Time to wait for a reply, [`LinkConfig::MIN_RESPONSE_TIMEOUT`] to
    /// [`LinkConfig::MAX_RESPONSE_TIMEOUT`] (default 100 ms; the SYNC guide asks for 60-100).
    pub response_timeout: Duration,
    /// Further attempts after the first one fails, 0-[`LinkConfig::MAX_RETRIES`] (default 2).
    pub retries: u8,
    /// Time between status polls, [`LinkConfig::MIN_POLL_INTERVAL`] to
    /// [`LinkConfig::MAX_POLL_INTERVAL`] (default 100 ms; faults must be checked at least every
    /// second, and a new fault should be known within 250 ms).
    pub poll_interval: Duration,
    /// Time between refreshes of slow data (limits, counters, cartridge, logs),
    /// [`LinkConfig::MIN_SLOW_DATA_INTERVAL`] to [`LinkConfig::MAX_SLOW_DATA_INTERVAL`] (default
    /// 30 s). Slow data is also read at start, on a cartridge change and on request.
    pub slow_data_interval: Duration,
    /// HPR multi-drop system id, 0-[`LinkConfig::MAX_HPR_ID`] (dip switches); ids other than 0
    /// need SLEEP/WAKE.
    pub hpr_id: u8,
    /// Consecutive failed transactions (all retries used) that heard nothing at all before
    /// the link is declared down, [`LinkConfig::MIN_FAILURES_BEFORE_DOWN`] to
    /// [`LinkConfig::MAX_FAILURES_BEFORE_DOWN`] (default 3).
    /// Damaged replies are no silence: they are counted and retried, and only
    /// [`UNANSWERED_FACTOR`](super::UNANSWERED_FACTOR) times as many failures in a row
    /// without one valid reply take the link down.
    pub failures_before_down: u8,
    /// After the unit's own power cycle (it answers again without the settings the bridge
    /// gave it, see `kept`), apply the kept settings again anyway (default off: switching the
    /// unit off is how an operator takes it back from remote control, and the CNC asks again
    /// when it wants it). After a lost link they are always re-applied.
    pub reapply_after_power_cycle: bool,
}

impl LinkConfig {
    /// True when going from `self` to `other` needs detection to start again: any change
    /// but the re-apply policy, which applies from the next decision on.
    pub fn needs_redetect(&self, other: &LinkConfig) -> bool {
        let same_policy = LinkConfig {
            reapply_after_power_cycle: other.reapply_after_power_cycle,
            ..*self
        };
        same_policy != *other
    }

    /// Lowest node address accepted (0 is the units' own "learn the address" setting).
    pub const MIN_NODE_ADDRESS: u8 = 1;
    /// Shortest response time-out accepted.
    pub const MIN_RESPONSE_TIMEOUT: Duration = Duration::from_millis(60);
    /// Longest response time-out accepted.
    pub const MAX_RESPONSE_TIMEOUT: Duration = Duration::from_millis(1000);
    /// Most retries accepted.
    pub const MAX_RETRIES: u8 = 5;
    /// Shortest poll interval accepted.
    pub const MIN_POLL_INTERVAL: Duration = Duration::from_millis(20);
    /// Longest poll interval accepted (the SYNC guide: check for faults every second).
    pub const MAX_POLL_INTERVAL: Duration = Duration::from_millis(1000);
    /// Shortest slow-data interval accepted.
    pub const MIN_SLOW_DATA_INTERVAL: Duration = Duration::from_secs(1);
    /// Longest slow-data interval accepted.
    pub const MAX_SLOW_DATA_INTERVAL: Duration = Duration::from_secs(3600);
    /// Highest HPR multi-drop id (dip switches 2-4 give 0-3; the rest are reserved).
    pub const MAX_HPR_ID: u8 = 3;
    /// Fewest consecutive failures accepted before link-down.
    pub const MIN_FAILURES_BEFORE_DOWN: u8 = 1;
    /// Most consecutive failures accepted before link-down.
    pub const MAX_FAILURES_BEFORE_DOWN: u8 = 10;

    /// Every field moved into its range (the nearest end when outside):
    /// [`PsLink::new`](super::PsLink::new) runs with this. It changes a field exactly when
    /// [`LinkConfig::validate`] refuses it.
    pub fn clamped(self) -> LinkConfig {
        let clamp = |d: Duration, lo: Duration, hi: Duration| d.max(lo).min(hi);
        LinkConfig {
            node_address: self.node_address.max(Self::MIN_NODE_ADDRESS),
            response_timeout: clamp(
                self.response_timeout,
                Self::MIN_RESPONSE_TIMEOUT,
                Self::MAX_RESPONSE_TIMEOUT,
            ),
            retries: self.retries.min(Self::MAX_RETRIES),
            poll_interval: clamp(
                self.poll_interval,
                Self::MIN_POLL_INTERVAL,
                Self::MAX_POLL_INTERVAL,
            ),
            slow_data_interval: clamp(
                self.slow_data_interval,
                Self::MIN_SLOW_DATA_INTERVAL,
                Self::MAX_SLOW_DATA_INTERVAL,
            ),
            hpr_id: self.hpr_id.min(Self::MAX_HPR_ID),
            failures_before_down: self.failures_before_down.clamp(
                Self::MIN_FAILURES_BEFORE_DOWN,
                Self::MAX_FAILURES_BEFORE_DOWN,
            ),
            ..self
        }
    }

    /// Check every field; the first problem found is returned.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.node_address < Self::MIN_NODE_ADDRESS {
            return Err(ConfigError::NodeAddressZero);
        }
        let timeout = self.response_timeout;
        if timeout < Self::MIN_RESPONSE_TIMEOUT || timeout > Self::MAX_RESPONSE_TIMEOUT {
            return Err(ConfigError::ResponseTimeoutOutOfRange {
                ms: timeout.as_millis(),
            });
        }
        if self.retries > Self::MAX_RETRIES {
            return Err(ConfigError::TooManyRetries {
                retries: self.retries,
            });
        }
        let poll = self.poll_interval;
        if poll < Self::MIN_POLL_INTERVAL || poll > Self::MAX_POLL_INTERVAL {
            return Err(ConfigError::PollIntervalOutOfRange {
                ms: poll.as_millis(),
            });
        }
        let slow = self.slow_data_interval;
        if slow < Self::MIN_SLOW_DATA_INTERVAL || slow > Self::MAX_SLOW_DATA_INTERVAL {
            return Err(ConfigError::SlowDataIntervalOutOfRange {
                ms: slow.as_millis(),
            });
        }
        if self.hpr_id > Self::MAX_HPR_ID {
            return Err(ConfigError::HprIdOutOfRange { id: self.hpr_id });
        }
        if self.failures_before_down < Self::MIN_FAILURES_BEFORE_DOWN
            || self.failures_before_down > Self::MAX_FAILURES_BEFORE_DOWN
        {
            return Err(ConfigError::FailuresBeforeDownOutOfRange {
                count: self.failures_before_down,
            });
        }
        Ok(())
    }

    /// The UART settings for Modbus with this configuration (19200 baud).
    pub const fn modbus_port(&self) -> PortConfig {
        PortConfig::new(
            PortConfig::MODBUS_DEFAULT.baud,
            self.modbus_parity,
            self.modbus_stop_bits,
        )
    }
}

impl Default for LinkConfig {
    fn default() -> Self {
        LinkConfig {
            protocol: ProtocolChoice::Auto,
            node_address: 1,
            modbus_parity: Parity::Even,
            modbus_stop_bits: StopBits::One,
            response_timeout: Duration::from_millis(100),
            retries: 2,
            poll_interval: Duration::from_millis(100),
            slow_data_interval: Duration::from_secs(30),
            hpr_id: 0,
            failures_before_down: 3,
            reapply_after_power_cycle: false,
        }
    }
}

/// Why a [`LinkConfig`] was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// Node address 0 is the units' own "learn the address" setting, not a valid target.
    NodeAddressZero,
    /// Response time-out outside its range ([`LinkConfig::MIN_RESPONSE_TIMEOUT`]...).
    ResponseTimeoutOutOfRange {
        /// The value given, in milliseconds.
        ms: u64,
    },
    /// More than [`LinkConfig::MAX_RETRIES`] retries.
    TooManyRetries {
        /// The value given.
        retries: u8,
    },
    /// Poll interval outside its range ([`LinkConfig::MIN_POLL_INTERVAL`]...).
    PollIntervalOutOfRange {
        /// The value given, in milliseconds.
        ms: u64,
    },
    /// Slow-data interval outside its range ([`LinkConfig::MIN_SLOW_DATA_INTERVAL`]...).
    SlowDataIntervalOutOfRange {
        /// The value given, in milliseconds.
        ms: u64,
    },
    /// HPR multi-drop id above [`LinkConfig::MAX_HPR_ID`].
    HprIdOutOfRange {
        /// The value given.
        id: u8,
    },
    /// Failures-before-down outside its range ([`LinkConfig::MIN_FAILURES_BEFORE_DOWN`]...).
    FailuresBeforeDownOutOfRange {
        /// The value given.
        count: u8,
    },
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        type C = LinkConfig;
        // Decimal: `u64`'s own Display would bring the 64-bit division into the board image.
        let ms = |d: Duration| Decimal(d.as_millis());
        match self {
            ConfigError::NodeAddressZero => write!(
                f,
                "node address must be {}-{}, not 0",
                C::MIN_NODE_ADDRESS,
                u8::MAX
            ),
            ConfigError::ResponseTimeoutOutOfRange { ms: value } => write!(
                f,
                "response time-out {} ms is outside {}-{} ms",
                Decimal(*value),
                ms(C::MIN_RESPONSE_TIMEOUT),
                ms(C::MAX_RESPONSE_TIMEOUT)
            ),
            ConfigError::TooManyRetries { retries } => write!(
                f,
                "{retries} retries is more than the maximum of {}",
                C::MAX_RETRIES
            ),
            ConfigError::PollIntervalOutOfRange { ms: value } => write!(
                f,
                "poll interval {} ms is outside {}-{} ms",
                Decimal(*value),
                ms(C::MIN_POLL_INTERVAL),
                ms(C::MAX_POLL_INTERVAL)
            ),
            ConfigError::SlowDataIntervalOutOfRange { ms: value } => write!(
                f,
                "slow-data interval {} ms is outside {} s - {} h",
                Decimal(*value),
                Decimal(const { C::MIN_SLOW_DATA_INTERVAL.as_millis() / 1000 }),
                Decimal(const { C::MAX_SLOW_DATA_INTERVAL.as_millis() / 3_600_000 })
            ),
            ConfigError::HprIdOutOfRange { id } => {
                write!(f, "HPR id {id} is outside 0-{}", C::MAX_HPR_ID)
            }
            ConfigError::FailuresBeforeDownOutOfRange { count } => write!(
                f,
                "failures before link-down {count} is outside {}-{}",
                C::MIN_FAILURES_BEFORE_DOWN,
                C::MAX_FAILURES_BEFORE_DOWN
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use super::*;

    #[test]
    fn each_error_says_the_range_the_constants_give() {
        let text = |e: ConfigError| e.to_string();
        assert_eq!(
            text(ConfigError::NodeAddressZero),
            "node address must be 1-255, not 0"
        );
        assert_eq!(
            text(ConfigError::ResponseTimeoutOutOfRange { ms: 59 }),
            "response time-out 59 ms is outside 60-1000 ms"
        );
        assert_eq!(
            text(ConfigError::TooManyRetries { retries: 6 }),
            "6 retries is more than the maximum of 5"
        );
        assert_eq!(
            text(ConfigError::PollIntervalOutOfRange { ms: 1500 }),
            "poll interval 1500 ms is outside 20-1000 ms"
        );
        assert_eq!(
            text(ConfigError::SlowDataIntervalOutOfRange { ms: 500 }),
            "slow-data interval 500 ms is outside 1 s - 1 h"
        );
        assert_eq!(
            text(ConfigError::HprIdOutOfRange { id: 4 }),
            "HPR id 4 is outside 0-3"
        );
        assert_eq!(
            text(ConfigError::FailuresBeforeDownOutOfRange { count: 11 }),
            "failures before link-down 11 is outside 1-10"
        );
    }

    #[test]
    fn clamping_moves_each_field_to_the_nearest_end_of_its_range() {
        let wild = LinkConfig {
            node_address: 0,
            response_timeout: Duration::from_millis(5),
            retries: 200,
            poll_interval: Duration::from_secs(60),
            slow_data_interval: Duration::from_millis(1),
            hpr_id: 9,
            failures_before_down: 0,
            ..LinkConfig::default()
        };
        let clamped = wild.clamped();
        assert_eq!(clamped.validate(), Ok(()));
        assert_eq!(clamped.node_address, LinkConfig::MIN_NODE_ADDRESS);
        assert_eq!(clamped.response_timeout, LinkConfig::MIN_RESPONSE_TIMEOUT);
        assert_eq!(clamped.retries, LinkConfig::MAX_RETRIES);
        assert_eq!(clamped.poll_interval, LinkConfig::MAX_POLL_INTERVAL);
        assert_eq!(
            clamped.slow_data_interval,
            LinkConfig::MIN_SLOW_DATA_INTERVAL
        );
        assert_eq!(clamped.hpr_id, LinkConfig::MAX_HPR_ID);
        assert_eq!(
            clamped.failures_before_down,
            LinkConfig::MIN_FAILURES_BEFORE_DOWN
        );
        let valid = LinkConfig::default();
        assert_eq!(valid.clamped(), valid);
        // Refusing and clamping read the same ranges: one field at a time, at and beyond
        // each end, validate refuses exactly what clamped changes.
        let ms = Duration::from_millis;
        for config in [
            LinkConfig {
                node_address: 1,
                ..valid
            },
            LinkConfig {
                node_address: 255,
                ..valid
            },
            LinkConfig {
                response_timeout: ms(59),
                ..valid
            },
            LinkConfig {
                response_timeout: ms(60),
                ..valid
            },
            LinkConfig {
                response_timeout: ms(1000),
                ..valid
            },
            LinkConfig {
                response_timeout: ms(1001),
                ..valid
            },
            LinkConfig {
                retries: 5,
                ..valid
            },
            LinkConfig {
                retries: 6,
                ..valid
            },
            LinkConfig {
                poll_interval: ms(19),
                ..valid
            },
            LinkConfig {
                poll_interval: ms(20),
                ..valid
            },
            LinkConfig {
                poll_interval: ms(1001),
                ..valid
            },
            LinkConfig {
                slow_data_interval: ms(999),
                ..valid
            },
            LinkConfig {
                slow_data_interval: ms(3_600_000),
                ..valid
            },
            LinkConfig {
                slow_data_interval: ms(3_600_001),
                ..valid
            },
            LinkConfig { hpr_id: 3, ..valid },
            LinkConfig { hpr_id: 4, ..valid },
            LinkConfig {
                failures_before_down: 10,
                ..valid
            },
            LinkConfig {
                failures_before_down: 11,
                ..valid
            },
            wild,
        ] {
            assert_eq!(
                config.validate().is_ok(),
                config.clamped() == config,
                "{config:?}"
            );
        }
    }

    #[test]
    fn defaults_are_valid_and_follow_the_manuals() {
        let config = LinkConfig::default();
        assert_eq!(config.validate(), Ok(()));
        assert_eq!(config.node_address, 1);
        assert_eq!(config.response_timeout, Duration::from_millis(100));
        assert_eq!(config.retries, 2);
        assert_eq!(config.modbus_port(), PortConfig::MODBUS_DEFAULT);
    }

    #[test]
    fn each_out_of_range_field_is_named() {
        let base = LinkConfig::default();
        let check = |config: LinkConfig| config.validate().err();
        assert_eq!(
            check(LinkConfig {
                node_address: 0,
                ..base
            }),
            Some(ConfigError::NodeAddressZero)
        );
        assert_eq!(
            check(LinkConfig {
                response_timeout: Duration::from_millis(59),
                ..base
            }),
            Some(ConfigError::ResponseTimeoutOutOfRange { ms: 59 })
        );
        assert_eq!(
            check(LinkConfig {
                response_timeout: Duration::from_millis(1001),
                ..base
            }),
            Some(ConfigError::ResponseTimeoutOutOfRange { ms: 1001 })
        );
        assert_eq!(
            check(LinkConfig {
                response_timeout: Duration::from_millis(60),
                ..base
            }),
            None
        );
        assert_eq!(
            check(LinkConfig {
                response_timeout: Duration::from_millis(1000),
                ..base
            }),
            None
        );
        assert_eq!(
            check(LinkConfig { retries: 6, ..base }),
            Some(ConfigError::TooManyRetries { retries: 6 })
        );
        assert_eq!(
            check(LinkConfig {
                poll_interval: Duration::from_millis(1500),
                ..base
            }),
            Some(ConfigError::PollIntervalOutOfRange { ms: 1500 })
        );
        assert_eq!(
            check(LinkConfig {
                slow_data_interval: Duration::from_millis(500),
                ..base
            }),
            Some(ConfigError::SlowDataIntervalOutOfRange { ms: 500 })
        );
        assert_eq!(
            check(LinkConfig { hpr_id: 4, ..base }),
            Some(ConfigError::HprIdOutOfRange { id: 4 })
        );
        assert_eq!(
            check(LinkConfig {
                failures_before_down: 0,
                ..base
            }),
            Some(ConfigError::FailuresBeforeDownOutOfRange { count: 0 })
        );
    }
}
