//! Measurements for the README, made by the emulated board (they cost a few words of RAM and
//! are logged from thread mode, never from the START path).
//!
//! - TORCH_ON edge → START: the EXTI handler of TORCH_ON stamps the edge; the first START
//!   change after it reports the cycles the core was *busy* in between (elapsed minus time in
//!   WFI), so a debounce wait does not count. Under `-icount shift=0` QEMU runs one
//!   instruction per virtual nanosecond: busy nanoseconds are instructions.
//! - Idle: every 10 s of guest time, the share of time in WFI and the wake-ups.
//!
//! Lines start with `emu-probe:`; `pbtool emu --measure` reads them.

use core::cell::Cell;

use critical_section::Mutex;
use defmt::info;

use crate::executor::{SleepStats, sleep_stats};
use crate::time_driver::{cycles_to_ns, now_cycles};

/// An edge seen and not yet followed by a START change: (when, cycles asleep so far).
static EDGE: Mutex<Cell<Option<(u64, u64)>>> = Mutex::new(Cell::new(None));
/// A finished measurement not yet logged: (busy, elapsed) cycles, START level.
static RESULT: Mutex<Cell<Option<(u64, u64, bool)>>> = Mutex::new(Cell::new(None));

/// From the TORCH_ON EXTI handler.
pub fn torch_on_edge() {
    let now = now_cycles();
    let asleep = sleep_stats().asleep;
    critical_section::with(|cs| EDGE.borrow(cs).set(Some((now, asleep))));
}

/// From the output driver, when START changed.
pub fn start_changed(level: bool) {
    let now = now_cycles();
    let asleep = sleep_stats().asleep;
    critical_section::with(|cs| {
        if let Some((edge, asleep_at_edge)) = EDGE.borrow(cs).take() {
            let elapsed = now - edge;
            let busy = elapsed.saturating_sub(asleep - asleep_at_edge);
            RESULT.borrow(cs).set(Some((busy, elapsed, level)));
        }
    });
}

/// Guest time between idle reports.
const IDLE_WINDOW_CYCLES: u64 = 10 * crate::rcc::SYSCLK_HZ as u64;

/// The start of the current idle window.
static WINDOW: Mutex<Cell<Option<(u64, SleepStats)>>> = Mutex::new(Cell::new(None));

/// Thread mode, after every executor poll: logs what was measured.
pub fn report() {
    if let Some((busy, elapsed, level)) = critical_section::with(|cs| RESULT.borrow(cs).take()) {
        info!(
            "emu-probe: TORCH_ON edge to START {=str}: {=u64} ns busy, {=u64} ns elapsed",
            if level { "on" } else { "off" },
            cycles_to_ns(busy),
            cycles_to_ns(elapsed)
        );
    }
    let now = now_cycles();
    let stats = sleep_stats();
    let Some((start, at_start)) = critical_section::with(|cs| WINDOW.borrow(cs).get()) else {
        critical_section::with(|cs| WINDOW.borrow(cs).set(Some((now, stats))));
        return;
    };
    if now - start < IDLE_WINDOW_CYCLES {
        return;
    }
    info!(
        "emu-probe: idle {=u64} ns asleep of {=u64} ns, {=u32} wake-ups, {=u32} polls",
        cycles_to_ns(stats.asleep - at_start.asleep),
        cycles_to_ns(now - start),
        stats.wake_ups.wrapping_sub(at_start.wake_ups),
        stats.polls.wrapping_sub(at_start.polls)
    );
    critical_section::with(|cs| WINDOW.borrow(cs).set(Some((now, stats))));
}
