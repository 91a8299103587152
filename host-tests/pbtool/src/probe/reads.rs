//! What `pbtool probe` asks, family by family: requests that only read.

use plasma_protocol::hpr::command::{COMMANDS, Class};
use plasma_protocol::hpr::frame::Frame as HprFrame;
use plasma_protocol::modbus_ascii::{self, DeviceIdCode, Request};
use plasma_protocol::powermax::registers::{
    LEGACY_COILS, LEGACY_REGISTERS, RegisterInfo, SYNC_COILS, SYNC_REGISTERS,
};
use plasma_sim::Family;

/// One read: what it is for, and its request frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Read {
    /// What is asked for, in a technician's words.
    pub what: String,
    /// The request frame (with CR LF for Modbus).
    pub request: String,
}

fn modbus(address: u8, request: &Request<'_>) -> String {
    let mut out = [0u8; modbus_ascii::MAX_FRAME_CHARS];
    match modbus_ascii::encode_request(address, request, &mut out) {
        Ok(n) => String::from_utf8_lossy(&out[..n]).into_owned(),
        // Every request built here fits; an empty frame would only go unanswered.
        Err(_) => String::new(),
    }
}

/// Read Device Identification, the product code object (as the bridge's detection asks).
pub fn device_id_request(node: u8) -> String {
    modbus(
        node,
        &Request::ReadDeviceIdentification {
            code: DeviceIdCode::Specific,
            object_id: plasma_protocol::powermax::device_id::PRODUCT_CODE_OBJECT,
        },
    )
}

/// A read of the first documented legacy register: any legacy unit answers it.
pub fn legacy_presence_request(node: u8) -> String {
    let first = LEGACY_REGISTERS.first().map_or(0x2093, |r| r.first);
    modbus(
        node,
        &Request::ReadInputRegisters {
            start: first,
            quantity: 1,
        },
    )
}

/// The HPR frame of command `id` without data.
pub fn hpr_request(id: u16) -> String {
    let mut out = [0u8; plasma_protocol::hpr::MAX_FRAME_LEN];
    match HprFrame::new(id, &[]).emit(&mut out) {
        Ok(n) => String::from_utf8_lossy(&out[..n]).into_owned(),
        Err(_) => String::new(),
    }
}

/// True for an HPR command that only reports: a [`Class::Normal`] command whose manual name
/// says it asks (HELLO, VERSION, CURRENT_ERROR, GET_..., READ_..., IS_...).
pub fn hpr_query(name: &str, class: Class) -> bool {
    class == Class::Normal
        && (matches!(name, "HELLO" | "VERSION" | "CURRENT_ERROR")
            || ["GET_", "READ_", "IS_"].iter().any(|p| name.starts_with(p)))
}

fn catalogue(registers: &[RegisterInfo], coils: &[RegisterInfo], node: u8) -> Vec<Read> {
    let registers = registers.iter().map(|r| Read {
        what: r.name.to_string(),
        request: modbus(
            node,
            &Request::ReadInputRegisters {
                start: r.first,
                quantity: r.last - r.first + 1,
            },
        ),
    });
    let coils = coils.iter().map(|c| Read {
        what: c.name.to_string(),
        request: modbus(
            node,
            &Request::ReadCoils {
                start: c.first,
                quantity: c.last - c.first + 1,
            },
        ),
    });
    registers.chain(coils).collect()
}

/// Everything to read from a unit of `family` (a Powermax at node `node`).
pub fn for_family(family: Family, node: u8) -> Vec<Read> {
    match family {
        // The identification is what detection read.
        Family::Sync => catalogue(SYNC_REGISTERS, SYNC_COILS, node),
        Family::Legacy => catalogue(LEGACY_REGISTERS, LEGACY_COILS, node),
        Family::Hpr => COMMANDS
            .iter()
            .filter(|c| hpr_query(c.name, c.class))
            .map(|c| Read {
                what: c.name.to_string(),
                request: hpr_request(c.id),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode::{Kind, decode_frames};

    #[test]
    fn every_read_is_a_valid_request_that_writes_nothing() {
        for family in [Family::Sync, Family::Legacy, Family::Hpr] {
            let reads = for_family(family, 1);
            assert!(reads.len() > 5, "{family:?}");
            for read in reads {
                let report = &decode_frames(&[read.request.as_str()])[0];
                assert!(report.valid, "{read:?}: {report:?}");
                assert_eq!(report.kind, Some(Kind::Request), "{read:?}");
                let function = report.function.as_ref().map(|f| f.code);
                assert!(
                    matches!(function, None | Some(0x01 | 0x04 | 0x2B)),
                    "{read:?} is not a read"
                );
                if let Some(name) = report.command.as_ref().and_then(|c| c.name) {
                    assert!(hpr_query(name, Class::Normal), "{read:?}");
                }
            }
        }
        assert_eq!(hpr_request(0), ">00090<");
        assert_eq!(device_id_request(1), ":012B0E0401C1\r\n");
    }

    #[test]
    fn setters_and_tests_are_not_queries() {
        assert!(hpr_query("GET_STATE", Class::Normal));
        assert!(!hpr_query("REMOTE_MODE", Class::Normal));
        assert!(!hpr_query("SET_NOMINAL_AMPS", Class::Normal));
        assert!(!hpr_query("GET_MFG_DATA1", Class::FactoryTestingOnly));
    }
}
