//! The CNC port answering as a Powermax: Modbus ASCII requests (`:` ... CR LF) on the same
//! port as the text protocol, answered at once from what the bridge holds. Sans-IO.
//!
//! - Node: `cnc_address` (CONFIG, default 1) for the first unit; with several units on the
//!   power-supply line (`CONFIG units`), unit N answers at `cnc_address + N - 1`, each with
//!   its own group of writes and refused setting. Requests for another node are ignored; a
//!   broadcast (node 0) is carried out for every unit and never answered.
//! - Functions 03 and 04 read the [register map](map); 06 and 0x10 write the force registers
//!   (0x2093/0x2094/0x2096, and 0x3080-0x3082 behind a SYNC unit); 0x10 to 0x308E/0x308F
//!   (SYNC) is the quick restart that stops 0-50-0, handed to the link; 01 reads and 05
//!   writes the [coils](coils) (Start, Motion, torch lead; the gas test). 0x2B/0x0E gives the
//!   Table 2 product code of the Powermax behind the bridge (SYNC or legacy), which is how a
//!   SYNC-aware CNC picks its register set, and is exception 01 for a unit without one (an
//!   HPR, a Powermax that did not identify itself). Exceptions: 01 for another function, 02
//!   for an address outside the map, 03 for a quantity or value no setting can have, 04 / 06
//!   for a gas test or restart the link cannot take (06 while it is busy).
//! - Writes are echoed at once and gathered by the [combiner](group): a complete group
//!   becomes one link command (SYNC one 0x10 write, legacy the force registers, HPR/MaxPro200
//!   the current), never a partial one. A value the unit refuses reads as its 0-11-x fault in
//!   0x2098 / 0x301A until a later change is accepted; zeros in all three return the unit to
//!   local control.
//! - The unit's link lost (or not up yet): no reply at all, as a Powermax with its cable cut,
//!   so a Powermax CNC reports a communication error instead of stale values.

mod coils;
mod group;
mod map;
#[cfg(test)]
mod tests;

#[cfg(test)]
use group::SETTLE;
pub use group::{Combiner, Forced};

use plasma_protocol::Error as WireError;
use plasma_protocol::modbus_ascii::pdu::{DeviceIdentification, MAX_READ_REGISTERS};
use plasma_protocol::modbus_ascii::{
    DeviceIdCode, ExceptionCode, FunctionCode, MAX_FRAME_CHARS, Registers, Request, Response,
    encode_response,
};
use plasma_protocol::powermax::device_id::{
    AddressingSystem, CONFORMITY_LEVEL, PRODUCT_CODE_OBJECT,
};
use plasma_protocol::powermax::{FaultCode, OperatingMode, legacy, sync};
use plasma_protocol::time::Instant;

use super::Context;
use super::describe::cnc_mode;
use crate::link::MAX_UNITS;
use crate::link::{
    CommandOutput, Family, LinkCommand, LinkEvent, Model, ProcessFailure, Refusal, Ticket,
};
use crate::settings::Process;
use crate::storage::history::ChangedBy;
use coils::Coils;
use group::is_force_register;
use map::{View, served};

/// 0-11-0, 0-11-1, 0-11-2: the mode, current or pressure the unit does not permit.
const MODE_REFUSED: FaultCode = FaultCode(110);
const CURRENT_REFUSED: FaultCode = FaultCode(111);
const PRESSURE_REFUSED: FaultCode = FaultCode(112);

/// The Powermax side of the CNC port. See the module docs.
#[derive(Debug)]
pub struct PowermaxPort {
    decoder: plasma_protocol::modbus_ascii::Decoder,
    /// One node per unit on the power-supply line: unit N answers at `cnc_address + N - 1`.
    nodes: [Node; MAX_UNITS],
    reply: [u8; MAX_FRAME_CHARS],
    reply_len: usize,
}

/// What the port keeps for one unit's node.
#[derive(Debug, Default)]
struct Node {
    combiner: Combiner,
    refused: Option<FaultCode>,
    /// The settings change in progress on the link, and what the settings keep once it is done.
    applying: Option<(Ticket, Keep)>,
}

impl Default for PowermaxPort {
    fn default() -> Self {
        PowermaxPort {
            decoder: plasma_protocol::modbus_ascii::Decoder::new(),
            nodes: Default::default(),
            reply: [0; MAX_FRAME_CHARS],
            reply_len: 0,
        }
    }
}

