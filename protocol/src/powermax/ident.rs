//! Torch, torch lead and power-supply ids: SYNC register 0x3000 (Tables 3 and 4) and the legacy
//! torch-lead coils 0x0808/0x0809.

use super::fault::SyncModels;
use crate::{Error, Result};

/// Torch lead length class. Both guides use the same three classes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LeadLength {
    /// Up to 7.6 m: 25 ft hand-torch lead, 15-25 ft machine-torch lead.
    Upto7m6,
    /// Up to 15 m: 50 ft hand-torch lead, 35-50 ft machine-torch lead.
    Upto15m,
    /// Up to 23 m: 75 ft lead.
    Upto23m,
}

impl LeadLength {
    /// From the legacy `torch_index` coils (read 2 coils from 0x0808): bit 0 is 0x0808, bit 1 is
    /// 0x0809; 00 = 15-25 ft, 01 = 35-50 ft, 10 = 75 ft. 11 is not listed: [`Error::Malformed`].
    pub fn from_legacy_coils(bits: &[u8]) -> Result<Self> {
        let byte = bits.first().ok_or(Error::Truncated)?;
        match byte & 0b11 {
            0b00 => Ok(LeadLength::Upto7m6),
            0b01 => Ok(LeadLength::Upto15m),
            0b10 => Ok(LeadLength::Upto23m),
            _ => Err(Error::Malformed),
        }
    }

    /// The two `torch_index` coils as a legacy unit answers them: bit 0 is 0x0808, bit 1 is
    /// 0x0809 (the inverse of [`LeadLength::from_legacy_coils`]).
    pub const fn legacy_coils(self) -> u8 {
        match self {
            LeadLength::Upto7m6 => 0b00,
            LeadLength::Upto15m => 0b01,
            LeadLength::Upto23m => 0b10,
        }
    }

    /// The longest lead of the class, in feet (25, 50, 75): what a cut chart is chosen by.
    pub const fn max_feet(self) -> u8 {
        match self {
            LeadLength::Upto7m6 => 25,
            LeadLength::Upto15m => 50,
            LeadLength::Upto23m => 75,
        }
    }
}

/// Hand or machine torch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TorchKind {
    /// Hand torch.
    Hand,
    /// Machine (mechanized) torch.
    Machine,
}

/// High byte of 0x3000 (Table 3 "Torch type and lead length").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TorchType {
    /// Hand or machine torch.
    pub kind: TorchKind,
    /// Lead length class.
    pub lead: LeadLength,
}

/// The manual's description for a host tool; empty without the `descriptions` feature (the
/// board never prints these, so its image leaves them out).
const fn host_text(text: &'static str) -> &'static str {
    if cfg!(feature = "descriptions") {
        text
    } else {
        ""
    }
}

/// Table 3, all 6 rows: (id, torch, description; the description is empty without the
/// `descriptions` feature).
pub static TORCH_TYPES: [(u8, TorchType, &str); 6] = [
    (
        0x00,
        torch(TorchKind::Hand, LeadLength::Upto7m6),
        host_text("Hand torch with 7.6 m (25-foot) lead"),
    ),
    (
        0x01,
        torch(TorchKind::Hand, LeadLength::Upto15m),
        host_text("Hand torch with 15 m (50-foot) lead"),
    ),
    (
        0x02,
        torch(TorchKind::Hand, LeadLength::Upto23m),
        host_text("Hand torch with 23 m (75-foot) lead"),
    ),
    (
        0x04,
        torch(TorchKind::Machine, LeadLength::Upto7m6),
        host_text("Machine torch with 4.6 m - 7.6 m (15-foot - 25-foot) lead"),
    ),
    (
        0x05,
        torch(TorchKind::Machine, LeadLength::Upto15m),
        host_text("Machine torch with 10.7 m - 15 m (35-foot - 50-foot) lead"),
    ),
    (
        0x06,
        torch(TorchKind::Machine, LeadLength::Upto23m),
        host_text("Machine torch with 23 m (75-foot) lead"),
    ),
];

const fn torch(kind: TorchKind, lead: LeadLength) -> TorchType {
    TorchType { kind, lead }
}

impl TorchType {
    /// Looks up a torch id (Table 3).
    pub fn from_id(id: u8) -> Option<Self> {
        TORCH_TYPES
            .iter()
            .find(|(i, _, _)| *i == id)
            .map(|(_, t, _)| *t)
    }

    /// The id byte.
    pub fn id(self) -> u8 {
        TORCH_TYPES
            .iter()
            .find(|(_, t, _)| *t == self)
            .map_or(0xFF, |(i, _, _)| *i)
    }

    /// Table 3's description.
    #[cfg(feature = "descriptions")]
    pub fn description(self) -> &'static str {
        TORCH_TYPES
            .iter()
            .find(|(_, t, _)| *t == self)
            .map_or("", |(_, _, d)| *d)
    }
}

