//! The discrete I/O task, on its own interrupt executor above all serial work.
//!
//! It owns the input and output pins and a `plasma_firmware::io::UnitsIo`: one `DiscreteIo`
//! per unit set of the pin table (`plasma_firmware::platform::pins::UnitSet`), each with its
//! own interlocks: one unit's TORCH_ON never reaches another's START, and one unit's fault or
//! lost link never blocks another's. It wakes on any input edge (EXTI, through the always-armed latch of
//! [`crate::edges`]: an edge while the task is busy wakes its next wait), on the I/O logic's
//! own deadlines, and on news from the bridge; each time it reads every input *level* of every
//! set (so a bouncing edge cannot leave START wrong), updates the logic and drives the outputs
//! at once; only then it logs and publishes.
//!
//! A set whose unit the bridge does not drive (`CONFIG units` names fewer, as the supervisor
//! tells) is inert (`UnitsIo`: outputs off, no events, whatever the settings allow).
//!
//! The exchange with the bridge (thread mode) is by small copies under a critical section:
//! the unit count, each unit's supply state and the I/O settings come in ([`News`]), each
//! unit's levels ([`SNAPSHOTS`]) and every unit's events, tagged ([`EVENTS`]), go out.

use core::cell::Cell;
use core::future::Future;
use core::sync::atomic::{AtomicU32, Ordering};

use defmt::{debug, info, warn};
use embassy_futures::select::{Either3, select3};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::Timer;
use plasma_firmware::io::{
    self, Inputs, IoConfig, IoEvent, Outputs, PinLevels, SupplyState, Transition, UnitsIo,
};
use plasma_firmware::platform::pins::{UNIT_SETS, UnitSet};
use plasma_firmware::platform::supervisor::IoExchange;
use plasma_firmware::platform::watchdog::TaskId;
use plasma_protocol::time::{Duration, Instant, div_rem_u16};

use crate::board::{InputPins, OutputPins};
use crate::clock::{embassy_instant, now};
use crate::edges::EDGES;
use crate::log_text::EventText;
use crate::progress::report;
use crate::safe_state::drive_outputs;

/// What the bridge told the I/O task since the task last looked, each the latest (bridge → I/O).
#[derive(Debug, Clone, Copy)]
struct News {
    /// How many units the bridge drives.
    unit_count: Option<usize>,
    /// Each set's unit's view of its supply.
    supplies: [Option<SupplyState>; UNIT_SETS],
    /// New I/O settings, the CNC's wiring included, after a CONFIG command.
    config: Option<IoConfig>,
}

impl News {
    /// Nothing new.
    const EMPTY: News = News {
        unit_count: None,
        supplies: [None; UNIT_SETS],
        config: None,
    };
}

static NEWS: Mutex<CriticalSectionRawMutex, Cell<News>> = Mutex::new(Cell::new(News::EMPTY));
/// Wakes the I/O task when [`NEWS`] has something.
static NEWS_READY: Signal<CriticalSectionRawMutex, ()> = Signal::new();

/// Adds to the news for the I/O task and wakes it.
fn tell(update: impl FnOnce(&mut News)) {
    NEWS.lock(|news| {
        let mut latest = news.get();
        update(&mut latest);
        news.set(latest);
    });
    NEWS_READY.signal(());
}

/// Each set's input and output levels after every change, latest wins (I/O → bridge).
pub static SNAPSHOTS: [Signal<CriticalSectionRawMutex, (Inputs, Outputs)>; UNIT_SETS] =
    [const { Signal::new() }; UNIT_SETS];
/// I/O events for the CNC session, each with its unit, in order (I/O → bridge).
pub static EVENTS: Channel<CriticalSectionRawMutex, (UnitSet, Instant, IoEvent), 16> =
    Channel::new();

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
    let levels = |unit| UnitSet::new(unit).map_or(PinLevels::ALL_HIGH, |set| pins.levels(set));
    let mut units = UnitsIo::<UNIT_SETS>::new(io_config, now(), levels);
    drive_all(&mut outputs, &units);
    debug!(
        "I/O: start gap {} ms, transfer time-out {} ms, ARC_OK debounce {} us, link required: {}",
        io_config.effective_start_gap().as_millis(),
        io_config.transfer_timeout.as_millis(),
        io_config.arc_ok_debounce.as_micros(),
        io_config.link_required
    );
    publish(&mut units, now());
    loop {
        let latest = now() + MAX_WAIT;
        let deadline = units.poll_at().map_or(latest, |at| at.min(latest));
        let woke = select3(
            EDGES.wait(),
            Timer::at(embassy_instant(deadline)),
            NEWS_READY.wait(),
        )
        .await;
        let now = now();
        if let Either3::Third(()) = woke {
            let news = NEWS.lock(|news| news.replace(News::EMPTY));
            if let Some(config) = news.config
                && units.reconfigure(now, config, levels)
            {
                info!(
                    "I/O: new settings: start gap {} ms, transfer time-out {} ms, link required {=bool}",
                    config.effective_start_gap().as_millis(),
                    config.transfer_timeout.as_millis(),
                    config.link_required
                );
            }
            for (unit, supply) in news.supplies.into_iter().enumerate() {
                if let Some(supply) = supply {
                    units.on_supply(now, unit, supply);
                }
            }
            if let Some(count) = news.unit_count
                && units.set_unit_count(now, count, levels)
            {
                info!(
                    "I/O: {=u8} of the board's unit sets driven",
                    count.min(UNIT_SETS) as u8
                );
            }
        }
        // Levels, not edges: whatever woke the task, the pins decide.
        units.on_pins(now, levels);
        units.poll(now);
        drive_all(&mut outputs, &units);
        publish(&mut units, now);
        report(progress);
    }
}

