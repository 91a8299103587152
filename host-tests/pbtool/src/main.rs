//! pbtool: the plasma-bridge technician's tool.
//!
//! `pbtool decode FRAME...` explains Modbus ASCII (`:`) and HPR (`>`) frames.
//! `pbtool sim --ps MODEL` runs the bridge against a simulated unit with the CNC text protocol
//! on stdin/stdout (see `pbtool::sim`).
//! `pbtool emu --ps MODEL` runs the firmware image itself on an emulated board (QEMU) against a
//! simulated unit, with the CNC port on stdin/stdout (see `pbtool::emu::console`);
//! `pbtool emu --measure` reports the image's latency and idle figures.
//! `pbtool run` runs the bridge where it can: the board, the emulated board or the simulator.
//! `pbtool monitor --sim sync65` shows a live dashboard of a bridge (see `pbtool::monitor`).
//! `pbtool history --port DEV` prints the bridge's event history.
//! `pbtool config --port DEV --cnc-framing 19200:8E1 --save` sets the board's CNC framing.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cli;

#[derive(Parser)]
#[command(
    name = "pbtool",
    version,
    about = "Tools for the plasma-bridge and Hypertherm power supplies"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Explain Modbus ASCII (`:...`) and HPR (`>...<`) frames.
    ///
    /// Each argument is one frame, with or without CR LF or the manuals' `<CR><LF>`. A frame
    /// right after a request is read as its reply. Exit status 1 when any frame is invalid.
    Decode(cli::decode::DecodeArgs),
    /// Run the bridge against a simulated power supply; the CNC protocol on stdin/stdout.
    ///
    /// Type commands (`SET PROCESS CUT 45 AUTO`, `STATUS`, `HELP`); `TORCH ON` / `TORCH OFF`
    /// drive the CNC's torch-on input (simulator only). Each command line is sent once the
    /// previous reply is out; the first once the link is up. From a pipe it prints one reply
    /// per command and exits at the end of input. Runs in real time unless `--fast`.
    Sim(cli::sim::SimArgs),
    /// Run the bridge: on a PC's serial port, on the board, on the emulated board or against
    /// a simulated power supply.
    ///
    /// With `--ps-port DEV`: here in real time on a serial port wired to the power supply
    /// (the CNC protocol on stdin/stdout as for `sim`, or on `--cnc-port DEV`). Otherwise on
    /// the board when a debug probe is attached (build, flash and run with probe-rs, showing
    /// the log), otherwise the firmware on the emulated board when QEMU is installed (as
    /// `emu`), otherwise against a simulated power supply (as `sim`).
    Run(cli::run::RunArgs),
    /// Run the firmware image on an emulated board (QEMU) against a simulated power supply;
    /// the board's CNC port on stdin/stdout.
    ///
    /// Builds the image (`cargo emu-fw`), starts qemu-system-arm 10 with it, puts the simulated
    /// unit on its power-supply port in real time and wires START and MOTION between them;
    /// several `--ps` share the line, each on its own unit set, and the board is told them
    /// with `CONFIG units`. Type CNC commands as for `sim`; `TORCH ON` / `TORCH OFF` (`@N
    /// TORCH ON`: unit N's) drive the board's TORCH_ON input pin. `--measure` (one unit)
    /// instead toggles TORCH_ON under QEMU's instruction counting and reports the
    /// instructions from the edge to START and the idle figures.
    Emu(cli::emu::EmuArgs),
    /// Serve a simulated power supply on a serial port in real time, answering any master.
    ///
    /// The port takes the unit's framing (Powermax 19200 8E1, HPR 19200 8N1). Lines on stdin
    /// control it while it runs: `FAULT CODE`, `CLEAR`, `POWER OFF`, `POWER ON`, `SILENT`
    /// (as if the cable were cut), `ANSWER`, and on a SYNC `CARTRIDGE UID` (another
    /// cartridge). Runs until stopped (Ctrl-C) or the port goes
    /// away (exit status 2).
    Unit(cli::unit::ServeArgs),
    /// Listen to a live line and explain every frame; never transmits.
    ///
    /// One port hears a 2-wire bus, two ports the two pairs of a 4-wire line. Each frame comes
    /// with its time and decoded as `decode` does; replies are paired with their requests, and
    /// missing replies, bad checksums, parity errors, pauses inside frames and noise are
    /// flagged. Runs until stopped (Ctrl-C) or a port goes away (exit status 2).
    Sniff(cli::sniff::SniffArgs),
    /// Find the unit on a serial port and report everything it tells; only reads, changes
    /// nothing.
    ///
    /// Tries every framing with Modbus (SYNC, legacy Powermax) and HPR, then reads the model
    /// and identification, limits, settings, actual outputs, the active fault (text, whether
    /// action is required), counters, cartridge data and logs (HPR: state, PS info, error
    /// log, timers). It sends read requests only. Each framing tried is shown on stderr. Exit
    /// status 0 when a unit answered, 1 when none did within --seconds (with what to check),
    /// 2 on a port error.
    Probe(cli::probe::ProbeArgs),
    /// Set the framing of the bridge's CNC port, both ends in step, and save it.
    ///
    /// Finds the board on the port whatever framing it runs (`ID` at each in turn, the one
    /// asked for first), then changes baud, parity and stop bits one at a time with `CONFIG`,
    /// the PC following each reply, checks with `ID` and, with `--save`, stores it. E.g.
    /// `pbtool config --port /dev/ttyACM0 --cnc-framing 19200:8E1 --save` for LinuxCNC's
    /// pmx485. Exit status 0 when done, 1 when no board answered or it refused, 2 on a port
    /// error.
    Config(cli::config::ConfigArgs),
    /// A live dashboard of a bridge: unit and link, process set and actual, the signals as
    /// lamps, the active fault and its steps, consumable life, the bridge's history, events,
    /// and a plot of current and pressure.
    ///
    /// Attaches through the CNC text protocol to a board's CNC port (`--port DEV`), the
    /// emulated board (`--emu`: `pbtool emu --ps MODEL --events` as a child) or the simulator
    /// (`--sim MODEL`: `pbtool sim --ps MODEL --events` as a child), sets the bridge's clock to
    /// the PC's (`CLOCK`), and keeps reconnecting when the port goes away or the child exits.
    /// Keys: g gas check, r remote off, c clear warnings, q quit. `--snapshot` prints one frame to stdout instead (for docs and bug
    /// reports).
    Monitor(cli::monitor::MonitorArgs),
    /// The bridge's event history (faults, link, resets, refused STARTs, process changes),
    /// newest first, as a table (`--json`, `--csv` for a spreadsheet).
    ///
    /// From the board's CNC port (`--port DEV`), the emulated board in real time (`--emu [--ps
    /// MODEL]`) or a simulated bridge in virtual time (`--sim MODEL`). Sets the bridge's clock to the PC's first
    /// (`CLOCK`), so this boot's entries carry the time. Each entry names the unit's family
    /// and model.
    /// Exit status 0 with the entries, 1 when the bridge refused, 2 on a port error (or an
    /// emulated board that cannot run).
    History(cli::history::HistoryArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Decode(args) => cli::decode::decode(&args),
        Command::Sim(args) => cli::sim::sim(&args),
        Command::Run(args) => cli::run::run(&args),
        Command::Emu(args) => cli::emu::emu(&args),
        Command::Unit(args) => cli::unit::unit(&args),
        Command::Sniff(args) => cli::sniff::sniff(&args),
        Command::Probe(args) => cli::probe::probe_command(&args),
        Command::Config(args) => cli::config::config(&args),
        Command::Monitor(args) => cli::monitor::monitor(&args),
        Command::History(args) => cli::history::history(&args),
    }
}