/// What a settings change done through the registers leaves in [`Settings::process`]
/// (`CONFIG SAVE` stores it), as a `SET` or `REMOTE OFF` command would.
///
/// [`Settings::process`]: crate::settings::Settings::process
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Keep {
    Process(Process),
    Forget,
    Unchanged,
}

/// What a byte did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Nothing to send yet.
    Pending,
    /// A reply frame is ready ([`PowermaxPort::reply`]).
    Reply,
    /// A settings change was refused before it was sent: the fault it reads as. The reply
    /// ([`PowermaxPort::reply`]) is empty when the request was a broadcast.
    Refused(FaultCode),
}

impl PowermaxPort {
    /// True between a `:` and the end of its frame.
    pub fn in_frame(&self) -> bool {
        self.decoder.in_frame()
    }

    /// Forget a frame that stopped arriving.
    pub fn abandon_frame(&mut self) {
        self.decoder.reset();
    }

    /// The last reply frame.
    pub fn reply(&self) -> &[u8] {
        self.reply.get(..self.reply_len).unwrap_or_default()
    }

    /// The fault a refused setting of unit `unit` reads as, until a change is accepted.
    pub fn refused(&self, unit: usize) -> Option<FaultCode> {
        self.node_ref(unit).refused
    }

    /// Unit `unit`'s node (the last one for an index out of range: units are checked
    /// against the count before they get here).
    #[allow(clippy::indexing_slicing)] // clamped to the array on the line above
    fn node(&mut self, unit: usize) -> &mut Node {
        let index = unit.min(MAX_UNITS - 1);
        &mut self.nodes[index]
    }

    #[allow(clippy::indexing_slicing)] // clamped to the array on the line above
    fn node_ref(&self, unit: usize) -> &Node {
        let index = unit.min(MAX_UNITS - 1);
        &self.nodes[index]
    }

    /// One byte from the CNC (the first of a frame is `:`).
    pub fn push(&mut self, ctx: &mut Context<'_>, byte: u8) -> Step {
        // The request is copied out of the decoder, which `request` cannot borrow with `self`.
        let mut pdu = [0u8; plasma_protocol::modbus_ascii::MAX_PDU_LEN];
        let (address, len) = match self.decoder.push(byte) {
            Some(Ok(frame)) => {
                for (slot, &b) in pdu.iter_mut().zip(frame.pdu) {
                    *slot = b;
                }
                (frame.address, frame.pdu.len())
            }
            // A broken frame (bad LRC, not hex): a Powermax does not answer it.
            _ => return Step::Pending,
        };
        self.request(ctx, address, pdu.get(..len).unwrap_or_default())
    }

    /// When [`PowermaxPort::poll`] has a group to complete.
    pub fn poll_at(&self) -> Option<Instant> {
        self.nodes.iter().filter_map(|n| n.combiner.due_at()).min()
    }

    /// Let time pass: a group of writes with nothing after it completes after
    /// [`SETTLE`](group::SETTLE). The fault of a change refused before it was sent, with the
    /// unit it is for (`ctx.unit` is left at that unit).
    pub fn poll(&mut self, ctx: &mut Context<'_>) -> Option<FaultCode> {
        for unit in 0..ctx.units.count() {
            if self
                .node(unit)
                .combiner
                .due_at()
                .is_some_and(|at| ctx.now >= at)
            {
                ctx.unit = unit;
                if let Some(fault) = self.complete_group(ctx) {
                    return Some(fault);
                }
            }
        }
        None
    }

    /// A link event: the outcome of the change it applies, the link lost.
    pub fn on_link_event(&mut self, ctx: &mut Context<'_>, event: &LinkEvent) {
        let node = self.node(ctx.unit);
        match event {
            LinkEvent::CommandDone { ticket, result } => {
                let Some((mine, process)) = node.applying else {
                    return;
                };
                if mine != *ticket {
                    return;
                }
                node.applying = None;
                // The settings persist the first unit's process only.
                let first = ctx.unit == 0;
                match (result, process) {
                    (Ok(CommandOutput::Process(_)), Keep::Process(p)) if first => {
                        super::history::keep_process(ctx, p, ChangedBy::ModbusCnc);
                    }
                    (Ok(_), Keep::Forget) if first => ctx.settings.process = None,
                    (Ok(_), _) => {}
                    (
                        Err(crate::link::CommandFailure::Process(ProcessFailure::RejectedByUnit {
                            fault,
                        })),
                        _,
                    ) => node.refused = Some(*fault),
                    (Err(crate::link::CommandFailure::NotAccepted), _) => {
                        node.refused = Some(CURRENT_REFUSED);
                    }
                    (Err(_), _) => {}
                }
            }
            LinkEvent::LinkDown { .. } => {
                node.combiner.abandon();
                node.applying = None;
            }
            // Settings applied by a text command (or re-applied): the force registers read
            // them from now on, not what the Modbus master wrote before.
            LinkEvent::ProcessApplied { .. } if node.applying.is_none() => {
                node.combiner.forget_written();
            }
            _ => {}
        }
    }

