//! Serial-port settings the bridge asks the board (or a simulator) to apply.
//!
//! Auto-detection switches between Modbus ASCII (19200 8E1 by default; SYNC units can be set
//! to odd/no parity and 1 or 2 stop bits) and the HPR protocol (19200 8N1).

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

/// Line settings of a UART, always 8 data bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PortConfig {
    /// Bits per second.
    pub baud: u32,
    /// Parity bit.
    pub parity: Parity,
    /// Stop bits.
    pub stop_bits: StopBits,
}

impl PortConfig {
    /// Powermax default: 19200 baud, 8 data bits, even parity, 1 stop bit.
    pub const MODBUS_DEFAULT: PortConfig = PortConfig {
        baud: 19_200,
        parity: Parity::Even,
        stop_bits: StopBits::One,
    };

    /// HPR / MaxPro200: 19200 baud, 8N1.
    pub const HPR: PortConfig = PortConfig {
        baud: 19_200,
        parity: Parity::None,
        stop_bits: StopBits::One,
    };

    /// Bits on the wire per character: start + 8 data + parity + stop.
    pub const fn bits_per_char(&self) -> u32 {
        let parity = match self.parity {
            Parity::None => 0,
            Parity::Even | Parity::Odd => 1,
        };
        let stop = match self.stop_bits {
            StopBits::One => 1,
            StopBits::Two => 2,
        };
        1 + 8 + parity + stop
    }

    /// Time one character takes on the wire, in nanoseconds (exact for the usual rates).
    pub const fn char_time_ns(&self) -> u64 {
        (self.bits_per_char() as u64 * 1_000_000_000) / self.baud as u64
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
    }
}
