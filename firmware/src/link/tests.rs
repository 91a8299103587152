//! The facade's entry points: reconfiguration, configurations out of range, UART-flagged
//! characters.

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Duration;

use crate::link::test_support::*;
use crate::link::{ConfigError, LinkConfig, LinkDownReason, LinkEvent, ProtocolChoice, PsLink};

#[test]
fn reconfiguring_pins_the_protocol_and_restarts_detection() {
    let mut bench = sync_bench();
    bench.events();
    let config = LinkConfig {
        protocol: ProtocolChoice::Hpr,
        ..LinkConfig::default()
    };
    bench.link.reconfigure(bench.now, config);
    assert_eq!(
        bench.events(),
        std::vec![LinkEvent::LinkDown {
            reason: LinkDownReason::Reconfigured
        }]
    );
    assert_eq!(bench.next_tx(bench.now).unwrap(), b">00090<");
    assert_eq!(bench.link.port_config(), PortConfig::HPR);
}

#[test]
fn invalid_configurations_are_refused_or_clamped() {
    let bad = LinkConfig {
        response_timeout: Duration::from_millis(10),
        hpr_id: 7,
        ..LinkConfig::default()
    };
    assert_eq!(
        PsLink::try_new(bad, ms(0)).err(),
        Some(ConfigError::ResponseTimeoutOutOfRange { ms: 10 })
    );
    let link = PsLink::new(bad, ms(0));
    assert_eq!(link.config().response_timeout, Duration::from_millis(60));
    assert_eq!(link.config().hpr_id, 3);
}

#[test]
fn a_uart_flagged_character_breaks_the_frame_it_falls_in() {
    let mut bench = Bench::new(LinkConfig::default());
    bench.next_tx(ms(0)).unwrap();
    let reply = b":012B0E0481000101010630383133333504\r\n";
    // The reply arrives whole and with a good LRC, but the UART flagged one character: the
    // frame is rejected and the request sent again at once.
    bench.rx(5, &reply[..10]);
    bench.link.handle_rx_error(bench.now);
    bench.link.handle_rx(bench.now, &reply[10..]);
    assert!(!bench.link.status().link_up);
    let d = bench.link.diagnostics();
    assert_eq!((d.rx_errors, d.malformed, d.retries), (1, 1, 1));
    assert_eq!(bench.next_tx(bench.now).unwrap(), b":012B0E0401C1\r\n");
    // A flagged character between frames only counts.
    bench.link.handle_rx_error(bench.now);
    bench.rx(5, reply);
    assert!(bench.link.status().link_up);
    assert_eq!(bench.link.diagnostics().rx_errors, 2);
    assert_eq!(bench.link.diagnostics().malformed, 1);
}
