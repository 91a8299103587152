//! What may reach the power supply, judged by the protocol's own tables.
//!
//! - Every frame decodes (Modbus ASCII or HPR) and fits the link's transmit buffer.
//! - A Modbus write reaches only registers or coils documented as writable in the map of the
//!   unit on the line (`powermax::registers`: a SYNC unit has the SYNC tables and, as
//!   `powermax::legacy` documents, the legacy ones; a legacy unit the legacy ones; an HPR or
//!   MaxPro200 none). Once injected power-supply bytes may have made the link believe in
//!   another unit, the map of the family it believes in also counts; without a simulated
//!   unit only that one does (any documented family's while it believes in none).
//! - An HPR command is [`Class::Normal`] in `hpr::command`.
//! - While the link speaks to a SYNC unit, a settings change is one 0x10 write of
//!   0x3080-0x3082, never a part of it (the firmware's property test says the same of Modbus
//!   masters, `no_sequence_of_modbus_writes_makes_a_partial_settings_write_or_a_start`):
//!   judged unless a `RAW` command, which may write one register on purpose, may have come.

use plasma_firmware::link::{Family as LinkFamily, TX_CAPACITY};
use plasma_protocol::hpr::{self, Class};
use plasma_protocol::modbus_ascii::{self, Request};
use plasma_protocol::powermax::registers::{
    self, Access, LEGACY_COILS, LEGACY_REGISTERS, RegisterInfo, SYNC_COILS, SYNC_REGISTERS,
};
use plasma_protocol::powermax::{legacy, sync};
use plasma_sim::Family;

/// What the board knows when a frame leaves for the power supply.
pub struct Judge {
    /// The family of the simulated unit on the line.
    pub unit: Option<Family>,
    /// The family the link believes it speaks to.
    pub link: Option<LinkFamily>,
    /// Steps injected power-supply bytes: the link may believe in a unit that is not there.
    pub impersonated: bool,
    /// The CNC may have sent a `RAW` command.
    pub raw_possible: bool,
}

/// A family's documented registers and coils.
struct Map {
    registers: &'static [&'static [RegisterInfo]],
    coils: &'static [&'static [RegisterInfo]],
}

fn map(family: Family) -> Map {
    match family {
        Family::Sync => Map {
            registers: &[SYNC_REGISTERS, LEGACY_REGISTERS],
            coils: &[SYNC_COILS, LEGACY_COILS],
        },
        Family::Legacy => Map {
            registers: &[LEGACY_REGISTERS],
            coils: &[LEGACY_COILS],
        },
        Family::Hpr => Map {
            registers: &[],
            coils: &[],
        },
    }
}

fn sim_family(family: LinkFamily) -> Family {
    match family {
        LinkFamily::PowermaxSync => Family::Sync,
        LinkFamily::PowermaxLegacy => Family::Legacy,
        LinkFamily::Hpr | LinkFamily::MaxPro200 => Family::Hpr,
    }
}

/// True when `start..start + quantity` (no wrap-around) is documented writable in `tables`.
fn writable(tables: &[&[RegisterInfo]], start: u16, quantity: u16) -> bool {
    quantity > 0
        && (0..quantity).all(|i| {
            start.checked_add(i).is_some_and(|address| {
                tables.iter().any(|table| {
                    table
                        .iter()
                        .any(|r| (r.first..=r.last).contains(&address) && r.access == Access::Write)
                })
            })
        })
}

impl Judge {
    /// The families whose maps may allow a write (empty: any documented family's).
    fn families(&self) -> Vec<Family> {
        let believed = self.link.map(sim_family);
        match self.unit {
            None => believed.into_iter().collect(),
            Some(unit) if self.impersonated => {
                [Some(unit), believed].into_iter().flatten().collect()
            }
            Some(unit) => vec![unit],
        }
    }

    fn registers_writable(&self, start: u16, quantity: u16) -> bool {
        let families = self.families();
        if families.is_empty() {
            return registers::registers_writable(start, quantity);
        }
        families
            .into_iter()
            .any(|f| writable(map(f).registers, start, quantity))
    }

    fn coil_writable(&self, address: u16) -> bool {
        let families = self.families();
        if families.is_empty() {
            return registers::coil_writable(address);
        }
        families
            .into_iter()
            .any(|f| writable(map(f).coils, address, 1))
    }

    /// Panics unless `frame` is one whole frame the bridge may send now.
    pub fn check(&self, frame: &[u8]) {
        assert!(frame.len() <= TX_CAPACITY, "frame over the transmit buffer");
        match frame.first() {
            Some(b':') => self.check_modbus(frame),
            Some(&hpr::frame::START) => {
                let parsed = hpr::Frame::parse(frame)
                    .unwrap_or_else(|e| panic!("sent an HPR frame that does not parse: {e:?}"));
                assert_eq!(
                    hpr::classify(parsed.id),
                    Some(Class::Normal),
                    "sent HPR command {:03} off the allow-list",
                    parsed.id
                );
            }
            _ => panic!("sent something that is no frame: {frame:?}"),
        }
    }

    fn check_modbus(&self, frame: &[u8]) {
        let mut buf = [0u8; modbus_ascii::MAX_FRAME_BYTES];
        let decoded = modbus_ascii::decode(frame, &mut buf)
            .unwrap_or_else(|e| panic!("sent a Modbus frame that does not decode: {e:?}"));
        let request = decoded
            .request()
            .unwrap_or_else(|e| panic!("sent a Modbus PDU that does not parse: {e:?}"));
        let allowed = match request {
            Request::ReadCoils { .. }
            | Request::ReadHoldingRegisters { .. }
            | Request::ReadInputRegisters { .. }
            | Request::ReadDeviceIdentification { .. } => true,
            Request::WriteSingleCoil { address, .. } => self.coil_writable(address),
            Request::WriteSingleRegister { address, .. } => self.registers_writable(address, 1),
            Request::WriteMultipleRegisters { start, values } => {
                u16::try_from(values.len()).is_ok_and(|n| self.registers_writable(start, n))
            }
        };
        assert!(
            allowed,
            "sent a write off the allow-list of {:?} (link: {:?}): {request:?}",
            self.unit, self.link
        );
        if self.link == Some(LinkFamily::PowermaxSync) && !self.raw_possible {
            check_whole_settings(&request);
        }
    }
}

/// The settings registers of both maps.
fn is_settings_register(address: u16) -> bool {
    (sync::REMOTE_MODE..=sync::REMOTE_PRESSURE).contains(&address)
        || [
            legacy::MODE_FORCE,
            legacy::CURRENT_FORCE,
            legacy::PRESSURE_FORCE,
        ]
        .contains(&address)
}

/// A write to a SYNC unit's settings is all of 0x3080-0x3082 in one 0x10 request.
fn check_whole_settings(request: &Request<'_>) {
    let touches = match *request {
        Request::WriteSingleRegister { address, .. } => is_settings_register(address),
        Request::WriteMultipleRegisters { start, values } => (0..values.len())
            .any(|i| u16::try_from(i).is_ok_and(|i| is_settings_register(start.wrapping_add(i)))),
        _ => false,
    };
    if !touches {
        return;
    }
    let whole = usize::from(sync::REMOTE_PRESSURE - sync::REMOTE_MODE) + 1;
    assert!(
        matches!(*request, Request::WriteMultipleRegisters { start, values }
            if start == sync::REMOTE_MODE && values.len() == whole),
        "a partial settings write to a SYNC unit: {request:?}"
    );
}
