//! The test rig of the CNC side: a [`Bridge`] driven against the simulated units of
//! `plasma-sim` over the line model ([`SimPs`]), the CNC bytes in and the reply bytes out
//! checked exactly, and the helpers that build what the CNC sends and expects (the `ERR`
//! lines take their texts from `texts`). The session's tests next to each file use it; the
//! expected lines there are the ones `docs/cnc-protocol.md` shows.

extern crate std;

use std::string::{String, ToString};
use std::vec::Vec;

use plasma_protocol::cnc::phoenix::{self, Format};
use plasma_protocol::modbus_ascii::{self, Request};

use embassy_futures::block_on;

use crate::bridge::{Bridge, SaveRequest};
use crate::link::ProtocolChoice;
use crate::platform::safe_state::ResetCause;
use crate::settings::{SaveError, Settings};
use crate::storage::Persistent as _;
use crate::storage::history::{HistoryStore, serve};
use crate::storage::ram_flash::RamFlash;
use crate::testing::SimPs;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::clock::{Accumulator, earliest};
use plasma_sim::powermax::{Counters, Process as PanelProcess};

/// A Modbus ASCII frame for node 1 (LRC computed by the encoder).
pub(crate) fn mb(pdu: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 600];
    let n = modbus_ascii::encode(1, pdu, &mut out).unwrap();
    out[..n].to_vec()
}

// ---------------------------------------------------------------------------------------
// the rig: bridge + unit + virtual time

/// What the CNC received: a line (without CR LF), or an ACK/NAK byte.
pub(crate) type Token = String;

pub(crate) struct Rig {
    pub bridge: Bridge,
    /// The power supply on the PS port (`None`: nothing connected).
    pub unit: Option<SimPs>,
    pub now: Instant,
    /// Every token the CNC received.
    pub received: Vec<Token>,
    partial: Vec<u8>,
    /// The answer to give a save request (`None`: leave it pending).
    pub save_result: Option<Result<(), SaveError>>,
    /// What a save stored.
    pub saved: Option<Vec<u8>>,
    /// The consumable record a save stored last.
    pub saved_consumables: Option<crate::consumables::ConsumableSet>,
    /// The history, in 8 pages of RAM flash: every draft is written at the next step.
    pub history: HistoryStore<RamFlash<HISTORY_BYTES>>,
}

/// The rig's history region: 8 pages, as the boards'.
const HISTORY_BYTES: usize = 8 * crate::storage::ram_flash::PAGE_SIZE;

pub(crate) const ACK_TOKEN: &str = "<ACK>";
pub(crate) const NAK_TOKEN: &str = "<NAK>";

impl Rig {
    /// A bridge with `settings` and the simulated `model` (pbtool's names: `sync65`,
    /// `hpr130`...; `None`: nothing on the PS port).
    pub(crate) fn new(settings: Settings, model: Option<&str>) -> Self {
        Rig {
            bridge: Bridge::new(settings, Instant::ZERO),
            unit: model.map(SimPs::new),
            now: Instant::ZERO,
            received: Vec::new(),
            partial: Vec::new(),
            save_result: Some(Ok(())),
            saved: None,
            saved_consumables: None,
            history: new_history(RamFlash::new()),
        }
    }

    /// A rig with a SYNC unit found and its slow data read. The unit's panel is set to cut,
    /// 45 A, 76 psi, and its life counters and cartridge carry some history, so that every
    /// field a reply shows is a real value.
    pub(crate) fn sync65(settings: Settings) -> Self {
        let mut rig = Rig::new(settings, Some("sync65"));
        let unit = rig.ps().powermax();
        unit.set_panel(PanelProcess {
            mode: 1,
            current: 45 * 64,
            pressure: 76 * 128,
        });
        unit.set_counters(Counters {
            starts: 1200,
            pilot: Accumulator::from_secs(300),
            transfers: 1100,
            transfer: Accumulator::from_secs(5000),
        });
        let cartridge = unit.cartridge_mut().expect("a SYNC unit has a cartridge");
        cartridge.starts = 17;
        cartridge.pilot = Accumulator::from_secs(40);
        cartridge.transfers = 15;
        cartridge.transfer = Accumulator::from_secs(40);
        cartridge.fault_log = [200, 500, 0, 0];
        rig.run(600);
        assert!(rig.bridge.status().link_up);
        assert!(rig.bridge.status().cartridge.is_some());
        rig
    }

