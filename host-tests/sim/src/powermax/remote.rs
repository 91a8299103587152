//! Remote mode: the force registers (mode, current, pressure), their validation and the
//! 0-11-n faults, leaving remote mode, the quick restart and the gas test.

use plasma_protocol::modbus_ascii::ExceptionCode;
use plasma_protocol::time::Instant;

use super::arc::{fault_allows_start, is_setting_fault};
use super::{ArcState, OutOfRange, Powermax, Process};

impl Powermax {
    pub(super) fn exit_remote(&mut self) {
        self.remote = false;
        self.force = Process::default();
        self.force_written = [false; 3];
        if is_setting_fault(self.fault) {
            self.fault = 0;
        }
    }

    /// Quick restart (SYNC 0x308E/0x308F).
    pub(crate) fn quick_restart(&mut self, now: Instant) {
        self.exit_remote();
        self.accrue(now);
        self.enter(ArcState::Idle, now);
        self.gas_test = false;
        if self.fault == 500 && self.cartridge.is_some() {
            self.fault = 0;
        }
        self.deaf_until = now + self.config.quick_restart_time;
        self.assembler.reset();
    }

    /// Which setting fault a bad value at force-register `index` raises.
    pub(super) fn setting_fault(index: usize) -> u16 {
        110 + index as u16
    }

    pub(super) fn valid_setting(&self, index: usize, value: u16) -> bool {
        let l = self.limits();
        match index {
            0 => value >= l.modes.0 && value <= l.modes.1 && value != 0,
            1 => value >= l.current.0 && value <= l.current.1 && value != 0,
            _ => value == 0 || (value >= l.pressure.0 && value <= l.pressure.1),
        }
    }

    pub(super) fn force_value_mut(&mut self, index: usize) -> &mut u16 {
        match index {
            0 => &mut self.force.mode,
            1 => &mut self.force.current,
            _ => &mut self.force.pressure,
        }
    }

    /// Writes to the force registers (index 0 mode, 1 current, 2 pressure) in one request.
    /// `one_request_enters`: SYNC rule (all three in one request) vs legacy (all three written).
    pub(crate) fn write_force(
        &mut self,
        writes: &[(usize, u16)],
        one_request_enters: bool,
    ) -> Result<(), ExceptionCode> {
        if self.config.out_of_range == OutOfRange::Exception
            && writes
                .iter()
                .any(|&(i, v)| v != 0 && !self.valid_setting(i, v))
        {
            return Err(ExceptionCode::IllegalDataValue);
        }
        let previous = self.force;
        for &(i, v) in writes {
            *self.force_value_mut(i) = v;
            self.force_written[i] = true;
        }
        if self.force == Process::default() {
            self.exit_remote();
            return Ok(());
        }
        if !self.remote {
            let covered = |i: usize| writes.iter().any(|&(w, _)| w == i);
            let complete = if one_request_enters {
                (0..3).all(covered)
            } else {
                self.force_written.iter().all(|&w| w)
            };
            if !complete {
                if one_request_enters {
                    let missing = (0..3).find(|&i| !covered(i)).unwrap_or(0);
                    self.raise(Self::setting_fault(missing));
                    self.force = Process::default();
                    self.force_written = [false; 3];
                }
                return Ok(());
            }
            let values = [self.force.mode, self.force.current, self.force.pressure];
            if let Some(bad) = (0..3).find(|&i| !self.valid_setting(i, values[i])) {
                self.raise(Self::setting_fault(bad));
                if one_request_enters {
                    // The request as a whole did not take.
                    self.force = Process::default();
                    self.force_written = [false; 3];
                } else {
                    // The registers keep what was written; the bad one must be written again.
                    *self.force_value_mut(bad) = 0;
                    self.force_written[bad] = false;
                }
                return Ok(());
            }
            self.remote = true;
            if is_setting_fault(self.fault) {
                self.fault = 0;
            }
            return Ok(());
        }
        let mut bad = None;
        for &(i, v) in writes {
            // Zero is accepted on the way back to manual control.
            if v != 0 && !self.valid_setting(i, v) {
                let old = [previous.mode, previous.current, previous.pressure][i];
                *self.force_value_mut(i) = old;
                bad.get_or_insert(i);
            }
        }
        match bad {
            Some(i) => self.raise(Self::setting_fault(i)),
            None if is_setting_fault(self.fault) => self.fault = 0,
            None => {}
        }
        Ok(())
    }

    /// Gas test coil (SYNC 0x3180, old 0x0832).
    pub(crate) fn set_gas_test(&mut self, on: bool) {
        if !on {
            self.gas_test = false;
        } else if self.arc == ArcState::Idle && fault_allows_start(self.fault) {
            self.gas_test = true;
        }
    }
}
