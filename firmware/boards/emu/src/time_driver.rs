//! embassy-time on SysTick, the only timer QEMU's STM32L4 models.
//!
//! SysTick counts SYSCLK cycles down from a period the driver chooses: until the next timer
//! is due, or the counter's longest period (2^24 cycles, 210 ms) when none is sooner. So the
//! core wakes when a timer is due, on time, and otherwise sleeps.
//!
//! The time is the sum of the finished periods *plus the counter*, never a count of
//! interrupts: a count loses time whenever the guest runs late, and an emulated guest runs
//! late whenever the host is busy (docs/developers.md). A period is shortened by
//! restarting the counter (a write to SYST_CVR, which reloads it one cycle later without an
//! interrupt, on the Cortex-M as in QEMU's model); only the cycles between reading the
//! counter and that write are lost, a few per restart.
//!
//! One concession to QEMU: its USART model does not tell its character back-end when RDR has
//! been read, so the next received byte is only fetched when QEMU's main loop runs again for
//! another reason, such as a timer. A tickless guest would then receive one byte per timer
//! (a 5-byte command took 60-115 ms). While bytes arrive ([`keep_receiving`], from the USART
//! interrupt), periods are therefore at most [`PUMP_PERIOD`]: the core (not the executor)
//! wakes every 100 µs, and QEMU fetches up to 10 bytes a millisecond, faster than 115200 baud.
//!
//! Time is kept in SYSCLK cycles ([`now_cycles`], 12.5 ns, used by the measurement probes);
//! embassy-time sees microseconds (`tick-hz-1_000_000`, as on the Nucleo).

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

/// The longest period: SYST_RVR is 24 bits.
const MAX_PERIOD: u32 = 1 << 24;
/// The shortest period, so that a restart always sees the reload (1 µs).
const MIN_PERIOD: u32 = CYCLES_PER_TICK;
/// The longest period while bytes arrive: 100 µs.
const PUMP_PERIOD: u32 = SYSCLK_HZ / 10_000;
/// How long after a received byte periods stay short: 2 ms, several byte times at the
/// slowest baud rate the link uses (9600).
const PUMP_WINDOW: u64 = SYSCLK_HZ as u64 / 500;
/// SYSCLK cycles per embassy-time tick (1 µs).
const CYCLES_PER_TICK: u32 = SYSCLK_HZ / 1_000_000;

struct SysTickDriver {
    /// Cycles at the start of the current period.
    base: Mutex<Cell<u64>>,
    /// Length of the current period (SYST_RVR + 1).
    period: Mutex<Cell<u32>>,
    /// The earliest timer, in cycles (`u64::MAX`: none).
    alarm: Mutex<Cell<u64>>,
    /// Until when periods stay short for a receiving USART, in cycles.
    pump_until: Mutex<Cell<u64>>,
    queue: Mutex<RefCell<Queue>>,
}

embassy_time_driver::time_driver_impl!(static DRIVER: SysTickDriver = SysTickDriver {
    base: Mutex::new(Cell::new(0)),
    period: Mutex::new(Cell::new(MAX_PERIOD)),
    alarm: Mutex::new(Cell::new(u64::MAX)),
    pump_until: Mutex::new(Cell::new(0)),
    queue: Mutex::new(RefCell::new(Queue::new())),
});

/// Starts SysTick on SYSCLK with the longest period, at the highest exception priority (like
/// EXTI), so that timers of the I/O task are served above everything else.
pub fn init(mut syst: SYST, scb: &mut SCB) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(MAX_PERIOD - 1);
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
    let base = DRIVER.base.borrow(cs).get();
    let period = DRIVER.period.borrow(cs).get();
    let mut remaining = SYST::get_current();
    // A wrap the interrupt has not handled yet (interrupts are off here): the pending bit
    // says so, and a counter read after seeing it belongs to the next period, which has the
    // same length (the counter reloads SYST_RVR).
    if SCB::is_pendst_pending() {
        remaining = SYST::get_current();
        base + u64::from(period) + elapsed_in(period, remaining)
    } else {
        base + elapsed_in(period, remaining)
    }
}

/// Cycles since the start of a period of `period` cycles whose counter reads `remaining`.
fn elapsed_in(period: u32, remaining: u32) -> u64 {
    u64::from(period - 1 - remaining.min(period - 1))
}

/// A USART received a byte: keep QEMU fetching the next ones (see the module docs).
pub fn keep_receiving() {
    critical_section::with(|cs| {
        let now = now_cycles_cs(cs);
        DRIVER.pump_until.borrow(cs).set(now + PUMP_WINDOW);
        let period_end = DRIVER.base.borrow(cs).get() + u64::from(DRIVER.period.borrow(cs).get());
        if period_end > now + u64::from(PUMP_PERIOD) {
            DRIVER.restart(cs);
        }
    })
}

/// SYSCLK cycles as nanoseconds (80 MHz: 12.5 ns each).
pub const fn cycles_to_ns(cycles: u64) -> u64 {
    cycles * 1_000_000_000 / SYSCLK_HZ as u64
}

impl SysTickDriver {
    /// Ends the current period now and starts one that ends at the alarm (or after the
    /// longest period, or the pump's while a USART receives).
    fn restart(&self, cs: CriticalSection) {
        let now = now_cycles_cs(cs);
        let longest = if now < self.pump_until.borrow(cs).get() {
            PUMP_PERIOD
        } else {
            MAX_PERIOD
        };
        let until_alarm = self.alarm.borrow(cs).get().saturating_sub(now);
        let period = u32::try_from(until_alarm)
            .unwrap_or(MAX_PERIOD)
            .clamp(MIN_PERIOD, longest);
        // SAFETY: SysTick belongs to this driver; interrupts are off.
        let syst = unsafe { &*SYST::PTR };
        unsafe {
            syst.rvr.write(period - 1);
            syst.cvr.write(0);
        }
        // A wrap pending from the old period is already in `now`.
        SCB::clear_pendst();
        // The counter reloads on the next cycle; until then it reads 0, which would look like
        // the end of the new period.
        while SYST::get_current() == 0 {}
        self.base.borrow(cs).set(now + 1);
        self.period.borrow(cs).set(period);
    }

    /// Wakes every timer that is due and keeps the next expiry (always later than now).
    fn fire_due(&self, cs: CriticalSection) {
        let now_ticks = now_cycles_cs(cs) / u64::from(CYCLES_PER_TICK);
        let next = self
            .queue
            .borrow(cs)
            .borrow_mut()
            .next_expiration(now_ticks);
        let next_cycles = next.saturating_mul(u64::from(CYCLES_PER_TICK));
        self.alarm.borrow(cs).set(next_cycles);
    }
}

impl Driver for SysTickDriver {
    fn now(&self) -> u64 {
        now_cycles() / u64::from(CYCLES_PER_TICK)
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        critical_section::with(|cs| {
            if self.queue.borrow(cs).borrow_mut().schedule_wake(at, waker) {
                let before = self.alarm.borrow(cs).get();
                self.fire_due(cs);
                // Only an earlier alarm needs a shorter period; a later one is taken up at
                // the next wrap.
                if self.alarm.borrow(cs).get() < before {
                    self.restart(cs);
                }
            }
        })
    }
}

#[exception]
fn SysTick() {
    critical_section::with(|cs| {
        let base = DRIVER.base.borrow(cs);
        base.set(base.get() + u64::from(DRIVER.period.borrow(cs).get()));
        DRIVER.fire_due(cs);
        DRIVER.restart(cs);
    });
}
