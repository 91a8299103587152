//! Where every output is (docs/board.md), and the register-level safe state used before any
//! driver exists and from the fault handlers. The same on both boards: the STM32L476RG and the
//! emulated STM32L475VG have the same GPIO ports and registers.

use plasma_firmware::safe_state::{Output as Signal, SAFE_OUTPUTS};

use crate::board::pac;
use crate::board::pac::gpio::{Gpio, vals::Moder};

/// Where each output is. All are active high at the MCU pin, with an external pull-down so
/// they are off while the pin is still high-impedance after reset.
pub const fn output_pin(signal: Signal) -> (Gpio, usize) {
    match signal {
        Signal::Start => (pac::GPIOB, 0),
        Signal::PsHold => (pac::GPIOC, 1),
        Signal::PsPierceComplete => (pac::GPIOC, 0),
        Signal::PsCornerCurrent => (pac::GPIOB, 8),
        Signal::CncArcOk => (pac::GPIOB, 9),
        Signal::CncReady => (pac::GPIOB, 6),
        Signal::CncFault => (pac::GPIOC, 7),
    }
}

/// Drives every output to its safe level with plain register writes: usable before the HAL
/// exists, and from the panic and fault handlers while tasks own the pins.
pub fn drive_safe_state() {
    pac::RCC.ahb2enr().modify(|w| {
        w.set_gpioben(true);
        w.set_gpiocen(true);
    });
    for (signal, on) in SAFE_OUTPUTS.levels() {
        let (port, pin) = output_pin(signal);
        // Level first, then output mode: the pin never drives the wrong level.
        port.bsrr().write(|w| {
            if on {
                w.set_bs(pin, true)
            } else {
                w.set_br(pin, true)
            }
        });
        port.moder().modify(|w| w.set_moder(pin, Moder::OUTPUT));
    }
}
