//! Gas type codes (manual section VI), used by 095, 096, 098, 122, 137 and the MaxPro200
//! form of 079.
//!
//! Revision N changed gas type 7 from CO2 to Argon; this table follows revision N.

/// A gas type code. Kept as a number so an unknown code in a reply still parses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GasCode(pub u16);

impl GasCode {
    /// 0: no gas (an invalid gas type).
    pub const NO_GAS: GasCode = GasCode(0);
    /// 1: oxygen.
    pub const OXYGEN: GasCode = GasCode(1);
    /// 2: methane (CH4).
    pub const METHANE: GasCode = GasCode(2);
    /// 3: H35 (argon-hydrogen).
    pub const H35: GasCode = GasCode(3);
    /// 4: H5.
    pub const H5: GasCode = GasCode(4);
    /// 5: air.
    pub const AIR: GasCode = GasCode(5);
    /// 6: nitrogen.
    pub const NITROGEN: GasCode = GasCode(6);
    /// 7: argon (CO2 before revision N).
    pub const ARGON: GasCode = GasCode(7);
    /// 8: N95.
    pub const N95: GasCode = GasCode(8);
    /// 9: N2 channel 1 (internal marking mode, not used by a CNC).
    pub const N2_CHANNEL_1: GasCode = GasCode(9);
    /// 10: N2 channel 2 (internal marking mode, not used by a CNC).
    pub const N2_CHANNEL_2: GasCode = GasCode(10);
    /// 11: F5.
    pub const F5: GasCode = GasCode(11);
    /// 12: Ar-Air (internal marking mode, not used by a CNC).
    pub const AR_AIR: GasCode = GasCode(12);
    /// Highest code in the table.
    pub const MAX: u16 = 12;

    /// Name from section VI, if the manual lists this code.
    pub fn name(self) -> Option<&'static str> {
        gas_name(self.0)
    }

    /// True if the manual lists this code.
    pub fn is_known(self) -> bool {
        self.0 <= Self::MAX
    }
}

/// One row of the gas table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GasInfo {
    /// Code number.
    pub code: u16,
    /// Gas type as printed.
    pub name: &'static str,
    /// Notes column, if any.
    pub note: Option<&'static str>,
}

const fn gas(code: u16, name: &'static str, note: Option<&'static str>) -> GasInfo {
    GasInfo { code, name, note }
}

const MARKING_N2: Option<&str> = Some("Internal N2 marking mode, not used by CNC");

/// Section VI, ascending code (the index equals the code).
pub const GAS_TYPES: &[GasInfo] = &[
    gas(0, "No Gas", Some("Invalid gas type")),
    gas(1, "Oxygen", None),
    gas(2, "Methane (CH4)", None),
    gas(
        3,
        "H35 (Argon - Hydrogen)",
        Some("Use H35 as plasma gas and N2 as shield gas for H35/N2 mixed plasma gas processes"),
    ),
    gas(4, "H5", None),
    gas(5, "Air", None),
    gas(6, "Nitrogen", None),
    // Revision N: "Gas type #7 changed from CO2 to Argon".
    gas(7, "Argon", None),
    gas(8, "N95", None),
    gas(9, "N2 Channel 1", MARKING_N2),
    gas(10, "N2 Channel 2", MARKING_N2),
    gas(11, "F5", None),
    gas(
        12,
        "Ar-Air",
        Some("Internal Ar marking mode, not used by CNC"),
    ),
];

/// The table row for `code`, if the manual lists it.
pub fn gas_info(code: u16) -> Option<&'static GasInfo> {
    GAS_TYPES.get(usize::from(code))
}

/// Name of gas `code`, if the manual lists it.
pub fn gas_name(code: u16) -> Option<&'static str> {
    gas_info(code).map(|g| g.name)
}

/// Note for gas `code`, if the manual gives one.
pub fn gas_note(code: u16) -> Option<&'static str> {
    gas_info(code).and_then(|g| g.note)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table() {
        assert!(
            GAS_TYPES
                .iter()
                .enumerate()
                .all(|(i, g)| usize::from(g.code) == i)
        );
        assert_eq!(GAS_TYPES.len(), usize::from(GasCode::MAX) + 1);
        assert_eq!(GasCode::ARGON.name(), Some("Argon"));
        assert_eq!(gas_name(6), Some("Nitrogen"));
        assert_eq!(
            gas_note(9),
            Some("Internal N2 marking mode, not used by CNC")
        );
        assert_eq!(gas_note(1), None);
        assert_eq!(gas_name(13), None);
        assert!(!GasCode(13).is_known() && GasCode(12).is_known());
    }
}
