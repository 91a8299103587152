//! A PC's serial port (a USB-RS485 adapter, a pty in the tests) for the real-time commands,
//! on the `serialport` crate.
//!
//! - [`Port::open`] says clearly why a port cannot be used: missing, in use, not permitted.
//! - The framing is a [`PortConfig`] and may change while the port is open (the bridge's
//!   detection tries 8E1, 8O1, 8N1 and two stop bits). What the port reads back is never
//!   checked: a pty keeps no parity and no character size (the kernel sets CS8 and drops
//!   PARENB), and that is no error.
//! - [`Port::read`] blocks up to a time-out, so a loop waiting for characters sleeps in the
//!   kernel instead of spinning. A character the UART flagged with a parity or framing error
//!   comes as [`Rx::Error`] (on Unix the port marks them, PARMRK); the caller counts it as
//!   the link does.
//! - A port that goes away (an adapter unplugged, the other end of a pty closed) is
//!   [`SerialError::Gone`], on read and on write.

use std::fmt;
use std::io::{self, Read, Write};
use std::time::Duration;

use plasma_protocol::serial::{DataBits, Parity, PortConfig, StopBits};

/// The bridge's CNC port until `CONFIG cnc_baud/cnc_parity/cnc_stop_bits/cnc_data_bits`
/// change it: the
/// settings' default (115200 8N1, as the board's ST-LINK virtual COM port).
pub const CNC_PORT: PortConfig = plasma_firmware::settings::CncPort::DEFAULT.framing;

/// How long one write may block (a port that takes no characters at all is gone).
const WRITE_TIMEOUT: Duration = Duration::from_secs(2);

/// Why a port cannot be used.
#[derive(Debug)]
pub enum SerialError {
    /// No such device.
    Missing(String),
    /// Another program has it open.
    Busy(String),
    /// The user may not open it.
    Permission(String),
    /// It went away while in use.
    Gone(String, io::Error),
    /// It is a file or a device other than a serial port (`/dev/null`, a typo'd path).
    NotSerial(String),
    /// Anything else the OS said.
    Other(String, String),
}

impl fmt::Display for SerialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SerialError::Missing(port) => write!(
                f,
                "serial port {port} does not exist (is the adapter plugged in? Linux: ls \
                 /dev/ttyUSB* /dev/serial/by-id; macOS: ls /dev/cu.*; Windows: COM3 etc. in the \
                 Device Manager)"
            ),
            SerialError::Busy(port) => {
                write!(f, "serial port {port} is in use by another program")
            }
            SerialError::Permission(port) => write!(
                f,
                "no permission to open serial port {port} (Linux: sudo usermod -aG dialout \
                 $USER, then log in again; Windows says this when another program has the \
                 port open)"
            ),
            SerialError::Gone(port, e) => write!(
                f,
                "serial port {port} went away ({e}): adapter unplugged or the line closed"
            ),
            SerialError::NotSerial(port) => write!(
                f,
                "{port} is not a serial port (a file or another kind of device): give the \
                 adapter's port (Linux: ls /dev/serial/by-id /dev/ttyUSB* /dev/ttyACM*)"
            ),
            SerialError::Other(port, e) => write!(f, "serial port {port}: {e}"),
        }
    }
}

impl std::error::Error for SerialError {}

/// One received character, or the mark of one the UART received with a parity or framing
/// error (or a break).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rx {
    /// A good character.
    Byte(u8),
    /// A flagged character.
    Error,
}

impl Rx {
    /// `received` as the bridge's CNC session takes it: a flagged character becomes `?`, one
    /// it cannot read, in its place.
    pub fn cnc_bytes(received: &[Rx]) -> Vec<u8> {
        received
            .iter()
            .map(|r| match r {
                Rx::Byte(b) => *b,
                Rx::Error => b'?',
            })
            .collect()
    }
}

