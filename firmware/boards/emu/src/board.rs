//! What the shared tasks take from this board ([`plasma_tasks::Board`]), and the tasks
//! themselves: `#[embassy_executor::task]` functions cannot be generic, so each is a thin
//! wrapper with this board's types that returns the shared body's future. Not an `async fn`
//! around `.await`: that future would keep the arguments twice (its own and the body's).

use core::future::Future;

use plasma_firmware::bridge::Bridge;
use plasma_firmware::io::IoConfig;
use plasma_firmware::watchdog::TaskId;
use plasma_tasks::Board;
use plasma_tasks::io::BoardIo;
use plasma_tasks::settings::Store;

use crate::flash::SettingsFlash;
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
    type SettingsFlash = SettingsFlash;

    /// The RAM model has no ECC: no read errors.
    fn flash_errors_seen() -> u32 {
        0
    }
}

/// The I/O task ([`plasma_tasks::io::run`]).
#[embassy_executor::task]
pub fn io_task(
    inputs: InputPins,
    outputs: OutputPins,
    config: IoConfig,
    progress: TaskId,
) -> impl Future<Output = ()> {
    plasma_tasks::io::run(inputs, outputs, config, progress)
}

/// The bridge task ([`plasma_tasks::bridge::run`]).
#[embassy_executor::task]
pub fn bridge_task(
    bridge: &'static mut Bridge,
    ps: Uart,
    cnc: ProbedCnc,
    io: BoardIo,
    progress: TaskId,
) -> impl Future<Output = ()> {
    plasma_tasks::bridge::run::<Emulated>(bridge, ps, cnc, io, progress)
}

/// The settings task ([`plasma_tasks::settings::run`]).
#[embassy_executor::task]
pub fn settings_task(store: Option<Store<Emulated>>, progress: TaskId) -> impl Future<Output = ()> {
    plasma_tasks::settings::run::<Emulated>(store, progress)
}

/// The heartbeat task ([`plasma_tasks::progress::heartbeat`]).
#[embassy_executor::task]
pub fn heartbeat_task(led: Led, progress: TaskId) -> impl Future<Output = ()> {
    plasma_tasks::progress::heartbeat(led, progress)
}
