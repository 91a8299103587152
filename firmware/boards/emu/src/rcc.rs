//! Clocks, by register: HSI16 → PLL → 80 MHz SYSCLK, as on the Nucleo image.
//!
//! QEMU models the RCC with its ready bits and feeds SYSCLK to the Cortex-M clock (so SysTick
//! runs at 80 MHz), but not FLASH or PWR: the wait states are written for a real chip and not
//! read back, which is what makes embassy-stm32's `init` hang there (docs/developers.md).

use stm32_metapac::rcc::vals::{Pllm, Plln, Pllr, Pllsrc, Sw, Usartsel};
use stm32_metapac::{FLASH, RCC};

/// SYSCLK = HCLK = PCLK1 = PCLK2 after [`init`], as [`init`] means to set it.
pub const SYSCLK_HZ: u32 = 80_000_000;
/// The CNC USART's kernel clock after [`init`]: HSI16, as on the Nucleo image (80 MHz cannot
/// make 1200 baud). The UARTs program BRR from the clock QEMU's RCC reports
/// (`plasma_tasks::clock_tree`), so the tests check that arithmetic too; this checks at build
/// time that every baud rate `CONFIG cnc_baud` accepts runs at the intended clock.
pub const CNC_USART_CLOCK_HZ: u32 = 16_000_000;
const _: () = assert!(plasma_tasks::uart::runs_every_baud(
    CNC_USART_CLOCK_HZ,
    &plasma_firmware::settings::CNC_BAUDS
));

/// HSI16 / 2 = 8 MHz PLL input, × 20 = 160 MHz VCO, / 2 = 80 MHz; GPIO A-C, SYSCFG (EXTI
/// routing), USART1 and USART2 clocked.
pub fn init() {
    RCC.cr().modify(|w| w.set_hsion(true));
    while !RCC.cr().read().hsirdy() {}

    RCC.pllcfgr().write(|w| {
        w.set_pllsrc(Pllsrc::HSI);
        w.set_pllm(Pllm::DIV2);
        w.set_plln(Plln::MUL20);
        w.set_pllr(Pllr::DIV2);
        w.set_pllren(true);
    });
    RCC.cr().modify(|w| w.set_pllon(true));
    while !RCC.cr().read().pllrdy() {}

    // 4 wait states at 80 MHz (RM0351 table 12); QEMU ignores the write.
    FLASH.acr().modify(|w| w.set_latency(4));
    RCC.cfgr().modify(|w| w.set_sw(Sw::PLL1_R));
    while RCC.cfgr().read().sws() != Sw::PLL1_R {}

    RCC.ahb2enr().modify(|w| {
        w.set_gpioaen(true);
        w.set_gpioben(true);
        w.set_gpiocen(true);
    });
    RCC.apb2enr().modify(|w| {
        w.set_syscfgen(true);
        w.set_usart1en(true);
    });
    RCC.apb1enr1().modify(|w| w.set_usart2en(true));
    RCC.ccipr().modify(|w| w.set_usart2sel(Usartsel::HSI));
}