#[cfg(unix)]
type Native = serialport::TTYPort;
#[cfg(windows)]
type Native = serialport::COMPort;

/// An open serial port.
pub struct Port {
    native: Native,
    name: String,
    config: PortConfig,
    marks: MarkDecoder,
}

impl fmt::Debug for Port {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Port")
            .field("name", &self.name)
            .field("config", &self.config)
            .finish()
    }
}

impl Port {
    /// Opens `name` (exclusively where the OS allows) with `config`.
    pub fn open(name: &str, config: PortConfig) -> Result<Port, SerialError> {
        let builder = serialport::new(name, config.baud)
            .data_bits(data_bits(config.data_bits))
            .parity(parity(config.parity))
            .stop_bits(stop_bits(config.stop_bits))
            .flow_control(serialport::FlowControl::None)
            .timeout(WRITE_TIMEOUT);
        let native = builder.open_native().map_err(|e| open_error(name, &e))?;
        let mut port = Port {
            native,
            name: name.to_string(),
            config,
            marks: MarkDecoder::default(),
        };
        port.mark_errors();
        Ok(port)
    }

    /// The name it was opened with.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The framing last set (not read back: see the module docs).
    pub fn config(&self) -> PortConfig {
        self.config
    }

    /// Another handle on the same port (a reader thread's).
    pub fn try_clone(&self) -> Result<Port, SerialError> {
        let native = self
            .native
            .try_clone_native()
            .map_err(|e| SerialError::Other(self.name.clone(), e.to_string()))?;
        Ok(Port {
            native,
            name: self.name.clone(),
            config: self.config,
            marks: MarkDecoder::default(),
        })
    }

    /// Sets the framing (nothing to do when it is already `config`).
    pub fn set_config(&mut self, config: PortConfig) -> Result<(), SerialError> {
        use serialport::SerialPort;
        if config == self.config {
            return Ok(());
        }
        let name = self.name.clone();
        let fail = |e: serialport::Error| match e.kind() {
            serialport::ErrorKind::Io(kind) => SerialError::Gone(name.clone(), kind.into()),
            _ => SerialError::Other(name.clone(), e.to_string()),
        };
        self.native.set_baud_rate(config.baud).map_err(fail)?;
        self.native
            .set_data_bits(data_bits(config.data_bits))
            .map_err(fail)?;
        self.native
            .set_parity(parity(config.parity))
            .map_err(fail)?;
        self.native
            .set_stop_bits(stop_bits(config.stop_bits))
            .map_err(fail)?;
        self.config = config;
        self.mark_errors();
        Ok(())
    }

    /// Waits up to `timeout` for characters and appends what came to `out` (nothing after a
    /// time-out).
    pub fn read(&mut self, timeout: Duration, out: &mut Vec<Rx>) -> Result<(), SerialError> {
        use serialport::SerialPort;
        // The crate's read time-out is the port's one time-out; writes set theirs back.
        self.native
            .set_timeout(timeout.max(Duration::from_millis(1)))
            .map_err(|e| SerialError::Other(self.name.clone(), e.to_string()))?;
        let mut buf = [0u8; 256];
        let result = self.native.read(&mut buf);
        match result {
            // A tty that reads nothing without a time-out has hung up.
            Ok(0) => Err(SerialError::Gone(
                self.name.clone(),
                io::Error::new(io::ErrorKind::UnexpectedEof, "end of file"),
            )),
            Ok(n) => {
                for &b in &buf[..n] {
                    self.marks.push(b, out);
                }
                Ok(())
            }
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock
                ) =>
            {
                Ok(())
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => Ok(()),
            Err(e) => Err(SerialError::Gone(self.name.clone(), e)),
        }
    }

