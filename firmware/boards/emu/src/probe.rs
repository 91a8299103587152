//! Measurements for the README, made by the emulated board (they cost a few words of RAM and
//! are logged from thread mode, never from the START path).
//!
//! - TORCH_ON edge → START: the EXTI handler of TORCH_ON stamps the edge; the first START
//!   change after it reports the cycles the core was *busy* in between (elapsed minus time in
//!   WFI), so a debounce wait does not count. Under `-icount shift=0` QEMU runs one
//!   instruction per virtual nanosecond: busy nanoseconds are instructions.
//! - Idle: every 10 s of guest time, the share of time in WFI and the wake-ups.
//! - CNC line → reply: from the read that takes a line's last byte (LF) off the CNC UART's
//!   ring to the write that hands the next reply's LF to it ([`ProbedCnc`]). QEMU transmits in
//!   no time, so this is the firmware's share of a Modbus master's wait; pmx485 allows 100 ms.
//!   Summed over each idle window and logged with it: a CNC master that never pauses (pmx485
//!   asks about 50 times a second, for hours) costs one line per window, not one per request.
//!
//! Lines start with `emu-probe:`; `pbtool emu --measure` reads them.

use core::cell::Cell;

use critical_section::Mutex;
use defmt::info;
use embedded_io_async::{ErrorType, Read, ReadReady, Write};
use plasma_firmware::platform::runner::{ConfigurablePort, UnsupportedConfig};
use plasma_protocol::serial::PortConfig;
use plasma_tasks::uart::{Uart, UartError};

use crate::executor::{SleepStats, sleep_stats};
use crate::time_driver::{cycles_to_ns, now_cycles};

/// An edge seen and not yet followed by a START change: (when, cycles asleep so far).
static EDGE: Mutex<Cell<Option<(u64, u64)>>> = Mutex::new(Cell::new(None));
/// A finished measurement not yet logged: (busy, elapsed) cycles, START level.
static RESULT: Mutex<Cell<Option<(u64, u64, bool)>>> = Mutex::new(Cell::new(None));

/// From the TORCH_ON EXTI handler.
pub fn torch_on_edge() {
    let now = now_cycles();
    let asleep = sleep_stats().asleep;
    critical_section::with(|cs| EDGE.borrow(cs).set(Some((now, asleep))));
}

/// From the output driver, when START changed.
pub fn start_changed(level: bool) {
    let now = now_cycles();
    let asleep = sleep_stats().asleep;
    critical_section::with(|cs| {
        if let Some((edge, asleep_at_edge)) = EDGE.borrow(cs).take() {
            let elapsed = now - edge;
            let busy = elapsed.saturating_sub(asleep - asleep_at_edge);
            RESULT.borrow(cs).set(Some((busy, elapsed, level)));
        }
    });
}

/// A CNC line read and not yet answered: (when, cycles asleep so far).
static CNC_LINE: Mutex<Cell<Option<(u64, u64)>>> = Mutex::new(Cell::new(None));
/// The CNC lines answered in this window.
static CNC_WINDOW: Mutex<Cell<CncFigures>> = Mutex::new(Cell::new(CncFigures::NONE));

/// Minimum, maximum and sum of one figure, in cycles.
#[derive(Clone, Copy)]
struct Spread {
    min: u64,
    max: u64,
    sum: u64,
}

impl Spread {
    const NONE: Spread = Spread {
        min: u64::MAX,
        max: 0,
        sum: 0,
    };

    fn add(self, cycles: u64) -> Spread {
        Spread {
            min: self.min.min(cycles),
            max: self.max.max(cycles),
            sum: self.sum.saturating_add(cycles),
        }
    }
}

/// CNC lines answered: how many, and how long each took.
#[derive(Clone, Copy)]
struct CncFigures {
    lines: u32,
    busy: Spread,
    elapsed: Spread,
}

impl CncFigures {
    const NONE: CncFigures = CncFigures {
        lines: 0,
        busy: Spread::NONE,
        elapsed: Spread::NONE,
    };
}

/// The emulated board's CNC UART, stamping each line that comes in and the reply that goes
/// out.
pub struct ProbedCnc(pub Uart);

