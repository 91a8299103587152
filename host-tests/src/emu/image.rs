//! The emulated board's firmware image: built once per process with
//! `cargo emu-fw --features test-hooks`, wherever the caller runs from. The alias builds the
//! `plasma-bridge-emu` binary through firmware/image, with the build machine's paths
//! remapped, so the tests run the very bytes a build by hand with the same feature gives.
//!
//! [`TEST_FEATURES`] adds what only tests use (the emulated board's src/test_hooks.rs: pins
//! that stall thread mode, panic or take a HardFault, for the fail-safe and fault-path tests,
//! see [`TestHook`](super::TestHook)); the Nucleo image and a plain `cargo emu-fw` never
//! contain it.
//!
//! Cargo is asked for the artifact's path (`--message-format=json`), so `CARGO_TARGET_DIR`
//! and the workspace's settings apply exactly as for a build by hand. `PLASMA_EMU_ELF` names
//! a prebuilt image instead.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;

use super::error::{Error, Result};

/// Environment variable naming a prebuilt image (skips the build).
pub const ELF_ENV: &str = "PLASMA_EMU_ELF";
/// The emulated board's binary.
pub const BINARY: &str = "plasma-bridge-emu";
/// Features of the emulated board that only test images have.
pub const TEST_FEATURES: &str = "test-hooks";
/// The MCU target.
pub const TARGET: &str = "thumbv7em-none-eabihf";

/// The workspace root (where `.cargo/config.toml` defines `emu-fw`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// The image: `$PLASMA_EMU_ELF`, or built by `cargo emu-fw` (once per process; later calls
/// return the first result).
pub fn firmware_elf() -> Result<PathBuf> {
    if let Some(path) = std::env::var_os(ELF_ENV) {
        return Ok(PathBuf::from(path));
    }
    static BUILT: OnceLock<std::result::Result<PathBuf, String>> = OnceLock::new();
    BUILT
        .get_or_init(|| build().map_err(|e| e.to_string()))
        .clone()
        .map_err(Error::Image)
}

/// Adds the MCU target with rustup when it is missing (a fresh machine), as `pbtool run`
/// does; without rustup the build below says what is wrong.
fn ensure_target() {
    let installed = Command::new("rustup")
        .args(["target", "list", "--installed"])
        .stdin(Stdio::null())
        .output();
    let Ok(installed) = installed else { return };
    if String::from_utf8_lossy(&installed.stdout)
        .lines()
        .any(|l| l.trim() == TARGET)
    {
        return;
    }
    eprintln!("emu: adding the {TARGET} target with rustup (the emulated board's image)");
    let _ = Command::new("rustup")
        .args(["target", "add", TARGET])
        .stdin(Stdio::null())
        .status();
}

/// Runs `cargo emu-fw --features test-hooks` and returns the ELF cargo reports.
fn build() -> Result<PathBuf> {
    ensure_target();
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut child = Command::new(&cargo)
        .current_dir(workspace_root())
        .args([
            "emu-fw",
            "--features",
            TEST_FEATURES,
            "--message-format=json-render-diagnostics",
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| Error::Image(format!("cannot run cargo to build the image: {e}")))?;
    // stderr on its own thread, so neither pipe can fill up and stall cargo.
    let stderr = child.stderr.take().expect("piped");
    let errors = std::thread::spawn(move || {
        let mut text = String::new();
        for line in BufReader::new(stderr).lines().map_while(|l| l.ok()) {
            text.push_str(&line);
            text.push('\n');
        }
        text
    });
    let stdout = child.stdout.take().expect("piped");
    let mut elf = None;
    for line in BufReader::new(stdout).lines().map_while(|l| l.ok()) {
        if let Some(path) = executable_of(&line, BINARY) {
            elf = Some(path);
        }
    }
    let status = child
        .wait()
        .map_err(|e| Error::Image(format!("waiting for cargo: {e}")))?;
    let errors = errors.join().unwrap_or_default();
    if !status.success() {
        let hint = if errors.contains("target may not be installed")
            || errors.contains("can't find crate for `core`")
        {
            format!("\nhint: rustup target add {TARGET}")
        } else if errors.contains("no such command: `emu-fw`") {
            "\nhint: the workspace's .cargo/config.toml lacks the emu-fw alias".to_string()
        } else {
            String::new()
        };
        return Err(Error::Image(format!(
            "`cargo emu-fw` failed ({status}):\n{}{hint}",
            tail(&errors, 40)
        )));
    }
    elf.ok_or_else(|| {
        Error::Image(format!(
            "`cargo emu-fw` succeeded but reported no `{BINARY}` executable:\n{}",
            tail(&errors, 20)
        ))
    })
}

/// The executable of `binary` in one line of cargo's JSON messages.
pub fn executable_of(line: &str, binary: &str) -> Option<PathBuf> {
    let message: serde_json::Value = serde_json::from_str(line).ok()?;
    if message.get("reason")?.as_str()? != "compiler-artifact" {
        return None;
    }
    if message.get("target")?.get("name")?.as_str()? != binary {
        return None;
    }
    message.get("executable")?.as_str().map(PathBuf::from)
}

fn tail(text: &str, lines: usize) -> String {
    let all: Vec<&str> = text.lines().collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_executable_is_found_in_cargos_messages() {
        let artifact = r#"{"reason":"compiler-artifact","package_id":"x","target":{"kind":["bin"],"name":"plasma-bridge-emu"},"executable":"/t/thumbv7em-none-eabihf/release/plasma-bridge-emu","fresh":true}"#;
        assert_eq!(
            executable_of(artifact, BINARY),
            Some(PathBuf::from(
                "/t/thumbv7em-none-eabihf/release/plasma-bridge-emu"
            ))
        );
        let lib = r#"{"reason":"compiler-artifact","target":{"kind":["lib"],"name":"plasma_firmware"},"executable":null}"#;
        assert_eq!(executable_of(lib, BINARY), None);
        let other = r#"{"reason":"compiler-artifact","target":{"name":"plasma-bridge"},"executable":"/t/plasma-bridge"}"#;
        assert_eq!(executable_of(other, BINARY), None);
        assert_eq!(
            executable_of(r#"{"reason":"build-finished","success":true}"#, BINARY),
            None
        );
        assert_eq!(executable_of("Compiling x", BINARY), None);
    }

    #[test]
    fn the_workspace_root_holds_the_cargo_config() {
        assert!(workspace_root().join(".cargo/config.toml").is_file());
    }
}