/// Low byte of 0x3000 (Table 4 "Plasma power supply type").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[allow(non_camel_case_types)]
pub enum SyncModel {
    /// 0x00 Powermax65 SYNC 200 V - 600 V CSA.
    Powermax65_Csa200_600,
    /// 0x01 Powermax65 SYNC 380 V CCC / 400 V CE.
    Powermax65_Ccc380_Ce400,
    /// 0x02 Powermax85 SYNC 200 V - 600 V CSA.
    Powermax85_Csa200_600,
    /// 0x03 Powermax85 SYNC 380 V CCC / 400 V CE.
    Powermax85_Ccc380_Ce400,
    /// 0x08 Powermax105 SYNC 200 V - 600 V CSA.
    Powermax105_Csa200_600,
    /// 0x09 Powermax105 SYNC 230 V - 400 V CE.
    Powermax105_Ce230_400,
    /// 0x0A Powermax105 SYNC 380 V CCC / 400 V CE.
    Powermax105_Ccc380_Ce400,
    /// 0x11 Powermax45 SYNC 230 V CSA and CE.
    Powermax45_Csa_Ce230,
    /// 0x12 Powermax45 SYNC 400 V CE.
    Powermax45_Ce400,
    /// 0x13 Powermax45 SYNC 480 V CSA.
    Powermax45_Csa480,
}

/// Table 4, all 10 rows: (id, model, description; the description is empty without the
/// `descriptions` feature).
pub static SYNC_MODELS: [(u8, SyncModel, &str); 10] = [
    (
        0x00,
        SyncModel::Powermax65_Csa200_600,
        host_text("Powermax65 SYNC 200 V - 600 V CSA"),
    ),
    (
        0x01,
        SyncModel::Powermax65_Ccc380_Ce400,
        host_text("Powermax65 SYNC 380 V CCC / 400 V CE"),
    ),
    (
        0x02,
        SyncModel::Powermax85_Csa200_600,
        host_text("Powermax85 SYNC 200 V - 600 V CSA"),
    ),
    (
        0x03,
        SyncModel::Powermax85_Ccc380_Ce400,
        host_text("Powermax85 SYNC 380 V CCC / 400 V CE"),
    ),
    (
        0x08,
        SyncModel::Powermax105_Csa200_600,
        host_text("Powermax105 SYNC 200 V - 600 V CSA"),
    ),
    (
        0x09,
        SyncModel::Powermax105_Ce230_400,
        host_text("Powermax105 SYNC 230 V - 400 V CE"),
    ),
    (
        0x0A,
        SyncModel::Powermax105_Ccc380_Ce400,
        host_text("Powermax105 SYNC 380 V CCC / 400 V CE"),
    ),
    (
        0x11,
        SyncModel::Powermax45_Csa_Ce230,
        host_text("Powermax45 SYNC 230 V CSA and CE"),
    ),
    (
        0x12,
        SyncModel::Powermax45_Ce400,
        host_text("Powermax45 SYNC 400 V CE"),
    ),
    (
        0x13,
        SyncModel::Powermax45_Csa480,
        host_text("Powermax45 SYNC 480 V CSA"),
    ),
];

impl SyncModel {
    /// Looks up a type id (Table 4).
    pub fn from_id(id: u8) -> Option<Self> {
        SYNC_MODELS
            .iter()
            .find(|(i, _, _)| *i == id)
            .map(|(_, m, _)| *m)
    }

    /// The type id byte.
    pub fn id(self) -> u8 {
        SYNC_MODELS
            .iter()
            .find(|(_, m, _)| *m == self)
            .map_or(0xFF, |(i, _, _)| *i)
    }

