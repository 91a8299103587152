//! The bridge `monitor` and `history` attach to, one set of options for both.

use clap::Args;
use plasma_protocol::serial::PortConfig;

use super::sim::{CNC_FRAMING_DEFAULT, cnc_framing};

/// A board's CNC port, the emulated board or the simulator, and how the simulated unit starts.
#[derive(Args)]
#[group(skip)]
#[command(group(clap::ArgGroup::new("bridge").required(true).args(["port", "sim", "emu"])))]
pub struct BridgeArgs {
    /// The board's CNC port (/dev/ttyACM0, COM5).
    #[arg(long, value_name = "DEV")]
    pub port: Option<String>,
    /// The simulator with this unit (sync65, hpr260, ...).
    #[arg(long, value_name = "MODEL")]
    pub sim: Option<String>,
    /// The firmware on the emulated board (QEMU) against a simulated unit.
    #[arg(long)]
    pub emu: bool,
    /// With --emu: the simulated unit.
    #[arg(
        long = "ps",
        value_name = "MODEL",
        default_value = "sync65",
        requires = "emu"
    )]
    pub emu_model: String,
    /// With --sim or --emu: the unit starts with this fault (`0-50-0`, HPR error number).
    #[arg(long, value_name = "CODE", conflicts_with = "port")]
    pub fault: Option<String>,
    /// With --port: the CNC port's framing, BAUD:DPS (data bits 7|8, parity N|E|O, stop bits 1|2).
    #[arg(long, alias = "framing", value_name = "FRAMING", default_value = CNC_FRAMING_DEFAULT, value_parser = cnc_framing)]
    pub cnc_framing: PortConfig,
}

/// Which bridge the options name.
pub enum Bridge<'a> {
    /// A board on this CNC port.
    Port(&'a str),
    /// A simulated unit of this model, against the firmware on the emulated board or against
    /// the simulator.
    Simulated { model: &'a str, emulated: bool },
}

impl BridgeArgs {
    /// The bridge named: clap requires one of `--port`, `--sim` and `--emu`.
    pub fn bridge(&self) -> Bridge<'_> {
        match (&self.port, &self.sim) {
            (Some(port), _) => Bridge::Port(port),
            (None, Some(model)) => Bridge::Simulated {
                model,
                emulated: false,
            },
            (None, None) => Bridge::Simulated {
                model: &self.emu_model,
                emulated: true,
            },
        }
    }
}
