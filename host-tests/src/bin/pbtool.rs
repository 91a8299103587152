//! pbtool: the plasma-bridge technician's tool.
//!
//! `pbtool decode FRAME...` explains Modbus ASCII (`:`) and HPR (`>`) frames.
//! `pbtool sim --ps MODEL` runs the bridge against a simulated unit with the CNC text protocol
//! on stdin/stdout (see `host_tests::console`).
//! `pbtool emu --ps MODEL` runs the firmware image itself on an emulated board (QEMU) against a
//! simulated unit, with the CNC port on stdin/stdout (see `host_tests::emu::console`);
//! `pbtool emu --measure` reports the image's latency and idle figures.

use std::io::{self, BufRead, IsTerminal, Write};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use host_tests::console::{Console, ConsoleOptions, parse_fault, read_line};
use host_tests::decode::{all_valid, decode_frames, to_json, to_text};
use host_tests::emu::console::EmuConsoleOptions;
use host_tests::emu::measure::{MeasureOptions, measure};
use host_tests::emu::qemu::ensure_qemu;
use plasma_sim::Model;

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
    Decode(DecodeArgs),
    /// Run the bridge against a simulated power supply; the CNC protocol on stdin/stdout.
    ///
    /// Type commands (`SET PROCESS CUT 45 AUTO`, `STATUS`, `HELP`); `TORCH ON` / `TORCH OFF`
    /// drive the CNC's torch-on input (simulator only). Each command line is sent once the
    /// previous reply is out; the first once the link is up. From a pipe it prints one reply
    /// per command and exits at the end of input. Runs in real time unless `--fast`.
    Sim(SimArgs),
    /// Run the bridge: on the board when a debug probe is attached (build, flash and run with
    /// probe-rs, showing the log), otherwise the firmware on the emulated board when QEMU is
    /// installed (as `emu`), otherwise against a simulated power supply (as `sim`).
    Run(RunArgs),
    /// Run the firmware image on an emulated board (QEMU) against a simulated power supply;
    /// the board's CNC port on stdin/stdout.
    ///
    /// Builds the image (`cargo emu-fw`), starts qemu-system-arm 10 with it, puts the simulated
    /// unit on its power-supply port in real time and wires START and MOTION between them.
    /// Type CNC commands as for `sim`; `TORCH ON` / `TORCH OFF` drive the board's TORCH_ON
    /// input pin. `--measure` instead toggles TORCH_ON under QEMU's instruction counting and
    /// reports the instructions from the edge to START and the idle figures.
    Emu(EmuArgs),
}

#[derive(Args)]
struct EmuArgs {
    #[command(flatten)]
    unit: UnitArgs,
    /// The firmware's own log (defmt, decoded) on stderr.
    #[arg(long)]
    log: bool,
    /// Measure instead: TORCH_ON edge to START in guest instructions, and idle behaviour.
    #[arg(long)]
    measure: bool,
    /// With --measure: TORCH_ON cycles.
    #[arg(long, default_value_t = 20, requires = "measure")]
    toggles: usize,
    /// With --measure: idle windows of 10 s of guest time to report.
    #[arg(long, default_value_t = 1, requires = "measure")]
    idle_windows: usize,
}

#[derive(Args)]
struct RunArgs {
    /// Use the simulator even when a probe is attached.
    #[arg(long)]
    sim: bool,
    /// Options of the simulator (used when no board is attached).
    #[command(flatten)]
    sim_args: SimArgs,
}

#[derive(Args)]
struct SimArgs {
    #[command(flatten)]
    unit: UnitArgs,
    /// Virtual time: no waiting, the same output on every run (scripts and tests).
    #[arg(long, alias = "virtual")]
    fast: bool,
    /// Log every change of the discrete outputs (START, ARC_OK, READY, FAULT) with its
    /// reason on stderr.
    #[arg(short, long)]
    verbose: bool,
}

/// The simulated unit and the session's start, common to `sim`, `emu` and `run`.
#[derive(Args, Clone)]
struct UnitArgs {
    /// The simulated unit: sync45 sync65 sync85 sync105 pm45xp pm65 pm85 pm105 pm125 hpr130
    /// hpr260 hpr400 hpr130xd hpr260xd hpr400xd maxpro200.
    #[arg(long = "ps", value_name = "MODEL", default_value = "sync65")]
    model: String,
    /// Start the unit with a fault: Powermax `0-50-0` (or decimal `500`), HPR error number.
    #[arg(long, value_name = "CODE")]
    fault: Option<String>,
    /// Event lines (`!LINK UP ...`, `!ARC ON`) on from the start.
    #[arg(long)]
    events: bool,
    /// Seed of the simulator's response-time jitter and the line model.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

#[derive(Args)]
struct DecodeArgs {
    /// Print one JSON object per frame, one per line.
    #[arg(long)]
    json: bool,
    /// Frames, e.g. `:010430440004<CR><LF>` `:010408007900790000000001`.
    #[arg(required = true, value_name = "FRAME")]
    frames: Vec<String>,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Decode(args) => decode(&args),
        Command::Sim(args) => sim(&args),
        Command::Run(args) => run(&args),
        Command::Emu(args) => emu(&args),
    }
}