    /// A rig with the HPR or MaxPro200 `model` found, its state read.
    pub(crate) fn hpr(model: &str) -> Self {
        let settings = Settings {
            link: crate::link::LinkConfig {
                protocol: ProtocolChoice::Hpr,
                ..Default::default()
            },
            ..Settings::default()
        };
        let mut rig = Rig::new(settings, Some(model));
        rig.run(300);
        assert!(rig.bridge.status().link_up);
        // Through power-up and the gas purge to state 3 (idle2 / ready for start).
        let ready = rig.now + Duration::from_secs(5);
        while rig.bridge.status().hpr.state.map(|s| s.0) != Some(3) && rig.now < ready {
            rig.run(100);
        }
        assert_eq!(rig.bridge.status().hpr.state.map(|s| s.0), Some(3));
        rig
    }

    /// A bridge with `CONFIG units` set to `units` and the simulated `models` (pbtool's
    /// names) on one multi-drop line, built as `pbtool` builds them: HPR ids and Powermax
    /// nodes in order (nodes from 1). Runs until every unit's link is up.
    pub(crate) fn on_line(mut settings: Settings, units: &str, models: &[&str]) -> Self {
        settings
            .set(plasma_protocol::cnc::ConfigKey::Units, units)
            .expect("units that can share a line");
        let models: Vec<plasma_sim::Model> = models
            .iter()
            .map(|m| plasma_sim::Model::from_name(m).expect("a plasma-sim model name"))
            .collect();
        let options = plasma_sim::SimOptions {
            modbus_address: 1,
            ..Default::default()
        };
        let units = plasma_sim::multidrop::units_for_one_line(&models, &options)
            .expect("simulated units for one line");
        let line = plasma_sim::multidrop::MultiDrop::new(units).expect("one serial setting");
        let mut rig = Rig::new(settings, None);
        rig.unit = Some(SimPs::with_unit(std::boxed::Box::new(line)));
        let up = rig.now + Duration::from_secs(10);
        while rig.now < up && !(0..rig.bridge.unit_count()).all(|u| rig.bridge.status_of(u).link_up)
        {
            rig.run(100);
        }
        rig
    }

    /// The simulated line of a rig built by [`Rig::on_line`].
    pub(crate) fn line(&mut self) -> &mut plasma_sim::multidrop::MultiDrop {
        self.ps()
            .unit()
            .as_any_mut()
            .downcast_mut()
            .expect("a rig built on_line")
    }

    pub(crate) fn collect(&mut self) {
        while let Some(bytes) = self.bridge.poll_cnc_output() {
            for &b in bytes {
                match b {
                    phoenix::ACK if self.partial.is_empty() => {
                        self.received.push(ACK_TOKEN.to_string())
                    }
                    phoenix::NAK if self.partial.is_empty() => {
                        self.received.push(NAK_TOKEN.to_string())
                    }
                    b'\n' => {
                        assert_eq!(self.partial.pop(), Some(b'\r'), "lines end with CR LF");
                        let line = String::from_utf8(core::mem::take(&mut self.partial)).unwrap();
                        self.received.push(line);
                    }
                    b => {
                        assert!(b == b'\r' || (0x20..0x7F).contains(&b), "byte {b:#04x}");
                        self.partial.push(b);
                    }
                }
            }
        }
    }

