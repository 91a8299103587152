//! The supervisor with a fake bridge, two fake UARTs, a fake I/O task and a fake flash saver,
//! in virtual time.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::vec::Vec;

use core::future::poll_fn;
use core::task::Poll;

use embassy_futures::block_on;
use embedded_io_async::{ErrorKind, ErrorType, ReadReady, Write};

use super::*;
use crate::platform::runner::UnsupportedConfig;
use plasma_protocol::serial::{Parity, PortConfig, StopBits};

/// The framing the fake CNC port is opened at.
const CNC_OPENED_AT: PortConfig = PortConfig::new(19_200, Parity::None, StopBits::One);

const PS: usize = 0;
const CNC: usize = 1;

#[derive(Debug, Clone, PartialEq, Eq)]
enum Seen {
    Write(u64, Vec<u8>),
    Flush(u64),
    Config(u64, PortConfig),
}

#[derive(Default)]
struct Line {
    rx: VecDeque<(u64, Vec<u8>)>,
    seen: Vec<Seen>,
}

#[derive(Default)]
struct World {
    now_us: u64,
    lines: [Line; 2],
    /// Times at which something other than received bytes becomes ready.
    wakeups: Vec<u64>,
}

type Shared = Rc<RefCell<World>>;

impl World {
    fn next_event_after_now(&self) -> Option<u64> {
        let rx = self
            .lines
            .iter()
            .filter_map(|l| l.rx.front().map(|(t, _)| *t));
        rx.chain(self.wakeups.iter().copied())
            .filter(|&t| t > self.now_us)
            .min()
    }

    fn written(&self, line: usize) -> Vec<u8> {
        self.lines[line]
            .seen
            .iter()
            .flat_map(|s| match s {
                Seen::Write(_, b) => b.clone(),
                Seen::Flush(_) | Seen::Config(..) => Vec::new(),
            })
            .collect()
    }
}

struct FakeClock(Shared);

impl Clock for FakeClock {
    fn now(&self) -> Instant {
        Instant::from_micros(self.0.borrow().now_us)
    }

    fn sleep_until(&self, at: Instant) -> impl Future<Output = ()> {
        let world = self.0.clone();
        poll_fn(move |cx| {
            let mut w = world.borrow_mut();
            let at = at.as_micros();
            if w.now_us >= at {
                return Poll::Ready(());
            }
            match w.next_event_after_now() {
                Some(t) if t < at => {
                    w.now_us = t;
                    cx.waker().wake_by_ref();
                    Poll::Pending
                }
                _ => {
                    w.now_us = at;
                    Poll::Ready(())
                }
            }
        })
    }
}

struct FakePort {
    world: Shared,
    line: usize,
}

impl ErrorType for FakePort {
    type Error = ErrorKind;
}

impl Read for FakePort {
    async fn read(&mut self, buf: &mut [u8]) -> core::result::Result<usize, ErrorKind> {
        poll_fn(|_| {
            let mut w = self.world.borrow_mut();
            let now = w.now_us;
            let line = &mut w.lines[self.line];
            match line.rx.front_mut() {
                Some((t, bytes)) if *t <= now => {
                    let n = bytes.len().min(buf.len());
                    buf[..n].copy_from_slice(&bytes[..n]);
                    bytes.drain(..n);
                    if bytes.is_empty() {
                        line.rx.pop_front();
                    }
                    Poll::Ready(Ok(n))
                }
                _ => Poll::Pending,
            }
        })
        .await
    }
}

impl ReadReady for FakePort {
    fn read_ready(&mut self) -> core::result::Result<bool, ErrorKind> {
        let w = self.world.borrow();
        Ok(w.lines[self.line]
            .rx
            .front()
            .is_some_and(|(t, _)| *t <= w.now_us))
    }
}

impl Write for FakePort {
    async fn write(&mut self, buf: &[u8]) -> core::result::Result<usize, ErrorKind> {
        let mut w = self.world.borrow_mut();
        let now = w.now_us;
        w.lines[self.line].seen.push(Seen::Write(now, buf.to_vec()));
        Ok(buf.len())
    }

