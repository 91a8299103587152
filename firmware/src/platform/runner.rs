//! Async glue between a sans-IO endpoint of the power-supply link and a serial port.
//!
//! The link ([`PsLink`], and the bridge that wraps it) never touches a UART: it hands out
//! whole frames, says which line settings it wants and when it needs to be polled. [`PsPort`]
//! does the rest over any [`embedded_io_async`] port and any [`Clock`], so the same code runs
//! on the board (the register-level USART driver of `plasma_tasks::uart` and embassy-time) and
//! in host tests (a fake port and a
//! virtual clock):
//!
//! - a frame is written whole and flushed before anything else happens, so the hardware
//!   driver-enable drops right after its last stop bit and the line settings never change
//!   in the middle of a frame; the end of the flush is reported to the endpoint
//!   ([`PsEndpoint::ps_transmitted`]), whose reply time-out starts there;
//! - the line settings are applied before each frame, as the endpoint reports them *after*
//!   handing out the frame (auto-detection switches parity when it starts a step);
//! - between frames it waits for received bytes, but no later than the endpoint's
//!   `poll_at` and never longer than [`MAX_WAIT`], so the caller can report progress to the
//!   watchdog even on a silent line.
//!
//! The port's `read` must be cancel-safe (bytes that arrive while nobody reads stay in its
//! buffer): the boards' driver is, since it reads from its ring buffer. A read error of kind
//! `InvalidData` is a character received with a parity, framing or noise error: it is passed
//! on in its place ([`PsEndpoint::handle_ps_rx_error`]), not taken as a failed turn. Bytes
//! already waiting are passed on before the endpoint is asked for frames, because asking it
//! also checks its reply time-out: a reply that came in time must not be taken for a
//! time-out only because the task was busy elsewhere when it arrived.

use core::future::Future;

use embedded_io_async::{Error as _, ErrorKind, Read, ReadReady, Write};
use heapless::Vec;

use crate::link::transaction::TX_CAPACITY;
use crate::link::{PsLink, SharedLine};
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};

/// The board's clock, or a simulator's.
pub trait Clock {
    /// Now.
    fn now(&self) -> Instant;
    /// Completes at `at`, at once if `at` has passed.
    fn sleep_until(&self, at: Instant) -> impl Future<Output = ()>;
}

/// The UART cannot run these line settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UnsupportedConfig;

/// A serial port whose line settings can change between frames.
pub trait ConfigurablePort: Read + ReadReady + Write {
    /// Use `config` from now on. Only called while nothing is being transmitted.
    fn set_port_config(&mut self, config: PortConfig) -> Result<(), UnsupportedConfig>;
}

/// What a driver of the power-supply port drives: the [`Bridge`](crate::bridge::Bridge) (the board's tasks, pbtool,
/// the scenario harness, the fuzz target), a bare [`PsLink`] (the link's own tests and
/// scenarios) or a [`SharedLine`] of several links. The one trait for it: a loop that moves
/// bytes between a port (a UART, a simulated line) and an endpoint is written against this,
/// whatever it runs on.
pub trait PsEndpoint {
    /// Bytes received from the supply.
    fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]);
    /// A character received with a parity, framing or noise error, in its place in the
    /// stream (the port reported it as an `InvalidData` read error).
    fn handle_ps_rx_error(&mut self, now: Instant);
    /// The next whole frame to transmit, if one is due.
    fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]>;
    /// The frame handed out last has left the wire (the port's flush returned) at `at`; its
    /// reply time-out runs from there. An endpoint without a time-out ignores it.
    fn ps_transmitted(&mut self, _at: Instant) {}
    /// The line settings the port must use now.
    fn ps_port_config(&self) -> PortConfig;
    /// When the endpoint must be polled again at the latest (`None`: only received bytes
    /// matter).
    fn poll_at(&self) -> Option<Instant>;
}

/// A link, or a line of links, is an endpoint through its own methods of the same names
/// (`handle_rx`, `poll_transmit`, ...): the one forwarding, written once for both.
macro_rules! endpoint_by_link_names {
    ($($link:ty),+) => {$(
        impl PsEndpoint for $link {
            fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]) {
                self.handle_rx(now, bytes);
            }

            fn handle_ps_rx_error(&mut self, now: Instant) {
                self.handle_rx_error(now);
            }

            fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]> {
                self.poll_transmit(now)
            }

            fn ps_transmitted(&mut self, at: Instant) {
                self.handle_transmitted(at);
            }

            fn ps_port_config(&self) -> PortConfig {
                self.port_config()
            }

            fn poll_at(&self) -> Option<Instant> {
                <$link>::poll_at(self)
            }
        }
    )+};
}

endpoint_by_link_names!(PsLink, SharedLine);

/// Longest wait in one [`Supervisor::turn`](super::supervisor::Supervisor::turn), so that a
/// task reports progress at least this often.
pub const MAX_WAIT: Duration = Duration::from_millis(100);

