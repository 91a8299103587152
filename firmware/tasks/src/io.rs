//! The discrete I/O task, on its own interrupt executor above all serial work.
//!
//! It owns the input and output pins and a `plasma_firmware::io::DiscreteIo`. It wakes
//! on any input edge (EXTI, through the always-armed latch of [`crate::edges`]: an edge while
//! the task is busy wakes its next wait), on the I/O logic's own deadlines, and on news from
//! the bridge; each time it reads every input *level* (so a bouncing edge cannot leave START
//! wrong), updates the logic and drives the outputs at once; only then it logs and publishes.
//!
//! The exchange with the bridge (thread mode) is by small copies under a critical section:
//! [`SUPPLY`] and [`CONFIG`] come in, [`SNAPSHOT`] and [`EVENTS`] go out.

use core::future::Future;
use core::sync::atomic::{AtomicU32, Ordering};

use defmt::{debug, info, warn};
use embassy_futures::select::{Either4, select4};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::Timer;
use plasma_firmware::io::{
    self, DiscreteIo, Inputs, IoConfig, IoEvent, Outputs, SupplyState, Transition,
};
use plasma_firmware::platform::supervisor::IoExchange;
use plasma_firmware::platform::watchdog::TaskId;
use plasma_protocol::time::{Duration, Instant, div_rem_u16};

use crate::board::{InputPins, OutputPins};
use crate::clock::{embassy_instant, now};
use crate::edges::EDGES;
use crate::log_text::EventText;
use crate::progress::report;
use crate::safe_state::drive_outputs;

/// The link's view of the supply, latest wins (bridge → I/O).
pub static SUPPLY: Signal<CriticalSectionRawMutex, SupplyState> = Signal::new();
/// New I/O settings, the CNC's wiring included, after a CONFIG command (bridge → I/O).
pub static CONFIG: Signal<CriticalSectionRawMutex, IoConfig> = Signal::new();
/// Input and output levels after every change, latest wins (I/O → bridge).
pub static SNAPSHOT: Signal<CriticalSectionRawMutex, (Inputs, Outputs)> = Signal::new();
/// I/O events for the CNC session, in order (I/O → bridge).
pub static EVENTS: Channel<CriticalSectionRawMutex, (Instant, IoEvent), 16> = Channel::new();

/// Longest sleep of the I/O task: it reports progress and re-reads the pins at least this
/// often, whatever happens.
const MAX_WAIT: Duration = Duration::from_millis(50);

/// The body of the I/O task. Each board runs it on an interrupt executor above every serial
/// interrupt, so the START path never waits behind serial work.
pub async fn run(
    pins: impl InputPins,
    mut outputs: impl OutputPins,
    io_config: IoConfig,
    progress: TaskId,
) {
    let mut io = DiscreteIo::new(io_config, now(), pins.levels());
    drive_outputs(&mut outputs, io.table_outputs());
    debug!(
        "I/O: start gap {} ms, transfer time-out {} ms, ARC_OK debounce {} us, link required: {}",
        io_config.effective_start_gap().as_millis(),
        io_config.transfer_timeout.as_millis(),
        io_config.arc_ok_debounce.as_micros(),
        io_config.link_required
    );
    publish(&mut io, now());
    loop {
        let latest = now() + MAX_WAIT;
        let deadline = io.poll_at().map_or(latest, |at| at.min(latest));
        let woke = select4(
            EDGES.wait(),
            Timer::at(embassy_instant(deadline)),
            SUPPLY.wait(),
            CONFIG.wait(),
        )
        .await;
        let now = now();
        match woke {
            Either4::First(()) | Either4::Second(()) => {}
            Either4::Third(supply) => io.on_supply(now, supply),
            Either4::Fourth(io_config) => {
                if io.reconfigure(now, io_config, pins.levels()) {
                    info!(
                        "I/O: new settings: start gap {} ms, transfer time-out {} ms, link required {=bool}",
                        io_config.effective_start_gap().as_millis(),
                        io_config.transfer_timeout.as_millis(),
                        io_config.link_required
                    );
                }
            }
        }
        // Levels, not edges: whatever woke the task, the pins decide.
        io.on_pins(now, pins.levels());
        io.poll(now);
        drive_outputs(&mut outputs, io.table_outputs());
        publish(&mut io, now);
        report(progress);
    }
}