    /// Writes all of `bytes`.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<(), SerialError> {
        use serialport::SerialPort;
        let _ = self.native.set_timeout(WRITE_TIMEOUT);
        self.native
            .write_all(bytes)
            .map_err(|e| SerialError::Gone(self.name.clone(), e))
    }

    /// Asks the OS to mark characters received with a parity or framing error (PARMRK)
    /// instead of dropping them or reading them as NUL. Best effort: where it cannot be set
    /// (a pty keeps the flag but has no UART) nothing is lost but the counting.
    #[cfg(unix)]
    fn mark_errors(&mut self) {
        use std::os::unix::io::AsRawFd;
        let fd = self.native.as_raw_fd();
        let mut termios = std::mem::MaybeUninit::<libc::termios>::uninit();
        // SAFETY: fd is this port's open descriptor; tcgetattr fills the struct on success.
        if unsafe { libc::tcgetattr(fd, termios.as_mut_ptr()) } != 0 {
            return;
        }
        // SAFETY: initialised by the successful tcgetattr above.
        let mut termios = unsafe { termios.assume_init() };
        termios.c_iflag |= libc::PARMRK;
        // Report framing errors and breaks too (serialport ignores them without parity);
        // keep the eighth bit.
        termios.c_iflag &= !(libc::IGNPAR | libc::IGNBRK | libc::BRKINT | libc::ISTRIP);
        // SAFETY: fd as above; termios is a valid settings struct.
        unsafe { libc::tcsetattr(fd, libc::TCSANOW, &termios) };
    }

    #[cfg(not(unix))]
    fn mark_errors(&mut self) {}
}

/// Undoes PARMRK's marking: `FF FF` is a received `FF`, `FF 00 x` a flagged character.
#[derive(Debug, Default, Clone, Copy)]
struct MarkDecoder {
    state: u8,
}

impl MarkDecoder {
    fn push(&mut self, byte: u8, out: &mut Vec<Rx>) {
        if cfg!(not(unix)) {
            out.push(Rx::Byte(byte));
            return;
        }
        match (self.state, byte) {
            (0, 0xFF) => self.state = 1,
            (0, b) => out.push(Rx::Byte(b)),
            (1, 0xFF) => {
                out.push(Rx::Byte(0xFF));
                self.state = 0;
            }
            (1, 0x00) => self.state = 2,
            // Not a marking the OS makes: keep both bytes.
            (1, b) => {
                out.push(Rx::Byte(0xFF));
                out.push(Rx::Byte(b));
                self.state = 0;
            }
            (_, _) => {
                out.push(Rx::Error);
                self.state = 0;
            }
        }
    }
}

fn data_bits(data_bits: DataBits) -> serialport::DataBits {
    match data_bits {
        DataBits::Seven => serialport::DataBits::Seven,
        DataBits::Eight => serialport::DataBits::Eight,
    }
}

fn parity(parity: Parity) -> serialport::Parity {
    match parity {
        Parity::None => serialport::Parity::None,
        Parity::Even => serialport::Parity::Even,
        Parity::Odd => serialport::Parity::Odd,
    }
}

fn stop_bits(stop_bits: StopBits) -> serialport::StopBits {
    match stop_bits {
        StopBits::One => serialport::StopBits::One,
        StopBits::Two => serialport::StopBits::Two,
    }
}

fn open_error(name: &str, e: &serialport::Error) -> SerialError {
    let name = name.to_string();
    match e.kind() {
        serialport::ErrorKind::Io(io::ErrorKind::NotFound) => SerialError::Missing(name),
        serialport::ErrorKind::Io(io::ErrorKind::PermissionDenied) => SerialError::Permission(name),
        // serialport reports a port locked by another program (TIOCEXCL, flock) as NoDevice.
        serialport::ErrorKind::NoDevice if std::path::Path::new(&name).exists() => {
            SerialError::Busy(name)
        }
        serialport::ErrorKind::NoDevice => SerialError::Missing(name),
        _ if cfg!(unix) && !std::path::Path::new(&name).exists() => SerialError::Missing(name),
        _ if is_not_a_terminal(&name) => SerialError::NotSerial(name),
        _ => SerialError::Other(name, e.to_string()),
    }
}

