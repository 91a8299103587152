//! `GASTEST CHECK`: the unit's gas test run by the bridge. It starts the test, lets the flow
//! settle, reads the pressure while the gas flows, ends the test and answers PASS or FAIL
//! with the measured and permitted pressures (docs/cnc-protocol.md).
//!
//! Like `HISTORY`, the command's reply waits (the lines after it wait in the queue) while
//! the session goes on: each step is one link request, the settling is a deadline in
//! [`Session::poll_at`]. The test is always ended: after the reading, on a failed step, when
//! TORCH_ON or START comes on (the operator wants to cut), and when the link is lost (then
//! the stop is sent as soon as the link is back).

use core::fmt;

use plasma_protocol::cnc::ErrorCode;
use plasma_protocol::cnc::reply::ReplyWriter;
use plasma_protocol::powermax::Psi;
use plasma_protocol::time::{Duration, Instant};

use super::table::GasCheckSteps;
use super::texts::{self, write_failure, write_refusal};
use super::{Context, Pending, ReplyLine, Session, err_line, line};
use crate::link::{CommandFailure, CommandOutput, LinkCommand, LinkEvent, Refusal, Ticket};
use crate::storage::history::Event;

/// The manuals name no settling time for the gas test (the SYNC manual's gas test figure,
/// lines 1832-1846, only says to test with the largest cartridge and while the compressor is
/// loaded): the first reading comes this long after the unit took the start.
pub const SETTLE_TIME: Duration = Duration::from_secs(2);
/// Between two readings while the pressure still moves.
pub const READ_INTERVAL: Duration = Duration::from_millis(500);
/// Two successive readings this close (psi) mean the flow has settled: the band in which the
/// HPR manual expects a steady plasma pressure to stay (002_72b43a5685974c77.txt line 286).
pub const SETTLED_BAND_PSI: u16 = 2;
/// The gas flows at most this long: a pressure still moving by then is a FAIL (`settled=NO`).
pub const MAX_FLOW_TIME: Duration = Duration::from_secs(10);

/// An HPR's or MaxPro200's permitted plasma pressure while it flows, psi (the manual's one
/// error table for both): error 044 "under lower limit (15 psi preflow, 50 psi outflow)" and
/// 045 "over upper limit (110 psi)" (HPR manual, 002_72b43a5685974c77.txt lines 382-383).
pub const HPR_PLASMA_PSI: (u16, u16) = (50, 110);
/// An HPR's permitted shield pressure, psi: errors 053 "under lower limit (2 psi)" and 054
/// "over upper limit (110 psi)" (lines 388-389).
pub const HPR_SHIELD_PSI: (u16, u16) = (2, 110);

/// A `GASTEST CHECK` under way.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct GasCheck {
    steps: GasCheckSteps,
    phase: Phase,
    /// The request whose answer the check waits for.
    ticket: Option<Ticket>,
    /// When the unit took the start.
    flowing_since: Instant,
    /// A Powermax's permitted range, as the unit reports it (0x3004/0x3005, 0x209C/0x209D).
    powermax_range: Option<(Psi, Psi)>,
    /// The last reading and whether it agreed with the one before.
    last: Option<Reading>,
    settled: bool,
    /// What the reply says once the test has ended.
    outcome: Outcome,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Starting,
    Settling { until: Instant },
    Reading,
    Ending,
}

/// One reading while the gas flows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reading {
    Powermax(Psi),
    /// An HPR's plasma and shield cutflow pressures (079), a MaxPro200's measured ones (141),
    /// whole psi.
    Hpr {
        plasma: u16,
        shield: u16,
    },
}

/// What the check ends with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    /// Still running.
    Pending,
    /// A reading was taken: PASS or FAIL.
    Measured,
    Refused(Refusal),
    Failed(CommandFailure),
    TorchOn,
    LinkLost,
}

/// TORCH_ON, START or MOTION on, as the last I/O snapshot shows them.
fn torch_on(ctx: &Context<'_>) -> bool {
    ctx.io()
        .is_some_and(|(inputs, outputs)| inputs.torch_on || inputs.motion || outputs.start)
}

