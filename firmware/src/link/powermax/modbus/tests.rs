//! Block reads with the documented fallback, and RAW Modbus requests against the allow-list.

use std::vec::Vec;

use plasma_protocol::powermax::FaultCode;
use plasma_protocol::time::Duration;
use plasma_sim::powermax::UndocumentedAddresses;

use crate::link::test_support::*;
use crate::link::{ActiveFault, CommandOutput, LinkCommand, LinkConfig, LinkEvent, Refusal};

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
