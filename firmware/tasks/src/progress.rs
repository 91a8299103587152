//! Task progress for the watchdog (`plasma_firmware::watchdog::ProgressMonitor`), and the
//! heartbeat LED. The board's watchdog task asks [`should_feed`] before every feed.

use core::cell::RefCell;

use defmt::error;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_time::Timer;
use plasma_firmware::watchdog::{ProgressMonitor, TaskId};
use plasma_protocol::time::Duration;

use crate::board::Led;
use crate::clock::now;
use crate::safe_state::trip_fail_safe;

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

/// Whether every task reported in time. When one did not, the outputs go safe at once (not
/// when the watchdog fires up to a second later) and stay safe (the fail-safe latch refuses
/// the I/O task's writes from then on), and the stalled task is logged: the caller must then
/// stop feeding for good.
pub fn should_feed() -> bool {
    if MONITOR.lock(|m| m.borrow_mut().should_feed(now())) {
        return true;
    }
    trip_fail_safe();
    if let Some(stall) = MONITOR.lock(|m| m.borrow().stalled()) {
        error!(
            "task '{}' silent for {} ms (limit {} ms): watchdog reset follows",
            stall.name,
            stall.silent_for.as_millis(),
            stall.deadline.as_millis()
        );
    }
    false
}

/// Toggles the LED every 500 ms: a blinking LED says thread mode runs. The body of the
/// board's heartbeat task.
pub async fn heartbeat(mut led: impl Led, progress: TaskId) {
    loop {
        led.toggle();
        report(progress);
        Timer::after_millis(500).await;
    }
}
