//! The HPR / MaxPro200 driver against scripted replies: retries over a blackout, error replies,
//! the pilot-arc pause, remote settings and their re-apply.

use std::vec::Vec;

use plasma_protocol::hpr::{ErrorCode, StateCode};
use plasma_protocol::time::Duration;

use crate::link::test_support::*;
use crate::link::{
    ActiveFault, CommandFailure, CommandOutput, Family, HprValue, LinkCommand, LinkConfig,
    LinkEvent, ProcessFailure, ProtocolChoice, Refusal,
};

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

/// The unit's answer to a slow-data read, 028 or 122 (`frame` is the request): the HPR
/// manual's (002_72b43a5685974c77.txt) sample replies where it prints one that passes its
/// checksum (098 line 187, 145 line 290), else a reply of the format it describes (001 line
/// 140: its sample `>001A.0 A.25<` fails its checksum).
fn slow_reply(frame: &[u8]) -> Vec<u8> {
    match &frame[1..4] {
        b"001" => hf(1, "A.0 A.2"),
        b"098" => b">0980001 000648<".to_vec(),
        b"145" => b">14500025C<".to_vec(),
        b"134" => hf(134, "000 000 000 000"),
        b"125" => hf(125, &"0000000 ".repeat(7)),
        b"028" => hf(28, "0000"),
        b"122" => hf(122, "0001 0006"),
        other => panic!("unexpected {other:?}"),
    }
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
fn an_hpr_poll_reads_the_pressures_the_set_point_and_the_output_current() {
    let mut bench = hpr_bench("HYPERFORMANCE130AUTO");
    // HPR manual (002_72b43a5685974c77.txt) line 168: the 079 sample, request and reply.
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">079A0<");
    bench.rx(
        2,
        b">079PC0044 PP0042 SC0034 SP0035 CS0040 ST0003 ER0000 CG0000 CG0000 MV0000 MV0000DE<",
    );
    let hpr = bench.link.status().hpr;
    assert_eq!(hpr.nominal_amps, Some(40));
    let pressures = hpr.ps_info.unwrap().pressures;
    assert_eq!(
        [
            pressures.plasma_cutflow,
            pressures.plasma_preflow,
            pressures.shield_cutflow,
            pressures.shield_preflow
        ],
        [44, 42, 34, 35]
    );
    // No main arc in state 3: 0 A, and no 028.
    assert_eq!(hpr.actual_amps, Some(0));
    // With the arc on (state 8, steady state) the output current follows the poll (line 148).
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        match &frame[1..4] {
            b"079" => break,
            _ => bench.rx(2, &slow_reply(&frame)),
        }
    }
    bench.rx(2, &ps_info(8, 0));
    plasma_amps_read(&mut bench);
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

/// An HPR130 in state 3 that took REMOTE_MODE and 058 at 100 A.
fn hpr_at_100_a() -> Bench {
    let mut bench = hpr_bench("HYPERFORMANCE130AUTO");
    // Past the first poll and the slow data (error log, timers).
    while bench.link.status().hpr.timers.is_none() {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        let reply = match &frame[1..4] {
            b"079" => ps_info_at(3, 130),
            _ => slow_reply(&frame),
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

/// The 028 READ_PLASMA_AMPS that follows an HPR poll with the arc on, answered with the
/// manual's sample:
/// ">0289A< >02801305E< (130 amps)", HPR manual (002_72b43a5685974c77.txt) line 148.
fn plasma_amps_read(bench: &mut Bench) {
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">0289A<");
    bench.rx(2, b">02801305E<");
    assert_eq!(bench.link.status().hpr.actual_amps, Some(130));
}

fn ps_info_at(state: u16, amps: u16) -> Vec<u8> {
    hf(
        79,
        &std::format!(
            "PC0044 PP0042 SC0034 SP0035 CS{amps:04} ST{state:04} ER0000 CG0000 CG0000 MV0000 MV0000"
        ),
    )
}

/// `reapply_after_power_cycle` on, changed without detection starting again.
fn reapply_after_power_cycle(bench: &mut Bench) {
    let config = LinkConfig {
        reapply_after_power_cycle: true,
        ..*bench.link.config()
    };
    bench.link.reconfigure(bench.now, config);
    assert!(bench.link.status().link_up, "no detection for the policy");
}

#[test]
fn an_hpr_back_in_its_power_up_state_was_power_cycled_and_keeps_local_control() {
    let mut bench = hpr_at_100_a();
    // A blip: the next poll finds the unit powering up, at its rated current.
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">079A0<"
    );
    bench.rx(2, &ps_info_at(0, 130));
    assert!(!bench.link.status().hpr.remote_accepted);
    let events = bench.events();
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: false }));
    assert!(events.contains(&LinkEvent::UnitPowerCycled { reapply: false }));
    assert!(bench.link.kept().hpr_requests().is_empty());
    // Ready again: polls only, no 004, no 058 until the CNC asks.
    for _ in 0..3 {
        assert_eq!(
            bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
            b">079A0<"
        );
        bench.rx(2, &ps_info_at(3, 130));
    }
}

