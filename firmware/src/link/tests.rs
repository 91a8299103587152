//! Byte-level tests of the whole link: the test feeds the exact reply bytes and moves time.
//!
//! Seed frames from the manuals are used only after their LRC/checksum was recomputed
//! (`assert_lrc` / `hpr_checksum_ok`); the one seed that is wrong is corrected with a note.

extern crate std;

use std::string::String;
use std::vec::Vec;

use plasma_protocol::hpr::{ErrorCode, GasCode, GasPair, StateCode, SystemId};
use plasma_protocol::powermax::{Amps, FaultCode, OperatingMode, PowerSupplyModel, Pressure, Psi};

use super::schedule::UNANSWERED_FACTOR;
use super::*;
use crate::testing::SimPs;
use plasma_protocol::serial::{Parity, PortConfig};
use plasma_sim::clock::earliest;
use plasma_sim::line::Wiring;
use plasma_sim::powermax::UndocumentedAddresses;
use plasma_sim::{Model as SimModel, SimOptions};

// ---------------------------------------------------------------------------------------
// helpers

fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

/// Modbus ASCII frame for node 1 from a binary PDU (LRC computed here, independently).
fn mb(pdu: &[u8]) -> Vec<u8> {
    let mut bytes = std::vec![1u8];
    bytes.extend_from_slice(pdu);
    let sum = bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    bytes.push(sum.wrapping_neg());
    let mut out = String::from(":");
    for b in bytes {
        out.push_str(&std::format!("{b:02X}"));
    }
    out.push_str("\r\n");
    out.into_bytes()
}

/// Recompute the LRC of a seed frame (`:...LL\r\n`) and check it.
fn assert_lrc(frame: &[u8]) {
    let text = core::str::from_utf8(frame).unwrap();
    let hex = text.trim_start_matches(':').trim_end_matches("\r\n");
    let bytes: Vec<u8> = (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect();
    let sum = bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    assert_eq!(sum, 0, "LRC of seed {text:?} does not check");
}

/// HPR frame `>ID data CK<` (checksum computed here).
fn hf(id: u16, data: &str) -> Vec<u8> {
    let body = std::format!("{id:03}{data}");
    let sum = body.bytes().fold(0u8, |s, b| s.wrapping_add(b));
    std::format!(">{body}{sum:02X}<").into_bytes()
}

fn hpr_checksum_ok(frame: &[u8]) -> bool {
    let inner = &frame[1..frame.len() - 3];
    let sum = inner.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    let ck = core::str::from_utf8(&frame[frame.len() - 3..frame.len() - 1]).unwrap();
    u8::from_str_radix(ck, 16).unwrap() == sum
}

/// Drives a link: collects transmitted frames, moves time, and either takes scripted reply
/// bytes from the test or runs the link against a simulated unit of `plasma-sim`.
struct Bench {
    link: PsLink,
    now: Instant,
    sent: Vec<(Instant, Vec<u8>)>,
    /// The unit on the line, for [`Bench::run`].
    unit: Option<SimPs>,
}

impl Bench {
    fn new(config: LinkConfig) -> Self {
        Bench {
            link: PsLink::new(config, Instant::ZERO),
            now: Instant::ZERO,
            sent: Vec::new(),
            unit: None,
        }
    }

    /// A link with the simulated `model` (pbtool's names) on the line.
    fn with_unit(config: LinkConfig, model: &str) -> Self {
        Bench {
            unit: Some(SimPs::new(model)),
            ..Bench::new(config)
        }
    }

    /// Next frame the link sends, advancing time to `poll_at` as needed (up to `limit`).
    fn next_tx(&mut self, limit: Instant) -> Option<Vec<u8>> {
        loop {
            if let Some(frame) = self.link.poll_transmit(self.now) {
                let frame = frame.to_vec();
                self.sent.push((self.now, frame.clone()));
                return Some(frame);
            }
            let at = self.link.poll_at()?;
            // Nothing was sent: the link must not ask for this instant again (a board task
            // sleeping until `poll_at` would spin).
            assert!(at > self.now, "poll_at {at:?} not after {:?}", self.now);
            if at > limit {
                return None;
            }
            self.now = at;
        }
    }

    fn rx(&mut self, delay_ms: u64, bytes: &[u8]) {
        self.now = self.now + Duration::from_millis(delay_ms);
        self.link.handle_rx(self.now, bytes);
    }

    /// The simulated unit.
    fn ps(&mut self) -> &mut SimPs {
        self.unit.as_mut().expect("a bench with a unit")
    }

    /// Run the link against the unit until `until`, or until it sends a frame `stop` accepts
    /// (returned; it is then on its way to the unit).
    fn run_until_sent(
        &mut self,
        until: Instant,
        mut stop: impl FnMut(&[u8]) -> bool,
    ) -> Option<Vec<u8>> {
        let unit = self.unit.as_mut().expect("a bench with a unit");
        loop {
            let mark = unit.sent.len();
            let mut line_next = unit.exchange(&mut self.link, self.now);
            let mut link_next = self.link.poll_at();
            if link_next.is_some_and(|at| at <= self.now) {
                // What just arrived may have made a frame due now: it goes out at once.
                line_next = earliest(line_next, unit.exchange(&mut self.link, self.now));
                link_next = self.link.poll_at();
                // Nothing more to send: the link must not ask for this instant again (a
                // board task sleeping until `poll_at` would spin).
                if let Some(at) = link_next {
                    assert!(at > self.now, "poll_at {at:?} not after {:?}", self.now);
                }
            }
            self.sent.extend(unit.sent[mark..].iter().cloned());
            if let Some((_, frame)) = unit.sent[mark..].iter().find(|(_, f)| stop(f)) {
                return Some(frame.clone());
            }
            match earliest(line_next, link_next) {
                Some(at) if at <= until => self.now = self.now.max(at),
                _ => break,
            }
        }
        self.now = self.now.max(until);
        None
    }

    /// Run the link against the unit until `until`.
    fn run(&mut self, until: Instant) {
        self.run_until_sent(until, |_| false);
    }

    /// The write requests (functions 05, 06, 0x10) sent since `mark` (an index into `sent`).
    fn writes_since(&self, mark: usize) -> Vec<Vec<u8>> {
        self.sent[mark..]
            .iter()
            .map(|(_, f)| f)
            .filter(|f| f.len() > 5 && matches!(&f[3..5], b"05" | b"06" | b"10"))
            .cloned()
            .collect()
    }

    /// Everything the unit sent the link so far, as one text.
    fn heard(&mut self) -> Vec<u8> {
        self.ps().heard.iter().map(|&(_, b)| b).collect()
    }

    /// The unit raises fault `code` now (its own numbering); 0 clears it.
    fn fault(&mut self, code: u16) {
        let now = self.now;
        let unit = self.ps().unit();
        match code {
            0 => unit.clear_fault(now),
            code => unit.inject_fault(now, code),
        }
    }

    /// Pulls the unit's serial cable now (true), or plugs it back (false).
    fn unplug(&mut self, unplugged: bool) {
        let now = self.now;
        self.ps().unplug(now, unplugged);
    }

    fn events(&mut self) -> Vec<LinkEvent> {
        core::iter::from_fn(|| self.link.poll_event()).collect()
    }
}

/// A Powermax65 SYNC found and its slow data read.
fn sync_bench() -> Bench {
    let mut bench = Bench::with_unit(LinkConfig::default(), "sync65");
    bench.run(ms(500));
    assert!(bench.link.status().link_up);
    assert!(
        bench.link.status().limits.is_some(),
        "slow data read at start"
    );
    bench
}

fn amps(a: u16) -> Amps {
    Amps::from_whole(a).unwrap()
}

// ---------------------------------------------------------------------------------------
// detection

#[test]
fn detects_sync_by_device_identification() {
    let mut bench = Bench::new(LinkConfig::default());
    assert_eq!(bench.link.port_config(), PortConfig::MODBUS_DEFAULT);
    let request = bench.next_tx(ms(0)).unwrap();
    // SYNC guide example request (LRC C1 rechecked).
    assert_lrc(b":012B0E0401C1\r\n");
    assert_eq!(request, b":012B0E0401C1\r\n");
    let reply = b":012B0E0481000101010630383133333504\r\n";
    assert_lrc(reply);
    // Any chunking: byte by byte.
    for &b in reply.iter() {
        bench.rx(0, &[b]);
    }
    assert_eq!(
        bench.events().first(),
        Some(&LinkEvent::LinkUp {
            model: Model::Powermax(PowerSupplyModel::Powermax65_85_105Sync),
            family: Family::PowermaxSync,
        })
    );
    // First SYNC poll: 0x3010-0x301A in ONE function-04 request.
    let poll = bench.next_tx(ms(10)).unwrap();
    assert_eq!(poll, mb(&[0x04, 0x30, 0x10, 0x00, 0x0B]));
}

#[test]
fn detects_legacy_by_device_identification() {
    let mut bench = Bench::with_unit(LinkConfig::default(), "pm65");
    bench.run(ms(100));
    assert_eq!(bench.link.status().family, Some(Family::PowermaxLegacy));
    assert_eq!(
        bench.link.status().model,
        Some(Model::Powermax(PowerSupplyModel::Powermax65_85_105))
    );
}

#[test]
fn finds_a_legacy_unit_without_device_identification_by_a_register_read() {
    let mut bench = Bench::new(LinkConfig::default());
    // Three attempts of 2B/0E time out (100 ms each, immediate retries).
    for attempt in 0..3 {
        assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
        assert_eq!(bench.now, ms(100 * attempt));
    }
    // Then the plain legacy fault read (legacy guide sample, LRC 42 rechecked).
    let probe = bench.next_tx(ms(1000)).unwrap();
    assert_lrc(b":01042098000142\r\n");
    assert_eq!(probe, b":01042098000142\r\n");
    assert_eq!(bench.now, ms(300));
    assert_eq!(bench.link.diagnostics().timeouts, 3);
    assert_eq!(bench.link.diagnostics().retries, 2);
    let reply = b":010402006F8A\r\n";
    assert_lrc(reply);
    bench.rx(5, reply);
    assert_eq!(bench.link.status().family, Some(Family::PowermaxLegacy));
    assert_eq!(bench.link.status().model, Some(Model::PowermaxUnidentified));
}

#[test]
fn a_unit_refusing_device_identification_is_probed_with_a_register_read() {
    let mut bench = Bench::new(LinkConfig::default());
    bench.next_tx(ms(0)).unwrap();
    bench.rx(5, &mb(&[0xAB, 0x01]));
    assert_eq!(bench.link.diagnostics().exceptions[0], 1);
    // Not retried: an exception is the unit's answer.
    assert_eq!(bench.next_tx(ms(10)).unwrap(), b":01042098000142\r\n");
}

#[test]
fn finds_hpr_after_modbus_silence_and_switches_to_8n1() {
    let mut bench = Bench::new(LinkConfig::default());
    for _ in 0..6 {
        let frame = bench.next_tx(ms(5000)).unwrap();
        assert_eq!(frame[0], b':');
    }
    let hello = bench.next_tx(ms(5000)).unwrap();
    assert_eq!(hello, b">00090<", "HELLO, no CR/LF");
    assert_eq!(bench.link.port_config(), PortConfig::HPR);
    // The manual's sample prints HYPERPERFORMANCE; its checksum only fits HYPERFORMANCE.
    let reply = hf(0, "HYPERFORMANCE130AUTO");
    assert_eq!(reply, b">000HYPERFORMANCE130AUTO30<");
    bench.rx(5, &reply);
    assert_eq!(bench.link.status().family, Some(Family::Hpr));
    let poll = bench.next_tx(ms(5000)).unwrap();
    assert_eq!(poll, b">079A0<");
    assert!(hpr_checksum_ok(&poll));
}

#[test]
fn detects_maxpro200() {
    let config = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        ..LinkConfig::default()
    };
    let mut bench = Bench::new(config);
    assert_eq!(bench.next_tx(ms(0)).unwrap(), b">00090<");
    let reply = b">000MaxPro20079<";
    assert!(hpr_checksum_ok(reply));
    bench.rx(3, reply);
    assert_eq!(bench.link.status().family, Some(Family::MaxPro200));
    assert_eq!(
        bench.link.status().model,
        Some(Model::Hpr(SystemId::MaxPro200))
    );
}

