//! An interrupt-driven USART by register, for QEMU's USART model.
//!
//! What QEMU's model needs, unlike embassy-stm32's driver (../shared/EMULATION.md): 32-bit
//! access to RDR/TDR (the register crate's only access width), never a 1 in ICR bit 7 (QEMU
//! clears TXE with it), and no reliance on the IDLE flag (never raised): bytes are handed on
//! as they arrive and the link's parser finds the end of a frame, as on the real board.
//!
//! Receive: RXNE interrupt → a ring buffer → the reading task. Overrun is counted and
//! reported once as an error, like the HAL's. Transmit: TXE interrupt (only while a write
//! waits). The USART drives DE in hardware (DEM), as on the Nucleo; QEMU ignores it.

use core::cell::RefCell;
use core::future::poll_fn;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::Poll;

use critical_section::Mutex;
use embassy_sync::waitqueue::AtomicWaker;
use embedded_io_async::{ErrorKind, ErrorType, Read, ReadReady, Write};
use heapless::Deque;
use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use stm32_metapac::usart::Usart;
use stm32_metapac::usart::vals::{M0, M1, Ps, Stop};

use crate::rcc::SYSCLK_HZ;

/// Receive buffer per port: a few frames.
const RX_CAPACITY: usize = 256;

/// What a read can report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum UartError {
    /// A byte arrived before the previous one was read: bytes were lost.
    Overrun,
}

impl core::fmt::Display for UartError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("receive overrun")
    }
}

impl core::error::Error for UartError {}

impl embedded_io_async::Error for UartError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// The interrupt side of one port.
pub struct UartState {
    rx: Mutex<RefCell<Deque<u8, RX_CAPACITY>>>,
    overrun: AtomicBool,
    rx_waker: AtomicWaker,
    tx_waker: AtomicWaker,
}

impl UartState {
    /// Empty.
    pub const fn new() -> Self {
        UartState {
            rx: Mutex::new(RefCell::new(Deque::new())),
            overrun: AtomicBool::new(false),
            rx_waker: AtomicWaker::new(),
            tx_waker: AtomicWaker::new(),
        }
    }
}

/// A configured USART with its interrupt state.
pub struct Uart {
    regs: Usart,
    state: &'static UartState,
}

/// BRR for `baud` at SYSCLK (oversampling by 16), if the USART can make it.
fn brr(baud: u32) -> Option<u16> {
    let div = SYSCLK_HZ.checked_div(baud)?;
    u16::try_from(div).ok().filter(|&d| d >= 16)
}

impl Uart {
    /// Takes `regs` (clocked, pins routed) with `config`; the caller unmasks its interrupt.
    pub fn new(
        regs: Usart,
        state: &'static UartState,
        config: PortConfig,
        driver_enable: bool,
    ) -> Option<Self> {
        let mut uart = Uart { regs, state };
        if driver_enable {
            // DE asserted half a bit before the start bit and held half a bit after the stop
            // bit, as on the Nucleo image.
            regs.cr3().modify(|w| w.set_dem(true));
        }
        uart.configure(config)?;
        Some(uart)
    }

    /// Line settings: disable, program, enable (RM0351: M, PCE, PS, STOP and BRR only
    /// change while UE is off).
    fn configure(&mut self, config: PortConfig) -> Option<()> {
        let brr = brr(config.baud)?;
        let regs = self.regs;
        regs.cr1().modify(|w| w.set_ue(false));
        regs.brr().write(|w| w.set_brr(brr));
        regs.cr2().modify(|w| {
            w.set_stop(match config.stop_bits {
                StopBits::One => Stop::STOP1,
                StopBits::Two => Stop::STOP2,
            })
        });
        regs.cr1().modify(|w| {
            // 8 data bits; with parity the word is 9 bits (M0) and the 9th is the parity bit.
            w.set_m1(M1::M0);
            w.set_m0(if config.parity == Parity::None {
                M0::BIT8
            } else {
                M0::BIT9
            });
            w.set_pce(config.parity != Parity::None);
            w.set_ps(if config.parity == Parity::Odd {
                Ps::ODD
            } else {
                Ps::EVEN
            });
            w.set_deat(8);
            w.set_dedt(8);
            w.set_te(true);
            w.set_re(true);
            w.set_rxneie(true);
            w.set_ue(true);
        });
        Some(())
    }
}

/// The USART interrupt: received bytes into the buffer, overrun noted, TXE passed on.
pub fn on_interrupt(regs: Usart, state: &UartState) {
    let isr = regs.isr().read();
    if isr.ore() {
        regs.icr().write(|w| w.set_ore(true));
        state.overrun.store(true, Ordering::Release);
        state.rx_waker.wake();
    }
    if isr.rxne() {
        // Reading RDR clears RXNE.
        let byte = regs.rdr().read().dr() as u8;
        let full =
            critical_section::with(|cs| state.rx.borrow(cs).borrow_mut().push_back(byte).is_err());
        if full {
            state.overrun.store(true, Ordering::Release);
        }
        state.rx_waker.wake();
        crate::time_driver::keep_receiving();
    }
    let cr1 = regs.cr1().read();
    if (cr1.txeie() && isr.txe()) || (cr1.tcie() && isr.tc()) {
        // The waiting writer re-enables what it still needs.
        regs.cr1().modify(|w| {
            w.set_txeie(false);
            w.set_tcie(false);
        });
        state.tx_waker.wake();
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
            let n = critical_section::with(|cs| {
                let mut rx = state.rx.borrow(cs).borrow_mut();
                let mut n = 0;
                for slot in buf.iter_mut() {
                    match rx.pop_front() {
                        Some(byte) => {
                            *slot = byte;
                            n += 1;
                        }
                        None => break,
                    }
                }
                n
            });
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

impl Uart {
    /// Waits until `flag` of ISR is set, with `enable` turning on its interrupt meanwhile.
    async fn wait_for(&mut self, flag: fn(&Usart) -> bool, enable: fn(&Usart)) {
        let regs = self.regs;
        let state = self.state;
        poll_fn(|cx| {
            state.tx_waker.register(cx.waker());
            if flag(&regs) {
                Poll::Ready(())
            } else {
                enable(&regs);
                Poll::Pending
            }
        })
        .await
    }
}

impl Write for Uart {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, UartError> {
        for &byte in buf {
            self.wait_for(
                |regs| regs.isr().read().txe(),
                |regs| regs.cr1().modify(|w| w.set_txeie(true)),
            )
            .await;
            // TC would otherwise still say "done" from the previous byte: flush waits for it.
            self.regs.icr().write(|w| w.set_tc(true));
            self.regs.tdr().write(|w| w.set_dr(u16::from(byte)));
        }
        Ok(buf.len())
    }

    async fn flush(&mut self) -> Result<(), UartError> {
        self.wait_for(
            |regs| regs.isr().read().tc(),
            |regs| regs.cr1().modify(|w| w.set_tcie(true)),
        )
        .await;
        Ok(())
    }
}

impl plasma_firmware::runner::ConfigurablePort for Uart {
    fn set_port_config(
        &mut self,
        config: PortConfig,
    ) -> Result<(), plasma_firmware::runner::UnsupportedConfig> {
        self.configure(config)
            .ok_or(plasma_firmware::runner::UnsupportedConfig)
    }
}
