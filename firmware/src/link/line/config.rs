//! Which units share the line, and whether they can.

use core::fmt;

use heapless::Vec;

use crate::link::{ConfigError, LinkConfig, ProtocolChoice};

/// The most units one line carries: HPR ids are 0-3 (HPR manual, 002_72b43a5685974c77.txt,
/// lines 93-105). Powermax nodes could be more; the bridge drives four at most.
pub const MAX_UNITS: usize = plasma_protocol::cnc::MAX_UNIT as usize;

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

/// The units `CONFIG units` names, in order: none (`AUTO`, one unit found by auto-detection,
/// the default) or 1-4 that can share a line. A small copyable value, kept in the settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NamedUnits {
    len: u8,
    units: [LineUnit; MAX_UNITS],
}

/// Why a `CONFIG units` value is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum UnitsError {
    /// A word that is not `AUTO`, `HPR:<id>`, `POWERMAX:<node>` or `MAXPRO200`.
    Syntax,
    /// Units that cannot share a line.
    Line(LineError),
}

impl fmt::Display for UnitsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UnitsError::Syntax => write!(f, "units: expected {}", NamedUnits::WORDS),
            UnitsError::Line(error) => write!(f, "units: {error}"),
        }
    }
}

impl NamedUnits {
    /// One unit, auto-detected.
    pub const AUTO: NamedUnits = NamedUnits {
        len: 0,
        units: [LineUnit::MaxPro200; MAX_UNITS],
    };

    /// What `CONFIG units` accepts.
    pub const WORDS: &'static str =
        "AUTO|<unit>[,<unit>...] with <unit> HPR:0-3|POWERMAX:1-255|MAXPRO200";

    /// `units`, checked as [`SharedLine::new`](super::SharedLine::new) checks them (`base` for
    /// the link settings they share); none is [`NamedUnits::AUTO`].
    pub fn new(base: LinkConfig, units: &[LineUnit]) -> Result<NamedUnits, LineError> {
        if units.is_empty() {
            return Ok(NamedUnits::AUTO);
        }
        link_configs(base, units)?;
        let mut named = NamedUnits::AUTO;
        for (slot, unit) in named.units.iter_mut().zip(units) {
            *slot = *unit;
        }
        named.len = units.len() as u8;
        Ok(named)
    }

    /// The units, in order (empty for `AUTO`).
    pub fn as_slice(&self) -> &[LineUnit] {
        self.units.get(..usize::from(self.len)).unwrap_or(&[])
    }

    /// How many units the bridge drives: 1 for `AUTO`.
    pub fn count(&self) -> usize {
        usize::from(self.len).max(1)
    }

    /// The value as `CONFIG units` types it: `AUTO`, or a comma-separated list.
    pub fn parse(base: LinkConfig, text: &str) -> Result<NamedUnits, UnitsError> {
        if text.eq_ignore_ascii_case("AUTO") {
            return Ok(NamedUnits::AUTO);
        }
        let mut units: Vec<LineUnit, MAX_UNITS> = Vec::new();
        let mut count = 0;
        // A predicate, not `split(',')`: the char searcher costs flash.
        #[allow(
            clippy::manual_pattern_char_comparison,
            reason = "the char searcher costs flash"
        )]
        let words = text.split(|c: char| c == ',');
        for word in words {
            count += 1;
            let unit = LineUnit::parse(word).ok_or(UnitsError::Syntax)?;
            // Past MAX_UNITS the count alone is reported.
            let _ = units.push(unit);
        }
        if count > MAX_UNITS {
            return Err(UnitsError::Line(LineError::TooManyUnits { count }));
        }
        NamedUnits::new(base, &units).map_err(UnitsError::Line)
    }
}

impl fmt::Display for NamedUnits {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.len == 0 {
            return f.write_str("AUTO");
        }
        for (index, unit) in self.as_slice().iter().enumerate() {
            if index > 0 {
                f.write_str(",")?;
            }
            unit.fmt(f)?;
        }
        Ok(())
    }
}

/// As `CONFIG units` writes it: `HPR:<id>`, `MAXPRO200`, `POWERMAX:<node>`.
impl fmt::Display for LineUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LineUnit::Hpr { id } => write!(f, "HPR:{id}"),
            LineUnit::MaxPro200 => f.write_str("MAXPRO200"),
            LineUnit::Powermax { node } => write!(f, "POWERMAX:{node}"),
        }
    }
}

impl LineUnit {
    /// One unit as `CONFIG units` writes it (any case): `HPR:<id>`, `POWERMAX:<node>`,
    /// `MAXPRO200`.
    fn parse(word: &str) -> Option<LineUnit> {
        if word.eq_ignore_ascii_case("MAXPRO200") {
            return Some(LineUnit::MaxPro200);
        }
        let colon = word.bytes().position(|b| b == b':')?;
        let (kind, number) = (word.get(..colon)?, word.get(colon + 1..)?);
        if number.is_empty() || !number.bytes().all(|b| b.is_ascii_digit()) || number.len() > 3 {
            return None;
        }
        let number: u8 = number.parse().ok()?;
        if kind.eq_ignore_ascii_case("HPR") {
            Some(LineUnit::Hpr { id: number })
        } else if kind.eq_ignore_ascii_case("POWERMAX") {
            Some(LineUnit::Powermax { node: number })
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use super::*;

    fn parse(text: &str) -> Result<NamedUnits, UnitsError> {
        NamedUnits::parse(LinkConfig::default(), text)
    }

    #[test]
    fn units_are_auto_or_a_list_that_can_share_a_line() {
        assert_eq!(parse("auto"), Ok(NamedUnits::AUTO));
        assert_eq!(NamedUnits::AUTO.count(), 1);
        let two = parse("hpr:0,HPR:1").unwrap();
        assert_eq!(
            two.as_slice(),
            [LineUnit::Hpr { id: 0 }, LineUnit::Hpr { id: 1 }]
        );
        assert_eq!(two.to_string(), "HPR:0,HPR:1");
        assert_eq!(parse(&two.to_string()), Ok(two));
        let nodes = parse("POWERMAX:1,POWERMAX:2,POWERMAX:3,POWERMAX:4").unwrap();
        assert_eq!(nodes.count(), 4);
        assert_eq!(parse("maxpro200").unwrap().to_string(), "MAXPRO200");
    }

    #[test]
    fn units_that_cannot_share_a_line_are_refused_with_the_reason() {
        let text = |t: &str| parse(t).unwrap_err().to_string();
        assert_eq!(
            text("HPR:0,POWERMAX:1"),
            "units: unit 2 cannot share the line: a Powermax speaks Modbus ASCII, an HPR or \
             MaxPro200 its own protocol"
        );
        assert_eq!(
            text("MAXPRO200,HPR:1"),
            "units: a MaxPro200 cannot share a line: it has no SLEEP/WAKE, so it answers every request"
        );
        assert_eq!(
            text("HPR:1,HPR:1"),
            "units: units 1 and 2 have the same id or node address"
        );
        assert_eq!(
            text("HPR:0,HPR:1,HPR:2,HPR:3,HPR:0"),
            "units: 5 units: a line carries 4 at most"
        );
        assert!(
            text("HPR:4").starts_with("units: unit 1: "),
            "{}",
            text("HPR:4")
        );
        assert!(text("POWERMAX:0").starts_with("units: unit 1: "));
        assert_eq!(
            text("hpr"),
            std::format!("units: expected {}", NamedUnits::WORDS)
        );
        assert_eq!(text("HPR:x"), text("hpr"));
        assert_eq!(text(""), text("hpr"));
    }
}
