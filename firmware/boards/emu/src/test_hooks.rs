//! Test images only (feature `test-hooks`, which only the QEMU harness's image build turns on;
//! `cargo emu-fw` and the Nucleo image are built without it): a way to stall a task on
//! purpose, to test the watchdog's fail-safe end to end.
//!
//! Pulling `plasma_firmware::pins::TEST_STALL` (PC13, the user button) low stalls thread
//! mode for good: the bridge, settings and heartbeat tasks stop reporting progress while the
//! I/O task (its own interrupt executor) runs on, exactly the case the fail-safe latch exists
//! for. The pin's EXTI line (13, on the inputs' EXTI15_10 interrupt) wakes the hook, so it
//! costs no wake-ups while unused (the idle figures stay those of the plain image).

use defmt::warn;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use plasma_firmware::pins::TEST_STALL;
use stm32_metapac::gpio::vals::{Moder, Pupdr};

use crate::gpio::gpio;

static REQUESTED: Signal<CriticalSectionRawMutex, ()> = Signal::new();

/// From the EXTI interrupt: `pending` lines were cleared; a stall is asked for if the hook's
/// line is among them.
pub fn on_edges(pending: u32) {
    if pending & TEST_STALL.mask() != 0 {
        REQUESTED.signal(());
    }
}

/// Waits for the stall pin's edge; then spins in thread mode for ever.
#[embassy_executor::task]
pub async fn stall_on_request() {
    let (port, n) = (gpio(TEST_STALL.port), TEST_STALL.number as usize);
    port.pupdr().modify(|w| w.set_pupdr(n, Pupdr::PULL_UP));
    port.moder().modify(|w| w.set_moder(n, Moder::INPUT));
    plasma_tasks::chip::arm_edge_line(TEST_STALL);
    REQUESTED.wait().await;
    warn!("test hook: thread mode stalls now");
    loop {
        cortex_m::asm::nop();
    }
}