#[test]
fn an_hpr_back_in_its_power_up_state_gets_its_settings_again_when_configured() {
    let mut bench = hpr_at_100_a();
    reapply_after_power_cycle(&mut bench);
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">079A0<"
    );
    bench.rx(2, &ps_info_at(0, 130));
    assert!(!bench.link.status().hpr.remote_accepted);
    let events = bench.events();
    assert!(events.contains(&LinkEvent::RemoteModeChanged { remote: false }));
    assert!(events.contains(&LinkEvent::UnitPowerCycled { reapply: true }));
    // Nothing is re-applied before the unit is in state 2 or 3.
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">079A0<"
    );
    bench.rx(2, &ps_info_at(2, 130));
    // The re-apply goes before the poll's 028.
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
fn an_hpr_set_point_other_than_the_kept_one_counts_as_a_power_cycle() {
    let mut bench = hpr_at_100_a();
    // The state never showed the restart, but the set point did.
    bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
    bench.rx(2, &ps_info_at(3, 130));
    assert!(
        bench
            .events()
            .contains(&LinkEvent::UnitPowerCycled { reapply: false })
    );
    assert_eq!(
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap(),
        b">079A0<"
    );
    let mut bench = hpr_at_100_a();
    reapply_after_power_cycle(&mut bench);
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
    assert!(bench.events().contains(&LinkEvent::ProcessFailed {
        reason: ProcessFailure::OutsideLimits
    }));
}

/// Submit `command` to a bench whose unit is in state 3 (after the poll and its 028, for an
/// HPR), and check that it goes out as `request` and that `reply` completes it with `result`.
fn gas_test_frames(
    bench: &mut Bench,
    command: LinkCommand<'_>,
    request: &[u8],
    reply: &[u8],
    result: Result<CommandOutput, CommandFailure>,
) {
    let ticket = bench.link.submit(bench.now, command).unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), request);
    bench.rx(2, reply);
    assert!(
        bench
            .events()
            .contains(&LinkEvent::CommandDone { ticket, result }),
        "{command:?}"
    );
}

#[test]
fn hpr_cutflow_and_preflow_gas_tests_go_out_as_the_manual_writes_them() {
    let mut bench = hpr_bench("HYPERFORMANCE130MANUAL");
    bench.next_tx(bench.now).unwrap();
    bench.rx(2, &ps_info(3, 0));
    // HPR manual (002_72b43a5685974c77.txt) lines 150, 153, 154, 155: request and reply.
    for (cutflow, on, request, reply) in [
        (false, true, &b">0649A<"[..], &b">0641CB<"[..]),
        (false, false, b">0659B<", b">0651CC<"),
        (true, true, b">0669C<", b">0661CD<"),
        (true, false, b">0679D<", b">0671CE<"),
    ] {
        let command = LinkCommand::HprGasTest { cutflow, on };
        gas_test_frames(&mut bench, command, request, reply, Ok(CommandOutput::Done));
    }
    // "0 = not accepted".
    let command = LinkCommand::HprGasTest {
        cutflow: true,
        on: true,
    };
    let refused = hf(66, "0");
    let failure = Err(CommandFailure::NotAccepted);
    gas_test_frames(&mut bench, command, b">0669C<", &refused, failure);
    // Not while cutting: the next poll (the slow data answered meanwhile) finds state 8.
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        match &frame[1..4] {
            b"079" => break,
            _ => bench.rx(2, &slow_reply(&frame)),
        }
    }
    bench.rx(2, &ps_info(8, 0));
    assert!(matches!(
        bench.link.submit(bench.now, command),
        Err(Refusal::StateForbids { .. })
    ));
}

