//! What a board provides to the tasks.

use embedded_storage_async::nor_flash::NorFlash;
use plasma_firmware::io::{Outputs, PinLevels};
use plasma_firmware::platform::pins::UnitSet;
use plasma_firmware::platform::runner::ConfigurablePort;

/// Every unit set's eight discrete inputs, owned by the I/O task. Their edges come through
/// the EXTI lines the board arms with [`crate::edges::arm_inputs`].
pub trait InputPins {
    /// Reads every pin of unit `set`'s set now (pin levels; the I/O logic applies the
    /// polarity); a board-wide input reads its one pin for every set.
    fn levels(&self, set: UnitSet) -> PinLevels;
}

/// Every unit set's eight discrete outputs, owned by the I/O task.
pub trait OutputPins {
    /// Sets every pin of unit `set`'s set to `outputs` (logical levels;
    /// `plasma_firmware::platform::pins` says which pin level each means). START first: it is
    /// the one whose latency matters.
    fn drive(&mut self, set: UnitSet, outputs: Outputs);
}

/// The heartbeat LED.
pub trait Led {
    /// On ↔ off.
    fn toggle(&mut self);
}

/// The board's watchdog, which the stall judge ([`crate::progress::judge`]) feeds while every
/// task reports progress.
pub trait Watchdog: Send + 'static {
    /// Every task is alive: keep the watchdog from resetting.
    fn feed(&mut self);
    /// A task stalled and the outputs are already safe: the reset follows (the IWDG's, or
    /// what stands for it); never completes.
    fn expire(self) -> impl core::future::Future<Output = ()> + Send;
}

/// A board: the types the tasks run over, and the few facts they need from it.
pub trait Board: 'static {
    /// The inputs.
    type InputPins: InputPins;
    /// The outputs.
    type OutputPins: OutputPins;
    /// The heartbeat LED.
    type Led: Led;
    /// The power-supply UART, whose line settings the link changes while detecting.
    type PsUart: ConfigurablePort<Error: defmt::Format>;
    /// The CNC UART, whose framing follows `CONFIG cnc_baud|cnc_parity|cnc_stop_bits`.
    type CncUart: ConfigurablePort<Error: defmt::Format>;
    /// The CNC UART's transmit buffer: the bridge writes output in pieces of at most this.
    const CNC_TX_BUFFER: usize;
    /// The watchdog the stall judge feeds.
    type Watchdog: Watchdog;
    /// The flash the settings are stored in.
    type SettingsFlash: NorFlash;
    /// The flash the event history is kept in.
    type HistoryFlash: NorFlash;

    /// Read errors the flash reported since the last call (torn writes the settings store or
    /// the history skipped).
    fn flash_errors_seen() -> u32;

    /// On the fault path, after its log line and before the reset: gives the logger time to
    /// get the line out (interrupts are off).
    fn drain_log();
}
