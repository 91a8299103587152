//! `pbtool run --ps-port DEV`: the bridge, the same firmware library the board runs, in real
//! time on a PC whose serial adapter is wired to the power supply.
//!
//! [`LineBridge`] is what the board's tasks are around the [`Bridge`]: the PS port (its
//! framing follows the link, 8E1/8O1/8N1 and two stop bits while detecting, 8N1 for an HPR;
//! flagged characters counted as the link counts them), the CNC port, the settings store
//! (in memory, or with [`LineBridge::keep_flash`] in a file: restarting is a power cycle of
//! the board), and the interlocks, which a PC has no pins
//! for but which still decide READY and the STATUS fields. The CNC side is a console
//! ([`run_console`]: stdin/stdout, paced like `pbtool sim`) or a second serial port
//! ([`run_cnc_port`]: the bytes as they are).

mod console;

pub use console::{FirstCommand, SETTLE_TIMEOUT, run_console};

use std::io;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Receiver;

use host_tests::harness::{BridgeEndpoint, WorldEndpoint};
use plasma_firmware::bridge::Bridge;
use plasma_firmware::io::{Inputs, Interlocks, SupplyState};
use plasma_firmware::platform::PsEndpoint;
use plasma_firmware::settings::Settings;
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant, earliest};

use crate::realtime::{Arrival, Clock, wait};
use crate::serial::{Port, Rx, SerialError};

/// When the last stop bit of `len` characters at `config`, handed to the OS at `handed_over`,
/// leaves the PC's UART: the reply time-out runs from there, as on the board (whose UART says
/// so, TC). A PC's driver sends from its buffer after `write` returns, so it is the frame's wire
/// time after the hand-over, and not before the write returned (`written`: a full buffer
/// blocks it). Computed rather than waited for: `tcdrain` has no time-out and a stuck adapter
/// would hang the bridge in it.
fn end_of_transmission(
    handed_over: Instant,
    written: Instant,
    config: PortConfig,
    len: usize,
) -> Instant {
    let wire_ns = config.char_time_ns().saturating_mul(len as u64);
    (handed_over + Duration::from_micros(wire_ns.div_ceil(1_000))).max(written)
}

/// How often the flash is written to its file when it changed (a run stopped with Ctrl-C
/// loses at most this much).
pub const FLASH_FILE_EVERY: Duration = Duration::from_secs(1);

/// The file that keeps the bridge's flash (`--flash FILE`), and what it holds.
struct FlashFile {
    path: PathBuf,
    written: Vec<u8>,
    next_write: Instant,
}

/// The bridge with its PS port, in real time.
pub struct LineBridge {
    endpoint: BridgeEndpoint,
    io: Interlocks,
    supply: SupplyState,
    ps: Port,
    clock: Clock,
    flash_file: Option<FlashFile>,
}

impl LineBridge {
    /// The bridge with `settings` on `ps` (its writing handle; a reader thread has the other).
    pub fn new(settings: Settings, mut ps: Port, clock: Clock) -> Result<Self, SerialError> {
        let now = clock.now();
        let endpoint = BridgeEndpoint::new(settings, now, false);
        ps.set_config(endpoint.bridge().ps_port_config())?;
        Ok(LineBridge {
            io: Interlocks::new(settings.io, now, Inputs::default()),
            endpoint,
            supply: SupplyState::default(),
            ps,
            clock,
            flash_file: None,
        })
    }

