//! The system identity string of the 000 HELLO reply.
//!
//! The manual shows `HYPERFORMANCE130MANUAL`, `HYPERFORMANCE130AUTO`,
//! `HYPERFORMANCE130AUTOMIX`, `HYPERFORMANCE400XD` (added in revision N) and `MaxPro200`.
//! The grammar used here is `HYPERFORMANCE` + rating (130, 260, 400) + optional `XD` +
//! optional gas console (`MANUAL`, `AUTO`, `AUTOMIX`). The copy of the manual the project has
//! prints `HYPERPERFORMANCE`: an OCR/typing error (the samples' checksums only match
//! `HYPERFORMANCE`). Both spellings are accepted; the correct one is emitted.

use super::field::DataWriter;
use crate::{Error, Result};

const HPR_PREFIX: &[u8] = b"HYPERFORMANCE";
const HPR_PREFIX_TYPO: &[u8] = b"HYPERPERFORMANCE";
const MAXPRO200: &[u8] = b"MaxPro200";

/// Current rating of an HPR power supply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HprRating {
    /// HPR130.
    Hpr130,
    /// HPR260.
    Hpr260,
    /// HPR400.
    Hpr400,
}

impl HprRating {
    /// Highest current in amps (the 058/095 limit on this model).
    pub const fn max_amps(self) -> u16 {
        match self {
            HprRating::Hpr130 => 130,
            HprRating::Hpr260 => 260,
            HprRating::Hpr400 => 400,
        }
    }

    const fn digits(self) -> &'static [u8] {
        match self {
            HprRating::Hpr130 => b"130",
            HprRating::Hpr260 => b"260",
            HprRating::Hpr400 => b"400",
        }
    }
}

/// Gas console named in an HPR identity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GasConsole {
    /// Manual gas console (`MANUAL`).
    Manual,
    /// Automatic gas console (`AUTO`).
    Auto,
    /// Automatic gas console with mixing (`AUTOMIX`).
    AutoMix,
}

impl GasConsole {
    const fn text(self) -> &'static [u8] {
        match self {
            GasConsole::Manual => b"MANUAL",
            GasConsole::Auto => b"AUTO",
            GasConsole::AutoMix => b"AUTOMIX",
        }
    }
}

/// Which system answered HELLO.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SystemId {
    /// A HyPerformance supply.
    Hpr {
        /// Current rating.
        rating: HprRating,
        /// An XD ("extended duty") model.
        xd: bool,
        /// Gas console, when the identity names one.
        console: Option<GasConsole>,
    },
    /// A MaxPro200.
    MaxPro200,
}

impl SystemId {
    /// Parse the HELLO reply data. Unknown identities are [`Error::Unsupported`].
    pub fn parse(text: &[u8]) -> Result<SystemId> {
        if text == MAXPRO200 {
            return Ok(SystemId::MaxPro200);
        }
        let rest = text
            .strip_prefix(HPR_PREFIX)
            .or_else(|| text.strip_prefix(HPR_PREFIX_TYPO))
            .ok_or(Error::Unsupported)?;
        let rating = [HprRating::Hpr130, HprRating::Hpr260, HprRating::Hpr400]
            .into_iter()
            .find(|r| rest.starts_with(r.digits()))
            .ok_or(Error::Unsupported)?;
        let rest = rest.get(3..).unwrap_or_default();
        let (xd, rest) = match rest.strip_prefix(b"XD") {
            Some(r) => (true, r),
            None => (false, rest),
        };
        let console = match rest {
            b"" => None,
            b"MANUAL" => Some(GasConsole::Manual),
            b"AUTO" => Some(GasConsole::Auto),
            b"AUTOMIX" => Some(GasConsole::AutoMix),
            _ => return Err(Error::Unsupported),
        };
        Ok(SystemId::Hpr {
            rating,
            xd,
            console,
        })
    }

    pub(crate) fn write(&self, w: &mut DataWriter) -> Result<()> {
        match self {
            SystemId::MaxPro200 => w.bytes(MAXPRO200),
            SystemId::Hpr {
                rating,
                xd,
                console,
            } => {
                w.bytes(HPR_PREFIX)?;
                w.bytes(rating.digits())?;
                if *xd {
                    w.bytes(b"XD")?;
                }
                match console {
                    Some(c) => w.bytes(c.text()),
                    None => Ok(()),
                }
            }
        }
    }

    /// True for a MaxPro200 (its 079 reply and 095/078 requests take the MaxPro200 forms).
    pub const fn is_maxpro200(&self) -> bool {
        matches!(self, SystemId::MaxPro200)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identities() {
        assert_eq!(SystemId::parse(b"MaxPro200"), Ok(SystemId::MaxPro200));
        assert_eq!(
            SystemId::parse(b"HYPERFORMANCE400XD"),
            Ok(SystemId::Hpr {
                rating: HprRating::Hpr400,
                xd: true,
                console: None
            })
        );
        assert_eq!(
            SystemId::parse(b"HYPERPERFORMANCE260AUTOMIX"),
            Ok(SystemId::Hpr {
                rating: HprRating::Hpr260,
                xd: false,
                console: Some(GasConsole::AutoMix)
            })
        );
        assert_eq!(
            SystemId::parse(b"HYPERFORMANCE200"),
            Err(Error::Unsupported)
        );
        assert_eq!(
            SystemId::parse(b"HYPERFORMANCE130AUTOX"),
            Err(Error::Unsupported)
        );
        assert_eq!(SystemId::parse(b"MAXPRO200"), Err(Error::Unsupported));
        assert_eq!(SystemId::parse(b""), Err(Error::Unsupported));
    }

    #[test]
    fn emits_correct_spelling() {
        let mut w = DataWriter::new();
        let id = SystemId::parse(b"HYPERPERFORMANCE130MANUAL").unwrap();
        id.write(&mut w).unwrap();
        assert_eq!(w.as_bytes(), b"HYPERFORMANCE130MANUAL");
    }
}
