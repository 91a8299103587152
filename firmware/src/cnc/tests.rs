//! End-to-end tests of the CNC side: a [`Bridge`] driven against the simulated units of
//! `plasma-sim` over the line model ([`SimPs`]), the CNC bytes in and the reply bytes out
//! checked exactly. The expected lines here are the ones `docs/cnc-protocol.md` shows.

extern crate std;

use std::string::{String, ToString};
use std::vec::Vec;

use plasma_protocol::cnc::phoenix::{self, Format};
use plasma_protocol::modbus_ascii::{self, Request};
use proptest::prelude::*;

use crate::bridge::Bridge;
use crate::cnc::SimCommand;
use crate::io::{Inputs, IoEvent, Outputs};
use crate::link::ProtocolChoice;
use crate::settings::{Process, SaveError, Settings};
use crate::storage::Settings as _;
use crate::testing::SimPs;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::clock::{Accumulator, earliest};
use plasma_sim::hpr::HprCounters;
use plasma_sim::powermax::{Counters, Settings as PanelSettings};

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
}

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
        }
    }

    /// A rig with a SYNC unit found and its slow data read. The unit's panel is set to cut,
    /// 45 A, 76 psi, and its life counters and cartridge carry some history, so that every
    /// field a reply shows is a real value.
    pub(crate) fn sync65(settings: Settings) -> Self {
        let mut rig = Rig::new(settings, Some("sync65"));
        let unit = rig.ps().powermax();
        unit.set_panel(PanelSettings {
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
            && let Some(settings) = self.bridge.take_save_request()
        {
            let mut record = [0u8; crate::storage::MAX_PAYLOAD];
            let len = settings.encode(&mut record);
            self.saved = Some(record[..len].to_vec());
            self.bridge.save_finished(self.now, result);
        }
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

pub(crate) fn is_reply(token: &str) -> bool {
    token.starts_with("OK") || token.starts_with("ERR")
}

fn count_replies(tokens: &[Token]) -> usize {
    tokens.iter().filter(|t| is_reply(t)).count()
}

fn events_on() -> Settings {
    Settings {
        events: true,
        ..Settings::default()
    }
}

fn framed(format: u8, message: &[u8]) -> Vec<u8> {
    let mut out = [0u8; 400];
    let n = phoenix::frame(Format::from_value(format).unwrap(), message, &mut out).unwrap();
    out[..n].to_vec()
}

// ---------------------------------------------------------------------------------------
// a session with a SYNC unit

#[test]
fn set_process_answers_once_after_the_read_back() {
    let mut rig = Rig::sync65(Settings::default());
    let reply = rig.cmd("SET PROCESS CUT 45 AUTO");
    assert_eq!(reply, "OK mode=CUT amps=45 psi=AUTO");
    // One write of all three remote registers: cut, 45 A x 64, automatic pressure.
    assert_eq!(rig.writes(), std::vec![(0x3080, std::vec![1, 2880, 0])]);
    assert_eq!(
        rig.bridge.settings().process,
        Some(Process {
            mode: plasma_protocol::cnc::Mode::Cut,
            amps: plasma_protocol::cnc::Amps::from_raw(2880),
            pressure: plasma_protocol::cnc::Pressure::Auto,
        })
    );
    rig.run(300);
    assert_eq!(
        rig.cmd("STATUS"),
        "OK link=UP model=Powermax65 family=SYNC remote=ON mode=CUT amps=45 psi=72 \
         out_amps=0 out_psi=0 fault=none start=OFF motion=OFF arc_ok=OFF ready=ON"
    );
}

#[test]
fn status_is_one_line_with_the_io_snapshot() {
    let mut rig = Rig::sync65(Settings::default());
    let inputs = Inputs {
        torch_on: true,
        motion: true,
        ..Inputs::NONE
    };
    let outputs = Outputs {
        start: true,
        arc_ok: true,
        ready: true,
        ..Outputs::OFF
    };
    rig.bridge.set_io_snapshot(inputs, outputs);
    assert_eq!(
        rig.cmd("status"),
        "OK link=UP model=Powermax65 family=SYNC remote=OFF mode=CUT amps=45 psi=76 \
         out_amps=0 out_psi=0 fault=none start=ON motion=ON arc_ok=ON ready=ON"
    );
}

#[test]
fn limits_are_refused_with_the_permitted_range_before_anything_is_sent() {
    let mut rig = Rig::sync65(Settings::default());
    assert_err(&rig.cmd("SET AMPS 120"), "ERR RANGE *120*20..65*");
    assert_err(&rig.cmd("SET PROCESS CUT 45 80"), "ERR RANGE *80*58..78*");
    assert_err(&rig.cmd("SET MODE GOUGE"), "ERR RANGE *GOUGE*CUT*EXPANDED*");
    // The protocol's absolute bounds come first.
    assert_err(&rig.cmd("SET AMPS 500"), "ERR RANGE *5..400*");
    assert_err(&rig.cmd("SET AMPS 45.01"), "ERR RANGE *1/64*");
    assert!(rig.writes().is_empty(), "nothing was sent");
    assert_eq!(
        rig.cmd("LIMITS"),
        "OK modes=CUT,EXPANDED amps=20..65 psi=58..78 scope=cartridge"
    );
}

#[test]
fn set_mode_amps_and_psi_combine_with_the_other_two_values() {
    let mut rig = Rig::sync65(Settings::default());
    // Nothing asked for yet: the unit's own settings (cut, 45 A, 76 psi) fill in.
    assert_eq!(rig.cmd("SET AMPS 40"), "OK mode=CUT amps=40 psi=76");
    assert_eq!(rig.cmd("SET PSI AUTO"), "OK mode=CUT amps=40 psi=AUTO");
    assert_eq!(
        rig.cmd("SET MODE EXPANDED"),
        "OK mode=EXPANDED amps=40 psi=AUTO"
    );
    assert_eq!(rig.cmd("SET PSI 70.5"), "OK mode=EXPANDED amps=40 psi=70.5");
    assert_eq!(
        rig.writes(),
        std::vec![
            (0x3080, std::vec![1, 40 * 64, 76 * 128]),
            (0x3080, std::vec![1, 40 * 64, 0]),
            (0x3080, std::vec![2, 40 * 64, 0]),
            (0x3080, std::vec![2, 40 * 64, 141 * 64]),
        ]
    );
}

#[test]
fn settings_that_do_not_read_back_are_an_error_with_the_read_back_values() {
    let mut rig = Rig::sync65(Settings::default());
    rig.ps().powermax().config_mut().remote_settings_apply = false;
    assert_err(
        &rig.cmd("SET PROCESS CUT 50 AUTO"),
        "ERR LINK *mode=CUT*amps=45*psi=76*",
    );
    assert_eq!(rig.bridge.settings().process, None);
    rig.unplug(true);
    assert_eq!(
        rig.cmd("SET PROCESS CUT 50 AUTO"),
        failure_line(&CommandFailure::Settings(SettingsFailure::Transaction(
            TransactionError::Timeout
        )))
    );
}

#[test]
fn every_command_on_a_sync_unit() {
    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(
        rig.cmd("HELP"),
        "OK commands=HELP,ID,STATUS,LIMITS,FAULT,FAULTLOG,COUNTERS,CARTRIDGE,SET_MODE,\
         SET_AMPS,SET_PSI,SET_PROCESS,REMOTE_OFF,GASTEST,RESTART,GASES,CORNER,RESET,CLEARWARN,\
         EVENTS,CONFIG,CONFIG_SAVE,RAW simulator_only=TORCH simulator=NO"
    );
    assert_eq!(
        rig.cmd("ID"),
        "OK bridge=plasma-bridge version=0.1.0 reset=unknown link=UP model=Powermax65 \
         family=SYNC product=081335"
    );
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    assert_eq!(rig.cmd("FAULTLOG"), "OK log=0-20-0,0-50-0");
    assert_eq!(
        rig.cmd("COUNTERS"),
        std::format!(
            "OK starts=1200 pilot_arc_s=300 transfers=1100 transfer_s=5000 link_ok={} \
             link_failed=0 retries=0 timeouts={} bad_checksums=0 link_downs=0",
            rig.bridge.diagnostics().transactions_ok,
            rig.bridge.diagnostics().timeouts
        )
    );
    assert_eq!(
        rig.cmd("CARTRIDGE"),
        "OK uid=E00401D0036FB25D part=428930 rev=1 nominal_amps=65 name=C_MECH starts=17 \
         pilot_arc_s=40 transfers=15 transfer_s=40"
    );
    assert_eq!(rig.cmd("GASTEST ON"), "OK gastest=ON");
    assert_eq!(rig.cmd("GASTEST OFF"), "OK gastest=OFF");
    assert_err(&rig.cmd("RESTART"), "ERR STATE *0-50-0*");
    rig.fault(500);
    rig.run(300);
    assert_eq!(
        rig.cmd("FAULT"),
        "OK fault=0-50-0 action=required text=The cartridge is off, the torch was disconnected \
         when you set the plasma power supply to ON (I), or the torch was in the yellow lock (X) \
         position during a restart."
    );
    let restart = rig.cmd("RESTART");
    assert_eq!(restart, "OK restart=done quiet_ms=2000");
    assert_eq!(rig.cmd("SET AMPS 40").split(' ').next(), Some("ERR"));
    rig.run(2500);
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    assert_eq!(
        rig.cmd("GASES O2 AIR"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::GASES, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("CORNER 80"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::CORNER, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("RESET"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::RESET, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("CLEARWARN"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::CLEAR_WARN, Family::PowermaxSync)
        )
    );
    assert_eq!(
        rig.cmd("SET PROCESS GOUGE 45 AUTO").split(' ').next(),
        Some("ERR")
    );
    assert_eq!(
        rig.cmd("SET PROCESS CUT 45 AUTO"),
        "OK mode=CUT amps=45 psi=AUTO"
    );
    assert_eq!(rig.cmd("REMOTE OFF"), "OK remote=OFF");
    assert_eq!(rig.writes().last(), Some(&(0x3080, std::vec![0, 0, 0])));
    assert_eq!(rig.bridge.settings().process, None);
    assert_eq!(
        rig.cmd("TORCH ON"),
        err(ErrorCode::Unsupported, texts::TORCH_SIMULATOR_ONLY)
    );
    assert_err(&rig.cmd("REMOTE ON"), "ERR SYNTAX *REMOTE*OFF*");
    assert_eq!(rig.cmd("FLY"), parse_err(ParseError::UnknownCommand));
}

#[test]
fn raw_frames_are_forwarded_or_refused_by_the_allow_list() {
    let mut rig = Rig::sync65(Settings::default());
    // Read the active fault register 0x301A.
    let read = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    let read = core::str::from_utf8(&read).unwrap().trim_end();
    assert_eq!(read, ":0104301A0001B0");
    assert_eq!(
        rig.cmd(&std::format!("RAW {read}")),
        "OK reply=:0104020000F9"
    );
    // A write to a register not documented as writable.
    let write = mb(&[0x06, 0x30, 0x10, 0x00, 0x01]);
    let write = core::str::from_utf8(&write).unwrap().trim_end();
    assert_err(&rig.cmd(&std::format!("RAW {write}")), "ERR REFUSED *3010*");
    assert_err(&rig.cmd("RAW :0104301A0001B1"), "ERR REFUSED *B0*B1*");
    assert_eq!(
        rig.cmd("RAW"),
        parse_err(ParseError::MissingArgument { what: "frame" })
    );
    assert!(rig.writes().is_empty());
}

#[test]
fn without_a_unit_commands_that_need_one_say_link() {
    let mut rig = Rig::new(Settings::default(), None);
    rig.run(50);
    for line in [
        "SET PROCESS CUT 45 AUTO",
        "SET AMPS 45",
        "REMOTE OFF",
        "GASTEST ON",
        "RESTART",
        "GASES O2 AIR",
        "CORNER 80",
        "RESET",
        "CLEARWARN",
        "FAULT",
        "FAULTLOG",
        "LIMITS",
        "CARTRIDGE",
    ] {
        assert_eq!(
            rig.cmd(line),
            err(ErrorCode::Link, texts::NO_LINK),
            "{line}"
        );
    }
    assert_eq!(
        rig.cmd("RAW :0104301A0001B0"),
        refusal_line(&Refusal::LinkNotUp, None)
    );
    assert_eq!(
        rig.cmd("STATUS"),
        "OK link=DOWN model=- family=- remote=OFF mode=- amps=- psi=- out_amps=- out_psi=- \
         fault=none start=OFF motion=OFF arc_ok=OFF ready=OFF"
    );
    assert!(rig.cmd("COUNTERS").starts_with("OK link_ok=0 link_failed="));
}

// ---------------------------------------------------------------------------------------
// HPR and MaxPro200

#[test]
fn every_command_on_an_hpr() {
    let mut rig = Rig::hpr("hpr130");
    assert_eq!(
        rig.cmd("STATUS"),
        "OK link=UP model=HPR130 family=HPR remote=OFF mode=- amps=130 psi=- out_amps=- \
         out_psi=- fault=none start=OFF motion=OFF arc_ok=OFF ready=ON state=3 \
         state_name=IDLE2"
    );
    assert_eq!(rig.cmd("LIMITS"), "OK amps=5..130 corner=50..100");
    assert_eq!(rig.cmd("SET AMPS 100"), "OK amps=100");
    let requests = rig.hpr_commands();
    let set = requests.iter().position(|&id| id == 58).unwrap();
    assert_eq!(requests[set - 1], 4, "REMOTE_MODE before the first setting");
    assert_err(&rig.cmd("SET AMPS 131"), "ERR RANGE *131*5..130*");
    assert_err(&rig.cmd("SET AMPS 45.5"), "ERR RANGE *45.5*");
    assert_eq!(
        rig.cmd("SET PROCESS CUT 45 AUTO"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::SET_PROCESS, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("SET MODE CUT"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::SET_MODE, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("SET PSI 60"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::SET_PSI, Family::Hpr)
        )
    );
    assert_eq!(rig.cmd("GASES O2 AIR"), "OK plasma=O2 shield=AIR");
    assert_eq!(rig.cmd("CORNER 80"), "OK corner=80");
    assert_err(&rig.cmd("CORNER 40"), "ERR RANGE *50..100*");
    assert_eq!(rig.cmd("CLEARWARN"), "OK clearwarn=done");
    assert_eq!(rig.cmd("GASTEST ON"), "OK gastest=ON");
    assert_eq!(rig.cmd("GASTEST OFF"), "OK gastest=OFF");
    assert_err(&rig.cmd("RESET"), "ERR STATE *3*IDLE2*000*NO*ERROR*");
    // Two errors come and go before the bridge polls: only the log keeps them.
    rig.fault(20);
    rig.fault(44);
    rig.fault(0);
    assert_eq!(rig.cmd("FAULTLOG"), "OK log=044,020");
    rig.ps().hpr().set_counters(HprCounters {
        arc_on: Accumulator::from_secs(3600),
        system_on: Accumulator::from_secs(900 * 60),
        starts: 420,
        start_errors: 3,
        rampdown_errors: 1,
    });
    assert!(rig.cmd("COUNTERS").starts_with(
        "OK arc_s=3600 system_min=900 starts=420 start_errors=3 rampdown_errors=1 link_ok="
    ));
    assert_eq!(
        rig.cmd("CARTRIDGE"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::CARTRIDGE, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("RESTART"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::RESTART, Family::Hpr)
        )
    );
    assert_eq!(
        rig.cmd("REMOTE OFF"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::REMOTE_OFF, Family::Hpr)
        )
    );
    assert_eq!(rig.cmd("RAW >00292<"), "OK reply=>002000355<");
    assert_err(&rig.cmd("RAW >12093<"), "ERR REFUSED *120*");
    rig.fault(44);
    rig.run(300);
    assert_eq!(
        rig.cmd("FAULT"),
        "OK fault=044 action=required text=LOW PLASMA GAS PRESSURE"
    );
}

#[test]
fn maxpro200_commands_that_do_not_apply_say_why() {
    let mut rig = Rig::hpr("maxpro200");
    assert_eq!(rig.cmd("LIMITS"), "OK amps=5..200");
    assert_eq!(rig.cmd("SET AMPS 200"), "OK amps=200");
    assert_eq!(rig.cmd("GASES AIR AIR"), "OK plasma=AIR shield=AIR");
    assert_eq!(
        rig.cmd("CLEARWARN"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::CLEAR_WARN, Family::MaxPro200)
        )
    );
    assert_eq!(
        rig.cmd("FAULTLOG"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::FAULT_LOG, Family::MaxPro200)
        )
    );
    assert_eq!(
        rig.cmd("GASTEST ON"),
        err(
            ErrorCode::Unsupported,
            UnsupportedText(unsupported::NOT_SUPPORTED, Family::MaxPro200)
        )
    );
    assert!(
        rig.cmd("STATUS")
            .ends_with("ready=ON state=3 state_name=READY_FOR_START")
    );
}

// ---------------------------------------------------------------------------------------
// events

#[test]
fn events_report_link_faults_settings_and_arc_when_on() {
    let mut rig = Rig::new(events_on(), Some("sync65"));
    rig.run(600);
    assert!(
        rig.received
            .contains(&"!LINK UP model=Powermax65/85/105 SYNC".to_string()),
        "{:?}",
        rig.received
    );
    let tokens = rig.send_bytes(b"SET PROCESS CUT 45 AUTO\r\n", 1);
    assert_eq!(
        tokens,
        [
            "!REMOTE ON",
            // The read-back: in automatic pressure the unit shows the pressure it picked.
            "!SETTINGS applied mode=CUT amps=45 psi=72",
            "OK mode=CUT amps=45 psi=AUTO"
        ]
    );
    rig.fault(200);
    let start = rig.received.len();
    rig.run(300);
    assert_eq!(
        rig.received[start..],
        [
            "!FAULT 0-20-0 The gas pressure is lower than the minimum pressure for the selected \
          process, operating mode, torch, lead length, and cartridge type."
        ]
    );
    rig.fault(0);
    let start = rig.received.len();
    rig.run(300);
    assert_eq!(rig.received[start..], ["!FAULT CLEARED code=0-20-0"]);
    rig.bridge.on_io_event(rig.now, IoEvent::ArcOn);
    rig.bridge.on_io_event(rig.now, IoEvent::ArcOff);
    rig.bridge.on_io_event(rig.now, IoEvent::TransferTimeout);
    rig.bridge.on_io_event(
        rig.now,
        IoEvent::StartRefused {
            reason: crate::io::Interlock::LinkDown,
        },
    );
    rig.collect();
    assert_eq!(
        rig.received[rig.received.len() - 4..],
        [
            "!ARC ON",
            "!ARC OFF",
            "!TRANSFER TIMEOUT",
            "!START REFUSED reason=link_down"
        ]
    );
    assert_eq!(rig.cmd("EVENTS OFF"), "OK events=OFF");
    rig.fault(200);
    let start = rig.received.len();
    rig.run(300);
    rig.bridge.on_io_event(rig.now, IoEvent::ArcOn);
    rig.collect();
    assert!(
        rig.received[start..].is_empty(),
        "{:?}",
        &rig.received[start..]
    );
    assert_eq!(rig.cmd("EVENTS ON"), "OK events=ON");
    rig.unplug(true);
    let start = rig.received.len();
    rig.run(2000);
    assert!(
        rig.received[start..]
            .contains(&"!LINK DOWN reason=no_answer failures=3 last=timeout".to_string()),
        "{:?}",
        &rig.received[start..]
    );
}

#[test]
fn hpr_state_changes_are_events() {
    let mut rig = Rig::hpr("hpr260");
    assert_eq!(rig.cmd("EVENTS ON"), "OK events=ON");
    // A start held by HOLD: the unit stays in preflow.
    let now = rig.now;
    rig.ps().hpr().set_hold(now, true);
    rig.ps().unit().set_start(now, true);
    let start = rig.received.len();
    rig.run(300);
    assert_eq!(rig.received[start..], ["!STATE 4 name=PREFLOW from=3"]);
}

// ---------------------------------------------------------------------------------------
// Phoenix serial messaging

#[test]
fn phoenix_messages_are_acked_or_naked_then_answered() {
    let mut rig = Rig::sync65(Settings::default());
    let tokens = rig.send_bytes(&framed(113, b"FAULT"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    // A wrong check byte: NAK, and the line says why.
    let mut bad = framed(113, b"FAULT");
    *bad.last_mut().unwrap() ^= 0x01;
    let tokens = rig.send_bytes(&bad, 1);
    assert_eq!(tokens, [NAK_TOKEN, frame_err(0x4A, 0x4B).as_str()]);
    // Intact but not a command: NAK too.
    let tokens = rig.send_bytes(&framed(113, b"FLY"), 1);
    assert_eq!(
        tokens,
        [NAK_TOKEN, parse_err(ParseError::UnknownCommand).as_str()]
    );
    // A command that waits for the unit: ACK at once, the reply after the read-back.
    let tokens = rig.send_bytes(&framed(113, b"SET PROCESS CUT 45 AUTO"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK mode=CUT amps=45 psi=AUTO"]);
    // Text lines still work around frames.
    assert_eq!(rig.cmd("FAULT"), "OK fault=none");
    // Another format, set by CONFIG.
    assert_eq!(rig.cmd("CONFIG phoenix_format 48"), "OK phoenix_format=48");
    let tokens = rig.send_bytes(&framed(48, b"FAULT"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    // Message type 22 as the part program writes it: `>22,33<FAULT` (STX, CR LF, ETX).
    assert_eq!(rig.cmd("CONFIG phoenix_format 33"), "OK phoenix_format=33");
    let tokens = rig.send_bytes(b"\x02FAULT\r\n\x03", 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    // A frame broken off by the next one.
    let tokens = rig.send_bytes(b"\x02FAU\x02FAULT\r\n\x03", 2);
    assert_eq!(
        tokens,
        [
            NAK_TOKEN,
            err(ErrorCode::Syntax, texts::PHOENIX_TRUNCATED).as_str(),
            ACK_TOKEN,
            "OK fault=none"
        ]
    );
    assert_eq!(rig.bridge.session_stats().naks, 3);
}

// ---------------------------------------------------------------------------------------
// bad input

#[test]
fn overlong_lines_binary_garbage_and_half_lines_get_an_error_and_the_session_goes_on() {
    let mut rig = Rig::sync65(Settings::default());
    let mut long = std::vec![b'A'; 200];
    long.extend_from_slice(b"\r\nFAULT\r\n");
    let tokens = rig.send_bytes(&long, 2);
    assert_eq!(
        tokens,
        [parse_err(ParseError::TooLong).as_str(), "OK fault=none"]
    );
    let tokens = rig.send_bytes(b"\x80\xff\x00junk\x1b[A\r\nFAULT\n", 2);
    assert_eq!(
        tokens,
        [parse_err(ParseError::Binary).as_str(), "OK fault=none"]
    );
    // A half line followed by a Phoenix frame.
    let mut half = b"SET AMP".to_vec();
    half.extend_from_slice(&framed(113, b"FAULT"));
    let tokens = rig.send_bytes(&half, 2);
    assert_eq!(
        tokens,
        [
            err(ErrorCode::Syntax, texts::LINE_INTERRUPTED).as_str(),
            ACK_TOKEN,
            "OK fault=none"
        ]
    );
    // A half line that goes on in the next chunk is one line.
    assert!(rig.send_bytes(b"FAU", 0).is_empty());
    assert_eq!(rig.send_bytes(b"LT\r", 1), ["OK fault=none"]);
    // LF after CR is part of the same line end; blank lines get no reply.
    assert_eq!(
        rig.send_bytes(b"\n\r\n  \t\r\nFAULT\n", 1),
        ["OK fault=none"]
    );
}

#[test]
fn lines_wait_while_a_command_is_in_progress_and_a_full_queue_says_busy() {
    let mut rig = Rig::sync65(Settings::default());
    let tokens = rig.send_bytes(
        b"SET PROCESS CUT 45 AUTO\r\nFAULT\r\nLIMITS\r\nFLY\r\nEVENTS OFF\r\nFAULT\r\n",
        6,
    );
    assert_eq!(
        tokens,
        [
            err(ErrorCode::Busy, texts::QUEUE_FULL).as_str(),
            "OK mode=CUT amps=45 psi=AUTO",
            "OK fault=none",
            "OK modes=CUT,EXPANDED amps=20..65 psi=58..78 scope=cartridge",
            parse_err(ParseError::UnknownCommand).as_str(),
            "OK events=OFF",
        ]
    );
}

// ---------------------------------------------------------------------------------------
// CONFIG

#[test]
fn config_get_set_and_save_round_trip_through_the_settings_record() {
    let mut rig = Rig::sync65(Settings::default());
    assert_eq!(
        rig.cmd("CONFIG"),
        "OK protocol=AUTO address=1 parity=EVEN stop_bits=1 timeout_ms=100 retries=2 \
         poll_ms=100 interlock_fault=ON interlock_link=ON arc_ok_debounce_ms=2 \
         transfer_timeout_ms=3000 transfer_timeout_drops_start=ON events=OFF hpr_id=0 \
         phoenix_format=113 torch_on_active=LOW torch_on_debounce_ms=1 hold_active=LOW \
         hold_debounce_ms=5 pierce_complete_active=LOW pierce_complete_debounce_ms=5 \
         corner_current_active=LOW corner_current_debounce_ms=5 motion_active=LOW \
         motion_debounce_ms=0 not_ready_active=LOW not_ready_debounce_ms=5 \
         rampdown_error_active=LOW rampdown_error_debounce_ms=5 ps_hold_active=HIGH \
         fault_active=HIGH cnc_address=1 cnc_baud=115200 cnc_parity=NONE \
         cnc_stop_bits=1"
    );
    assert_eq!(rig.cmd("CONFIG timeout_ms"), "OK timeout_ms=100");
    assert_err(&rig.cmd("CONFIG timeout_ms 30"), "ERR RANGE *30*60..1000*");
    assert_err(&rig.cmd("CONFIG parity mark"), "ERR SYNTAX *NONE|EVEN|ODD*");
    assert_err(&rig.cmd("CONFIG baud 9600"), "ERR SYNTAX *SAVE*CONFIG*");
    assert_eq!(
        rig.cmd("CONFIG timeout_ms 80"),
        "OK timeout_ms=80 link=redetecting"
    );
    assert_eq!(
        rig.bridge.link().config().response_timeout,
        Duration::from_millis(80)
    );
    assert!(!rig.bridge.status().link_up, "the link detects again");
    assert_eq!(rig.bridge.take_io_config_change(), None);
    assert_eq!(
        rig.cmd("CONFIG arc_ok_debounce_ms 5"),
        "OK arc_ok_debounce_ms=5"
    );
    assert_eq!(
        rig.bridge
            .take_io_config_change()
            .map(|c| c.arc_ok_debounce),
        Some(Duration::from_millis(5))
    );
    assert_eq!(rig.cmd("CONFIG events on"), "OK events=ON");
    // SAVE waits for the store; a line sent meanwhile waits behind it.
    rig.save_result = None;
    let tokens = rig.send_bytes(b"CONFIG SAVE\r\nCONFIG hpr_id\r\n", 0);
    assert!(tokens.iter().all(|t| !is_reply(t)), "{tokens:?}");
    let settings = rig.bridge.take_save_request().unwrap();
    assert_eq!(rig.bridge.take_save_request(), None, "once");
    let mut record = [0u8; 64];
    let len = settings.encode(&mut record);
    let restored = Settings::decode(&record[..len]).unwrap();
    assert_eq!(restored, *rig.bridge.settings());
    rig.bridge.save_finished(rig.now, Ok(()));
    rig.collect();
    let n = rig.received.len();
    assert_eq!(rig.received[n - 2..], ["OK config=saved", "OK hpr_id=0"]);
    // A failed store.
    rig.save_result = Some(Err(SaveError::Flash));
    assert_err(&rig.cmd("CONFIG SAVE"), "ERR STORAGE *");
    // After a power cycle the bridge runs with what was saved.
    let mut rig = Rig::new(restored, Some("sync65"));
    assert_eq!(rig.cmd("CONFIG timeout_ms"), "OK timeout_ms=80");
    assert_eq!(rig.cmd("CONFIG events"), "OK events=ON");
}

// ---------------------------------------------------------------------------------------
// simulator commands

#[test]
fn torch_is_handed_to_the_simulator_driver() {
    let mut rig = Rig::new(Settings::default(), None);
    assert_eq!(
        rig.cmd("TORCH ON"),
        err(ErrorCode::Unsupported, texts::TORCH_SIMULATOR_ONLY)
    );
    assert_eq!(rig.bridge.poll_sim_command(), None);
    rig.bridge.enable_sim_commands();
    assert_eq!(rig.cmd("TORCH ON"), "OK torch=ON");
    assert_eq!(rig.cmd("torch off"), "OK torch=OFF");
    assert_eq!(rig.bridge.poll_sim_command(), Some(SimCommand::Torch(true)));
    assert_eq!(
        rig.bridge.poll_sim_command(),
        Some(SimCommand::Torch(false))
    );
    assert_eq!(rig.bridge.poll_sim_command(), None);
    assert!(
        rig.cmd("HELP")
            .ends_with("simulator_only=TORCH simulator=YES")
    );
}

// ---------------------------------------------------------------------------------------
// properties

/// Words commands are made of, so that random lines are often real commands.
const WORDS: [&str; 22] = [
    "HELP",
    "ID",
    "STATUS",
    "LIMITS",
    "FAULT",
    "SET",
    "MODE",
    "AMPS",
    "PSI",
    "PROCESS",
    "CUT",
    "45",
    "AUTO",
    "EVENTS",
    "ON",
    "OFF",
    "CONFIG",
    "SAVE",
    "timeout_ms",
    "RAW",
    "TORCH",
    "GASES",
];

fn line_content() -> impl Strategy<Value = Vec<u8>> {
    let word = prop_oneof![
        proptest::sample::select(&WORDS[..]).prop_map(|w| w.as_bytes().to_vec()),
        // Anything but the line ends and the Phoenix start bytes.
        proptest::collection::vec(
            any::<u8>().prop_filter("no CR, LF, SOH, STX", |b| {
                !matches!(*b, b'\r' | b'\n' | 0x01 | 0x02)
            }),
            0..40
        ),
    ];
    proptest::collection::vec(word, 0..8).prop_map(|words| words.join(&b' '))
}

const TERMINATORS: [&[u8]; 3] = [b"\r\n", b"\n", b"\r"];

fn terminator() -> impl Strategy<Value = &'static [u8]> {
    proptest::sample::select(&TERMINATORS[..])
}

/// Feed `bytes` in chunks of `chunk`, serving saves and collecting output after each.
fn feed(rig: &mut Rig, bytes: &[u8], chunk: usize) {
    for part in bytes.chunks(chunk.max(1)) {
        rig.bridge.handle_cnc_rx(rig.now, part);
        rig.now = rig.now + Duration::from_millis(1);
        rig.run(2);
    }
    rig.run(100);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn every_complete_line_gets_exactly_one_reply(
        lines in proptest::collection::vec((line_content(), terminator()), 1..12),
        chunk in 1usize..48,
    ) {
        let mut rig = Rig::new(Settings::default(), None);
        let mut bytes = Vec::new();
        let mut expected = 0;
        for (content, end) in &lines {
            if content.iter().any(|b| *b != b' ' && *b != b'\t') {
                expected += 1;
            }
            bytes.extend_from_slice(content);
            bytes.extend_from_slice(end);
        }
        feed(&mut rig, &bytes, chunk);
        let replies = rig.received.iter().filter(|t| is_reply(t)).count();
        prop_assert_eq!(replies, expected, "{:?}", rig.received);
    }

    #[test]
    fn random_bytes_never_panic_and_output_stays_well_formed(
        bytes in proptest::collection::vec(any::<u8>(), 0..600),
        chunk in 1usize..64,
    ) {
        let mut rig = Rig::sync65(Settings::default());
        let before = rig.received.len();
        feed(&mut rig, &bytes, chunk);
        // `collect` checked every line ends with CR LF and holds printable ASCII only.
        for token in &rig.received[before..] {
            prop_assert!(
                is_reply(token) || token.starts_with('!') || token == ACK_TOKEN
                    || token == NAK_TOKEN,
                "{:?}",
                token
            );
        }
        // The session still answers.
        // End whatever half line the noise left (its reply, if any, is an ERR).
        rig.send_bytes(b"\r\n", 0);
        let reply = rig.cmd("FAULT");
        prop_assert_eq!(reply.as_str(), "OK fault=none");
    }
}

// ---------------------------------------------------------------------------------------
// the remaining replies docs/cnc-protocol.md shows

#[test]
fn documented_replies_not_covered_above() {
    let mut rig = Rig::sync65(Settings::default());
    assert_err(
        &rig.cmd("SET MODE PLASMA"),
        "ERR SYNTAX *CUT|CPA|EXPANDED|GOUGE*",
    );
    assert_err(
        &rig.cmd("GASES XENON AIR"),
        "ERR SYNTAX *O2|CH4|H35|H5|AIR|N2|AR|N95|F5*",
    );
    assert_err(&rig.cmd("EVENTS MAYBE"), "ERR SYNTAX *EVENTS*ON|OFF*");
    rig.fault(500);
    rig.run(300);
    assert_eq!(rig.cmd("RESTART"), "OK restart=done quiet_ms=2000");
    assert!(
        rig.cmd("SET AMPS 40")
            .starts_with("ERR BUSY the unit restarts: quiet for another "),
    );

    let mut rig = Rig::hpr("hpr400xd");
    // RESET only in a shutdown error (state 14, error above 79).
    rig.fault(80);
    rig.run(300);
    assert_eq!(rig.cmd("RESET"), "OK reset=done");
    assert!(rig.cmd("STATUS").contains(" model=HPR400XD family=HPR "));
}

// ---------------------------------------------------------------------------------------
// ERR lines: tests match the code and the values that matter; where the text matters they
// take it from where the session writes it, so no wording is pinned here.

use crate::cnc::texts::{self, UnsupportedText, unsupported};
use crate::link::{CommandFailure, Family, Refusal, SettingsFailure, TransactionError};
use plasma_protocol::cnc::{ErrorCode, ParseError};

/// An `ERR` line with `code` and `text`.
fn err(code: ErrorCode, text: impl core::fmt::Display) -> String {
    std::format!("ERR {code} {text}")
}

/// The `ERR` line of a line that did not parse (the protocol crate's text).
fn parse_err(error: ParseError) -> String {
    err(error.code(), error)
}

/// The `ERR` line of a Phoenix message with a wrong check byte.
fn frame_err(expected: u8, found: u8) -> String {
    let error = plasma_protocol::Error::BadChecksum { expected, found };
    texts::frame_error(error).trim_end().to_string()
}

/// The `ERR` line of a command the link refused.
fn refusal_line(refusal: &Refusal, family: Option<Family>) -> String {
    let mut line = super::ReplyLine::new();
    let _ = super::texts::write_refusal(&mut line, refusal, family, Instant::ZERO);
    line.trim_end().to_string()
}

/// The `ERR` line of a command that was sent and failed.
fn failure_line(failure: &CommandFailure) -> String {
    let mut line = super::ReplyLine::new();
    let _ = super::texts::write_failure(&mut line, failure, None);
    line.trim_end().to_string()
}

/// Assert that `reply` matches `pattern`, where `*` stands for any run of characters: an
/// `ERR` code and the values that matter, not the wording around them.
#[track_caller]
fn assert_err(reply: &str, pattern: &str) {
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

#[test]
fn phoenix_framing_is_recognised_without_setting_phoenix_format() {
    let mut rig = Rig::sync65(Settings::default());
    // Default 113; the CNC sends 112 (no CR LF), 97 (no check byte), then 33 (STX only).
    for format in [112, 97, 97, 33, 33, 113] {
        let tokens = rig.send_bytes(&framed(format, b"FAULT"), 1);
        assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"], "format {format}");
    }
    // A frame no format takes is still refused.
    let mut bad = framed(113, b"FAULT");
    *bad.last_mut().unwrap() ^= 0x01;
    let tokens = rig.send_bytes(&bad, 1);
    assert_eq!(tokens[0], NAK_TOKEN, "{tokens:?}");
    // Once recognised, a format is used at once: no wait for a check byte that never comes.
    rig.send_bytes(&framed(97, b"FAULT"), 1);
    let start = rig.now;
    let tokens = rig.send_bytes(&framed(97, b"FAULT"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    assert_eq!(rig.now, start, "answered without waiting");
    // The key stays an override: set, it is the format expected first again.
    assert_eq!(
        rig.cmd("CONFIG phoenix_format 113"),
        "OK phoenix_format=113"
    );
    let tokens = rig.send_bytes(&framed(113, b"FAULT"), 1);
    assert_eq!(tokens, [ACK_TOKEN, "OK fault=none"]);
    let after = rig.received.len();
    rig.run(200);
    assert_eq!(
        rig.received[after..],
        [] as [String; 0],
        "nothing left over"
    );
}
