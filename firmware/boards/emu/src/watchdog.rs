//! The watchdog task. QEMU models no IWDG, so the emulated board does in software what the
//! IWDG does on the Nucleo: once a task stops reporting progress (`plasma_tasks::progress`, the
//! same check as the Nucleo's), the outputs go safe at once and, after the IWDG's time-out,
//! the core resets.
//!
//! Like the IWDG, it must not depend on the tasks it watches: it runs on its own interrupt
//! executor above every task (`main.rs`), so a task that hangs in thread mode or in the I/O
//! executor cannot keep it from judging.
//!
//! One difference: a guest's clock can jump (by up to one SysTick period, 210 ms) when the
//! host stops QEMU for a while, and then every task looks late at once. So the check is only
//! made when this task itself woke on time; after a jump the tasks get one feed period to
//! report. Nothing but a jump or an interrupt handler at its own priority can make it late.

use defmt::warn;
use embassy_time::{Duration, Instant, Timer};

use plasma_firmware::safe_state::ResetFlags;
use plasma_tasks::progress::should_feed;

/// The IWDG time-out of the Nucleo image.
const TIMEOUT: Duration = Duration::from_millis(1000);
const FEED_PERIOD: Duration = Duration::from_millis(100);

#[embassy_executor::task]
pub async fn watchdog() {
    loop {
        let due = Instant::now() + FEED_PERIOD;
        Timer::at(due).await;
        let late = Instant::now().saturating_duration_since(due);
        if late > FEED_PERIOD {
            warn!(
                "guest time jumped {=u64} ms (host busy): progress not judged this round",
                late.as_millis()
            );
            continue;
        }
        if !should_feed() {
            break;
        }
    }
    Timer::after(TIMEOUT).await;
    // The next boot reports what the IWDG's reset would: `watchdog`.
    crate::reset_flags::arm(ResetFlags::INDEPENDENT_WATCHDOG);
    cortex_m::peripheral::SCB::sys_reset()
}
