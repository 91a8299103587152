//! Modbus pieces shared by the SYNC and legacy drivers: an owned copy of a request (so a
//! transaction can validate its reply), block reads with the documented fallback, and the
//! RAW allow-list.

use heapless::Vec;
use plasma_protocol::modbus_ascii::{
    self, DeviceIdCode, ExceptionCode, Registers, Request, Response,
};
use plasma_protocol::powermax::BlockRead;

use crate::link::command::Refusal;
use crate::link::status::Family;
use crate::link::transaction::TransactionError;

/// Most registers a request built by the link writes (remote settings: 3).
pub(crate) const MAX_WRITE_WORDS: usize = 8;

/// A Modbus request the link owns (a [`Request`] borrows its written values).
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) enum MbRequest {
    /// Function 04.
    ReadInput {
        /// First register.
        start: u16,
        /// Count.
        quantity: u16,
    },
    /// Function 03.
    ReadHolding {
        /// First register.
        start: u16,
        /// Count.
        quantity: u16,
    },
    /// Function 01.
    ReadCoils {
        /// First coil.
        start: u16,
        /// Count.
        quantity: u16,
    },
    /// Function 05.
    WriteCoil {
        /// Coil.
        address: u16,
        /// State.
        on: bool,
    },
    /// Function 06.
    WriteRegister {
        /// Register.
        address: u16,
        /// Value.
        value: u16,
    },
    /// Function 0x10.
    WriteRegisters {
        /// First register.
        start: u16,
        /// Values.
        values: Vec<u16, MAX_WRITE_WORDS>,
    },
    /// Function 0x2B / 0x0E.
    ReadDeviceId {
        /// Access code.
        code: DeviceIdCode,
        /// First object.
        object: u8,
    },
}

impl MbRequest {
    /// Owned copy of `request`; `None` when it writes more than [`MAX_WRITE_WORDS`] registers.
    pub(crate) fn from_request(request: &Request<'_>) -> Option<Self> {
        Some(match *request {
            Request::ReadCoils { start, quantity } => MbRequest::ReadCoils { start, quantity },
            Request::ReadHoldingRegisters { start, quantity } => {
                MbRequest::ReadHolding { start, quantity }
            }
            Request::ReadInputRegisters { start, quantity } => {
                MbRequest::ReadInput { start, quantity }
            }
            Request::WriteSingleCoil { address, on } => MbRequest::WriteCoil { address, on },
            Request::WriteSingleRegister { address, value } => {
                MbRequest::WriteRegister { address, value }
            }
            Request::WriteMultipleRegisters { start, values } => {
                let mut owned = Vec::new();
                for value in values.iter() {
                    owned.push(value).ok()?;
                }
                MbRequest::WriteRegisters {
                    start,
                    values: owned,
                }
            }
            Request::ReadDeviceIdentification { code, object_id } => MbRequest::ReadDeviceId {
                code,
                object: object_id,
            },
        })
    }

    /// The borrowed form the protocol crate works with.
    pub(crate) fn as_request(&self) -> Request<'_> {
        match self {
            MbRequest::ReadInput { start, quantity } => Request::ReadInputRegisters {
                start: *start,
                quantity: *quantity,
            },
            MbRequest::ReadHolding { start, quantity } => Request::ReadHoldingRegisters {
                start: *start,
                quantity: *quantity,
            },
            MbRequest::ReadCoils { start, quantity } => Request::ReadCoils {
                start: *start,
                quantity: *quantity,
            },
            MbRequest::WriteCoil { address, on } => Request::WriteSingleCoil {
                address: *address,
                on: *on,
            },
            MbRequest::WriteRegister { address, value } => Request::WriteSingleRegister {
                address: *address,
                value: *value,
            },
            MbRequest::WriteRegisters { start, values } => Request::WriteMultipleRegisters {
                start: *start,
                values: Registers::Words(values),
            },
            MbRequest::ReadDeviceId { code, object } => Request::ReadDeviceIdentification {
                code: *code,
                object_id: *object,
            },
        }
    }

    /// The ASCII frame for node `address`, written into `out`.
    pub(crate) fn encode(&self, address: u8, out: &mut [u8]) -> plasma_protocol::Result<usize> {
        modbus_ascii::encode_request(address, &self.as_request(), out)
    }
}

/// Registers of a read reply (function 03 or 04).
pub(crate) fn read_values<'a>(response: &Response<'a>) -> Option<Registers<'a>> {
    match response {
        Response::ReadInputRegisters { values } | Response::ReadHoldingRegisters { values } => {
            Some(*values)
        }
        _ => None,
    }
}

/// How a protocol-crate error on a received frame counts.
pub(crate) fn classify(error: plasma_protocol::Error) -> TransactionError {
    match error {
        plasma_protocol::Error::BadChecksum { .. } => TransactionError::BadChecksum,
        plasma_protocol::Error::Mismatch => TransactionError::Mismatch,
        _ => TransactionError::Malformed,
    }
}

