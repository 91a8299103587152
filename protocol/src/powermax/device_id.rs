//! Which power supply is on the line: Read Device Identification (0x2B/0x0E) and Table 2 of the
//! SYNC guide.
//!
//! Table 2 keys on one string, the product code (object 0x01), which the guide reads with
//! `:012B0E0401C1` (specific object 0x01) and gets back as `081335` for a Powermax65/85/105
//! SYNC. The vendor name and revision objects play no part in the table.

use super::ident::SyncModel;
use crate::modbus_ascii::pdu::DeviceIdentification;
use crate::modbus_ascii::{DeviceIdCode, Request};
use crate::{Error, Result};

/// Register family a power supply speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AddressingSystem {
    /// "Old 0x2xxx addresses" ([`legacy`](super::legacy)).
    Legacy,
    /// "New 0x3xxx addresses" ([`sync`](super::sync)).
    Sync,
}

/// A power supply type of Table 2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[allow(non_camel_case_types)]
pub enum PowerSupplyModel {
    /// Powermax45 XP (`081288`).
    Powermax45Xp,
    /// Powermax65/85/105 (`081223`).
    Powermax65_85_105,
    /// Powermax125 (`081251`).
    Powermax125,
    /// Powermax65/85/105 SYNC (`081335`).
    Powermax65_85_105Sync,
    /// Powermax45 SYNC (`081374`).
    Powermax45Sync,
}

/// Table 2, all 5 rows: (product code, model, addressing system).
pub static DEVICE_IDENTIFICATIONS: [(&str, PowerSupplyModel, AddressingSystem); 5] = [
    (
        "081288",
        PowerSupplyModel::Powermax45Xp,
        AddressingSystem::Legacy,
    ),
    (
        "081223",
        PowerSupplyModel::Powermax65_85_105,
        AddressingSystem::Legacy,
    ),
    (
        "081251",
        PowerSupplyModel::Powermax125,
        AddressingSystem::Legacy,
    ),
    (
        "081335",
        PowerSupplyModel::Powermax65_85_105Sync,
        AddressingSystem::Sync,
    ),
    (
        "081374",
        PowerSupplyModel::Powermax45Sync,
        AddressingSystem::Sync,
    ),
];

/// Device Identification object id of the product code.
pub const PRODUCT_CODE_OBJECT: u8 = 0x01;

/// The conformity level a Powermax gives in its reply: 0x81 in the guide's sample
/// (`:012B0E0481000101010630383133333504`), which the Modbus specification reads as "basic
/// identification, stream and individual access".
pub const CONFORMITY_LEVEL: u8 = 0x81;

impl PowerSupplyModel {
    /// The product code Table 2 lists.
    pub fn product_code(self) -> &'static str {
        DEVICE_IDENTIFICATIONS
            .iter()
            .find(|(_, m, _)| *m == self)
            .map_or("", |(code, _, _)| *code)
    }

    /// Which registers to use.
    pub const fn addressing(self) -> AddressingSystem {
        match self {
            PowerSupplyModel::Powermax65_85_105Sync | PowerSupplyModel::Powermax45Sync => {
                AddressingSystem::Sync
            }
            _ => AddressingSystem::Legacy,
        }
    }

    /// Table 2's name.
    pub const fn name(self) -> &'static str {
        match self {
            PowerSupplyModel::Powermax45Xp => "Powermax45 XP",
            PowerSupplyModel::Powermax65_85_105 => "Powermax65/85/105",
            PowerSupplyModel::Powermax125 => "Powermax125",
            PowerSupplyModel::Powermax65_85_105Sync => "Powermax65/85/105 SYNC",
            PowerSupplyModel::Powermax45Sync => "Powermax45 SYNC",
        }
    }
}

impl From<SyncModel> for PowerSupplyModel {
    /// The Table 2 type a Table 4 id belongs to.
    fn from(model: SyncModel) -> Self {
        if model.size() == 45 {
            PowerSupplyModel::Powermax45Sync
        } else {
            PowerSupplyModel::Powermax65_85_105Sync
        }
    }
}

/// The request of the guide's example: product code only (`:012B0E0401C1` at node 1).
pub const fn read_product_code() -> Request<'static> {
    Request::ReadDeviceIdentification {
        code: DeviceIdCode::Specific,
        object_id: PRODUCT_CODE_OBJECT,
    }
}

/// Table 2 lookup by product code. Trailing NULs and spaces are ignored (some Modbus stacks pad
/// fixed-size objects); nothing else is.
pub fn model_from_product_code(product_code: &[u8]) -> Option<PowerSupplyModel> {
    let end = product_code
        .iter()
        .rposition(|&b| b != 0 && b != b' ')
        .map_or(0, |last| last + 1);
    let trimmed = product_code.get(..end)?;
    DEVICE_IDENTIFICATIONS
        .iter()
        .find(|(code, _, _)| code.as_bytes() == trimmed)
        .map(|(_, model, _)| *model)
}

