//! Tests of the HPR / MaxPro200 simulator: identity, replies, the sequence, remote settings.

use super::*;
use crate::hpr_wire;

fn ms(t: u64) -> Instant {
    Instant::from_millis(t)
}

fn unit(model: Model) -> Hpr {
    Hpr::new(HprConfig::for_model(model))
}

/// Sends `frame` at `now`; returns the reply text (or None) and when it started.
fn talk_at(u: &mut Hpr, now: Instant, frame: &str) -> Option<(String, Instant)> {
    for b in frame.bytes() {
        u.receive(now, b);
    }
    let due = u.outbox.back().map(|&(due, _)| due)?;
    let mut last = None;
    while let Some(bytes) = u.poll_transmit(due) {
        last = Some(String::from_utf8(bytes).unwrap());
    }
    last.map(|s| (s, due))
}

fn talk(u: &mut Hpr, now: Instant, frame: &str) -> Option<String> {
    talk_at(u, now, frame).map(|(s, _)| s)
}

fn cmd(u: &mut Hpr, now: Instant, id: u16, data: &str) -> Option<String> {
    let frame = String::from_utf8(hpr_wire::encode(id, data)).unwrap();
    talk(u, now, &frame)
}

#[test]
fn hello_identifies_the_model() {
    let mut u = unit(Model::Hpr130);
    assert_eq!(
        talk(&mut u, ms(0), ">00090<").unwrap(),
        ">000HYPERFORMANCE130AUTO30<"
    );
    u.config_mut().console = GasConsole::Manual;
    assert_eq!(
        talk(&mut u, ms(10), ">00090<").unwrap(),
        ">000HYPERFORMANCE130MANUALB5<"
    );
    let mut u = unit(Model::MaxPro200);
    assert_eq!(talk(&mut u, ms(0), ">00090<").unwrap(), ">000MaxPro20079<");
    let mut u = unit(Model::Hpr400Xd);
    assert!(
        talk(&mut u, ms(0), ">00090<")
            .unwrap()
            .starts_with(">000HYPERFORMANCE400XD")
    );
}

#[test]
fn error_replies_500_and_501() {
    let mut u = unit(Model::Hpr260);
    assert_eq!(talk(&mut u, ms(0), ">00091<").unwrap(), ">50095<");
    assert_eq!(talk(&mut u, ms(10), ">999AB<").unwrap(), ">50196<");
    // A command this system does not have.
    assert_eq!(cmd(&mut u, ms(20), 137, "200 5 5").unwrap(), ">50196<");
    // A damaged character makes the frame fail its check.
    for b in b">0".iter() {
        u.receive(ms(30), *b);
    }
    u.receive_error(ms(30));
    let r = talk(&mut u, ms(30), "090<");
    assert_eq!(r.unwrap(), ">50095<");
}

#[test]
fn replies_come_1_to_7_ms_after_the_request_and_faster_on_xd() {
    let mut u = unit(Model::Hpr130);
    let mut t = ms(0);
    for _ in 0..50 {
        let (_, due) = talk_at(&mut u, t, ">00292<").unwrap();
        let d = due.saturating_since(t).as_micros();
        assert!((1_000..=7_000).contains(&d), "{d}");
        t = due + Duration::from_millis(1);
    }
    let mut u = unit(Model::Hpr260Xd);
    let (_, due) = talk_at(&mut u, ms(0), ">00292<").unwrap();
    assert!(due <= Instant::from_micros(3_500));
    // 136 adds 1.0-1.8 ms.
    assert_eq!(talk(&mut u, ms(10), ">1361CB<").unwrap(), ">1361CB<");
    let (_, due) = talk_at(&mut u, ms(20), ">00292<").unwrap();
    let d = due.saturating_since(ms(20)).as_micros();
    assert!((1_500..=5_300).contains(&d), "{d}");
    // HPR manual (002_72b43a5685974c77.txt) line 274: disabling is answered `>1361CB<` too
    // (an accept flag), and the delay is gone.
    assert_eq!(talk(&mut u, ms(30), ">1360CA<").unwrap(), ">1361CB<");
    let (_, due) = talk_at(&mut u, ms(40), ">00292<").unwrap();
    assert!(due <= ms(40) + Duration::from_micros(3_500));
    // Not on a plain HPR.
    let mut u = unit(Model::Hpr130);
    assert_eq!(talk(&mut u, ms(0), ">1361CB<").unwrap(), ">50196<");
}

