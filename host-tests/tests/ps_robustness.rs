//! Scenario tests of a damaged line: random corruption never yields a wrong value, only
//! retries; garbage and a hostile unit never crash the link or make it send anything off its
//! allow-list, and the link recovers when the line is clean again.

use std::any::Any;
use std::collections::VecDeque;

use host_tests::harness::{RxErrors, World, WorldOptions};
use plasma_firmware::link::{
    ActiveFault, CommandOutput, LinkCommand, LinkConfig, ProtocolChoice, UnitStatus,
};
use plasma_protocol::hpr::{self, ErrorCode, StateCode};
use plasma_protocol::modbus_ascii;
use plasma_protocol::powermax::{Amps, FaultCode, OperatingMode, Pressure, Psi};
use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::hpr::Hpr;
use plasma_sim::powermax::Powermax;
use plasma_sim::{Model, SimulatedUnit};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

fn secs(n: u64) -> Duration {
    Duration::from_secs(n)
}

/// Run for `duration`, checking `check` after every step; panics on the first mismatch.
fn run_checking(
    world: &mut World,
    duration: Duration,
    check: impl Fn(&World) -> Result<(), String>,
) {
    let mut failure = None;
    let _ = world.run_until(
        |w| {
            if let Err(e) = check(w) {
                failure = Some(format!("{} ms: {e}", w.now().as_millis()));
                return true;
            }
            false
        },
        duration,
    );
    if let Some(e) = failure {
        panic!("wrong value: {e}\n{}", world.trace().tail(12));
    }
}

fn fault_ok(status: &UnitStatus, allowed: &[Option<ActiveFault>]) -> Result<(), String> {
    if allowed.contains(&status.active_fault) {
        Ok(())
    } else {
        Err(format!(
            "fault {:?} not in {allowed:?}",
            status.active_fault
        ))
    }
}

/// The link's Powermax picture against the simulator's truth (idle unit, settings stable).
fn powermax_consistent(w: &World, faults: &[Option<ActiveFault>]) -> Result<(), String> {
    let s = w.link().status();
    let sim = w.sim_ref::<Powermax>();
    let truth = sim.settings();
    let sync = sim.config().model.family() == plasma_sim::Family::Sync;
    if !s.link_up {
        return fault_ok(s, &[None]);
    }
    if let Some(read) = s.settings {
        let mode = read
            .mode
            .map(|m| if sync { m.to_sync() } else { m.to_legacy() });
        // SYNC reads back the pressure in use; legacy units the force register as written.
        let pressure = if sync {
            sim.effective_pressure()
        } else {
            sim.force_registers().pressure
        };
        if mode != Some(truth.mode)
            || read.current.raw() != truth.current
            || read.pressure.raw() != pressure
        {
            return Err(format!("settings {read:?} vs unit {truth:?}"));
        }
    }
    if let Some(l) = s.limits {
        let t = sim.limits();
        if (l.min_current.raw(), l.max_current.raw()) != t.current
            || (l.min_pressure.raw(), l.max_pressure.raw()) != t.pressure
        {
            return Err(format!("limits {l:?} vs unit {t:?}"));
        }
    }
    if s.actual_current.is_some_and(|a| a.raw() != 0) {
        return Err(format!(
            "actual current {:?} on an idle unit",
            s.actual_current
        ));
    }
    if let (Some(c), Some(t)) = (s.cartridge, sim.cartridge())
        && c.uid.0 != t.uid
    {
        return Err(format!("cartridge uid {:?}", c.uid));
    }
    fault_ok(s, faults)
}

/// A Powermax session on a line that corrupts 1% of the characters (and drops `drop`): the
/// link's picture is checked against the unit after every step. At 8E1 every flipped bit
/// raises a UART parity error, which the board glue reports to the link
/// (`PsLink::handle_rx_error`): the frame it falls in is broken (the LRC alone misses two
/// errors that cancel, see `uart_errors_reported_to_the_link_catch_what_the_lrc_misses`).
/// The protocol is pinned here; `one_percent_corrupted_bytes_cause_only_retries_never_a_link_down`
/// checks that no link-down happens at all.
fn corrupted_powermax_session(model: Model, seed: u64, drop: f64) -> World {
    corrupted_powermax_session_with(model, seed, drop, RxErrors::Report)
}

