//! What a failed transaction counts toward: silence takes the link down, damaged replies only much
//! later.

use plasma_protocol::time::Duration;

use crate::link::schedule::UNANSWERED_FACTOR;
use crate::link::test_support::*;
use crate::link::{LinkDownReason, LinkEvent, TransactionError};

#[test]
fn link_goes_down_after_consecutive_failures_and_detection_restarts() {
    let mut bench = sync_bench();
    bench.events();
    bench.unplug(true);
    // 3 transactions x 3 attempts x 100 ms, with a poll interval between them.
    bench.run(bench.now + Duration::from_millis(1100));
    let events = bench.events();
    assert!(events.iter().any(|e| matches!(
        e,
        LinkEvent::LinkDown {
            reason: LinkDownReason::ConsecutiveFailures {
                count: 3,
                last_error: TransactionError::Timeout
            }
        }
    )));
    assert!(!bench.link.status().link_up);
    assert_eq!(bench.link.diagnostics().link_downs, 1);
    let next = bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
    assert_eq!(next, b":012B0E0401C1\r\n", "auto-detection again");
}

#[test]
fn damaged_replies_are_no_silence_and_do_not_take_the_link_down_early() {
    let mut bench = sync_bench();
    bench.events();
    let damaged = b":0104020005F0\r\n"; // LRC should be F5
    let mut failed = 0;
    while failed < 3 * UNANSWERED_FACTOR {
        bench.next_tx(bench.now + Duration::from_secs(1)).unwrap();
        bench.rx(5, damaged);
        let d = bench.link.diagnostics();
        if d.transactions_failed > u32::from(failed) {
            failed += 1;
            if failed < 3 * UNANSWERED_FACTOR {
                assert!(
                    bench.link.status().link_up,
                    "after {failed} damaged transactions"
                );
            }
        }
    }
    // A line that never carries one valid reply is no link either.
    assert!(!bench.link.status().link_up);
    assert!(bench.events().iter().any(|e| matches!(
        e,
        LinkEvent::LinkDown {
            reason: LinkDownReason::ConsecutiveFailures {
                count: 12,
                last_error: TransactionError::BadChecksum
            }
        }
    )));
}