impl Session {
    /// `GASTEST CHECK`: refused while the torch is on or a fault requires action, else the
    /// test starts; `None` while it runs.
    pub(super) fn start_gas_check(
        &mut self,
        ctx: &mut Context<'_>,
        steps: GasCheckSteps,
    ) -> Option<ReplyLine> {
        let status = ctx.link().status();
        if torch_on(ctx) {
            return Some(err_line(ErrorCode::State, texts::GAS_CHECK_TORCH_ON));
        }
        // A low-pressure fault (0-12-1, 0-20-0, HPR 044) is what a check looks into: only a
        // fault that requires action refuses it.
        if let Some(fault) = status.active_fault.filter(|f| f.action_required()) {
            return Some(err_line(
                ErrorCode::State,
                format_args!(
                    "{} {}",
                    texts::GAS_CHECK_FAULTED,
                    super::describe::FaultId(fault)
                ),
            ));
        }
        let powermax_range = match steps.read {
            LinkCommand::ReadGasPressure => match status.limits {
                Some(l) => Some((l.min_pressure, l.max_pressure)),
                None => return Some(err_line(ErrorCode::State, texts::LIMITS_NOT_READ)),
            },
            _ => None,
        };
        let family = status.family;
        let ticket = match ctx.submit(steps.start) {
            Ok(ticket) => ticket,
            Err(refusal) => {
                return Some(line(|l| write_refusal(l, &refusal, family, ctx.now)));
            }
        };
        self.pending = Some(Pending::GasCheck(GasCheck {
            steps,
            phase: Phase::Starting,
            ticket: Some(ticket),
            flowing_since: ctx.now,
            powermax_range,
            last: None,
            settled: false,
            outcome: Outcome::Pending,
        }));
        None
    }

    /// The check under way, if any.
    fn gas_check(&mut self) -> Option<&mut GasCheck> {
        match &mut self.pending {
            Some(Pending::GasCheck(check)) => Some(check),
            _ => None,
        }
    }

    /// A link event while a check runs: the answer to its request, or the link lost.
    pub(super) fn gas_check_link_event(&mut self, ctx: &mut Context<'_>, event: &LinkEvent) {
        // The check is the command being answered: its unit's events only.
        if ctx.unit != self.answering {
            return;
        }
        let Some(check) = self.gas_check() else {
            return;
        };
        let mut check = *check;
        match *event {
            LinkEvent::CommandDone { ticket, result } if check.ticket == Some(ticket) => {
                check.ticket = None;
                self.gas_check_answer(ctx, check, result);
            }
            // Settling has no request in flight to fail: the loss ends the check here.
            LinkEvent::LinkDown { .. } if matches!(check.phase, Phase::Settling { .. }) => {
                check.outcome = Outcome::LinkLost;
                self.gas_stop_owed = Some((self.answering, check.steps.stop));
                self.gas_check_reply(ctx, check);
            }
            _ => {}
        }
    }

    fn gas_check_answer(
        &mut self,
        ctx: &mut Context<'_>,
        mut check: GasCheck,
        result: Result<CommandOutput, CommandFailure>,
    ) {
        match (check.phase, result) {
            (Phase::Ending, Ok(_)) => self.gas_check_reply(ctx, check),
            (Phase::Ending, Err(failure)) => {
                // The test may still run: the stop is sent again once the link answers.
                self.gas_stop_owed = Some((self.answering, check.steps.stop));
                check.outcome = match failure {
                    CommandFailure::LinkDown => Outcome::LinkLost,
                    _ if matches!(check.outcome, Outcome::Measured) => Outcome::Failed(failure),
                    _ => check.outcome,
                };
                self.gas_check_reply(ctx, check);
            }
            (Phase::Starting, Ok(_)) => {
                check.flowing_since = ctx.now;
                check.phase = Phase::Settling {
                    until: ctx.now + SETTLE_TIME,
                };
                self.pending = Some(Pending::GasCheck(check));
            }
            (Phase::Reading, Ok(output)) => {
                let reading = match output {
                    CommandOutput::Pressure(psi) => Some(Reading::Powermax(psi)),
                    CommandOutput::HprPressures { plasma, shield } => {
                        Some(Reading::Hpr { plasma, shield })
                    }
                    _ => None,
                };
                check.settled = match (check.last, reading) {
                    (Some(before), Some(now)) => within_band(before, now),
                    _ => false,
                };
                check.last = reading.or(check.last);
                let flowed = ctx.now.saturating_since(check.flowing_since);
                if check.settled || flowed >= MAX_FLOW_TIME {
                    check.outcome = Outcome::Measured;
                    self.gas_check_end(ctx, check);
                } else {
                    check.phase = Phase::Settling {
                        until: ctx.now + READ_INTERVAL,
                    };
                    self.pending = Some(Pending::GasCheck(check));
                }
            }
            (_, Err(CommandFailure::LinkDown)) => {
                check.outcome = Outcome::LinkLost;
                self.gas_check_end(ctx, check);
            }
            (_, Err(failure)) => {
                check.outcome = Outcome::Failed(failure);
                self.gas_check_end(ctx, check);
            }
            (Phase::Settling { .. }, Ok(_)) => self.pending = Some(Pending::GasCheck(check)),
        }
    }