    /// Keeps the bridge's flash (stored settings and history) in the file at `path`: when
    /// it exists, the bridge boots from it as the board does after a power cycle (stored
    /// settings, a new boot in the history); from then on it is written every
    /// [`FLASH_FILE_EVERY`] that it changed ([`LineBridge::write_flash`]).
    pub fn keep_flash(&mut self, path: &Path) -> Result<(), String> {
        let written = match std::fs::read(path) {
            Ok(image) => {
                self.endpoint.load_flash_image(&image)?;
                let now = self.clock.now();
                self.endpoint.power_cycle(now);
                self.io = Interlocks::new(self.bridge().settings().io, now, Inputs::default());
                self.supply = SupplyState::default();
                let config = self.endpoint.bridge().ps_port_config();
                self.ps.set_config(config).map_err(|e| e.to_string())?;
                image
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(e.to_string()),
        };
        self.flash_file = Some(FlashFile {
            path: path.to_path_buf(),
            written,
            next_write: self.clock.now(),
        });
        Ok(())
    }

    /// Writes the flash to its file (see [`LineBridge::keep_flash`]) if it changed since the
    /// last write; `force` writes now, else only once [`FLASH_FILE_EVERY`] has passed.
    pub fn write_flash(&mut self, now: Instant, force: bool) -> io::Result<()> {
        let due = self
            .flash_file
            .as_ref()
            .is_some_and(|file| force || now >= file.next_write);
        if !due {
            return Ok(());
        }
        let image = self.endpoint.flash_image();
        let Some(file) = &mut self.flash_file else {
            return Ok(());
        };
        file.next_write = now + FLASH_FILE_EVERY;
        if image != file.written {
            std::fs::write(&file.path, &image).map_err(|e| {
                io::Error::new(e.kind(), format!("--flash {}: {e}", file.path.display()))
            })?;
            file.written = image;
        }
        Ok(())
    }

    /// Sets the bridge's wall clock to `unix_seconds`, as `CLOCK` from a CNC would; returns
    /// its reply. The console and the CNC port show what the bridge writes after it.
    pub fn set_clock(&mut self, unix_seconds: u32) -> Result<String, SerialError> {
        let now = self.clock.now();
        let before = self.cnc_records().len();
        let line = format!("{}\r\n", crate::history::clock_command(unix_seconds));
        self.endpoint.cnc_rx(now, line.as_bytes());
        self.service(now)?;
        Ok(self.cnc_records()[before..]
            .iter()
            .filter_map(|r| r.item.line())
            .find(|l| host_tests::harness::is_reply_line(l))
            .unwrap_or("no reply")
            .to_string())
    }

    /// The bridge (read only).
    pub fn bridge(&self) -> &Bridge {
        self.endpoint.bridge()
    }

    /// Everything the bridge wrote to the CNC, split into lines, ACK and NAK.
    pub fn cnc_records(&self) -> &[host_tests::harness::CncRecord] {
        self.endpoint.records()
    }

    /// Every byte the bridge wrote to the CNC.
    pub fn cnc_bytes(&self) -> &[u8] {
        self.endpoint.raw()
    }

    /// Reply lines (not events, not ACK/NAK) so far.
    pub fn reply_count(&self) -> usize {
        self.cnc_records()
            .iter()
            .filter(|r| r.item.is_reply())
            .count()
    }

    /// Characters from the power supply.
    pub fn ps_rx(&mut self, now: Instant, rx: &[Rx]) {
        let mut good = Vec::with_capacity(rx.len());
        for &item in rx {
            match item {
                Rx::Byte(b) => good.push(b),
                Rx::Error => {
                    // In its place among the characters, as the board's UART reports it.
                    self.endpoint.handle_ps_rx(now, &std::mem::take(&mut good));
                    self.endpoint.handle_ps_rx_error(now);
                }
            }
        }
        self.endpoint.handle_ps_rx(now, &good);
    }

    /// Bytes from the CNC.
    pub fn cnc_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.endpoint.cnc_rx(now, bytes);
    }

