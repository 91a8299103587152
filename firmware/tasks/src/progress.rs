//! Task progress for the watchdog (`plasma_firmware::platform::watchdog::ProgressMonitor`), the stall
//! judge that feeds the board's watchdog while every task reports ([`judge`]), and the
//! heartbeat LED.

use core::cell::RefCell;

use defmt::{error, warn};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_time::Timer;
use plasma_firmware::platform::watchdog::{ProgressMonitor, TaskId};
use plasma_protocol::time::Duration;

use crate::board::{Led, Watchdog};
use crate::clock::now;
use crate::safe_state::trip_fail_safe;

/// One slot per task that matters: I/O, bridge (PS and CNC), settings, history, heartbeat.
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

/// How often the judge looks at the tasks and feeds the watchdog.
const FEED_PERIOD: embassy_time::Duration = embassy_time::Duration::from_millis(100);

/// The stall judge, the body of the board's judge task (on its own executor above every task
/// it judges: `crate::layout`): feeds `watchdog` while [`should_feed`]; when a task stalls,
/// the outputs go safe at once and `watchdog` expires.
///
/// A round in which the judge itself woke more than a feed period late is not judged: every
/// task looks late after a jump of the clock (the emulated board's guest clock jumps when the
/// host stops QEMU), so the tasks get one more period. Only a jump, or interrupts held off
/// that long, make the judge late; a task that really stalled is caught a round later.
pub async fn judge(mut watchdog: impl Watchdog) {
    loop {
        watchdog.feed();
        let due = embassy_time::Instant::now() + FEED_PERIOD;
        Timer::at(due).await;
        let late = embassy_time::Instant::now().saturating_duration_since(due);
        if late > FEED_PERIOD {
            // In microseconds (the tick): `as_millis` is a 64-bit division, 1 KB of flash.
            warn!(
                "the stall judge woke {=u64} us late: progress not judged this round",
                late.as_micros()
            );
            continue;
        }
        if !should_feed() {
            break;
        }
    }
    watchdog.expire().await
}
