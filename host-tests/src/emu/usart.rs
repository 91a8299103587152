//! The emulated board's USARTs as the harness reads them through qtest: where their registers
//! are (QEMU's STM32L4x5 map, the same as the STM32L476's) and the framing they describe.
//!
//! QEMU's socket carries bytes, not bits: the framing the firmware set is read from the
//! registers, so the harness can model a mismatch between the board and the other end.

use plasma_protocol::serial::{DataBits, Parity, PortConfig, StopBits};

use super::error::Result;
use super::qtest::Qtest;

/// The PS USART's kernel clock on the emulated board (SYSCLK, as on the Nucleo image), to
/// turn BRR into a baud rate.
pub const KERNEL_CLOCK_HZ: u32 = 80_000_000;
/// The CNC USART's kernel clock on the emulated board (HSI16, as on the Nucleo image: 80 MHz
/// cannot make 1200 baud).
pub const CNC_KERNEL_CLOCK_HZ: u32 = 16_000_000;

/// One USART's register block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Usart {
    base: u64,
}

impl Usart {
    /// USART1, the PS port (QEMU's serial0).
    pub const PS: Usart = Usart { base: 0x4001_3800 };
    /// USART2, the CNC port (QEMU's serial1).
    pub const CNC: Usart = Usart { base: 0x4000_4400 };

    /// Control register 1.
    pub const fn cr1(self) -> u64 {
        self.base
    }

    /// Control register 2.
    pub const fn cr2(self) -> u64 {
        self.base + 0x04
    }

    /// Baud rate register.
    pub const fn brr(self) -> u64 {
        self.base + 0x0C
    }

    /// The framing the firmware set, read now (see [`port_from_registers`]); `Ok(None)` while
    /// the USART is off or at a word length the bridge never sets.
    pub fn framing(
        self,
        qtest: &Qtest,
        clock_hz: Option<u32>,
        nominal_baud: u32,
    ) -> Result<Option<PortConfig>> {
        let (cr1, cr2, brr) = (
            qtest.readl(self.cr1())?,
            qtest.readl(self.cr2())?,
            qtest.readl(self.brr())?,
        );
        Ok(port_from_registers(cr1, cr2, brr, clock_hz, nominal_baud))
    }
}

/// The port settings a USART's registers describe: `None` while the USART is disabled or set
/// to anything but 7 or 8 data bits. A baud rate within 2 % of `nominal_baud` (the unit's; BRR
/// rounds, and a UART tolerates that much) is taken as `nominal_baud`; without the clock the
/// baud rate is taken as `nominal_baud`.
pub fn port_from_registers(
    cr1: u32,
    cr2: u32,
    brr: u32,
    clock_hz: Option<u32>,
    nominal_baud: u32,
) -> Option<PortConfig> {
    const UE: u32 = 1 << 0;
    const PS: u32 = 1 << 9;
    const PCE: u32 = 1 << 10;
    const M0: u32 = 1 << 12;
    const M1: u32 = 1 << 28;
    const OVER8: u32 = 1 << 15;
    if cr1 & UE == 0 {
        return None;
    }
    // Word length counts the parity bit: 8 data bits are M=00 without parity, M=01 with; 7
    // data bits M=10 without, M=00 with.
    let word_bits = match (cr1 & M1 != 0, cr1 & M0 != 0) {
        (false, false) => 8,
        (false, true) => 9,
        (true, false) => 7,
        (true, true) => return None,
    };
    let parity = match (cr1 & PCE != 0, cr1 & PS != 0) {
        (false, _) => Parity::None,
        (true, false) => Parity::Even,
        (true, true) => Parity::Odd,
    };
    let data_bits = match word_bits - u32::from(parity != Parity::None) {
        7 => DataBits::Seven,
        8 => DataBits::Eight,
        _ => return None,
    };
    let stop_bits = match (cr2 >> 12) & 0b11 {
        0b00 => StopBits::One,
        0b10 => StopBits::Two,
        // 0.5 and 1.5 stop bits: nothing the bridge uses; read as one.
        _ => StopBits::One,
    };
    let baud = match clock_hz {
        Some(clock) if brr != 0 => {
            // OVER8: BRR[3:0] holds USARTDIV[3:0] shifted right by one.
            let div = if cr1 & OVER8 != 0 {
                (brr & !0xF) | ((brr & 0x7) << 1)
            } else {
                brr
            };
            let over = if cr1 & OVER8 != 0 { 2 } else { 1 };
            let baud = over * clock / div;
            if baud.abs_diff(nominal_baud).saturating_mul(50) <= nominal_baud {
                nominal_baud
            } else {
                baud
            }
        }
        _ => nominal_baud,
    };
    Some(PortConfig::new(baud, parity, stop_bits).with_data_bits(data_bits))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registers_give_the_framing() {
        const UE: u32 = 1;
        const PCE: u32 = 1 << 10;
        const PS: u32 = 1 << 9;
        const M0: u32 = 1 << 12;
        let even = port_from_registers(UE | PCE | M0, 0, 0, None, 19_200).unwrap();
        assert_eq!(even, PortConfig::MODBUS_DEFAULT);
        let odd_two = port_from_registers(UE | PCE | PS | M0, 0b10 << 12, 0, None, 19_200);
        assert_eq!(
            odd_two,
            Some(PortConfig::new(19_200, Parity::Odd, StopBits::Two))
        );
        // 8N1 at 80 MHz: BRR = 80e6 / 19200 = 4166, 19203 baud: the unit's 19200 within 2 %.
        let hpr = port_from_registers(UE, 0, 4166, Some(80_000_000), 19_200).unwrap();
        assert_eq!(hpr, PortConfig::HPR);
        // Against a 9600-baud unit it is a mismatch.
        let fast = port_from_registers(UE, 0, 4166, Some(80_000_000), 9600).unwrap();
        assert_eq!(fast.baud, 19_203);
        // 7 data bits: an 8-bit word with parity, a 7-bit word (M1) without.
        const M1: u32 = 1 << 28;
        let seven = |framing| PortConfig::from_framing(19_200, framing);
        assert_eq!(
            port_from_registers(UE | PCE, 0, 0, None, 19_200),
            seven("7E1")
        );
        assert_eq!(
            port_from_registers(UE | M1, 0b10 << 12, 0, None, 19_200),
            seven("7N2")
        );
        // Disabled; a 7-bit word with parity (6 data bits); M=11 (reserved).
        assert_eq!(port_from_registers(PCE | M0, 0, 0, None, 19_200), None);
        assert_eq!(port_from_registers(UE | PCE | M1, 0, 0, None, 19_200), None);
        assert_eq!(port_from_registers(UE | M1 | M0, 0, 0, None, 19_200), None);
    }

    #[test]
    fn the_register_map_is_the_stm32l4s() {
        // RM0351, memory map: USART1 on APB2, USART2 on APB1; CR1, CR2 and BRR at 0, 4, 0xC.
        assert_eq!(Usart::PS.cr1(), 0x4001_3800);
        assert_eq!(Usart::PS.brr(), 0x4001_380C);
        assert_eq!(Usart::CNC.cr2(), 0x4000_4404);
        assert_eq!(Usart::CNC.brr(), 0x4000_440C);
    }
}