#[test]
fn states_through_a_cut() {
    let mut u = unit(Model::Hpr260);
    let state = |u: &mut Hpr, t| cmd(u, ms(t), 2, "").unwrap();
    assert_eq!(state(&mut u, 0), ">002000052<"); // 0 idle
    assert_eq!(u.state_code(), 0);
    u.advance(ms(600));
    assert_eq!(u.state_code(), 2); // purge
    u.advance(ms(2_600));
    assert_eq!(u.state_code(), 3); // idle2
    u.set_start(ms(3_000), true);
    assert_eq!(u.state_code(), 4); // preflow
    u.advance(ms(3_500));
    assert_eq!(u.state_code(), 5); // pilot arc
    assert_eq!(
        u.take_noise_bursts(),
        vec![(ms(3_500), Duration::from_millis(50))]
    );
    u.advance(ms(3_550));
    assert_eq!(u.state_code(), 6); // transfer
    assert!(u.motion());
    u.advance(ms(3_560));
    assert_eq!(u.state_code(), 7); // ramp-up
    u.advance(ms(3_610));
    assert_eq!(u.state_code(), 8); // steady state
    assert_eq!(
        cmd(&mut u, ms(4_000), 28, "").unwrap(),
        ">0280260".to_string() + &format!("{:02X}<", hpr_wire::checksum(b"0280260"))
    );
    u.set_start(ms(5_000), false);
    assert_eq!(u.state_code(), 9); // ramp-down
    assert!(!u.motion());
    u.advance(ms(5_100));
    assert_eq!(u.state_code(), 10); // final ramp-down
    u.advance(ms(5_200));
    assert_eq!(u.state_code(), 11); // auto off
    u.advance(ms(7_200));
    assert_eq!(u.state_code(), 3);
    assert_eq!(u.active_fault(), 0);
    // One transfer, 1.45 s of arc.
    assert_eq!(u.counters().starts, 1);
    assert_eq!(u.counters().arc_on.secs(), 1);
}

#[test]
fn maxpro_states_through_a_cut() {
    let mut u = unit(Model::MaxPro200);
    u.advance(ms(500));
    assert_eq!(u.state_code(), 1);
    u.advance(ms(1_000));
    assert_eq!(u.state_code(), 2);
    u.advance(ms(3_000));
    assert_eq!(u.state_code(), 3);
    assert_eq!(cmd(&mut u, ms(3_000), 138, "").unwrap(), ">1381CD<");
    u.set_hold(ms(3_100), true);
    u.set_start(ms(3_100), true);
    assert_eq!(u.state_code(), 5); // preflow hold
    u.advance(ms(10_000));
    assert_eq!(u.state_code(), 5);
    u.set_hold(ms(10_000), false);
    u.advance(ms(10_001));
    assert_eq!(u.state_code(), 6); // ignite
    u.advance(ms(10_011));
    assert_eq!(u.state_code(), 7); // pilot arc
    u.advance(ms(10_061));
    assert_eq!(u.state_code(), 8); // ramp-up
    u.advance(ms(10_111));
    assert_eq!(u.state_code(), 9); // main arc
    u.set_start(ms(11_000), false);
    assert_eq!(u.state_code(), 10);
    u.advance(ms(11_100));
    assert_eq!(u.state_code(), 11);
    u.advance(ms(13_100));
    assert_eq!(u.state_code(), 12);
    u.advance(ms(13_200));
    assert_eq!(u.state_code(), 3);
}