#[test]
fn a_maxpro200_gas_test_is_143_test_mode_1_in_state_3_only() {
    let mut bench = hpr_bench("MaxPro200");
    bench.next_tx(bench.now).unwrap();
    let info = |state: u16| {
        hf(
            79,
            &std::format!("st{state:04} er0000 pg0001 ps0056 sg0001 ss0058 cs0200 dm0001 lm0000"),
        )
    };
    bench.rx(2, &info(2));
    // "When the system is in state #3 - Ready for Start" (HPR manual
    // (002_72b43a5685974c77.txt) line 283): refused in the purge.
    assert!(matches!(
        bench
            .link
            .submit(bench.now, LinkCommand::MaxProTestGas { on: true }),
        Err(Refusal::StateForbids {
            state: Some(StateCode(2)),
            ..
        })
    ));
    // The next poll, after the firmware and torch read once after detection.
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        if &frame[1..4] == b"079" {
            break;
        }
        bench.rx(2, &slow_reply(&frame));
    }
    bench.rx(2, &info(3));
    // The manual's sample: ">1431C9< //request test mode 1 >1431C9<" (line 283).
    let on = LinkCommand::MaxProTestGas { on: true };
    gas_test_frames(
        &mut bench,
        on,
        b">1431C9<",
        b">1431C9<",
        Ok(CommandOutput::Done),
    );
    // Mode 0, "No test": the gases stop.
    let off = LinkCommand::MaxProTestGas { on: false };
    let stop = hf(143, "0");
    gas_test_frames(&mut bench, off, &stop, &stop, Ok(CommandOutput::Done));
    // A unit that answers mode 1 with 0 did not take it.
    let refused = hf(143, "0");
    let failure = Err(CommandFailure::NotAccepted);
    gas_test_frames(&mut bench, on, b">1431C9<", &refused, failure);
}

#[test]
fn a_manual_gas_console_hpr_is_sent_only_what_its_console_takes() {
    let mut bench = hpr_bench("HYPERFORMANCE130MANUAL");
    bench.next_tx(bench.now).unwrap();
    bench.rx(2, &ps_info(3, 0));
    let system = plasma_protocol::hpr::SystemId::parse(b"HYPERFORMANCE130MANUAL").unwrap();
    // HPR manual (002_72b43a5685974c77.txt) line 149: 058 SET_NOMINAL_AMPS is "Auto Gas
    // System MaxPro200"; its sample request, typed or RAW, is refused before it is sent.
    let refused = Err(Refusal::NotOnThisSystem { id: 58, system });
    let amps = LinkCommand::HprSetNominalAmps { amps: 130 };
    assert_eq!(bench.link.submit(bench.now, amps), refused);
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::Raw(b">05813031<")),
        refused
    );
    // Line 180: 096 SET_INLET_GASES is "Auto Gas System MaxPro200" too.
    let gases = plasma_protocol::hpr::GasPair {
        plasma: plasma_protocol::hpr::GasCode(1),
        shield: plasma_protocol::hpr::GasCode(6),
    };
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSetInletGases(gases)),
        Err(Refusal::NotOnThisSystem { id: 96, system })
    );
    // Line 252: 122 READ_GAS_SWITCH, the slow data of a manual console, read with the
    // manual's sample ">12295< >1220001 00063C<" (plasma O2, shield N2).
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        if frame == b">12295<" {
            break;
        }
        assert_ne!(&frame[1..4], b"058");
        bench.rx(2, &ps_info(3, 0));
    }
    bench.rx(2, b">1220001 00063C<");
    assert_eq!(bench.link.status().hpr.gases, Some(gases));
}

