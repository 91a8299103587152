//! The whole bridge in the [`World`]: [`WorldEndpoint`] for the firmware's
//! [`Bridge`](plasma_firmware::bridge::Bridge), and [`BridgeEndpoint`], which adds what a
//! board does around it: the CNC port (bytes in, lines/ACK/NAK out), the settings store for
//! `CONFIG SAVE` (in memory, through the real record encoding), and the simulator-only
//! `TORCH ON|OFF`.
//!
//! ```
//! use host_tests::harness::{World, WorldOptions};
//! use plasma_sim::Model;
//! use plasma_firmware::settings::Settings;
//! use plasma_protocol::time::Duration;
//!
//! let mut world = World::with_bridge(Model::Sync65, WorldOptions::default(), Settings::default());
//! world.wait_link_up(Duration::from_secs(1)).unwrap();
//! assert!(world.cnc_line("ID").starts_with("OK bridge=plasma-bridge"));
//! ```

use std::collections::VecDeque;

use embassy_futures::block_on;
use plasma_firmware::platform::safe_state::ResetCause;
use plasma_firmware::storage::history::{HistoryStore, serve};
use plasma_firmware::storage::ram_flash::{PAGE_SIZE, RamFlash};

use plasma_firmware::bridge::SimCommand;
use plasma_firmware::bridge::{Bridge, SaveRequest};
use plasma_firmware::consumables::ConsumableSet;
use plasma_firmware::io::{Inputs, IoConfig, IoEvent, Outputs, SupplyState};
use plasma_firmware::link::{Diagnostics, LinkEvent, UnitStatus};
use plasma_firmware::platform::PsEndpoint;
use plasma_firmware::settings::{SaveError, Settings};
use plasma_firmware::storage::{MAX_PAYLOAD, Persistent as _};
use plasma_protocol::cnc::phoenix::{ACK, NAK};
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};

use super::endpoint::WorldEndpoint;
use super::options::WorldOptions;
use super::world::{Timeout, World};
use plasma_sim::{Model, SimulatedUnit};

/// How long [`World::cnc_line`] waits for its reply (virtual time): longer than any command
/// takes (a settings write with retries, a restart's quiet time).
pub const CNC_REPLY_TIMEOUT: Duration = Duration::from_secs(10);

/// The bare bridge: its port side is the firmware's [`PsEndpoint`]. The bridge consumes the
/// link's events itself (they become replies and `!` lines), so [`WorldEndpoint::poll`]
/// reports none. Its CNC output is left for the caller; [`BridgeEndpoint`] collects it.
impl WorldEndpoint for Bridge {
    fn poll(&mut self, now: Instant, _events: &mut Vec<LinkEvent>) {
        Bridge::poll(self, now);
    }

    fn status(&self) -> &UnitStatus {
        Bridge::status(self)
    }

    fn diagnostics(&self) -> &Diagnostics {
        Bridge::diagnostics(self)
    }

    fn supply_state_of(&self, unit: usize) -> SupplyState {
        Bridge::supply_state_of(self, unit)
    }

    fn set_io_snapshot_of(&mut self, unit: usize, inputs: Inputs, outputs: Outputs) {
        Bridge::set_io_snapshot_of(self, unit, inputs, outputs);
    }

    fn on_io_event_of(&mut self, unit: usize, now: Instant, event: IoEvent) {
        Bridge::on_io_event_of(self, unit, now, event);
    }

    fn take_io_config_change(&mut self) -> Option<IoConfig> {
        Bridge::take_io_config_change(self)
    }

    fn poll_torch_request(&mut self) -> Option<(usize, bool)> {
        match self.poll_sim_command()? {
            SimCommand::Torch { unit, on } => Some((unit, on)),
        }
    }
}

/// One thing the CNC received.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CncItem {
    /// The ACK byte (0x06): a Phoenix message was accepted.
    Ack,
    /// The NAK byte (0x15): a Phoenix message was refused.
    Nak,
    /// A reply (`OK ...`, `ERR ...`) or event (`!...`) line, without CR LF.
    Line(String),
}

impl CncItem {
    /// The line, if this is one.
    pub fn line(&self) -> Option<&str> {
        match self {
            CncItem::Line(line) => Some(line),
            _ => None,
        }
    }