#[test]
fn start_lost_and_no_transfer_are_warnings() {
    let mut u = unit(Model::Hpr130);
    u.advance(ms(3_000));
    u.set_start(ms(3_000), true);
    u.set_start(ms(3_200), false);
    assert_eq!(u.active_fault(), 31);
    assert_eq!(cmd(&mut u, ms(3_300), 131, "").unwrap(), ">1311C6<");
    assert_eq!(u.active_fault(), 0);
    u.advance(ms(6_000));
    u.config_mut().timings.transfer_delay = None;
    u.set_start(ms(6_000), true);
    u.advance(ms(7_000));
    assert_eq!(u.active_fault(), 21);
    assert_eq!(u.counters().start_errors, 1);
    assert!(!u.motion());
    // The 1 s HF burst is cut short by the 300 ms pilot time-out.
    assert_eq!(
        u.take_noise_bursts(),
        vec![(ms(6_500), Duration::from_millis(300))]
    );
    assert_eq!(
        cmd(&mut u, ms(7_100), 134, "").unwrap(),
        format!(
            ">134021 031 000 000{:02X}<",
            hpr_wire::checksum(b"134021 031 000 000")
        )
    );
}

#[test]
fn shutdown_errors_need_a_software_reset() {
    let mut u = unit(Model::Hpr400);
    u.advance(ms(3_000));
    assert_eq!(cmd(&mut u, ms(3_000), 68, "").unwrap(), ">0680CE<");
    u.inject_fault(ms(3_100), 93);
    assert_eq!(u.state_code(), 14);
    u.set_start(ms(3_200), true);
    assert_eq!(u.state_code(), 14);
    u.set_start(ms(3_300), false);
    assert_eq!(
        cmd(&mut u, ms(3_400), 3, "").unwrap(),
        format!(">0030093{:02X}<", hpr_wire::checksum(b"0030093"))
    );
    assert_eq!(cmd(&mut u, ms(3_500), 68, "").unwrap(), ">0681CF<");
    assert_eq!(u.active_fault(), 0);
    u.advance(ms(7_000));
    assert_eq!(u.state_code(), 3);
}

#[test]
fn blocking_errors_prevent_a_start() {
    let mut u = unit(Model::Hpr130);
    u.advance(ms(3_000));
    u.inject_fault(ms(3_000), 44);
    u.set_start(ms(3_100), true);
    assert_eq!(u.state_code(), 3);
}

#[test]
fn sleep_and_wake_on_a_multi_drop_line() {
    let mut id0 = unit(Model::Hpr130);
    let mut config = HprConfig::for_model(Model::Hpr260);
    config.id = 2;
    let mut id2 = Hpr::new(config);
    // At power-up only id 0 talks.
    assert!(talk(&mut id0, ms(0), ">00090<").is_some());
    assert!(talk(&mut id2, ms(0), ">00090<").is_none());
    assert!(talk(&mut id2, ms(0), ">00091<").is_none()); // not even 500
    // SLEEP: no reply from anyone.
    for u in [&mut id0, &mut id2] {
        assert!(talk(u, ms(10), ">0869E<").is_none());
    }
    // WAKE 2: echoed by id 2 only.
    assert!(talk(&mut id0, ms(20), ">0852CF<").is_none());
    assert_eq!(talk(&mut id2, ms(20), ">0852CF<").unwrap(), ">0852CF<");
    assert!(talk(&mut id0, ms(30), ">00090<").is_none());
    assert!(talk(&mut id2, ms(30), ">00090<").unwrap().contains("260"));
    // SLEEP, WAKE 0.
    for u in [&mut id0, &mut id2] {
        talk(u, ms(40), ">0869E<");
    }
    assert_eq!(talk(&mut id0, ms(50), ">0850CD<").unwrap(), ">0850CD<");
    assert!(talk(&mut id2, ms(50), ">0850CD<").is_none());
    // Power cycle: id 2 asleep again, id 0 awake.
    id2.power_off(ms(60));
    id2.power_on(ms(70));
    assert!(!id2.is_awake());
}