    async fn flush(&mut self) -> core::result::Result<(), ErrorKind> {
        let mut w = self.world.borrow_mut();
        let now = w.now_us;
        w.lines[self.line].seen.push(Seen::Flush(now));
        Ok(())
    }
}

impl ConfigurablePort for FakePort {
    fn set_port_config(
        &mut self,
        config: PortConfig,
    ) -> core::result::Result<(), UnsupportedConfig> {
        let mut w = self.world.borrow_mut();
        let now = w.now_us;
        // A port without odd parity.
        if config.parity == Parity::Odd {
            return Err(UnsupportedConfig);
        }
        w.lines[self.line].seen.push(Seen::Config(now, config));
        Ok(())
    }
}

/// A bridge that echoes CNC lines, answers `SAVE` with a save request and `BIG` with 300
/// bytes, sends one PS frame when told to, and answers `FRAMING <baud> <N|E|O>` by asking for
/// that CNC framing.
struct FakeBridge {
    world: Shared,
    line: Vec<u8>,
    output: VecDeque<Vec<u8>>,
    current: Vec<u8>,
    ps_frame_due: bool,
    ps_rx: Vec<u8>,
    /// Each unit's supply state; as many units as states.
    supplies: Vec<SupplyState>,
    io_config: IoConfig,
    snapshots: Vec<(usize, Inputs, Outputs)>,
    /// (unit, event time, event, time the bridge got it)
    events: Vec<(usize, Instant, IoEvent, u64)>,
    save_request: Option<u32>,
    next_settings: u32,
    cnc_framing: PortConfig,
}

impl FakeBridge {
    fn new(world: &Shared) -> Self {
        FakeBridge {
            world: world.clone(),
            line: Vec::new(),
            output: VecDeque::new(),
            current: Vec::new(),
            ps_frame_due: false,
            ps_rx: Vec::new(),
            supplies: vec![SupplyState::default()],
            io_config: IoConfig::default(),
            snapshots: Vec::new(),
            events: Vec::new(),
            save_request: None,
            next_settings: 1,
            cnc_framing: CNC_OPENED_AT,
        }
    }
}

impl PsEndpoint for FakeBridge {
    fn handle_ps_rx_error(&mut self, _: Instant) {}
    fn handle_ps_rx(&mut self, _: Instant, bytes: &[u8]) {
        self.ps_rx.extend_from_slice(bytes);
    }
    fn poll_ps_transmit(&mut self, _: Instant) -> Option<&[u8]> {
        if !self.ps_frame_due {
            return None;
        }
        self.ps_frame_due = false;
        Some(b"PING\r\n")
    }
    fn ps_port_config(&self) -> PortConfig {
        PortConfig::HPR
    }
    fn poll_at(&self) -> Option<Instant> {
        None
    }
}

impl BridgeEndpoint for FakeBridge {
    type Saved = u32;
    type SaveError = ();