    /// True for a reply line (`OK` / `ERR`), false for an event line, a data line of a
    /// multi-line reply (`HISTORY ...`) or ACK/NAK.
    pub fn is_reply(&self) -> bool {
        self.line().is_some_and(is_reply_line)
    }
}

/// `OK ...` or `ERR ...`: the line that ends a command's reply.
pub fn is_reply_line(line: &str) -> bool {
    line.starts_with("OK") || line.starts_with("ERR")
}

/// What the CNC received, with the instant it was taken from the bridge.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CncRecord {
    /// When the bridge handed it out.
    pub at: Instant,
    /// What it was.
    pub item: CncItem,
}

/// The first bytes of [`BridgeEndpoint::flash_image`].
pub const FLASH_IMAGE_MAGIC: [u8; 8] = *b"PBFLASH1";

/// The history region: 8 pages, as the boards'.
const HISTORY_BYTES: usize = 8 * PAGE_SIZE;
type HistoryFlash = RamFlash<HISTORY_BYTES>;

/// A history over `flash`, scanned as at boot.
fn open_history(flash: HistoryFlash) -> HistoryStore<HistoryFlash> {
    let mut store = HistoryStore::new(flash, 0..HISTORY_BYTES as u32).expect("8 whole pages");
    // A RAM flash does not fail.
    let _ = block_on(store.scan());
    store
}

/// The result of the next `CONFIG SAVE`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum SaveOutcome {
    #[default]
    Store,
    Fail(SaveError),
}

/// The bridge as a board runs it: the [`Bridge`] plus its CNC port, settings store and the
/// simulator's TORCH_ON. Every CNC byte the bridge writes is collected in order.
#[derive(Debug)]
pub struct BridgeEndpoint {
    bridge: Bridge,
    sim_commands: bool,
    /// Every byte written to the CNC.
    raw: Vec<u8>,
    /// The bytes split into ACK, NAK and lines.
    records: Vec<CncRecord>,
    partial: Vec<u8>,
    torch: VecDeque<(usize, bool)>,
    /// The stored record payload (what the flash would hold).
    stored: Option<Vec<u8>>,
    /// The consumable record stored last (saved by the bridge itself, at most once a minute).
    stored_consumables: Option<ConsumableSet>,
    /// The history, in flash as the board's; it survives [`BridgeEndpoint::power_cycle`].
    history: HistoryStore<HistoryFlash>,
    saves: u32,
    next_save: SaveOutcome,
}

impl BridgeEndpoint {
    /// A bridge started at `now` with `settings`; `sim_commands` accepts `TORCH ON|OFF`.
    pub fn new(settings: Settings, now: Instant, sim_commands: bool) -> Self {
        let mut bridge = Bridge::new(settings, now);
        if sim_commands {
            bridge.enable_sim_commands();
        }
        BridgeEndpoint {
            bridge,
            sim_commands,
            raw: Vec::new(),
            records: Vec::new(),
            partial: Vec::new(),
            torch: VecDeque::new(),
            stored: None,
            stored_consumables: None,
            history: open_history(HistoryFlash::new()),
            saves: 0,
            next_save: SaveOutcome::Store,
        }
    }

    /// The bridge.
    pub fn bridge(&self) -> &Bridge {
        &self.bridge
    }

    /// The bridge, mutable.
    pub fn bridge_mut(&mut self) -> &mut Bridge {
        &mut self.bridge
    }