#[test]
fn a_maxpro200_process_goes_out_as_the_manuals_137_sample_and_is_kept() {
    let mut bench = hpr_bench("MaxPro200");
    bench.next_tx(bench.now).unwrap();
    bench.rx(
        2,
        &hf(
            79,
            "st0003 er0000 pg0001 ps0056 sg0001 ss0058 cs0130 dm0001 lm0000",
        ),
    );
    let gases = plasma_protocol::hpr::GasPair {
        plasma: plasma_protocol::hpr::GasCode(5),
        shield: plasma_protocol::hpr::GasCode(5),
    };
    let process = LinkCommand::MaxProSetProcess { amps: 200, gases };
    // 5-200 A (HPR manual (002_72b43a5685974c77.txt) line 275).
    assert!(matches!(
        bench.link.submit(
            bench.now,
            LinkCommand::MaxProSetProcess { amps: 201, gases }
        ),
        Err(Refusal::HprValueOutOfRange { max: 200, .. })
    ));
    let ticket = bench.link.submit(bench.now, process).unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00494<");
    bench.rx(2, b">0041C5<");
    // Line 275: ">137200 5 5D7< >1371CC<".
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">137200 5 5D7<");
    bench.rx(2, b">1371CC<");
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Done)
    }));
    assert_eq!(
        bench.link.kept().hpr_requests(),
        [plasma_protocol::hpr::Request::SetProcess { amps: 200, gases }]
    );
}

/// What does not change while the unit is on the line is read once after detection, where
/// the manual's "System" column names the system: 001 VERSION on every system (HPR manual
/// (002_72b43a5685974c77.txt) line 140), 145 READ TORCH ID on a MaxPro200 only (line 290,
/// its sample `>1459A<` answered `>14500025C<`, id 2); an automatic console's inlet gases
/// (098, line 187, sample `>098A1<` answered `>0980001 000648<`) are slow data.
#[test]
fn firmware_and_torch_are_read_once_where_the_system_takes_them() {
    use plasma_protocol::hpr::{GasCode, GasPair, TorchId};
    let sent = |bench: &mut Bench, rounds: usize| {
        let mut sent = Vec::new();
        for _ in 0..rounds {
            let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
            let reply = match &frame[1..4] {
                b"079" if bench.link.status().family == Some(Family::MaxPro200) => hf(
                    79,
                    "st0003 er0000 pg0001 ps0056 sg0001 ss0058 cs0200 dm0001 lm0000",
                ),
                b"079" => ps_info(3, 0),
                _ => slow_reply(&frame),
            };
            sent.push(frame);
            bench.rx(2, &reply);
        }
        sent
    };
    let mut maxpro = hpr_bench("MaxPro200");
    let frames = sent(&mut maxpro, 4);
    assert!(frames.contains(&b">00191<".to_vec()), "{frames:?}");
    assert!(frames.contains(&b">1459A<".to_vec()), "{frames:?}");
    let status = maxpro.link.status().hpr;
    assert_eq!(status.torch, Some(TorchId(2)));
    let firmware = status.firmware.unwrap();
    assert_eq!(firmware.power_supply.as_str(), "A.0");
    assert_eq!(firmware.gas_console.map(|r| r.as_str().len()), Some(3));
    // Never again while the unit stays on the line.
    let later = sent(&mut maxpro, 20);
    assert!(
        later.iter().all(|f| f.as_slice() == b">079A0<"),
        "{later:?}"
    );

    let mut auto = hpr_bench("HYPERFORMANCE130AUTO");
    let frames = sent(&mut auto, 12);
    assert_eq!(
        frames.iter().filter(|f| f.as_slice() == b">00191<").count(),
        1
    );
    assert!(!frames.iter().any(|f| f.as_slice() == b">1459A<"));
    assert!(frames.contains(&b">098A1<".to_vec()), "{frames:?}");
    let status = auto.link.status().hpr;
    assert!(status.firmware.is_some());
    assert_eq!(status.torch, None);
    let o2_n2 = GasPair {
        plasma: GasCode(1),
        shield: GasCode(6),
    };
    assert_eq!(status.inlet_gases, Some(o2_n2));
}