    fn handle_cnc_rx(&mut self, _: Instant, bytes: &[u8]) {
        for &b in bytes {
            if b != b'\r' {
                self.line.push(b);
                continue;
            }
            let line = core::mem::take(&mut self.line);
            match line.as_slice() {
                b"SAVE" => {
                    self.save_request = Some(self.next_settings);
                    self.next_settings += 1;
                }
                b"BIG" => self.output.push_back(vec![b'x'; 300]),
                b"PING" => self.ps_frame_due = true,
                [b'F', b'R', b'A', b'M', b'I', b'N', b'G', b' ', rest @ ..] => {
                    let text = String::from_utf8_lossy(rest);
                    let (baud, parity) = text.split_once(' ').unwrap_or((&text, "N"));
                    self.cnc_framing = PortConfig::new(
                        baud.parse().unwrap_or(0),
                        match parity {
                            "E" => Parity::Even,
                            "O" => Parity::Odd,
                            _ => Parity::None,
                        },
                        StopBits::One,
                    );
                    self.output.push_back(b"OK framing\r\n".to_vec());
                }
                _ => {
                    let mut reply = line.clone();
                    reply.extend_from_slice(b"\r\n");
                    self.output.push_back(reply);
                }
            }
        }
    }
    fn poll_cnc_output(&mut self) -> Option<&[u8]> {
        self.current = self.output.pop_front()?;
        Some(&self.current)
    }
    fn cnc_port_config(&self) -> PortConfig {
        self.cnc_framing
    }
    fn poll(&mut self, _: Instant) {}
    fn unit_count(&self) -> usize {
        self.supplies.len()
    }
    fn supply_state_of(&self, unit: usize) -> SupplyState {
        self.supplies.get(unit).copied().unwrap_or_default()
    }
    fn io_config(&self) -> IoConfig {
        self.io_config
    }
    fn set_io_snapshot_of(&mut self, unit: usize, inputs: Inputs, outputs: Outputs) {
        self.snapshots.push((unit, inputs, outputs));
    }
    fn on_io_event_of(&mut self, unit: usize, now: Instant, event: IoEvent) {
        let seen_at = self.world.borrow().now_us;
        self.events.push((unit, now, event, seen_at));
    }
    fn take_save_request(&mut self) -> Option<u32> {
        self.save_request.take()
    }
    fn save_finished(&mut self, _: Instant, result: core::result::Result<(), ()>) {
        self.output.push_back(match result {
            Ok(()) => b"SAVED\r\n".to_vec(),
            Err(()) => b"SAVE FAILED\r\n".to_vec(),
        });
    }
    fn take_history_draft(&mut self) -> Option<crate::storage::history::Draft> {
        None
    }
    fn history_drafts_waiting(&self) -> bool {
        false
    }
    fn take_history_request(&mut self) -> Option<crate::storage::history::HistoryRequest> {
        None
    }
    fn history_finished(&mut self, _: Instant, _: &crate::storage::history::HistoryAnswer) {}
}

#[derive(Default)]
struct FakeIo {
    world: Shared,
    snapshots: [Option<(Inputs, Outputs)>; UNIT_SETS],
    /// (ready at, unit, event time, event)
    events: VecDeque<(u64, UnitSet, Instant, IoEvent)>,
    unit_counts: Vec<usize>,
    supplies: Vec<(UnitSet, SupplyState)>,
    configs: Vec<IoConfig>,
}

impl IoExchange for FakeIo {
    fn take_snapshot(&mut self, unit: UnitSet) -> Option<(Inputs, Outputs)> {
        self.snapshots[unit.index()].take()
    }
    fn try_event(&mut self) -> Option<(UnitSet, Instant, IoEvent)> {
        let now = self.world.borrow().now_us;
        match self.events.front() {
            Some(&(ready, unit, at, event)) if ready <= now => {
                self.events.pop_front();
                Some((unit, at, event))
            }
            _ => None,
        }
    }
    fn event_ready(&mut self) -> impl Future<Output = ()> {
        let world = self.world.clone();
        let ready = self.events.front().map(|e| e.0);
        poll_fn(move |_| match ready {
            Some(t) if t <= world.borrow().now_us => Poll::Ready(()),
            _ => Poll::Pending,
        })
    }
    fn send_unit_count(&mut self, count: usize) {
        self.unit_counts.push(count);
    }
    fn send_supply(&mut self, unit: UnitSet, supply: SupplyState) {
        self.supplies.push((unit, supply));
    }
    fn send_io_config(&mut self, config: IoConfig) {
        self.configs.push(config);
    }
}

/// A supervisor over the two fake ports (the CNC one's transmit buffer `cnc_buffer` bytes,
/// its framing unknown), the fake I/O task and `saver`.
fn supervisor<S, E>(
    world: &Shared,
    cnc_buffer: usize,
    saver: FakeSaver<S, E>,
) -> Supervisor<FakePort, FakePort, FakeIo, FakeSaver<S, E>> {
    let port = |line| FakePort {
        world: world.clone(),
        line,
    };
    Supervisor::new(
        port(PS),
        port(CNC),
        cnc_buffer,
        FakeIo {
            world: world.clone(),
            ..FakeIo::default()
        },
        saver,
    )
}

