//! An interrupt-driven USART by register (USART v3, the same on the STM32L476RG and the
//! emulated STM32L475VG), for both UARTs of both boards.
//!
//! Why not embassy-stm32 0.6.0's `BufferedUart` (docs/board.md, "Faults found in review"):
//! it logs a parity, framing or noise error and hands the byte on as good data, so the link
//! never hears of it; and its `flush()` can return while bytes are still queued, after which
//! a line-settings change strands them. Here:
//!
//! - receive: RXNE interrupt → a ring of bytes, each with its error flags; a read returns the
//!   good bytes before a flagged one, and the flagged one as its own error
//!   ([`UartError::Parity`], `Framing`, `Noise`, of kind `InvalidData`), in its place in the
//!   stream: the runner hands that to the link as a character received in error. Overrun is
//!   reported once, like the HAL's.
//! - transmit: a ring the TXE interrupt empties; [`Write::flush`] returns only when the ring
//!   is empty *and* TC says the last stop bit has left, so the driver-enable has dropped and
//!   the settings may change.
//!
//! What QEMU's model needs as well (docs/developers.md, "QEMU's board model"): 32-bit access to RDR/TDR (the
//! register crate's only width), never a 1 in ICR bit 7, and no reliance on the IDLE flag:
//! bytes are handed on as they arrive and the link's parser finds the end of a frame.
//!
//! The board owns the USART's clock, pins and NVIC line; it calls [`on_interrupt`] from the
//! USART's vector with the port's [`UartState`].

use core::cell::RefCell;
use core::future::poll_fn;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::Poll;

use critical_section::Mutex;

use crate::clock_tree::UsartClock;
use embassy_sync::waitqueue::AtomicWaker;
use embedded_io_async::{ErrorKind, ErrorType, Read, ReadReady, Write};
use heapless::Deque;
use plasma_firmware::platform::runner::{ConfigurablePort, UnsupportedConfig};
use plasma_protocol::serial::{DataBits, Parity, PortConfig, StopBits};
use stm32_metapac::usart::Usart;
use stm32_metapac::usart::vals::{M0, M1, Ps, Stop};

/// Receive ring per port: a few frames.
const RX_CAPACITY: usize = 256;
/// Transmit ring per port: the longest PS frame, or a CNC piece (`Board::CNC_TX_BUFFER`).
pub const TX_CAPACITY: usize = 256;

/// The most bytes moved between a ring and a caller under one critical section. Every
/// interrupt waits while one runs (PRIMASK): the I/O executor's START path and the other
/// USART, whose receiver has no FIFO. Eight bytes keep each section to a couple of hundred
/// cycles (docs/board.md, "START path latency"), far below one character time.
const BYTES_PER_CRITICAL_SECTION: usize = 8;

/// Driver-enable assertion and de-assertion time, in 1/16 bit (8 = half a bit, 26 us at
/// 19200: far more than a transceiver's enable time).
const DE_TIME: u8 = 8;

/// What a read can report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UartError {
    /// A byte arrived before the previous one was read: bytes were lost.
    Overrun,
    /// A character with a wrong parity bit.
    Parity,
    /// A character without its stop bit (framing error; a break reads as one too).
    Framing,
    /// A character whose bits the receiver sampled with noise.
    Noise,
}

impl UartError {
    /// What happened, in words (`framing error`).
    pub const fn as_str(self) -> &'static str {
        match self {
            UartError::Overrun => "receive overrun",
            UartError::Parity => "parity error",
            UartError::Framing => "framing error",
            UartError::Noise => "noise error",
        }
    }
}

impl core::fmt::Display for UartError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl defmt::Format for UartError {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "{=str}", self.as_str())
    }
}

impl core::error::Error for UartError {}

impl embedded_io_async::Error for UartError {
    /// A character received in error is `InvalidData` (the runner passes it to the link in
    /// its place); a lost byte is `Other`.
    fn kind(&self) -> ErrorKind {
        match self {
            UartError::Overrun => ErrorKind::Other,
            UartError::Parity | UartError::Framing | UartError::Noise => ErrorKind::InvalidData,
        }
    }
}

/// A received character: the byte, and the error it came with.
#[derive(Clone, Copy)]
struct Received {
    byte: u8,
    error: Option<UartError>,
}

/// The interrupt side of one port.
pub struct UartState {
    rx: Mutex<RefCell<Deque<Received, RX_CAPACITY>>>,
    tx: Mutex<RefCell<Deque<u8, TX_CAPACITY>>>,
    overrun: AtomicBool,
    rx_waker: AtomicWaker,
    tx_waker: AtomicWaker,
}

