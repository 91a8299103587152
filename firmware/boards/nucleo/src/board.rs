//! What the shared tasks take from this board ([`plasma_tasks::Board`]), and the tasks
//! themselves, declared with this board's types by [`plasma_tasks::board_tasks!`].

use plasma_tasks::Board;

use crate::cnc_uart::CncUart;
use crate::pins::{InputPins, Led, OutputPins};
use plasma_tasks::uart::Uart;

/// The Nucleo-L476RG.
pub struct Nucleo;

impl Board for Nucleo {
    type InputPins = InputPins;
    type OutputPins = OutputPins;
    type Led = Led;
    type PsUart = Uart;
    type CncUart = CncUart;
    /// The shared driver's transmit ring: the bridge writes CNC output in pieces of this.
    const CNC_TX_BUFFER: usize = plasma_tasks::uart::TX_CAPACITY;
    type Watchdog = crate::watchdog::Iwdg;
    type SettingsFlash = crate::flash::Region;
    type HistoryFlash = crate::flash::Region;

    fn flash_errors_seen() -> u32 {
        crate::flash::flash_errors_seen()
    }

    fn drain_log() {
        crate::fault::drain_log()
    }
}

// io_task, bridge_task, settings_task, heartbeat_task, judge_task and start_tasks.
plasma_tasks::board_tasks!(Nucleo);
