//! The interrupt executor the I/O task runs on, and the interrupt priorities around it.

use embassy_executor::{InterruptExecutor, SendSpawner};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};

/// The I/O task's executor, run from the UART4 interrupt (a vector this board leaves unused).
static EXECUTOR: InterruptExecutor = InterruptExecutor::new();

#[interrupt]
unsafe fn UART4() {
    // SAFETY: called from its own interrupt only, after `start` below.
    unsafe { EXECUTOR.on_interrupt() }
}

/// Priorities, highest first (Cortex-M: lower number = more urgent). EXTI stays at P0 (the
/// HAL's default): its handler only wakes the I/O task. The I/O executor comes next; every
/// serial and flash interrupt goes below it, so the START path never waits behind them.
pub const IO_EXECUTOR_PRIORITY: Priority = Priority::P1;
/// USART1, USART2 and FLASH.
pub const SERIAL_PRIORITY: Priority = Priority::P4;

/// Starts the I/O executor; the I/O task is spawned on what this returns.
pub fn start_io_executor() -> SendSpawner {
    interrupt::UART4.set_priority(IO_EXECUTOR_PRIORITY);
    EXECUTOR.start(interrupt::UART4)
}