    /// One step: serve saves, exchange frames with the unit, move time to the next wake-up
    /// (at most `limit`). Returns false when time reached `limit`.
    fn step(&mut self, limit: Instant) -> bool {
        if let Some(result) = self.save_result
            && let Some(request) = self.bridge.take_save_request()
        {
            match request {
                SaveRequest::Settings(settings) => {
                    let mut record = [0u8; crate::storage::MAX_PAYLOAD];
                    let len = settings.encode(&mut record);
                    self.saved = Some(record[..len].to_vec());
                }
                SaveRequest::Consumables(set) => self.saved_consumables = Some(set),
            }
            self.bridge.save_finished(self.now, result);
        }
        self.serve_history();
        let line_next = self.exchange();
        self.bridge.poll(self.now);
        self.collect();
        // What the poll queued goes on the wire at once.
        let line_next = earliest(line_next, self.exchange());
        let next = match earliest(self.bridge.poll_at(), line_next) {
            Some(at) if at > self.now => at,
            Some(_) => self.now + Duration::from_millis(1),
            None => limit,
        };
        if next >= limit {
            self.now = limit;
            self.exchange();
            self.bridge.poll(self.now);
            self.collect();
            return false;
        }
        self.now = next;
        true
    }

    /// Writes the history's drafts and answers a `HISTORY` at once.
    fn serve_history(&mut self) {
        while let Some(draft) = self.bridge.take_history_draft() {
            block_on(self.history.record(draft)).unwrap();
        }
        if let Some(request) = self.bridge.take_history_request() {
            let answer = block_on(serve(&mut self.history, request));
            self.bridge.history_finished(self.now, &answer);
            self.collect();
        }
    }

    /// Power cycle of the board: a new bridge with `settings` over the same history flash,
    /// recording its reset as the boards do.
    pub(crate) fn reboot(&mut self, settings: Settings, cause: ResetCause) {
        self.serve_history();
        let flash = core::mem::replace(&mut self.history, new_history(RamFlash::new()));
        self.history = new_history(flash.into_flash());
        self.bridge = Bridge::new(settings, self.now);
        if let Some(set) = self.saved_consumables {
            self.bridge.restore_consumables(set);
        }
        self.bridge.record_reset(self.now, cause);
    }

    /// The bridge's frames to the unit, the unit's replies to the bridge (with nothing
    /// connected, frames go nowhere); the next instant the line or the unit is due.
    fn exchange(&mut self) -> Option<Instant> {
        let next = match &mut self.unit {
            Some(unit) => unit.exchange(&mut self.bridge, self.now),
            None => {
                while self.bridge.poll_ps_transmit(self.now).is_some() {}
                None
            }
        };
        self.collect();
        next
    }

    /// The simulated unit.
    pub(crate) fn ps(&mut self) -> &mut SimPs {
        self.unit.as_mut().expect("a rig with a unit")
    }

    /// The unit raises fault `code` now (its own numbering: 500 is 0-50-0, HPR error ids);
    /// 0 clears it.
    pub(crate) fn fault(&mut self, code: u16) {
        let now = self.now;
        let unit = self.ps().unit();
        match code {
            0 => unit.clear_fault(now),
            code => unit.inject_fault(now, code),
        }
    }

    /// Pulls the unit's serial cable now (true), or plugs it back (false).
    pub(crate) fn unplug(&mut self, unplugged: bool) {
        let now = self.now;
        self.ps().unplug(now, unplugged);
    }

    /// Let `ms` of virtual time pass.
    pub(crate) fn run(&mut self, ms: u64) {
        let limit = self.now + Duration::from_millis(ms);
        while self.step(limit) {}
    }

    /// Send raw bytes from the CNC and run until `replies` more reply lines (`OK`/`ERR`)
    /// have come (at most 5 s); returns every token received meanwhile.
    pub(crate) fn send_bytes(&mut self, bytes: &[u8], replies: usize) -> Vec<Token> {
        let start = self.received.len();
        self.bridge.handle_cnc_rx(self.now, bytes);
        self.collect();
        let limit = self.now + Duration::from_secs(5);
        while count_replies(&self.received[start..]) < replies && self.step(limit) {}
        self.received[start..].to_vec()
    }

