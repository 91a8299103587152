//! The Powermax driver (SYNC and legacy): polling, slow data, settings and commands over
//! Modbus ASCII. Family specifics live in [`super::sync`] and [`super::legacy`].

use heapless::Deque;
use plasma_protocol::modbus_ascii::{self, Request, Response};
use plasma_protocol::powermax::sync::{Cartridge, FaultLog, Identification, PsCounters};
use plasma_protocol::powermax::{
    Amps, CartridgeName, CartridgeUid, FaultCode, OperatingMode, Pressure, Psi, device_id,
};

use super::Core;
use super::command::{LinkCommand, Refusal};
use super::config::ProtocolChoice;
use super::event::{CommandFailure, CommandOutput, LinkEvent, SettingsFailure, Ticket};
use super::legacy;
use super::modbus::{self, BlockPart, BlockPoller, MbRequest, read_values};
use super::slow::SlowData;
use super::status::{ActiveFault, Family, Limits, Model, PowermaxSettings};
use super::sync::{self, SlowItem};
use super::transaction::TransactionError;
use plasma_protocol::time::{Duration, Instant};

/// Silence after a quick restart (SYNC guide: "wait 2 seconds before you send a new read or
/// write request").
pub const QUICK_RESTART_BLACKOUT: Duration = Duration::from_secs(2);
/// How often the SYNC cartridge UID is read to notice a cartridge change.
pub const UID_CHECK_INTERVAL: Duration = Duration::from_secs(1);
/// Wait before re-applying kept settings again after a re-apply failed.
pub const REAPPLY_BACKOFF: Duration = Duration::from_secs(5);
/// Commands waiting behind the active one.
const QUEUE_CAPACITY: usize = 4;

/// Which register family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    /// 0x3xxx.
    Sync,
    /// 0x2xxx.
    Legacy,
}

/// What a Modbus transaction of this driver is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MbPurpose {
    /// Status poll (whole block or part).
    Poll(BlockPart),
    /// A slow-data span.
    Slow(SlowItem),
    /// The SYNC cartridge block (whole or part).
    CartridgeBlock(BlockPart),
    /// The UID read that notices a cartridge change.
    UidCheck,
    /// Read Device Identification again for a unit detection found only by the legacy
    /// register probe (a SYNC unit whose identification replies were lost is told apart).
    Identify,
    /// The current step of the active command.
    Active,
}

/// Settings the CNC asked for, validated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Desired {
    mode: OperatingMode,
    current: Amps,
    pressure: Pressure,
    /// Set point written first when `pressure` is automatic on a legacy unit.
    legacy_first_pressure: Psi,
}

impl Desired {
    fn as_settings(&self) -> PowermaxSettings {
        PowermaxSettings {
            mode: Some(self.mode),
            current: self.current,
            pressure: self.pressure,
        }
    }

    fn from_settings(settings: &PowermaxSettings, limits: &Limits) -> Option<Self> {
        Some(Desired {
            mode: settings.mode?,
            current: settings.current,
            pressure: settings.pressure,
            legacy_first_pressure: limits.min_pressure,
        })
    }

    /// True when `read` shows these settings (automatic pressure reads back as whatever the
    /// unit chose).
    fn matches(&self, read: &PowermaxSettings) -> bool {
        let pressure_ok = match self.pressure {
            Pressure::Auto => true,
            Pressure::Set(_) => read.pressure == self.pressure,
        };
        read.mode == Some(self.mode) && read.current == self.current && pressure_ok
    }
}

