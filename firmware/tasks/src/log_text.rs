//! How the board's log names the unit, its faults and the I/O events: the words a person
//! reads on the unit's panel and in the docs (`link up: Powermax65/85/105 SYNC`, `power supply
//! fault 0-50-0`, `start refused: link to power supply down`), not the library's types as
//! `defmt::Format` derives them (`Some(Powermax(Powermax65_85_105Sync))`). The texts are the
//! library's and the protocol crate's own (`Display`, `name()`), formatted through `core::fmt`
//! (already in the image for the CNC replies).

use defmt::{Display2Format, Format, Formatter, write};
use plasma_firmware::io::IoEvent;
use plasma_firmware::link::{ActiveFault, Model};
use plasma_firmware::platform::runner::PortError;
use plasma_firmware::platform::supervisor::TurnError;
use plasma_protocol::Text;
use plasma_protocol::hpr::SystemId;
use plasma_protocol::serial::PortConfig;

/// The unit that answered: the model's name (`Powermax65/85/105 SYNC`, `HPR260XD`,
/// `MaxPro200`, `Powermax` when it did not say which).
pub struct UnitName(pub Option<Model>);

impl Format for UnitName {
    fn format(&self, f: Formatter<'_>) {
        match self.0 {
            Some(Model::Powermax(model)) => write!(f, "{=str}", model.name()),
            Some(Model::PowermaxUnidentified) => write!(f, "Powermax"),
            Some(Model::Hpr(SystemId::MaxPro200)) => write!(f, "MaxPro200"),
            Some(Model::Hpr(SystemId::Hpr { rating, xd, .. })) => write!(
                f,
                "HPR{=u16}{=str}",
                rating.max_amps(),
                if xd { "XD" } else { "" }
            ),
            None => write!(f, "unknown unit"),
        }
    }
}

/// A fault as the unit shows it: `0-50-0` (Powermax, X-YY-Z) or `error 023 <name>` (HPR,
/// MaxPro200).
pub struct FaultName(pub ActiveFault);

impl Format for FaultName {
    fn format(&self, f: Formatter<'_>) {
        match self.0 {
            ActiveFault::Powermax(code) => write!(f, "{}", Display2Format(&code)),
            ActiveFault::Hpr(code) => write!(
                f,
                "error {=u16:03} {}",
                code.0,
                code.name().unwrap_or(Text::plain("(not in the manual)"))
            ),
        }
    }
}

/// An I/O event in the library's words (`io::IoEvent`'s `Display`).
pub struct EventText(pub IoEvent);

impl Format for EventText {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{}", Display2Format(&self.0))
    }
}

/// A serial port's failure in a bridge turn, naming the port (`CNC port: read failed:
/// framing error`).
pub struct TurnFailure<'a, P, C>(pub &'a TurnError<P, C>);

impl<P: Format, C: Format> Format for TurnFailure<'_, P, C> {
    fn format(&self, f: Formatter<'_>) {
        match self.0 {
            TurnError::Ps(PortError::Read(e)) => write!(f, "power-supply port: read failed: {}", e),
            TurnError::Ps(PortError::Write(e)) => {
                write!(f, "power-supply port: write failed: {}", e)
            }
            TurnError::Ps(PortError::Closed) => write!(f, "power-supply port closed"),
            TurnError::Ps(PortError::Unsupported(config)) => write!(
                f,
                "power-supply port cannot run {=u32} baud {}",
                config.baud,
                Framing(*config)
            ),
            TurnError::CncRead(e) => write!(f, "CNC port: read failed: {}", e),
            TurnError::CncWrite(e) => write!(f, "CNC port: write failed, output lost: {}", e),
            TurnError::CncClosed => write!(f, "CNC port closed"),
            TurnError::CncUnsupported(config) => write!(
                f,
                "CNC port cannot run {=u32} baud {}",
                config.baud,
                Framing(*config)
            ),
        }
    }
}

/// A line setting's short form (`8E1`, `7N2`), as `PortConfig::framing` writes it.
pub struct Framing(pub PortConfig);

impl Format for Framing {
    fn format(&self, f: Formatter<'_>) {
        let PortConfig {
            data_bits,
            parity,
            stop_bits,
            ..
        } = self.0;
        write!(
            f,
            "{=u8}{=char}{=u8}",
            data_bits.number(),
            parity.letter(),
            stop_bits.number()
        )
    }
}