/// A save through the boards' store (read-back flash) on a flash whose programs report success
/// and store nothing, as embassy-stm32 0.6.0's L4 driver reports a failed program.
fn save_on_silently_failing_flash(
    request: &crate::bridge::SaveRequest,
) -> core::result::Result<(), crate::settings::SaveError> {
    let crate::bridge::SaveRequest::Settings(settings) = request else {
        return Ok(());
    };
    use crate::storage::SettingsStore;
    use crate::storage::ram_flash::{PAGE_SIZE, RamFlash};
    use crate::storage::verified::VerifiedFlash;
    let mut flash = RamFlash::<{ 4 * PAGE_SIZE }>::new();
    flash.fail_silently(0, u32::MAX);
    let region = 0..(4 * PAGE_SIZE) as u32;
    let mut store = SettingsStore::new(VerifiedFlash::new(flash), region)
        .map_err(crate::settings::SaveError::from)?;
    block_on(store.save_settings(settings)).map_err(crate::settings::SaveError::from)
}

#[test]
fn a_flash_that_fails_silently_makes_config_save_fail() {
    use crate::bridge::Bridge;
    use crate::settings::{SaveError, Settings};

    let world: Shared = Rc::default();
    let clock = FakeClock(world.clone());
    let mut sup = supervisor(
        &world,
        64,
        FakeSaver::<crate::bridge::SaveRequest, SaveError>::new(
            &world,
            save_on_silently_failing_flash,
        ),
    );
    let mut bridge = Bridge::new(Settings::default(), Instant::ZERO);
    cnc_rx(&world, 50, b"CONFIG SAVE\r\n");
    block_on(async {
        while clock.now() < Instant::from_millis(200) {
            sup.turn(&mut bridge, &clock).await.unwrap();
        }
    });
    let cnc = String::from_utf8_lossy(&world.borrow().written(CNC)).into_owned();
    assert!(
        cnc.contains("ERR STORAGE settings not saved: flash write failed\r\n"),
        "{cnc}"
    );
    assert!(!cnc.contains("OK config=saved"), "{cnc}");
}

/// Saves take 30 ms; `outcome` decides how each ends.
struct FakeSaver<S, E> {
    world: Shared,
    started: Vec<(u64, S)>,
    outcome: fn(&S) -> core::result::Result<(), E>,
    done: Option<(u64, core::result::Result<(), E>)>,
}

impl<S, E> FakeSaver<S, E> {
    fn new(world: &Shared, outcome: fn(&S) -> core::result::Result<(), E>) -> Self {
        FakeSaver {
            world: world.clone(),
            started: Vec::new(),
            outcome,
            done: None,
        }
    }
}

impl<S, E: Copy> SettingsSaver<S, E> for FakeSaver<S, E> {
    fn start(&mut self, settings: S) {
        let mut w = self.world.borrow_mut();
        let now = w.now_us;
        self.done = Some((now + 30_000, (self.outcome)(&settings)));
        self.started.push((now, settings));
        w.wakeups.push(now + 30_000);
    }
    fn finished(&mut self) -> impl Future<Output = core::result::Result<(), E>> {
        let world = self.world.clone();
        let done = self.done;
        poll_fn(move |_| match done {
            Some((t, result)) if t <= world.borrow().now_us => Poll::Ready(result),
            _ => Poll::Pending,
        })
    }
}

/// Every third save fails.
fn every_third_fails(settings: &u32) -> core::result::Result<(), ()> {
    if settings.is_multiple_of(3) {
        Err(())
    } else {
        Ok(())
    }
}

type Sup = Supervisor<FakePort, FakePort, FakeIo, FakeSaver<u32, ()>>;

fn setup(cnc_buffer: usize) -> (Shared, FakeClock, Sup, FakeBridge) {
    let world: Shared = Rc::default();
    let sup = supervisor(
        &world,
        cnc_buffer,
        FakeSaver::new(&world, every_third_fails),
    )
    .with_cnc_framing(CNC_OPENED_AT);
    let bridge = FakeBridge::new(&world);
    (world.clone(), FakeClock(world), sup, bridge)
}

fn cnc_rx(world: &Shared, at_ms: u64, bytes: &[u8]) {
    world.borrow_mut().lines[CNC]
        .rx
        .push_back((at_ms * 1000, bytes.to_vec()));
}

fn run_until(sup: &mut Sup, bridge: &mut FakeBridge, clock: &FakeClock, until_ms: u64) {
    block_on(async {
        while clock.now() < Instant::from_millis(until_ms) {
            sup.turn(bridge, clock).await.unwrap();
        }
    });
}