fn corrupted_powermax_session_with(
    model: Model,
    seed: u64,
    drop: f64,
    rx_errors: RxErrors,
) -> World {
    let protocol = match model.family() {
        plasma_sim::Family::Sync => ProtocolChoice::Sync,
        _ => ProtocolChoice::Legacy,
    };
    let options = WorldOptions {
        seed,
        corrupt_probability: 0.01,
        drop_probability: drop,
        rx_errors,
        ..WorldOptions::with_link(LinkConfig {
            protocol,
            ..LinkConfig::default()
        })
    };
    let mut world = World::new(model, options);
    world
        .wait_link_up(secs(5))
        .expect("link up despite corruption");
    world
        .run_until(|w| w.link().status().limits.is_some(), secs(5))
        .expect("limits");
    let result = world.command(
        LinkCommand::ApplyProcess {
            mode: OperatingMode::Cut,
            current: Amps::from_whole(45).unwrap(),
            pressure: Pressure::Set(Psi::from_whole(70).unwrap()),
        },
        secs(5),
    );
    assert!(
        matches!(result, Ok(CommandOutput::Process(_))),
        "{seed}: {result:?}"
    );
    let none = [None];
    run_checking(&mut world, secs(15), |w| powermax_consistent(w, &none));
    world.inject_fault(300);
    let fault = Some(ActiveFault::Powermax(FaultCode(300)));
    run_checking(&mut world, secs(10), |w| {
        powermax_consistent(w, &[None, fault])
    });
    world
        .run_until(|w| w.link().status().active_fault == fault, secs(10))
        .unwrap_or_else(|t| panic!("{model} seed {seed}: fault never known: {t}"));
    world.clear_fault();
    run_checking(&mut world, secs(5), |w| {
        powermax_consistent(w, &[fault, None])
    });
    world
        .run_until(
            |w| w.link().status().active_fault.is_none() && w.link().status().link_up,
            secs(10),
        )
        .unwrap_or_else(|t| panic!("{model} seed {seed}: fault never cleared: {t}"));

    let d = world.link().diagnostics();
    let line = world.line().stats();
    assert!(line.corrupted > 100, "{model} seed {seed}: {line:?}");
    // Damage was seen and retried, never taken for a value.
    assert!(
        d.retries > 50 && d.bad_checksums + d.malformed > 20,
        "{model} seed {seed}: {d:?}"
    );
    // After a link-down the settings were re-applied: the unit is still in remote mode with
    // what was asked.
    world
        .run_until(|w| w.link().status().remote, secs(10))
        .expect("remote again");
    assert!(world.sim::<Powermax>().in_remote_mode());
    assert_eq!(world.sim::<Powermax>().settings().current, 45 * 64);
    world
}

#[test]
fn one_percent_corrupted_bytes_never_give_a_wrong_sync_value_only_retries() {
    for seed in [1, 2, 3, 4] {
        corrupted_powermax_session(Model::Sync65, seed, 0.0);
    }
}

#[test]
fn one_percent_corrupted_bytes_cause_only_retries_never_a_link_down() {
    for seed in [1, 2, 3, 4] {
        let world = corrupted_powermax_session(Model::Sync65, seed, 0.0);
        assert_eq!(world.link().diagnostics().link_downs, 0, "seed {seed}");
    }
}

/// With the characters handed over as received (`RxErrors::Deliver`), the 8-bit LRC alone
/// misses two errors that cancel: at 1% corruption (seed 7, 13 s in) a poll reply whose mode
/// word 0x0001 arrived as 0x8081 passed the LRC. The board glue reports the UART's parity
/// errors to the link (`PsLink::handle_rx_error`, the harness default), which breaks the frame
/// they fall in: the same session then never shows a wrong value.
#[test]
fn uart_errors_reported_to_the_link_catch_what_the_lrc_misses() {
    let world = corrupted_powermax_session_with(Model::Sync105, 7, 0.005, RxErrors::Report);
    assert!(world.link().diagnostics().rx_errors > 100);
}