    /// Time passes: a settled flow is read, a stop owed is sent, the torch on stops the check.
    pub(super) fn gas_check_poll(&mut self, ctx: &mut Context<'_>) {
        let caller = ctx.unit;
        self.gas_check_poll_units(ctx);
        ctx.unit = caller;
    }

    fn gas_check_poll_units(&mut self, ctx: &mut Context<'_>) {
        // A stop owed is sent once its unit's link is up; its answer is nobody's (the check
        // that owed it has replied). Another family on the line now has no such test running.
        if let Some((unit, stop)) = self.gas_stop_owed {
            ctx.unit = unit;
            if ctx.link().status().link_up
                && matches!(ctx.submit(stop), Ok(_) | Err(Refusal::NotSupported { .. }))
            {
                self.gas_stop_owed = None;
            }
        }
        // The check is the command being answered: its unit's link and torch.
        ctx.unit = self.answering;
        let Some(check) = self.gas_check() else {
            return;
        };
        let mut check = *check;
        if torch_on(ctx) && !matches!(check.phase, Phase::Ending) {
            check.outcome = Outcome::TorchOn;
            return self.gas_check_end(ctx, check);
        }
        let Phase::Settling { until } = check.phase else {
            return;
        };
        if ctx.now < until {
            return;
        }
        match ctx.submit(check.steps.read) {
            Ok(ticket) => {
                check.ticket = Some(ticket);
                check.phase = Phase::Reading;
                self.pending = Some(Pending::GasCheck(check));
            }
            Err(refusal) => {
                check.outcome = Outcome::Refused(refusal);
                self.gas_check_end(ctx, check);
            }
        }
    }

    /// When the settling ends.
    pub(super) fn gas_check_poll_at(&self) -> Option<Instant> {
        match self.pending {
            Some(Pending::GasCheck(GasCheck {
                phase: Phase::Settling { until },
                ..
            })) => Some(until),
            _ => None,
        }
    }

    /// End the test: the stop is sent (at once, behind a request still in flight); the reply
    /// follows its answer.
    fn gas_check_end(&mut self, ctx: &mut Context<'_>, mut check: GasCheck) {
        check.phase = Phase::Ending;
        match ctx.submit(check.steps.stop) {
            Ok(ticket) => {
                check.ticket = Some(ticket);
                self.pending = Some(Pending::GasCheck(check));
            }
            Err(refusal) => {
                self.gas_stop_owed = Some((self.answering, check.steps.stop));
                if matches!(check.outcome, Outcome::Pending | Outcome::Measured) {
                    check.outcome = Outcome::Refused(refusal);
                }
                self.gas_check_reply(ctx, check);
            }
        }
    }

    /// The test has ended (or cannot be ended now): the reply, and the history's entry of a
    /// result.
    fn gas_check_reply(&mut self, ctx: &mut Context<'_>, check: GasCheck) {
        self.pending = None;
        let family = ctx.link().status().family;
        let reply = match (check.outcome, check.last) {
            (Outcome::Measured, Some(reading)) => {
                let verdict = Verdict::of(reading, check.powermax_range, check.settled);
                super::history::note(ctx, verdict.entry());
                line(|l| verdict.write(l))
            }
            (Outcome::Refused(refusal), _) => line(|l| write_refusal(l, &refusal, family, ctx.now)),
            (Outcome::Failed(failure), _) => line(|l| write_failure(l, &failure, family)),
            (Outcome::TorchOn, _) => err_line(ErrorCode::State, texts::GAS_CHECK_STOPPED_TORCH),
            (Outcome::LinkLost, _) => err_line(ErrorCode::Link, texts::GAS_CHECK_LINK_LOST),
            (Outcome::Measured | Outcome::Pending, _) => {
                err_line(ErrorCode::Link, texts::GAS_CHECK_NO_READING)
            }
        };
        self.send(reply);
        self.pump(ctx);
    }
}

