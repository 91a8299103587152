//! The power-supply link on USART1, driven by `plasma_firmware::runner::PsPort`.

use defmt::{info, warn};
use plasma_firmware::link::{LinkConfig, PsLink};
use plasma_firmware::runner::{Clock, PortError, PsPort};
use plasma_firmware::watchdog::TaskId;

use crate::clock::EmbassyClock;
use crate::ps_uart::{PsUart, describe};
use crate::watchdog::report;

#[embassy_executor::task]
pub async fn link(uart: PsUart, config: LinkConfig, progress: TaskId) {
    let clock = EmbassyClock;
    let mut link = PsLink::new(config, clock.now());
    let mut port = PsPort::new(uart);
    loop {
        match port.turn(&mut link, &clock).await {
            Ok(turn) => {
                if let Some(config) = turn.new_config {
                    info!("PS UART: {} baud {=str}", config.baud, describe(config));
                }
            }
            Err(PortError::Unsupported(config)) => {
                warn!(
                    "PS UART cannot run {} baud {=str}",
                    config.baud,
                    describe(config)
                )
            }
            Err(e) => warn!("PS UART: {}", e),
        }
        while let Some(event) = link.poll_event() {
            info!("link: {}", event);
        }
        crate::discrete::log_transitions();
        report(progress);
    }
}
