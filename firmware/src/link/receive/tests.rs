//! Receiving, byte by byte: replies checked against the request in flight, noise, late replies and
//! the echo of our own request.

use plasma_protocol::powermax::{OperatingMode, Pressure};
use plasma_protocol::time::Duration;
use plasma_sim::line::Wiring;
use plasma_sim::{Model as SimModel, SimOptions};

use crate::link::test_support::*;
use crate::link::{CommandOutput, Family, LinkCommand, LinkConfig, LinkEvent};
use crate::testing::SimPs;

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
            LinkCommand::ApplyProcess {
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
    assert!(bench.events().iter().any(|e| matches!(e, LinkEvent::CommandDone { ticket: t, result: Ok(CommandOutput::Process(_)) } if *t == ticket)));
}