    // --- requests -----------------------------------------------------------------------

    /// A request for `address`: unit N's node is `cnc_address + N - 1`; a broadcast (node 0)
    /// is every unit's (and answered by none). `ctx.unit` is left at the unit it was for (a
    /// broadcast: the first whose change was refused).
    fn request(&mut self, ctx: &mut Context<'_>, address: u8, pdu: &[u8]) -> Step {
        if address == 0 {
            let mut refused = None;
            for unit in 0..ctx.units.count() {
                ctx.unit = unit;
                if let Step::Refused(fault) = self.serve(ctx, address, pdu) {
                    refused = refused.or(Some((unit, fault)));
                }
            }
            return match refused {
                Some((unit, fault)) => {
                    ctx.unit = unit;
                    Step::Refused(fault)
                }
                None => Step::Pending,
            };
        }
        let unit = address
            .checked_sub(ctx.settings.cnc.address)
            .map(usize::from)
            .filter(|&unit| unit < ctx.units.count());
        let Some(unit) = unit else {
            return Step::Pending;
        };
        ctx.unit = unit;
        self.serve(ctx, address, pdu)
    }

    /// A request for `ctx.unit`'s node `address` (0: a broadcast).
    fn serve(&mut self, ctx: &mut Context<'_>, address: u8, pdu: &[u8]) -> Step {
        let broadcast = address == 0;
        let status = ctx.link().status();
        // Link lost or not up yet: silence, as a unit with its cable cut.
        let Some(family) = status.family.filter(|_| status.link_up) else {
            return Step::Pending;
        };
        let request = match Request::parse(pdu) {
            Ok(request) => request,
            Err(error) => {
                let function = pdu.first().copied().unwrap_or(0);
                let code = match error {
                    WireError::Unsupported => ExceptionCode::IllegalFunction,
                    _ => ExceptionCode::IllegalDataValue,
                };
                return self.answer(broadcast, address, &exception(function, code));
            }
        };
        let mut refused = None;
        let function = request.function() as u8;
        let mut words = [0u16; MAX_READ_REGISTERS as usize];
        let mut bits = [0u8; coils::MAX_COIL_BYTES];
        let mut ident = [0u8; 64];
        let response = match request {
            Request::ReadHoldingRegisters { start, quantity }
            | Request::ReadInputRegisters { start, quantity } => {
                // A read ends a group of writes: pmx485 reads right after its last write.
                refused = self.complete_group(ctx);
                match self.read(ctx, family, start, quantity, &mut words) {
                    Err(code) => exception(function, code),
                    Ok(values) if function == FunctionCode::ReadHoldingRegisters as u8 => {
                        Response::ReadHoldingRegisters { values }
                    }
                    Ok(values) => Response::ReadInputRegisters { values },
                }
            }
            // The quick restart takes both registers in one 0x10 request.
            Request::WriteSingleRegister { address: reg, .. }
                if is_quick_restart(reg, 1, family) =>
            {
                exception(function, ExceptionCode::IllegalDataValue)
            }
            Request::WriteSingleRegister {
                address: reg,
                value,
            } => match self.write(ctx, family, reg, &[value]) {
                Err(code) => exception(function, code),
                Ok(()) => Response::WriteSingleRegister {
                    address: reg,
                    value,
                },
            },
            Request::WriteMultipleRegisters { start, values } => {
                let mut buf = [0u16; 3];
                let n = values.len();
                for (slot, v) in buf.iter_mut().zip(values.iter()) {
                    *slot = v;
                }
                if is_quick_restart(start, n, family) {
                    refused = self.complete_group(ctx);
                    let result = match buf.get(..n) {
                        Some(values) => quick_restart(ctx, start, values),
                        None => Err(ExceptionCode::IllegalDataValue),
                    };
                    let response = match result {
                        Ok(()) => Response::WriteMultipleRegisters {
                            start,
                            quantity: n as u16,
                        },
                        Err(code) => exception(function, code),
                    };
                    let step = self.answer(broadcast, address, &response);
                    return refused.map_or(step, Step::Refused);
                }
                // More than the three force registers: an address outside the map.
                match buf.get(..n).map(|v| self.write(ctx, family, start, v)) {
                    None => exception(function, ExceptionCode::IllegalDataAddress),
                    Some(Err(code)) => exception(function, code),
                    Some(Ok(())) => {
                        // One 0x10 request is a whole group.
                        refused = self.complete_group(ctx);
                        Response::WriteMultipleRegisters {
                            start,
                            quantity: n as u16,
                        }
                    }
                }
            }
            Request::ReadDeviceIdentification { code, object_id } => {
                match identification(ctx, code, object_id, &mut ident) {
                    Ok(len) => {
                        let pdu = ident.get(..len).unwrap_or_default();
                        return self.answer_pdu(broadcast, address, pdu, refused);
                    }
                    Err(code) => exception(function, code),
                }
            }
            Request::ReadCoils { start, quantity } => {
                refused = self.complete_group(ctx);
                let coils = Coils {
                    status: ctx.link().status(),
                    io: ctx.io(),
                };
                match coils.read_many(start, quantity, &mut bits) {
                    Ok(len) => Response::ReadCoils {
                        bits: bits.get(..len).unwrap_or_default(),
                    },
                    Err(code) => exception(function, code),
                }
            }
            Request::WriteSingleCoil { address: coil, on } => {
                refused = self.complete_group(ctx);
                let coils = Coils {
                    status: ctx.link().status(),
                    io: ctx.io(),
                };
                if !coils.is_gas_test(coil) {
                    exception(function, ExceptionCode::IllegalDataAddress)
                } else {
                    match ctx.submit(LinkCommand::GasTest { on }) {
                        Ok(_) => Response::WriteSingleCoil { address: coil, on },
                        Err(refusal) => exception(function, refusal_exception(&refusal)),
                    }
                }
            }
        };
        let step = self.answer(broadcast, address, &response);
        match refused {
            Some(fault) => Step::Refused(fault),
            None => step,
        }
    }