    /// Table 4's description.
    #[cfg(feature = "descriptions")]
    pub fn description(self) -> &'static str {
        SYNC_MODELS
            .iter()
            .find(|(_, m, _)| *m == self)
            .map_or("", |(_, _, d)| *d)
    }

    /// The number in the model name: 45, 65, 85 or 105.
    pub const fn size(self) -> u16 {
        match self {
            SyncModel::Powermax65_Csa200_600 | SyncModel::Powermax65_Ccc380_Ce400 => 65,
            SyncModel::Powermax85_Csa200_600 | SyncModel::Powermax85_Ccc380_Ce400 => 85,
            SyncModel::Powermax105_Csa200_600
            | SyncModel::Powermax105_Ce230_400
            | SyncModel::Powermax105_Ccc380_Ce400 => 105,
            SyncModel::Powermax45_Csa_Ce230
            | SyncModel::Powermax45_Ce400
            | SyncModel::Powermax45_Csa480 => 45,
        }
    }

    /// The table-restriction family this model belongs to (Powermax45 SYNC or 65/85/105 SYNC).
    pub const fn family(self) -> SyncModels {
        if self.size() == 45 {
            SyncModels::Powermax45
        } else {
            SyncModels::Powermax65_85_105
        }
    }
}

impl SyncModels {
    /// True when a row restricted to `self` applies to `model`.
    pub const fn includes(self, model: SyncModel) -> bool {
        match self {
            SyncModels::All => true,
            SyncModels::Powermax65_85_105 => model.size() != 45,
            SyncModels::Powermax45 => model.size() == 45,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_consistent() {
        for (id, t, _) in TORCH_TYPES.iter() {
            assert_eq!(TorchType::from_id(*id), Some(*t));
            assert_eq!(t.id(), *id);
        }
        for (id, m, d) in SYNC_MODELS.iter() {
            assert_eq!(SyncModel::from_id(*id), Some(*m));
            assert_eq!(m.id(), *id);
            if !cfg!(feature = "descriptions") {
                assert_eq!(*d, "");
                continue;
            }
            assert!(d.starts_with("Powermax"));
            let size = m.size();
            let name_size = match size {
                45 => "Powermax45 ",
                65 => "Powermax65 ",
                85 => "Powermax85 ",
                _ => "Powermax105 ",
            };
            assert!(d.starts_with(name_size), "{d}");
        }
        assert_eq!(TorchType::from_id(0x03), None);
        assert_eq!(SyncModel::from_id(0x04), None);
        assert_eq!(SyncModel::from_id(0x10), None);
    }

    #[test]
    fn manual_example_0508() {
        // 0x0508: machine torch 35-50 ft lead, Powermax105 SYNC 200-600 V CSA.
        assert_eq!(
            TorchType::from_id(0x05),
            Some(TorchType {
                kind: TorchKind::Machine,
                lead: LeadLength::Upto15m
            })
        );
        let model = SyncModel::from_id(0x08).unwrap();
        assert_eq!(model, SyncModel::Powermax105_Csa200_600);
        assert_eq!(model.size(), 105);
        assert_eq!(model.family(), SyncModels::Powermax65_85_105);
        assert!(SyncModels::Powermax65_85_105.includes(model));
        assert!(!SyncModels::Powermax45.includes(model));
    }

    #[test]
    fn legacy_lead_coils() {
        // Legacy guide: :01010100FD 15-25 ft, :01010101FC 35-50 ft, :01010102FB 75 ft.
        assert_eq!(
            LeadLength::from_legacy_coils(&[0x00]),
            Ok(LeadLength::Upto7m6)
        );
        assert_eq!(
            LeadLength::from_legacy_coils(&[0x01]),
            Ok(LeadLength::Upto15m)
        );
        assert_eq!(
            LeadLength::from_legacy_coils(&[0x02]),
            Ok(LeadLength::Upto23m)
        );
        assert_eq!(
            LeadLength::from_legacy_coils(&[0x03]),
            Err(Error::Malformed)
        );
        assert_eq!(LeadLength::from_legacy_coils(&[]), Err(Error::Truncated));
        // Bits above the two coils read are padding.
        assert_eq!(
            LeadLength::from_legacy_coils(&[0xFC]),
            Ok(LeadLength::Upto7m6)
        );
        for lead in [
            LeadLength::Upto7m6,
            LeadLength::Upto15m,
            LeadLength::Upto23m,
        ] {
            assert_eq!(
                LeadLength::from_legacy_coils(&[lead.legacy_coils()]),
                Ok(lead)
            );
        }
        // The classes' longest leads, in feet, as both guides name them.
        assert_eq!(
            [
                LeadLength::Upto7m6,
                LeadLength::Upto15m,
                LeadLength::Upto23m
            ]
            .map(LeadLength::max_feet),
            [25, 50, 75]
        );
    }
}