/// Frames written in one turn at most. The link sends one and waits for its reply; the
/// bound only keeps a misbehaving endpoint from starving the receiver.
pub const MAX_FRAMES_PER_TURN: usize = 4;

/// Bytes taken from the power-supply port per read.
pub const PS_RX_CHUNK: usize = 64;

/// What went wrong on the port.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PortError<E> {
    /// Reading failed (the bytes are lost; the link's checksums and time-outs cope).
    Read(E),
    /// Writing or flushing failed (the frame is lost; the link retries).
    Write(E),
    /// The port reported end of input.
    Closed,
    /// The port cannot use the line settings the endpoint asks for.
    Unsupported(PortConfig),
}

/// A serial port driven for a [`PsEndpoint`].
pub struct PsPort<P> {
    port: P,
    pub(super) applied: Option<PortConfig>,
    frame: Vec<u8, TX_CAPACITY>,
}

impl<P: ConfigurablePort> PsPort<P> {
    /// A port whose current settings are unknown: the first turn applies the endpoint's.
    pub fn new(port: P) -> Self {
        PsPort {
            port,
            applied: None,
            frame: Vec::new(),
        }
    }

    fn apply(&mut self, config: PortConfig) -> Result<bool, PortError<P::Error>> {
        if self.applied == Some(config) {
            return Ok(false);
        }
        self.port
            .set_port_config(config)
            .map_err(|UnsupportedConfig| PortError::Unsupported(config))?;
        self.applied = Some(config);
        Ok(true)
    }

    /// Transmits every frame the endpoint has now, each with the line settings it asks for,
    /// written whole and flushed. Returns the number of frames and the settings applied if
    /// they changed.
    pub async fn transmit<E: PsEndpoint + ?Sized>(
        &mut self,
        endpoint: &mut E,
        clock: &impl Clock,
    ) -> Result<(usize, Option<PortConfig>), PortError<P::Error>> {
        self.drain_ready(endpoint, clock).await?;
        let mut changed = None;
        let mut sent = 0;
        while sent < MAX_FRAMES_PER_TURN {
            let Some(frame) = endpoint.poll_ps_transmit(clock.now()) else {
                break;
            };
            // Copied out so the endpoint can be asked for the settings that go with it.
            self.frame.clear();
            if self.frame.extend_from_slice(frame).is_err() {
                // Longer than any frame the link builds; nothing sensible to send.
                continue;
            }
            let config = endpoint.ps_port_config();
            if self.apply(config)? {
                changed = Some(config);
            }
            self.port
                .write_all(&self.frame)
                .await
                .map_err(PortError::Write)?;
            // The flush returns once the last stop bit has left (TC): the reply time-out
            // starts now, not when the frame was handed to the UART.
            self.port.flush().await.map_err(PortError::Write)?;
            endpoint.ps_transmitted(clock.now());
            sent += 1;
        }
        // Listen with the settings the endpoint expects its next reply in.
        let config = endpoint.ps_port_config();
        if self.apply(config)? {
            changed = Some(config);
        }
        Ok((sent, changed))
    }

    /// Reads what the port has (waits for at least one byte; cancel-safe if the port is).
    pub async fn read(&mut self, buf: &mut [u8]) -> Result<usize, PortError<P::Error>> {
        match self.port.read(buf).await {
            Ok(0) => Err(PortError::Closed),
            Ok(n) => Ok(n),
            Err(e) => Err(PortError::Read(e)),
        }
    }

    /// Passes every byte already waiting in the port to the endpoint, without waiting.
    pub async fn drain_ready<E: PsEndpoint + ?Sized>(
        &mut self,
        endpoint: &mut E,
        clock: &impl Clock,
    ) -> Result<usize, PortError<P::Error>> {
        let mut total = 0;
        let mut buf = [0u8; PS_RX_CHUNK];
        while self.port.read_ready().map_err(PortError::Read)? {
            let received = self.read(&mut buf).await;
            total += self.hand_over(endpoint, clock, received, &buf)?;
        }
        Ok(total)
    }

    /// Passes a read's outcome to the endpoint: the bytes, or a character received in error
    /// (a read error of kind `InvalidData`: parity, framing, noise) in its place in the
    /// stream. Returns the characters passed on; any other error ends the turn.
    fn hand_over<E: PsEndpoint + ?Sized>(
        &mut self,
        endpoint: &mut E,
        clock: &impl Clock,
        received: Result<usize, PortError<P::Error>>,
        buf: &[u8],
    ) -> Result<usize, PortError<P::Error>> {
        match received {
            Ok(n) => {
                endpoint.handle_ps_rx(clock.now(), buf.get(..n).unwrap_or(buf));
                Ok(n)
            }
            Err(PortError::Read(e)) if e.kind() == ErrorKind::InvalidData => {
                endpoint.handle_ps_rx_error(clock.now());
                Ok(1)
            }
            Err(e) => Err(e),
        }
    }
}

#[cfg(test)]
mod tests;
