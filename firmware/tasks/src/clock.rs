//! embassy-time as the library's clock.

use core::future::Future;

use plasma_firmware::platform::runner::Clock;
use plasma_protocol::time::Instant;

/// Now, in the library's microseconds (embassy-time runs at 1 MHz: tick-hz-1_000_000).
pub fn now() -> Instant {
    Instant::from_micros(embassy_time::Instant::now().as_micros())
}

/// The library's instant as an embassy-time instant.
pub fn embassy_instant(at: Instant) -> embassy_time::Instant {
    embassy_time::Instant::from_micros(at.as_micros())
}

/// [`Clock`] on embassy-time.
pub struct EmbassyClock;

impl Clock for EmbassyClock {
    fn now(&self) -> Instant {
        now()
    }

    fn sleep_until(&self, at: Instant) -> impl Future<Output = ()> {
        embassy_time::Timer::at(embassy_instant(at))
    }
}
