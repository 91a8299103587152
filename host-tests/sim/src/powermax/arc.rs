//! The arc sequence on the discrete Start / Motion signals, faults and whether they allow a
//! start, and the life counters the arc accrues.

use plasma_protocol::time::Instant;

use super::{ArcState, Powermax};

/// Faults that leave the unit able to fire (SYNC guide Table 6: "No" or "No, but recommended"
/// in "Steps required to remove?"; the legacy warnings 0-12-0 and 0-13-0 likewise).
pub(super) fn fault_allows_start(code: u16) -> bool {
    matches!(
        code,
        0 | 110
            | 111
            | 112
            | 120
            | 121
            | 122
            | 123
            | 130
            | 141
            | 200
            | 321
            | 502
            | 503
            | 980
            | 981
            | 982
    )
}

pub(super) fn is_setting_fault(code: u16) -> bool {
    matches!(code, 110..=112)
}

impl Powermax {
    pub(super) fn raise(&mut self, code: u16) {
        if code == 0 {
            return;
        }
        if self.fault == 0 || is_setting_fault(self.fault) || !is_setting_fault(code) {
            self.fault = code;
        }
        if let Some(c) = &mut self.cartridge {
            c.log_fault(code);
        }
        if !fault_allows_start(code) && matches!(self.arc, ArcState::Pilot | ArcState::Transferred)
        {
            self.enter(ArcState::Postflow, self.now);
        }
    }

    pub(super) fn enter(&mut self, state: ArcState, at: Instant) {
        self.arc = state;
        self.arc_since = at;
    }

    pub(super) fn can_fire(&self) -> bool {
        self.powered
            && self.now >= self.deaf_until
            && fault_allows_start(self.fault)
            && !self.gas_test
            && matches!(self.arc, ArcState::Idle | ArcState::Postflow)
            && (!self.is_sync() || self.cartridge.is_some())
    }

    pub(super) fn accrue(&mut self, until: Instant) {
        let d = until.saturating_since(self.now);
        match self.arc {
            ArcState::Pilot => {
                self.counters.pilot.add(d);
                if let Some(c) = &mut self.cartridge {
                    c.pilot.add(d);
                }
            }
            ArcState::Transferred => {
                self.counters.transfer.add(d);
                if let Some(c) = &mut self.cartridge {
                    c.transfer.add(d);
                }
            }
            _ => {}
        }
        self.now = self.now.max(until);
    }

    pub(super) fn arc_deadline(&self) -> Option<Instant> {
        let t = &self.config.timings;
        match self.arc {
            ArcState::Pilot => {
                let timeout = self.arc_since + t.pilot_timeout;
                Some(match t.transfer_delay {
                    Some(d) if d < t.pilot_timeout => self.arc_since + d,
                    _ => timeout,
                })
            }
            ArcState::Postflow => Some(self.arc_since + t.postflow),
            _ => None,
        }
    }

    pub(super) fn run_timers(&mut self, now: Instant) {
        while let Some(at) = self.arc_deadline().filter(|&at| at <= now) {
            self.accrue(at);
            match self.arc {
                ArcState::Pilot => {
                    let transfers = self
                        .config
                        .timings
                        .transfer_delay
                        .is_some_and(|d| d < self.config.timings.pilot_timeout);
                    if transfers {
                        self.counters.transfers = self.counters.transfers.wrapping_add(1);
                        if let Some(c) = &mut self.cartridge {
                            c.transfers = c.transfers.wrapping_add(1);
                        }
                        self.enter(ArcState::Transferred, at);
                    } else {
                        self.enter(ArcState::Postflow, at);
                    }
                }
                _ => self.enter(ArcState::Idle, at),
            }
        }
        self.accrue(now);
    }

    pub(super) fn fire(&mut self, now: Instant) {
        self.counters.starts = self.counters.starts.wrapping_add(1);
        if let Some(c) = &mut self.cartridge {
            c.starts = c.starts.wrapping_add(1);
        }
        self.enter(ArcState::Pilot, now);
    }
}