/// The board when a probe is attached, the simulator otherwise.
fn run(args: &RunArgs) -> ExitCode {
    if !args.sim {
        if let Some(probe) = attached_probe() {
            eprintln!("pbtool run: debug probe found ({probe}); flashing the board image");
            return flash_board();
        }
        let unit = Model::from_name(&args.sim_args.unit.model)
            .map_or("unit".to_string(), |m| m.to_string());
        if !args.sim_args.fast {
            match ensure_qemu() {
                Ok(_) => {
                    eprintln!(
                        "pbtool run: no debug probe found; running the firmware on the emulated \
                         board against a simulated {unit} (pbtool emu --ps {})",
                        args.sim_args.unit.model
                    );
                    return emu(&EmuArgs {
                        unit: args.sim_args.unit.clone(),
                        log: args.sim_args.verbose,
                        measure: false,
                        toggles: 0,
                        idle_windows: 0,
                    });
                }
                Err(e) => eprintln!("pbtool run: no emulated board ({e})"),
            }
        }
        eprintln!(
            "pbtool run: no debug probe found; running the bridge against a simulated {unit} \
             (pbtool sim --ps {})",
            args.sim_args.unit.model,
        );
    }
    sim(&args.sim_args)
}

/// The firmware on the emulated board: the CNC console, or the measurements.
fn emu(args: &EmuArgs) -> ExitCode {
    let (model, fault) = match simulated_unit("emu", &args.unit.model, args.unit.fault.as_deref()) {
        Ok(unit) => unit,
        Err(status) => return status,
    };
    if args.measure {
        let options = MeasureOptions {
            model,
            toggles: args.toggles,
            idle_windows: args.idle_windows,
        };
        return match measure(&options, |note| eprintln!("pbtool emu: {note}")) {
            Ok(figures) => {
                print!("{}", figures.report());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("pbtool emu --measure: {e}");
                ExitCode::FAILURE
            }
        };
    }
    if io::stdin().is_terminal() {
        eprintln!(
            "pbtool emu: the firmware on an emulated board (QEMU) against a simulated {model}; \
             CNC port on stdin/stdout. HELP lists the commands, TORCH ON|OFF drives the \
             TORCH_ON pin, end of input (Ctrl-D) quits."
        );
    }
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut stdin = io::stdin().lock();
        while let Ok(Some(line)) = read_line(&mut stdin as &mut dyn BufRead) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let options = EmuConsoleOptions {
        model,
        fault,
        events: args.unit.events,
        log: args.log,
        seed: args.unit.seed,
    };
    let mut out = io::stdout().lock();
    match host_tests::emu::console::run(&options, rx, &mut out, &mut io::stderr()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(host_tests::emu::Error::Io { source, .. })
            if source.kind() == io::ErrorKind::BrokenPipe =>
        {
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("pbtool emu: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The first probe `probe-rs list` reports, if probe-rs is installed and one is attached.
fn attached_probe() -> Option<String> {
    let output = std::process::Command::new("probe-rs")
        .arg("list")
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&output.stdout);
    // Probes are listed as `[0]: STLink V2-1 -- 0483:374b:... (ST-LINK)`.
    text.lines()
        .map(str::trim)
        .find(|line| line.starts_with('[') && line.contains("]:"))
        .map(str::to_string)
}

/// `cargo flash` from the workspace root: release build, flash and run with probe-rs.
fn flash_board() -> ExitCode {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
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

/// Exit status for a bad argument (as clap uses).
const USAGE: u8 = 2;

fn model_list() -> String {
    Model::ALL.map(Model::name).join(" ")
}

/// The unit `--ps` names and its `--fault`, or the usage status after saying what is wrong.
fn simulated_unit(
    command: &str,
    model: &str,
    fault: Option<&str>,
) -> Result<(Model, Option<u16>), ExitCode> {
    let Some(unit) = Model::from_name(model) else {
        eprintln!(
            "pbtool {command}: unknown model {model:?}; models: {}",
            model_list()
        );
        return Err(ExitCode::from(USAGE));
    };
    match fault.map(|f| parse_fault(unit, f)).transpose() {
        Ok(fault) => Ok((unit, fault)),
        Err(e) => {
            eprintln!("pbtool {command}: {e}");
            Err(ExitCode::from(USAGE))
        }
    }
}

fn sim(args: &SimArgs) -> ExitCode {
    let (model, fault) = match simulated_unit("sim", &args.unit.model, args.unit.fault.as_deref()) {
        Ok(unit) => unit,
        Err(status) => return status,
    };
    let mut console = Console::new(ConsoleOptions {
        model,
        fault,
        events: args.unit.events,
        seed: args.unit.seed,
        verbose: args.verbose,
    });
    let interactive = io::stdin().is_terminal();
    if interactive || args.verbose {
        eprintln!(
            "pbtool sim: the bridge against a simulated {model}{}; CNC protocol on stdin/stdout. \
             HELP lists the commands, TORCH ON|OFF drives torch-on (simulator only), \
             end of input (Ctrl-D) quits.",
            if args.fast { " in virtual time" } else { "" },
        );
    }
    let mut out = io::stdout().lock();
    let mut err = io::stderr();
    let result = if args.fast {
        console.run_virtual(&mut io::stdin().lock(), &mut out, &mut err)
    } else {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut stdin = io::stdin().lock();
            while let Ok(Some(line)) = read_line(&mut stdin as &mut dyn BufRead) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        console.run_realtime(rx, &mut out, &mut err)
    };
    let _ = out.flush();
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // A closed stdout (`| head`) ends the simulation quietly.
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("pbtool sim: {e}");
            ExitCode::FAILURE
        }
    }
}

fn decode(args: &DecodeArgs) -> ExitCode {
    let reports = decode_frames(&args.frames);
    if args.json {
        for report in &reports {
            println!("{}", to_json(report));
        }
    } else {
        print!("{}", to_text(&reports));
    }
    if all_valid(&reports) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