    fn read<'w>(
        &self,
        ctx: &Context<'_>,
        family: Family,
        start: u16,
        quantity: u16,
        words: &'w mut [u16; MAX_READ_REGISTERS as usize],
    ) -> Result<Registers<'w>, ExceptionCode> {
        let n = usize::from(quantity);
        if n == 0 || n > words.len() {
            return Err(ExceptionCode::IllegalDataValue);
        }
        let view = View {
            status: ctx.link().status(),
            forced: self.forced(ctx),
            refused: self.node_ref(ctx.unit).refused,
        };
        for (i, slot) in words.iter_mut().take(n).enumerate() {
            let address = start
                .checked_add(i as u16)
                .filter(|&a| served(a, family))
                .ok_or(ExceptionCode::IllegalDataAddress)?;
            *slot = view.read(address);
        }
        Ok(Registers::Words(words.get(..n).unwrap_or_default()))
    }

    /// Writes to force registers: checked, then added to the open group.
    fn write(
        &mut self,
        ctx: &Context<'_>,
        family: Family,
        start: u16,
        values: &[u16],
    ) -> Result<(), ExceptionCode> {
        for (i, &value) in values.iter().enumerate() {
            let address = start.wrapping_add(i as u16);
            if !is_force_register(address) || !served(address, family) {
                return Err(ExceptionCode::IllegalDataAddress);
            }
            // No mode has another number: a value no setting can have.
            if matches!(address, legacy::MODE_FORCE | sync::REMOTE_MODE) && value > 3 {
                return Err(ExceptionCode::IllegalDataValue);
            }
        }
        let base = self.forced(ctx);
        for (i, &value) in values.iter().enumerate() {
            self.node(ctx.unit)
                .combiner
                .write(ctx.now, base, start.wrapping_add(i as u16), value);
        }
        Ok(())
    }

    /// The force registers: as written, else the process the link keeps or the unit's.
    fn forced(&self, ctx: &Context<'_>) -> Forced {
        self.node_ref(ctx.unit)
            .combiner
            .forced()
            .unwrap_or_else(|| {
                let kept = ctx.link().kept().powermax();
                kept.or(ctx.link().status().settings)
                    .map(|s| Forced {
                        mode: s.mode.map_or(0, OperatingMode::to_legacy),
                        current: s.current.raw(),
                        pressure: s.pressure.raw(),
                    })
                    .unwrap_or_default()
            })
    }

    /// The group of writes is complete: one settings change (or none), never a partial one.
    fn complete_group(&mut self, ctx: &mut Context<'_>) -> Option<FaultCode> {
        let forced = self.node(ctx.unit).combiner.close()?;
        let status = ctx.link().status();
        let family = status.family.filter(|_| status.link_up)?;
        let (command, process) = match change(forced, family) {
            Change::Local if family.is_modbus() => (LinkCommand::ExitRemote, Keep::Forget),
            Change::Local => {
                self.node(ctx.unit).refused = None;
                return None;
            }
            Change::Refused(fault) => {
                self.node(ctx.unit).refused = Some(fault);
                return Some(fault);
            }
            Change::Powermax {
                mode,
                current,
                pressure,
            } => {
                let process = Process {
                    mode: cnc_mode(mode, Some(family)),
                    amps: current,
                    pressure,
                };
                if ctx.link().kept().powermax().is_some_and(|k| {
                    k.mode == Some(mode) && k.current == current && k.pressure == pressure
                }) && status.remote
                {
                    self.node(ctx.unit).refused = None;
                    return None;
                }
                super::history::process_change_starts(ctx);
                let command = LinkCommand::ApplyProcess {
                    mode,
                    current,
                    pressure,
                };
                (command, Keep::Process(process))
            }
            Change::HprAmps(amps) => (LinkCommand::HprSetNominalAmps { amps }, Keep::Unchanged),
        };
        match ctx.submit(command) {
            Ok(ticket) => {
                self.node(ctx.unit).refused = None;
                self.node(ctx.unit).applying = Some((ticket, process));
                None
            }
            Err(refusal) => {
                let fault = refusal_fault(&refusal);
                let node = self.node(ctx.unit);
                node.refused = fault.or(node.refused);
                fault
            }
        }
    }

    // --- replies ------------------------------------------------------------------------

    fn answer(&mut self, broadcast: bool, address: u8, response: &Response<'_>) -> Step {
        // No reply now leaves none behind: a `Step::Refused` after a broadcast must not send
        // the previous request's reply again.
        self.reply_len = 0;
        if broadcast {
            return Step::Pending;
        }
        match encode_response(address, response, &mut self.reply) {
            Ok(len) => {
                self.reply_len = len;
                Step::Reply
            }
            Err(_) => Step::Pending,
        }
    }

    fn answer_pdu(
        &mut self,
        broadcast: bool,
        address: u8,
        pdu: &[u8],
        refused: Option<FaultCode>,
    ) -> Step {
        self.reply_len = 0;
        if broadcast {
            return Step::Pending;
        }
        match plasma_protocol::modbus_ascii::encode(address, pdu, &mut self.reply) {
            Ok(len) => {
                self.reply_len = len;
                refused.map_or(Step::Reply, Step::Refused)
            }
            Err(_) => Step::Pending,
        }
    }
}

