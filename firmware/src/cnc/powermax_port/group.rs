//! The write combiner: single-register writes of mode, current and pressure become ONE
//! settings change.
//!
//! LinuxCNC's pmx485 writes 0x2093, 0x2094 and 0x2096 one request at a time, each after the
//! echo of the one before, and then (with no pause) reads: the limits after connecting, the
//! next register of its cycle otherwise; when it disconnects it writes three zeros and closes
//! the port. So a group of writes is complete at the first request that is not a write to a
//! force register, or [`SETTLE`] after the last write when nothing follows. Until then
//! nothing goes to the unit, so the unit never sees a partial setting (mode of one process,
//! current of another).

use plasma_protocol::powermax::{legacy, sync};
use plasma_protocol::time::{Duration, Instant};

/// A group of writes with nothing after it is complete this long after its last write:
/// pmx485's own reply time-out, so a master that writes the three registers back to back
/// (each waiting for its echo) is never cut in the middle.
pub const SETTLE: Duration = Duration::from_millis(100);

/// The three force registers as written: mode (legacy numbering), amps x 64, psi x 128.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Forced {
    /// 0x2093 / 0x3080.
    pub mode: u16,
    /// 0x2094 / 0x3081.
    pub current: u16,
    /// 0x2096 / 0x3082.
    pub pressure: u16,
}

impl Forced {
    /// All three zero: back to local control.
    pub const fn is_local(&self) -> bool {
        self.mode == 0 && self.current == 0 && self.pressure == 0
    }

    /// Store `value` at force register `address`; false when `address` is not one.
    pub fn set(&mut self, address: u16, value: u16) -> bool {
        let slot = match address {
            legacy::MODE_FORCE | sync::REMOTE_MODE => &mut self.mode,
            legacy::CURRENT_FORCE | sync::REMOTE_CURRENT => &mut self.current,
            legacy::PRESSURE_FORCE | sync::REMOTE_PRESSURE => &mut self.pressure,
            _ => return false,
        };
        *slot = value;
        true
    }
}

/// True for the force registers of both maps.
pub fn is_force_register(address: u16) -> bool {
    Forced::default().set(address, 0)
}

/// The combiner. Holds the force registers as written and whether a group is open.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Combiner {
    forced: Option<Forced>,
    last_write: Option<Instant>,
}

impl Combiner {
    /// The force registers as the CNC wrote them, if it ever did.
    pub fn forced(&self) -> Option<Forced> {
        self.forced
    }

    /// A write to force register `address` (checked by the caller): opens a group or adds to
    /// the open one; unwritten registers keep their values, starting from `base`.
    pub fn write(&mut self, now: Instant, base: Forced, address: u16, value: u16) {
        let forced = self.forced.get_or_insert(base);
        forced.set(address, value);
        self.last_write = Some(now);
    }

    /// When the open group completes by itself.
    pub fn due_at(&self) -> Option<Instant> {
        self.last_write.map(|at| at + SETTLE)
    }

    /// Close the open group: the settings change to make, once.
    pub fn close(&mut self) -> Option<Forced> {
        self.last_write.take()?;
        self.forced
    }

    /// Settings came from elsewhere (a text command): the force registers no longer hold
    /// what the master wrote, unless a group is open.
    pub fn forget_written(&mut self) {
        if self.last_write.is_none() {
            self.forced = None;
        }
    }

    /// Forget the open group (the link went down: the change is not made).
    pub fn abandon(&mut self) {
        self.last_write = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T0: Instant = Instant::ZERO;

    #[test]
    fn three_writes_close_as_one_change() {
        let mut c = Combiner::default();
        assert_eq!(c.close(), None);
        c.write(T0, Forced::default(), 0x2093, 1);
        c.write(T0, Forced::default(), 0x2094, 2880);
        c.write(T0, Forced::default(), 0x2096, 0);
        assert_eq!(c.due_at(), Some(T0 + SETTLE));
        let change = c.close().unwrap();
        assert_eq!((change.mode, change.current, change.pressure), (1, 2880, 0));
        assert_eq!(c.close(), None, "once");
        assert_eq!(
            c.forced(),
            Some(change),
            "the registers keep what was written"
        );
    }

    #[test]
    fn a_single_write_keeps_the_other_two() {
        let mut c = Combiner::default();
        let base = Forced {
            mode: 1,
            current: 2880,
            pressure: 0,
        };
        c.write(T0, base, 0x3081, 1920);
        assert_eq!(
            c.close(),
            Some(Forced {
                current: 1920,
                ..base
            })
        );
    }

    #[test]
    fn only_force_registers_are_force_registers() {
        for a in [0x2093, 0x2094, 0x2096, 0x3080, 0x3081, 0x3082] {
            assert!(is_force_register(a), "{a:#x}");
        }
        for a in [0x2095, 0x2098, 0x3083, 0x308E] {
            assert!(!is_force_register(a), "{a:#x}");
        }
    }
}
