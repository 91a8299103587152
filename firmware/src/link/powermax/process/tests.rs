//! SYNC settings against a simulated unit: range checks before sending, the guide's frames, read-
//! back, and re-apply after a power cycle or a link-down.

use plasma_protocol::powermax::{OperatingMode, Pressure, Psi};
use plasma_protocol::time::Duration;

use crate::link::test_support::*;
use crate::link::{
    CommandFailure, CommandOutput, LinkCommand, LinkConfig, LinkEvent, PowermaxProcess,
    ProcessFailure, Refusal,
};

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
            LinkCommand::ApplyProcess {
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
            LinkCommand::ApplyProcess {
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
    let applied = PowermaxProcess {
        mode: Some(OperatingMode::Cut),
        current: amps(63),
        pressure: Pressure::Auto,
    };
    // What the unit reads back: in automatic pressure, the pressure it picked.
    let read_back = PowermaxProcess {
        pressure: Pressure::Set(Psi::from_whole(72).unwrap()),
        ..applied
    };
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: true }));
    assert!(events.contains(&LinkEvent::ProcessApplied {
        settings: read_back,
        reapplied: false
    }));
    assert!(events.contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Process(read_back))
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
            LinkCommand::ApplyProcess {
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
        LinkEvent::CommandDone { ticket: t, result: Err(CommandFailure::Process(ProcessFailure::ReadBackDiffers { .. })) } if *t == ticket
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

/// A SYNC unit at 63 A cut, in remote control, its events taken.
fn sync_at_63_a(reapply_after_power_cycle: bool) -> Bench {
    let mut bench = Bench::with_unit(
        LinkConfig {
            reapply_after_power_cycle,
            ..LinkConfig::default()
        },
        "sync65",
    );
    bench.run(bench.now + Duration::from_millis(500));
    bench
        .link
        .submit(
            bench.now,
            LinkCommand::ApplyProcess {
                mode: OperatingMode::Cut,
                current: amps(63),
                pressure: Pressure::Auto,
            },
        )
        .unwrap();
    bench.run(bench.now + Duration::from_millis(300));
    assert!(bench.link.status().remote);
    bench.events();
    bench
}

/// SYNC manual (000_dd931256418ae627.txt) line 1189: "You can also stop remote control mode
/// by setting the power switch on the plasma power supply to the OFF (O) position and
/// waiting approximately 1 minute." A unit back on its own settings was switched off and
/// on: the bridge does not take it back.
#[test]
fn a_unit_back_on_its_own_settings_after_a_power_blip_keeps_local_control() {
    let mut bench = sync_at_63_a(false);
    let mark = bench.sent.len();
    let now = bench.now;
    bench.ps().unit().power_off(now);
    bench.ps().unit().power_on(now);
    bench.run(bench.now + Duration::from_millis(1000));
    let events = bench.events();
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: false }));
    assert!(events.contains(&LinkEvent::UnitPowerCycled { reapply: false }));
    assert_eq!(
        bench.writes_since(mark),
        [] as [Vec<u8>; 0],
        "nothing written"
    );
    assert!(!bench.link.status().remote);
    assert_eq!(bench.link.kept().powermax(), None);
}

#[test]
fn kept_settings_are_reapplied_after_a_power_cycle_when_configured() {
    let mut bench = sync_at_63_a(true);
    let mark = bench.sent.len();
    let now = bench.now;
    bench.ps().unit().power_off(now);
    bench.ps().unit().power_on(now);
    bench.run(bench.now + Duration::from_millis(300));
    let events = bench.events();
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: false }));
    assert!(events.contains(&LinkEvent::UnitPowerCycled { reapply: true }));
    assert!(events.iter().any(|e| matches!(
        e,
        LinkEvent::ProcessApplied {
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

/// Off for longer than a link-down (the manual's "approximately 1 minute"): the unit
/// returns on its own settings, a power cycle, not a lost link.
#[test]
fn a_unit_switched_off_for_a_minute_returns_in_local_control() {
    let mut bench = sync_at_63_a(false);
    let now = bench.now;
    bench.ps().unit().power_off(now);
    bench.run(bench.now + Duration::from_secs(60));
    assert!(!bench.link.status().link_up);
    let now = bench.now;
    bench.ps().unit().power_on(now);
    let mark = bench.sent.len();
    bench.run(bench.now + Duration::from_secs(5));
    assert!(bench.link.status().link_up);
    let events = bench.events();
    assert!(events.contains(&LinkEvent::UnitPowerCycled { reapply: false }));
    assert_eq!(
        bench.writes_since(mark),
        [] as [Vec<u8>; 0],
        "nothing written"
    );
    assert!(!bench.link.status().remote);
}

#[test]
fn kept_settings_are_reapplied_when_the_link_returns() {
    let mut bench = sync_at_63_a(false);
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

#[test]
fn a_reapply_waiting_for_limits_does_not_make_poll_at_spin() {
    let mut bench = sync_at_63_a(false);
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
