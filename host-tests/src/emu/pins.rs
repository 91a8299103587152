//! The emulated board's pin map (docs/board.md, the same as the Nucleo-L476RG board): which
//! GPIO port and pin carries each discrete signal, and how QEMU names and maps them.
//!
//! Inputs are active LOW with pull-ups (an opto-coupler pulls the pin down when the signal is
//! on); outputs are active HIGH.

use plasma_firmware::io::{Input, Output};

/// A GPIO port of the STM32L475 that the board uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Port {
    /// GPIOA.
    A,
    /// GPIOB.
    B,
    /// GPIOC.
    C,
}

impl Port {
    /// The port's QOM path, as qtest's `set_irq_in` and `irq_intercept_out` name it.
    pub const fn qom_path(self) -> &'static str {
        match self {
            Port::A => "/machine/soc/gpioa",
            Port::B => "/machine/soc/gpiob",
            Port::C => "/machine/soc/gpioc",
        }
    }

    /// Address of the port's output data register (ODR, offset 0x14).
    pub const fn odr_address(self) -> u64 {
        self.base() + 0x14
    }

    /// Address of the port's input data register (IDR, offset 0x10).
    pub const fn idr_address(self) -> u64 {
        self.base() + 0x10
    }

    const fn base(self) -> u64 {
        match self {
            Port::A => 0x4800_0000,
            Port::B => 0x4800_0400,
            Port::C => 0x4800_0800,
        }
    }
}

/// A pin: port and number (0-15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Pin {
    /// The port.
    pub port: Port,
    /// The pin number within the port.
    pub number: u8,
}

impl Pin {
    const fn new(port: Port, number: u8) -> Pin {
        Pin { port, number }
    }

    /// This pin's bit in a port register.
    pub const fn mask(self) -> u32 {
        1 << self.number
    }
}

impl core::fmt::Display for Pin {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let port = match self.port {
            Port::A => 'A',
            Port::B => 'B',
            Port::C => 'C',
        };
        write!(f, "P{port}{}", self.number)
    }
}

/// The pin of a discrete input.
pub const fn input_pin(input: Input) -> Pin {
    match input {
        Input::TorchOn => Pin::new(Port::A, 0),
        Input::Motion => Pin::new(Port::A, 1),
        Input::Hold => Pin::new(Port::A, 4),
        Input::PierceComplete => Pin::new(Port::A, 6),
        Input::CornerCurrent => Pin::new(Port::A, 7),
        Input::NotReady => Pin::new(Port::A, 8),
        Input::RampdownError => Pin::new(Port::B, 10),
    }
}

/// The pin of a discrete output.
pub const fn output_pin(output: Output) -> Pin {
    match output {
        Output::Start => Pin::new(Port::B, 0),
        Output::Hold => Pin::new(Port::C, 1),
        Output::PierceComplete => Pin::new(Port::C, 0),
        Output::CornerCurrent => Pin::new(Port::B, 8),
        Output::ArcOk => Pin::new(Port::B, 9),
        Output::Ready => Pin::new(Port::B, 6),
        Output::Fault => Pin::new(Port::C, 7),
    }
}

/// The green heartbeat LED (LD2).
pub const HEARTBEAT_LED: Pin = Pin::new(Port::A, 5);

/// The level to drive on an input pin for a signal that is `active` (inputs are active low).
pub const fn input_level(active: bool) -> bool {
    !active
}

/// The signal read back from an output pin's level (outputs are active high).
pub const fn output_active(level: bool) -> bool {
    level
}

/// The port whose output edges the harness streams with qtest's `irq_intercept_out`: START,
/// ARC_OK, READY and PS_CORNER_CURRENT. Intercepting detaches the port from EXTI, so it must
/// hold outputs only; GPIOA (TORCH_ON, MOTION) must never be intercepted.
pub const WATCHED_PORT: Port = Port::B;

/// The inputs on the watched port (their EXTI is detached while it is watched).
pub fn watched_port_inputs() -> impl Iterator<Item = Input> {
    Input::ALL
        .into_iter()
        .filter(|&i| input_pin(i).port == WATCHED_PORT)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pins_match_the_board_map() {
        assert_eq!(input_pin(Input::TorchOn).to_string(), "PA0");
        assert_eq!(input_pin(Input::RampdownError).to_string(), "PB10");
        assert_eq!(output_pin(Output::Start).to_string(), "PB0");
        assert_eq!(output_pin(Output::Fault).to_string(), "PC7");
        assert_eq!(Port::B.odr_address(), 0x4800_0414);
        assert_eq!(Port::C.odr_address(), 0x4800_0814);
        assert_eq!(output_pin(Output::ArcOk).mask(), 1 << 9);
    }

    #[test]
    fn no_two_signals_share_a_pin() {
        let mut pins: Vec<Pin> = Input::ALL.into_iter().map(input_pin).collect();
        pins.extend(Output::ALL.into_iter().map(output_pin));
        pins.push(HEARTBEAT_LED);
        let count = pins.len();
        pins.sort_by_key(|p| (p.port as u8, p.number));
        pins.dedup();
        assert_eq!(pins.len(), count);
    }

    #[test]
    fn the_watched_port_holds_start_and_arc_ok_and_no_torch_input() {
        assert_eq!(output_pin(Output::Start).port, WATCHED_PORT);
        assert_eq!(output_pin(Output::ArcOk).port, WATCHED_PORT);
        assert!(watched_port_inputs().all(|i| i == Input::RampdownError));
    }
}
