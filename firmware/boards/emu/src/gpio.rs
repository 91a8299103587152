//! The discrete pins by register: inputs with pull-ups on EXTI lines, push-pull outputs, the
//! LED, all placed by the one pin table (`plasma_firmware::platform::pins`, the Nucleo's). QEMU's GPIO,
//! SYSCFG and EXTI models carry an edge driven from its qtest socket to the EXTI interrupt.

use cortex_m::peripheral::NVIC;
use plasma_firmware::io::{self, Input, InputConfig, Outputs, PinLevels, Pull};
use plasma_firmware::platform::pins::{self, Pin, Port, UnitSet};
use stm32_metapac::gpio::Gpio;
use stm32_metapac::gpio::vals::{Idr, Moder, Pupdr};
use stm32_metapac::{GPIOA, GPIOB, GPIOC, Interrupt, interrupt};

use crate::probe;

/// The register block of a port of the table.
pub const fn gpio(port: Port) -> Gpio {
    match port {
        Port::A => GPIOA,
        Port::B => GPIOB,
        Port::C => GPIOC,
    }
}

/// The EXTI line of the first unit's TORCH_ON, whose edges the latency probe stamps.
const TORCH_ON_LINE: usize = pins::input(Input::TorchOn).pin.number as usize;

/// The interrupt of EXTI line `line`.
const fn exti_irq(line: u8) -> Interrupt {
    match line {
        0 => Interrupt::EXTI0,
        1 => Interrupt::EXTI1,
        2 => Interrupt::EXTI2,
        3 => Interrupt::EXTI3,
        4 => Interrupt::EXTI4,
        5..=9 => Interrupt::EXTI9_5,
        _ => Interrupt::EXTI15_10,
    }
}

/// The interrupts of the input lines; the handlers below exist for these only.
const EXTI_IRQS: [Interrupt; 7] = [
    Interrupt::EXTI0,
    Interrupt::EXTI1,
    Interrupt::EXTI2,
    Interrupt::EXTI3,
    Interrupt::EXTI4,
    Interrupt::EXTI9_5,
    Interrupt::EXTI15_10,
];

// Every armed input's line (every unit set's) must raise one of the interrupts handled here.
const _: () = {
    let mut i = 0;
    while i < pins::EDGE_INPUTS.len() {
        let irq = exti_irq(pins::EDGE_INPUTS[i].number) as u16;
        let mut handled = false;
        let mut j = 0;
        while j < EXTI_IRQS.len() {
            handled |= EXTI_IRQS[j] as u16 == irq;
            j += 1;
        }
        assert!(
            handled,
            "an input's EXTI interrupt has no handler in gpio.rs"
        );
        i += 1;
    }
};

/// Every unit set's eight inputs, owned by the I/O task.
pub struct InputPins(());

impl InputPins {
    /// Inputs with the pull that reads inactive when open, both edges on their EXTI lines
    /// (armed for good by `plasma_tasks::edges`),
    /// the EXTI interrupts at the highest priority (as on the Nucleo: they only wake the I/O
    /// task).
    pub fn new(config: &InputConfig) -> Self {
        let every_input = UnitSet::ALL
            .into_iter()
            .flat_map(|set| Input::ALL.map(|input| (set.input(input).pin, input)));
        for (Pin { port, number }, input) in every_input {
            let (pin, port) = (number as usize, gpio(port));
            let pull = match config.get(input).polarity.pull() {
                Pull::Up => Pupdr::PULL_UP,
                Pull::Down => Pupdr::PULL_DOWN,
            };
            port.pupdr().modify(|w| w.set_pupdr(pin, pull));
            port.moder().modify(|w| w.set_moder(pin, Moder::INPUT));
        }
        plasma_tasks::edges::arm_inputs();
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
}

impl plasma_tasks::board::InputPins for InputPins {
    fn levels(&self, set: UnitSet) -> PinLevels {
        Input::ALL
            .iter()
            .fold(PinLevels::ALL_LOW, |levels, &input| {
                let pin = set.input(input).pin;
                let high = gpio(pin.port).idr().read().idr(pin.number as usize) == Idr::HIGH;
                levels.with(input, high)
            })
    }
}

/// Every input EXTI interrupt: the shared body (clear, note the edge for the I/O task), and
/// TORCH_ON's edge stamped for the probe.
fn on_exti() {
    let pending = plasma_tasks::edges::on_interrupt();
    if pending & (1 << TORCH_ON_LINE) != 0 {
        probe::torch_on_edge();
    }
    #[cfg(feature = "test-hooks")]
    crate::test_hooks::on_edges(pending);
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
fn EXTI2() {
    on_exti();
}

#[interrupt]
fn EXTI3() {
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

/// Sets `pin` high or low in one write.
fn set(pin: Pin, high: bool) {
    let (port, pin) = (gpio(pin.port), pin.number as usize);
    port.bsrr().write(|w| {
        if high {
            w.set_bs(pin, true)
        } else {
            w.set_br(pin, true)
        }
    });
}

/// Every unit set's eight outputs, owned by the I/O task.
/// `plasma_tasks::safe_state::drive_safe_state` made them outputs, all off, before anything
/// else ran.
pub struct OutputPins {
    start: bool,
}

impl OutputPins {
    /// The outputs as the safe state left them.
    pub fn new() -> Self {
        OutputPins { start: false }
    }
}

impl plasma_tasks::board::OutputPins for OutputPins {
    fn drive(&mut self, unit: UnitSet, outputs: Outputs) {
        for (output, wiring) in io::Output::ALL.into_iter().zip(unit.outputs()) {
            set(wiring.pin, wiring.level(outputs.get(output)));
        }
        // The probe times the first unit's TORCH_ON to START.
        if unit.index() == 0 && outputs.start != self.start {
            self.start = outputs.start;
            probe::start_changed(outputs.start);
        }
    }
}

/// The heartbeat LED (`plasma_firmware::platform::pins::HEARTBEAT_LED`).
pub struct Led {
    on: bool,
}

impl Led {
    /// The LED's pin, output, off.
    pub fn new() -> Self {
        let pin = pins::HEARTBEAT_LED.pin;
        set(pin, pins::HEARTBEAT_LED.level(false));
        gpio(pin.port)
            .moder()
            .modify(|w| w.set_moder(pin.number as usize, Moder::OUTPUT));
        Led { on: false }
    }
}

impl plasma_tasks::board::Led for Led {
    fn toggle(&mut self) {
        self.on = !self.on;
        set(pins::HEARTBEAT_LED.pin, pins::HEARTBEAT_LED.level(self.on));
    }
}
