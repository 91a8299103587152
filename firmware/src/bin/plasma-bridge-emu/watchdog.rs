//! The watchdog task. QEMU models no IWDG, so the emulated board does in software what the
//! IWDG does on the Nucleo: once a task stops reporting progress (`tasks::progress`, the
//! same check as the Nucleo's), the outputs go safe at once and, after the IWDG's time-out,
//! the core resets.

use embassy_time::Timer;

use crate::tasks::progress::should_feed;

/// The IWDG time-out of the Nucleo image.
const TIMEOUT_MS: u64 = 1000;
const FEED_PERIOD_MS: u64 = 100;

#[embassy_executor::task]
pub async fn watchdog() {
    while should_feed() {
        Timer::after_millis(FEED_PERIOD_MS).await;
    }
    Timer::after_millis(TIMEOUT_MS).await;
    cortex_m::peripheral::SCB::sys_reset()
}
