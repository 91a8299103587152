//! Legacy Powermax: block-read fallback and the three force registers.

use std::vec::Vec;

use plasma_protocol::powermax::{FaultCode, OperatingMode, Pressure, Psi};
use plasma_protocol::time::Duration;
use plasma_sim::powermax::UndocumentedAddresses;

use crate::link::test_support::*;
use crate::link::{ActiveFault, CommandOutput, LinkCommand, LinkConfig, LinkEvent};

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
            LinkCommand::ApplyProcess {
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
    assert!(bench.events().iter().any(|e| matches!(e, LinkEvent::CommandDone { ticket: t, result: Ok(CommandOutput::Process(_)) } if *t == ticket)));
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