#[test]
fn multi_drop_id_sleeps_the_line_then_wakes_the_unit() {
    let config = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        hpr_id: 2,
        ..LinkConfig::default()
    };
    let mut bench = Bench::new(config);
    assert_eq!(bench.next_tx(ms(0)).unwrap(), b">0869E<");
    // SLEEP has no reply: WAKE follows after the quiet time.
    assert_eq!(bench.next_tx(ms(100)).unwrap(), hf(85, "2"));
    assert_eq!(bench.now, ms(20));
    bench.rx(2, &hf(85, "2"));
    assert_eq!(bench.next_tx(ms(100)).unwrap(), b">00090<");
}

#[test]
fn auto_detection_tries_other_modbus_framings_in_later_rounds() {
    let mut bench = Bench::new(LinkConfig::default());
    let mut ports = Vec::new();
    while bench.now < ms(8000) {
        if bench.next_tx(ms(8000)).is_some() {
            ports.push(bench.link.port_config());
        } else {
            break;
        }
    }
    assert!(ports.iter().any(|p| p.parity == Parity::Odd));
    assert!(ports.contains(&PortConfig::HPR));
}

// ---------------------------------------------------------------------------------------
// transactions: validation and classification

#[test]
fn replies_are_validated_and_errors_classified() {
    let mut bench = Bench::new(LinkConfig::default());
    bench.next_tx(ms(0)).unwrap();
    // Wrong node address: mismatch, retried.
    let mut other = b":022B0E0481000101010630383133333503\r\n".to_vec();
    assert_lrc(&other);
    bench.rx(5, &other);
    assert_eq!(bench.link.diagnostics().mismatches, 1);
    assert_eq!(bench.next_tx(ms(10)).unwrap(), b":012B0E0401C1\r\n");
    // Damaged LRC: bad checksum, retried.
    other = b":012B0E0481000101010630383133333505\r\n".to_vec();
    bench.rx(5, &other);
    assert_eq!(bench.link.diagnostics().bad_checksums, 1);
    assert_eq!(bench.link.diagnostics().retries, 2);
    bench.next_tx(ms(20)).unwrap();
    bench.rx(5, b":012B0E0481000101010630383133333504\r\n");
    assert!(bench.link.status().link_up);
    assert_eq!(bench.link.diagnostics().transactions_ok, 1);
}

#[test]
fn link_goes_down_after_consecutive_failures_and_detection_restarts() {
    let mut bench = sync_bench();
    bench.events();
    bench.unplug(true);
    // 3 transactions x 3 attempts x 100 ms, with a poll interval between them.
    bench.run(bench.now + Duration::from_millis(1100));
    let events = bench.events();
    assert!(events.iter().any(|e| matches!(
        e,
        LinkEvent::LinkDown {
            reason: LinkDownReason::ConsecutiveFailures {
                count: 3,
                last_error: TransactionError::Timeout
            }
        }
    )));
    assert!(!bench.link.status().link_up);
    assert_eq!(bench.link.diagnostics().link_downs, 1);
    let next = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
    assert_eq!(next, b":012B0E0401C1\r\n", "auto-detection again");
}

