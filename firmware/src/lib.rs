//! The bridge's behaviour, free of any HAL: built and tested on the host.
//!
//! Every piece is a sans-IO state machine that takes `now` and events and returns actions, so
//! the board layers (firmware/boards/) and the host simulators drive exactly the same code.
//!
//! - [`bridge`]: the façade the board and the host harness drive: link, CNC session and
//!   settings behind one sans-IO object.
//! - [`cnc`]: the CNC side: the text protocol, Phoenix serial messaging, the Powermax-speaking
//!   port and the one command table.
//! - [`settings`]: what survives a power cycle, and the `CONFIG` keys.
//! - [`consumables`]: consumable life, one record per set, kept across power cycles.
//! - [`link`]: the power-supply link (Modbus ASCII and HPR).
//! - [`io`]: all of the torch-safe discrete I/O: the CNC's wiring (input polarity and
//!   debounce, output levels), the START interlocks, ARC_OK, READY, FAULT, the board's
//!   [`io::DiscreteIo`] and the independent [`io::SafetyMonitor`] used by every scenario test.
//! - [`storage`]: power-cut-safe settings storage, as logic.
//! - [`platform`]: the async loops around the link and the bridge over any
//!   `embedded-io-async` UART and clock ([`platform::PsEndpoint`] is what they drive), and the
//!   board-facing policy: watchdog feeding, the reset/panic safe state, the pin map.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// Input from the CNC or the power supply must never panic the bridge.
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::unreachable,
        clippy::indexing_slicing
    )
)]

/// Texts for logs, written once: `as_str` (host displays and traces) and, with `defmt`, a
/// `defmt::Format` that logs the same text as an interned string. The board image then keeps
/// only an index: the text lives in the ELF's `.defmt` section for the host decoder, not in
/// flash. A `delegate` arm hands a variant that wraps another such type to that type.
macro_rules! log_texts {
    (
        $ty:ident $(, delegate $delegate:pat => $inner:ident)? {
            $($variant:pat => $text:literal,)*
        }
    ) => {
        impl $ty {
            /// Text for logs.
            pub const fn as_str(self) -> &'static str {
                match self {
                    $($delegate => $inner.as_str(),)?
                    $($variant => $text,)*
                }
            }
        }

        #[cfg(feature = "defmt")]
        impl defmt::Format for $ty {
            fn format(&self, f: defmt::Formatter<'_>) {
                match *self {
                    $($delegate => defmt::Format::format(&$inner, f),)?
                    $($variant => defmt::write!(f, $text),)*
                }
            }
        }
    };
}

pub mod bridge;
mod cnc;
pub mod consumables;
pub mod io;
pub mod link;
pub mod platform;
/// The CNC-visible texts of the ERR replies, written once: tests take them from here.
pub use cnc::texts;
pub mod settings;
pub mod storage;

#[cfg(test)]
mod testing;