    /// Send one command line; returns its reply line (exactly one reply line must come).
    pub(crate) fn cmd(&mut self, line: &str) -> String {
        let tokens = self.send_bytes(std::format!("{line}\r\n").as_bytes(), 1);
        let replies: Vec<&Token> = tokens.iter().filter(|t| is_reply(t)).collect();
        assert_eq!(replies.len(), 1, "{line}: {tokens:?}");
        replies[0].clone()
    }

    /// The Modbus writes the bridge sent the unit: (address, values); a coil as one value.
    pub(crate) fn writes(&mut self) -> Vec<(u16, Vec<u16>)> {
        let mut writes = Vec::new();
        for (_, frame) in &self.ps().sent {
            let mut buf = [0u8; 300];
            let Ok(decoded) = modbus_ascii::decode(frame, &mut buf) else {
                continue;
            };
            match Request::parse(decoded.pdu) {
                Ok(Request::WriteMultipleRegisters { start, values }) => {
                    writes.push((start, values.iter().collect()))
                }
                Ok(Request::WriteSingleCoil { address, on }) => {
                    writes.push((address, std::vec![on as u16]))
                }
                _ => {}
            }
        }
        writes
    }

    /// The HPR command ids the unit received, in order.
    pub(crate) fn hpr_commands(&mut self) -> Vec<u16> {
        self.ps().hpr().commands_received().to_vec()
    }
}

/// A history over `flash`, scanned as at boot.
fn new_history(flash: RamFlash<HISTORY_BYTES>) -> HistoryStore<RamFlash<HISTORY_BYTES>> {
    let mut store = HistoryStore::new(flash, 0..HISTORY_BYTES as u32).unwrap();
    block_on(store.scan()).unwrap();
    store
}

pub(crate) fn is_reply(token: &str) -> bool {
    token.starts_with("OK") || token.starts_with("ERR")
}

pub(crate) fn count_replies(tokens: &[Token]) -> usize {
    tokens.iter().filter(|t| is_reply(t)).count()
}

pub(crate) fn events_on() -> Settings {
    Settings {
        events: true,
        ..Settings::default()
    }
}

pub(crate) fn framed(format: u8, message: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 400];
    let n = phoenix::frame(Format::from_value(format).unwrap(), message, &mut out).unwrap();
    out[..n].to_vec()
}

// ---------------------------------------------------------------------------------------
// ERR lines: tests match the code and the values that matter; where the text matters they
// take it from where the session writes it, so no wording is pinned here.

use crate::cnc::texts::{self};
use crate::link::CommandFailure;
use plasma_protocol::cnc::{ErrorCode, ParseError};

/// An `ERR` line with `code` and `text`.
pub(crate) fn err(code: ErrorCode, text: impl core::fmt::Display) -> String {
    std::format!("ERR {code} {text}")
}

/// The `ERR` line of a line that did not parse (the protocol crate's text).
pub(crate) fn parse_err(error: ParseError) -> String {
    err(error.code(), error)
}

/// The `ERR` line of a Phoenix message with a wrong check byte.
pub(crate) fn frame_err(expected: u8, found: u8) -> String {
    let error = plasma_protocol::Error::BadChecksum { expected, found };
    texts::frame_error(error).trim_end().to_string()
}

/// The `ERR` line of a command that was sent and failed.
pub(crate) fn failure_line(failure: &CommandFailure) -> String {
    let mut line = super::ReplyLine::new();
    let _ = super::texts::write_failure(&mut line, failure, None);
    line.trim_end().to_string()
}

/// Assert that `reply` matches `pattern`, where `*` stands for any run of characters: an
/// `ERR` code and the values that matter, not the wording around them.
#[track_caller]
pub(crate) fn assert_err(reply: &str, pattern: &str) {
    let mut parts = pattern.split('*');
    let mut rest = parts
        .next()
        .and_then(|first| reply.strip_prefix(first))
        .unwrap_or_else(|| panic!("{reply:?} does not start like {pattern:?}"));
    for part in parts {
        let at = rest
            .find(part)
            .unwrap_or_else(|| panic!("{reply:?} does not match {pattern:?}"));
        rest = &rest[at + part.len()..];
    }
}