// ---------------------------------------------------------------------------------------
// SYNC settings

#[test]
fn settings_outside_the_limits_are_refused_before_anything_is_sent() {
    let mut bench = Bench::new(LinkConfig::default());
    assert_eq!(
        bench.link.submit(ms(0), LinkCommand::ExitRemote),
        Err(Refusal::LinkNotUp)
    );
    let mut bench = sync_bench();
    let before = bench.sent.len();
    let now = bench.now;
    let refuse = |bench: &mut Bench, mode, current, pressure| {
        bench.link.submit(
            now,
            LinkCommand::ApplySettings {
                mode,
                current,
                pressure,
            },
        )
    };
    assert_eq!(
        refuse(&mut bench, OperatingMode::Cut, amps(66), Pressure::Auto),
        Err(Refusal::CurrentOutOfRange {
            requested: amps(66),
            min: amps(20),
            max: amps(65)
        })
    );
    assert_eq!(
        refuse(&mut bench, OperatingMode::Cut, amps(19), Pressure::Auto),
        Err(Refusal::CurrentOutOfRange {
            requested: amps(19),
            min: amps(20),
            max: amps(65)
        })
    );
    let psi = |p| Psi::from_whole(p).unwrap();
    assert_eq!(
        refuse(
            &mut bench,
            OperatingMode::Cut,
            amps(45),
            Pressure::Set(psi(80))
        ),
        Err(Refusal::PressureOutOfRange {
            requested: psi(80),
            min: psi(58),
            max: psi(78)
        })
    );
    assert!(matches!(
        refuse(&mut bench, OperatingMode::Gouge, amps(45), Pressure::Auto),
        Err(Refusal::ModeNotPermitted {
            mode: OperatingMode::Gouge,
            ..
        })
    ));
    // Nothing but polls goes out afterwards.
    bench.run(now + Duration::from_millis(300));
    assert!(bench.sent.len() > before);
    assert!(bench.writes_since(before).is_empty());
}

#[test]
fn cut_at_63_a_with_automatic_pressure_is_the_guides_frame_and_is_read_back() {
    let mut bench = sync_bench();
    bench.events();
    let ticket = bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplySettings {
                mode: OperatingMode::Cut,
                current: amps(63),
                pressure: Pressure::Auto,
            },
        )
        .unwrap();
    // Let any poll in flight finish, then the write goes out.
    let limit = bench.now + Duration::from_secs(1);
    let write = bench
        .run_until_sent(limit, |f| f.starts_with(b":0110"))
        .unwrap();
    assert_lrc(b":0110308000030600010FC0000066\r\n");
    assert_eq!(write, b":0110308000030600010FC0000066\r\n");
    // Read back 0x3010-0x3012 (guide's request, LRC B8 rechecked) after the unit's reply.
    let limit = bench.now + Duration::from_millis(200);
    let read_back = bench
        .run_until_sent(limit, |f| f.starts_with(b":01043010"))
        .unwrap();
    assert!(bench.heard().ends_with(b":0110308000033C\r\n"));
    assert_eq!(read_back, b":010430100003B8\r\n");
    bench.run(bench.now + Duration::from_millis(100));
    let events = bench.events();
    let applied = PowermaxSettings {
        mode: Some(OperatingMode::Cut),
        current: amps(63),
        pressure: Pressure::Auto,
    };
    // What the unit reads back: in automatic pressure, the pressure it picked.
    let read_back = PowermaxSettings {
        pressure: Pressure::Set(Psi::from_whole(72).unwrap()),
        ..applied
    };
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: true }));
    assert!(events.contains(&LinkEvent::SettingsApplied {
        settings: read_back,
        reapplied: false
    }));
    assert!(events.contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Settings(read_back))
    }));
    assert_eq!(bench.link.kept().powermax(), Some(applied));
    assert!(bench.link.status().remote);
}

#[test]
fn a_read_back_that_differs_fails_the_command() {
    let mut bench = sync_bench();
    // A unit that acknowledges the write but keeps its panel settings.
    bench.ps().powermax().config_mut().remote_settings_apply = false;
    let ticket = bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplySettings {
                mode: OperatingMode::Cut,
                current: amps(63),
                pressure: Pressure::Auto,
            },
        )
        .unwrap();
    let limit = bench.now + Duration::from_millis(200);
    bench
        .run_until_sent(limit, |f| f == b":010430100003B8\r\n")
        .unwrap();
    bench.run(bench.now + Duration::from_millis(100));
    let events = bench.events();
    assert!(events.iter().any(|e| matches!(
        e,
        LinkEvent::CommandDone { ticket: t, result: Err(CommandFailure::Settings(SettingsFailure::ReadBackDiffers { .. })) } if *t == ticket
    )));
    assert_eq!(bench.link.kept().powermax(), None);
}

#[test]
fn exit_remote_writes_zeros_to_all_three_registers() {
    let mut bench = sync_bench();
    bench
        .link
        .submit(bench.now, LinkCommand::ExitRemote)
        .unwrap();
    let limit = bench.now + Duration::from_secs(1);
    let write = bench
        .run_until_sent(limit, |f| f.starts_with(b":0110"))
        .unwrap();
    // The SYNC guide prints `:01103080000306000000000000036`, which has one '0' too many
    // (15 characters after 06 instead of 12 zeros + LRC). Recomputed: LRC 36 over
    // 01 10 30 80 00 03 06 00 00 00 00 00 00.
    assert_lrc(b":0110308000030600000000000036\r\n");
    assert_eq!(write, b":0110308000030600000000000036\r\n");
}

#[test]
fn kept_settings_are_reapplied_when_the_unit_reverts_after_a_power_cycle() {
    let mut bench = sync_bench();
    bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplySettings {
                mode: OperatingMode::Cut,
                current: amps(63),
                pressure: Pressure::Auto,
            },
        )
        .unwrap();
    bench.run(bench.now + Duration::from_millis(300));
    assert!(bench.link.status().remote);
    bench.events();
    let mark = bench.sent.len();
    // Power cycle: the unit is back on its own settings.
    let now = bench.now;
    bench.ps().unit().power_off(now);
    bench.ps().unit().power_on(now);
    bench.run(bench.now + Duration::from_millis(300));
    let events = bench.events();
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: false }));
    assert!(events.iter().any(|e| matches!(
        e,
        LinkEvent::SettingsApplied {
            reapplied: true,
            ..
        }
    )));
    assert_eq!(
        bench.writes_since(mark).first().map(|w| w.as_slice()),
        Some(&b":0110308000030600010FC0000066\r\n"[..])
    );
    assert!(bench.link.status().remote);
}

#[test]
fn kept_settings_are_reapplied_when_the_link_returns() {
    let mut bench = sync_bench();
    bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplySettings {
                mode: OperatingMode::Cut,
                current: amps(63),
                pressure: Pressure::Auto,
            },
        )
        .unwrap();
    bench.run(bench.now + Duration::from_millis(300));
    bench.unplug(true);
    bench.run(bench.now + Duration::from_millis(1000));
    assert!(!bench.link.status().link_up);
    assert!(
        bench.link.kept().powermax().is_some(),
        "kept across the link-down"
    );
    bench.unplug(false);
    let mark = bench.sent.len();
    bench.run(bench.now + Duration::from_millis(2000));
    assert!(bench.link.status().link_up);
    assert_eq!(
        bench.writes_since(mark).first().map(|w| w.as_slice()),
        Some(&b":0110308000030600010FC0000066\r\n"[..])
    );
}