#[test]
fn cnc_commands_reach_the_bridge_and_its_frames_the_supply() {
    let (world, clock, mut sup, mut bridge) = setup(256);
    cnc_rx(&world, 10, b"HEL");
    cnc_rx(&world, 12, b"LO\rPING\r");
    world.borrow_mut().lines[PS]
        .rx
        .push_back((40_000, b"PONG".to_vec()));
    run_until(&mut sup, &mut bridge, &clock, 100);
    let w = world.borrow();
    assert_eq!(w.written(CNC), b"HELLO\r\n");
    assert_eq!(w.written(PS), b"PING\r\n");
    // The PING frame went out in the turn that received the command, at 12 ms.
    assert!(
        w.lines[PS]
            .seen
            .contains(&Seen::Write(12_000, b"PING\r\n".to_vec()))
    );
    assert_eq!(bridge.ps_rx, b"PONG");
}

#[test]
fn long_output_goes_out_in_pieces_each_after_the_last_has_left() {
    let (world, clock, mut sup, mut bridge) = setup(64);
    cnc_rx(&world, 5, b"BIG\r");
    run_until(&mut sup, &mut bridge, &clock, 20);
    let w = world.borrow();
    assert_eq!(w.written(CNC), vec![b'x'; 300]);
    let seen = &w.lines[CNC].seen;
    let mut last_was_flush = false;
    for s in seen {
        match s {
            Seen::Write(_, bytes) => {
                assert!(bytes.len() <= 64);
                assert!(last_was_flush, "a write must follow a flush: {seen:?}");
                last_was_flush = false;
            }
            Seen::Flush(_) => last_was_flush = true,
            Seen::Config(..) => panic!("no framing change was asked for: {seen:?}"),
        }
    }
}

fn cnc_configs(world: &Shared) -> Vec<Seen> {
    world.borrow().lines[CNC]
        .seen
        .iter()
        .filter(|s| matches!(s, Seen::Config(..)))
        .cloned()
        .collect()
}

#[test]
fn a_new_cnc_framing_applies_once_the_reply_has_left() {
    let (world, clock, mut sup, mut bridge) = setup(256);
    cnc_rx(&world, 60, b"FRAMING 9600 E\r");
    cnc_rx(&world, 80, b"HELLO\r");
    run_until(&mut sup, &mut bridge, &clock, 200);
    let wanted = PortConfig::new(9_600, Parity::Even, StopBits::One);
    let w = world.borrow();
    // Nothing set before: the port was opened at the bridge's framing.
    assert_eq!(
        w.lines[CNC].seen,
        [
            Seen::Flush(60_000),
            Seen::Write(60_000, b"OK framing\r\n".to_vec()),
            Seen::Flush(60_000),
            Seen::Config(60_000, wanted),
            Seen::Flush(80_000),
            Seen::Write(80_000, b"HELLO\r\n".to_vec()),
        ]
    );
    assert_eq!(sup.cnc_framing(), Some(wanted));
}

#[test]
fn a_cnc_port_of_unknown_framing_gets_the_bridges_in_the_first_turn() {
    let world: Shared = Rc::default();
    let clock = FakeClock(world.clone());
    let mut sup: Sup = supervisor(&world, 64, FakeSaver::new(&world, every_third_fails));
    let mut bridge = FakeBridge::new(&world);
    run_until(&mut sup, &mut bridge, &clock, 300);
    assert_eq!(cnc_configs(&world), [Seen::Config(0, CNC_OPENED_AT)]);
}

#[test]
fn a_framing_the_cnc_port_refuses_is_reported_once_and_the_port_runs_on() {
    let (world, clock, mut sup, mut bridge) = setup(256);
    cnc_rx(&world, 10, b"FRAMING 19200 O\r");
    cnc_rx(&world, 30, b"HELLO\r");
    let mut errors = Vec::new();
    block_on(async {
        while clock.now() < Instant::from_millis(300) {
            if let Err(e) = sup.turn(&mut bridge, &clock).await {
                errors.push((clock.now(), e));
            }
        }
    });
    let refused = PortConfig {
        parity: Parity::Odd,
        ..CNC_OPENED_AT
    };
    assert_eq!(
        errors,
        [(Instant::from_millis(10), TurnError::CncUnsupported(refused))]
    );
    assert_eq!(cnc_configs(&world), []);
    assert_eq!(world.borrow().written(CNC), b"OK framing\r\nHELLO\r\n");
}

