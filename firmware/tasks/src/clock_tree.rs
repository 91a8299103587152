//! The clocks the RCC is running, worked out from its registers (RM0351 section 6.4), so that
//! what depends on a frequency (the USARTs' BRR, the fault path's drain delay) follows the
//! clock actually set, not a constant that a clock change would silently falsify. Pure
//! arithmetic over a snapshot of the registers ([`crate::chip::rcc_snapshot`] reads one),
//! tested on the host.

/// The RCC registers the clock tree is read from, as read.
#[derive(Clone, Copy, Debug)]
pub struct RccSnapshot {
    /// RCC_CR: MSIRANGE (bits 7:4), MSIRGSEL (bit 3).
    pub cr: u32,
    /// RCC_CFGR: SWS (bits 3:2), HPRE (7:4), PPRE1 (10:8), PPRE2 (13:11).
    pub cfgr: u32,
    /// RCC_PLLCFGR: PLLSRC (1:0), PLLM (6:4), PLLN (14:8), PLLR (26:25).
    pub pllcfgr: u32,
    /// RCC_CCIPR: USART1SEL (1:0), USART2SEL (3:2).
    pub ccipr: u32,
    /// RCC_CSR: MSISRANGE (11:8), the MSI range after a reset while MSIRGSEL is 0.
    pub csr: u32,
}

/// HSI16.
const HSI_HZ: u32 = 16_000_000;
/// LSE, the 32.768 kHz crystal.
const LSE_HZ: u32 = 32_768;
/// MSI frequency per MSIRANGE value (RM0351 RCC_CR).
const MSI_HZ: [u32; 12] = [
    100_000, 200_000, 400_000, 800_000, 1_000_000, 2_000_000, 4_000_000, 8_000_000, 16_000_000,
    24_000_000, 32_000_000, 48_000_000,
];

/// The USARTs the boards use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UsartClock {
    /// USART1, on APB2.
    Usart1,
    /// USART2, on APB1.
    Usart2,
}

fn field(register: u32, shift: u32, bits: u32) -> u32 {
    (register >> shift) & ((1 << bits) - 1)
}

impl RccSnapshot {
    fn msi_hz(&self) -> Option<u32> {
        let range = if field(self.cr, 3, 1) == 1 {
            field(self.cr, 4, 4)
        } else {
            field(self.csr, 8, 4)
        };
        MSI_HZ.get(range as usize).copied()
    }

    /// SYSCLK; `None` for a source whose frequency the board cannot know (HSE: neither board
    /// fits a crystal) or a reserved register value.
    pub fn sysclk_hz(&self) -> Option<u32> {
        match field(self.cfgr, 2, 2) {
            0b00 => self.msi_hz(),
            0b01 => Some(HSI_HZ),
            0b11 => self.pll_r_hz(),
            _ => None,
        }
    }

    fn pll_r_hz(&self) -> Option<u32> {
        let input = match field(self.pllcfgr, 0, 2) {
            0b01 => self.msi_hz()?,
            0b10 => HSI_HZ,
            _ => return None,
        };
        let m = field(self.pllcfgr, 4, 3) + 1;
        let n = field(self.pllcfgr, 8, 7);
        let r = 2 * (field(self.pllcfgr, 25, 2) + 1);
        // A VCO (input / M × N) beyond u32 is far out of the datasheet (344 MHz at most):
        // `None`, as for a setting that gives no clock. (No u64: its division is 1 KB of
        // flash.)
        let vco = (input / m).checked_mul(n)?;
        Some(vco / r).filter(|&hz| hz > 0)
    }

    /// HCLK: SYSCLK / the AHB prescaler.
    pub fn hclk_hz(&self) -> Option<u32> {
        let hpre = field(self.cfgr, 4, 4);
        let shift = match hpre {
            0..=7 => 0,
            8..=11 => hpre - 7,
            // 1100: /64 ... 1111: /512 (no /32).
            _ => hpre - 6,
        };
        Some(self.sysclk_hz()? >> shift)
    }

    fn pclk_hz(&self, ppre: u32) -> Option<u32> {
        let shift = if ppre < 4 { 0 } else { ppre - 3 };
        Some(self.hclk_hz()? >> shift)
    }

