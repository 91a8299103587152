//! Formatting done before logging.
//!
//! defmt-rtt holds a critical section (all interrupts masked, EXTI0 included) while a log
//! frame is written. `defmt::Debug2Format` would run `core::fmt` inside it; formatting into a
//! buffer first keeps the masked time to a copy.

use core::fmt::{Debug, Write};

use heapless::String;

/// `value`'s Debug text, cut at 160 bytes.
pub fn debug<T: Debug>(value: &T) -> String<160> {
    let mut text = String::new();
    // On overflow the text is simply cut.
    let _ = write!(text, "{value:?}");
    text
}
