//! Serial-port settings the bridge asks the board (or a simulator) to apply.
//!
//! Auto-detection switches between Modbus ASCII (19200 8E1 by default; SYNC units can be set
//! to odd/no parity and 1 or 2 stop bits) and the HPR protocol (19200 8N1). The CNC port
//! also runs 7 data bits (a Phoenix CNC's messaging port offers 7 or 8).
//!
//! ```
//! use plasma_protocol::serial::{DataBits, PortConfig};
//!
//! let phoenix = PortConfig::from_framing(9600, "7e1").unwrap();
//! assert_eq!(phoenix.data_bits, DataBits::Seven);
//! assert_eq!(phoenix.to_string(), "9600 7E1");
//! assert_eq!(PortConfig::from_framing(9600, "9N1"), None);
//! ```

use core::fmt;

/// Parity bit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Parity {
    /// No parity bit.
    None,
    /// Even parity (the Modbus default).
    Even,
    /// Odd parity.
    Odd,
}

/// Number of stop bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StopBits {
    /// One stop bit.
    One,
    /// Two stop bits.
    Two,
}

impl Parity {
    /// The letter of the short form (`N`, `E`, `O`).
    pub const fn letter(self) -> char {
        match self {
            Parity::None => 'N',
            Parity::Even => 'E',
            Parity::Odd => 'O',
        }
    }
}

impl StopBits {
    /// How many.
    pub const fn number(self) -> u8 {
        match self {
            StopBits::One => 1,
            StopBits::Two => 2,
        }
    }
}

/// Number of data bits in a character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DataBits {
    /// Seven: ASCII only, the top bit of a byte is not sent.
    Seven,
    /// Eight (every power-supply protocol).
    Eight,
}

impl DataBits {
    /// How many.
    pub const fn number(self) -> u8 {
        match self {
            DataBits::Seven => 7,
            DataBits::Eight => 8,
        }
    }
}

/// Line settings of a UART.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PortConfig {
    /// Bits per second.
    pub baud: u32,
    /// Data bits.
    pub data_bits: DataBits,
    /// Parity bit.
    pub parity: Parity,
    /// Stop bits.
    pub stop_bits: StopBits,
}

impl PortConfig {
    /// Powermax default: 19200 baud, 8 data bits, even parity, 1 stop bit.
    pub const MODBUS_DEFAULT: PortConfig = PortConfig::new(19_200, Parity::Even, StopBits::One);

    /// HPR / MaxPro200: 19200 baud, 8N1.
    pub const HPR: PortConfig = PortConfig::new(19_200, Parity::None, StopBits::One);

    /// `baud` with 8 data bits, `parity` and `stop_bits`.
    pub const fn new(baud: u32, parity: Parity, stop_bits: StopBits) -> PortConfig {
        PortConfig {
            baud,
            data_bits: DataBits::Eight,
            parity,
            stop_bits,
        }
    }

    /// The same with `data_bits`.
    pub const fn with_data_bits(self, data_bits: DataBits) -> PortConfig {
        PortConfig { data_bits, ..self }
    }

    /// `baud` with the short form `framing` (`8E1`, `7n2`: data bits, parity letter, stop
    /// bits; any case), or `None`.
    pub fn from_framing(baud: u32, framing: &str) -> Option<PortConfig> {
        let &[data, parity, stop] = framing.as_bytes() else {
            return None;
        };
        let data_bits = match data {
            b'7' => DataBits::Seven,
            b'8' => DataBits::Eight,
            _ => return None,
        };
        let parity = match parity.to_ascii_uppercase() {
            b'N' => Parity::None,
            b'E' => Parity::Even,
            b'O' => Parity::Odd,
            _ => return None,
        };
        let stop_bits = match stop {
            b'1' => StopBits::One,
            b'2' => StopBits::Two,
            _ => return None,
        };
        Some(PortConfig::new(baud, parity, stop_bits).with_data_bits(data_bits))
    }

    /// The short form without the baud rate (`8E1`), as [`fmt::Display`] writes it.
    pub fn framing(&self) -> impl fmt::Display {
        Framing(*self)
    }

    /// Bits on the wire per character: start + data + parity + stop.
    pub const fn bits_per_char(&self) -> u32 {
        let parity = match self.parity {
            Parity::None => 0,
            Parity::Even | Parity::Odd => 1,
        };
        1 + self.data_bits.number() as u32 + parity + self.stop_bits.number() as u32
    }

    /// Time one character takes on the wire, in nanoseconds (exact for the usual rates).
    pub const fn char_time_ns(&self) -> u64 {
        (self.bits_per_char() as u64 * 1_000_000_000) / self.baud as u64
    }
}

/// [`PortConfig::framing`].
struct Framing(PortConfig);

impl fmt::Display for Framing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let PortConfig {
            data_bits,
            parity,
            stop_bits,
            ..
        } = self.0;
        write!(
            f,
            "{}{}{}",
            data_bits.number(),
            parity.letter(),
            stop_bits.number()
        )
    }
}

/// `19200 8E1`.
impl fmt::Display for PortConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.baud, self.framing())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn character_times_follow_the_frame_format() {
        assert_eq!(PortConfig::MODBUS_DEFAULT.bits_per_char(), 11);
        assert_eq!(PortConfig::HPR.bits_per_char(), 10);
        // 11 bits at 19200 baud = 572.9 us.
        assert_eq!(PortConfig::MODBUS_DEFAULT.char_time_ns(), 572_916);
        assert_eq!(PortConfig::HPR.char_time_ns(), 520_833);
        // 7E1 is as long as 8N1: 10 bits.
        let seven_even = PortConfig::MODBUS_DEFAULT.with_data_bits(DataBits::Seven);
        assert_eq!(seven_even.bits_per_char(), 10);
    }

    #[test]
    fn the_short_form_round_trips() {
        extern crate std;
        use std::string::ToString;
        for data in ["7", "8"] {
            for parity in ["N", "E", "O"] {
                for stop in ["1", "2"] {
                    let text = [data, parity, stop].concat();
                    let port = PortConfig::from_framing(4800, &text).unwrap();
                    assert_eq!(port.to_string(), ["4800 ", &text].concat());
                    assert_eq!(port.framing().to_string(), text);
                }
            }
        }
        assert_eq!(
            PortConfig::from_framing(19_200, "8e1"),
            Some(PortConfig::MODBUS_DEFAULT)
        );
        for bad in ["", "8E", "8E1 ", "6N1", "9N1", "8X1", "8N3", "78N1"] {
            assert_eq!(PortConfig::from_framing(9600, bad), None, "{bad:?}");
        }
    }
}
