//! The unit's model as one byte, for what is stored (a history entry's model code), and its
//! name as the CNC reads it (`STATUS model=`, `!LINK UP`, `HISTORY model=`).
//!
//! [`MODEL_NAMES`] is the one table: code `n` is `MODEL_NAMES[n - 1]`, 0 is "none known".
//! Codes are kept in flash, so the table only grows at its end: a code never changes meaning.

use plasma_protocol::hpr::{HprRating, SystemId};
use plasma_protocol::powermax::PowerSupplyModel;
use plasma_protocol::powermax::sync::Identification;

use super::{Model, UnitStatus};

/// The model names, by code minus one: the code of a name is its place here plus one.
pub const MODEL_NAMES: [&str; 15] = [
    "Powermax",
    "Powermax45XP",
    "Powermax65/85/105",
    "Powermax125",
    "Powermax45",
    "Powermax65",
    "Powermax85",
    "Powermax105",
    "MaxPro200",
    "HPR130",
    "HPR130XD",
    "HPR260",
    "HPR260XD",
    "HPR400",
    "HPR400XD",
];

/// The code of the name at `index` of [`MODEL_NAMES`] (a constant below the table's length).
const fn code(index: usize) -> u8 {
    index as u8 + 1
}

/// The model code of the unit `status` describes: 0 while none is known. A SYNC unit is
/// named by its exact size once its identification (0x3000) has been read.
pub fn model_code(status: &UnitStatus) -> u8 {
    let size = status
        .identification
        .and_then(|Identification { model, .. }| model)
        .map(|m| m.size());
    let index = match status.model {
        None => return 0,
        Some(Model::PowermaxUnidentified) => 0,
        Some(Model::Powermax(model)) => match (model, size) {
            (
                PowerSupplyModel::Powermax65_85_105Sync | PowerSupplyModel::Powermax45Sync,
                Some(45),
            ) => 4,
            (
                PowerSupplyModel::Powermax65_85_105Sync | PowerSupplyModel::Powermax45Sync,
                Some(65),
            ) => 5,
            (
                PowerSupplyModel::Powermax65_85_105Sync | PowerSupplyModel::Powermax45Sync,
                Some(85),
            ) => 6,
            (
                PowerSupplyModel::Powermax65_85_105Sync | PowerSupplyModel::Powermax45Sync,
                Some(105),
            ) => 7,
            (PowerSupplyModel::Powermax45Xp, _) => 1,
            (PowerSupplyModel::Powermax65_85_105 | PowerSupplyModel::Powermax65_85_105Sync, _) => 2,
            (PowerSupplyModel::Powermax125, _) => 3,
            (PowerSupplyModel::Powermax45Sync, _) => 4,
        },
        Some(Model::Hpr(SystemId::MaxPro200)) => 8,
        Some(Model::Hpr(SystemId::Hpr { rating, xd, .. })) => {
            let base = match rating {
                HprRating::Hpr130 => 9,
                HprRating::Hpr260 => 11,
                HprRating::Hpr400 => 13,
            };
            base + usize::from(xd)
        }
    };
    code(index)
}

/// The name of model `code`; `None` for 0 (none known) or a code this build does not know.
pub fn model_name(code: u8) -> Option<&'static str> {
    MODEL_NAMES.get(usize::from(code).checked_sub(1)?).copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::hpr::GasConsole;
    use plasma_protocol::powermax::SyncModel;

    /// The code of the model named `name` (as [`model_name`] gives it).
    fn model_code_of(name: &str) -> Option<u8> {
        MODEL_NAMES.iter().position(|&n| n == name).map(code)
    }

    fn status(model: Option<Model>, sync: Option<SyncModel>) -> UnitStatus {
        UnitStatus {
            model,
            identification: sync.map(|model| Identification {
                raw: 0,
                torch: None,
                model: Some(model),
            }),
            ..UnitStatus::default()
        }
    }

    #[test]
    fn every_code_names_one_model_and_back() {
        assert_eq!(model_name(0), None);
        for (index, name) in MODEL_NAMES.iter().enumerate() {
            let code = code(index);
            assert_eq!(model_name(code), Some(*name));
            assert_eq!(model_code_of(name), Some(code), "{name}");
        }
        assert_eq!(model_name(code(MODEL_NAMES.len())), None);
        assert_eq!(model_code_of(""), None);
        assert_eq!(model_code_of("Powermax 65"), None);
    }

    #[test]
    fn every_unit_the_link_finds_has_its_code() {
        let sync = Some(Model::Powermax(PowerSupplyModel::Powermax65_85_105Sync));
        let hpr = |rating, xd| {
            Some(Model::Hpr(SystemId::Hpr {
                rating,
                xd,
                console: Some(GasConsole::Manual),
            }))
        };
        let cases = [
            (status(None, None), None),
            (
                status(Some(Model::PowermaxUnidentified), None),
                Some("Powermax"),
            ),
            (
                status(Some(Model::Powermax(PowerSupplyModel::Powermax45Xp)), None),
                Some("Powermax45XP"),
            ),
            (
                status(
                    Some(Model::Powermax(PowerSupplyModel::Powermax65_85_105)),
                    None,
                ),
                Some("Powermax65/85/105"),
            ),
            (
                status(Some(Model::Powermax(PowerSupplyModel::Powermax125)), None),
                Some("Powermax125"),
            ),
            // SYNC before 0x3000 is read: the Table 2 family; after: the exact size.
            (status(sync, None), Some("Powermax65/85/105")),
            (
                status(
                    Some(Model::Powermax(PowerSupplyModel::Powermax45Sync)),
                    None,
                ),
                Some("Powermax45"),
            ),
            (
                status(sync, Some(SyncModel::Powermax65_Csa200_600)),
                Some("Powermax65"),
            ),
            (
                status(sync, Some(SyncModel::Powermax85_Ccc380_Ce400)),
                Some("Powermax85"),
            ),
            (
                status(sync, Some(SyncModel::Powermax105_Ce230_400)),
                Some("Powermax105"),
            ),
            (
                status(
                    Some(Model::Powermax(PowerSupplyModel::Powermax45Sync)),
                    Some(SyncModel::Powermax45_Ce400),
                ),
                Some("Powermax45"),
            ),
            (
                status(Some(Model::Hpr(SystemId::MaxPro200)), None),
                Some("MaxPro200"),
            ),
            (status(hpr(HprRating::Hpr130, false), None), Some("HPR130")),
            (status(hpr(HprRating::Hpr130, true), None), Some("HPR130XD")),
            (status(hpr(HprRating::Hpr260, false), None), Some("HPR260")),
            (status(hpr(HprRating::Hpr260, true), None), Some("HPR260XD")),
            (status(hpr(HprRating::Hpr400, false), None), Some("HPR400")),
            (status(hpr(HprRating::Hpr400, true), None), Some("HPR400XD")),
        ];
        for (status, name) in &cases {
            assert_eq!(model_name(model_code(status)), *name, "{:?}", status.model);
        }
        // Every name is some unit's.
        for name in MODEL_NAMES {
            assert!(cases.iter().any(|(_, n)| *n == Some(name)), "{name}");
        }
    }
}
