//! The independent watchdog (IWDG), fed only while every task reports progress
//! (`plasma_tasks::progress`).

use embassy_stm32::wdg::IndependentWatchdog;
use embassy_stm32::{Peri, pac, peripherals};
use embassy_time::Timer;

use plasma_tasks::progress::should_feed;

/// How long the IWDG runs without a feed before it resets the MCU.
const IWDG_TIMEOUT_US: u32 = 1_000_000;
const FEED_PERIOD_MS: u64 = 100;

#[embassy_executor::task]
pub async fn watchdog(iwdg: Peri<'static, peripherals::IWDG>) {
    // Halting the core in a debugger must not reset it.
    pac::DBGMCU.apb1fzr1().modify(|w| w.set_iwdg(true));
    let mut dog = IndependentWatchdog::new(iwdg, IWDG_TIMEOUT_US);
    dog.unleash();
    while should_feed() {
        dog.pet();
        Timer::after_millis(FEED_PERIOD_MS).await;
    }
    // No more feeds: the IWDG resets the MCU within IWDG_TIMEOUT_US.
    loop {
        Timer::after_secs(1).await;
    }
}