impl UartState {
    /// Empty.
    pub const fn new() -> Self {
        UartState {
            rx: Mutex::new(RefCell::new(Deque::new())),
            tx: Mutex::new(RefCell::new(Deque::new())),
            overrun: AtomicBool::new(false),
            rx_waker: AtomicWaker::new(),
            tx_waker: AtomicWaker::new(),
        }
    }
}

impl Default for UartState {
    fn default() -> Self {
        Self::new()
    }
}

/// A configured USART with its interrupt state.
pub struct Uart {
    regs: Usart,
    state: &'static UartState,
    kernel_clock_hz: u32,
}

/// BRR for `baud` from the USART's kernel clock (oversampling by 16), if it can make it;
/// rounded to the nearest (at 16 MHz, 115200 baud is BRR 139, 0.08 % slow, where truncating
/// to 138 made it 0.64 % fast).
fn brr(kernel_clock_hz: u32, baud: u32) -> Option<u16> {
    if !runs_baud(kernel_clock_hz, baud) {
        return None;
    }
    // Kernel clocks stay below 2^32 - baud / 2 (80 MHz at most), so this cannot saturate.
    u16::try_from(kernel_clock_hz.saturating_add(baud / 2) / baud).ok()
}

/// Whether a USART clocked at `kernel_clock_hz` runs `baud` (oversampling by 16: BRR from 16
/// to 0xFFFF).
pub const fn runs_baud(kernel_clock_hz: u32, baud: u32) -> bool {
    if baud == 0 {
        return false;
    }
    let div = kernel_clock_hz / baud;
    div >= 16 && div <= 0xFFFF
}

/// Whether a USART clocked at `kernel_clock_hz` runs every one of `bauds`; for the boards'
/// compile-time checks against the baud rates the settings accept.
pub const fn runs_every_baud(kernel_clock_hz: u32, bauds: &[u32]) -> bool {
    let mut i = 0;
    while i < bauds.len() {
        if !runs_baud(kernel_clock_hz, bauds[i]) {
            return false;
        }
        i += 1;
    }
    true
}

impl Uart {
    /// Takes `regs` (its clock on, pins routed) with `config`; with `driver_enable` the USART
    /// drives its DE pin (RS-485). The caller unmasks its interrupt. BRR follows the kernel
    /// clock the RCC runs (`clock`'s, read now: `crate::clock_tree`), whatever the board meant
    /// to set; `None` if that clock is unknown or cannot make the baud rate.
    pub fn new(
        regs: Usart,
        state: &'static UartState,
        clock: UsartClock,
        config: PortConfig,
        driver_enable: bool,
    ) -> Option<Self> {
        let kernel_clock_hz = crate::chip::rcc_snapshot().usart_clock_hz(clock)?;
        let mut uart = Uart {
            regs,
            state,
            kernel_clock_hz,
        };
        regs.cr1().modify(|w| w.set_ue(false));
        // Errors are read with RXNE; their own interrupt (EIE: framing, noise, overrun
        // without RXNE) wakes the handler as well.
        regs.cr3().modify(|w| {
            w.set_dem(driver_enable);
            w.set_eie(true);
        });
        uart.configure(config)?;
        Some(uart)
    }

    /// Line settings: disable, program, enable (RM0351: M, PCE, PS, STOP and BRR only
    /// change while UE is off). Only called with nothing queued (after a flush).
    fn configure(&mut self, config: PortConfig) -> Option<()> {
        let brr = brr(self.kernel_clock_hz, config.baud)?;
        let regs = self.regs;
        regs.cr1().modify(|w| w.set_ue(false));
        regs.brr().write(|w| w.set_brr(brr));
        regs.cr2().modify(|w| {
            w.set_stop(match config.stop_bits {
                StopBits::One => Stop::STOP1,
                StopBits::Two => Stop::STOP2,
            })
        });
        let (m1, m0) = word_length(config);
        regs.cr1().modify(|w| {
            w.set_m1(m1);
            w.set_m0(m0);
            w.set_pce(config.parity != Parity::None);
            w.set_ps(if config.parity == Parity::Odd {
                Ps::ODD
            } else {
                Ps::EVEN
            });
            w.set_peie(config.parity != Parity::None);
            w.set_deat(DE_TIME);
            w.set_dedt(DE_TIME);
            w.set_te(true);
            w.set_re(true);
            w.set_rxneie(true);
            w.set_ue(true);
        });
        Some(())
    }
}

