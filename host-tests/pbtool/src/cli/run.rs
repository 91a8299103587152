//! `pbtool run`: with `--ps-port`, the bridge on a PC's serial port; otherwise the board when
//! a debug probe is attached, else the emulated board, else the simulator.

use std::process::ExitCode;

use clap::Args;
use host_tests::emu::qemu::ensure_qemu;
use pbtool::serial::describe;
use plasma_protocol::serial::PortConfig;
use plasma_sim::Model;

use super::emu::{EmuArgs, emu};
use super::sim::{SimArgs, sim_bridge};

#[derive(Args)]
pub struct RunArgs {
    /// Run the bridge here, in real time, on this serial port wired to the power supply
    /// (/dev/ttyUSB0, COM3); the CNC protocol on stdin/stdout, or on --cnc-port.
    #[arg(long, value_name = "DEV", conflicts_with_all = ["sim", "fast", "models", "fault"])]
    ps_port: Option<String>,
    /// Use the simulator even when a probe is attached.
    #[arg(long)]
    sim: bool,
    /// Options of the simulator (used when no board is attached).
    #[command(flatten)]
    sim_args: SimArgs,
}

/// The board when a probe is attached, the simulator otherwise. `pbtool run` is the bridge:
/// a bridge on this PC (the library on a serial port, the emulated board, the simulator in real
/// time) gets the PC's wall clock at start, as a CNC would set it with `CLOCK`.
pub fn run(args: &RunArgs) -> ExitCode {
    let flash = args.sim_args.flash.as_deref();
    if let Some(ps_port) = &args.ps_port {
        return super::line::run_on_ports(&super::line::LineOptions {
            ps_port,
            cnc_port: args.sim_args.cnc_port.as_deref(),
            cnc_framing: args.sim_args.cnc_framing,
            events: args.sim_args.unit.events,
            flash,
        });
    }
    // A CNC port without a PS port: the emulated board's CNC port on it (or the simulator's).
    let cnc_port = args.sim_args.cnc_port.as_deref();
    if flash.is_some() && !args.sim {
        // The board and the emulated board keep their flash themselves; only a bridge that
        // is this process keeps it in a file.
        eprintln!(
            "pbtool run: --flash keeps the flash of the bridge on this PC in a file: running \
             the simulator (pbtool sim {} --flash ...)",
            args.sim_args.unit.ps_args()
        );
    }
    if !args.sim && flash.is_none() {
        let mut no_board = "no debug probe found";
        if cnc_port.is_none() {
            match find_probe() {
                Probe::Attached(probe) => {
                    eprintln!("pbtool run: debug probe found ({probe}); flashing the board image");
                    return flash_board();
                }
                Probe::NotInstalled => {
                    eprintln!("pbtool run: {PROBE_RS_MISSING}");
                    no_board = "no board";
                }
                Probe::NoneAttached => {}
            }
        }
        let units = &args.sim_args.unit.models;
        let unit = match units.as_slice() {
            [one] => {
                Model::from_name(one).map_or("unit".to_string(), |m| format!("a simulated {m}"))
            }
            several => format!("{} simulated units on one line", several.len()),
        };
        let ps_args = args.sim_args.unit.ps_args();
        let on_port = cnc_port.map_or(String::new(), |dev| {
            format!(
                " --cnc-port {dev} --cnc-framing {}",
                framing_arg(args.sim_args.cnc_framing)
            )
        });
        if !args.sim_args.fast {
            match ensure_qemu() {
                Ok(_) => {
                    eprintln!(
                        "pbtool run: {no_board}; running the firmware on the emulated \
                         board against {unit} (pbtool emu {ps_args}{on_port})"
                    );
                    return emu(&EmuArgs {
                        unit: args.sim_args.unit.clone(),
                        log: args.sim_args.verbose,
                        measure: false,
                        toggles: 0,
                        modbus_cycles: 0,
                        idle_windows: 0,
                        cnc_port: args.sim_args.cnc_port.clone(),
                        cnc_framing: args.sim_args.cnc_framing,
                        own_clock: true,
                    });
                }
                Err(e) => eprintln!("pbtool run: no emulated board ({e})"),
            }
        }
        eprintln!(
            "pbtool run: {no_board}; running the bridge against {unit} \
             (pbtool sim {ps_args}{on_port})"
        );
    }
    // Virtual time (`--fast`) repeats its output exactly: no wall clock there.
    sim_bridge(&args.sim_args, !args.sim_args.fast)
}

/// What `pbtool run` says when probe-rs cannot be run, before it falls back.
const PROBE_RS_MISSING: &str = "probe-rs is not installed, so no board can be flashed \
    (install it with `cargo install probe-rs-tools --locked`, or the installer on \
    https://probe.rs; on Linux also its udev rules)";

/// Whether a debug probe is there to flash the board.
enum Probe {
    /// `probe-rs list` reported this one (the first).
    Attached(String),
    /// probe-rs ran and reported none.
    NoneAttached,
    /// probe-rs could not be started.
    NotInstalled,
}

/// Asks `probe-rs list` for the attached probes.
fn find_probe() -> Probe {
    let output = match std::process::Command::new("probe-rs").arg("list").output() {
        Ok(output) => output,
        Err(_) => return Probe::NotInstalled,
    };
    let text = String::from_utf8_lossy(&output.stdout);
    // Probes are listed as `[0]: STLink V2-1 -- 0483:374b:... (ST-LINK)`.
    text.lines()
        .map(str::trim)
        .find(|line| line.starts_with('[') && line.contains("]:"))
        .map_or(Probe::NoneAttached, |line| {
            Probe::Attached(line.to_string())
        })
}

/// `cargo flash` from the workspace root: release build, flash and run with probe-rs.
fn flash_board() -> ExitCode {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    // This crate sits at host-tests/pbtool in the workspace.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // A fresh machine lacks the MCU target; adding it is a no-op when it is there.
    let target = std::process::Command::new("rustup")
        .args(["target", "add", "thumbv7em-none-eabihf"])
        .status();
    if !matches!(target, Ok(status) if status.success()) {
        eprintln!(
            "pbtool run: could not add the thumbv7em-none-eabihf target with rustup; \
             trying the build anyway"
        );
    }
    match std::process::Command::new(cargo)
        .current_dir(root)
        .arg("flash")
        .status()
    {
        Ok(status) if status.success() => ExitCode::SUCCESS,
        Ok(_) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("pbtool run: cannot start cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `framing` as `--cnc-framing` takes it (`19200:8E1`).
fn framing_arg(framing: PortConfig) -> String {
    describe(framing).replacen(' ', ":", 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::serial::{Parity, StopBits};

    #[test]
    fn the_hint_spells_the_framing_as_cnc_framing_reads_it() {
        for parity in [Parity::None, Parity::Even, Parity::Odd] {
            for stop_bits in [StopBits::One, StopBits::Two] {
                let framing = PortConfig::new(19_200, parity, stop_bits);
                assert_eq!(
                    super::super::sim::cnc_framing(&framing_arg(framing)),
                    Ok(framing)
                );
            }
        }
    }
}
