//! The runner against a fake UART and a virtual clock: line settings per frame, whole frames,
//! waits bounded by the link's deadlines, progress on a silent line.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::vec::Vec as StdVec;

use core::future::poll_fn;
use core::task::Poll;

use embassy_futures::block_on;
use embassy_futures::select::{Either, select};
use embedded_io_async::{ErrorKind, ErrorType, Read, ReadReady, Write};

use super::*;
use crate::link::LinkConfig;
use plasma_protocol::serial::{Parity, StopBits};

/// What the fake port saw.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Seen {
    Config(u64, PortConfig),
    /// Written bytes, the settings in force, the time the write started.
    Write(u64, PortConfig, StdVec<u8>),
    Flush(u64),
}

type Responder = Box<dyn FnMut(&[u8], PortConfig) -> Option<StdVec<u8>>>;

#[derive(Default)]
struct World {
    now_us: u64,
    /// Bytes that arrive at a time.
    rx: VecDeque<(u64, StdVec<u8>)>,
    seen: StdVec<Seen>,
    responder: Option<Responder>,
    fail_writes: bool,
}

type Shared = Rc<RefCell<World>>;

struct FakeClock(Shared);

impl Clock for FakeClock {
    fn now(&self) -> Instant {
        Instant::from_micros(self.0.borrow().now_us)
    }