/// The other ways a UART driver may treat flagged characters keep values right too (a NUL
/// in their place breaks the frame from outside the link).
#[test]
fn a_board_that_substitutes_flagged_characters_works_too() {
    corrupted_powermax_session_with(Model::Sync65, 3, 0.0, RxErrors::Substitute);
}

/// A unit whose first `damaged` replies starting with `prefix` arrive with a bad LRC (noise at
/// that moment), then clean ones.
struct DamagedReplies {
    inner: Box<dyn SimulatedUnit>,
    prefix: &'static [u8],
    damaged: usize,
}

impl SimulatedUnit for DamagedReplies {
    fn model(&self) -> Model {
        self.inner.model()
    }
    fn port(&self) -> PortConfig {
        self.inner.port()
    }
    fn receive(&mut self, now: Instant, byte: u8) {
        self.inner.receive(now, byte)
    }
    fn receive_error(&mut self, now: Instant) {
        self.inner.receive_error(now)
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        let mut reply = self.inner.poll_transmit(now)?;
        if reply.starts_with(self.prefix) && self.damaged > 0 {
            self.damaged -= 1;
            reply[10] ^= 0x01; // one flipped bit in the data: the LRC no longer matches
        }
        Some(reply)
    }
    fn next_wakeup(&self) -> Option<Instant> {
        self.inner.next_wakeup()
    }
    fn advance(&mut self, now: Instant) {
        self.inner.advance(now)
    }
    fn set_start(&mut self, now: Instant, on: bool) {
        self.inner.set_start(now, on)
    }
    fn motion(&self) -> bool {
        self.inner.motion()
    }
    fn power_off(&mut self, now: Instant) {
        self.inner.power_off(now)
    }
    fn power_on(&mut self, now: Instant) {
        self.inner.power_on(now)
    }
    fn is_powered(&self) -> bool {
        self.inner.is_powered()
    }
    fn inject_fault(&mut self, now: Instant, code: u16) {
        self.inner.inject_fault(now, code)
    }
    fn clear_fault(&mut self, now: Instant) {
        self.inner.clear_fault(now)
    }
    fn active_fault(&self) -> u16 {
        self.inner.active_fault()
    }
    fn in_remote_mode(&self) -> bool {
        self.inner.in_remote_mode()
    }
    fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)> {
        self.inner.take_noise_bursts()
    }
    fn as_any(&self) -> &dyn Any {
        self.inner.as_any()
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self.inner.as_any_mut()
    }
}

#[test]
fn damaged_device_id_replies_do_not_make_a_sync_unit_legacy() {
    let unit = DamagedReplies {
        inner: Model::Sync65.build(&plasma_sim::SimOptions::default()),
        prefix: b":012B",
        damaged: 3,
    };
    let mut world = World::with_unit(Box::new(unit), WorldOptions::default());
    world.wait_link_up(secs(5)).expect("link up");
    world.run_for(secs(5));
    assert_eq!(
        world.link().status().family,
        Some(plasma_firmware::link::Family::PowermaxSync)
    );
}

#[test]
fn one_percent_corrupted_bytes_never_give_a_wrong_legacy_value_only_retries() {
    for seed in [5, 6] {
        corrupted_powermax_session(Model::Pm85, seed, 0.0);
    }
}

#[test]
fn corrupted_and_dropped_bytes_together() {
    corrupted_powermax_session(Model::Sync105, 7, 0.005);
}