fn exception(function: u8, code: ExceptionCode) -> Response<'static> {
    Response::Exception {
        function: function & 0x7F,
        code,
    }
}

/// The reply PDU to Read Device Identification, as the unit behind the bridge gives it: its
/// Table 2 product code (object 0x01), the only object the bridge holds, with the conformity
/// level the unit gave at detection. Individual access (code 04) to object 0x01 is the guide's sample reply
/// (next object id 0x01 as there); another object is exception 02. Stream access (codes
/// 01-03) lists the objects from the one asked for, an object not held restarting at the
/// first (the Modbus rule), so it is the product code in one reply (no more follows).
/// `Err(01)`, as a unit without identification answers, when no Table 2 unit is behind or its
/// addressing system is not the map the bridge serves (a SYNC unit run on the legacy map).
fn identification(
    ctx: &Context<'_>,
    code: DeviceIdCode,
    object_id: u8,
    out: &mut [u8],
) -> Result<usize, ExceptionCode> {
    let status = ctx.link().status();
    let model = match (status.model, status.family) {
        (Some(Model::Powermax(model)), Some(family))
            if (model.addressing() == AddressingSystem::Sync)
                == (family == Family::PowermaxSync) =>
        {
            model
        }
        _ => return Err(ExceptionCode::IllegalFunction),
    };
    let objects: [(u8, &[u8]); 1] = [(PRODUCT_CODE_OBJECT, model.product_code().as_bytes())];
    let next_object_id = match code {
        DeviceIdCode::Specific if object_id != PRODUCT_CODE_OBJECT => {
            return Err(ExceptionCode::IllegalDataAddress);
        }
        DeviceIdCode::Specific => object_id,
        _ => 0,
    };
    // A unit that gave no level of its own (as a legacy unit, whose guide has no 0x2B/0x0E)
    // is answered with the level of the SYNC manual's sample (000_dd931256418ae627.txt line
    // 587).
    let conformity = status.device_id_conformity.unwrap_or(CONFORMITY_LEVEL);
    DeviceIdentification::emit_objects(code, conformity, false, next_object_id, &objects, out)
        .map_err(|_| ExceptionCode::ServerDeviceFailure)
}

