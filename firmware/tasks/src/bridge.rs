//! The bridge task (thread mode): `plasma_firmware::platform::supervisor::Supervisor` around the
//! `Bridge`, over the PS UART, the CNC UART, the I/O task, the settings task and the history
//! task.

use defmt::{debug, info, warn};
use plasma_firmware::bridge::Bridge;
use plasma_firmware::link::UnitStatus;
use plasma_firmware::platform::supervisor::{Supervisor, TurnError};
use plasma_firmware::platform::watchdog::TaskId;
use plasma_protocol::serial::PortConfig;

use crate::Board;
use crate::clock::EmbassyClock;
use crate::history::BoardHistory;
use crate::io::BoardIo;
use crate::log_text::{FaultName, Framing, TurnFailure, UnitName};
use crate::progress::report;
use crate::settings::BoardSaver;

/// The body of the bridge task. The bridge arrives by reference: a task's arguments live in
/// its future next to the state the body keeps across awaits, so a `Bridge` by value would
/// take its ~8 KB of RAM twice.
pub async fn run<B: Board>(
    bridge: &'static mut Bridge,
    ps: B::PsUart,
    cnc: B::CncUart,
    io: BoardIo,
    progress: TaskId,
) {
    let clock = EmbassyClock;
    // The board opened the CNC UART at the framing of the settings the bridge was built from.
    let mut cnc_framing = bridge.cnc_port_config();
    let mut supervisor = Supervisor::new(ps, cnc, B::CNC_TX_BUFFER, io, BoardSaver)
        .with_history(BoardHistory)
        .with_cnc_framing(cnc_framing);
    let mut applied: Option<PortConfig> = None;
    let mut status = Seen::default();
    loop {
        let turn = supervisor.turn(bridge, &clock).await;
        if let Err(e) = &turn {
            warn!("serial: {}", TurnFailure(e));
        }
        let now_applied = supervisor.ps_framing();
        if now_applied != applied {
            applied = now_applied;
            if let Some(config) = now_applied {
                debug!("PS UART: {} baud {}", config.baud, Framing(config));
            }
        }
        if let Some(now_framing) = supervisor.cnc_framing()
            && now_framing != cnc_framing
        {
            cnc_framing = now_framing;
            // A refused framing was logged as the turn's error; the UART kept its old one.
            if !matches!(turn, Err(TurnError::CncUnsupported(_))) {
                info!(
                    "CNC UART: {} baud {}",
                    cnc_framing.baud,
                    Framing(cnc_framing)
                );
            }
        }
        status.log_changes(bridge.status());
        report(progress);
    }
}

/// What was last logged about the unit, to log changes only.
#[derive(Default, PartialEq)]
struct Seen {
    link_up: bool,
    fault: Option<plasma_firmware::link::ActiveFault>,
    ready: bool,
}

impl Seen {
    fn log_changes(&mut self, status: &UnitStatus) {
        let now = Seen {
            link_up: status.link_up,
            fault: status.active_fault,
            ready: status.ready,
        };
        if now == *self {
            return;
        }
        if now.link_up != self.link_up {
            if now.link_up {
                info!("link up: {}", UnitName(status.model));
            } else {
                warn!("link down");
            }
        }
        if now.fault != self.fault {
            match now.fault {
                Some(fault) => warn!(
                    "power supply fault {}{=str}",
                    FaultName(fault),
                    if fault.action_required() {
                        " (action required)"
                    } else {
                        ""
                    }
                ),
                None => info!("power supply fault cleared"),
            }
        }
        if now.ready != self.ready {
            info!("power supply ready: {=bool}", now.ready);
        }
        *self = now;
    }
}