#[test]
fn one_percent_corrupted_bytes_never_give_a_wrong_hpr_value_only_retries() {
    for seed in [8, 9] {
        let options = WorldOptions {
            seed,
            corrupt_probability: 0.01,
            ..WorldOptions::with_link(LinkConfig {
                protocol: ProtocolChoice::Hpr,
                ..LinkConfig::default()
            })
        };
        let mut world = World::new(Model::Hpr260, options);
        world.wait_link_up(secs(5)).expect("link up");
        world
            .run_until(|w| w.link().status().ready, secs(10))
            .expect("ready");
        let result = world.command(LinkCommand::HprSetNominalAmps { amps: 180 }, secs(5));
        assert_eq!(result, Ok(CommandOutput::Value(180)), "seed {seed}");
        let consistent = |w: &World, errors: &[u16]| -> Result<(), String> {
            // Unknown (None, e.g. after a link-down) is allowed; a wrong value is not.
            let s = w.link().status();
            let sim = w.sim_ref::<Hpr>();
            if s.hpr.nominal_amps.is_some_and(|a| a != sim.nominal_amps()) {
                return Err(format!(
                    "amps {:?} vs {}",
                    s.hpr.nominal_amps,
                    sim.nominal_amps()
                ));
            }
            if s.hpr
                .state
                .is_some_and(|st| st != StateCode(sim.state_code()))
            {
                return Err(format!("state {:?} vs {}", s.hpr.state, sim.state_code()));
            }
            match s.hpr.error {
                None => Ok(()),
                Some(ErrorCode(e)) if errors.contains(&e) => Ok(()),
                other => Err(format!("error {other:?} not in {errors:?}")),
            }
        };
        run_checking(&mut world, secs(15), |w| consistent(w, &[0]));
        world.inject_fault(44);
        run_checking(&mut world, secs(5), |w| consistent(w, &[0, 44]));
        world
            .run_until(
                |w| w.link().status().hpr.error == Some(ErrorCode(44)),
                secs(10),
            )
            .expect("error known");
        let d = world.link().diagnostics();
        assert!(d.retries > 10 && d.bad_checksums > 5, "seed {seed}: {d:?}");
    }
}

#[test]
fn garbage_on_the_line_never_panics_and_the_link_recovers_when_it_stops() {
    for (model, seed) in [
        (Model::Sync65, 21),
        (Model::Pm125, 22),
        (Model::Hpr260, 23),
        (Model::MaxPro200, 24),
    ] {
        let options = WorldOptions {
            seed,
            noise_density: Some(1.0),
            ..WorldOptions::default()
        };
        let mut world = World::new(model, options);
        world.wait_link_up(secs(3)).expect("link up");
        world.run_for(secs(3));
        // Five seconds of dense garbage in both directions.
        world.add_noise(secs(5));
        world.run_for(secs(5));
        let quiet = world.now();
        assert!(world.line().stats().noise > 5_000, "{model}");
        // Back: at most one detection rotation (~13 s, see ps_powermax).
        let back = world
            .run_until(|w| w.link().status().link_up, secs(20))
            .unwrap_or_else(|t| panic!("{model}: {t}"));
        world.run_for(secs(3));
        let status = world.link().status();
        assert!(status.link_up, "{model}");
        let family_ok = match model {
            Model::Hpr260 | Model::MaxPro200 => {
                status.hpr.ps_info.is_some() || status.hpr.maxpro_info.is_some()
            }
            _ => status.settings.is_some() || status.limits.is_some(),
        };
        assert!(family_ok, "{model}: polling again");
        assert!(back >= quiet || world.link().diagnostics().link_downs == 0);
        // No write and no command off the allow-list came out of the garbage.
        for f in world.trace().requests() {
            assert!(request_is_harmless(f), "{model}: {}", f.text());
        }
    }
}

/// True for a request the link may send without being asked to: reads (the legacy torch-lead
/// coils among them), detection, line control, polls, the HPR's slow data and what it reads
/// once after detection (001 VERSION, 145 READ TORCH ID); no write of any kind.
fn request_is_harmless(f: &host_tests::harness::TraceFrame) -> bool {
    if f.is_modbus() {
        return matches!(f.modbus_function(), Some(0x01 | 0x03 | 0x04 | 0x2B));
    }
    match f.hpr_id() {
        Some(id) => {
            hpr::is_allowed(id)
                && matches!(
                    id,
                    0 | 1 | 2 | 28 | 79 | 85 | 86 | 98 | 122 | 125 | 134 | 145
                )
        }
        None => false,
    }
}