/// After the pins are set: hand transitions, events and levels to thread mode. Nothing is
/// logged here: a defmt frame masks every interrupt while it is written, and this task
/// should be ready for the next edge as soon as possible.
fn publish(io: &mut DiscreteIo, now: Instant) {
    while let Some(transition) = io.poll_transition() {
        if TRANSITIONS.try_send(transition).is_err() {
            LOST_TRANSITIONS.fetch_add(1, Ordering::Relaxed);
        }
    }
    while let Some(event) = io.poll_event() {
        if EVENTS.try_send((now, event)).is_err() {
            LOST_EVENTS.fetch_add(1, Ordering::Relaxed);
        }
    }
    SNAPSHOT.signal((io.inputs(), io.outputs()));
}

/// Output changes for the log (I/O → thread mode).
static TRANSITIONS: Channel<CriticalSectionRawMutex, Transition, 32> = Channel::new();
static LOST_TRANSITIONS: AtomicU32 = AtomicU32::new(0);
static LOST_EVENTS: AtomicU32 = AtomicU32::new(0);

/// Thread mode: logs every output change the I/O task made, with its reason.
pub fn log_transitions() {
    while let Ok(t) = TRANSITIONS.try_receive() {
        let (ms, us) = div_rem_u16(t.at.as_micros(), 1000);
        info!(
            "I/O {=u64}.{=u16:03} ms: {=istr} {=str}: {}",
            ms,
            us,
            output_name(t.output),
            if t.level { "on" } else { "off" },
            t.reason
        );
    }
    let lost = LOST_TRANSITIONS.swap(0, Ordering::Relaxed);
    if lost > 0 {
        warn!("I/O: {} output changes not logged (log queue full)", lost);
    }
    let lost = LOST_EVENTS.swap(0, Ordering::Relaxed);
    if lost > 0 {
        warn!(
            "I/O: {} events not passed to the CNC session (queue full)",
            lost
        );
    }
}

/// Thread mode: logs an I/O event as it is passed to the CNC session.
pub fn log_event(at: Instant, event: IoEvent) {
    match event {
        IoEvent::ArcOn | IoEvent::ArcOff => {
            debug!("I/O event at {} us: {}", at.as_micros(), EventText(event))
        }
        _ => warn!("I/O event at {} us: {}", at.as_micros(), EventText(event)),
    }
}

/// The supervisor's side of the exchange (thread mode).
pub struct BoardIo;

impl IoExchange for BoardIo {
    fn take_snapshot(&mut self) -> Option<(Inputs, Outputs)> {
        log_transitions();
        SNAPSHOT.try_take()
    }

    fn try_event(&mut self) -> Option<(Instant, IoEvent)> {
        let (at, event) = EVENTS.try_receive().ok()?;
        log_event(at, event);
        Some((at, event))
    }

    fn event_ready(&mut self) -> impl Future<Output = ()> {
        EVENTS.ready_to_receive()
    }

    fn send_supply(&mut self, supply: SupplyState) {
        debug!(
            "supply: link {=bool}, ready {=bool}, fault {=bool} (requires action {=bool})",
            supply.link_up, supply.unit_ready, supply.fault_active, supply.fault_requires_action
        );
        SUPPLY.signal(supply);
    }

    fn send_io_config(&mut self, config: IoConfig) {
        CONFIG.signal(config);
    }
}

/// The names of the io outputs as docs/board.md writes them, for logs (interned: the texts stay
/// in the ELF for the host decoder, not in flash).
pub fn output_name(output: io::Output) -> defmt::Str {
    match output {
        io::Output::Start => defmt::intern!("START"),
        io::Output::Hold => defmt::intern!("PS_HOLD"),
        io::Output::PierceComplete => defmt::intern!("PS_PIERCE_COMPLETE"),
        io::Output::CornerCurrent => defmt::intern!("PS_CORNER_CURRENT"),
        io::Output::ArcOk => defmt::intern!("ARC_OK"),
        io::Output::Ready => defmt::intern!("READY"),
        io::Output::Fault => defmt::intern!("FAULT"),
        io::Output::RemotePower => defmt::intern!("PS_REMOTE_POWER"),
    }
}
