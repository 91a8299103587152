//! The thread-mode executor, with sleep accounting.
//!
//! The Nucleo image sleeps with embassy's `Executor` (WFE). Here the same raw executor sleeps
//! with WFI *with interrupts masked*, so the time in WFI is measured before any interrupt
//! handler runs: time asleep is exactly the time the core did nothing, and under QEMU's
//! `-icount shift=0` the rest (elapsed − asleep) is the number of instructions executed. The
//! wake-up request of the executor is an otherwise unused interrupt (UART5): pending it wakes
//! WFI, and its handler marks that there is work.

use core::cell::Cell;
use core::sync::atomic::{AtomicBool, Ordering};

use critical_section::Mutex;
use embassy_executor::{Spawner, raw};
use stm32_metapac::{Interrupt, interrupt};

use crate::time_driver::now_cycles;

/// The interrupt that wakes the thread executor (embassy's `__pender` pends it).
const WAKE_IRQ: Interrupt = Interrupt::UART5;

/// Set by the wake interrupt: a task was woken, poll again before sleeping.
static WORK: AtomicBool = AtomicBool::new(false);

#[interrupt]
fn UART5() {
    WORK.store(true, Ordering::Release);
}

/// Sleep statistics since boot, in SYSCLK cycles.
#[derive(Clone, Copy, Default)]
pub struct SleepStats {
    /// Cycles spent in WFI.
    pub asleep: u64,
    /// Times the core left WFI.
    pub wake_ups: u32,
    /// Times the executor polled its tasks.
    pub polls: u32,
}

static STATS: Mutex<Cell<SleepStats>> = Mutex::new(Cell::new(SleepStats {
    asleep: 0,
    wake_ups: 0,
    polls: 0,
}));

/// The statistics so far.
pub fn sleep_stats() -> SleepStats {
    critical_section::with(|cs| STATS.borrow(cs).get())
}

/// Runs the executor forever; `idle_work` runs in thread mode after every poll (the
/// measurement reports).
pub fn run(init: impl FnOnce(Spawner), mut idle_work: impl FnMut()) -> ! {
    static EXECUTOR: static_cell::StaticCell<raw::Executor> = static_cell::StaticCell::new();
    let executor: &'static raw::Executor =
        EXECUTOR.init(raw::Executor::new(WAKE_IRQ as usize as *mut ()));
    // SAFETY: the wake interrupt's handler only touches an atomic.
    unsafe {
        cortex_m::peripheral::NVIC::unmask(WAKE_IRQ);
    }
    init(executor.spawner());
    WORK.store(true, Ordering::Release);
    loop {
        // Poll only when a task was woken: a SysTick wrap with no timer due wakes the core
        // but not the executor.
        if WORK.swap(false, Ordering::AcqRel) {
            // SAFETY: the executor lives for ever and is polled from thread mode only.
            unsafe { executor.poll() };
            critical_section::with(|cs| {
                let stats = STATS.borrow(cs);
                let mut counted = stats.get();
                counted.polls = counted.polls.wrapping_add(1);
                stats.set(counted);
            });
            idle_work();
        }
        critical_section::with(|cs| {
            // A wake-up during the poll already ran its handler: poll again at once. One after
            // this check pends the interrupt, which ends WFI even though it is masked.
            if WORK.load(Ordering::Acquire) {
                return;
            }
            let fell_asleep = now_cycles();
            cortex_m::asm::wfi();
            let slept = now_cycles() - fell_asleep;
            let stats = STATS.borrow(cs);
            let mut counted = stats.get();
            counted.asleep += slept;
            counted.wake_ups = counted.wake_ups.wrapping_add(1);
            stats.set(counted);
        });
        // Interrupts on again: whatever ended WFI is handled here.
    }
}