/// True when a write of `n` registers from `start` touches the quick restart registers
/// (0x308E/0x308F) of a SYNC unit.
fn is_quick_restart(start: u16, n: usize, family: Family) -> bool {
    let end = usize::from(start) + n;
    family == Family::PowermaxSync
        && usize::from(start) <= usize::from(sync::QUICK_RESTART_APPROVAL)
        && end > usize::from(sync::QUICK_RESTART_COMMAND)
}

/// The special quick restart that stops fault 0-50-0 (SYNC manual: 0x0404 to 0x308E and 0x0618
/// to 0x308F in one 0x10 request), handed to the link. Anything else written there is
/// exception 03. The unit's restart stops 0-50-0 only, so without 0-50-0 active the link
/// sends nothing and the write is still echoed: it stops no fault, as on the unit.
fn quick_restart(ctx: &mut Context<'_>, start: u16, values: &[u16]) -> Result<(), ExceptionCode> {
    let words = [
        sync::QUICK_RESTART_COMMAND_VALUE,
        sync::QUICK_RESTART_APPROVAL_VALUE,
    ];
    if start != sync::QUICK_RESTART_COMMAND || values != words {
        return Err(ExceptionCode::IllegalDataValue);
    }
    match ctx.submit(LinkCommand::QuickRestart) {
        Ok(_) | Err(Refusal::QuickRestartNeeds050 { .. }) => Ok(()),
        Err(refusal) => Err(refusal_exception(&refusal)),
    }
}

/// The exception for a command the link does not take now: 06 (busy) while commands queue or
/// the unit restarts, 04 otherwise.
fn refusal_exception(refusal: &Refusal) -> ExceptionCode {
    match refusal {
        Refusal::QueueFull | Refusal::Blackout { .. } => ExceptionCode::ServerDeviceBusy,
        _ => ExceptionCode::ServerDeviceFailure,
    }
}

/// What a complete group of force-register writes becomes on `family`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Change {
    /// Back to local control.
    Local,
    /// Refused before sending: the fault it reads as.
    Refused(FaultCode),
    /// A Powermax: the three settings in one change.
    Powermax {
        mode: OperatingMode,
        current: plasma_protocol::powermax::Amps,
        pressure: plasma_protocol::powermax::Pressure,
    },
    /// An HPR or MaxPro200: the current only (whole amps).
    HprAmps(u16),
}

fn change(forced: Forced, family: Family) -> Change {
    use plasma_protocol::powermax::{Amps, Pressure};
    if forced.is_local() {
        return Change::Local;
    }
    let Some(mode) = OperatingMode::from_legacy(forced.mode) else {
        return Change::Refused(MODE_REFUSED);
    };
    let current = Amps::from_raw(forced.current);
    if !current.is_positive() {
        return Change::Refused(CURRENT_REFUSED);
    }
    let pressure = Pressure::from_raw(forced.pressure);
    if family.is_modbus() {
        return Change::Powermax {
            mode,
            current,
            pressure,
        };
    }
    // HPR / MaxPro200: the unit has one cutting mode and sets its gas pressures itself.
    if mode != OperatingMode::Cut {
        return Change::Refused(MODE_REFUSED);
    }
    if pressure != Pressure::Auto {
        return Change::Refused(PRESSURE_REFUSED);
    }
    if !current.is_whole() {
        return Change::Refused(CURRENT_REFUSED);
    }
    Change::HprAmps(forced.current / 64)
}

/// The 0-11-x fault a refusal reads as (`None`: not a setting the unit refuses).
fn refusal_fault(refusal: &Refusal) -> Option<FaultCode> {
    match refusal {
        Refusal::ModeNotPermitted { .. } => Some(MODE_REFUSED),
        Refusal::CurrentOutOfRange { .. } | Refusal::HprValueOutOfRange { .. } => {
            Some(CURRENT_REFUSED)
        }
        Refusal::PressureOutOfRange { .. } => Some(PRESSURE_REFUSED),
        _ => None,
    }
}
