//! Which task runs in which executor at which priority: one definition, every board.
//!
//! Both boards start their tasks through the `start_tasks` function that
//! [`board_tasks!`](crate::board_tasks) declares for them, over the executors and priorities
//! here, so what the emulated board's tests prove (the stall judge outranks a thread mode that
//! spins, START never waits behind serial work) is the Nucleo's arrangement too. A board brings
//! only its thread executor (the Nucleo embassy's, the emulated board one that measures its
//! sleep) and the [`Tasks`] it built.
//!
//! | Context | NVIC priority | Tasks |
//! |---|---|---|
//! | EXTI (inputs), the time base | 0 (reset value) | edges only, alarms |
//! | judge executor (USART3 vector) | [`JUDGE_PRIORITY`] = 0 | the stall judge ([`crate::progress::judge`]) |
//! | I/O executor (UART4 vector) | [`IO_PRIORITY`] = 1 | the I/O task |
//! | USART1, USART2, FLASH | [`SERIAL_PRIORITY`] = 4 | the UART driver, flash |
//! | thread mode | below all | bridge, settings, history, heartbeat |
//!
//! UART4 and USART3 are vectors neither board uses for a peripheral (the pin table puts no
//! UART there); the executors pend them in software.

use embassy_executor::{InterruptExecutor, SendSpawner};
use plasma_firmware::bridge::Bridge;
use plasma_firmware::io::IoConfig;
use plasma_protocol::time::Duration;
use stm32_metapac::{Interrupt, interrupt};

use crate::Board;
use crate::{history, settings};

/// NVIC priorities use the upper nibble (16 levels on the STM32L4).
const fn level(priority: u8) -> u8 {
    priority << 4
}

/// The stall judge: above every task it judges, like the IWDG it stands for.
pub const JUDGE_PRIORITY: u8 = level(0);
/// The I/O task: above every serial and flash interrupt, so START never waits behind them.
pub const IO_PRIORITY: u8 = level(1);
/// The UARTs and the flash.
pub const SERIAL_PRIORITY: u8 = level(4);

const JUDGE_IRQ: Interrupt = Interrupt::USART3;
const IO_IRQ: Interrupt = Interrupt::UART4;
/// The interrupts at [`SERIAL_PRIORITY`].
const SERIAL_IRQS: [Interrupt; 3] = [Interrupt::USART1, Interrupt::USART2, Interrupt::FLASH];

/// Progress deadlines (`plasma_firmware::platform::watchdog::ProgressMonitor`), per task.
pub const IO_DEADLINE: Duration = Duration::from_millis(200);
/// The bridge task's.
pub const BRIDGE_DEADLINE: Duration = Duration::from_millis(500);
/// The settings task's (a page erase runs in it).
pub const SETTINGS_DEADLINE: Duration = Duration::from_secs(1);
/// The history task's (a page erase, or `HISTORY CLEAR`'s eight, runs in it).
pub const HISTORY_DEADLINE: Duration = Duration::from_secs(1);
/// The heartbeat's.
pub const HEARTBEAT_DEADLINE: Duration = Duration::from_secs(1);

static JUDGE_EXECUTOR: InterruptExecutor = InterruptExecutor::new();
static IO_EXECUTOR: InterruptExecutor = InterruptExecutor::new();

#[interrupt]
fn USART3() {
    // SAFETY: called from its own interrupt only, which `judge_executor` started.
    unsafe { JUDGE_EXECUTOR.on_interrupt() }
}

#[interrupt]
fn UART4() {
    // SAFETY: as above, `io_executor`.
    unsafe { IO_EXECUTOR.on_interrupt() }
}

/// Everything the tasks run over, built by the board.
pub struct Tasks<B: Board> {
    /// The inputs, for the I/O task.
    pub inputs: B::InputPins,
    /// The outputs, for the I/O task.
    pub outputs: B::OutputPins,
    /// The I/O settings at boot.
    pub io_config: IoConfig,
    /// The bridge, for the bridge task.
    pub bridge: &'static mut Bridge,
    /// The power-supply UART, unmasked.
    pub ps: B::PsUart,
    /// The CNC UART, unmasked.
    pub cnc: B::CncUart,
    /// The settings store (`None`: settings are not kept).
    pub store: Option<settings::Store<B>>,
    /// The history (`None`: no history is kept; `HISTORY` answers `ERR STORAGE`).
    pub history: Option<history::Store<B>>,
    /// The heartbeat LED.
    pub led: B::Led,
    /// The watchdog the judge feeds.
    pub watchdog: B::Watchdog,
}

/// Sets the priorities of the serial and flash interrupts; call before unmasking them.
pub fn set_serial_priorities() {
    for irq in SERIAL_IRQS {
        set_priority(irq, SERIAL_PRIORITY);
    }
}

fn set_priority(irq: Interrupt, priority: u8) {
    // SAFETY: one byte of NVIC_IPR per interrupt, written at boot before that interrupt is
    // unmasked; no priority-based critical sections exist in the images (PRIMASK only).
    unsafe {
        cortex_m::Peripherals::steal()
            .NVIC
            .set_priority(irq, priority)
    }
}

/// Starts the I/O executor ([`IO_PRIORITY`]).
pub fn io_executor() -> SendSpawner {
    set_priority(IO_IRQ, IO_PRIORITY);
    IO_EXECUTOR.start(IO_IRQ)
}

/// Starts the judge's executor ([`JUDGE_PRIORITY`]).
pub fn judge_executor() -> SendSpawner {
    set_priority(JUDGE_IRQ, JUDGE_PRIORITY);
    JUDGE_EXECUTOR.start(JUDGE_IRQ)
}