    /// Virtual time jumps to `at`, or to the next arrival if that comes first (then the
    /// sleep stays pending so that `select` lets the read take the bytes).
    fn sleep_until(&self, at: Instant) -> impl Future<Output = ()> {
        let world = self.0.clone();
        poll_fn(move |cx| {
            let mut w = world.borrow_mut();
            let at = at.as_micros();
            if w.now_us >= at {
                return Poll::Ready(());
            }
            match w.rx.front().map(|(t, _)| *t) {
                Some(t) if t < at => {
                    w.now_us = w.now_us.max(t);
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
    config: Option<PortConfig>,
}

impl ErrorType for FakePort {
    type Error = ErrorKind;
}

impl Read for FakePort {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
        let world = self.world.clone();
        poll_fn(move |_| {
            let mut w = world.borrow_mut();
            let now = w.now_us;
            match w.rx.front_mut() {
                // An empty chunk: one character received with a parity error.
                Some((t, bytes)) if *t <= now && bytes.is_empty() => {
                    w.rx.pop_front();
                    Poll::Ready(Err(ErrorKind::InvalidData))
                }
                Some((t, bytes)) if *t <= now => {
                    let n = bytes.len().min(buf.len());
                    buf[..n].copy_from_slice(&bytes[..n]);
                    bytes.drain(..n);
                    if bytes.is_empty() {
                        w.rx.pop_front();
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
    fn read_ready(&mut self) -> Result<bool, ErrorKind> {
        let w = self.world.borrow();
        Ok(w.rx.front().is_some_and(|(t, _)| *t <= w.now_us))
    }
}

impl Write for FakePort {
    /// Takes everything at once; the wire time passes at flush.
    async fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        let mut w = self.world.borrow_mut();
        if w.fail_writes {
            return Err(ErrorKind::Other);
        }
        let config = self
            .config
            .expect("written before any line settings were applied");
        let now = w.now_us;
        w.seen.push(Seen::Write(now, config, buf.to_vec()));
        Ok(buf.len())
    }

    async fn flush(&mut self) -> Result<(), ErrorKind> {
        let mut w = self.world.borrow_mut();
        let config = self.config.unwrap_or(PortConfig::HPR);
        let pending: StdVec<u8> = w
            .seen
            .iter()
            .rev()
            .take_while(|s| matches!(s, Seen::Write(..)))
            .flat_map(|s| match s {
                Seen::Write(_, _, bytes) => bytes.clone(),
                _ => StdVec::new(),
            })
            .collect();
        let wire_us = pending.len() as u64 * config.char_time_ns() / 1000;
        w.now_us += wire_us;
        let now = w.now_us;
        w.seen.push(Seen::Flush(now));
        if let Some(mut responder) = w.responder.take() {
            if let Some(reply) = responder(&pending, config) {
                // The supply answers 5 ms after the request, in two pieces.
                let (a, b) = reply.split_at(reply.len() / 2);
                w.rx.push_back((now + 5_000, a.to_vec()));
                w.rx.push_back((now + 8_000, b.to_vec()));
            }
            w.responder = Some(responder);
        }
        Ok(())
    }
}

impl ConfigurablePort for FakePort {
    fn set_port_config(&mut self, config: PortConfig) -> Result<(), UnsupportedConfig> {
        if config.baud == 0 {
            return Err(UnsupportedConfig);
        }
        let mut w = self.world.borrow_mut();
        let now = w.now_us;
        w.seen.push(Seen::Config(now, config));
        self.config = Some(config);
        Ok(())
    }
}

fn setup() -> (Shared, FakeClock, PsPort<FakePort>) {
    let world: Shared = Rc::default();
    let clock = FakeClock(world.clone());
    let port = PsPort::new(FakePort {
        world: world.clone(),
        config: None,
    });
    (world, clock, port)
}

/// What one [`turn`] did.
#[derive(Debug, PartialEq, Eq)]
struct Turn {
    frames_sent: usize,
    bytes_received: usize,
    new_config: Option<PortConfig>,
}

/// The smallest loop over the port's pieces (the board's loop is the supervisor's turn, which
/// adds the CNC port and the I/O): transmit what is due, then wait for bytes until the
/// endpoint's `poll_at`, at most [`MAX_WAIT`].
async fn turn<E: PsEndpoint + ?Sized>(
    port: &mut PsPort<FakePort>,
    endpoint: &mut E,
    clock: &FakeClock,
) -> Result<Turn, PortError<ErrorKind>> {
    let (frames_sent, new_config) = port.transmit(endpoint, clock).await?;
    let latest = clock.now() + MAX_WAIT;
    let deadline = endpoint.poll_at().map_or(latest, |at| at.min(latest));
    let mut buf = [0u8; PS_RX_CHUNK];
    let bytes_received = match select(port.read(&mut buf), clock.sleep_until(deadline)).await {
        Either::First(received) => port.hand_over(endpoint, clock, received, &buf)?,
        Either::Second(()) => 0,
    };
    Ok(Turn {
        frames_sent,
        bytes_received,
        new_config,
    })
}

/// Runs turns until virtual time reaches `until_ms`; returns the turns' start times.
fn run_until(
    link: &mut impl PsEndpoint,
    port: &mut PsPort<FakePort>,
    clock: &FakeClock,
    until_ms: u64,
) -> StdVec<u64> {
    let mut starts = StdVec::new();
    block_on(async {
        while clock.now() < Instant::from_millis(until_ms) {
            starts.push(clock.now().as_micros());
            turn(port, link, clock).await.unwrap();
        }
    });
    starts
}

const DEVICE_ID_REQUEST: &[u8] = b":012B0E0401C1\r\n";
/// A Powermax65/85/105 SYNC answering Read Device Identification (the link's doc example).
const DEVICE_ID_REPLY: &[u8] = b":012B0E0481000101010630383133333504\r\n";

fn writes(world: &Shared) -> StdVec<(u64, PortConfig, StdVec<u8>)> {
    world
        .borrow()
        .seen
        .iter()
        .filter_map(|s| match s {
            Seen::Write(t, c, b) => Some((*t, *c, b.clone())),
            _ => None,
        })
        .collect()
}

#[test]
fn detects_a_powermax_through_the_port() {
    let (world, clock, mut port) = setup();
    world.borrow_mut().responder = Some(Box::new(|frame, config| {
        (frame == DEVICE_ID_REQUEST && config == PortConfig::MODBUS_DEFAULT)
            .then(|| DEVICE_ID_REPLY.to_vec())
    }));
    let mut link = PsLink::new(LinkConfig::default(), Instant::ZERO);
    run_until(&mut link, &mut port, &clock, 40);
    assert!(link.status().link_up, "{:?}", world.borrow().seen);
    // The settings came first, then the frame in one piece, then the flush.
    let seen = world.borrow().seen.clone();
    assert_eq!(seen[0], Seen::Config(0, PortConfig::MODBUS_DEFAULT));
    assert_eq!(
        seen[1],
        Seen::Write(0, PortConfig::MODBUS_DEFAULT, DEVICE_ID_REQUEST.to_vec())
    );
    assert!(matches!(seen[2], Seen::Flush(_)));
    assert_eq!(port.applied, Some(PortConfig::MODBUS_DEFAULT));
}

#[test]
fn every_frame_goes_out_whole_with_the_settings_the_link_asked_for() {
    /// Records the settings the link reports right after handing out each frame.
    struct Recording {
        link: PsLink,
        frame: StdVec<u8>,
        asked: StdVec<(StdVec<u8>, PortConfig)>,
    }
    impl PsEndpoint for Recording {
        fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]) {
            self.link.handle_rx(now, bytes);
        }
        fn handle_ps_rx_error(&mut self, now: Instant) {
            self.link.handle_rx_error(now);
        }
        fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]> {
            self.frame = self.link.poll_transmit(now)?.to_vec();
            self.asked
                .push((self.frame.clone(), self.link.port_config()));
            Some(&self.frame)
        }
        fn ps_port_config(&self) -> PortConfig {
            self.link.port_config()
        }
        fn poll_at(&self) -> Option<Instant> {
            self.link.poll_at()
        }
    }

    let (world, clock, mut port) = setup();
    let mut endpoint = Recording {
        link: PsLink::new(LinkConfig::default(), Instant::ZERO),
        frame: StdVec::new(),
        asked: StdVec::new(),
    };
    // Nobody answers: detection walks through every framing and the HPR protocol.
    run_until(&mut endpoint, &mut port, &clock, 30_000);

    let sent: StdVec<(StdVec<u8>, PortConfig)> = writes(&world)
        .into_iter()
        .map(|(_, config, bytes)| (bytes, config))
        .collect();
    assert_eq!(sent, endpoint.asked);
    let configs: StdVec<PortConfig> = sent.iter().map(|(_, c)| *c).collect();
    for (parity, stop_bits) in [
        (Parity::Even, StopBits::One),
        (Parity::Odd, StopBits::One),
        (Parity::None, StopBits::Two),
    ] {
        assert!(
            configs
                .iter()
                .any(|c| c.parity == parity && c.stop_bits == stop_bits),
            "never tried {parity:?} {stop_bits:?}: {configs:?}"
        );
    }
    assert!(configs.contains(&PortConfig::HPR));

    // A settings change only ever happens on an idle line: every write is flushed before the
    // next settings change.
    let seen = world.borrow().seen.clone();
    let mut open_write = false;
    for s in &seen {
        match s {
            Seen::Write(..) => open_write = true,
            Seen::Flush(_) => open_write = false,
            Seen::Config(..) => assert!(!open_write, "settings changed mid-frame: {seen:?}"),
        }
    }
}

#[test]
fn waits_follow_the_links_deadlines() {
    let (world, clock, mut port) = setup();
    let mut link = PsLink::new(LinkConfig::default(), Instant::ZERO);
    run_until(&mut link, &mut port, &clock, 1_000);
    let sent = writes(&world);
    assert!(sent.len() >= 3, "{sent:?}");
    // Unanswered: the next attempt goes out exactly when the previous one times out
    // (100 ms after its last stop bit left, the end of its flush; Modbus retries are
    // immediate), not later, and not 100 ms after it was handed to the UART.
    let (t0, config, first) = &sent[0];
    let (t1, _, second) = &sent[1];
    assert_eq!(first, second, "a retry repeats the frame");
    let flushed = world
        .borrow()
        .seen
        .iter()
        .find_map(|s| match s {
            Seen::Flush(t) if t > t0 => Some(*t),
            _ => None,
        })
        .unwrap();
    let wire_us = first.len() as u64 * config.char_time_ns() / 1000;
    assert_eq!(
        flushed - *t0,
        wire_us,
        "the fake port's flush takes the wire time"
    );
    assert!(
        wire_us > 5_000,
        "{wire_us} us: a frame long enough to matter"
    );
    assert_eq!(*t1 - flushed, 100_000);
}

#[test]
fn a_silent_endpoint_still_turns_every_max_wait() {
    struct Idle;
    impl PsEndpoint for Idle {
        fn handle_ps_rx(&mut self, _: Instant, _: &[u8]) {}
        fn handle_ps_rx_error(&mut self, _: Instant) {}
        fn poll_ps_transmit(&mut self, _: Instant) -> Option<&[u8]> {
            None
        }
        fn ps_port_config(&self) -> PortConfig {
            PortConfig::HPR
        }
        fn poll_at(&self) -> Option<Instant> {
            None
        }
    }
    let (world, clock, mut port) = setup();
    let starts = run_until(&mut Idle, &mut port, &clock, 1_000);
    let gaps: StdVec<u64> = starts.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(gaps.iter().all(|&g| g == MAX_WAIT.as_micros()), "{gaps:?}");
    // Settings applied once, before listening.
    assert_eq!(world.borrow().seen, [Seen::Config(0, PortConfig::HPR)]);
}

#[test]
fn bytes_wake_the_turn_before_its_deadline() {
    let (world, clock, mut port) = setup();
    let mut link = PsLink::new(LinkConfig::default(), Instant::ZERO);
    world.borrow_mut().rx.push_back((30_000, b":01".to_vec()));
    block_on(async {
        let first = turn(&mut port, &mut link, &clock).await.unwrap();
        assert_eq!(first.frames_sent, 1);
        assert_eq!(first.new_config, Some(PortConfig::MODBUS_DEFAULT));
        assert_eq!(first.bytes_received, 3);
    });
    assert_eq!(clock.now(), Instant::from_millis(30));
}

#[test]
fn port_errors_are_reported_not_swallowed() {
    let (world, clock, mut port) = setup();
    world.borrow_mut().fail_writes = true;
    let mut link = PsLink::new(LinkConfig::default(), Instant::ZERO);
    let result = block_on(turn(&mut port, &mut link, &clock));
    assert_eq!(result, Err(PortError::Write(ErrorKind::Other)));

    struct Impossible;
    impl PsEndpoint for Impossible {
        fn handle_ps_rx(&mut self, _: Instant, _: &[u8]) {}
        fn handle_ps_rx_error(&mut self, _: Instant) {}
        fn poll_ps_transmit(&mut self, _: Instant) -> Option<&[u8]> {
            None
        }
        fn ps_port_config(&self) -> PortConfig {
            PortConfig {
                baud: 0,
                ..PortConfig::HPR
            }
        }
        fn poll_at(&self) -> Option<Instant> {
            None
        }
    }
    let (_, clock, mut port) = setup();
    let result = block_on(turn(&mut port, &mut Impossible, &clock));
    assert!(matches!(result, Err(PortError::Unsupported(c)) if c.baud == 0));
}

#[test]
fn a_reply_waiting_in_the_port_beats_the_time_out() {
    let (world, clock, mut port) = setup();
    let mut link = PsLink::new(LinkConfig::default(), Instant::ZERO);
    block_on(async {
        let turn = port.transmit(&mut link, &clock).await.unwrap();
        assert_eq!(turn.0, 1);
    });
    // The reply arrives within the 100 ms time-out, but the task only gets to it at 150 ms
    // (busy elsewhere, e.g. writing to the CNC).
    {
        let mut w = world.borrow_mut();
        w.rx.push_back((50_000, DEVICE_ID_REPLY.to_vec()));
        w.now_us = 150_000;
    }
    block_on(turn(&mut port, &mut link, &clock)).unwrap();
    assert!(link.status().link_up);
    assert_eq!(link.diagnostics().timeouts, 0);
}

#[test]
fn a_character_received_in_error_reaches_the_link_in_its_place() {
    /// Records what the runner passes on, in order.
    #[derive(Default)]
    struct Heard(StdVec<Option<StdVec<u8>>>);
    impl PsEndpoint for Heard {
        fn handle_ps_rx(&mut self, _: Instant, bytes: &[u8]) {
            self.0.push(Some(bytes.to_vec()));
        }
        fn handle_ps_rx_error(&mut self, _: Instant) {
            self.0.push(None);
        }
        fn poll_ps_transmit(&mut self, _: Instant) -> Option<&[u8]> {
            None
        }
        fn ps_port_config(&self) -> PortConfig {
            PortConfig::MODBUS_DEFAULT
        }
        fn poll_at(&self) -> Option<Instant> {
            None
        }
    }

    let (world, clock, mut port) = setup();
    {
        let mut w = world.borrow_mut();
        w.rx.push_back((1_000, b":01".to_vec()));
        w.rx.push_back((1_000, StdVec::new())); // a parity error
        w.rx.push_back((1_000, b"03\r\n".to_vec()));
    }
    let mut heard = Heard::default();
    block_on(async {
        for _ in 0..4 {
            turn(&mut port, &mut heard, &clock).await.unwrap();
        }
    });
    assert_eq!(
        heard.0,
        [Some(b":01".to_vec()), None, Some(b"03\r\n".to_vec())]
    );
}