/// The HPR manual's 095 sample values (002_72b43a5685974c77.txt line 180): 100 A, corner 75 %,
/// plasma O2 (1), shield N2 (6), set points 55 45 35 25, no mix.
fn manual_095() -> plasma_protocol::hpr::HprParameters {
    use plasma_protocol::hpr::{GasCode, GasFlows, GasPair, HprParameters};
    HprParameters {
        amps: 100,
        corner_percent: 75,
        gases: GasPair {
            plasma: GasCode(1),
            shield: GasCode(6),
        },
        flows: GasFlows::from_array([55, 45, 35, 25, 0, 0]),
    }
}

/// An HPR130 with an automatic console in state 3 at 130 A, past its slow data.
fn hpr130_auto_ready() -> Bench {
    let mut bench = hpr_bench("HYPERFORMANCE130AUTO");
    while bench.link.status().hpr.timers.is_none() {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        let reply = match &frame[1..4] {
            b"079" => ps_info_at(3, 130),
            _ => slow_reply(&frame),
        };
        bench.rx(2, &reply);
    }
    bench.events();
    bench
}

/// 095 sent as the manual's sample and acknowledged with it, then read back (099, 097, 098,
/// 079: see `confirm`) with the manual's sample requests and, where they carry these values,
/// its sample replies.
fn send_manual_095(bench: &mut Bench) {
    assert_eq!(
        bench.next_tx(bench.now).unwrap(),
        b">095100 75 1 6 55 45 35 25 00 0084<"
    );
    bench.rx(2, b">0951CF<");
    // Line 192: `>099A2<`; its sample reply has other mix set points, so one of its format.
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">099A2<");
    bench.rx(2, &hf(99, "0055 0045 0035 0025 0000 0000"));
    // Line 186: `>097A0< >09700756C<` (75%).
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">097A0<");
    bench.rx(2, b">09700756C<");
    // Line 187: `>098A1< >0980001 000648<` (plasma O2, shield N2).
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">098A1<");
    bench.rx(2, b">0980001 000648<");
    // Line 168: `>079A0<`, with the current set point 100 A.
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">079A0<");
    bench.rx(2, &ps_info_at(3, 100));
}

#[test]
fn hpr_095_goes_out_as_the_manuals_sample_is_read_back_and_kept() {
    use plasma_protocol::hpr::Request;
    let mut bench = hpr130_auto_ready();
    let parameters = manual_095();
    // The HPR130 takes up to 130 A (line 149); nothing in the gas change while cutting.
    let over = plasma_protocol::hpr::HprParameters {
        amps: 131,
        ..parameters
    };
    assert!(matches!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSetAllParameters(over)),
        Err(Refusal::HprValueOutOfRange { max: 130, .. })
    ));
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::HprSetAllParameters(parameters))
        .unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00494<");
    bench.rx(2, b">0041C5<");
    send_manual_095(&mut bench);
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Done)
    }));
    assert_eq!(
        bench.link.kept().hpr_requests(),
        [Request::SetAllParameters(parameters)]
    );
    // A MaxPro200's form never goes to an HPR.
    let maxpro = plasma_protocol::hpr::MaxProPressures {
        plasma: 50,
        shield: 58,
    };
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::MaxProSetAllGasFlows(maxpro)),
        Err(Refusal::NotSupported {
            family: Family::Hpr
        })
    );
}

