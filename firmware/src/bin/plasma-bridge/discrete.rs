//! The discrete I/O task, on its own interrupt executor above all serial work.
//!
//! It owns the input and output pins and a `plasma_firmware::discrete::DiscreteIo`. It wakes
//! on any input edge (EXTI), on the I/O logic's own deadlines, and on news from the bridge;
//! each time it reads every input *level* (so a missed or bouncing edge cannot leave START
//! wrong), updates the logic and drives the outputs at once; only then it logs and publishes.
//!
//! The exchange with the bridge (thread mode) is by small copies under a critical section:
//! [`SUPPLY`] and [`CONFIG`] come in, [`SNAPSHOT`] and [`EVENTS`] go out.

use defmt::{debug, info, warn};
use embassy_executor::InterruptExecutor;
use embassy_futures::select::{Either4, select4};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::Timer;
use plasma_firmware::discrete::DiscreteIo;
use plasma_firmware::inputs::InputConfig;
use plasma_firmware::io::{Inputs, IoConfig, IoEvent, Outputs, SupplyState};
use plasma_firmware::time::{Duration, Instant};
use plasma_firmware::watchdog::TaskId;

use crate::clock::{embassy_instant, now};
use crate::pins::{InputPins, OutputPins, output_name};
use crate::watchdog::report;

/// The link's view of the supply, latest wins (bridge → I/O).
pub static SUPPLY: Signal<CriticalSectionRawMutex, SupplyState> = Signal::new();
/// New I/O settings after a CONFIG command (bridge → I/O).
pub static CONFIG: Signal<CriticalSectionRawMutex, (IoConfig, InputConfig)> = Signal::new();
/// Input and output levels after every change, latest wins (I/O → bridge).
pub static SNAPSHOT: Signal<CriticalSectionRawMutex, (Inputs, Outputs)> = Signal::new();
/// I/O events for the CNC session, in order (I/O → bridge).
pub static EVENTS: Channel<CriticalSectionRawMutex, (Instant, IoEvent), 16> = Channel::new();

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

/// Starts the I/O executor and spawns the I/O task on it.
pub fn start(
    pins: InputPins,
    outputs: OutputPins,
    config: (IoConfig, InputConfig),
    progress: TaskId,
) {
    interrupt::UART4.set_priority(IO_EXECUTOR_PRIORITY);
    let spawner = EXECUTOR.start(interrupt::UART4);
    spawner.spawn(io_task(pins, outputs, config, progress).unwrap());
}

/// Longest sleep of the I/O task: it reports progress and re-reads the pins at least this
/// often, whatever happens.
const MAX_WAIT: Duration = Duration::from_millis(50);

#[embassy_executor::task]
async fn io_task(
    mut pins: InputPins,
    mut outputs: OutputPins,
    config: (IoConfig, InputConfig),
    progress: TaskId,
) {
    let (io_config, input_config) = config;
    let mut io = DiscreteIo::new(io_config, input_config, now(), pins.levels());
    outputs.drive(io.outputs());
    info!(
        "I/O: start gap {} ms, transfer time-out {} ms, ARC_OK debounce {} us, link required: {}",
        io_config.effective_start_gap().as_millis(),
        io_config.transfer_timeout.as_millis(),
        io_config.arc_ok_debounce.as_micros(),
        io_config.link_required
    );
    publish(&mut io);
    loop {
        let latest = now() + MAX_WAIT;
        let deadline = io.poll_at().map_or(latest, |at| at.min(latest));
        let woke = select4(
            pins.any_edge(),
            Timer::at(embassy_instant(deadline)),
            SUPPLY.wait(),
            CONFIG.wait(),
        )
        .await;
        let now = now();
        match woke {
            Either4::First(()) | Either4::Second(()) => {}
            Either4::Third(supply) => io.on_supply(now, supply),
            Either4::Fourth((io_config, input_config)) => {
                if io.reconfigure(now, io_config, input_config, pins.levels()) {
                    warn!("I/O: new settings; START off until TORCH_ON is released");
                }
            }
        }
        // Levels, not edges: whatever woke the task, the pins decide.
        io.on_pins(now, pins.levels());
        io.poll(now);
        outputs.drive(io.outputs());
        publish(&mut io);
        report(progress);
    }
}

/// After the pins are set: log every transition with its reason, pass events on, publish
/// the levels.
fn publish(io: &mut DiscreteIo) {
    while let Some(t) = io.poll_transition() {
        info!(
            "I/O {=u64}.{=u64:03} ms: {=str} {=str}: {=str}",
            t.at.as_micros() / 1000,
            t.at.as_micros() % 1000,
            output_name(t.output),
            if t.level { "on" } else { "off" },
            t.reason.as_str()
        );
    }
    while let Some(event) = io.poll_event() {
        match event {
            IoEvent::ArcOn | IoEvent::ArcOff => debug!("I/O event: {}", event),
            _ => warn!("I/O event: {}", event),
        }
        if EVENTS.try_send((now(), event)).is_err() {
            warn!("I/O: event queue full, event not passed to the CNC session");
        }
    }
    SNAPSHOT.signal((io.inputs(), io.outputs()));
}