/// The value of object `id` in a Read Device Identification object list
/// (`id`, `length`, value bytes, repeated). [`Error::Truncated`] if the list ends inside an
/// object.
pub fn find_object(objects: &[u8], id: u8) -> Result<Option<&[u8]>> {
    let mut rest = objects;
    while let Some((&object_id, after_id)) = rest.split_first() {
        let (&length, after_length) = after_id.split_first().ok_or(Error::Truncated)?;
        let length = usize::from(length);
        let value = after_length.get(..length).ok_or(Error::Truncated)?;
        if object_id == id {
            return Ok(Some(value));
        }
        rest = after_length.get(length..).unwrap_or(&[]);
    }
    Ok(None)
}

/// The model named by a Read Device Identification reply, from its product-code object.
/// `Ok(None)` when the reply has no product code or Table 2 does not list it.
pub fn model_from_device_id(reply: &DeviceIdentification<'_>) -> Result<Option<PowerSupplyModel>> {
    Ok(find_object(reply.objects, PRODUCT_CODE_OBJECT)?.and_then(model_from_product_code))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_2() {
        // Hex column of Table 2, decoded.
        let rows: [(&[u8], PowerSupplyModel, AddressingSystem); 5] = [
            (
                &[0x30, 0x38, 0x31, 0x32, 0x38, 0x38],
                PowerSupplyModel::Powermax45Xp,
                AddressingSystem::Legacy,
            ),
            (
                &[0x30, 0x38, 0x31, 0x32, 0x32, 0x33],
                PowerSupplyModel::Powermax65_85_105,
                AddressingSystem::Legacy,
            ),
            (
                &[0x30, 0x38, 0x31, 0x32, 0x35, 0x31],
                PowerSupplyModel::Powermax125,
                AddressingSystem::Legacy,
            ),
            (
                &[0x30, 0x38, 0x31, 0x33, 0x33, 0x35],
                PowerSupplyModel::Powermax65_85_105Sync,
                AddressingSystem::Sync,
            ),
            (
                &[0x30, 0x38, 0x31, 0x33, 0x37, 0x34],
                PowerSupplyModel::Powermax45Sync,
                AddressingSystem::Sync,
            ),
        ];
        for (code, model, addressing) in rows {
            assert_eq!(model_from_product_code(code), Some(model));
            assert_eq!(model.addressing(), addressing);
            assert_eq!(model.product_code().as_bytes(), code);
        }
        assert_eq!(
            model_from_product_code(b"081335\0\0 "),
            Some(PowerSupplyModel::Powermax65_85_105Sync)
        );
        assert_eq!(model_from_product_code(b" 081335"), None);
        assert_eq!(model_from_product_code(b"08133"), None);
        assert_eq!(model_from_product_code(b""), None);
        assert_eq!(model_from_product_code(b"\0\0"), None);
    }

    #[test]
    fn sync_model_family() {
        assert_eq!(
            PowerSupplyModel::from(SyncModel::Powermax105_Csa200_600),
            PowerSupplyModel::Powermax65_85_105Sync
        );
        assert_eq!(
            PowerSupplyModel::from(SyncModel::Powermax45_Csa480),
            PowerSupplyModel::Powermax45Sync
        );
        for (_, model, _) in crate::powermax::SYNC_MODELS.iter() {
            assert_eq!(
                PowerSupplyModel::from(*model).addressing(),
                AddressingSystem::Sync
            );
        }
    }

    #[test]
    fn guide_example() {
        // Request :012B0E0401C1 (LRC verified).
        assert_eq!(
            read_product_code(),
            Request::ReadDeviceIdentification {
                code: DeviceIdCode::Specific,
                object_id: 0x01
            }
        );
        // Response :012B0E0481000101010630383133333504: code 04, conformity 0x81, no more
        // follows, next object 0x01, 1 object: id 0x01, length 6, "081335".
        let reply = DeviceIdentification {
            code: DeviceIdCode::Specific,
            conformity: 0x81,
            more_follows: false,
            next_object_id: 0x01,
            object_count: 1,
            objects: &[0x01, 0x06, 0x30, 0x38, 0x31, 0x33, 0x33, 0x35],
        };
        assert_eq!(
            model_from_device_id(&reply),
            Ok(Some(PowerSupplyModel::Powermax65_85_105Sync))
        );
    }

    #[test]
    fn object_list() {
        let list = [
            0x00, 0x02, b'H', b'T', 0x01, 0x03, b'a', b'b', b'c', 0x02, 0x00,
        ];
        assert_eq!(find_object(&list, 0x00), Ok(Some(&b"HT"[..])));
        assert_eq!(find_object(&list, 0x01), Ok(Some(&b"abc"[..])));
        assert_eq!(find_object(&list, 0x02), Ok(Some(&b""[..])));
        assert_eq!(find_object(&list, 0x03), Ok(None));
        assert_eq!(find_object(&[], 0x01), Ok(None));
        assert_eq!(find_object(&[0x00], 0x01), Err(Error::Truncated));
        assert_eq!(find_object(&[0x00, 0x05, 1], 0x01), Err(Error::Truncated));
    }
}
