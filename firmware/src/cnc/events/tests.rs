//! Event lines, end to end on the rig.

extern crate std;

use std::string::ToString;

use crate::io::IoEvent;

use crate::cnc::rig::*;

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
