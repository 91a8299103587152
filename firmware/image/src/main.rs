//! Builds or runs a board image with the build machine's paths remapped, so that the image's
//! bytes do not depend on where the checkout, the cargo registry or the target directory lie.
//!
//! Paths reach the image through panic locations (`file!()` of every panic site, in `.rodata`)
//! and the debug info. rustc's `--remap-path-prefix` rewrites them; stable cargo has no
//! `trim-paths` yet and an alias cannot compute a path, so `cargo fw`, `cargo emu-fw` and
//! `cargo flash` (.cargo/config.toml) run this program, which runs cargo for the MCU target
//! with one remapping per prefix:
//!
//! | prefix | becomes |
//! |---|---|
//! | the workspace root | `/plasma-bridge` |
//! | the target directory (`$CARGO_TARGET_DIR`, build scripts' generated code) | `/target` |
//! | each registry's sources (`$CARGO_HOME/registry/src/<index>`) | `/deps` |
//! | git dependencies (`$CARGO_HOME/git/checkouts`) | `/git` |
//!
//! The flags are given with `--config target.<triple>.rustflags=[...]`, which cargo appends
//! to the workspace's own rustflags (linker scripts, CPU, inline threshold) instead of
//! replacing them, and which quotes paths with spaces correctly.
//!
//! ```text
//! plasma-image build plasma-bridge [cargo build options]   # cargo fw
//! plasma-image build plasma-bridge-emu [cargo build options]   # cargo emu-fw
//! plasma-image run plasma-bridge [cargo run options]   # cargo flash
//! ```

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

/// The MCU target of every board.
const TARGET: &str = "thumbv7em-none-eabihf";

/// The board images: binary name and the package that holds it.
const IMAGES: [(&str, &str); 2] = [
    ("plasma-bridge", "plasma-board-nucleo"),
    ("plasma-bridge-emu", "plasma-board-emu"),
];

