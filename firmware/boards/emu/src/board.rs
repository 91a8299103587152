//! What the shared tasks take from this board ([`plasma_tasks::Board`]), and the tasks
//! themselves, declared with this board's types by [`plasma_tasks::board_tasks!`].

use plasma_tasks::Board;

use crate::flash::{HistoryFlash, SettingsFlash};
use crate::gpio::{InputPins, Led, OutputPins};
use crate::probe::ProbedCnc;
use plasma_tasks::uart::Uart;

/// QEMU's b-l475e-iot01a.
pub struct Emulated;

impl Board for Emulated {
    type InputPins = InputPins;
    type OutputPins = OutputPins;
    type Led = Led;
    type PsUart = Uart;
    type CncUart = ProbedCnc;
    /// The shared driver's transmit ring, as on the Nucleo.
    const CNC_TX_BUFFER: usize = plasma_tasks::uart::TX_CAPACITY;
    type Watchdog = crate::watchdog::SoftWatchdog;
    type SettingsFlash = SettingsFlash;
    type HistoryFlash = HistoryFlash;

    /// The RAM model has no ECC: no read errors.
    fn flash_errors_seen() -> u32 {
        0
    }

    /// Semihosting writes each log line before it returns: nothing to drain.
    fn drain_log() {}
}

// io_task, bridge_task, settings_task, heartbeat_task, judge_task and start_tasks.
plasma_tasks::board_tasks!(Emulated);
