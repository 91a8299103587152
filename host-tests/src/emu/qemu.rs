//! Starting QEMU with the emulated board: the sockets, the command line, and the process's
//! lifetime (killed when the [`Qemu`] is dropped).
//!
//! The harness listens on every socket first and then starts QEMU, whose socket chardevs are
//! clients: they connect while QEMU starts, before the guest runs, so nothing the firmware
//! writes is lost. QEMU starts paused (`-S`); [`Qemu::resume`] starts the CPU once the caller
//! has set the input pins through qtest. The firmware's defmt frames (semihosting) arrive on
//! QEMU's standard output, which goes to the run's log file.

use std::fs;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

use super::error::{Error, Result};
use super::image::workspace_root;
use super::qmp::Qmp;

/// The QEMU machine: STM32L475VG, the same family, flash and RAM as the board's STM32L476RG.
pub const MACHINE: &str = "b-l475e-iot01a";
/// The oldest QEMU whose STM32L4x5 models (RCC, GPIO, EXTI, USART) the board layer works on.
pub const MIN_QEMU_MAJOR: u32 = 10;
/// Environment variable naming another QEMU binary.
pub const QEMU_ENV: &str = "PLASMA_QEMU";
/// How long QEMU may take to connect its sockets.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(20);

/// How to install QEMU 10 on Debian bookworm (what `.ci/install-qemu` does).
pub const INSTALL_HINT: &str = "install QEMU 10 from Debian bookworm-backports: \
    `bash .ci/install-qemu` (adds the bookworm-backports suite to the apt sources, then \
    `apt-get update && apt-get install -y -t bookworm-backports qemu-system-arm`), \
    or point PLASMA_QEMU at a qemu-system-arm 10 binary";

/// The QEMU binary: `$PLASMA_QEMU` or `qemu-system-arm` on `PATH`.
pub fn qemu_binary() -> PathBuf {
    std::env::var_os(QEMU_ENV).map_or_else(|| PathBuf::from("qemu-system-arm"), PathBuf::from)
}

/// Checks that the QEMU binary runs and is recent enough; returns its version line.
pub fn check_qemu() -> Result<String> {
    check_qemu_binary(&qemu_binary())
}

/// As [`check_qemu`], but when `qemu-system-arm` 10 is missing (and `PLASMA_QEMU` does not
/// name another binary) runs the workspace's `.ci/install-qemu` first, once per process, so
/// that `cargo test` and `cargo emu` work on a fresh machine. A failed install is an error
/// with the script's output.
pub fn ensure_qemu() -> Result<String> {
    let missing = match check_qemu() {
        Ok(version) => return Ok(version),
        Err(e) => e,
    };
    if std::env::var_os(QEMU_ENV).is_some() {
        return Err(missing);
    }
    static INSTALLED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    INSTALLED
        .get_or_init(install_qemu)
        .clone()
        .map_err(|why| Error::Qemu(format!("{missing}\n{why}")))?;
    check_qemu()
}

/// Runs `.ci/install-qemu` (needs root or sudo, and the Debian archive).
fn install_qemu() -> std::result::Result<(), String> {
    let script = workspace_root().join(".ci").join("install-qemu");
    if !script.is_file() {
        return Err(format!("{} not found", script.display()));
    }
    eprintln!(
        "emu: qemu-system-arm {MIN_QEMU_MAJOR} is missing; installing it from Debian \
         bookworm-backports with {} (a minute or two)",
        script.display()
    );
    let output = Command::new("bash")
        .arg(&script)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
    if output.status.success() {
        eprintln!("emu: qemu-system-arm installed");
        return Ok(());
    }
    Err(format!(
        "{} failed ({}):\n{}{}",
        script.display(),
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    ))
}

/// As [`check_qemu`], for the binary `binary`.
pub fn check_qemu_binary(binary: &Path) -> Result<String> {
    let output = Command::new(binary)
        .arg("--version")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| {
            Error::Qemu(format!(
                "cannot run {} ({e}): the emulated board needs qemu-system-arm {MIN_QEMU_MAJOR} \
                 or later; {INSTALL_HINT}",
                binary.display()
            ))
        })?;
    let text = String::from_utf8_lossy(&output.stdout);
    let first = text.lines().next().unwrap_or("").trim().to_string();
    match parse_version(&first) {
        Some((major, _)) if major >= MIN_QEMU_MAJOR => Ok(first),
        Some(_) => Err(Error::Qemu(format!(
            "{} is too old ({first}): the emulated board needs qemu-system-arm \
             {MIN_QEMU_MAJOR} or later; {INSTALL_HINT}",
            binary.display()
        ))),
        None => Err(Error::Qemu(format!(
            "{} --version printed {first:?}, not a QEMU version; {INSTALL_HINT}",
            binary.display()
        ))),
    }
}