/// Check settings against the permitted limits (nothing is sent when this fails).
pub fn validate_settings(
    limits: Option<&Limits>,
    mode: OperatingMode,
    current: Amps,
    pressure: Pressure,
) -> Result<(), Refusal> {
    let limits = limits.ok_or(Refusal::LimitsUnknown)?;
    if let Some(permitted) = limits.modes
        && !permitted.contains(mode)
    {
        return Err(Refusal::ModeNotPermitted { mode, permitted });
    }
    if current < limits.min_current || current > limits.max_current || !current.is_positive() {
        return Err(Refusal::CurrentOutOfRange {
            requested: current,
            min: limits.min_current,
            max: limits.max_current,
        });
    }
    if let Some(psi) = pressure.psi()
        && (psi < limits.min_pressure || psi > limits.max_pressure)
    {
        return Err(Refusal::PressureOutOfRange {
            requested: psi,
            min: limits.min_pressure,
            max: limits.max_pressure,
        });
    }
    Ok(())
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Job {
    Apply(Desired),
    Exit,
    GasTest(bool),
    QuickRestart,
    Raw(MbRequest),
}

#[derive(Debug, Clone, PartialEq, Eq)]
struct Active {
    /// `None` for a re-apply the link started itself.
    ticket: Option<Ticket>,
    job: Job,
    step: u8,
}

/// Driver state for one detected Powermax.
#[derive(Debug, Clone)]
pub struct PowermaxDriver {
    variant: Variant,
    poll: BlockPoller,
    poll_started: Instant,
    next_poll_at: Instant,
    cartridge: BlockPoller,
    slow: SlowData,
    next_uid_check_at: Instant,
    queue: Deque<(Ticket, Job), QUEUE_CAPACITY>,
    active: Option<Active>,
    reapply_pending: bool,
    reapply_not_before: Instant,
    blackout_until: Option<Instant>,
    /// The unit refused device identification (an exception): it is not asked again.
    identify_refused: bool,
    /// The last transaction started was a poll (the next turn goes to other due work).
    polled_last: bool,
    now: Instant,
}

impl PowermaxDriver {
    /// A driver for a unit just detected; slow data is read first, and kept settings are
    /// re-applied (the link returned).
    pub fn new(variant: Variant, now: Instant, core: &Core) -> Self {
        let plan = match variant {
            Variant::Sync => sync::POLL_PLAN,
            Variant::Legacy => legacy::POLL_PLAN,
        };
        PowermaxDriver {
            variant,
            poll: BlockPoller::new(plan),
            poll_started: now,
            next_poll_at: now,
            cartridge: BlockPoller::new(plasma_protocol::powermax::sync::CARTRIDGE_BLOCK),
            slow: SlowData::new(
                match variant {
                    Variant::Sync => SlowItem::ALL_ITEMS,
                    Variant::Legacy => 0,
                },
                now,
                core.config.slow_data_interval,
            ),
            next_uid_check_at: now + UID_CHECK_INTERVAL,
            queue: Deque::new(),
            active: None,
            reapply_pending: core.status.desired.is_some(),
            reapply_not_before: now,
            blackout_until: None,
            identify_refused: false,
            polled_last: false,
            now,
        }
    }

    /// The family this driver speaks.
    pub fn family(&self) -> Family {
        match self.variant {
            Variant::Sync => Family::PowermaxSync,
            Variant::Legacy => Family::PowermaxLegacy,
        }
    }

    /// True when the active command is a RAW forward (its reply bytes are kept).
    pub fn active_is_raw(&self) -> bool {
        matches!(
            self.active,
            Some(Active {
                job: Job::Raw(_),
                ..
            })
        )
    }

    /// True while the quick-restart silence lasts.
    fn in_blackout(&self, now: Instant) -> bool {
        self.blackout_until.is_some_and(|until| now < until)
    }

    /// Earliest time the driver wants to send something. It mirrors
    /// [`PowermaxDriver::next_request`]: a time not after the last call is only returned when
    /// that call will send something, so a caller sleeping until then never spins.
    pub fn wake_at(&self, core: &Core) -> Option<Instant> {
        if let Some(until) = self.blackout_until.filter(|&u| self.now < u) {
            return Some(until);
        }
        let busy = self.poll.in_cycle()
            || self.active.is_some()
            || !self.queue.is_empty()
            || self.slow.pending() != 0;
        if busy {
            return Some(self.now);
        }
        let mut at = self.next_poll_at.min(self.slow.wake_at());
        // The UID check needs a cartridge read first (slow data, retried on its own).
        if self.variant == Variant::Sync && core.status.cartridge.is_some() {
            at = at.min(self.next_uid_check_at);
        }
        // A re-apply waits for the limits (slow data, retried on its own).
        if self.reapply_pending && core.status.limits.is_some() {
            at = at.min(self.reapply_not_before.max(self.now));
        }
        Some(at)
    }

    /// The next request to send, if any (called only when nothing is in flight).
    /// Returns the purpose, the request and a retry count overriding the configured one.
    pub fn next_request(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        self.now = now;
        if self.in_blackout(now) {
            return None;
        }
        // A poll cycle split into parts finishes first.
        if self.poll.in_cycle() {
            return self
                .poll
                .request()
                .map(|(request, part)| (MbPurpose::Poll(part), request, None));
        }
        if let Some(request) = self.active_request(now, core) {
            return Some(request);
        }
        // Round robin: after a poll, whatever else is due (slow data, the cartridge check)
        // gets one transaction before the next poll, so a short poll interval cannot starve
        // it; a poll waits for at most one such transaction.
        let poll_due = now >= self.next_poll_at;
        if poll_due && !self.polled_last {
            return self.start_poll(now);
        }
        if let Some(request) = self.other_request(now, core) {
            self.polled_last = false;
            return Some(request);
        }
        if poll_due {
            return self.start_poll(now);
        }
        None
    }

    fn start_poll(&mut self, now: Instant) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        self.poll.start();
        self.poll_started = now;
        self.polled_last = true;
        self.poll
            .request()
            .map(|(request, part)| (MbPurpose::Poll(part), request, None))
    }

    /// Slow data, the cartridge check, the slow-data refresh: whatever is due.
    fn other_request(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        self.slow.take_due_retries(now);
        if let Some(request) = self.slow_request() {
            return Some(request);
        }
        if self.variant == Variant::Sync
            && now >= self.next_uid_check_at
            && core.status.cartridge.is_some()
        {
            self.next_uid_check_at = now + UID_CHECK_INTERVAL;
            return Some((MbPurpose::UidCheck, sync::read_uid(), None));
        }
        if self.slow.refresh_due(now, core.config.slow_data_interval) {
            match self.variant {
                Variant::Sync => {
                    self.slow.request(SlowItem::ALL_ITEMS);
                    return self.slow_request();
                }
                Variant::Legacy if self.wants_identify(core) => {
                    return MbRequest::from_request(&device_id::read_product_code())
                        .map(|request| (MbPurpose::Identify, request, None));
                }
                Variant::Legacy => {}
            }
        }
        None
    }

    /// True while the unit runs as legacy only because the legacy register probe found it:
    /// device identification is asked again at each slow-data refresh (auto-detection only).
    fn wants_identify(&self, core: &Core) -> bool {
        self.variant == Variant::Legacy
            && !self.identify_refused
            && core.config.protocol == ProtocolChoice::Auto
            && core.status.model == Some(Model::PowermaxUnidentified)
    }

    fn active_request(
        &mut self,
        now: Instant,
        core: &mut Core,
    ) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        if self.active.is_none() {
            if let Some((ticket, job)) = self.queue.pop_front() {
                self.active = Some(Active {
                    ticket: Some(ticket),
                    job,
                    step: 0,
                });
            } else if self.reapply_pending && now >= self.reapply_not_before {
                self.start_reapply(now, core);
            }
        }
        let active = self.active.as_ref()?;
        let Some(request) = self.step_request(active) else {
            // A step that cannot be encoded (commands are validated before, so not expected):
            // fail the command rather than leave it in the way.
            if let Some(Active {
                ticket: Some(ticket),
                ..
            }) = self.active.take()
            {
                core.emit(LinkEvent::CommandDone {
                    ticket,
                    result: Err(CommandFailure::Transaction(TransactionError::Malformed)),
                });
            }
            return None;
        };
        // The quick restart is never repeated: the unit may already be restarting.
        let retries = matches!(active.job, Job::QuickRestart).then_some(0);
        Some((MbPurpose::Active, request, retries))
    }

    fn start_reapply(&mut self, now: Instant, core: &mut Core) {
        let Some(settings) = core.status.desired else {
            self.reapply_pending = false;
            return;
        };
        // Limits first: they are part of the slow data read at start.
        let Some(limits) = core.status.limits else {
            return;
        };
        self.reapply_pending = false;
        let Some(mode) = settings.mode else {
            return;
        };
        if validate_settings(Some(&limits), mode, settings.current, settings.pressure).is_err() {
            self.reapply_not_before = now + REAPPLY_BACKOFF;
            self.reapply_pending = true;
            core.emit(LinkEvent::SettingsFailed {
                reason: SettingsFailure::OutsideLimits,
            });
            return;
        }
        if let Some(desired) = Desired::from_settings(&settings, &limits) {
            self.active = Some(Active {
                ticket: None,
                job: Job::Apply(desired),
                step: 0,
            });
        }
    }

    fn step_request(&self, active: &Active) -> Option<MbRequest> {
        let step = usize::from(active.step);
        match (&active.job, self.variant) {
            (Job::Apply(d), Variant::Sync) => match step {
                0 => sync::settings_words(d.mode, d.current, d.pressure).map(sync::write_settings),
                1 => Some(sync::read_back()),
                _ => None,
            },
            (Job::Apply(d), Variant::Legacy) => {
                let writes = legacy_writes(d);
                match writes.get(step) {
                    Some(write) => Some(write.clone()),
                    None if step == writes.len() => Some(legacy::read_fault()),
                    None => None,
                }
            }
            (Job::Exit, Variant::Sync) => (step == 0).then(sync::exit_remote),
            (Job::Exit, Variant::Legacy) => legacy::exit_writes().get(step).cloned(),
            (Job::GasTest(on), Variant::Sync) => (step == 0).then(|| sync::gas_test(*on)),
            (Job::GasTest(on), Variant::Legacy) => (step == 0).then(|| legacy::gas_test(*on)),
            (Job::QuickRestart, _) => (step == 0).then(sync::quick_restart).flatten(),
            (Job::Raw(request), _) => (step == 0).then(|| request.clone()),
        }
    }

    fn slow_request(&mut self) -> Option<(MbPurpose, MbRequest, Option<u8>)> {
        let item = SlowItem::ALL
            .into_iter()
            .find(|item| self.slow.pending() & item.bit() != 0)?;
        match item.span() {
            Some(span) => Some((MbPurpose::Slow(item), sync::read(span), None)),
            None => {
                if !self.cartridge.in_cycle() {
                    self.cartridge.start();
                }
                self.cartridge
                    .request()
                    .map(|(request, part)| (MbPurpose::CartridgeBlock(part), request, None))
            }
        }
    }

    /// A valid reply arrived for `purpose`. `raw_len` is the length of the reply frame kept
    /// for a RAW command.
    pub fn on_response(
        &mut self,
        now: Instant,
        purpose: MbPurpose,
        response: &Response<'_>,
        raw_len: usize,
        core: &mut Core,
    ) {
        self.now = now;
        match purpose {
            MbPurpose::Poll(part) => match read_values(response) {
                Some(values) => {
                    if self.poll.on_values(part, values) {
                        self.finish_poll(now, core);
                    }
                }
                None => self.on_failed(now, purpose, TransactionError::Mismatch, core),
            },
            MbPurpose::Slow(item) => {
                let mut error = None;
                if let Some(values) = read_values(response) {
                    match item {
                        SlowItem::Permitted => match sync::limits(values) {
                            Some(limits) => core.status.limits = Some(limits),
                            // Settings depend on them: read them again soon.
                            None => error = Some(TransactionError::Malformed),
                        },
                        SlowItem::Identification => {
                            core.status.identification = Identification::decode(values).ok();
                        }
                        SlowItem::PsCounters => {
                            core.status.ps_counters = PsCounters::decode(values).ok();
                        }
                        SlowItem::FaultLog => core.status.fault_log = FaultLog::decode(values).ok(),
                        SlowItem::CartridgeName => {
                            core.status.cartridge_name = CartridgeName::decode(values).ok();
                        }
                        SlowItem::Cartridge => {}
                    }
                }
                self.slow_done(now, item, error, core);
            }
            MbPurpose::CartridgeBlock(part) => {
                let Some(values) = read_values(response) else {
                    return self.on_failed(now, purpose, TransactionError::Mismatch, core);
                };
                if self.cartridge.on_values(part, values) {
                    self.finish_cartridge(now, core);
                }
            }
            MbPurpose::UidCheck => {
                let uid = read_values(response).and_then(|v| CartridgeUid::decode(v).ok());
                if let (Some(uid), Some(known)) = (uid, core.status.cartridge)
                    && uid != known.uid
                {
                    // The cartridge block read emits CartridgeChanged with the new data.
                    self.slow.request(SlowItem::CARTRIDGE_ITEMS);
                }
            }
            MbPurpose::Active => self.advance_active(now, response, raw_len, core),
            // The link itself acts on the answer (it may change the family).
            MbPurpose::Identify => {}
        }
    }

    /// `purpose` failed for good (retries used, or a final answer such as an exception).
    pub fn on_failed(
        &mut self,
        now: Instant,
        purpose: MbPurpose,
        error: TransactionError,
        core: &mut Core,
    ) {
        self.now = now;
        match purpose {
            MbPurpose::Poll(part) => {
                if modbus::is_illegal_address(error) {
                    if self.poll.on_illegal_address(part) {
                        self.finish_poll(now, core);
                    }
                } else {
                    self.poll.abort();
                    self.next_poll_at = now + core.config.poll_interval;
                }
            }
            MbPurpose::Slow(item) => self.slow_done(now, item, Some(error), core),
            MbPurpose::CartridgeBlock(part) => {
                if modbus::is_illegal_address(error) {
                    if self.cartridge.on_illegal_address(part) {
                        self.finish_cartridge(now, core);
                    }
                } else {
                    self.cartridge.abort();
                    self.slow_done(now, SlowItem::Cartridge, Some(error), core);
                }
            }
            MbPurpose::UidCheck => {}
            MbPurpose::Identify => {
                if matches!(error, TransactionError::Exception(_)) {
                    self.identify_refused = true;
                }
            }
            MbPurpose::Active => {
                if let Some(active) = self.active.take() {
                    let failure = match active.job {
                        Job::Apply(_) => {
                            let reason = SettingsFailure::Transaction(error);
                            core.emit(LinkEvent::SettingsFailed { reason });
                            if active.ticket.is_none() {
                                self.reapply_pending = true;
                                self.reapply_not_before = now + REAPPLY_BACKOFF;
                            }
                            CommandFailure::Settings(reason)
                        }
                        Job::QuickRestart => {
                            // The unit may be restarting without answering: stay quiet anyway.
                            self.start_blackout(now, core);
                            CommandFailure::Transaction(error)
                        }
                        _ => CommandFailure::Transaction(error),
                    };
                    if let Some(ticket) = active.ticket {
                        core.emit(LinkEvent::CommandDone {
                            ticket,
                            result: Err(failure),
                        });
                    }
                }
            }
        }
    }

    fn finish_poll(&mut self, now: Instant, core: &mut Core) {
        self.next_poll_at = (self.poll_started + core.config.poll_interval).max(now);
        match self.variant {
            Variant::Sync => {
                if !self.poll.complete() {
                    return;
                }
                let Some(data) = sync::decode_poll(self.poll.registers()) else {
                    return;
                };
                core.status.settings = Some(data.settings);
                core.status.actual_current = Some(data.actual_current);
                core.status.actual_pressure = Some(data.actual_pressure);
                self.update_fault(now, data.fault, core);
                self.check_revert(now, &data.settings, core);
            }
            Variant::Legacy => {
                let Some(data) = legacy::decode_poll(&self.poll) else {
                    return;
                };
                core.status.limits = Some(data.limits);
                core.status.arc_seconds = Some(data.arc_seconds);
                self.update_fault(now, data.fault, core);
                if let Some(settings) = data.settings {
                    core.status.settings = Some(settings);
                    self.check_revert(now, &settings, core);
                }
            }
        }
    }

    fn update_fault(&mut self, now: Instant, code: FaultCode, core: &mut Core) {
        let new = (!code.is_none()).then_some(ActiveFault::Powermax(code));
        if core.set_active_fault(new) {
            // Cartridge faults come and go with cartridge changes: look at the UID soon.
            self.next_uid_check_at = now;
        }
    }

    /// Settings differ from the kept ones while the bridge holds remote control: the unit
    /// was power-cycled (or someone took over); re-apply.
    fn check_revert(&mut self, now: Instant, read: &PowermaxSettings, core: &mut Core) {
        if self.active.is_some() || self.reapply_pending || !core.status.remote {
            return;
        }
        let Some(desired) = core.status.desired else {
            return;
        };
        let Some(limits) = core.status.limits else {
            return;
        };
        let Some(desired) = Desired::from_settings(&desired, &limits) else {
            return;
        };
        if !desired.matches(read) {
            core.status.remote = false;
            core.emit(LinkEvent::RemoteModeChanged { remote: false });
            self.reapply_pending = true;
            self.reapply_not_before = now;
        }
    }

    fn finish_cartridge(&mut self, now: Instant, core: &mut Core) {
        if self.cartridge.complete()
            && let Ok(cartridge) = Cartridge::decode(self.cartridge.registers())
        {
            if core
                .status
                .cartridge
                .is_some_and(|known| known.uid != cartridge.uid)
            {
                core.emit(LinkEvent::CartridgeChanged {
                    uid: cartridge.uid.0,
                });
            }
            core.status.cartridge = Some(cartridge);
        }
        self.slow_done(now, SlowItem::Cartridge, None, core);
    }

    /// A slow-data item is read (`error` = None) or failed for good (see [`SlowData::finish`]).
    fn slow_done(
        &mut self,
        now: Instant,
        item: SlowItem,
        error: Option<TransactionError>,
        core: &mut Core,
    ) {
        let interval = core.config.slow_data_interval;
        self.slow.finish(now, item.bit(), error, interval, core);
    }

    fn start_blackout(&mut self, now: Instant, core: &mut Core) {
        let until = now + QUICK_RESTART_BLACKOUT;
        self.blackout_until = Some(until);
        core.status.restart_blackout_until = Some(until);
        self.poll.abort();
        self.next_poll_at = until;
        // The restart may come with another cartridge: read its data again afterwards.
        if self.variant == Variant::Sync {
            self.slow.request(SlowItem::ALL_ITEMS);
        }
    }

    fn advance_active(
        &mut self,
        now: Instant,
        response: &Response<'_>,
        raw_len: usize,
        core: &mut Core,
    ) {
        let Some(mut active) = self.active.take() else {
            return;
        };
        let outcome: Option<Result<CommandOutput, CommandFailure>> = match &active.job {
            Job::Apply(desired) => {
                let is_final = self.step_request_after(&active).is_none();
                if !is_final {
                    None
                } else {
                    Some(self.confirm_settings(
                        now,
                        desired,
                        response,
                        active.ticket.is_none(),
                        core,
                    ))
                }
            }
            Job::Exit => {
                if self.step_request_after(&active).is_none() {
                    core.status.desired = None;
                    self.reapply_pending = false;
                    if core.status.remote {
                        core.status.remote = false;
                        core.emit(LinkEvent::RemoteModeChanged { remote: false });
                    }
                    Some(Ok(CommandOutput::Done))
                } else {
                    None
                }
            }
            Job::GasTest(_) => Some(Ok(CommandOutput::Done)),
            Job::QuickRestart => {
                self.start_blackout(now, core);
                Some(Ok(CommandOutput::Done))
            }
            Job::Raw(_) => Some(Ok(CommandOutput::Raw { len: raw_len })),
        };
        match outcome {
            None => {
                active.step = active.step.saturating_add(1);
                self.active = Some(active);
            }
            Some(result) => {
                if let Some(ticket) = active.ticket {
                    core.emit(LinkEvent::CommandDone { ticket, result });
                }
            }
        }
    }

    fn step_request_after(&self, active: &Active) -> Option<MbRequest> {
        let next = Active {
            ticket: active.ticket,
            job: active.job.clone(),
            step: active.step.saturating_add(1),
        };
        self.step_request(&next)
    }

    /// The last step of an Apply answered: compare and report.
    fn confirm_settings(
        &mut self,
        now: Instant,
        desired: &Desired,
        response: &Response<'_>,
        reapplied: bool,
        core: &mut Core,
    ) -> Result<CommandOutput, CommandFailure> {
        let values = read_values(response);
        let verdict: Result<PowermaxSettings, SettingsFailure> = match self.variant {
            Variant::Sync => match values.and_then(sync::decode_settings) {
                Some(read_back) if desired.matches(&read_back) => Ok(read_back),
                Some(read_back) => Err(SettingsFailure::ReadBackDiffers {
                    written: desired.as_settings(),
                    read_back,
                }),
                None => Err(SettingsFailure::Transaction(TransactionError::Malformed)),
            },
            Variant::Legacy => match values.and_then(|v| v.get(0)).map(FaultCode) {
                Some(fault) => {
                    self.update_fault(now, fault, core);
                    if legacy::is_setting_fault(fault) {
                        Err(SettingsFailure::RejectedByUnit { fault })
                    } else {
                        Ok(desired.as_settings())
                    }
                }
                None => Err(SettingsFailure::Transaction(TransactionError::Malformed)),
            },
        };
        match verdict {
            Ok(read_back) => {
                core.status.desired = Some(desired.as_settings());
                core.status.settings = Some(read_back);
                if !core.status.remote {
                    core.status.remote = true;
                    core.emit(LinkEvent::RemoteModeChanged { remote: true });
                }
                core.emit(LinkEvent::SettingsApplied {
                    settings: read_back,
                    reapplied,
                });
                Ok(CommandOutput::Settings(read_back))
            }
            Err(reason) => {
                core.emit(LinkEvent::SettingsFailed { reason });
                if reapplied {
                    self.reapply_pending = true;
                    self.reapply_not_before = now + REAPPLY_BACKOFF;
                }
                Err(CommandFailure::Settings(reason))
            }
        }
    }

    /// Validate and queue a command.
    pub fn submit(
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
        let job = match command {
            LinkCommand::ApplySettings {
                mode,
                current,
                pressure,
            } => {
                let limits = core.status.limits;
                validate_settings(limits.as_ref(), *mode, *current, *pressure)?;
                let limits = limits.ok_or(Refusal::LimitsUnknown)?;
                Job::Apply(Desired {
                    mode: *mode,
                    current: *current,
                    pressure: *pressure,
                    legacy_first_pressure: limits.min_pressure,
                })
            }
            LinkCommand::ExitRemote => Job::Exit,
            LinkCommand::GasTest { on } => Job::GasTest(*on),
            LinkCommand::QuickRestart => {
                if self.variant != Variant::Sync {
                    return Err(Refusal::NotSupported { family });
                }
                let fault = match core.status.active_fault {
                    Some(ActiveFault::Powermax(code)) => Some(code),
                    _ => None,
                };
                if fault != Some(FaultCode(500)) {
                    return Err(Refusal::QuickRestartNeeds050 { active: fault });
                }
                Job::QuickRestart
            }
            LinkCommand::RefreshSlowData => {
                if self.variant == Variant::Legacy {
                    // Everything a legacy unit reports comes with each poll.
                    self.next_poll_at = now;
                    core.emit(LinkEvent::CommandDone {
                        ticket,
                        result: Ok(CommandOutput::Done),
                    });
                    return Ok(());
                }
                return self.slow.request_for(ticket, SlowItem::ALL_ITEMS);
            }
            LinkCommand::Raw(bytes) => {
                Job::Raw(parse_raw(bytes, core.config.node_address, family)?)
            }
            _ => return Err(Refusal::NotSupported { family }),
        };
        self.queue
            .push_back((ticket, job))
            .map_err(|_| Refusal::QueueFull)
    }

    /// The link went down: every pending command fails.
    pub fn abort(&mut self, core: &mut Core) {
        let active = self.active.take().and_then(|active| active.ticket);
        core.fail_commands(active, &mut self.queue);
        self.slow.fail_all(core);
    }
}

fn legacy_writes(desired: &Desired) -> heapless::Vec<MbRequest, 4> {
    let limits = Limits {
        modes: None,
        min_current: desired.current,
        max_current: desired.current,
        min_pressure: desired.legacy_first_pressure,
        max_pressure: desired.legacy_first_pressure,
    };
    legacy::settings_writes(desired.mode, desired.current, desired.pressure, &limits)
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