/// Whether `name` opens but is not a terminal device (the OS's "Not a typewriter").
#[cfg(unix)]
fn is_not_a_terminal(name: &str) -> bool {
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::AsRawFd;
    let opened = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(name);
    // SAFETY: isatty only inspects a descriptor the file owns.
    opened.is_ok_and(|file| unsafe { libc::isatty(file.as_raw_fd()) } == 0)
}

#[cfg(not(unix))]
fn is_not_a_terminal(_name: &str) -> bool {
    false
}

/// Text for a `PortConfig`: `19200 8E1`.
pub fn describe(config: PortConfig) -> String {
    config.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serialport::SerialPort as _;

    fn unmark(bytes: &[u8]) -> Vec<Rx> {
        let mut decoder = MarkDecoder::default();
        let mut out = Vec::new();
        for &b in bytes {
            decoder.push(b, &mut out);
        }
        out
    }

    #[cfg(unix)]
    #[test]
    fn marked_characters_become_errors_and_a_doubled_ff_one_ff() {
        use Rx::{Byte, Error};
        assert_eq!(
            unmark(b":0\xff\x00\x41\xff\xff1\xff\x00\x00"),
            [Byte(b':'), Byte(b'0'), Error, Byte(0xFF), Byte(b'1'), Error]
        );
        assert_eq!(unmark(b"\xff7"), [Byte(0xFF), Byte(b'7')]);
    }

    #[test]
    fn a_missing_port_says_so() {
        let err = Port::open("/dev/pbtool-no-such-port", PortConfig::MODBUS_DEFAULT).unwrap_err();
        assert!(matches!(err, SerialError::Missing(_)), "{err:?}");
        assert!(err.to_string().contains("does not exist"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn a_pty_takes_every_framing_and_carries_bytes() {
        let (mut master, slave) = serialport::TTYPort::pair().expect("pty pair");
        let name = slave.name().expect("slave has a name");
        let mut port = Port::open(&name, PortConfig::MODBUS_DEFAULT).expect("opens at 8E1");
        for config in [
            PortConfig::HPR,
            PortConfig {
                parity: Parity::Odd,
                stop_bits: StopBits::Two,
                ..PortConfig::MODBUS_DEFAULT
            },
            // A Phoenix messaging port's 7 data bits: the pty takes the setting (and keeps
            // CS8: it carries bytes, not bits).
            PortConfig::new(4800, Parity::Even, StopBits::One).with_data_bits(DataBits::Seven),
            PortConfig::new(1200, Parity::None, StopBits::Two).with_data_bits(DataBits::Seven),
        ] {
            port.set_config(config).expect("framing set");
        }
        master.write_all(b">00090<").unwrap();
        let mut got = Vec::new();
        while got.len() < 7 {
            port.read(Duration::from_secs(5), &mut got).unwrap();
        }
        assert_eq!(got, b">00090<".map(Rx::Byte));
        port.write_all(b":01\r\n").unwrap();
        let mut back = [0u8; 5];
        master.read_exact(&mut back).unwrap();
        assert_eq!(&back, b":01\r\n");
        assert_eq!(describe(port.config()), "1200 7N2");
    }

    #[cfg(unix)]
    #[test]
    fn a_port_whose_other_end_closes_is_gone() {
        let (master, slave) = serialport::TTYPort::pair().expect("pty pair");
        let name = slave.name().expect("slave has a name");
        let mut port = Port::open(&name, PortConfig::MODBUS_DEFAULT).expect("opens");
        drop(master);
        let mut got = Vec::new();
        let err = port.read(Duration::from_secs(5), &mut got).unwrap_err();
        assert!(matches!(err, SerialError::Gone(..)), "{err:?}");
        assert!(err.to_string().contains("went away"), "{err}");
    }
}