impl ErrorType for ProbedCnc {
    type Error = UartError;
}

impl Read for ProbedCnc {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, UartError> {
        let n = self.0.read(buf).await?;
        if buf.get(..n).is_some_and(|read| read.contains(&b'\n')) {
            let (now, asleep) = (now_cycles(), sleep_stats().asleep);
            critical_section::with(|cs| CNC_LINE.borrow(cs).set(Some((now, asleep))));
        }
        Ok(n)
    }
}

impl ReadReady for ProbedCnc {
    fn read_ready(&mut self) -> Result<bool, UartError> {
        self.0.read_ready()
    }
}

impl Write for ProbedCnc {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, UartError> {
        let n = self.0.write(buf).await?;
        if buf.get(..n).is_some_and(|written| written.contains(&b'\n')) {
            let (now, asleep) = (now_cycles(), sleep_stats().asleep);
            critical_section::with(|cs| {
                if let Some((line, asleep_at_line)) = CNC_LINE.borrow(cs).take() {
                    let elapsed = now - line;
                    let busy = elapsed.saturating_sub(asleep - asleep_at_line);
                    let window = CNC_WINDOW.borrow(cs);
                    let figures = window.get();
                    window.set(CncFigures {
                        lines: figures.lines.saturating_add(1),
                        busy: figures.busy.add(busy),
                        elapsed: figures.elapsed.add(elapsed),
                    });
                }
            });
        }
        Ok(n)
    }

    async fn flush(&mut self) -> Result<(), UartError> {
        self.0.flush().await
    }
}

impl ConfigurablePort for ProbedCnc {
    fn set_port_config(&mut self, config: PortConfig) -> Result<(), UnsupportedConfig> {
        self.0.set_port_config(config)
    }
}

/// Guest time between idle reports.
const IDLE_WINDOW_CYCLES: u64 = 10 * crate::rcc::SYSCLK_HZ as u64;

/// The start of the current idle window.
static WINDOW: Mutex<Cell<Option<(u64, SleepStats)>>> = Mutex::new(Cell::new(None));

/// Thread mode, after every executor poll: logs what was measured.
pub fn report() {
    if let Some((busy, elapsed, level)) = critical_section::with(|cs| RESULT.borrow(cs).take()) {
        info!(
            "emu-probe: TORCH_ON edge to START {=str}: {=u64} ns busy, {=u64} ns elapsed",
            if level { "on" } else { "off" },
            cycles_to_ns(busy),
            cycles_to_ns(elapsed)
        );
    }
    let now = now_cycles();
    let stats = sleep_stats();
    let Some((start, at_start)) = critical_section::with(|cs| WINDOW.borrow(cs).get()) else {
        critical_section::with(|cs| WINDOW.borrow(cs).set(Some((now, stats))));
        return;
    };
    if now - start < IDLE_WINDOW_CYCLES {
        return;
    }
    let cnc = critical_section::with(|cs| CNC_WINDOW.borrow(cs).replace(CncFigures::NONE));
    if cnc.lines > 0 {
        info!(
            "emu-probe: CNC line to reply: {=u32} lines, busy min {=u64} max {=u64} sum {=u64} ns, elapsed min {=u64} max {=u64} sum {=u64} ns",
            cnc.lines,
            cycles_to_ns(cnc.busy.min),
            cycles_to_ns(cnc.busy.max),
            cycles_to_ns(cnc.busy.sum),
            cycles_to_ns(cnc.elapsed.min),
            cycles_to_ns(cnc.elapsed.max),
            cycles_to_ns(cnc.elapsed.sum)
        );
    }
    info!(
        "emu-probe: idle {=u64} ns asleep of {=u64} ns, {=u32} wake-ups, {=u32} polls",
        cycles_to_ns(stats.asleep - at_start.asleep),
        cycles_to_ns(now - start),
        stats.wake_ups.wrapping_sub(at_start.wake_ups),
        stats.polls.wrapping_sub(at_start.polls)
    );
    critical_section::with(|cs| WINDOW.borrow(cs).set(Some((now, stats))));
}