fn main() -> ExitCode {
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    let request = match Request::parse(&args) {
        Ok(request) => request,
        Err(message) => {
            eprintln!("plasma-image: {message}\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    let paths = BuildPaths::from_env(workspace_root());
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(&paths.workspace_root)
        .args(request.cargo_args(&paths))
        .status();
    match status {
        Ok(status) if status.success() => ExitCode::SUCCESS,
        Ok(status) => ExitCode::from(
            status
                .code()
                .and_then(|c| u8::try_from(c).ok())
                .unwrap_or(1),
        ),
        Err(e) => {
            eprintln!("plasma-image: cannot run cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

const USAGE: &str = "usage: plasma-image build|run plasma-bridge|plasma-bridge-emu [cargo options]";

/// What to do, parsed from the command line.
#[derive(Debug, PartialEq)]
struct Request<'a> {
    /// `build` or `run`.
    command: &'static str,
    binary: &'static str,
    package: &'static str,
    /// Passed on to cargo after ours (`--features panic-message`, `--message-format=json`).
    extra: &'a [OsString],
}

impl<'a> Request<'a> {
    fn parse(args: &'a [OsString]) -> Result<Self, String> {
        let [command, binary, extra @ ..] = args else {
            return Err("a command and an image are needed".to_string());
        };
        let command = match command.to_str() {
            Some("build") => "build",
            Some("run") => "run",
            _ => return Err(format!("unknown command {command:?}")),
        };
        let (binary, package) = IMAGES
            .into_iter()
            .find(|(name, _)| binary.to_str() == Some(name))
            .ok_or_else(|| format!("unknown image {binary:?}"))?;
        Ok(Request {
            command,
            binary,
            package,
            extra,
        })
    }

    /// `--config <remapping> <command> -p <package> --bin <binary> --release --target <MCU>
    /// <extra>`.
    fn cargo_args(&self, paths: &BuildPaths) -> Vec<OsString> {
        let mut args: Vec<OsString> = vec!["--config".into(), paths.rustflags_config().into()];
        args.extend(
            [
                self.command,
                "-p",
                self.package,
                "--bin",
                self.binary,
                "--release",
                "--target",
                TARGET,
            ]
            .map(OsString::from),
        );
        args.extend(self.extra.iter().cloned());
        args
    }
}

/// The workspace root: this package lives in `<root>/firmware/image`.
///
/// `cargo run` sets `CARGO_MANIFEST_DIR` at run time to the checkout it runs in; the value
/// compiled in is only the fallback for a binary started by hand. Preferring the compiled-in
/// path would build another checkout's sources when a `target/` directory was copied from it
/// (cargo reuses the binary, whose compiled-in path still names the first checkout).
fn workspace_root() -> PathBuf {
    let manifest = std::env::var_os("CARGO_MANIFEST_DIR")
        .map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")), PathBuf::from);
    let root = manifest
        .ancestors()
        .nth(2)
        .unwrap_or(&manifest)
        .to_path_buf();
    root.canonicalize().unwrap_or(root)
}

/// The build machine's paths that end up in an image.
#[derive(Debug)]
struct BuildPaths {
    workspace_root: PathBuf,
    target_dir: PathBuf,
    cargo_home: Option<PathBuf>,
    /// The registries' source directories (`$CARGO_HOME/registry/src/<index>`).
    registries: Vec<PathBuf>,
}

impl BuildPaths {
    fn from_env(workspace_root: PathBuf) -> Self {
        let target_dir = match std::env::var_os("CARGO_TARGET_DIR") {
            Some(dir) => absolute(&workspace_root, Path::new(&dir)),
            None => workspace_root.join("target"),
        };
        let cargo_home = std::env::var_os("CARGO_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|home| Path::new(&home).join(".cargo")))
            .map(|home| absolute(&workspace_root, &home));
        let registries = cargo_home
            .as_ref()
            .and_then(|home| std::fs::read_dir(home.join("registry/src")).ok())
            .map(|entries| {
                let mut dirs: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
                dirs.sort();
                dirs
            })
            .unwrap_or_default();
        BuildPaths {
            workspace_root,
            target_dir,
            cargo_home,
            registries,
        }
    }

    /// `(from, to)` for each prefix. rustc applies the last remapping that matches, so the
    /// longer prefixes (the target directory, usually inside the workspace) come later.
    fn remappings(&self) -> Vec<(PathBuf, &'static str)> {
        let mut remap = vec![
            (self.workspace_root.clone(), "/plasma-bridge"),
            (self.target_dir.clone(), "/target"),
        ];
        if let Some(home) = &self.cargo_home {
            remap.push((home.join("git/checkouts"), "/git"));
        }
        remap.extend(self.registries.iter().map(|dir| (dir.clone(), "/deps")));
        // Source paths are the ones cargo gives, but the debug info's compilation directory
        // is where rustc runs (a dependency's own directory), with symbolic links resolved:
        // a CARGO_HOME reached through a link needs its real path remapped too.
        let resolved: Vec<(PathBuf, &'static str)> = remap
            .iter()
            .filter_map(|(from, to)| {
                let real = from.canonicalize().ok()?;
                (real != *from).then_some((real, *to))
            })
            .collect();
        remap.extend(resolved);
        remap
    }

    /// `target.<MCU>.rustflags=[...]` for `cargo --config`: TOML, so any path is quoted.
    fn rustflags_config(&self) -> String {
        let flags: Vec<String> = self
            .remappings()
            .iter()
            .map(|(from, to)| toml_string(&format!("--remap-path-prefix={}={to}", from.display())))
            .collect();
        format!("target.{TARGET}.rustflags=[{}]", flags.join(", "))
    }
}

/// `path` made absolute against `base`, as cargo makes it (against the directory it runs in,
/// the workspace root here) and hands it to rustc: symbolic links are not resolved, or the
/// prefix would not match.
fn absolute(base: &Path, path: &Path) -> PathBuf {
    base.join(path)
}

/// A TOML basic string.
fn toml_string(text: &str) -> String {
    let mut quoted = String::with_capacity(text.len() + 2);
    quoted.push('"');
    for c in text.chars() {
        match c {
            '"' => quoted.push_str("\\\""),
            '\\' => quoted.push_str("\\\\"),
            c if c.is_control() => quoted.push_str(&format!("\\u{:04X}", c as u32)),
            c => quoted.push(c),
        }
    }
    quoted.push('"');
    quoted
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paths() -> BuildPaths {
        BuildPaths {
            workspace_root: PathBuf::from("/home/a b/plasma"),
            target_dir: PathBuf::from("/home/a b/plasma/target"),
            cargo_home: Some(PathBuf::from("/home/u/.cargo")),
            registries: vec![PathBuf::from(
                "/home/u/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f",
            )],
        }
    }

    fn os(args: &[&str]) -> Vec<OsString> {
        args.iter().map(OsString::from).collect()
    }

    #[test]
    fn every_machine_path_is_remapped_longest_last() {
        let config = paths().rustflags_config();
        assert_eq!(
            config,
            "target.thumbv7em-none-eabihf.rustflags=[\
             \"--remap-path-prefix=/home/a b/plasma=/plasma-bridge\", \
             \"--remap-path-prefix=/home/a b/plasma/target=/target\", \
             \"--remap-path-prefix=/home/u/.cargo/git/checkouts=/git\", \
             \"--remap-path-prefix=/home/u/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f=/deps\"]"
        );
    }

    #[test]
    fn the_images_map_to_their_board_packages() {
        let args = os(&["build", "plasma-bridge-emu", "--message-format=json"]);
        let request = Request::parse(&args).unwrap();
        assert_eq!(request.package, "plasma-board-emu");
        let cargo = request.cargo_args(&paths());
        let text: Vec<&str> = cargo.iter().map(|a| a.to_str().unwrap()).collect();
        assert_eq!(text[0], "--config");
        assert_eq!(
            text[2..],
            [
                "build",
                "-p",
                "plasma-board-emu",
                "--bin",
                "plasma-bridge-emu",
                "--release",
                "--target",
                "thumbv7em-none-eabihf",
                "--message-format=json"
            ]
        );
        let run = os(&["run", "plasma-bridge"]);
        assert_eq!(Request::parse(&run).unwrap().package, "plasma-board-nucleo");
    }

    #[test]
    fn unknown_commands_and_images_are_refused() {
        assert!(Request::parse(&os(&["build"])).is_err());
        assert!(Request::parse(&os(&["flash", "plasma-bridge"])).is_err());
        assert!(Request::parse(&os(&["build", "plasma"])).is_err());
    }

    #[test]
    fn toml_strings_escape_quotes_and_backslashes() {
        assert_eq!(toml_string(r#"C:\a "b""#), r#""C:\\a \"b\"""#);
    }

    #[test]
    fn the_workspace_root_holds_the_memory_map() {
        assert!(workspace_root().join("memory.x").is_file());
    }
}