/// A "unit" that answers every frame it hears with random but well-formed frames (valid LRC
/// or checksum, random functions, counts and values), random bytes, or nothing.
struct HostileUnit {
    port: PortConfig,
    rng: Xoshiro256PlusPlus,
    outbox: VecDeque<(Instant, Vec<u8>)>,
}

impl HostileUnit {
    fn new(port: PortConfig, seed: u64) -> Self {
        HostileUnit {
            port,
            rng: Xoshiro256PlusPlus::seed_from_u64(seed),
            outbox: VecDeque::new(),
        }
    }

    fn reply(&mut self) -> Vec<u8> {
        let rng = &mut self.rng;
        match rng.random_range(0..4u8) {
            0 | 1 => {
                let address = if rng.random_bool(0.8) {
                    1
                } else {
                    rng.random()
                };
                let functions = [0x03, 0x04, 0x06, 0x10, 0x05, 0x2B, 0x83, 0x84, 0x90];
                let mut pdu = vec![functions[rng.random_range(0..functions.len())]];
                let len = rng.random_range(0..60usize);
                if rng.random_bool(0.5) {
                    pdu.push(len as u8);
                }
                pdu.extend((0..len).map(|_| rng.random::<u8>()));
                let mut out = [0u8; 600];
                let n = modbus_ascii::encode(address, &pdu, &mut out).unwrap();
                out[..n].to_vec()
            }
            2 => {
                let id = rng.random_range(0..1000u16);
                let data: String = (0..rng.random_range(0..40))
                    .map(|_| rng.random_range(b' '..=b'~') as char)
                    .filter(|c| *c != '<' && *c != '>')
                    .collect();
                format!(">{id:03}{data}{:02X}<", hpr::checksum(id, data.as_bytes())).into_bytes()
            }
            _ => (0..rng.random_range(0..80)).map(|_| rng.random()).collect(),
        }
    }
}

