//! `pbtool run --ps-port DEV [--cnc-port DEV]`.

use std::io::{self, IsTerminal};
use std::path::Path;
use std::process::ExitCode;

use pbtool::realtime::{Clock, spawn_reader, spawn_stdin};
use pbtool::run::{FirstCommand, LineBridge, Stop, run_cnc_port, run_console};
use pbtool::serial::{Port, SerialError, describe};
use plasma_firmware::settings::Settings;
use plasma_protocol::serial::PortConfig;

use super::serial_failure;

/// What `pbtool run --ps-port` runs with.
pub struct LineOptions<'a> {
    /// The port wired to the power supply.
    pub ps_port: &'a str,
    /// The CNC's port; stdin/stdout without.
    pub cnc_port: Option<&'a str>,
    /// Its framing.
    pub cnc_framing: PortConfig,
    /// Event lines on from the start.
    pub events: bool,
    /// The file that keeps the bridge's flash (`--flash`).
    pub flash: Option<&'a Path>,
}

/// The bridge on `ps_port`; the CNC protocol on `cnc_port` or on stdin/stdout. Its wall
/// clock is the PC's from the start.
pub fn run_on_ports(options: &LineOptions<'_>) -> ExitCode {
    let LineOptions {
        ps_port,
        cnc_port,
        cnc_framing,
        events,
        flash,
    } = *options;
    let mut settings = Settings {
        events,
        ..Settings::default()
    };
    settings.cnc.framing = cnc_framing;
    let clock = Clock::start();
    let opened = open(ps_port, cnc_port, settings, clock);
    let (mut bridge, ps_reader, mut cnc) = match opened {
        Ok(opened) => opened,
        Err(e) => return serial_failure("run", &e),
    };
    if let Some(path) = flash
        && let Err(e) = bridge.keep_flash(path)
    {
        eprintln!("pbtool run: --flash {}: {e}", path.display());
        return ExitCode::from(super::USAGE);
    }
    if let Err(e) = bridge.set_clock(pbtool::history::pc_unix_seconds()) {
        return serial_failure("run", &e);
    }
    let (inbox, arrivals) = std::sync::mpsc::channel();
    spawn_reader(ps_reader, 0, inbox.clone());
    let framing = describe(bridge.bridge().ps_port_config());
    let result = match cnc.as_mut() {
        Some(cnc) => {
            match cnc.try_clone() {
                Ok(reader) => spawn_reader(reader, 1, inbox),
                Err(e) => return serial_failure("run", &e),
            }
            eprintln!(
                "pbtool run: the bridge on {ps_port} (from {framing}, following the unit), the \
                 CNC protocol on {} at {}",
                cnc.name(),
                describe(cnc.config())
            );
            run_cnc_port(&mut bridge, &arrivals, cnc)
        }
        None => {
            let interactive = io::stdin().is_terminal();
            if interactive {
                eprintln!(
                    "pbtool run: the bridge on {ps_port} (from {framing}, following the unit); \
                     CNC protocol on stdin/stdout. HELP lists the commands, end of input \
                     (Ctrl-D) quits."
                );
            }
            spawn_stdin(inbox);
            let first = if interactive {
                FirstCommand::AtOnce
            } else {
                FirstCommand::AfterDetection
            };
            run_console(
                &mut bridge,
                &arrivals,
                first,
                &mut io::stdout(),
                &mut io::stderr(),
            )
        }
    };
    let result = result.and_then(|()| {
        let now = bridge.now();
        Ok(bridge.write_flash(now, true)?)
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Stop::Port(e)) => serial_failure("run", &e),
        // A closed stdout (`| head`) ends the run quietly.
        Err(Stop::Console(e)) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(Stop::Console(e)) => {
            eprintln!("pbtool run: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The ports, and the bridge on the PS port; also a reading handle on that port.
fn open(
    ps_port: &str,
    cnc_port: Option<&str>,
    settings: Settings,
    clock: Clock,
) -> Result<(LineBridge, Port, Option<Port>), SerialError> {
    // Opened at the Modbus default; the bridge sets what its link asks for at once.
    let ps = Port::open(ps_port, PortConfig::MODBUS_DEFAULT)?;
    let ps_reader = ps.try_clone()?;
    let cnc = cnc_port
        .map(|name| Port::open(name, settings.cnc_port_config()))
        .transpose()?;
    Ok((LineBridge::new(settings, ps, clock)?, ps_reader, cnc))
}