/// Bit `index` of a part set (0 for an index beyond the set; plans have at most 4 parts).
fn bit(index: usize) -> u8 {
    u32::try_from(index)
        .ok()
        .and_then(|i| 1u8.checked_shl(i))
        .unwrap_or(0)
}

/// Largest block a [`BlockPoller`] can assemble.
const BLOCK_CAPACITY: usize = 32;

/// A block read that falls back to its documented parts when the unit answers exception 02
/// (illegal data address), and remembers that for the unit (and any part it refuses too).
#[derive(Debug, Clone)]
pub(crate) struct BlockPoller {
    plan: BlockRead,
    use_parts: bool,
    refused_parts: u8,
    /// Part to read next in this cycle (when using parts).
    next_part: usize,
    in_cycle: bool,
    /// Parts read in this cycle (bit per part; all bits when read whole).
    read_parts: u8,
    buf: [u16; BLOCK_CAPACITY],
}

/// What a [`BlockPoller`] asks for: the whole block (`None`) or part `Some(i)`.
pub(crate) type BlockPart = Option<u8>;

impl BlockPoller {
    /// A poller that tries the whole block first.
    pub(crate) fn new(plan: BlockRead) -> Self {
        BlockPoller {
            plan,
            use_parts: false,
            refused_parts: 0,
            next_part: 0,
            in_cycle: false,
            read_parts: 0,
            buf: [0; BLOCK_CAPACITY],
        }
    }

    /// True once the unit refused the whole block (the fallback is remembered).
    pub(crate) fn uses_parts(&self) -> bool {
        self.use_parts
    }

    /// True while a cycle is in progress.
    pub(crate) fn in_cycle(&self) -> bool {
        self.in_cycle
    }

    /// Begin a cycle.
    pub(crate) fn start(&mut self) {
        self.in_cycle = true;
        self.next_part = 0;
        self.read_parts = 0;
        self.skip_refused();
    }

    /// Abandon the cycle (a read failed).
    pub(crate) fn abort(&mut self) {
        self.in_cycle = false;
    }

    fn skip_refused(&mut self) {
        while self.next_part < self.plan.parts().len()
            && self.refused_parts & (bit(self.next_part)) != 0
        {
            self.next_part += 1;
        }
    }

    /// The read to send next in this cycle.
    pub(crate) fn request(&self) -> Option<(MbRequest, BlockPart)> {
        if !self.in_cycle {
            return None;
        }
        if !self.use_parts {
            let block = self.plan.block();
            return Some((
                MbRequest::ReadInput {
                    start: block.start,
                    quantity: block.quantity,
                },
                None,
            ));
        }
        let part = self.plan.parts().get(self.next_part)?;
        Some((
            MbRequest::ReadInput {
                start: part.start,
                quantity: part.quantity,
            },
            u8::try_from(self.next_part).ok(),
        ))
    }

    /// Store the reply to `part`. Returns true when the cycle is complete.
    pub(crate) fn on_values(&mut self, part: BlockPart, values: Registers<'_>) -> bool {
        let len = self.plan.len().min(BLOCK_CAPACITY);
        match part {
            None => {
                for (slot, value) in self.buf.iter_mut().take(len).zip(values.iter()) {
                    *slot = value;
                }
                self.read_parts = u8::MAX;
                self.in_cycle = false;
                true
            }
            Some(index) => {
                let index = usize::from(index);
                if let Some(block) = self.buf.get_mut(..len)
                    && self.plan.place(index, values, block).is_ok()
                {
                    self.read_parts |= bit(index);
                }
                self.next_part = index + 1;
                self.skip_refused();
                if self.next_part >= self.plan.parts().len() {
                    self.in_cycle = false;
                    true
                } else {
                    false
                }
            }
        }
    }

    /// The unit refused `part` with exception 02: fall back (and remember it). Returns true
    /// when the cycle is complete (nothing left to read).
    pub(crate) fn on_illegal_address(&mut self, part: BlockPart) -> bool {
        match part {
            None => {
                self.use_parts = true;
                self.next_part = 0;
                self.skip_refused();
                false
            }
            Some(index) => {
                let index = usize::from(index);
                self.refused_parts |= bit(index);
                self.next_part = index + 1;
                self.skip_refused();
                if self.next_part >= self.plan.parts().len() {
                    self.in_cycle = false;
                    true
                } else {
                    false
                }
            }
        }
    }

    /// True when part `index` holds fresh values from this cycle.
    pub(crate) fn part_read(&self, index: usize) -> bool {
        self.read_parts & (bit(index)) != 0
    }

    /// True when every documented part holds fresh values.
    pub(crate) fn complete(&self) -> bool {
        (0..self.plan.parts().len()).all(|i| self.part_read(i))
    }

    /// The block-shaped registers (positions of unread parts hold stale values).
    pub(crate) fn registers(&self) -> Registers<'_> {
        let len = self.plan.len().min(BLOCK_CAPACITY);
        Registers::Words(self.buf.get(..len).unwrap_or(&[]))
    }
}

