//! Test images only (feature `test-hooks`, which only the QEMU harness's image build turns on;
//! `cargo emu-fw` and the Nucleo image are built without it): a way to stall a task on
//! purpose, to test the watchdog's fail-safe end to end.
//!
//! Pulling `plasma_firmware::pins::TEST_STALL` (PC13, the user button) low stalls thread
//! mode for good: the bridge, settings and heartbeat tasks stop reporting progress while the
//! I/O task (its own interrupt executor) runs on, exactly the case the fail-safe latch exists
//! for.

use defmt::warn;
use embassy_time::Timer;
use plasma_firmware::pins::TEST_STALL;
use stm32_metapac::gpio::vals::{Idr, Moder, Pupdr};

use crate::gpio::gpio;

/// Polls the stall pin; once it reads low, spins in thread mode for ever.
#[embassy_executor::task]
pub async fn stall_on_request() {
    let (port, n) = (gpio(TEST_STALL.port), TEST_STALL.number as usize);
    port.pupdr().modify(|w| w.set_pupdr(n, Pupdr::PULL_UP));
    port.moder().modify(|w| w.set_moder(n, Moder::INPUT));
    loop {
        if port.idr().read().idr(n) == Idr::LOW {
            warn!("test hook: thread mode stalls now");
            loop {
                cortex_m::asm::nop();
            }
        }
        Timer::after_millis(10).await;
    }
}