/// M1:M0, the word length (RM0351, USART_CR1): it counts the parity bit, which takes the
/// word's top bit. 8 data bits: an 8-bit word (M=00) without parity, 9 bits (M=01) with; 7
/// data bits: a 7-bit word (M=10) without parity, 8 bits (M=00) with (embassy-stm32 0.6.0's
/// `DataBits7`/`DataBits8` map the same). Every framing the settings take has a word length.
fn word_length(config: PortConfig) -> (M1, M0) {
    match (config.data_bits, config.parity != Parity::None) {
        (DataBits::Eight, false) | (DataBits::Seven, true) => (M1::M0, M0::BIT8),
        (DataBits::Eight, true) => (M1::M0, M0::BIT9),
        (DataBits::Seven, false) => (M1::BIT7, M0::BIT8),
    }
}

/// The data bits of a character RDR holds: with parity its top bit is the parity bit (RM0351,
/// "the value read in the MSB bit is the received parity bit"), so a 7E1 character reads 0x7F
/// at most only when masked; an 8-bit read of a 9-bit word drops the parity bit by itself.
fn data_mask(cr1: stm32_metapac::usart::regs::Cr1) -> u8 {
    let seven_bit_word = cr1.m1() == M1::BIT7;
    let eight_bit_word_with_parity = cr1.m1() == M1::M0 && cr1.m0() == M0::BIT8 && cr1.pce();
    if seven_bit_word || eight_bit_word_with_parity {
        0x7F
    } else {
        0xFF
    }
}

/// The USART interrupt: received characters (with their errors) into the ring, overrun
/// noted, the transmit ring fed to TDR, TC passed on. Returns whether a character arrived
/// (the emulated board keeps QEMU fetching the next one).
pub fn on_interrupt(regs: Usart, state: &UartState) -> bool {
    let isr = regs.isr().read();
    let error = if isr.pe() {
        Some(UartError::Parity)
    } else if isr.fe() {
        Some(UartError::Framing)
    } else if isr.ne() {
        Some(UartError::Noise)
    } else {
        None
    };
    if isr.pe() || isr.fe() || isr.ne() || isr.ore() {
        // Write-1-to-clear, only what was seen (never ICR bit 7: QEMU clears TXE with it).
        regs.icr().write(|w| {
            w.set_pe(isr.pe());
            w.set_fe(isr.fe());
            w.set_ne(isr.ne());
            w.set_ore(isr.ore());
        });
    }
    if isr.ore() {
        state.overrun.store(true, Ordering::Release);
        state.rx_waker.wake();
    }
    let cr1 = regs.cr1().read();
    if isr.rxne() {
        // Reading RDR clears RXNE.
        let byte = regs.rdr().read().dr() as u8 & data_mask(cr1);
        let full = critical_section::with(|cs| {
            state
                .rx
                .borrow(cs)
                .borrow_mut()
                .push_back(Received { byte, error })
                .is_err()
        });
        if full {
            state.overrun.store(true, Ordering::Release);
        }
        state.rx_waker.wake();
    } else if let Some(error) = error {
        // Flagged without a character to read (a break, or noise on an idle line): still
        // one character received in error, in its place.
        critical_section::with(|cs| {
            let _ = state.rx.borrow(cs).borrow_mut().push_back(Received {
                byte: 0,
                error: Some(error),
            });
        });
        state.rx_waker.wake();
    }
    if cr1.txeie() && isr.txe() {
        let next = critical_section::with(|cs| state.tx.borrow(cs).borrow_mut().pop_front());
        match next {
            Some(byte) => {
                // TC must not still say "done" from the previous byte while this one goes
                // out (QEMU does not clear it on a TDR write).
                regs.icr().write(|w| w.set_tc(true));
                regs.tdr().write(|w| w.set_dr(u16::from(byte)));
            }
            None => regs.cr1().modify(|w| w.set_txeie(false)),
        }
        // Room in the ring, or the ring ran empty: a writer or a flush may go on.
        state.tx_waker.wake();
    }
    if cr1.tcie() && isr.tc() {
        regs.cr1().modify(|w| w.set_tcie(false));
        state.tx_waker.wake();
    }
    isr.rxne()
}

/// Sets an interrupt enable of CR1 from thread mode: the read-modify-write under a critical
/// section, so the interrupt's own CR1 changes cannot be undone by it.
fn enable(regs: Usart, set: impl FnOnce(&mut stm32_metapac::usart::regs::Cr1)) {
    critical_section::with(|_| regs.cr1().modify(set));
}