#[test]
fn broadcast_mode_listens_without_answering() {
    let mut u = unit(Model::Hpr130);
    assert!(cmd(&mut u, ms(0), 87, "").is_none());
    assert!(cmd(&mut u, ms(10), 4, "").is_none());
    assert!(u.in_remote_mode());
    assert_eq!(talk(&mut u, ms(20), ">0850CD<").unwrap(), ">0850CD<");
    assert!(cmd(&mut u, ms(30), 0, "").is_some());
}

#[test]
fn remote_settings_on_an_auto_gas_hpr() {
    let mut u = unit(Model::Hpr130);
    u.advance(ms(3_000));
    // Refused before remote mode: the set value is unchanged.
    assert_eq!(
        cmd(&mut u, ms(3_000), 58, "100").unwrap(),
        format!(">0580130{:02X}<", hpr_wire::checksum(b"0580130"))
    );
    assert_eq!(talk(&mut u, ms(3_010), ">00494<").unwrap(), ">0041C5<");
    assert_eq!(
        talk(&mut u, ms(3_020), ">05813031<").unwrap(),
        ">058013061<"
    );
    // Limited to 130 A on an HPR130.
    assert_eq!(cmd(&mut u, ms(3_030), 58, "260").unwrap(), ">058013061<");
    assert_eq!(talk(&mut u, ms(3_040), ">0707503<").unwrap(), ">070007563<");
    assert_eq!(talk(&mut u, ms(3_050), ">097A0<").unwrap(), ">09700756C<");
    // All parameters (the guide's sample): O2 plasma, N2 shield -> purge.
    assert_eq!(
        talk(&mut u, ms(3_060), ">095100 75 1 6 55 45 35 25 00 0084<").unwrap(),
        ">0951CF<"
    );
    assert_eq!(u.nominal_amps(), 100);
    assert_eq!(u.gases(), (1, 6));
    assert_eq!(u.state_code(), 2);
    assert_eq!(
        talk(&mut u, ms(3_070), ">098A1<").unwrap(),
        ">0980001 000648<"
    );
    assert_eq!(
        talk(&mut u, ms(3_080), ">099A2<").unwrap(),
        format!(
            ">0990055 0045 0035 0025 0000 0000{:02X}<",
            hpr_wire::checksum(b"0990055 0045 0035 0025 0000 0000")
        )
    );
    // All gas flows, the manual's sample (line 165), read back with 099's sample (line 192).
    assert_eq!(
        talk(&mut u, ms(3_090), ">07855 45 35 25 50 50AB<").unwrap(),
        ">0781D0<"
    );
    assert_eq!(
        talk(&mut u, ms(3_100), ">099A2<").unwrap(),
        ">0990055 0045 0035 0025 0050 0050EE<"
    );
    assert_eq!(
        cmd(&mut u, ms(3_110), 78, "55 45 35 25 50 101").unwrap(),
        ">0780CF<"
    );
    // Inlet gases: same gases, no purge needed; invalid gas refused.
    u.advance(ms(6_000));
    assert_eq!(talk(&mut u, ms(6_000), ">0961 626<").unwrap(), ">0961D0<");
    assert_eq!(u.state_code(), 3);
    assert_eq!(cmd(&mut u, ms(6_010), 96, "9 6").unwrap(), ">0960CF<");
    // Not while cutting.
    u.set_start(ms(6_100), true);
    assert_eq!(cmd(&mut u, ms(6_200), 96, "5 5").unwrap(), ">0960CF<");
    assert_eq!(
        cmd(&mut u, ms(6_200), 95, "100 75 1 6 55 45 35 25 0 0").unwrap(),
        ">0950CE<"
    );
}