    /// Everything due at `now`: link events into the session, frames to the unit (the port
    /// switched to the framing the link asks for first), the interlocks.
    pub fn service(&mut self, now: Instant) -> Result<(), SerialError> {
        // Asking for a frame polls the bridge; the poll after the frames takes what they
        // raised and the bridge's CNC output.
        while let Some(frame) = self.endpoint.poll_ps_transmit(now).map(<[u8]>::to_vec) {
            let config = self.endpoint.ps_port_config();
            self.ps.set_config(config)?;
            let handed_over = self.clock.now();
            self.ps.write_all(&frame)?;
            let end = end_of_transmission(handed_over, self.clock.now(), config, frame.len());
            self.endpoint.ps_transmitted(end);
        }
        self.endpoint.poll(now, &mut Vec::new());
        if let Some(config) = self.endpoint.take_io_config_change() {
            self.io.set_config(now, config);
        }
        // The PC has no discrete I/O of its own: one set, the first unit's.
        let supply = self.endpoint.supply_state_of(0);
        if supply != self.supply {
            self.io.on_supply(now, supply);
            self.supply = supply;
        }
        self.io.poll(now);
        while self.io.poll_transition().is_some() {}
        while let Some(event) = self.io.poll_event() {
            self.endpoint.on_io_event_of(0, now, event);
        }
        self.endpoint
            .set_io_snapshot_of(0, self.io.inputs(), self.io.outputs());
        Ok(())
    }

    /// When [`LineBridge::service`] is next due.
    pub fn wake(&self) -> Option<Instant> {
        earliest(self.endpoint.poll_at(), self.io.poll_at())
    }

    /// Now, on the bridge's clock.
    pub fn now(&self) -> Instant {
        self.clock.now()
    }
}

/// How a run ended other than by the end of input.
#[derive(Debug)]
pub enum Stop {
    /// A port failed.
    Port(SerialError),
    /// Writing the console failed.
    Console(io::Error),
}

impl From<SerialError> for Stop {
    fn from(e: SerialError) -> Self {
        Stop::Port(e)
    }
}

impl From<io::Error> for Stop {
    fn from(e: io::Error) -> Self {
        Stop::Console(e)
    }
}

/// The CNC protocol on a serial port (`cnc`, the writing handle; its characters come through
/// `inbox` as port 1): bytes in both directions as they are. Runs until a port fails.
pub fn run_cnc_port(
    bridge: &mut LineBridge,
    inbox: &Receiver<Arrival>,
    cnc: &mut Port,
) -> Result<(), Stop> {
    // What the bridge wrote before (the reply to setting its clock) is not the CNC's.
    let mut sent = bridge.cnc_bytes().len();
    loop {
        let arrival = wait(inbox, &bridge.clock, bridge.wake());
        let now = bridge.now();
        match arrival {
            Some(Arrival::Serial { port: 0, rx, .. }) => bridge.ps_rx(now, &rx),
            Some(Arrival::Serial { rx, .. }) => bridge.cnc_rx(now, &Rx::cnc_bytes(&rx)),
            Some(Arrival::Failed(e)) => return Err(e.into()),
            Some(Arrival::Line(_) | Arrival::EndOfInput) | None => {}
        }
        bridge.service(now)?;
        bridge.write_flash(now, false)?;
        let raw = bridge.cnc_bytes();
        if raw.len() > sent {
            let fresh = raw[sent..].to_vec();
            sent = raw.len();
            cnc.write_all(&fresh)?;
        }
        // After `CONFIG cnc_baud ...` (its reply already written at the old framing).
        cnc.set_config(bridge.bridge().cnc_port_config())?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_out_starts_when_the_frame_has_left_the_wire() {
        // `:01030000000AF2\r\n` (17 characters) at 19200 8E1: 11 bits each, 9.74 ms.
        let at = Instant::from_millis(100);
        let end = end_of_transmission(at, at, PortConfig::MODBUS_DEFAULT, 17);
        assert_eq!(end, Instant::from_micros(100_000 + 9_740));
        // A write that blocked longer than that (the driver's buffer was full).
        let late = Instant::from_millis(150);
        assert_eq!(
            end_of_transmission(at, late, PortConfig::MODBUS_DEFAULT, 17),
            late
        );
    }
}
