//! The arc sequence: entering phases, their time-outs, errors that stop or block a start, and
//! the counters the sequence accrues (section V state codes, see [`super`]).

use plasma_protocol::time::{Duration, Instant};

use super::{Hpr, Phase};

impl Hpr {
    pub(super) fn cutting(&self) -> bool {
        let code = self.state_code();
        !matches!(self.phase, Phase::TestCutflow | Phase::TestPreflow) && (4..=10).contains(&code)
    }

    pub(super) fn error_blocks_start(&self) -> bool {
        self.error >= 43
    }

    pub(super) fn raise(&mut self, code: u16) {
        if code == 0 {
            return;
        }
        self.error = code;
        self.error_log.rotate_right(1);
        self.error_log[0] = code;
        if code > 79 {
            self.enter(Phase::Shutdown, self.now);
        } else if code >= 43 && self.arc_on() {
            self.enter(Phase::AutoOff, self.now);
        }
    }

    pub(super) fn arc_on(&self) -> bool {
        matches!(
            self.phase,
            Phase::Preflow
                | Phase::PreflowHold
                | Phase::Ignite
                | Phase::Pilot
                | Phase::Transfer
                | Phase::Rampup
                | Phase::Steady
        )
    }

    pub(super) fn enter(&mut self, phase: Phase, at: Instant) {
        self.phase = phase;
        self.phase_since = at;
        if matches!(phase, Phase::Pilot | Phase::Ignite) {
            let t = &self.config.timings;
            let until_transfer = t.transfer_delay.unwrap_or(t.pilot_timeout);
            let length = if until_transfer < t.hf_max {
                until_transfer
            } else {
                t.hf_max
            };
            if phase == Phase::Pilot || self.is_maxpro() {
                self.noise.push((at, length));
            }
        }
    }

    /// When the current phase ends by itself, and what follows.
    pub(super) fn phase_deadline(&self) -> Option<(Instant, Phase)> {
        let t = &self.config.timings;
        let maxpro = self.is_maxpro();
        let at = |d: Duration| self.phase_since + d;
        match self.phase {
            Phase::PowerUp if maxpro => Some((at(t.power_up), Phase::InitialChecks)),
            Phase::PowerUp | Phase::InitialChecks => Some((at(t.power_up), Phase::Purge)),
            Phase::Purge => Some((at(t.purge), Phase::Ready)),
            Phase::Preflow | Phase::PreflowHold if self.hold => {
                Some((at(Duration::from_secs(60)), Phase::AutoOff))
            }
            Phase::Preflow | Phase::PreflowHold => Some((
                at(t.preflow),
                if maxpro { Phase::Ignite } else { Phase::Pilot },
            )),
            Phase::Ignite => Some((at(Duration::from_millis(10)), Phase::Pilot)),
            Phase::Pilot => match t.transfer_delay {
                Some(d) if d < t.pilot_timeout => Some((
                    at(d),
                    if maxpro {
                        Phase::Rampup
                    } else {
                        Phase::Transfer
                    },
                )),
                _ => Some((at(t.pilot_timeout), Phase::AutoOff)),
            },
            Phase::Transfer => Some((at(Duration::from_millis(10)), Phase::Rampup)),
            Phase::Rampup => Some((at(t.rampup), Phase::Steady)),
            Phase::Rampdown if maxpro => Some((at(t.rampdown), Phase::AutoOff)),
            Phase::Rampdown => Some((at(t.rampdown), Phase::FinalRampdown)),
            Phase::FinalRampdown => Some((at(t.rampdown), Phase::AutoOff)),
            Phase::AutoOff if maxpro => Some((at(t.postflow), Phase::EndOfCycle)),
            Phase::AutoOff => Some((at(t.postflow), Phase::Ready)),
            Phase::EndOfCycle => Some((at(Duration::from_millis(100)), Phase::Ready)),
            _ => None,
        }
    }

    pub(super) fn accrue(&mut self, until: Instant) {
        let d = until.saturating_since(self.now);
        self.counters.system_on.add(d);
        if matches!(self.phase, Phase::Transfer | Phase::Rampup | Phase::Steady) {
            self.counters.arc_on.add(d);
        }
        self.now = self.now.max(until);
    }

    pub(super) fn run_timers(&mut self, now: Instant) {
        while let Some((at, next)) = self.phase_deadline().filter(|&(at, _)| at <= now) {
            self.accrue(at);
            let from = self.phase;
            self.enter(next, at);
            match (from, next) {
                (Phase::Preflow | Phase::PreflowHold, Phase::AutoOff) => self.raise(32),
                (Phase::Pilot, Phase::AutoOff) => {
                    self.counters.start_errors += 1;
                    self.raise(21);
                }
                (Phase::Pilot, _) => self.counters.starts += 1,
                _ => {}
            }
        }
        if self.is_maxpro() && self.phase == Phase::Preflow && self.hold {
            self.phase = Phase::PreflowHold;
        }
        self.accrue(now);
    }
}