// ---------------------------------------------------------------------------------------
// faults, quick restart, gas test

#[test]
fn a_new_fault_is_reported_within_one_poll_interval() {
    let mut bench = sync_bench();
    bench.events();
    let t0 = bench.now;
    bench.fault(500);
    bench.run(t0 + Duration::from_millis(200));
    let events = bench.events();
    let raised = LinkEvent::FaultRaised {
        code: ActiveFault::Powermax(FaultCode(500)),
        action_required: true,
    };
    assert!(events.contains(&raised));
    assert!(!bench.link.status().ready);
    bench.fault(0);
    bench.run(bench.now + Duration::from_millis(200));
    assert!(bench.events().contains(&LinkEvent::FaultCleared {
        code: ActiveFault::Powermax(FaultCode(500))
    }));
    assert!(bench.link.status().ready);
}

/// The SYNC reads that see the active fault: the status block, and the fault register alone.
fn sync_fault_reads(sent: &[(Instant, Vec<u8>)]) -> (Vec<Instant>, usize, usize) {
    let block = mb(&[0x04, 0x30, 0x10, 0x00, 0x0B]);
    let alone = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    let at: Vec<Instant> = sent
        .iter()
        .filter(|(_, f)| *f == block || *f == alone)
        .map(|(t, _)| *t)
        .collect();
    let polls = sent.iter().filter(|(_, f)| *f == block).count();
    (at, polls, sent.iter().filter(|(_, f)| *f == alone).count())
}

/// The longest time between two reads of the fault register.
fn longest_gap(at: &[Instant]) -> Duration {
    at.windows(2)
        .map(|w| w[1].saturating_since(w[0]))
        .max()
        .unwrap()
}

#[test]
fn between_two_polls_the_fault_register_is_read_alone() {
    let mut bench = sync_bench();
    let mark = bench.sent.len();
    bench.run(bench.now + Duration::from_millis(2000));
    let (at, polls, alone) = sync_fault_reads(&bench.sent[mark..]);
    // The poll keeps its 100 ms; one short read goes between two polls.
    assert!((19..=21).contains(&polls), "{polls}");
    assert!(alone.abs_diff(polls) <= 1, "{polls} {alone}");
    // Alone never sooner than the interval after the last read of the fault register, and
    // late only by a transaction already on the line (the cartridge check, 8 registers).
    let alone_at: Vec<Instant> = bench.sent[mark..]
        .iter()
        .filter(|(_, f)| *f == mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]))
        .map(|(t, _)| *t)
        .collect();
    for (previous, next) in at.iter().zip(&at[1..]) {
        if alone_at.contains(next) {
            assert!(
                next.saturating_since(*previous) >= FAULT_CHECK_INTERVAL,
                "{at:?}"
            );
        }
    }
    assert!(
        longest_gap(&at) <= FAULT_CHECK_INTERVAL + Duration::from_millis(45),
        "{at:?}"
    );
    // Its answer raises a fault that appeared after the poll's read.
    let block = mb(&[0x04, 0x30, 0x10, 0x00, 0x0B]);
    let alone = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    bench.run_until_sent(bench.now + Duration::from_millis(200), |f| f == block);
    bench.run(bench.now + Duration::from_millis(50));
    bench.events();
    bench.fault(500);
    let sent = bench.run_until_sent(bench.now + Duration::from_millis(200), |f| {
        f == block || f == alone
    });
    assert_eq!(sent, Some(alone));
    // Request, the unit's 3 ms, the reply: about 21 ms.
    bench.run(bench.now + Duration::from_millis(25));
    assert!(
        bench
            .events()
            .iter()
            .any(|e| matches!(e, LinkEvent::FaultRaised { .. }))
    );
}

#[test]
fn a_stream_of_commands_starves_neither_the_fault_checks_nor_the_slow_data() {
    let mut bench = sync_bench();
    bench.events();
    let counters = bench
        .link
        .submit(bench.now, LinkCommand::RefreshSlowData)
        .unwrap();
    let mark = bench.sent.len();
    let until = bench.now + Duration::from_millis(2000);
    let mut applied = 0;
    let mut counters_done = false;
    while bench.now < until {
        // The queue is kept full.
        while bench
            .link
            .submit(
                bench.now,
                LinkCommand::ApplySettings {
                    mode: OperatingMode::Cut,
                    current: amps(40 + (applied % 2) as u16 * 5),
                    pressure: Pressure::Auto,
                },
            )
            .is_ok()
        {
            applied += 1;
        }
        bench.run(bench.now + Duration::from_millis(10));
        for event in bench.events() {
            if let LinkEvent::CommandDone { ticket, result } = event
                && ticket == counters
            {
                assert_eq!(result, Ok(CommandOutput::Done));
                counters_done = true;
            }
        }
    }
    assert!(counters_done, "the slow data was read all the same");
    assert!(applied >= 10, "{applied}");
    let (at, polls, _) = sync_fault_reads(&bench.sent[mark..]);
    // A command of two transactions, then the fault register (or a poll, when due).
    assert!(polls >= 10, "{polls}");
    assert!(
        longest_gap(&at) <= FAULT_CHECK_INTERVAL + Duration::from_millis(80),
        "{at:?}"
    );
}

#[test]
fn a_unit_that_refuses_the_fault_register_alone_is_left_to_the_polls() {
    let mut bench = Bench::new(LinkConfig::default());
    bench.next_tx(ms(0)).unwrap();
    bench.rx(20, b":012B0E0481000101010630383133333504\r\n");
    let alone = mb(&[0x04, 0x30, 0x1A, 0x00, 0x01]);
    let mut refused = 0;
    // Every read answered with zeros, but the fault register alone with exception 02.
    while let Some(request) = bench.next_tx(ms(2000)) {
        let text = core::str::from_utf8(&request).unwrap();
        let quantity = u16::from_str_radix(&text[9..13], 16).unwrap();
        let reply = if request == alone {
            refused += 1;
            mb(&[0x84, 0x02])
        } else {
            let mut pdu = std::vec![0x04, (quantity * 2) as u8];
            pdu.resize(2 + usize::from(quantity) * 2, 0);
            mb(&pdu)
        };
        bench.rx(30, &reply);
    }
    assert_eq!(refused, 1);
    let (at, polls, _) = sync_fault_reads(&bench.sent);
    assert!(polls >= 15, "{polls}");
    // Every 100 ms, late by at most one other transaction (30 ms here).
    assert!(
        longest_gap(&at[2..]) <= Duration::from_millis(130),
        "{at:?}"
    );
}

