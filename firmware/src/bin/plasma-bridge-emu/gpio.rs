//! The discrete pins by register: inputs with pull-ups on EXTI lines, push-pull outputs, the
//! LED. Same pins as the Nucleo (docs/board.md); QEMU's GPIO, SYSCFG and EXTI models carry
//! an edge driven from its qtest socket to the EXTI interrupt.

use core::future::poll_fn;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::Poll;

use cortex_m::peripheral::NVIC;
use embassy_sync::waitqueue::AtomicWaker;
use plasma_firmware::inputs::{InputConfig, PinLevels, Pull};
use plasma_firmware::io::{Input, Outputs};
use stm32_metapac::gpio::Gpio;
use stm32_metapac::gpio::vals::{Moder, Pupdr};
use stm32_metapac::{EXTI, GPIOA, GPIOB, Interrupt, SYSCFG, interrupt};

use crate::probe;

/// Where each input is: port, port index for SYSCFG_EXTICR (A = 0), pin (= EXTI line).
const fn input_pin(input: Input) -> (Gpio, u8, usize) {
    match input {
        Input::TorchOn => (GPIOA, 0, 0),
        Input::Motion => (GPIOA, 0, 1),
        Input::Hold => (GPIOA, 0, 4),
        Input::PierceComplete => (GPIOA, 0, 6),
        Input::CornerCurrent => (GPIOA, 0, 7),
        Input::NotReady => (GPIOA, 0, 8),
        Input::RampdownError => (GPIOB, 1, 10),
    }
}

/// The EXTI line of TORCH_ON, whose edges the latency probe stamps.
const TORCH_ON_LINE: usize = input_pin(Input::TorchOn).2;

/// The interrupts of the input lines: 0, 1, 4, 5-9, 10-15.
const EXTI_IRQS: [Interrupt; 5] = [
    Interrupt::EXTI0,
    Interrupt::EXTI1,
    Interrupt::EXTI4,
    Interrupt::EXTI9_5,
    Interrupt::EXTI15_10,
];

/// The seven inputs, owned by the I/O task.
pub struct InputPins(());

/// An edge on some input since the I/O task last looked.
static EDGE: AtomicBool = AtomicBool::new(false);
static EDGE_WAKER: AtomicWaker = AtomicWaker::new();

impl InputPins {
    /// Inputs with the pull that reads inactive when open, both edges on their EXTI lines,
    /// the EXTI interrupts at the highest priority (as on the Nucleo: they only wake the I/O
    /// task).
    pub fn new(config: &InputConfig) -> Self {
        for input in Input::ALL {
            let (port, port_index, pin) = input_pin(input);
            let pull = match config.get(input).polarity.pull() {
                Pull::Up => Pupdr::PULL_UP,
                Pull::Down => Pupdr::PULL_DOWN,
            };
            port.pupdr().modify(|w| w.set_pupdr(pin, pull));
            port.moder().modify(|w| w.set_moder(pin, Moder::INPUT));
            SYSCFG
                .exticr(pin / 4)
                .modify(|w| w.set_exti(pin % 4, port_index));
            EXTI.rtsr(0).modify(|w| w.set_line(pin, true));
            EXTI.ftsr(0).modify(|w| w.set_line(pin, true));
            EXTI.imr(0).modify(|w| w.set_line(pin, true));
        }
        let mut nvic = unsafe { cortex_m::Peripherals::steal() }.NVIC;
        for irq in EXTI_IRQS {
            // SAFETY: the handlers below only touch atomics and the EXTI pending register.
            unsafe {
                nvic.set_priority(irq, 0);
                NVIC::unmask(irq);
            }
        }
        InputPins(())
    }

    /// Reads every pin now.
    pub fn levels(&self) -> PinLevels {
        Input::ALL
            .iter()
            .fold(PinLevels::ALL_LOW, |levels, &input| {
                let (port, _, pin) = input_pin(input);
                levels.with(
                    input,
                    port.idr().read().idr(pin) == stm32_metapac::gpio::vals::Idr::HIGH,
                )
            })
    }

    /// Completes on the next edge of any input (a bounce included: the caller reads levels).
    pub async fn any_edge(&mut self) {
        poll_fn(|cx| {
            EDGE_WAKER.register(cx.waker());
            if EDGE.swap(false, Ordering::AcqRel) {
                Poll::Ready(())
            } else {
                Poll::Pending
            }
        })
        .await
    }
}

/// Every input EXTI interrupt: clear what is pending, stamp TORCH_ON for the probe, wake the
/// I/O task.
fn on_exti() {
    let pending = EXTI.pr(0).read();
    // Write-1-to-clear, only the lines that were seen.
    EXTI.pr(0).write_value(pending);
    if pending.line(TORCH_ON_LINE) {
        probe::torch_on_edge();
    }
    EDGE.store(true, Ordering::Release);
    EDGE_WAKER.wake();
}

#[interrupt]
fn EXTI0() {
    on_exti();
}

#[interrupt]
fn EXTI1() {
    on_exti();
}

#[interrupt]
fn EXTI4() {
    on_exti();
}

#[interrupt]
fn EXTI9_5() {
    on_exti();
}

#[interrupt]
fn EXTI15_10() {
    on_exti();
}

/// Sets pin `pin` of `port` high or low in one write.
fn set(port: Gpio, pin: usize, high: bool) {
    port.bsrr().write(|w| {
        if high {
            w.set_bs(pin, true)
        } else {
            w.set_br(pin, true)
        }
    });
}

/// The seven outputs, owned by the I/O task. `pin_map::drive_safe_state` made them outputs,
/// all off, before anything else ran.
pub struct OutputPins {
    start: bool,
}

impl OutputPins {
    /// The outputs as the safe state left them.
    pub fn new() -> Self {
        OutputPins { start: false }
    }

    /// Sets every pin to `outputs` (all active high). START first: its latency matters.
    pub fn drive(&mut self, outputs: Outputs) {
        use crate::tasks::pin_map::output_pin;
        use plasma_firmware::safe_state::Output as Signal;
        let levels = [
            (Signal::Start, outputs.start),
            (Signal::PsHold, outputs.hold),
            (Signal::PsPierceComplete, outputs.pierce_complete),
            (Signal::PsCornerCurrent, outputs.corner_current),
            (Signal::CncArcOk, outputs.arc_ok),
            (Signal::CncReady, outputs.ready),
            (Signal::CncFault, outputs.fault),
        ];
        for (signal, on) in levels {
            let (port, pin) = output_pin(signal);
            set(port, pin, on);
        }
        if outputs.start != self.start {
            self.start = outputs.start;
            probe::start_changed(outputs.start);
        }
    }
}

/// The heartbeat LED (LD1 on the B-L475E-IOT01A is PA5, as LD2 on the Nucleo).
pub struct Led {
    on: bool,
}

impl Led {
    /// PA5, output, off.
    pub fn new() -> Self {
        set(GPIOA, 5, false);
        GPIOA.moder().modify(|w| w.set_moder(5, Moder::OUTPUT));
        Led { on: false }
    }

    /// On ↔ off.
    pub fn toggle(&mut self) {
        self.on = !self.on;
        set(GPIOA, 5, self.on);
    }
}