/// Two readings agree within [`SETTLED_BAND_PSI`].
fn within_band(a: Reading, b: Reading) -> bool {
    let band = SETTLED_BAND_PSI;
    match (a, b) {
        (Reading::Powermax(a), Reading::Powermax(b)) => {
            a.raw().abs_diff(b.raw()) <= band * Psi::STEPS_PER_UNIT
        }
        (
            Reading::Hpr {
                plasma: p1,
                shield: s1,
            },
            Reading::Hpr {
                plasma: p2,
                shield: s2,
            },
        ) => p1.abs_diff(p2) <= band && s1.abs_diff(s2) <= band,
        _ => false,
    }
}

/// One gas's reading against its permitted range.
#[derive(Debug, Clone, Copy)]
struct GasResult {
    measured: Psi,
    min: Psi,
    max: Psi,
}

impl GasResult {
    fn whole(measured: u16, (min, max): (u16, u16)) -> Self {
        let psi = |v: u16| Psi::from_whole(v).unwrap_or(Psi::from_raw(u16::MAX));
        GasResult {
            measured: psi(measured),
            min: psi(min),
            max: psi(max),
        }
    }

    fn passed(&self) -> bool {
        (self.min.raw()..=self.max.raw()).contains(&self.measured.raw())
    }

    /// `keys`: the measured, least and most pressure's keys.
    fn write(&self, w: &mut ReplyWriter<&mut ReplyLine>, keys: [&str; 3]) -> fmt::Result {
        w.field(keys[0], self.measured)?;
        w.field(keys[1], self.min)?;
        w.field(keys[2], self.max)
    }
}

/// A check's result.
#[derive(Debug, Clone, Copy)]
struct Verdict {
    /// A Powermax's one gas, or an HPR's plasma.
    first: GasResult,
    /// An HPR's shield.
    shield: Option<GasResult>,
    settled: bool,
}

impl Verdict {
    fn of(reading: Reading, powermax_range: Option<(Psi, Psi)>, settled: bool) -> Self {
        match reading {
            Reading::Powermax(measured) => {
                let (min, max) = powermax_range.unwrap_or((Psi::from_raw(0), Psi::from_raw(0)));
                Verdict {
                    first: GasResult { measured, min, max },
                    shield: None,
                    settled,
                }
            }
            Reading::Hpr { plasma, shield } => Verdict {
                first: GasResult::whole(plasma, HPR_PLASMA_PSI),
                shield: Some(GasResult::whole(shield, HPR_SHIELD_PSI)),
                settled,
            },
        }
    }

    fn passed(&self) -> bool {
        self.settled && self.first.passed() && self.shield.is_none_or(|s| s.passed())
    }

    /// The history keeps one gas: the one that failed, else the first.
    fn entry(&self) -> Event {
        let kept = match self.shield {
            Some(shield) if self.first.passed() && !shield.passed() => shield,
            _ => self.first,
        };
        Event::GasCheck {
            passed: self.passed(),
            measured: kept.measured,
            permitted_min: kept.min,
            permitted_max: kept.max,
        }
    }

    fn write(&self, l: &mut ReplyLine) -> fmt::Result {
        let mut w = ReplyWriter::ok(l)?;
        w.word("GASTEST")?;
        w.word("CHECK")?;
        w.field("result", if self.passed() { "PASS" } else { "FAIL" })?;
        match self.shield {
            None => self
                .first
                .write(&mut w, ["measured_psi", "min_psi", "max_psi"])?,
            Some(shield) => {
                let plasma = ["plasma_psi", "plasma_min_psi", "plasma_max_psi"];
                self.first.write(&mut w, plasma)?;
                shield.write(&mut w, ["shield_psi", "shield_min_psi", "shield_max_psi"])?;
            }
        }
        if !self.settled {
            w.field("settled", "NO")?;
        }
        w.finish().map(|_| ())
    }
}

#[cfg(test)]
mod tests;