#[test]
fn quick_restart_needs_0_50_0_and_is_followed_by_2_s_of_silence() {
    let mut bench = sync_bench();
    assert_eq!(
        bench.link.submit(bench.now, LinkCommand::QuickRestart),
        Err(Refusal::QuickRestartNeeds050 { active: None })
    );
    bench.fault(121);
    bench.run(bench.now + Duration::from_millis(200));
    assert_eq!(
        bench.link.submit(bench.now, LinkCommand::QuickRestart),
        Err(Refusal::QuickRestartNeeds050 {
            active: Some(FaultCode(121))
        })
    );
    bench.fault(500);
    bench.run(bench.now + Duration::from_millis(200));
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::QuickRestart)
        .unwrap();
    let limit = bench.now + Duration::from_secs(1);
    let restart = bench
        .run_until_sent(limit, |f| f.starts_with(b":0110308E"))
        .unwrap();
    assert_lrc(b":0110308E0002040404061805\r\n");
    assert_eq!(restart, b":0110308E0002040404061805\r\n");
    // The unit's reply; nothing goes out afterwards (the quiet time).
    bench.run(bench.now + Duration::from_millis(100));
    assert!(bench.heard().ends_with(b":0110308E00022F\r\n"));
    let t_reply = bench.ps().heard.last().unwrap().0;
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Done)
    }));
    assert_eq!(
        bench.link.status().restart_blackout_until,
        Some(t_reply + Duration::from_secs(2))
    );
    assert!(!bench.link.status().ready);
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::GasTest { on: true }),
        Err(Refusal::Blackout {
            until: t_reply + Duration::from_secs(2)
        })
    );
    assert_eq!(bench.link.poll_at(), Some(t_reply + Duration::from_secs(2)));
    assert!(
        bench
            .link
            .poll_transmit(t_reply + Duration::from_millis(1999))
            .is_none()
    );
    let next = bench
        .link
        .poll_transmit(t_reply + Duration::from_secs(2))
        .map(|f| f.to_vec());
    assert!(next.is_some(), "traffic resumes after 2 s");
}

#[test]
fn gas_test_writes_the_coil() {
    let mut bench = sync_bench();
    bench
        .link
        .submit(bench.now, LinkCommand::GasTest { on: true })
        .unwrap();
    bench.run(bench.now + Duration::from_millis(200));
    assert_lrc(b":01053180FF004A\r\n");
    assert!(
        bench
            .writes_since(0)
            .iter()
            .any(|w| w == b":01053180FF004A\r\n")
    );
}

// ---------------------------------------------------------------------------------------
// block reads with fallback

#[test]
fn sync_block_read_falls_back_to_documented_parts_and_remembers() {
    let mut bench = Bench::with_unit(LinkConfig::default(), "sync65");
    // A unit that refuses block reads over 0x3013-0x3017.
    bench.ps().powermax().config_mut().undocumented = UndocumentedAddresses::Refuse;
    bench.run(ms(1000));
    let polls: Vec<&Vec<u8>> = bench
        .sent
        .iter()
        .map(|(_, f)| f)
        .filter(|f| f.starts_with(b":01043010") || f.starts_with(b":01043018"))
        .collect();
    // Whole block once, then only the parts.
    let whole = mb(&[0x04, 0x30, 0x10, 0x00, 0x0B]);
    assert_eq!(polls.iter().filter(|f| ***f == whole).count(), 1);
    assert!(
        polls
            .iter()
            .filter(|f| ***f == mb(&[0x04, 0x30, 0x10, 0x00, 0x03]))
            .count()
            >= 3
    );
    assert!(
        polls
            .iter()
            .filter(|f| ***f == mb(&[0x04, 0x30, 0x18, 0x00, 0x03]))
            .count()
            >= 3
    );
    bench.fault(500);
    bench.run(ms(1300));
    assert_eq!(
        bench.link.status().active_fault,
        Some(ActiveFault::Powermax(FaultCode(500)))
    );
}

#[test]
fn legacy_block_read_falls_back_and_drops_refused_parts() {
    let mut bench = Bench::with_unit(LinkConfig::default(), "pm65");
    // A unit that refuses the gaps and the write-only force registers.
    let config = bench.ps().powermax().config_mut();
    config.undocumented = UndocumentedAddresses::Refuse;
    config.refused_registers = std::vec![0x2093, 0x2094, 0x2096];
    bench.fault(111);
    bench.run(ms(1000));
    let sent: Vec<Vec<u8>> = bench.sent.iter().map(|(_, f)| f.clone()).collect();
    let whole = mb(&[0x04, 0x20, 0x93, 0x00, 0x0D]);
    let force = mb(&[0x04, 0x20, 0x93, 0x00, 0x02]);
    let status = mb(&[0x04, 0x20, 0x98, 0x00, 0x03]);
    assert_eq!(sent.iter().filter(|f| **f == whole).count(), 1);
    assert_eq!(
        sent.iter().filter(|f| **f == force).count(),
        1,
        "refused part not asked again"
    );
    assert!(sent.iter().filter(|f| **f == status).count() >= 3);
    let s = bench.link.status();
    assert_eq!(s.active_fault, Some(ActiveFault::Powermax(FaultCode(111))));
    assert_eq!(s.limits.map(|l| l.max_current), Some(amps(65)));
    assert_eq!(
        bench
            .link
            .diagnostics()
            .exceptions_with(plasma_protocol::modbus_ascii::ExceptionCode::IllegalDataAddress),
        3
    );
}

#[test]
fn legacy_settings_use_the_three_force_registers() {
    let mut bench = Bench::with_unit(LinkConfig::default(), "pm65");
    bench.run(ms(300));
    let mark = bench.sent.len();
    let ticket = bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplySettings {
                mode: OperatingMode::Cut,
                current: amps(65),
                pressure: Pressure::Set(Psi::from_whole(70).unwrap()),
            },
        )
        .unwrap();
    bench.run(bench.now + Duration::from_millis(300));
    // Legacy guide samples (LRCs 45, F5, 20 rechecked).
    for seed in [
        &b":01062093000145\r\n"[..],
        b":010620941040F5\r\n",
        b":01062096230020\r\n",
    ] {
        assert_lrc(seed);
    }
    let writes = bench.writes_since(mark);
    let writes: Vec<&[u8]> = writes.iter().map(|w| w.as_slice()).collect();
    assert_eq!(
        writes,
        std::vec![
            &b":01062093000145\r\n"[..],
            b":010620941040F5\r\n",
            b":01062096230020\r\n"
        ]
    );
    assert!(bench.events().iter().any(|e| matches!(e, LinkEvent::CommandDone { ticket: t, result: Ok(CommandOutput::Settings(_)) } if *t == ticket)));
    let mark = bench.sent.len();
    bench
        .link
        .submit(bench.now, LinkCommand::ExitRemote)
        .unwrap();
    bench.run(bench.now + Duration::from_millis(300));
    let zeros: Vec<Vec<u8>> = [0x93u8, 0x94, 0x96]
        .iter()
        .map(|&r| mb(&[0x06, 0x20, r, 0, 0]))
        .collect();
    assert_eq!(bench.writes_since(mark), zeros);
}

// ---------------------------------------------------------------------------------------
// RAW and allow-lists

#[test]
fn raw_modbus_reads_are_forwarded_and_unlisted_writes_refused() {
    let mut bench = sync_bench();
    fn raw(bytes: &[u8]) -> LinkCommand<'_> {
        LinkCommand::Raw(bytes)
    }
    let now = bench.now;
    assert_eq!(
        bench
            .link
            .submit(now, raw(&mb(&[0x10, 0x30, 0x8E, 0, 2, 4, 4, 4, 6, 0x18]))),
        Err(Refusal::RawWriteNotAllowed { address: 0x308E })
    );
    assert_eq!(
        bench.link.submit(now, raw(&mb(&[0x06, 0x30, 0x00, 0, 1]))),
        Err(Refusal::RawWriteNotAllowed { address: 0x3000 })
    );
    assert_eq!(
        bench
            .link
            .submit(now, raw(&mb(&[0x05, 0x31, 0x00, 0xFF, 0]))),
        Err(Refusal::RawWriteNotAllowed { address: 0x3100 })
    );
    assert!(matches!(
        bench.link.submit(now, raw(b":0104301A0001B1\r\n")),
        Err(Refusal::RawMalformed(
            plasma_protocol::Error::BadChecksum { .. }
        ))
    ));
    let ticket = bench.link.submit(now, raw(b":0104301A0001B0\r\n")).unwrap();
    bench.fault(500);
    bench.run(now + Duration::from_millis(200));
    let done = bench.events().into_iter().find_map(|e| match e {
        LinkEvent::CommandDone { ticket: t, result } if t == ticket => Some(result),
        _ => None,
    });
    assert_eq!(done, Some(Ok(CommandOutput::Raw { len: 15 })));
    assert_lrc(b":01040201F404\r\n");
    assert_eq!(bench.link.raw_reply(), b":01040201F404\r\n");
}