impl SimulatedUnit for HostileUnit {
    fn model(&self) -> Model {
        Model::Sync65
    }
    fn port(&self) -> PortConfig {
        self.port
    }
    fn receive(&mut self, now: Instant, byte: u8) {
        if matches!(byte, b'\n' | b'<') && self.rng.random_bool(0.9) {
            let reply = self.reply();
            let delay = Duration::from_micros(self.rng.random_range(500..20_000));
            self.outbox.push_back((now + delay, reply));
        }
    }
    fn receive_error(&mut self, _now: Instant) {}
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
        match self.outbox.front() {
            Some(&(due, _)) if due <= now => self.outbox.pop_front().map(|(_, b)| b),
            _ => None,
        }
    }
    fn next_wakeup(&self) -> Option<Instant> {
        self.outbox.front().map(|&(due, _)| due)
    }
    fn advance(&mut self, _now: Instant) {}
    fn set_start(&mut self, _now: Instant, _on: bool) {}
    fn motion(&self) -> bool {
        false
    }
    fn power_off(&mut self, _now: Instant) {}
    fn power_on(&mut self, _now: Instant) {}
    fn is_powered(&self) -> bool {
        true
    }
    fn inject_fault(&mut self, _now: Instant, _code: u16) {}
    fn clear_fault(&mut self, _now: Instant) {}
    fn active_fault(&self) -> u16 {
        0
    }
    fn in_remote_mode(&self) -> bool {
        false
    }
    fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)> {
        Vec::new()
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

#[test]
fn a_hostile_unit_never_crashes_the_link_or_draws_a_write_out_of_it() {
    for (seed, protocol, port) in [
        (31, ProtocolChoice::Auto, PortConfig::MODBUS_DEFAULT),
        (32, ProtocolChoice::Sync, PortConfig::MODBUS_DEFAULT),
        (33, ProtocolChoice::Legacy, PortConfig::MODBUS_DEFAULT),
        (34, ProtocolChoice::Hpr, PortConfig::HPR),
        (35, ProtocolChoice::Auto, PortConfig::HPR),
    ] {
        let link = LinkConfig {
            protocol,
            ..LinkConfig::default()
        };
        let mut world = World::with_unit(
            Box::new(HostileUnit::new(port, seed)),
            WorldOptions {
                seed,
                ..WorldOptions::with_link(link)
            },
        );
        world.run_for(secs(60));
        assert!(
            world.trace().replies().count() > 20,
            "seed {seed}: {} replies, {:?}\n{}",
            world.trace().replies().count(),
            world.stats(),
            world.trace().tail(10)
        );
        for f in world.trace().requests() {
            assert!(request_is_harmless(f), "seed {seed}: {}", f.text());
        }
        // It is still alive and still asking.
        let last = world.trace().requests().last().unwrap().start;
        assert!(world.now().saturating_since(last) < secs(3), "seed {seed}");
        let _ = world.link().status();
    }
}

fn two_wire(model: Model, master_echo: bool) -> World {
    let options = WorldOptions {
        wiring: plasma_sim::line::Wiring::TwoWire { master_echo },
        ..WorldOptions::default()
    };
    let mut world = World::new(model, options);
    world
        .wait_link_up(secs(2))
        .expect("link up despite the echo");
    world.run_for(secs(3));
    assert!(world.link().status().settings.is_some());
    assert_eq!(world.link().diagnostics().link_downs, 0);
    let result = world.command(
        LinkCommand::ApplyProcess {
            mode: OperatingMode::Cut,
            current: Amps::from_whole(60).unwrap(),
            pressure: Pressure::Auto,
        },
        secs(3),
    );
    assert!(result.is_ok(), "{result:?}");
    world
}

#[test]
fn limits_are_known_soon_even_when_their_first_read_is_damaged() {
    // The three attempts at 0x3001-0x3005 (a 10-byte reply) arrive damaged.
    let unit = DamagedReplies {
        inner: Model::Sync65.build(&plasma_sim::SimOptions::default()),
        prefix: b":01040A",
        damaged: 3,
    };
    let mut world = World::with_unit(Box::new(unit), WorldOptions::default());
    world.wait_link_up(secs(1)).expect("link up");
    world
        .run_until(|w| w.link().status().limits.is_some(), secs(3))
        .expect("limits read again within 3 s");
}

#[test]
fn poll_at_never_stays_in_the_past() {
    // Every cartridge block reply damaged: the read keeps failing (and is tried again with
    // a growing wait).
    let unit = DamagedReplies {
        inner: Model::Sync65.build(&plasma_sim::SimOptions::default()),
        prefix: b":010428",
        damaged: usize::MAX,
    };
    let mut world = World::with_unit(Box::new(unit), WorldOptions::default());
    world.wait_link_up(secs(1)).expect("link up");
    world.run_for(secs(5));
    assert!(
        world.link().status().cartridge.is_none(),
        "the scenario holds"
    );
    assert_eq!(
        world.stats().stale_wakeups,
        0,
        "ms spent spinning on a past poll_at"
    );
    // Tried again, with a growing wait (0.2, 0.4, 0.8, 1.6 s...): not at every turn.
    let block = world
        .trace()
        .requests()
        .filter(|f| f.modbus_function() == Some(0x04) && f.modbus_address() == Some(0x3030))
        .count();
    assert!(
        (6..=21).contains(&block),
        "{block} cartridge block requests"
    );
    assert!(world.link().status().limits.is_some());
}

#[test]
fn a_two_wire_half_duplex_line_works() {
    // RS-485 2-wire, the transceiver's receiver off while it drives the line.
    let world = two_wire(Model::Sync85, false);
    assert_eq!(world.link().diagnostics().echoes, 0);
}

#[test]
fn a_two_wire_line_with_echo_works() {
    // The master's receiver left on: the bridge hears its own requests, and ignores them.
    for model in [Model::Sync85, Model::Pm85] {
        let world = two_wire(model, true);
        assert!(world.link().diagnostics().echoes > 20, "{model}");
        assert_eq!(world.link().diagnostics().malformed, 0, "{model}");
        // Legacy settings are 06 writes, whose replies repeat the request: the echo was
        // told from the reply, the unit took them.
        assert!(world.sim_ref::<Powermax>().in_remote_mode(), "{model}");
    }
}
