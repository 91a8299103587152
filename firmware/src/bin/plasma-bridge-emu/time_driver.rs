//! embassy-time on SysTick, the only timer QEMU's STM32L4 models.
//!
//! SysTick counts SYSCLK down through a fixed 1 ms period and interrupts at every wrap. The
//! time is the wrap count *plus the counter*, never a count of interrupts: a tick count loses
//! time whenever the guest runs late, and an emulated guest runs late whenever the host is
//! busy (../shared/EMULATION.md). The wrap interrupt also fires due alarms, so a timer is at
//! most one period late; the executor is woken only when a timer is due.
//!
//! Internally time is kept in SYSCLK cycles ([`now_cycles`], 12.5 ns, used by the
//! measurement probes); embassy-time sees microseconds (`tick-hz-1_000_000`, as on the
//! Nucleo).

use core::cell::{Cell, RefCell};
use core::task::Waker;

use cortex_m::peripheral::scb::SystemHandler;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};
use cortex_m_rt::exception;
use critical_section::{CriticalSection, Mutex};
use embassy_time_driver::Driver;
use embassy_time_queue_utils::Queue;

use crate::rcc::SYSCLK_HZ;

/// SYSCLK cycles per wrap: 1 ms.
const PERIOD: u32 = SYSCLK_HZ / 1000;
/// SYSCLK cycles per embassy-time tick (1 µs).
const CYCLES_PER_TICK: u32 = SYSCLK_HZ / 1_000_000;

struct SysTickDriver {
    /// Wraps handled by the interrupt.
    wraps: Mutex<Cell<u64>>,
    /// The earliest alarm, in embassy-time ticks (`u64::MAX`: none).
    alarm: Mutex<Cell<u64>>,
    queue: Mutex<RefCell<Queue>>,
}

embassy_time_driver::time_driver_impl!(static DRIVER: SysTickDriver = SysTickDriver {
    wraps: Mutex::new(Cell::new(0)),
    alarm: Mutex::new(Cell::new(u64::MAX)),
    queue: Mutex::new(RefCell::new(Queue::new())),
});

/// Starts SysTick: SYSCLK, 1 ms period, the highest exception priority (like EXTI), so that
/// timers of the I/O task are served above everything else.
pub fn init(mut syst: SYST, scb: &mut SCB) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(PERIOD - 1);
    syst.clear_current();
    // SAFETY: priority 0 on SysTick breaks no priority-based critical section: this image
    // uses only `critical_section` (interrupts off).
    unsafe { scb.set_priority(SystemHandler::SysTick, 0) };
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Cycles since SysTick started; monotonic.
pub fn now_cycles() -> u64 {
    critical_section::with(now_cycles_cs)
}

fn now_cycles_cs(cs: CriticalSection) -> u64 {
    let wraps = DRIVER.wraps.borrow(cs).get();
    let mut remaining = SYST::get_current();
    // A wrap the interrupt has not handled yet (interrupts are off here): the pending bit
    // says so, and a counter read after seeing it belongs to the new period.
    let pending = SCB::is_pendst_pending();
    let wraps = if pending {
        remaining = SYST::get_current();
        wraps + 1
    } else {
        wraps
    };
    wraps * u64::from(PERIOD) + u64::from(PERIOD - 1 - remaining.min(PERIOD - 1))
}

/// SYSCLK cycles as nanoseconds (80 MHz: 12.5 ns each).
pub const fn cycles_to_ns(cycles: u64) -> u64 {
    cycles * 1_000_000_000 / SYSCLK_HZ as u64
}

impl SysTickDriver {
    /// Wakes every timer that is due and keeps the next expiry (always later than `now`).
    fn arm(&self, cs: CriticalSection, now: u64) {
        let next = self.queue.borrow(cs).borrow_mut().next_expiration(now);
        self.alarm.borrow(cs).set(next);
    }
}

impl Driver for SysTickDriver {
    fn now(&self) -> u64 {
        now_cycles() / u64::from(CYCLES_PER_TICK)
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        critical_section::with(|cs| {
            let changed = self.queue.borrow(cs).borrow_mut().schedule_wake(at, waker);
            if changed {
                let now = now_cycles_cs(cs) / u64::from(CYCLES_PER_TICK);
                self.arm(cs, now);
            }
        })
    }
}

#[exception]
fn SysTick() {
    critical_section::with(|cs| {
        let wraps = DRIVER.wraps.borrow(cs);
        wraps.set(wraps.get() + 1);
        let now = now_cycles_cs(cs) / u64::from(CYCLES_PER_TICK);
        if now >= DRIVER.alarm.borrow(cs).get() {
            DRIVER.arm(cs, now);
        }
    });
}