#[test]
fn supply_state_and_io_settings_go_to_the_io_task_only_when_they_change() {
    let (world, clock, mut sup, mut bridge) = setup(256);
    let [first, second] = UnitSet::ALL;
    run_until(&mut sup, &mut bridge, &clock, 300);
    // Every set's supply once, not every turn; the second set's unit is not driven: no link.
    assert_eq!(
        sup.io().supplies,
        [
            (first, SupplyState::default()),
            (second, SupplyState::default())
        ]
    );
    assert_eq!(sup.io().unit_counts, [1]);
    bridge.supplies[0] = SupplyState::HEALTHY;
    bridge.io_config.link_required = false;
    cnc_rx(&world, 310, b"x\r");
    run_until(&mut sup, &mut bridge, &clock, 1_000);
    assert_eq!(sup.io().supplies[2..], [(first, SupplyState::HEALTHY)]);
    assert_eq!(sup.io().configs.len(), 2);
    assert!(!sup.io().configs[1].link_required);
    assert_eq!(sup.io().unit_counts, [1], "sent once, not every turn");
}

#[test]
fn each_units_supply_goes_to_its_own_set_and_each_sets_io_to_its_own_unit() {
    let (world, clock, mut sup, mut bridge) = setup(256);
    let [first, second] = UnitSet::ALL;
    let faulted = SupplyState {
        fault_active: true,
        ..SupplyState::HEALTHY
    };
    bridge.supplies = vec![faulted, SupplyState::HEALTHY];
    let torch_on = Inputs {
        torch_on: true,
        ..Inputs::NONE
    };
    let start = Outputs {
        start: true,
        ..Outputs::OFF
    };
    sup.io().snapshots = [None, Some((torch_on, start))];
    sup.io().events.extend([
        (20_000, second, Instant::from_micros(19_990), IoEvent::ArcOn),
        (20_000, first, Instant::from_micros(19_995), IoEvent::ArcOff),
    ]);
    world.borrow_mut().wakeups.push(20_000);
    run_until(&mut sup, &mut bridge, &clock, 200);
    assert_eq!(sup.io().unit_counts, [2]);
    assert_eq!(
        sup.io().supplies,
        [(first, faulted), (second, SupplyState::HEALTHY)]
    );
    assert_eq!(bridge.snapshots, [(1, torch_on, start)]);
    let got: Vec<(usize, IoEvent)> = bridge.events.iter().map(|e| (e.0, e.2)).collect();
    assert_eq!(got, [(1, IoEvent::ArcOn), (0, IoEvent::ArcOff)]);
    // The second unit's link drops: only its set hears it; the count follows CONFIG units.
    bridge.supplies = vec![faulted];
    cnc_rx(&world, 210, b"x\r");
    run_until(&mut sup, &mut bridge, &clock, 400);
    assert_eq!(sup.io().unit_counts, [2, 1]);
    assert_eq!(sup.io().supplies[2..], [(second, SupplyState::default())]);
}

#[test]
fn io_events_wake_the_loop_and_reach_the_bridge_in_order() {
    let (world, clock, mut sup, mut bridge) = setup(256);
    let first = UnitSet::ALL[0];
    sup.io().snapshots[0] = Some((Inputs::NONE, Outputs::OFF));
    sup.io().events.extend([
        (20_000, first, Instant::from_micros(19_990), IoEvent::ArcOn),
        (
            20_000,
            first,
            Instant::from_micros(19_995),
            IoEvent::TransferTimeout,
        ),
    ]);
    world.borrow_mut().wakeups.push(20_000);
    run_until(&mut sup, &mut bridge, &clock, 200);
    assert_eq!(bridge.snapshots, [(0, Inputs::NONE, Outputs::OFF)]);
    assert!(bridge.events.iter().all(|e| e.0 == 0), "the first unit's");
    let got: Vec<(Instant, IoEvent)> = bridge.events.iter().map(|e| (e.1, e.2)).collect();
    assert_eq!(
        got,
        [
            (Instant::from_micros(19_990), IoEvent::ArcOn),
            (Instant::from_micros(19_995), IoEvent::TransferTimeout)
        ]
    );
    // Woken by the event, not by the 100 ms idle wait.
    assert!(
        bridge.events.iter().all(|e| e.3 == 20_000),
        "{:?}",
        bridge.events
    );
}