/// Documented writable targets a RAW Modbus write may reach, per family.
///
/// SYNC: remote settings 0x3080-0x3082 (functions 06 and 0x10), the gas-test coil 0x3180, and
/// the old-address equivalents of SYNC Table 1 (0x2093, 0x2094, 0x2096 with 06; coil 0x0832).
/// Legacy: the force registers 0x2093, 0x2094, 0x2096 (06) and the gas-test coil 0x0832.
/// The quick restart (0x308E/0x308F) is deliberately not here: it must go through
/// `LinkCommand::QuickRestart`, which checks for 0-50-0 and keeps the 2 s silence.
pub(crate) fn check_raw_request(family: Family, request: &Request<'_>) -> Result<(), Refusal> {
    const LEGACY_FORCE: [u16; 3] = [0x2093, 0x2094, 0x2096];
    let sync = family == Family::PowermaxSync;
    match *request {
        Request::ReadCoils { .. }
        | Request::ReadHoldingRegisters { .. }
        | Request::ReadInputRegisters { .. }
        | Request::ReadDeviceIdentification { .. } => Ok(()),
        Request::WriteSingleCoil { address, .. } => {
            if address == 0x0832 || (sync && address == 0x3180) {
                Ok(())
            } else {
                Err(Refusal::RawWriteNotAllowed { address })
            }
        }
        Request::WriteSingleRegister { address, .. } => {
            if LEGACY_FORCE.contains(&address) || (sync && (0x3080..=0x3082).contains(&address)) {
                Ok(())
            } else {
                Err(Refusal::RawWriteNotAllowed { address })
            }
        }
        Request::WriteMultipleRegisters { start, values } => {
            let last = u32::from(start) + values.len() as u32;
            if sync && (0x3080..=0x3082).contains(&start) && last <= 0x3083 && !values.is_empty() {
                Ok(())
            } else {
                Err(Refusal::RawWriteNotAllowed { address: start })
            }
        }
    }
}

/// True for exception 02.
pub(crate) fn is_illegal_address(error: TransactionError) -> bool {
    error == TransactionError::Exception(ExceptionCode::IllegalDataAddress)
}

#[cfg(test)]
mod raw_allow_list_tests {
    //! The RAW allow-list spells its addresses out (the register catalogue's names would cost
    //! flash); these tests keep it in step with `powermax::registers`, the one catalogue.

    use plasma_protocol::modbus_ascii::{Registers, Request};
    use plasma_protocol::powermax::registers::{
        self, Access, LEGACY_COILS, LEGACY_REGISTERS, RegisterInfo, SYNC_COILS, SYNC_REGISTERS,
    };
    use plasma_protocol::powermax::sync::{QUICK_RESTART_APPROVAL, QUICK_RESTART_COMMAND};

    use super::{Family, check_raw_request};

    fn writable_in(tables: &[&[RegisterInfo]], address: u16) -> bool {
        tables.iter().any(|table| {
            table
                .iter()
                .any(|r| (r.first..=r.last).contains(&address) && r.access == Access::Write)
        })
    }

    /// The family's own addresses; SYNC units also answer the legacy ones (SYNC Table 1).
    fn tables(
        family: Family,
    ) -> (
        &'static [&'static [RegisterInfo]],
        &'static [&'static [RegisterInfo]],
    ) {
        match family {
            Family::PowermaxSync => (
                &[SYNC_REGISTERS, LEGACY_REGISTERS],
                &[SYNC_COILS, LEGACY_COILS],
            ),
            _ => (&[LEGACY_REGISTERS], &[LEGACY_COILS]),
        }
    }

    #[test]
    fn single_writes_reach_exactly_the_catalogues_writable_addresses() {
        for family in [Family::PowermaxSync, Family::PowermaxLegacy] {
            let (regs, coils) = tables(family);
            for address in 0..=u16::MAX {
                let quick_restart =
                    address == QUICK_RESTART_COMMAND || address == QUICK_RESTART_APPROVAL;
                let register = Request::WriteSingleRegister { address, value: 1 };
                assert_eq!(
                    check_raw_request(family, &register).is_ok(),
                    writable_in(regs, address) && !quick_restart,
                    "{family:?} register {address:#06X}"
                );
                let coil = Request::WriteSingleCoil { address, on: true };
                assert_eq!(
                    check_raw_request(family, &coil).is_ok(),
                    writable_in(coils, address),
                    "{family:?} coil {address:#06X}"
                );
            }
        }
    }

    #[test]
    fn block_writes_stay_inside_documented_writable_runs() {
        let words = [0u16; 4];
        for start in 0x3070..=0x3090u16 {
            for quantity in 1..=4usize {
                let values = Registers::Words(&words[..quantity]);
                let request = Request::WriteMultipleRegisters { start, values };
                let allowed = check_raw_request(Family::PowermaxSync, &request).is_ok();
                if allowed {
                    assert!(
                        registers::registers_writable(start, quantity as u16),
                        "{start:#06X}+{quantity} allowed but not documented writable"
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