// ---------------------------------------------------------------------------------------
// HPR

fn hpr_bench(system: &str) -> Bench {
    let config = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        ..LinkConfig::default()
    };
    let mut bench = Bench::new(config);
    bench.next_tx(ms(0)).unwrap();
    bench.rx(3, &hf(0, system));
    assert!(bench.link.status().link_up);
    bench
}

fn ps_info(state: u16, error: u16) -> Vec<u8> {
    hf(
        79,
        &std::format!(
            "PC0044 PP0042 SC0034 SP0035 CS0130 ST{state:04} ER{error:04} CG0000 CG0000 MV0000 MV0000"
        ),
    )
}

#[test]
fn hpr_retries_span_more_than_a_one_second_blackout() {
    let mut bench = hpr_bench("HYPERFORMANCE260AUTO");
    let t0 = bench.now;
    let mut times = Vec::new();
    for _ in 0..3 {
        bench.next_tx(t0 + Duration::from_secs(5)).unwrap();
        times.push(bench.now);
    }
    assert_eq!(
        times[1].saturating_since(times[0]),
        Duration::from_millis(450)
    );
    assert!(times[2].saturating_since(times[0]) > Duration::from_millis(1200));
    // The third attempt gets through the noise.
    bench.rx(3, &ps_info(3, 0));
    assert_eq!(bench.link.status().hpr.state, Some(StateCode(3)));
    assert!(bench.link.status().ready);
}

#[test]
fn hpr_error_replies_are_classified() {
    let mut bench = hpr_bench("HYPERFORMANCE130MANUAL");
    bench.next_tx(bench.now).unwrap();
    bench.rx(2, b">50095<");
    assert_eq!(bench.link.diagnostics().hpr_bad_checksum_500, 1);
    let retry = bench.next_tx(bench.now + Duration::from_secs(2)).unwrap();
    assert_eq!(retry, b">079A0<");
    bench.rx(2, b">50196<");
    assert_eq!(bench.link.diagnostics().hpr_unknown_command_501, 1);
    assert_eq!(bench.link.diagnostics().transactions_failed, 1);
}

#[test]
fn hpr_pauses_during_pilot_arc_then_asks_only_for_the_state() {
    let mut bench = hpr_bench("HYPERFORMANCE130AUTO");
    bench.next_tx(bench.now).unwrap();
    bench.rx(2, &ps_info(5, 0));
    let t = bench.now;
    assert_eq!(bench.link.poll_at(), Some(t + Duration::from_secs(1)));
    assert!(
        bench
            .link
            .poll_transmit(t + Duration::from_millis(999))
            .is_none()
    );
    assert_eq!(
        bench
            .link
            .poll_transmit(t + Duration::from_secs(1))
            .map(|f| f.to_vec()),
        Some(b">00292<".to_vec())
    );
}

#[test]
fn hpr_settings_are_range_checked_and_preceded_by_remote_mode() {
    let mut bench = hpr_bench("HYPERFORMANCE130AUTO");
    bench.next_tx(bench.now).unwrap();
    bench.rx(2, &ps_info(3, 0));
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSetNominalAmps { amps: 131 }),
        Err(Refusal::HprValueOutOfRange {
            value: HprValue::Amps,
            requested: 131,
            min: 5,
            max: 130
        })
    );
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSetCornerCurrent { percent: 49 }),
        Err(Refusal::HprValueOutOfRange {
            value: HprValue::CornerPercent,
            requested: 49,
            min: 50,
            max: 100
        })
    );
    assert_eq!(
        bench.link.submit(bench.now, LinkCommand::HprSoftwareReset),
        Err(Refusal::StateForbids {
            state: Some(StateCode(3)),
            error: Some(ErrorCode(0))
        })
    );
    assert_eq!(
        bench.link.submit(bench.now, LinkCommand::QuickRestart),
        Err(Refusal::NotSupported {
            family: Family::Hpr
        })
    );
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::HprSetNominalAmps { amps: 130 })
        .unwrap();
    let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
    assert_eq!(frame, b">00494<", "REMOTE_MODE first");
    bench.rx(2, b">0041C5<");
    let frame = bench.next_tx(bench.now).unwrap();
    assert_eq!(frame, b">05813031<");
    bench.rx(2, b">058013061<");
    let events = bench.events();
    std::println!("{events:?}");
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: true }));
    assert!(events.contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Value(130))
    }));
}

#[test]
fn maxpro_set_process_needs_state_2_or_3() {
    let mut bench = hpr_bench("MaxPro200");
    let gases = GasPair {
        plasma: GasCode(5),
        shield: GasCode(5),
    };
    assert!(matches!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSetProcess { amps: 200, gases }),
        Err(Refusal::StateForbids { state: None, .. })
    ));
    bench.next_tx(bench.now).unwrap();
    bench.rx(
        2,
        &hf(
            79,
            "st0003 er0000 pg0005 ps0056 sg0005 ss0058 cs0200 dm0001 lm0000",
        ),
    );
    assert_eq!(bench.link.status().hpr.state, Some(StateCode(3)));
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSetProcess { amps: 201, gases }),
        Err(Refusal::HprValueOutOfRange {
            value: HprValue::Amps,
            requested: 201,
            min: 5,
            max: 200
        })
    );
    bench
        .link
        .submit(bench.now, LinkCommand::HprSetProcess { amps: 200, gases })
        .unwrap();
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">00494<"
    );
    bench.rx(2, b">0041C5<");
    // Manual sample `>137200 5 5D7<`.
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">137200 5 5D7<");
}

#[test]
fn hpr_raw_commands_outside_the_allow_list_are_refused() {
    let mut bench = hpr_bench("HYPERFORMANCE400XD");
    fn raw(bytes: &[u8]) -> LinkCommand<'_> {
        LinkCommand::Raw(bytes)
    }
    for id in [120u16, 119, 102, 101, 71, 103, 85, 86, 87, 999] {
        let frame = hf(id, "");
        assert_eq!(
            bench.link.submit(bench.now, raw(&frame)),
            Err(Refusal::RawCommandNotAllowed { id }),
            "id {id}"
        );
    }
    let ticket = bench.link.submit(bench.now, raw(b">00292<")).unwrap();
    // Commands go before the next poll.
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00292<");
    bench.rx(2, b">002000355<");
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Raw { len: 11 })
    }));
    assert_eq!(bench.link.raw_reply(), b">002000355<");
}

#[test]
fn hpr_errors_raise_and_clear_faults() {
    let mut bench = hpr_bench("HYPERFORMANCE130AUTO");
    bench.events();
    bench.next_tx(bench.now).unwrap();
    bench.rx(2, &ps_info(14, 116));
    let events = bench.events();
    assert!(events.contains(&LinkEvent::FaultRaised {
        code: ActiveFault::Hpr(ErrorCode(116)),
        action_required: true
    }));
    assert!(events.contains(&LinkEvent::StateChanged {
        from: None,
        to: StateCode(14)
    }));
    // Shutdown error: software reset allowed now.
    assert!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSoftwareReset)
            .is_ok()
    );
}

