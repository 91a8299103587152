//! Moves between phases: a unit the legacy probe found is identified again later.

use plasma_protocol::time::Duration;

use crate::link::test_support::*;
use crate::link::{Family, LinkConfig, LinkEvent};
use crate::testing::SimPs;

#[test]
fn a_unit_found_by_the_legacy_probe_is_identified_again_later() {
    let config = LinkConfig {
        slow_data_interval: Duration::from_secs(1),
        ..LinkConfig::default()
    };
    let mut bench = Bench::new(config);
    // Device identification lost three times, the legacy probe answered.
    for _ in 0..3 {
        assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":012B0E0401C1\r\n");
    }
    assert_eq!(bench.next_tx(ms(1000)).unwrap(), b":01042098000142\r\n");
    bench.rx(5, b":010402006F8A\r\n");
    assert_eq!(bench.link.status().family, Some(Family::PowermaxLegacy));
    // At the next slow-data refresh the unit says it is a SYNC.
    bench.unit = Some(SimPs::new("sync65"));
    bench.run(ms(2000));
    assert_eq!(bench.link.status().family, Some(Family::PowermaxSync));
    let ups = bench
        .events()
        .into_iter()
        .filter(|e| matches!(e, LinkEvent::LinkUp { .. }))
        .count();
    assert_eq!(ups, 2);
    assert_eq!(bench.link.diagnostics().link_downs, 0);
}
