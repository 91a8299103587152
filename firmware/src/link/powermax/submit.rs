//! A command checked before it is queued: settings against the permitted limits, the quick
//! restart against the active fault, a RAW frame against the allow-list.

use plasma_protocol::modbus_ascii::{self, Request};
use plasma_protocol::powermax::FaultCode;
use plasma_protocol::time::Instant;

use super::process::{DesiredProcess, validate_process};
use super::{Job, PowermaxDriver, Variant};
use crate::link::command::{LinkCommand, Refusal};
use crate::link::core::Core;
use crate::link::event::{CommandOutput, LinkEvent, Ticket};
use crate::link::powermax::modbus::{self, MbRequest};
use crate::link::powermax::sync::SlowItem;
use crate::link::status::{ActiveFault, Family};

impl PowermaxDriver {
    /// Validate and queue a command.
    pub(crate) fn submit(
        &mut self,
        now: Instant,
        ticket: Ticket,
        command: &LinkCommand<'_>,
        core: &mut Core,
    ) -> Result<(), Refusal> {
        self.now = now;
        if let Some(until) = self.blackout_until.filter(|&u| now < u) {
            return Err(Refusal::Blackout { until });
        }
        let family = self.family();
        if !command.runs_on(family) {
            return Err(Refusal::NotSupported { family });
        }
        let job = match command {
            LinkCommand::ApplyProcess {
                mode,
                current,
                pressure,
            } => {
                let limits = core.status.limits;
                validate_process(limits.as_ref(), *mode, *current, *pressure)?;
                let limits = limits.ok_or(Refusal::LimitsUnknown)?;
                Job::Apply(DesiredProcess {
                    mode: *mode,
                    current: *current,
                    pressure: *pressure,
                    legacy_first_pressure: limits.min_pressure,
                })
            }
            LinkCommand::ExitRemote => Job::Exit,
            LinkCommand::GasTest { on } => Job::GasTest(*on),
            LinkCommand::ReadGasPressure => Job::ReadPressure,
            LinkCommand::QuickRestart => self.quick_restart_job(core)?,
            LinkCommand::RefreshSlowData => return self.refresh_slow_data(now, ticket, core),
            LinkCommand::Raw(bytes) => {
                Job::Raw(parse_raw(bytes, core.config.node_address, family)?)
            }
            // `runs_on` lets no other command through to a Powermax.
            _ => return Err(Refusal::NotSupported { family }),
        };
        self.queue
            .push_back((ticket, job))
            .map_err(|_| Refusal::QueueFull)
    }

    /// A quick restart (`runs_on` lets it through on SYNC only), allowed with fault
    /// 0-50-0 active.
    fn quick_restart_job(&self, core: &Core) -> Result<Job, Refusal> {
        let fault = match core.status.active_fault {
            Some(ActiveFault::Powermax(code)) => Some(code),
            _ => None,
        };
        if fault != Some(FaultCode(500)) {
            return Err(Refusal::QuickRestartNeeds050 { active: fault });
        }
        Ok(Job::QuickRestart)
    }

    /// Read the slow data again; a legacy unit reports everything with each poll, so the
    /// next poll comes at once.
    fn refresh_slow_data(
        &mut self,
        now: Instant,
        ticket: Ticket,
        core: &mut Core,
    ) -> Result<(), Refusal> {
        if self.variant == Variant::Legacy {
            self.next_poll_at = now;
            core.emit(LinkEvent::CommandDone {
                ticket,
                result: Ok(CommandOutput::Done),
            });
            return Ok(());
        }
        self.slow.request_for(ticket, SlowItem::ALL_ITEMS)
    }
}

/// Parse and check a RAW Modbus frame: valid framing and LRC, this link's node address, a
/// read or an allowed write.
fn parse_raw(bytes: &[u8], node_address: u8, family: Family) -> Result<MbRequest, Refusal> {
    let mut pdu = [0u8; modbus_ascii::MAX_FRAME_BYTES];
    let frame = modbus_ascii::decode(bytes, &mut pdu).map_err(Refusal::RawMalformed)?;
    if frame.address != node_address {
        return Err(Refusal::RawWrongAddress {
            expected: node_address,
            found: frame.address,
        });
    }
    let request = Request::parse(frame.pdu).map_err(|e| match e {
        plasma_protocol::Error::Unsupported => Refusal::RawFunctionNotAllowed {
            function: frame.pdu.first().copied().unwrap_or(0),
        },
        other => Refusal::RawMalformed(other),
    })?;
    modbus::check_raw_request(family, &request)?;
    MbRequest::from_request(&request).ok_or(Refusal::RawMalformed(plasma_protocol::Error::Overlong))
}