#[test]
fn reconfiguring_pins_the_protocol_and_restarts_detection() {
    let mut bench = sync_bench();
    bench.events();
    let config = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        ..LinkConfig::default()
    };
    bench.link.reconfigure(bench.now, config);
    assert_eq!(
        bench.events(),
        std::vec![LinkEvent::LinkDown {
            reason: LinkDownReason::Reconfigured
        }]
    );
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00090<");
    assert_eq!(bench.link.port_config(), PortConfig::HPR);
}

#[test]
fn invalid_configurations_are_refused_or_clamped() {
    let bad = LinkConfig {
        response_timeout: Duration::from_millis(10),
        hpr_id: 7,
        ..LinkConfig::default()
    };
    assert_eq!(
        PsLink::try_new(bad, ms(0)).err(),
        Some(ConfigError::ResponseTimeoutOutOfRange { ms: 10 })
    );
    let link = PsLink::new(bad, ms(0));
    assert_eq!(link.config().response_timeout, Duration::from_millis(60));
    assert_eq!(link.config().hpr_id, 3);
}

#[test]
fn noise_and_late_replies_do_not_disturb_the_link() {
    let mut bench = sync_bench();
    // Nothing awaited (between two reads): a stray frame and line noise are counted and
    // ignored.
    while bench.link.txn.is_some() {
        bench.run(bench.now + Duration::from_millis(1));
    }
    bench
        .link
        .handle_rx(bench.now, b"\x00\xff:0104020508EC\r\n>0041C5<garbage");
    assert_eq!(bench.link.diagnostics().unsolicited_frames, 1);
    bench.run(bench.now + Duration::from_millis(300));
    assert!(bench.link.status().link_up);
}

#[test]
fn a_uart_flagged_character_breaks_the_frame_it_falls_in() {
    let mut bench = Bench::new(LinkConfig::default());
    bench.next_tx(ms(0)).unwrap();
    let reply = b":012B0E0481000101010630383133333504\r\n";
    // The reply arrives whole and with a good LRC, but the UART flagged one character: the
    // frame is rejected and the request sent again at once.
    bench.rx(5, &reply[..10]);
    bench.link.handle_rx_error(bench.now);
    bench.link.handle_rx(bench.now, &reply[10..]);
    assert!(!bench.link.status().link_up);
    let d = bench.link.diagnostics();
    assert_eq!((d.rx_errors, d.malformed, d.retries), (1, 1, 1));
    assert_eq!(bench.next_tx(bench.now).unwrap(), b":012B0E0401C1\r\n");
    // A flagged character between frames only counts.
    bench.link.handle_rx_error(bench.now);
    bench.rx(5, reply);
    assert!(bench.link.status().link_up);
    assert_eq!(bench.link.diagnostics().rx_errors, 2);
    assert_eq!(bench.link.diagnostics().malformed, 1);
}

#[test]
fn the_echo_of_our_own_request_is_ignored() {
    let mut bench = Bench::new(LinkConfig::default());
    let request = bench.next_tx(ms(0)).unwrap();
    // A 2-wire line with the receiver on: the request comes back as it goes out (16
    // characters at 19200 8E1 take 9.2 ms).
    bench.rx(9, &request);
    assert_eq!(bench.link.diagnostics().echoes, 1);
    assert_eq!(bench.link.diagnostics().malformed, 0);
    bench.rx(12, b":012B0E0481000101010630383133333504\r\n");
    assert!(bench.link.status().link_up);
}

#[test]
fn a_reply_equal_to_its_request_is_told_from_the_echo_once_the_line_is_known_to_echo() {
    // Legacy settings use function 06, whose reply repeats the request. On a 2-wire line with
    // the bridge's receiver on, every request also comes back as it goes out.
    let mut bench = Bench::new(LinkConfig::default());
    let echoing = Wiring::TwoWire { master_echo: true };
    bench.unit = Some(SimPs::on_line(
        SimModel::Pm65.build(&SimOptions::default()),
        echoing,
    ));
    // Detection teaches the link that the line echoes.
    bench.run(ms(300));
    assert_eq!(bench.link.status().family, Some(Family::PowermaxLegacy));
    let mark = bench.sent.len();
    let ticket = bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplySettings {
                mode: OperatingMode::Cut,
                current: amps(45),
                pressure: Pressure::Auto,
            },
        )
        .unwrap();
    bench.run(bench.now + Duration::from_millis(300));
    let writes = bench.writes_since(mark);
    assert!(writes.len() >= 3, "mode, current, pressure: {writes:?}");
    assert!(writes.iter().all(|w| w[3..5] == *b"06"));
    // Every echo was ignored once; every reply equal to its request was taken.
    let d = bench.link.diagnostics();
    assert_eq!(d.echoes as usize, bench.sent.len());
    assert_eq!(d.transactions_failed, 0);
    assert!(bench.events().iter().any(|e| matches!(e, LinkEvent::CommandDone { ticket: t, result: Ok(CommandOutput::Settings(_)) } if *t == ticket)));
}

#[test]
fn damaged_replies_are_no_silence_and_do_not_take_the_link_down_early() {
    let mut bench = sync_bench();
    bench.events();
    let damaged = b":0104020005F0\r\n"; // LRC should be F5
    let mut failed = 0;
    while failed < 3 * UNANSWERED_FACTOR {
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        bench.rx(5, damaged);
        let d = bench.link.diagnostics();
        if d.transactions_failed > u32::from(failed) {
            failed += 1;
            if failed < 3 * UNANSWERED_FACTOR {
                assert!(
                    bench.link.status().link_up,
                    "after {failed} damaged transactions"
                );
            }
        }
    }
    // A line that never carries one valid reply is no link either.
    assert!(!bench.link.status().link_up);
    assert!(bench.events().iter().any(|e| matches!(
        e,
        LinkEvent::LinkDown {
            reason: LinkDownReason::ConsecutiveFailures {
                count: 12,
                last_error: TransactionError::BadChecksum
            }
        }
    )));
}

#[test]
fn damaged_device_id_replies_are_asked_again_not_taken_for_silence() {
    let mut bench = Bench::new(LinkConfig::default());
    let damaged = b":012B0E0481000101010630383133333505\r\n";
    for _ in 0..3 {
        assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
        bench.rx(20, damaged);
    }
    // Not the legacy probe: device identification again.
    assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
    bench.rx(20, b":012B0E0481000101010630383133333504\r\n");
    assert_eq!(bench.link.status().family, Some(Family::PowermaxSync));
}

#[test]
fn a_unit_found_by_the_legacy_probe_is_identified_again_later() {
    let config = LinkConfig {
        slow_data_interval: Duration::from_secs(1),
        ..LinkConfig::default()
    };
    let mut bench = Bench::new(config);
    // Device identification lost three times, the legacy probe answered.
    for _ in 0..3 {
        assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
    }
    assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":01042098000142\r\n");
    bench.rx(5, b":010402006F8A\r\n");
    assert_eq!(bench.link.status().family, Some(Family::PowermaxLegacy));
    // At the next slow-data refresh the unit says it is a SYNC.
    bench.unit = Some(SimPs::new("sync65"));
    bench.run(ms(2000));
    assert_eq!(bench.link.status().family, Some(Family::PowermaxSync));
    let ups = bench
        .events()
        .into_iter()
        .filter(|e| matches!(e, LinkEvent::LinkUp { .. }))
        .count();
    assert_eq!(ups, 2);
    assert_eq!(bench.link.diagnostics().link_downs, 0);
}

