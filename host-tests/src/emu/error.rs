//! The one error type of the emulation harness.

use std::fmt;
use std::io;

/// What went wrong while running the emulated board.
#[derive(Debug)]
pub enum Error {
    /// `qemu-system-arm` is not installed (or not on `PATH`), or too old.
    Qemu(String),
    /// The firmware image could not be built or found.
    Image(String),
    /// An I/O error, with what was being done.
    Io {
        /// What the harness was doing.
        context: String,
        /// The error.
        source: io::Error,
    },
    /// QEMU answered something the protocol does not allow (qtest `FAIL`, a malformed line).
    Protocol(String),
    /// Something did not happen in time.
    Timeout(String),
    /// QEMU exited (or closed a socket) while the harness still needed it.
    Exited(String),
}

impl Error {
    /// An [`Error::Io`] with its context.
    pub fn io(context: impl Into<String>, source: io::Error) -> Error {
        Error::Io {
            context: context.into(),
            source,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Qemu(text) | Error::Image(text) => f.write_str(text),
            Error::Io { context, source } => write!(f, "{context}: {source}"),
            Error::Protocol(text) => write!(f, "protocol error: {text}"),
            Error::Timeout(text) => write!(f, "timed out: {text}"),
            Error::Exited(text) => write!(f, "QEMU is gone: {text}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// The harness's result type.
pub type Result<T> = std::result::Result<T, Error>;