#[test]
fn a_manual_gas_console_has_no_remote_gas_commands() {
    let mut config = HprConfig::for_model(Model::Hpr260);
    config.console = GasConsole::Manual;
    let mut u = Hpr::new(config);
    cmd(&mut u, ms(0), 4, "");
    assert_eq!(talk(&mut u, ms(10), ">05813031<").unwrap(), ">50196<");
    assert_eq!(talk(&mut u, ms(20), ">0961 626<").unwrap(), ">50196<");
    assert_eq!(
        talk(&mut u, ms(22), ">07855 45 35 25 50 50AB<").unwrap(),
        ">50196<"
    );
    // Corner current and gas tests work.
    assert_eq!(talk(&mut u, ms(30), ">0707503<").unwrap(), ">070007563<");
    u.advance(ms(3_000));
    assert_eq!(talk(&mut u, ms(3_000), ">0649A<").unwrap(), ">0641CB<");
    assert_eq!(u.state_code(), 20);
    assert_eq!(talk(&mut u, ms(3_100), ">0659B<").unwrap(), ">0651CC<");
    assert_eq!(u.state_code(), 3);
}

#[test]
fn maxpro_process_and_info() {
    let mut u = unit(Model::MaxPro200);
    cmd(&mut u, ms(0), 4, "");
    // Not in state 2 or 3 yet (power up).
    assert_eq!(talk(&mut u, ms(10), ">137200 5 5D7<").unwrap(), ">1372CD<");
    u.advance(ms(3_000));
    assert_eq!(
        talk(&mut u, ms(3_000), ">137200 5 5D7<").unwrap(),
        ">1371CC<"
    );
    assert_eq!(u.gases(), (5, 5));
    let info = cmd(&mut u, ms(3_010), 79, "").unwrap();
    assert!(info.starts_with(">079st0002 er0000 pg0005"), "{info}");
    assert!(info.contains("cs0200"));
    // 078 in the MaxPro200 form, the set points as the manual writes them ("0050", "0058",
    // line 165): its 079 shows them.
    assert_eq!(cmd(&mut u, ms(3_012), 78, "0050 0058").unwrap(), ">0781D0<");
    let info = cmd(&mut u, ms(3_014), 79, "").unwrap();
    assert!(info.contains("ps0050 sg0005 ss0058"), "{info}");
    assert_eq!(
        cmd(&mut u, ms(3_016), 78, "55 45 35 25 0 0").unwrap(),
        ">0780CF<"
    );
    // HPR-only commands are unknown here.
    assert_eq!(cmd(&mut u, ms(3_020), 85, "0").unwrap(), ">50196<");
    assert_eq!(cmd(&mut u, ms(3_030), 125, "").unwrap(), ">50196<");
}

#[test]
fn timer_counter_and_info_formats() {
    let mut u = unit(Model::Hpr130);
    let r = cmd(&mut u, ms(0), 125, "").unwrap();
    let data = "0000000 0000000 0000000 0000000 0000000 0000000 0000000 ";
    assert_eq!(
        r,
        format!(
            ">125{data}{:02X}<",
            hpr_wire::checksum(format!("125{data}").as_bytes())
        )
    );
    let info = cmd(&mut u, ms(10), 79, "").unwrap();
    assert!(
        info.starts_with(">079PC0055 PP0045 SC0035 SP0025 CS0130 ST0000 ER0000 "),
        "{info}"
    );
}

#[test]
fn every_command_is_logged() {
    let mut u = unit(Model::Hpr130);
    cmd(&mut u, ms(0), 0, "");
    cmd(&mut u, ms(10), 120, "");
    assert_eq!(u.commands_received(), &[0, 120]);
}

#[test]
fn a_unit_that_is_off_needs_no_wakeup_and_does_not_answer() {
    let mut u = unit(Model::Hpr130);
    u.power_off(ms(100));
    assert_eq!(u.next_wakeup(), None);
    assert!(talk(&mut u, ms(200), ">00090<").is_none());
    u.power_on(ms(300));
    assert_eq!(u.next_wakeup(), Some(ms(800)));
}

#[test]
fn start_held_at_power_up_is_error_050() {
    let mut u = unit(Model::Hpr130);
    u.power_off(ms(0));
    u.set_start(ms(10), true);
    u.power_on(ms(20));
    assert_eq!(u.active_fault(), 50);
    u.advance(ms(3_000));
    u.set_start(ms(3_000), false);
    assert_eq!(u.active_fault(), 0);
}