#[test]
fn saves_run_one_at_a_time_and_their_result_reaches_the_bridge() {
    let (world, clock, mut sup, mut bridge) = setup(256);
    cnc_rx(&world, 10, b"SAVE\r");
    cnc_rx(&world, 20, b"SAVE\r"); // while the first save runs
    cnc_rx(&world, 150, b"SAVE\r"); // the third one fails
    run_until(&mut sup, &mut bridge, &clock, 400);
    assert_eq!(
        sup.saver().started,
        [(10_000, 1), (40_000, 2), (150_000, 3)]
    );
    assert!(!sup.is_saving());
    assert_eq!(
        world.borrow().written(CNC),
        b"SAVED\r\nSAVED\r\nSAVE FAILED\r\n"
    );
}

#[test]
fn drives_the_real_bridge_end_to_end() {
    use crate::bridge::Bridge;
    use crate::settings::{SaveError, Settings};

    let world: Shared = Rc::default();
    let clock = FakeClock(world.clone());
    let mut sup = supervisor(
        &world,
        64,
        FakeSaver::<crate::bridge::SaveRequest, SaveError>::new(&world, |_| Ok(())),
    );
    let mut bridge = Bridge::new(Settings::default(), Instant::ZERO);
    // A Powermax SYNC answers the first detection request; the CNC saves the settings.
    world.borrow_mut().lines[PS]
        .rx
        .push_back((20_000, b":012B0E0481000101010630383133333504\r\n".to_vec()));
    cnc_rx(&world, 50, b"CONFIG SAVE\r\n");
    block_on(async {
        let mut turns = 0;
        while clock.now() < Instant::from_millis(300) {
            sup.turn(&mut bridge, &clock).await.unwrap();
            turns += 1;
            assert!(
                turns < 10_000,
                "stuck at {:?}, bridge poll_at {:?}",
                clock.now(),
                bridge.poll_at()
            );
        }
    });
    let w = world.borrow();
    assert!(w.written(PS).starts_with(b":012B0E0401C1\r\n"));
    // The interlocks heard that the link is up.
    assert!(
        sup.io()
            .supplies
            .iter()
            .any(|&(unit, s)| unit.index() == 0 && s.link_up),
        "{:?}",
        sup.io().supplies
    );
    assert_eq!(sup.saver().started.len(), 1);
    assert_eq!(sup.saver().started[0].0, 50_000);
    let cnc = String::from_utf8_lossy(&w.written(CNC)).into_owned();
    assert!(cnc.contains("OK config=saved\r\n"), "{cnc}");
}

/// A history over a RAM flash: drafts written at once, requests answered at once.
struct RamHistory {
    store: crate::storage::history::HistoryStore<
        crate::storage::ram_flash::RamFlash<{ 8 * crate::storage::ram_flash::PAGE_SIZE }>,
    >,
    answer: Option<crate::storage::history::HistoryAnswer>,
    recorded: usize,
    /// Drafts it takes before it is full (the board's channel).
    room: usize,
}

impl RamHistory {
    /// An empty history over 8 pages that takes `room` drafts before it is full.
    fn new(room: usize) -> RamHistory {
        use crate::storage::ram_flash::{PAGE_SIZE, RamFlash};
        let mut store =
            crate::storage::history::HistoryStore::new(RamFlash::new(), 0..(8 * PAGE_SIZE) as u32)
                .unwrap();
        block_on(store.scan()).unwrap();
        RamHistory {
            store,
            answer: None,
            recorded: 0,
            room,
        }
    }
}