/// Drives every set's outputs, the first unit's first; an inert set's all off (safe state).
fn drive_all(outputs: &mut impl OutputPins, units: &UnitsIo<UNIT_SETS>) {
    for set in UnitSet::ALL {
        drive_outputs(outputs, set, units.table_outputs(set.index()));
    }
}

/// After the pins are set: hand every driven unit's transitions, events and levels to thread
/// mode. Nothing is logged here: a defmt frame masks every interrupt while it is written, and
/// this task should be ready for the next edge as soon as possible.
fn publish(units: &mut UnitsIo<UNIT_SETS>, now: Instant) {
    for (unit, io) in units.driven() {
        let (Some(set), Some(snapshot)) = (UnitSet::new(unit), SNAPSHOTS.get(unit)) else {
            continue;
        };
        while let Some(transition) = io.poll_transition() {
            if TRANSITIONS.try_send((set, transition)).is_err() {
                LOST_TRANSITIONS.fetch_add(1, Ordering::Relaxed);
            }
        }
        while let Some(event) = io.poll_event() {
            if EVENTS.try_send((set, now, event)).is_err() {
                LOST_EVENTS.fetch_add(1, Ordering::Relaxed);
            }
        }
        snapshot.signal((io.inputs(), io.outputs()));
    }
}

/// Output changes for the log (I/O → thread mode).
static TRANSITIONS: Channel<CriticalSectionRawMutex, (UnitSet, Transition), 32> = Channel::new();
static LOST_TRANSITIONS: AtomicU32 = AtomicU32::new(0);
static LOST_EVENTS: AtomicU32 = AtomicU32::new(0);

/// Thread mode: logs every output change the I/O task made, with its reason.
pub fn log_transitions() {
    while let Ok((set, t)) = TRANSITIONS.try_receive() {
        let (ms, us) = div_rem_u16(t.at.as_micros(), 1000);
        let level = if t.level { "on" } else { "off" };
        // The first unit's lines as with one unit; another's name it as the CNC port does.
        if set.index() == 0 {
            info!(
                "I/O {=u64}.{=u16:03} ms: {=istr} {=str}: {}",
                ms,
                us,
                output_name(t.output),
                level,
                t.reason
            );
        } else {
            info!(
                "I/O @{=u8} {=u64}.{=u16:03} ms: {=istr} {=str}: {}",
                unit_number(set),
                ms,
                us,
                output_name(t.output),
                level,
                t.reason
            );
        }
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
pub fn log_event(set: UnitSet, at: Instant, event: IoEvent) {
    let unit = unit_number(set);
    match event {
        IoEvent::ArcOn | IoEvent::ArcOff => {
            debug!(
                "I/O event @{=u8} at {} us: {}",
                unit,
                at.as_micros(),
                EventText(event)
            )
        }
        _ => warn!(
            "I/O event @{=u8} at {} us: {}",
            unit,
            at.as_micros(),
            EventText(event)
        ),
    }
}

/// The supervisor's side of the exchange (thread mode).
pub struct BoardIo;

impl IoExchange for BoardIo {
    fn take_snapshot(&mut self, unit: UnitSet) -> Option<(Inputs, Outputs)> {
        log_transitions();
        SNAPSHOTS.get(unit.index())?.try_take()
    }

    fn try_event(&mut self) -> Option<(UnitSet, Instant, IoEvent)> {
        let (unit, at, event) = EVENTS.try_receive().ok()?;
        log_event(unit, at, event);
        Some((unit, at, event))
    }

    fn event_ready(&mut self) -> impl Future<Output = ()> {
        EVENTS.ready_to_receive()
    }

    fn send_unit_count(&mut self, count: usize) {
        tell(|news| news.unit_count = Some(count));
    }

    fn send_supply(&mut self, unit: UnitSet, supply: SupplyState) {
        debug!(
            "supply @{=u8}: link {=bool}, ready {=bool}, fault {=bool} (requires action {=bool})",
            unit_number(unit),
            supply.link_up,
            supply.unit_ready,
            supply.fault_active,
            supply.fault_requires_action
        );
        tell(|news| {
            if let Some(slot) = news.supplies.get_mut(unit.index()) {
                *slot = Some(supply);
            }
        });
    }

    fn send_io_config(&mut self, config: IoConfig) {
        tell(|news| news.config = Some(config));
    }
}

/// How the CNC port numbers `set`'s unit (`@1` is the first).
fn unit_number(set: UnitSet) -> u8 {
    set.index() as u8 + 1
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
