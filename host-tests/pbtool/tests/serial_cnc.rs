//! The CNC side on a serial port: `pbtool sim --cnc-port` (CNC software talks to a simulated
//! bridge and unit) and `pbtool run --ps-port --cnc-port` (the bridge between two ports).

mod common;

use common::{Cable, CncEnd, Pbtool};

#[test]
fn cnc_software_talks_to_the_simulator_on_a_serial_port() {
    let cnc = Cable::new();
    let _sim = Pbtool::spawn(&["sim", "--ps", "hpr260", "--cnc-port", &cnc.a]);
    let mut end = CncEnd::open(&cnc.b);
    let id = end.command("ID").expect("a reply to ID");
    assert!(id.starts_with("OK bridge=plasma-bridge"), "{id}");
    let status = wait_link_up(&mut end);
    assert!(status.contains("model=HPR260"), "{status}");
}

#[test]
fn the_bridge_runs_between_a_ps_port_and_a_cnc_port() {
    let ps = Cable::new();
    let cnc = Cable::new();
    let _unit = Pbtool::spawn(&["unit", "--ps", "pm85", "--port", &ps.b]);
    let _run = Pbtool::spawn(&["run", "--ps-port", &ps.a, "--cnc-port", &cnc.a]);
    let mut end = CncEnd::open(&cnc.b);
    let status = wait_link_up(&mut end);
    assert!(status.contains("family=LEGACY"), "{status}");
    let set = end.command("SET PROCESS CUT 45 AUTO").expect("a reply");
    assert!(set.starts_with("OK mode=CUT amps=45"), "{set}");
}

/// STATUS until the link is up (detection takes a moment); that STATUS line.
fn wait_link_up(end: &mut CncEnd) -> String {
    let deadline = std::time::Instant::now() + common::LONG;
    loop {
        let status = end.command("STATUS").expect("a reply to STATUS");
        if status.starts_with("OK link=UP") {
            return status;
        }
        assert!(std::time::Instant::now() < deadline, "{status}");
        std::thread::sleep(std::time::Duration::from_millis(200));
    }
}