#[test]
fn hpr_078_is_confirmed_by_099_or_reported_failed() {
    use plasma_protocol::hpr::{GasFlows, Request};
    let mut bench = hpr130_auto_ready();
    let flows = GasFlows::from_array([55, 45, 35, 25, 50, 50]);
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::HprSetAllGasFlows(flows))
        .unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00494<");
    bench.rx(2, b">0041C5<");
    // HPR manual (002_72b43a5685974c77.txt) line 165: `>07855 45 35 25 50 50AB< >0781D0<`;
    // line 192: `>099A2< >0990055 0045 0035 0025 0050 0050EE<`, the same set points.
    assert_eq!(
        bench.next_tx(bench.now).unwrap(),
        b">07855 45 35 25 50 50AB<"
    );
    bench.rx(2, b">0781D0<");
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">099A2<");
    bench.rx(2, b">0990055 0045 0035 0025 0050 0050EE<");
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Done)
    }));
    assert_eq!(
        bench.link.kept().hpr_requests(),
        [Request::SetAllGasFlows(flows)]
    );
    // Accepted but read back with other set points: 004 again and once more, then failed;
    // the kept set points stay those the unit confirmed.
    let other = GasFlows::from_array([60, 45, 35, 25, 50, 50]);
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::HprSetAllGasFlows(other))
        .unwrap();
    for _ in 0..2 {
        let mut frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        if frame == b">00494<" {
            bench.rx(2, b">0041C5<");
            frame = bench.next_tx(bench.now).unwrap();
        }
        assert_eq!(frame, hf(78, "60 45 35 25 50 50"));
        bench.rx(2, b">0781D0<");
        assert_eq!(bench.next_tx(bench.now).unwrap(), b">099A2<");
        bench.rx(2, b">0990055 0045 0035 0025 0050 0050EE<");
    }
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Err(CommandFailure::NotAccepted)
    }));
    assert_eq!(
        bench.link.kept().hpr_requests(),
        [Request::SetAllGasFlows(flows)]
    );
}

#[test]
fn hpr_095_and_078_are_kept_and_reapplied_after_a_link_loss() {
    use plasma_protocol::hpr::{GasFlows, Request};
    let mut bench = hpr130_auto_ready();
    bench
        .link
        .submit(bench.now, LinkCommand::HprSetAllParameters(manual_095()))
        .unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00494<");
    bench.rx(2, b">0041C5<");
    send_manual_095(&mut bench);
    // 078 afterwards sets the pressures again: both are kept, the 095 first.
    let flows = GasFlows::from_array([55, 45, 35, 25, 50, 50]);
    bench
        .link
        .submit(bench.now, LinkCommand::HprSetAllGasFlows(flows))
        .unwrap();
    assert_eq!(
        bench.next_tx(bench.now).unwrap(),
        b">07855 45 35 25 50 50AB<"
    );
    bench.rx(2, b">0781D0<");
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">099A2<");
    bench.rx(2, b">0990055 0045 0035 0025 0050 0050EE<");
    let kept = [
        Request::SetAllParameters(manual_095()),
        Request::SetAllGasFlows(flows),
    ];
    assert_eq!(bench.link.kept().hpr_requests(), kept);
    // The cable is pulled: link down, the kept settings stay.
    while bench.link.status().link_up {
        bench.next_tx(bench.now + Duration::from_secs(10)).unwrap();
    }
    assert_eq!(bench.link.kept().hpr_requests(), kept);
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(10)).unwrap();
        if frame == b">00090<" {
            break;
        }
    }
    bench.events();
    bench.rx(3, &hf(0, "HYPERFORMANCE130AUTO"));
    // Back in state 3 on the kept set point: a lost link, not a power cycle; 095 and 078 go
    // out again (after 004) and are read back again.
    let frame = loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        match &frame[1..4] {
            b"079" => bench.rx(2, &ps_info_at(3, 100)),
            b"004" => break frame,
            _ => bench.rx(2, &slow_reply(&frame)),
        }
    };
    assert_eq!(frame, b">00494<");
    bench.rx(2, b">0041C5<");
    send_manual_095(&mut bench);
    assert_eq!(
        bench.next_tx(bench.now).unwrap(),
        b">07855 45 35 25 50 50AB<"
    );
    bench.rx(2, b">0781D0<");
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">099A2<");
    bench.rx(2, b">0990055 0045 0035 0025 0050 0050EE<");
    let events = bench.events();
    assert!(!events.contains(&LinkEvent::UnitPowerCycled { reapply: false }));
    assert!(
        !events
            .iter()
            .any(|e| matches!(e, LinkEvent::ProcessFailed { .. }))
    );
    assert_eq!(bench.link.kept().hpr_requests(), kept);
    // Once: then the polls and the slow data, nothing set again.
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        if frame == b">079A0<" {
            break;
        }
        assert!(!matches!(&frame[1..4], b"095" | b"078"));
        bench.rx(2, &slow_reply(&frame));
    }
}

