//! What stands for the IWDG, which QEMU does not model: once the stall judge
//! (`plasma_tasks::progress::judge`, on the executor and at the priority the Nucleo runs it,
//! `plasma_tasks::layout`) stops feeding, the core resets after the IWDG's time-out, and the
//! next boot says `watchdog` as the Nucleo's would. The judge has already made the outputs safe.

use embassy_time::{Duration, Timer};

use plasma_firmware::platform::safe_state::ResetFlags;

/// The IWDG time-out of the Nucleo image.
const TIMEOUT: Duration = Duration::from_millis(1000);

/// The software watchdog.
pub struct SoftWatchdog;

impl plasma_tasks::board::Watchdog for SoftWatchdog {
    /// Nothing to feed: only the judge's decision to stop counts.
    fn feed(&mut self) {}

    async fn expire(self) {
        Timer::after(TIMEOUT).await;
        crate::reset_flags::arm(ResetFlags::INDEPENDENT_WATCHDOG);
        cortex_m::peripheral::SCB::sys_reset()
    }
}