    /// Bytes from the CNC.
    pub fn cnc_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.bridge.handle_cnc_rx(now, bytes);
        self.collect(now);
    }

    /// Everything written to the CNC so far, split up.
    pub fn records(&self) -> &[CncRecord] {
        &self.records
    }

    /// Every byte written to the CNC so far.
    pub fn raw(&self) -> &[u8] {
        &self.raw
    }

    /// The settings stored by the last successful `CONFIG SAVE`, decoded from the stored
    /// record.
    pub fn saved_settings(&self) -> Option<Settings> {
        self.stored.as_deref().and_then(Settings::decode)
    }

    /// Completed `CONFIG SAVE`s (successful or not).
    pub fn saves(&self) -> u32 {
        self.saves
    }

    /// The consumable record the bridge stored last.
    pub fn saved_consumables(&self) -> Option<ConsumableSet> {
        self.stored_consumables
    }

    /// The bridge's flash as a file keeps it (`pbtool sim --flash`): [`FLASH_IMAGE_MAGIC`],
    /// the stored settings payload (length as u16 little endian, `0xFFFF`: none saved, then
    /// the bytes), then the history region's bytes, then (when one was stored) the consumable
    /// record's payload (an image without it loads as before).
    pub fn flash_image(&mut self) -> Vec<u8> {
        self.serve_history(Instant::ZERO);
        let mut image = FLASH_IMAGE_MAGIC.to_vec();
        match &self.stored {
            Some(payload) => {
                image.extend_from_slice(&(payload.len() as u16).to_le_bytes());
                image.extend_from_slice(payload);
            }
            None => image.extend_from_slice(&u16::MAX.to_le_bytes()),
        }
        image.extend_from_slice(self.history.flash().bytes());
        if let Some(set) = self.stored_consumables {
            let mut payload = [0u8; MAX_PAYLOAD];
            let len = set.encode(&mut payload);
            image.extend_from_slice(&payload[..len]);
        }
        image
    }

    /// Takes the flash from an image of [`BridgeEndpoint::flash_image`]; the bridge runs on
    /// until the next [`BridgeEndpoint::power_cycle`] (the board reads its flash at boot).
    pub fn load_flash_image(&mut self, image: &[u8]) -> Result<(), String> {
        let rest = image
            .strip_prefix(FLASH_IMAGE_MAGIC.as_slice())
            .ok_or("not a plasma-bridge flash image")?;
        let (len, rest) = rest.split_at_checked(2).ok_or("flash image truncated")?;
        let (stored, rest) = match u16::from_le_bytes([len[0], len[1]]) {
            u16::MAX => (None, rest),
            len => {
                let (payload, rest) = rest
                    .split_at_checked(usize::from(len))
                    .ok_or("flash image truncated")?;
                (Some(payload.to_vec()), rest)
            }
        };
        let Some((history, consumables)) = rest.split_at_checked(HISTORY_BYTES) else {
            return Err(format!(
                "flash image: history region of {} bytes, expected {HISTORY_BYTES}",
                rest.len()
            ));
        };
        let stored_consumables = match consumables {
            [] => None,
            payload => Some(
                ConsumableSet::decode(payload)
                    .ok_or("flash image: the consumable record is damaged")?,
            ),
        };
        let mut flash = HistoryFlash::new();
        flash.bytes_mut().copy_from_slice(history);
        self.history = open_history(flash);
        self.stored = stored;
        self.stored_consumables = stored_consumables;
        Ok(())
    }

    /// Make the next `CONFIG SAVE` fail with `error`.
    pub fn fail_next_save(&mut self, error: SaveError) {
        self.next_save = SaveOutcome::Fail(error);
    }

    /// Power cycle: a new [`Bridge`] from the stored settings (the defaults if none were
    /// saved); the CNC output so far is kept, a partial line is lost.
    pub fn power_cycle(&mut self, now: Instant) {
        let settings = self.saved_settings().unwrap_or_default();
        self.serve_history(now);
        let flash = std::mem::replace(&mut self.history, open_history(HistoryFlash::new()));
        self.history = open_history(flash.into_flash());
        self.bridge = Bridge::new(settings, now);
        if let Some(set) = self.stored_consumables {
            self.bridge.restore_consumables(set);
        }
        self.bridge.record_reset(now, ResetCause::PowerOn);
        if self.sim_commands {
            self.bridge.enable_sim_commands();
        }
        self.partial.clear();
        self.torch.clear();
    }

    /// Take the bridge's output, serve a save request and simulator commands.
    fn collect(&mut self, now: Instant) {
        loop {
            while let Some(bytes) = self.bridge.poll_cnc_output() {
                let bytes = bytes.to_vec();
                self.absorb(now, &bytes);
            }
            while let Some(command) = self.bridge.poll_sim_command() {
                match command {
                    SimCommand::Torch { unit, on } => self.torch.push_back((unit, on)),
                }
            }
            if self.serve_history(now) {
                continue;
            }
            let result = match self.bridge.take_save_request() {
                None => break,
                Some(SaveRequest::Settings(settings)) => {
                    self.saves += 1;
                    self.store(&settings)
                }
                Some(SaveRequest::Consumables(set)) => {
                    self.stored_consumables = Some(set);
                    Ok(())
                }
            };
            self.bridge.save_finished(now, result);
        }
    }

    /// Writes the history's drafts; answers a `HISTORY` (true if one was answered).
    fn serve_history(&mut self, now: Instant) -> bool {
        while let Some(draft) = self.bridge.take_history_draft() {
            // A RAM flash does not fail; the entry is the board's to lose, not the harness's.
            let _ = block_on(self.history.record(draft));
        }
        let Some(request) = self.bridge.take_history_request() else {
            return false;
        };
        let answer = block_on(serve(&mut self.history, request));
        self.bridge.history_finished(now, &answer);
        true
    }

    fn store(&mut self, settings: &Settings) -> Result<(), SaveError> {
        if let SaveOutcome::Fail(error) = std::mem::take(&mut self.next_save) {
            return Err(error);
        }
        let mut payload = vec![0u8; MAX_PAYLOAD];
        let len = settings.encode(&mut payload);
        if len > payload.len() {
            return Err(SaveError::TooLarge);
        }
        payload.truncate(len);
        self.stored = Some(payload);
        Ok(())
    }

    fn absorb(&mut self, now: Instant, bytes: &[u8]) {
        self.raw.extend_from_slice(bytes);
        for &b in bytes {
            let item = match b {
                // The session writes control bytes only as ACK/NAK, never inside a line.
                ACK if self.partial.is_empty() => CncItem::Ack,
                NAK if self.partial.is_empty() => CncItem::Nak,
                b'\n' if self.partial.last() == Some(&b'\r') => {
                    self.partial.pop();
                    let line = String::from_utf8_lossy(&self.partial).into_owned();
                    self.partial.clear();
                    CncItem::Line(line)
                }
                _ => {
                    self.partial.push(b);
                    continue;
                }
            };
            self.records.push(CncRecord { at: now, item });
        }
    }
}

