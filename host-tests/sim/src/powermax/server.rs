//! The Modbus ASCII server: block reads over the register and coil maps of [`crate::sync`]
//! and [`crate::legacy`], the requests the unit answers, node address and address learning.

use plasma_protocol::modbus_ascii::{DeviceIdCode, ExceptionCode, Request};
use plasma_protocol::time::{Duration, Instant};
use rand::RngExt;

use super::{DeviceIdSupport, Powermax, UndocumentedAddresses};
use crate::modbus_wire::{self, Reply};
use crate::{legacy, sync};

/// One read cell of a register or coil map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Cell {
    Value(u16),
    /// Undocumented address inside a documented block.
    Gap,
    /// Not an address of this unit.
    Unknown,
}

impl Powermax {
    pub(super) fn read_block(
        &self,
        start: u16,
        quantity: u16,
        max: u16,
        lookup: impl Fn(&Self, u16) -> Cell,
    ) -> Result<Vec<u16>, ExceptionCode> {
        if quantity == 0 || quantity > max {
            return Err(ExceptionCode::IllegalDataValue);
        }
        let end = u32::from(start) + u32::from(quantity);
        if end > 0x1_0000 {
            return Err(ExceptionCode::IllegalDataAddress);
        }
        (start..=(end - 1) as u16)
            .map(|a| match lookup(self, a) {
                Cell::Value(v) => Ok(v),
                Cell::Gap if self.config.undocumented == UndocumentedAddresses::Accept => Ok(0),
                _ => Err(ExceptionCode::IllegalDataAddress),
            })
            .collect()
    }

    pub(super) fn register(&self, address: u16) -> Cell {
        if self.config.refused_registers.contains(&address) {
            return Cell::Unknown;
        }
        match (self.is_sync(), address) {
            (true, 0x3000..=0x3FFF) => sync::register(self, address),
            (_, 0x2000..=0x2FFF) => legacy::register(self, address),
            _ => Cell::Unknown,
        }
    }

    pub(super) fn coil(&self, address: u16) -> Cell {
        match (self.is_sync(), address) {
            (true, 0x3000..=0x3FFF) => sync::coil(self, address),
            _ => legacy::coil(self, address),
        }
    }

    /// Acts on one request addressed to this unit.
    pub(super) fn handle(&mut self, now: Instant, request: &Request<'_>) -> Option<Reply> {
        use ExceptionCode::*;
        let function = request.function().to_u8();
        let refuse = |code| Some(Reply::exception(function, code));
        self.requests += 1;
        match *request {
            Request::ReadCoils { start, quantity } => {
                match self.read_block(start, quantity, 2000, Self::coil) {
                    Ok(bits) => {
                        let mut packed = vec![0u8; bits.len().div_ceil(8)];
                        for (i, b) in bits.iter().enumerate() {
                            if *b != 0 {
                                packed[i / 8] |= 1 << (i % 8);
                            }
                        }
                        Some(Reply::Coils(packed))
                    }
                    Err(code) => refuse(code),
                }
            }
            Request::ReadHoldingRegisters { start, quantity }
            | Request::ReadInputRegisters { start, quantity } => {
                match self.read_block(start, quantity, 125, Self::register) {
                    Ok(values) if function == 0x03 => Some(Reply::HoldingRegisters(values)),
                    Ok(values) => Some(Reply::InputRegisters(values)),
                    Err(code) => refuse(code),
                }
            }
            Request::WriteSingleCoil { address, on } => {
                let gas_test = address == 0x0832 || (self.is_sync() && address == 0x3180);
                if !gas_test {
                    return refuse(IllegalDataAddress);
                }
                self.set_gas_test(on);
                Some(Reply::WriteSingleCoil { address, on })
            }
            Request::WriteSingleRegister { address, value } => {
                let (index, one_request) = match (self.is_sync(), address) {
                    (true, 0x3080..=0x3082) => ((address - 0x3080) as usize, true),
                    // The old addresses take one register per request (function 06), so
                    // on every unit they follow the legacy rule.
                    (_, 0x2093 | 0x2094 | 0x2096) => {
                        (legacy::force_index(address).unwrap_or(0), false)
                    }
                    _ => return refuse(IllegalDataAddress),
                };
                match self.write_force(&[(index, value)], one_request) {
                    Ok(()) => Some(Reply::WriteSingleRegister { address, value }),
                    Err(code) => refuse(code),
                }
            }
            Request::WriteMultipleRegisters { start, values } => {
                let quantity = values.len() as u16;
                let words: Vec<u16> = values.iter().collect();
                let result = if self.is_sync() && (0x3080..=0x308F).contains(&start) {
                    sync::write_multiple(self, now, start, &words)
                } else if (0x2093..=0x2096).contains(&start) {
                    legacy::write_multiple(self, start, &words)
                } else {
                    Err(IllegalDataAddress)
                };
                match result {
                    Ok(()) => Some(Reply::WriteMultipleRegisters { start, quantity }),
                    Err(code) => refuse(code),
                }
            }
            Request::ReadDeviceIdentification { code, object_id } => match self.config.device_id {
                DeviceIdSupport::Silent => None,
                DeviceIdSupport::IllegalFunction => refuse(IllegalFunction),
                DeviceIdSupport::Answers { conformity } => {
                    if code != DeviceIdCode::Specific {
                        return refuse(IllegalDataValue);
                    }
                    if object_id != 0x01 {
                        return refuse(IllegalDataAddress);
                    }
                    let product = if self.is_sync() {
                        sync::product_code(self.config.model)
                    } else {
                        legacy::product_code(self.config.model)
                    };
                    // Header as in the SYNC guide's example reply: next object id 0x01.
                    Some(Reply::DeviceIdentification {
                        code,
                        conformity,
                        next_object_id: 0x01,
                        objects: vec![(0x01, product.as_bytes().to_vec())],
                    })
                }
            },
        }
    }

    pub(super) fn on_frame(&mut self, now: Instant, address: u8, pdu: &[u8]) {
        let broadcast = address == 0;
        if !broadcast {
            match self.address() {
                None => self.learned = Some(address),
                Some(a) if a == address => {}
                Some(_) => return,
            }
        }
        let reply = match modbus_wire::parse_request(pdu) {
            Ok(request) => self.handle(now, &request),
            Err(refused) => Some(Reply::exception(refused.function, refused.code)),
        };
        if let (Some(reply), false) = (reply, broadcast) {
            let jitter = self.config.latency_jitter.as_micros();
            let extra = if jitter > 0 {
                self.rng.random_range(0..=jitter)
            } else {
                0
            };
            let due = now + self.config.latency + Duration::from_micros(extra);
            let bytes = modbus_wire::encode(address, &reply.to_pdu());
            self.outbox.push_back((due, bytes));
        }
    }
}