/// The UARTs' pins of the one pin table (`plasma_firmware::platform::pins::PS_UART`, `CNC_UART`) to
/// alternate function 7, receive pins pulled up (an idle line reads as mark also while a
/// 2-wire transceiver's receiver is off). The GPIO clocks must be on.
pub fn route_pins() {
    use plasma_firmware::platform::pins::{CNC_UART, PS_UART};
    use stm32_metapac::gpio::Gpio;
    use stm32_metapac::gpio::vals::{Moder, Pupdr};
    for uart in [PS_UART, CNC_UART] {
        for pin in uart.pins() {
            // SAFETY: the pin table's ports are GPIO register blocks of both chips.
            let port = unsafe { Gpio::from_ptr(pin.port.register_block() as usize as *mut ()) };
            let n = usize::from(pin.number);
            port.afr(n / 8).modify(|w| w.set_afr(n % 8, 7));
            if pin == uart.rx {
                port.pupdr().modify(|w| w.set_pupdr(n, Pupdr::PULL_UP));
            }
            port.moder().modify(|w| w.set_moder(n, Moder::ALTERNATE));
        }
    }
}

impl ErrorType for Uart {
    type Error = UartError;
}

impl Read for Uart {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, UartError> {
        if buf.is_empty() {
            return Ok(0);
        }
        let state = self.state;
        poll_fn(|cx| {
            state.rx_waker.register(cx.waker());
            if state.overrun.swap(false, Ordering::AcqRel) {
                return Poll::Ready(Err(UartError::Overrun));
            }
            // A flagged character first in the ring is reported alone...
            let flagged = critical_section::with(|cs| {
                let mut rx = state.rx.borrow(cs).borrow_mut();
                match rx.front().copied() {
                    Some(Received {
                        error: Some(error), ..
                    }) => {
                        rx.pop_front();
                        Some(error)
                    }
                    _ => None,
                }
            });
            if let Some(error) = flagged {
                return Poll::Ready(Err(error));
            }
            // ...otherwise the good ones up to the next flagged one, a few per critical
            // section (only this reader takes from the ring; the interrupt only adds).
            let mut n = 0;
            for chunk in buf.chunks_mut(BYTES_PER_CRITICAL_SECTION) {
                let taken = critical_section::with(|cs| {
                    let mut rx = state.rx.borrow(cs).borrow_mut();
                    let mut taken = 0;
                    for slot in chunk.iter_mut() {
                        match rx.front() {
                            Some(Received { byte, error: None }) => {
                                *slot = *byte;
                                rx.pop_front();
                                taken += 1;
                            }
                            _ => break,
                        }
                    }
                    taken
                });
                n += taken;
                if taken < chunk.len() {
                    break;
                }
            }
            if n > 0 {
                Poll::Ready(Ok(n))
            } else {
                Poll::Pending
            }
        })
        .await
    }
}

impl ReadReady for Uart {
    fn read_ready(&mut self) -> Result<bool, UartError> {
        let state = self.state;
        Ok(state.overrun.load(Ordering::Acquire)
            || critical_section::with(|cs| !state.rx.borrow(cs).borrow().is_empty()))
    }
}

impl Write for Uart {
    /// Queues as much of `buf` as the ring takes (waits only while it is full).
    async fn write(&mut self, buf: &[u8]) -> Result<usize, UartError> {
        if buf.is_empty() {
            return Ok(0);
        }
        let (regs, state) = (self.regs, self.state);
        poll_fn(|cx| {
            state.tx_waker.register(cx.waker());
            // A few bytes per critical section (only this writer adds to the ring; the
            // interrupt only takes).
            let mut n = 0;
            for chunk in buf.chunks(BYTES_PER_CRITICAL_SECTION) {
                let queued = critical_section::with(|cs| {
                    let mut tx = state.tx.borrow(cs).borrow_mut();
                    chunk
                        .iter()
                        .take_while(|&&b| tx.push_back(b).is_ok())
                        .count()
                });
                n += queued;
                if queued < chunk.len() {
                    break;
                }
            }
            if n > 0 {
                enable(regs, |w| w.set_txeie(true));
                Poll::Ready(Ok(n))
            } else {
                Poll::Pending
            }
        })
        .await
    }

    /// Returns once nothing is queued and the last stop bit has left (TC).
    async fn flush(&mut self) -> Result<(), UartError> {
        let (regs, state) = (self.regs, self.state);
        poll_fn(|cx| {
            state.tx_waker.register(cx.waker());
            let queued = critical_section::with(|cs| !state.tx.borrow(cs).borrow().is_empty());
            if queued {
                enable(regs, |w| w.set_txeie(true));
                return Poll::Pending;
            }
            // TXEIE off means the ISR has moved the last byte to TDR (or nothing was sent).
            if !regs.cr1().read().txeie() && regs.isr().read().tc() {
                Poll::Ready(Ok(()))
            } else {
                enable(regs, |w| w.set_tcie(true));
                Poll::Pending
            }
        })
        .await
    }
}

impl ConfigurablePort for Uart {
    fn set_port_config(&mut self, config: PortConfig) -> Result<(), UnsupportedConfig> {
        self.configure(config).ok_or(UnsupportedConfig)
    }
}
