//! How a [`World`](super::World) is built.

use plasma_firmware::io::IoConfig;
use plasma_firmware::link::LinkConfig;

use plasma_sim::SimOptions;
use plasma_sim::line::Wiring;

/// What the bridge's UART does with a character the line delivers with a parity or framing
/// error flag.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RxErrors {
    /// Tell the endpoint ([`PsLink::handle_rx_error`](plasma_firmware::link::PsLink::handle_rx_error)),
    /// in its place among the characters: what the board glue does with its UART's error
    /// flags. The default.
    #[default]
    Report,
    /// Hand it to the endpoint like any other character (a UART driver that ignores its
    /// error flags: only the frame checksum can catch the damage).
    Deliver,
    /// Drop it (a UART driver that discards flagged characters).
    Drop,
    /// Hand over a NUL instead: a character no frame may contain, so the frame it falls in
    /// is rejected whatever its checksum says (a board glue that breaks the frame itself).
    Substitute,
}

/// Everything that makes one [`World`](super::World).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldOptions {
    /// Seed of the line's fault-injection PRNG.
    pub seed: u64,
    /// The link's configuration (a bare `PsLink` endpoint is built from it).
    pub link: LinkConfig,
    /// Simulator options (address, HPR id, gas console, its own seed).
    pub sim: SimOptions,
    /// Discrete I/O settings.
    pub io: IoConfig,
    /// 2-wire or 4-wire.
    pub wiring: Wiring,
    /// Probability that a character gets a random bit flipped.
    pub corrupt_probability: f64,
    /// Probability that a character is lost.
    pub drop_probability: f64,
    /// Spurious characters per character time during a noise burst (`None`: line default).
    pub noise_density: Option<f64>,
    /// Characters flagged by the UART.
    pub rx_errors: RxErrors,
}

impl Default for WorldOptions {
    fn default() -> Self {
        WorldOptions {
            seed: 1,
            link: LinkConfig::default(),
            sim: SimOptions::default(),
            io: IoConfig::default(),
            wiring: Wiring::FourWire,
            corrupt_probability: 0.0,
            drop_probability: 0.0,
            noise_density: None,
            rx_errors: RxErrors::Report,
        }
    }
}

impl WorldOptions {
    /// Defaults with `link` as the link configuration.
    pub fn with_link(link: LinkConfig) -> Self {
        WorldOptions {
            link,
            ..Self::default()
        }
    }
}
