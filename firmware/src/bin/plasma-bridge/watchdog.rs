//! The independent watchdog, fed only while every registered task reports progress
//! (`plasma_firmware::watchdog::ProgressMonitor`), and the heartbeat LED.

use core::cell::RefCell;

use defmt::error;
use embassy_stm32::gpio::Output;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_stm32::{Peri, pac, peripherals};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_time::Timer;
use plasma_firmware::time::Duration;
use plasma_firmware::watchdog::{ProgressMonitor, TaskId};

use crate::clock::now;
use crate::pins::drive_safe_state;

/// One slot per task that matters: I/O, bridge (PS and CNC), settings, heartbeat.
const TASKS: usize = 6;

static MONITOR: Mutex<CriticalSectionRawMutex, RefCell<ProgressMonitor<TASKS>>> =
    Mutex::new(RefCell::new(ProgressMonitor::new()));

/// Registers a task that must report at least every `deadline`.
pub fn register(name: &'static str, deadline: Duration) -> TaskId {
    let registered = MONITOR.lock(|m| m.borrow_mut().register(name, deadline, now()));
    match registered {
        Ok(id) => id,
        // A build-time mistake (more tasks than slots): fail at boot, in safe state.
        Err(_) => defmt::panic!("watchdog: no slot for task '{}'", name),
    }
}

/// The task made progress.
pub fn report(task: TaskId) {
    MONITOR.lock(|m| m.borrow_mut().report(task, now()));
}

/// How long the IWDG runs without a feed before it resets the MCU.
const IWDG_TIMEOUT_US: u32 = 1_000_000;
const FEED_PERIOD_MS: u64 = 100;

#[embassy_executor::task]
pub async fn watchdog(iwdg: Peri<'static, peripherals::IWDG>) {
    // Halting the core in a debugger must not reset it.
    pac::DBGMCU.apb1fzr1().modify(|w| w.set_iwdg(true));
    let mut dog = IndependentWatchdog::new(iwdg, IWDG_TIMEOUT_US);
    dog.unleash();
    loop {
        let feed = MONITOR.lock(|m| m.borrow_mut().should_feed(now()));
        if feed {
            dog.pet();
        } else {
            // Stop feeding for good; the outputs go safe now rather than when the IWDG
            // fires up to a second later.
            drive_safe_state();
            if let Some(stall) = MONITOR.lock(|m| m.borrow().stalled()) {
                error!(
                    "task '{}' silent for {} ms (limit {} ms): watchdog reset follows",
                    stall.name,
                    stall.silent_for.as_millis(),
                    stall.deadline.as_millis()
                );
            }
            loop {
                Timer::after_secs(1).await;
            }
        }
        Timer::after_millis(FEED_PERIOD_MS).await;
    }
}

#[embassy_executor::task]
pub async fn heartbeat(mut led: Output<'static>, progress: TaskId) {
    loop {
        led.toggle();
        report(progress);
        Timer::after_millis(500).await;
    }
}
