//! What went over the wire: every frame each end put on the line, with its timing.
//!
//! The bridge hands over whole frames, and the simulators whole replies, so one entry is one
//! frame as *sent* (what the other end heard may differ when the line corrupts it).

use std::fmt;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::Instant;

/// Which way a frame went.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Bridge to power supply (a request).
    ToUnit,
    /// Power supply to bridge (a reply).
    ToBridge,
}

/// One frame on the wire.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TraceFrame {
    /// Which way.
    pub direction: Direction,
    /// When its first character started on the wire.
    pub start: Instant,
    /// When its last stop bit left the wire.
    pub end: Instant,
    /// The sender's port settings.
    pub port: PortConfig,
    /// The characters as sent.
    pub bytes: Vec<u8>,
}

impl TraceFrame {
    /// True for a request (bridge to unit).
    pub fn is_request(&self) -> bool {
        self.direction == Direction::ToUnit
    }

    /// The frame as text (non-printable characters escaped).
    pub fn text(&self) -> String {
        self.bytes.escape_ascii().to_string()
    }

    /// Modbus ASCII: the function code of the frame (`:AAFF...`), if it is one.
    pub fn modbus_function(&self) -> Option<u8> {
        self.modbus_field(3, 2).map(|v| v as u8)
    }

    /// Modbus ASCII: the first address field after the function (start register / coil).
    pub fn modbus_address(&self) -> Option<u16> {
        self.modbus_field(5, 4)
    }

    /// Modbus ASCII: the quantity field of a read request.
    pub fn modbus_quantity(&self) -> Option<u16> {
        self.modbus_field(9, 4)
    }

    fn modbus_field(&self, at: usize, len: usize) -> Option<u16> {
        if self.bytes.first() != Some(&b':') {
            return None;
        }
        let text = std::str::from_utf8(self.bytes.get(at..at + len)?).ok()?;
        u16::from_str_radix(text, 16).ok()
    }

    /// HPR: the three-digit command id (`>IDD...<`), if it is one.
    pub fn hpr_id(&self) -> Option<u16> {
        if self.bytes.first() != Some(&b'>') {
            return None;
        }
        std::str::from_utf8(self.bytes.get(1..4)?)
            .ok()?
            .parse()
            .ok()
    }

    /// True for a Modbus ASCII frame.
    pub fn is_modbus(&self) -> bool {
        self.bytes.first() == Some(&b':')
    }

    /// True for an HPR frame.
    pub fn is_hpr(&self) -> bool {
        self.bytes.first() == Some(&b'>')
    }
}

impl fmt::Display for TraceFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let arrow = match self.direction {
            Direction::ToUnit => "->",
            Direction::ToBridge => "<-",
        };
        write!(
            f,
            "{:>10.3} ms {arrow} {}",
            self.start.as_micros() as f64 / 1000.0,
            self.text()
        )
    }
}

/// The frames of a run, in the order they were put on the wire.
#[derive(Debug, Clone, Default)]
pub struct WireTrace {
    frames: Vec<TraceFrame>,
}

impl WireTrace {
    pub(crate) fn push(&mut self, frame: TraceFrame) {
        self.frames.push(frame);
    }

    /// The last frame, to extend a frame that arrives in pieces (real-time traffic).
    pub(crate) fn last_mut(&mut self) -> Option<&mut TraceFrame> {
        self.frames.last_mut()
    }

    /// Every frame.
    pub fn frames(&self) -> &[TraceFrame] {
        &self.frames
    }

    /// Frames the bridge sent.
    pub fn requests(&self) -> impl Iterator<Item = &TraceFrame> {
        self.frames.iter().filter(|f| f.is_request())
    }

    /// Frames the unit sent.
    pub fn replies(&self) -> impl Iterator<Item = &TraceFrame> {
        self.frames.iter().filter(|f| !f.is_request())
    }

    /// Requests that started in `[from, to)`.
    pub fn requests_between(
        &self,
        from: Instant,
        to: Instant,
    ) -> impl Iterator<Item = &TraceFrame> {
        self.requests()
            .filter(move |f| f.start >= from && f.start < to)
    }

    /// Requests whose bytes are exactly `bytes`.
    pub fn count_requests(&self, bytes: &[u8]) -> usize {
        self.requests().filter(|f| f.bytes == bytes).count()
    }

    /// Number of frames so far (an index to pass to [`WireTrace::since`]).
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True when nothing was sent yet.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Frames from index `mark` on.
    pub fn since(&self, mark: usize) -> &[TraceFrame] {
        self.frames.get(mark..).unwrap_or(&[])
    }

    /// The last `n` frames, one per line (for failure messages).
    pub fn tail(&self, n: usize) -> String {
        let skip = self.frames.len().saturating_sub(n);
        self.frames
            .iter()
            .skip(skip)
            .map(|f| format!("{f}\n"))
            .collect()
    }
}