/// The port side is the bridge's.
impl PsEndpoint for BridgeEndpoint {
    fn handle_ps_rx(&mut self, now: Instant, bytes: &[u8]) {
        self.bridge.handle_ps_rx(now, bytes);
    }

    fn handle_ps_rx_error(&mut self, now: Instant) {
        self.bridge.handle_ps_rx_error(now);
    }

    fn poll_ps_transmit(&mut self, now: Instant) -> Option<&[u8]> {
        self.bridge.poll_ps_transmit(now)
    }

    fn ps_transmitted(&mut self, at: Instant) {
        self.bridge.ps_transmitted(at);
    }

    fn ps_port_config(&self) -> PortConfig {
        self.bridge.ps_port_config()
    }

    fn poll_at(&self) -> Option<Instant> {
        self.bridge.poll_at()
    }
}

impl WorldEndpoint for BridgeEndpoint {
    fn poll(&mut self, now: Instant, _events: &mut Vec<LinkEvent>) {
        self.bridge.poll(now);
        self.collect(now);
    }

    fn status(&self) -> &UnitStatus {
        self.bridge.status()
    }

    fn diagnostics(&self) -> &Diagnostics {
        self.bridge.diagnostics()
    }

    fn supply_state_of(&self, unit: usize) -> SupplyState {
        self.bridge.supply_state_of(unit)
    }

    fn set_io_snapshot_of(&mut self, unit: usize, inputs: Inputs, outputs: Outputs) {
        self.bridge.set_io_snapshot_of(unit, inputs, outputs);
    }

    fn on_io_event_of(&mut self, unit: usize, now: Instant, event: IoEvent) {
        self.bridge.on_io_event_of(unit, now, event);
        // `!ARC ON` reaches the CNC at this instant, not at the next poll.
        self.collect(now);
    }

    fn take_io_config_change(&mut self) -> Option<IoConfig> {
        self.bridge.take_io_config_change()
    }

    fn poll_torch_request(&mut self) -> Option<(usize, bool)> {
        self.torch.pop_front()
    }
}

/// The whole bridge against a simulated unit, driven from the CNC side.
impl World<BridgeEndpoint> {
    /// The bridge with `settings` (simulator commands on) against a simulated `model`; the
    /// interlocks use `settings.io` (`options.io` is ignored).
    pub fn with_bridge(model: Model, options: WorldOptions, settings: Settings) -> Self {
        let unit = model.build(&options.sim);
        Self::with_bridge_unit(unit, options, settings)
    }

