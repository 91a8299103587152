//! Which units share the line, and whether they can.

use core::fmt;

use heapless::Vec;

use crate::link::{ConfigError, LinkConfig, ProtocolChoice};

/// The most units one line carries: HPR ids are 0-3 (HPR manual, 002_72b43a5685974c77.txt,
/// lines 93-105). Powermax nodes could be more; the bridge drives four at most.
pub const MAX_UNITS: usize = 4;

/// One unit on the line and how it is addressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LineUnit {
    /// An HPR system with this dip-switch id (0-3); several share a line by SLEEP / WAKE.
    Hpr {
        /// The unit's system id.
        id: u8,
    },
    /// A MaxPro200: it has no SLEEP / WAKE (the command table gives 085-087 to the HPR
    /// systems only, HPR manual lines 172-174), so it answers every request: alone only.
    MaxPro200,
    /// A Powermax at this node address (1-255); several share a line by address.
    Powermax {
        /// The unit's node address.
        node: u8,
    },
}

impl LineUnit {
    const fn speaks_modbus(self) -> bool {
        matches!(self, LineUnit::Powermax { .. })
    }

    /// The link configuration for this unit: `base` with its protocol and address.
    pub fn link_config(self, base: LinkConfig) -> LinkConfig {
        match self {
            LineUnit::Hpr { id } => LinkConfig {
                protocol: ProtocolChoice::Hpr,
                hpr_id: id,
                ..base
            },
            LineUnit::MaxPro200 => LinkConfig {
                protocol: ProtocolChoice::Hpr,
                hpr_id: 0,
                ..base
            },
            LineUnit::Powermax { node } => LinkConfig {
                protocol: match base.protocol {
                    ProtocolChoice::Sync | ProtocolChoice::Legacy => base.protocol,
                    ProtocolChoice::Auto | ProtocolChoice::Hpr => ProtocolChoice::Auto,
                },
                node_address: node,
                ..base
            },
        }
    }
}

/// Why a set of units cannot share one line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LineError {
    /// No unit at all.
    NoUnits,
    /// More than [`MAX_UNITS`].
    TooManyUnits {
        /// How many were given.
        count: usize,
    },
    /// A Powermax (Modbus ASCII) and an HPR or MaxPro200 (its own protocol and framing).
    MixedProtocols {
        /// The first unit of the other kind (0 = the first unit).
        unit: usize,
    },
    /// A MaxPro200 with other units: it cannot be put to sleep.
    NoMultiDrop,
    /// Two units with the same HPR id or node address.
    SameAddress {
        /// The earlier unit.
        first: usize,
        /// The later one.
        second: usize,
    },
    /// A unit's link configuration is refused (an HPR id above 3, node address 0...).
    Link {
        /// The unit.
        unit: usize,
        /// Why.
        error: ConfigError,
    },
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LineError::NoUnits => f.write_str("a line needs at least one unit"),
            LineError::TooManyUnits { count } => {
                write!(f, "{count} units: a line carries {MAX_UNITS} at most")
            }
            LineError::MixedProtocols { unit } => write!(
                f,
                "unit {} cannot share the line: a Powermax speaks Modbus ASCII, an HPR or \
                 MaxPro200 its own protocol",
                unit + 1
            ),
            LineError::NoMultiDrop => f.write_str(
                "a MaxPro200 cannot share a line: it has no SLEEP/WAKE, so it answers every \
                 request",
            ),
            LineError::SameAddress { first, second } => write!(
                f,
                "units {} and {} have the same id or node address",
                first + 1,
                second + 1
            ),
            LineError::Link { unit, error } => write!(f, "unit {}: {error}", unit + 1),
        }
    }
}

/// The link configuration of each of `units`, checked: one protocol family, a MaxPro200
/// alone, no address twice, each configuration valid.
pub(super) fn link_configs(
    base: LinkConfig,
    units: &[LineUnit],
) -> Result<Vec<LinkConfig, MAX_UNITS>, LineError> {
    let first = *units.first().ok_or(LineError::NoUnits)?;
    if units.len() > MAX_UNITS {
        return Err(LineError::TooManyUnits { count: units.len() });
    }
    if let Some(unit) = units
        .iter()
        .position(|u| u.speaks_modbus() != first.speaks_modbus())
    {
        return Err(LineError::MixedProtocols { unit });
    }
    if units.len() > 1 && units.contains(&LineUnit::MaxPro200) {
        return Err(LineError::NoMultiDrop);
    }
    let mut configs = Vec::new();
    for (second, unit) in units.iter().enumerate() {
        if let Some(first) = units.iter().take(second).position(|u| u == unit) {
            return Err(LineError::SameAddress { first, second });
        }
        let config = unit.link_config(base);
        config.validate().map_err(|error| LineError::Link {
            unit: second,
            error,
        })?;
        // At most MAX_UNITS, checked above.
        let _ = configs.push(config);
    }
    Ok(configs)
}