#[test]
fn maxpro200_095_and_078_are_read_back_from_its_079() {
    use plasma_protocol::hpr::{GasCode, GasPair, MaxProParameters, MaxProPressures, Request};
    let mut bench = hpr_bench("MaxPro200");
    bench.next_tx(bench.now).unwrap();
    let info = |amps: u16, plasma: u16, shield: u16| {
        hf(
            79,
            &std::format!(
                "st0003 er0000 pg0001 ps{plasma:04} sg0005 ss{shield:04} cs{amps:04} dm0001 lm0000"
            ),
        )
    };
    bench.rx(2, &info(130, 56, 58));
    let parameters = MaxProParameters {
        amps: 150,
        gases: GasPair {
            plasma: GasCode(1),
            shield: GasCode(5),
        },
        pressures: MaxProPressures {
            plasma: 60,
            shield: 40,
        },
    };
    let ticket = bench
        .link
        .submit(bench.now, LinkCommand::MaxProSetAllParameters(parameters))
        .unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00494<");
    bench.rx(2, b">0041C5<");
    // The MaxPro200 form (HPR manual (002_72b43a5685974c77.txt) line 180): current, plasma
    // and shield gas codes, plasma and shield pressure set points; no sample is printed.
    assert_eq!(bench.next_tx(bench.now).unwrap(), hf(95, "150 1 5 60 40"));
    bench.rx(2, &hf(95, "1"));
    // Its 079 carries gases, set points and current (line 168).
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">079A0<");
    bench.rx(2, &info(150, 60, 40));
    assert!(bench.events().contains(&LinkEvent::CommandDone {
        ticket,
        result: Ok(CommandOutput::Done)
    }));
    // 078, MaxPro200 form: the set points as the manual writes them ("0050", "0058").
    let pressures = MaxProPressures {
        plasma: 50,
        shield: 58,
    };
    bench
        .link
        .submit(bench.now, LinkCommand::MaxProSetAllGasFlows(pressures))
        .unwrap();
    assert_eq!(bench.next_tx(bench.now).unwrap(), hf(78, "0050 0058"));
    bench.rx(2, &hf(78, "1"));
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">079A0<");
    bench.rx(2, &info(150, 50, 58));
    assert_eq!(
        bench.link.kept().hpr_requests(),
        [
            Request::SetAllParametersMaxPro200(parameters),
            Request::SetAllGasFlowsMaxPro200(pressures)
        ]
    );
    // "2 = data invalid or system not in state #2 or #3" (line 180): not sent while cutting.
    loop {
        let frame = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        if frame == b">079A0<" {
            break;
        }
        bench.rx(2, &slow_reply(&frame));
    }
    bench.rx(
        2,
        &hf(
            79,
            "st0009 er0000 pg0001 ps0050 sg0005 ss0058 cs0150 dm0001 lm0000",
        ),
    );
    assert!(matches!(
        bench
            .link
            .submit(bench.now, LinkCommand::MaxProSetAllParameters(parameters)),
        Err(Refusal::StateForbids { .. })
    ));
}

#[test]
fn a_manual_gas_console_hpr_is_sent_no_095_or_078() {
    use plasma_protocol::hpr::{GasFlows, SystemId};
    let mut bench = hpr_bench("HYPERFORMANCE130MANUAL");
    bench.next_tx(bench.now).unwrap();
    bench.rx(2, &ps_info(3, 0));
    let system = SystemId::parse(b"HYPERFORMANCE130MANUAL").unwrap();
    // HPR manual (002_72b43a5685974c77.txt) lines 165 and 180: "Auto Gas System MaxPro200".
    assert_eq!(
        bench
            .link
            .submit(bench.now, LinkCommand::HprSetAllParameters(manual_095())),
        Err(Refusal::NotOnThisSystem { id: 95, system })
    );
    assert_eq!(
        bench.link.submit(
            bench.now,
            LinkCommand::HprSetAllGasFlows(GasFlows::from_array([55, 45, 35, 25, 50, 50]))
        ),
        Err(Refusal::NotOnThisSystem { id: 78, system })
    );
}