/// (major, minor) from `QEMU emulator version 10.0.2 (Debian ...)`.
pub fn parse_version(line: &str) -> Option<(u32, u32)> {
    let rest = line.split("version").nth(1)?.trim_start();
    let number = rest.split_whitespace().next()?;
    let mut parts = number.split('.');
    let major = parts.next()?.parse().ok()?;
    let minor = parts.next().and_then(|m| m.parse().ok()).unwrap_or(0);
    Some((major, minor))
}

/// QEMU is killed when the thread that starts it ends, however it ends: a `pbtool emu
/// --cnc-port` stopped with SIGKILL (or SIGTERM) never leaves a QEMU running. [`Qemu`] is
/// dropped by that thread in every use (a test, pbtool's main thread); this is the backstop
/// for the deaths that run no destructor. QEMU 10's `-run-with` has no `exit-with-parent` in
/// Debian's build.
#[cfg(target_os = "linux")]
fn die_with_this_thread(command: &mut Command) {
    use std::os::unix::process::CommandExt;
    // SAFETY: between fork and exec only `prctl`, which is async-signal-safe, runs in the
    // child; nothing is allocated and no lock is taken.
    unsafe {
        command.pre_exec(|| {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) == -1 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// Elsewhere QEMU outlives a killed harness; [`Qemu`]'s drop still kills it.
#[cfg(not(target_os = "linux"))]
fn die_with_this_thread(_: &mut Command) {}

/// How to run QEMU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct QemuOptions {
    /// The firmware ELF.
    pub elf: PathBuf,
    /// `-icount shift=0,sleep=on`: one guest nanosecond per instruction while the core runs,
    /// the host's time while it sleeps. The guest's clock then never runs ahead of what it
    /// executed and never loses a tick to a busy host, and instruction counts can be measured.
    /// Without it QEMU's clock follows the host's.
    pub icount: bool,
}

/// The private directory of one QEMU run, removed when dropped.
#[derive(Debug)]
pub struct RunDir {
    path: PathBuf,
}

impl RunDir {
    /// A fresh, empty directory under the system's temporary directory. Unix socket paths are
    /// limited to about 100 bytes, so the name stays short.
    pub fn new() -> Result<RunDir> {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = std::env::temp_dir().join(format!("pb-emu-{}-{n}", std::process::id()));
        // A directory left by a crashed process with a reused pid.
        let _ = fs::remove_dir_all(&path);
        fs::create_dir_all(&path)
            .map_err(|e| Error::io(format!("creating {}", path.display()), e))?;
        Ok(RunDir { path })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for RunDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.path);
    }
}

/// The QEMU command line for `options`, with its sockets and log file in `dir`.
pub fn command_line(options: &QemuOptions, dir: &Path) -> Vec<String> {
    let path = |name: &str| dir.join(name).display().to_string();
    let mut args: Vec<String> = [
        "-machine",
        MACHINE,
        "-display",
        "none",
        "-monitor",
        "none",
        "-nodefaults",
        "-S",
    ]
    .map(str::to_string)
    .into();
    args.push("-kernel".to_string());
    args.push(options.elf.display().to_string());
    // serial0 = USART1 = the PS port, serial1 = USART2 = the CNC port.
    for (id, file) in [("ps", "ps.sock"), ("cnc", "cnc.sock")] {
        args.push("-chardev".to_string());
        args.push(format!("socket,id={id},path={}", path(file)));
        args.push("-serial".to_string());
        args.push(format!("chardev:{id}"));
    }
    // Semihosting writes to `:tt` (defmt-semihosting's frames) go to QEMU's standard output
    // whatever `chardev=` says: the harness sends that to the log file.
    args.push("-semihosting-config".to_string());
    args.push("enable=on,target=native".to_string());
    args.push("-chardev".to_string());
    args.push(format!("socket,id=qmp,path={}", path("qmp.sock")));
    args.push("-mon".to_string());
    args.push("chardev=qmp,mode=control".to_string());
    args.push("-accel".to_string());
    args.push("tcg".to_string());
    args.push("-qtest".to_string());
    args.push(format!("unix:{}", path("qtest.sock")));
    // Without it QEMU echoes every qtest exchange on stderr.
    args.push("-qtest-log".to_string());
    args.push("/dev/null".to_string());
    if options.icount {
        args.push("-icount".to_string());
        args.push("shift=0,sleep=on".to_string());
    }
    args
}

/// The sockets of a started QEMU.
pub struct Sockets {
    /// USART1: the power-supply port.
    pub ps: UnixStream,
    /// USART2: the CNC port.
    pub cnc: UnixStream,
    /// The qtest session.
    pub qtest: UnixStream,
}

/// A running QEMU, paused until [`Qemu::resume`]; killed on drop.
pub struct Qemu {
    child: Child,
    qmp: Qmp,
    log_path: PathBuf,
    stderr_path: PathBuf,
    // Last: the sockets and files live in it.
    dir: RunDir,
}

impl Qemu {
    /// Starts QEMU with `options`; returns it (paused) with its connected sockets.
    pub fn start(options: &QemuOptions) -> Result<(Qemu, Sockets)> {
        ensure_qemu()?;
        if !options.elf.is_file() {
            return Err(Error::Image(format!(
                "the firmware image {} does not exist (build it with `cargo emu-fw`)",
                options.elf.display()
            )));
        }
        let dir = RunDir::new()?;
        let listen = |name: &str| {
            let path = dir.path().join(name);
            let listener = UnixListener::bind(&path)
                .map_err(|e| Error::io(format!("listening on {}", path.display()), e))?;
            listener
                .set_nonblocking(true)
                .map_err(|e| Error::io("socket", e))?;
            Ok::<_, Error>(listener)
        };
        let ps = listen("ps.sock")?;
        let cnc = listen("cnc.sock")?;
        let qmp = listen("qmp.sock")?;
        let qtest = listen("qtest.sock")?;
        let log_path = dir.path().join("log.defmt");
        let stderr_path = dir.path().join("qemu.stderr");
        let stderr = fs::File::create(&stderr_path)
            .map_err(|e| Error::io(format!("creating {}", stderr_path.display()), e))?;
        let log = fs::File::create(&log_path)
            .map_err(|e| Error::io(format!("creating {}", log_path.display()), e))?;
        let mut command = Command::new(qemu_binary());
        command
            .args(command_line(options, dir.path()))
            .stdin(Stdio::null())
            .stdout(log)
            .stderr(stderr);
        die_with_this_thread(&mut command);
        let child = command.spawn().map_err(|e| {
            Error::Qemu(format!("cannot start qemu-system-arm: {e}; {INSTALL_HINT}"))
        })?;
        let mut starting = Starting {
            child: Some(child),
            stderr_path: stderr_path.clone(),
            deadline: Instant::now() + CONNECT_TIMEOUT,
        };
        let ps = starting.accept(&ps, "PS serial")?;
        let cnc = starting.accept(&cnc, "CNC serial")?;
        let qmp = starting.accept(&qmp, "QMP")?;
        let qtest = starting.accept(&qtest, "qtest")?;
        let qmp = Qmp::handshake(qmp)?;
        let child = starting.child.take().expect("still starting");
        Ok((
            Qemu {
                child,
                qmp,
                log_path,
                stderr_path,
                dir,
            },
            Sockets { ps, cnc, qtest },
        ))
    }

    /// Starts the guest CPU.
    pub fn resume(&mut self) -> Result<()> {
        self.qmp.cont()
    }

    /// The QMP session (run state, resets).
    pub fn qmp(&mut self) -> &mut Qmp {
        &mut self.qmp
    }

    /// The semihosting log file (defmt frames).
    pub fn log_path(&self) -> &Path {
        &self.log_path
    }

    /// The run's directory.
    pub fn dir(&self) -> &Path {
        self.dir.path()
    }

    /// What QEMU wrote on stderr so far.
    pub fn stderr(&self) -> String {
        fs::read_to_string(&self.stderr_path).unwrap_or_default()
    }

    /// `Some(status)` once QEMU has exited.
    pub fn exited(&mut self) -> Option<std::process::ExitStatus> {
        self.child.try_wait().ok().flatten()
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// QEMU while its sockets connect: killed if they don't.
struct Starting {
    child: Option<Child>,
    stderr_path: PathBuf,
    deadline: Instant,
}

impl Starting {
    fn accept(&mut self, listener: &UnixListener, what: &str) -> Result<UnixStream> {
        loop {
            match listener.accept() {
                Ok((stream, _)) => {
                    stream
                        .set_nonblocking(false)
                        .map_err(|e| Error::io(what.to_string(), e))?;
                    return Ok(stream);
                }
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(e) => return Err(Error::io(format!("accepting the {what} socket"), e)),
            }
            let child = self.child.as_mut().expect("still starting");
            if let Ok(Some(status)) = child.try_wait() {
                let stderr = fs::read_to_string(&self.stderr_path).unwrap_or_default();
                return Err(Error::Exited(format!(
                    "qemu-system-arm exited ({status}) before connecting its {what} socket:\n{}",
                    stderr.trim()
                )));
            }
            if Instant::now() > self.deadline {
                return Err(Error::Timeout(format!(
                    "qemu-system-arm did not connect its {what} socket in {} s",
                    CONNECT_TIMEOUT.as_secs()
                )));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

impl Drop for Starting {
    fn drop(&mut self) {
        if let Some(child) = &mut self.child {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_are_read_from_the_banner() {
        assert_eq!(
            parse_version("QEMU emulator version 10.0.2 (Debian 1:10.0.2+ds-2+deb13u1~bpo12+1)"),
            Some((10, 0))
        );
        assert_eq!(
            parse_version("QEMU emulator version 7.2.15 (Debian 1:7.2+dfsg-7+deb12u13)"),
            Some((7, 2))
        );
        assert_eq!(parse_version("bash: qemu: not found"), None);
    }

    #[test]
    fn the_command_line_follows_the_contract() {
        let dir = Path::new("/tmp/x");
        let options = QemuOptions {
            elf: PathBuf::from("/fw.elf"),
            icount: false,
        };
        let line = command_line(&options, dir).join(" ");
        for part in [
            "-machine b-l475e-iot01a",
            "-kernel /fw.elf",
            "-chardev socket,id=ps,path=/tmp/x/ps.sock -serial chardev:ps",
            "-chardev socket,id=cnc,path=/tmp/x/cnc.sock -serial chardev:cnc",
            "-semihosting-config enable=on,target=native",
            "-accel tcg -qtest unix:/tmp/x/qtest.sock",
            "-S",
        ] {
            assert!(line.contains(part), "{part:?} missing from {line}");
        }
        // PS first: serial0 is USART1.
        assert!(line.find("chardev:ps").unwrap() < line.find("chardev:cnc").unwrap());
        assert!(!line.contains("icount"));
        let measured = command_line(
            &QemuOptions {
                icount: true,
                ..options
            },
            dir,
        );
        assert!(measured.join(" ").ends_with("-icount shift=0,sleep=on"));
    }

    #[test]
    fn a_missing_or_old_qemu_says_how_to_install_it() {
        let err = check_qemu_binary(Path::new("/nonexistent/qemu-system-arm"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("cannot run /nonexistent/qemu-system-arm"),
            "{err}"
        );
        assert!(
            err.contains("apt-get install -y -t bookworm-backports qemu-system-arm"),
            "{err}"
        );

        let dir = RunDir::new().unwrap();
        let fake = |name: &str, banner: &str| {
            let path = dir.path().join(name);
            fs::write(&path, format!("#!/bin/sh\necho '{banner}'\n")).unwrap();
            let mut permissions = fs::metadata(&path).unwrap().permissions();
            std::os::unix::fs::PermissionsExt::set_mode(&mut permissions, 0o755);
            fs::set_permissions(&path, permissions).unwrap();
            path
        };
        let old = fake("old", "QEMU emulator version 7.2.15 (Debian 1:7.2+dfsg-7)");
        let err = check_qemu_binary(&old).unwrap_err().to_string();
        assert!(
            err.contains("is too old (QEMU emulator version 7.2.15"),
            "{err}"
        );
        assert!(err.contains("bookworm-backports"), "{err}");
        let new = fake("new", "QEMU emulator version 10.0.2 (Debian)");
        assert_eq!(
            check_qemu_binary(&new).unwrap(),
            "QEMU emulator version 10.0.2 (Debian)"
        );
    }
}