#[test]
fn after_a_link_down_the_known_good_probe_alternates_with_the_search() {
    let mut bench = sync_bench();
    bench.unplug(true);
    bench.run(bench.now + Duration::from_millis(1100));
    assert!(!bench.link.status().link_up);
    let device_id = b":012B0E0401C1\r\n".to_vec();
    // Probes (3 attempts each) and their ports for the next 8 s, nobody answering.
    let mut probes: Vec<(Instant, PortConfig, Vec<u8>)> = Vec::new();
    let until = bench.now + Duration::from_secs(8);
    let mut last: Option<(PortConfig, Vec<u8>)> = None;
    let mut repeats = 0;
    while let Some(frame) = bench.next_tx(until) {
        let port = bench.link.port_config();
        let same = last
            .as_ref()
            .is_some_and(|(p, f)| *p == port && *f == frame);
        if same && repeats < 2 {
            repeats += 1;
            continue;
        }
        repeats = 0;
        last = Some((port, frame.clone()));
        probes.push((bench.now, port, frame));
    }
    let good =
        |p: &(Instant, PortConfig, Vec<u8>)| p.1 == PortConfig::MODBUS_DEFAULT && p.2 == device_id;
    assert!(good(&probes[0]), "the known-good probe first");
    // Every other probe is the known-good one; the search goes on in between.
    for pair in probes.chunks(2) {
        assert!(good(&pair[0]), "{:?}", pair[0]);
        if let Some(search) = pair.get(1) {
            assert!(!good(search), "{search:?}");
        }
    }
    // The gap between two known-good probes stays short (here: under 1 s).
    for w in probes
        .iter()
        .filter(|p| good(p))
        .collect::<Vec<_>>()
        .windows(2)
    {
        assert!(w[1].0.saturating_since(w[0].0) < Duration::from_secs(1));
    }
    // The search still covers the legacy probe, HPR and the other framings.
    assert!(probes.iter().any(|p| p.2 == b":01042098000142\r\n"));
    assert!(probes.iter().any(|p| p.1 == PortConfig::HPR));
    assert!(probes.iter().any(|p| p.1.parity == Parity::Odd));
    // Another kind of unit on the line is still found: an HPR answers HELLO.
    while bench.link.port_config() != PortConfig::HPR {
        bench.next_tx(bench.now + Duration::from_secs(5)).unwrap();
    }
    bench.rx(3, &hf(0, "HYPERFORMANCE130AUTO"));
    assert_eq!(bench.link.status().family, Some(Family::Hpr));
}

#[test]
fn a_reapply_waiting_for_limits_does_not_make_poll_at_spin() {
    let mut bench = sync_bench();
    bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplySettings {
                mode: OperatingMode::Cut,
                current: amps(63),
                pressure: Pressure::Auto,
            },
        )
        .unwrap();
    bench.run(bench.now + Duration::from_millis(300));
    bench.unplug(true);
    bench.run(bench.now + Duration::from_millis(1000));
    assert!(!bench.link.status().link_up);
    // Back, but the limits cannot be read: the re-apply waits, and `Bench` checks that
    // `poll_at` is never left in the past meanwhile.
    bench.unplug(false);
    bench.ps().powermax().config_mut().refused_registers = std::vec![0x3001];
    let mark = bench.sent.len();
    bench.run(bench.now + Duration::from_millis(3000));
    assert!(bench.link.status().link_up);
    assert!(bench.link.status().limits.is_none());
    assert!(bench.writes_since(mark).is_empty());
}

/// An HPR130 in state 3 that took REMOTE_MODE and 058 at 100 A.
fn hpr_at_100_a() -> Bench {
    let mut bench = hpr_bench("HYPERFORMANCE130AUTO");
    // Past the first poll and the slow data (error log, timers).
    while bench.link.status().hpr.timers.is_none() {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        let reply = match &frame[1..4] {
            b"079" => ps_info_at(3, 130),
            b"134" => hf(134, "000 000 000 000"),
            b"125" => hf(125, &"0000000 ".repeat(7)),
            other => panic!("unexpected {other:?}"),
        };
        bench.rx(2, &reply);
    }
    bench
        .link
        .submit(bench.now, LinkCommand::HprSetNominalAmps { amps: 100 })
        .unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00494<");
    bench.rx(2, b">0041C5<");
    assert_eq!(bench.next_tx(bench.now).unwrap(), hf(58, "100"));
    bench.rx(2, &hf(58, "0100"));
    assert_eq!(
        bench.link.kept().hpr_requests(),
        [plasma_protocol::hpr::Request::SetNominalAmps { amps: 100 }]
    );
    bench.events();
    bench
}

fn ps_info_at(state: u16, amps: u16) -> Vec<u8> {
    hf(
        79,
        &std::format!(
            "PC0044 PP0042 SC0034 SP0035 CS{amps:04} ST{state:04} ER0000 CG0000 CG0000 MV0000 MV0000"
        ),
    )
}

#[test]
fn an_hpr_back_in_its_power_up_state_gets_remote_mode_and_its_settings_again() {
    let mut bench = hpr_at_100_a();
    // A blip: the next poll finds the unit powering up, at its rated current.
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">079A0<"
    );
    bench.rx(2, &ps_info_at(0, 130));
    assert!(!bench.link.status().hpr.remote_accepted);
    assert!(
        bench
            .events()
            .contains(&LinkEvent::RemoteModeChanged { remote: false })
    );
    // Nothing is re-applied before the unit is in state 2 or 3.
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">079A0<"
    );
    bench.rx(2, &ps_info_at(2, 130));
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">00494<"
    );
    bench.rx(2, b">0041C5<");
    assert_eq!(bench.next_tx(bench.now).unwrap(), hf(58, "100"));
    bench.rx(2, &hf(58, "0100"));
    assert!(bench.link.status().hpr.remote_accepted);
}

#[test]
fn an_hpr_set_point_other_than_the_kept_one_is_set_again() {
    let mut bench = hpr_at_100_a();
    // The state never showed the restart, but the set point did.
    bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
    bench.rx(2, &ps_info_at(3, 130));
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">00494<"
    );
}

#[test]
fn an_hpr_setting_answered_with_another_value_is_never_a_success() {
    let mut bench = hpr_at_100_a();
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::HprSetNominalAmps { amps: 80 })
        .unwrap();
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        hf(58, "80")
    );
    // The unit answers its old value (it left remote mode): 004 again, then 058 once more.
    bench.rx(2, &hf(58, "0100"));
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00494<");
    bench.rx(2, b">0041C5<");
    assert_eq!(bench.next_tx(bench.now).unwrap(), hf(58, "80"));
    bench.rx(2, &hf(58, "0100"));
    let events = bench.events();
    assert!(events.contains(&LinkEvent::CommandDone {
        ticket,
        result: Err(CommandFailure::NotAccepted)
    }));
    // What is kept is what the unit confirmed.
    assert_eq!(
        bench.link.kept().hpr_requests(),
        [plasma_protocol::hpr::Request::SetNominalAmps { amps: 100 }]
    );
}

#[test]
fn kept_hpr_settings_are_not_given_to_another_model() {
    let mut bench = hpr_at_100_a();
    // The HPR130 goes silent: link down.
    while bench.link.status().link_up {
        bench.next_tx(bench.now + Duration::from_secs(10)).unwrap();
    }
    assert!(
        !bench.link.kept().hpr_requests().is_empty(),
        "kept across the link-down"
    );
    // An HPR260 answers HELLO instead.
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(10)).unwrap();
        if frame == b">00090<" {
            break;
        }
    }
    bench.events();
    bench.rx(3, &hf(0, "HYPERFORMANCE260AUTO"));
    assert!(bench.link.status().link_up);
    assert!(bench.link.kept().hpr_requests().is_empty());
    assert!(bench.events().contains(&LinkEvent::SettingsFailed {
        reason: SettingsFailure::OutsideLimits
    }));
}
