//! Event lines, end to end on the rig.

extern crate std;

use std::string::ToString;

use crate::io::IoEvent;

use crate::cnc::rig::*;

// ---------------------------------------------------------------------------------------
// events

/// `!FAULT` carries the same `action=` as the FAULT reply: SYNC manual
/// (000_dd931256418ae627.txt) Table 6, line 967 (0-50-0: "Yes") and line 945 (0-12-1: "No, but
/// recommended").
#[test]
fn fault_events_say_what_action_the_fault_needs() {
    let mut rig = Rig::new(events_on(), Some("sync65"));
    rig.run(600);
    for (code, word) in [(500, "required"), (121, "recommended")] {
        rig.fault(code);
        let start = rig.received.len();
        rig.run(300);
        let event = rig.received[start..]
            .iter()
            .find(|l| l.starts_with("!FAULT 0-"))
            .cloned()
            .unwrap_or_default();
        let reply = rig.cmd("FAULT");
        let action = |line: &str| {
            line.split(' ')
                .find(|w| w.starts_with("action="))
                .map(ToString::to_string)
        };
        assert_eq!(
            action(&event),
            Some(std::format!("action={word}")),
            "{event}"
        );
        assert_eq!(action(&event), action(&reply), "{reply}");
        assert!(event.contains(" text="), "{event}");
        rig.fault(0);
        rig.run(300);
    }
}

/// Each event line's exact text, and EVENTS OFF silencing them. Events caused by the unit,
/// the torch and the cable over time (the fault output, ARC from a real transfer, START
/// DELAYED, the process applied again after a pulled cable) are the harness's scenario
/// (`events_follow_the_unit_the_torch_and_the_cable_over_time`, host-tests/tests/cnc_scenarios.rs).
#[test]
fn event_lines_say_exactly_what_happened_and_events_off_silences_them() {
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
    // SYNC manual (000_dd931256418ae627.txt) line 952: 0-20-0, steps required "No, but
    // recommended".
    assert_eq!(
        rig.received[start..],
        [
            "!FAULT 0-20-0 action=recommended text=The gas pressure is lower than the minimum \
          pressure for the selected process, operating mode, torch, lead length, and cartridge \
          type."
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