    /// The bridge against a simulator built by the caller.
    pub fn with_bridge_unit(
        unit: Box<dyn SimulatedUnit>,
        options: WorldOptions,
        settings: Settings,
    ) -> Self {
        let options = WorldOptions {
            io: settings.io,
            link: settings.link,
            ..options
        };
        let endpoint = BridgeEndpoint::new(settings, Instant::ZERO, true);
        World::with_endpoint(endpoint, unit, options)
    }

    /// The bridge.
    pub fn bridge(&self) -> &Bridge {
        self.endpoint().bridge()
    }

    /// The bridge, mutable (its own API; call [`World::drive`] to let the world react).
    pub fn bridge_mut(&mut self) -> &mut Bridge {
        self.endpoint_mut().bridge_mut()
    }

    /// Bytes from the CNC, now (any chunking: half lines, frames, garbage).
    pub fn cnc_send(&mut self, bytes: &[u8]) {
        self.drive(|e, now| e.cnc_rx(now, bytes));
    }

    /// Send `line` (CR LF appended) and run until its one reply line arrives; returns it.
    /// Event lines and ACK/NAK that come meanwhile stay in [`World::cnc_output`]. Panics
    /// when no reply comes within [`CNC_REPLY_TIMEOUT`].
    pub fn cnc_line(&mut self, line: &str) -> String {
        let mark = self.cnc_reply_count();
        let mut bytes = line.as_bytes().to_vec();
        bytes.extend_from_slice(b"\r\n");
        self.cnc_send(&bytes);
        self.wait_cnc_replies(mark + 1, CNC_REPLY_TIMEOUT)
            .unwrap_or_else(|t| panic!("no reply to {line:?}: {t}\n{}", self.trace().tail(10)));
        let reply = self.cnc_replies().nth(mark).expect("waited for it");
        reply.to_string()
    }

    /// Run until `count` reply lines have arrived in all; returns the instant.
    pub fn wait_cnc_replies(
        &mut self,
        count: usize,
        timeout: Duration,
    ) -> Result<Instant, Timeout> {
        self.run_until(|w| w.cnc_reply_count() >= count, timeout)
    }

    /// Run until a line starting with `prefix` arrives (after this call); returns it.
    pub fn wait_cnc_line(&mut self, prefix: &str, timeout: Duration) -> Result<String, Timeout> {
        let mark = self.cnc_output().len();
        let find = |w: &Self| {
            w.cnc_output()[mark..]
                .iter()
                .filter_map(|r| r.item.line())
                .find(|l| l.starts_with(prefix))
                .map(str::to_string)
        };
        self.run_until(|w| find(w).is_some(), timeout)?;
        Ok(find(self).expect("found by run_until"))
    }

    /// Everything the CNC received, in order.
    pub fn cnc_output(&self) -> &[CncRecord] {
        self.endpoint().records()
    }

    /// Every byte the CNC received.
    pub fn cnc_bytes(&self) -> &[u8] {
        self.endpoint().raw()
    }

    /// Every line the CNC received (replies and events).
    pub fn cnc_lines(&self) -> impl Iterator<Item = &str> {
        self.cnc_output().iter().filter_map(|r| r.item.line())
    }

    /// The reply lines (`OK` / `ERR`) the CNC received.
    pub fn cnc_replies(&self) -> impl Iterator<Item = &str> {
        self.cnc_lines().filter(|l| is_reply_line(l))
    }

    /// How many reply lines the CNC has received.
    pub fn cnc_reply_count(&self) -> usize {
        self.cnc_replies().count()
    }

    /// The event lines (`!...`) the CNC received.
    pub fn cnc_events(&self) -> impl Iterator<Item = &str> {
        self.cnc_lines().filter(|l| l.starts_with('!'))
    }

    /// The settings the last successful `CONFIG SAVE` stored.
    pub fn saved_settings(&self) -> Option<Settings> {
        self.endpoint().saved_settings()
    }

    /// Switch the bridge's board off and on: the bridge starts again from the stored
    /// settings, the interlocks from reset (see [`World::reset_bridge`]). The unit keeps
    /// running.
    pub fn power_cycle_bridge(&mut self) {
        let io = self.saved_settings().unwrap_or_default().io;
        self.reset_bridge(io, |e, now| e.power_cycle(now));
    }
}