    /// The kernel clock of `usart` (RCC_CCIPR): its APB clock, SYSCLK, HSI16 or LSE.
    pub fn usart_clock_hz(&self, usart: UsartClock) -> Option<u32> {
        let (select, ppre) = match usart {
            UsartClock::Usart1 => (field(self.ccipr, 0, 2), field(self.cfgr, 11, 3)),
            UsartClock::Usart2 => (field(self.ccipr, 2, 2), field(self.cfgr, 8, 3)),
        };
        match select {
            0b00 => self.pclk_hz(ppre),
            0b01 => self.sysclk_hz(),
            0b10 => Some(HSI_HZ),
            _ => Some(LSE_HZ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// After reset: MSI at 4 MHz (MSIRANGE 6, RM0351 RCC_CR reset value 0x63), every
    /// prescaler 1, USARTs on their APB clock.
    const RESET: RccSnapshot = RccSnapshot {
        cr: 0x0000_0063,
        cfgr: 0,
        pllcfgr: 0x0000_1000,
        ccipr: 0,
        csr: 0x0C00_0600,
    };

    /// The boards' clock: HSI16 / 2 × 20 / 2 = 80 MHz on the PLL's R output, SW = SWS = PLL.
    fn eighty_mhz() -> RccSnapshot {
        RccSnapshot {
            cr: RESET.cr | 1 << 8 | 1 << 10 | 1 << 24 | 1 << 25,
            cfgr: 0b11 << 2 | 0b11,
            pllcfgr: 0b10 | 1 << 4 | 20 << 8 | 1 << 24,
            ..RESET
        }
    }

    #[test]
    fn the_boot_clock_is_msi_at_4_mhz() {
        assert_eq!(RESET.sysclk_hz(), Some(4_000_000));
        assert_eq!(RESET.usart_clock_hz(UsartClock::Usart2), Some(4_000_000));
        // MSIRGSEL clear: the range comes from RCC_CSR's MSISRANGE.
        let standby_range = RccSnapshot {
            cr: 0x0000_0061,
            csr: 7 << 8,
            ..RESET
        };
        assert_eq!(standby_range.sysclk_hz(), Some(8_000_000));
    }

    #[test]
    fn the_boards_pll_gives_80_mhz_to_both_usarts() {
        let clocks = eighty_mhz();
        assert_eq!(clocks.sysclk_hz(), Some(80_000_000));
        assert_eq!(clocks.usart_clock_hz(UsartClock::Usart1), Some(80_000_000));
        assert_eq!(clocks.usart_clock_hz(UsartClock::Usart2), Some(80_000_000));
    }

    #[test]
    fn prescalers_and_kernel_clock_choices_apply() {
        let clocks = RccSnapshot {
            // AHB /2 (1000), APB1 /4 (101), APB2 /16 (111).
            cfgr: eighty_mhz().cfgr | 0b1000 << 4 | 0b101 << 8 | 0b111 << 11,
            ..eighty_mhz()
        };
        assert_eq!(clocks.hclk_hz(), Some(40_000_000));
        assert_eq!(clocks.usart_clock_hz(UsartClock::Usart2), Some(10_000_000));
        assert_eq!(clocks.usart_clock_hz(UsartClock::Usart1), Some(2_500_000));
        let ahb_64 = RccSnapshot {
            cfgr: eighty_mhz().cfgr | 0b1100 << 4,
            ..eighty_mhz()
        };
        assert_eq!(ahb_64.hclk_hz(), Some(1_250_000));
        let chosen = RccSnapshot {
            ccipr: 0b01 | 0b10 << 2,
            ..clocks
        };
        assert_eq!(chosen.usart_clock_hz(UsartClock::Usart1), Some(80_000_000));
        assert_eq!(chosen.usart_clock_hz(UsartClock::Usart2), Some(HSI_HZ));
        let lse = RccSnapshot {
            ccipr: 0b11 << 2,
            ..clocks
        };
        assert_eq!(lse.usart_clock_hz(UsartClock::Usart2), Some(LSE_HZ));
    }

    #[test]
    fn an_unknown_source_gives_no_frequency() {
        let hse = RccSnapshot {
            cfgr: 0b10 << 2,
            ..RESET
        };
        assert_eq!(hse.sysclk_hz(), None);
        assert_eq!(hse.usart_clock_hz(UsartClock::Usart1), None);
        let pll_from_hse = RccSnapshot {
            pllcfgr: eighty_mhz().pllcfgr | 0b11,
            ..eighty_mhz()
        };
        assert_eq!(pll_from_hse.sysclk_hz(), None);
        let reserved_msi = RccSnapshot {
            cr: 0x0000_00F9,
            ..RESET
        };
        assert_eq!(reserved_msi.sysclk_hz(), None);
    }
}