impl HistoryKeeper for RamHistory {
    fn has_room(&self) -> bool {
        self.room > 0
    }
    fn record(&mut self, draft: Draft) {
        block_on(self.store.record(draft)).unwrap();
        self.recorded += 1;
        self.room -= 1;
    }
    fn start(&mut self, request: HistoryRequest) {
        let answer = block_on(crate::storage::history::serve(&mut self.store, request));
        self.answer = Some(answer);
    }
    fn finished(&mut self) -> impl Future<Output = HistoryAnswer> {
        let answer = self.answer.take();
        poll_fn(move |_| match answer.clone() {
            Some(answer) => Poll::Ready(answer),
            None => Poll::Pending,
        })
    }
}

/// The real bridge's `HISTORY` over the supervisor: `ERR STORAGE` without a keeper; with one,
/// the drafts are written and the request served.
#[test]
fn history_reaches_its_keeper_and_the_answer_the_cnc() {
    use crate::bridge::Bridge;
    use crate::platform::safe_state::ResetCause;
    use crate::settings::{SaveError, Settings};

    let run = |with_keeper: bool| {
        let world: Shared = Rc::default();
        let clock = FakeClock(world.clone());
        let sup = supervisor(
            &world,
            64,
            FakeSaver::<crate::bridge::SaveRequest, SaveError>::new(&world, |_| Ok(())),
        );
        let mut bridge = Bridge::new(Settings::default(), Instant::ZERO);
        bridge.record_reset(Instant::ZERO, ResetCause::Pin);
        cnc_rx(&world, 50, b"HISTORY\r\n");
        let keeper = RamHistory::new(usize::MAX);
        let recorded = if with_keeper {
            let mut sup = sup.with_history(keeper);
            block_on(async {
                while clock.now() < Instant::from_millis(200) {
                    sup.turn(&mut bridge, &clock).await.unwrap();
                }
            });
            sup.history.recorded
        } else {
            let mut sup = sup;
            block_on(async {
                while clock.now() < Instant::from_millis(200) {
                    sup.turn(&mut bridge, &clock).await.unwrap();
                }
            });
            0
        };
        let cnc = String::from_utf8_lossy(&world.borrow().written(CNC)).into_owned();
        (cnc, recorded)
    };
    let (cnc, _) = run(false);
    assert_eq!(cnc, "ERR STORAGE history not available\r\n");
    let (cnc, recorded) = run(true);
    assert_eq!(recorded, 1);
    assert_eq!(
        cnc,
        "HISTORY seq=0 boot=0 uptime_ms=0 clock=- family=- model=- event=RESET cause=reset_pin\r\n\
         OK history=1 skipped=0\r\n"
    );
}

/// `HISTORY` shows everything noted before it, also what the keeper had no room for when it
/// came (the board's channel is full at boot while its history task scans the flash).
#[test]
fn history_waits_for_the_drafts_its_keeper_had_no_room_for() {
    use crate::bridge::Bridge;
    use crate::platform::safe_state::ResetCause;
    use crate::settings::{SaveError, Settings};

    let world: Shared = Rc::default();
    let clock = FakeClock(world.clone());
    let mut bridge = Bridge::new(Settings::default(), Instant::ZERO);
    for cause in [ResetCause::PowerOn, ResetCause::Pin, ResetCause::Software] {
        bridge.record_reset(Instant::ZERO, cause);
    }
    cnc_rx(&world, 10, b"HISTORY\r\n");
    let keeper = RamHistory::new(1);
    let mut sup = supervisor(
        &world,
        64,
        FakeSaver::<crate::bridge::SaveRequest, SaveError>::new(&world, |_| Ok(())),
    )
    .with_history(keeper);
    block_on(async {
        while clock.now() < Instant::from_millis(400) {
            sup.turn(&mut bridge, &clock).await.unwrap();
            // One draft's room per turn from 100 ms on: the request came with two waiting.
            if clock.now() >= Instant::from_millis(100) {
                sup.history.room = 1;
            }
        }
    });
    assert_eq!(sup.history.recorded, 3);
    let cnc = String::from_utf8_lossy(&world.borrow().written(CNC)).into_owned();
    assert!(cnc.ends_with("OK history=3 skipped=0\r\n"), "{cnc}");
}
