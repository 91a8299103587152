//! SYNC cartridge data: UID (0x3030-0x3037), part number (0x3038-0x303A, Table 5), usage
//! counters (0x3040-0x3043) and name (0x3048-0x304D, Table 7).
//!
//! Text registers carry two ASCII bytes each, the first byte in the high half.

use super::fault::SyncModels;
use super::plan::{bytes, need, word};
use crate::Result;
use crate::modbus_ascii::Registers;

/// The text of `bytes` up to the first NUL, if it is ASCII.
fn ascii_until_nul(bytes: &[u8]) -> Option<&str> {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    let text = bytes.get(..end)?;
    if text.is_ascii() {
        core::str::from_utf8(text).ok()
    } else {
        None
    }
}

/// The 16-character cartridge UID (0x3030-0x3037); all zero bytes means the cartridge could not
/// be read (communication or radio-frequency failure).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CartridgeUid(pub [u8; 16]);

impl CartridgeUid {
    /// Registers in the UID.
    pub const REGISTERS: usize = 8;

    /// Decodes 8 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        bytes(&registers, 0).map(CartridgeUid)
    }

    /// True when every byte is zero (the guide's "cartridge communication failure").
    pub fn is_read_failure(&self) -> bool {
        self.0.iter().all(|&b| b == 0)
    }

    /// The UID text, if ASCII (up to the first NUL).
    pub fn as_str(&self) -> Option<&str> {
        ascii_until_nul(&self.0)
    }
}

/// The 6-character cartridge part number (0x3038-0x303A), e.g. `428936`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PartNumber(pub [u8; 6]);

impl PartNumber {
    /// Registers in the part number.
    pub const REGISTERS: usize = 3;

    /// Decodes 3 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        bytes(&registers, 0).map(PartNumber)
    }

    /// True for Table 5's "cartridge communication failure or radio frequency error" row.
    /// The table shows it as hex `000000000000` (NUL bytes) but also as ASCII `000000`; both
    /// spellings are accepted.
    pub fn is_read_failure(&self) -> bool {
        self.0.iter().all(|&b| b == 0) || &self.0 == b"000000"
    }

    /// The part number text, if ASCII (up to the first NUL).
    pub fn as_str(&self) -> Option<&str> {
        ascii_until_nul(&self.0)
    }

    /// The Table 5 row for this part number.
    pub fn cartridge_type(&self) -> Option<&'static CartridgeType> {
        CARTRIDGE_TYPES
            .iter()
            .find(|row| row.part_number.as_bytes() == self.0)
    }
}

/// What a cartridge is for, from its part number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CartridgeProcess {
    /// Cut.
    Cut,
    /// FineCut.
    FineCut,
    /// Maximum-control gouging.
    MaxControlGouge,
    /// Maximum-removal gouging.
    MaxRemovalGouge,
}

/// One row of Table 5 "Machine torch cartridge type".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CartridgeType {
    /// Part number text.
    pub part_number: &'static str,
    /// Process.
    pub process: CartridgeProcess,
    /// The current ratings the table names (e.g. `[65, 85]` for "65 A / 85 A").
    pub rated_amps: &'static [u16],
    /// Models the row is restricted to.
    pub models: SyncModels,
    /// The table's text.
    pub description: &'static str,
}

const fn cartridge(
    part_number: &'static str,
    process: CartridgeProcess,
    rated_amps: &'static [u16],
    models: SyncModels,
    description: &'static str,
) -> CartridgeType {
    CartridgeType {
        part_number,
        process,
        rated_amps,
        models,
        description,
    }
}

/// Table 5, the 10 cartridge rows in table order (its 11th row, all zero, is
/// [`PartNumber::is_read_failure`]).
pub static CARTRIDGE_TYPES: [CartridgeType; 10] = {
    use CartridgeProcess::*;
    use SyncModels::{All, Powermax65_85_105};
    [
        cartridge("428936", Cut, &[105], All, "Cut: 105 A cartridge"),
        cartridge("428934", Cut, &[85], All, "Cut: 85 A cartridge"),
        cartridge("428930", Cut, &[65], All, "Cut: 65 A cartridge"),
        cartridge("428925", Cut, &[45], All, "Cut: 45 A cartridge"),
        cartridge("428926", FineCut, &[45], All, "FineCut: 45 A cartridge"),
        cartridge(
            "428939",
            MaxControlGouge,
            &[105],
            All,
            "Max Control gouge: 105 A cartridge",
        ),
        cartridge(
            "428933",
            MaxControlGouge,
            &[65, 85],
            All,
            "Max Control gouge: 65 A / 85 A cartridge",
        ),
        cartridge(
            "428929",
            MaxControlGouge,
            &[45],
            Powermax65_85_105,
            "Max Control gouge: 45 A cartridge (Powermax65/85/105 SYNC only)",
        ),
        cartridge(
            "428938",
            MaxRemovalGouge,
            &[105],
            All,
            "Max Removal gouge: 105 A cartridge",
        ),
        cartridge(
            "428932",
            MaxRemovalGouge,
            &[45, 65, 85],
            All,
            "Max Removal gouge: 45 A / 65 A / 85 A cartridge",
        ),
    ]
};

/// Cartridge usage counters (0x3040-0x3043), each 16 bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CartridgeCounters {
    /// Pilot arc starts (0x3040).
    pub starts: u16,
    /// Cumulative pilot arc time in seconds (0x3041).
    pub pilot_arc_seconds: u16,
    /// Arc transfers (0x3042).
    pub transfers: u16,
    /// Cumulative arc transfer time in counts of 2 seconds (0x3043).
    pub transfer_time_counts: u16,
}

impl CartridgeCounters {
    /// Registers in the counters.
    pub const REGISTERS: usize = 4;

    /// Decodes 4 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        need(&registers, Self::REGISTERS)?;
        Ok(CartridgeCounters {
            starts: word(&registers, 0)?,
            pilot_arc_seconds: word(&registers, 1)?,
            transfers: word(&registers, 2)?,
            transfer_time_counts: word(&registers, 3)?,
        })
    }

    /// Cumulative arc transfer time in seconds (each count is 2 s).
    pub const fn transfer_seconds(&self) -> u32 {
        self.transfer_time_counts as u32 * 2
    }
}

/// The 12-byte cartridge name (0x3048-0x304D), NUL padded, e.g. `C MECH`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CartridgeName(pub [u8; 12]);

impl CartridgeName {
    /// Registers in the name.
    pub const REGISTERS: usize = 6;

    /// Decodes 6 registers.
    pub fn decode(registers: Registers<'_>) -> Result<Self> {
        bytes(&registers, 0).map(CartridgeName)
    }

    /// The name up to the first NUL, if ASCII.
    pub fn as_str(&self) -> Option<&str> {
        ascii_until_nul(&self.0)
    }

    /// The Table 7 row for this name.
    pub fn info(&self) -> Option<&'static CartridgeNameInfo> {
        let name = self.as_str()?;
        CARTRIDGE_NAMES.iter().find(|row| row.name == name)
    }
}

/// One row of Table 7 "Cartridge names".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CartridgeNameInfo {
    /// The name as read (without NUL padding).
    pub name: &'static str,
    /// What it stands for.
    pub description: &'static str,
    /// Models the row is restricted to (rows marked "*Powermax65/85/105").
    pub models: SyncModels,
}

/// Table 7, all 7 rows in table order.
pub static CARTRIDGE_NAMES: [CartridgeNameInfo; 7] = {
    const fn n(
        name: &'static str,
        description: &'static str,
        models: SyncModels,
    ) -> CartridgeNameInfo {
        CartridgeNameInfo {
            name,
            description,
            models,
        }
    }
    use SyncModels::{All, Powermax65_85_105};
    [
        n("C MECH", "Standard Mechanized Cutting", All),
        n("C MFNC", "FineCut Mechanized Cutting", All),
        n("G CNTL", "Maximum Control Gouging", Powermax65_85_105),
        n("G RMVL", "Maximum Removal Gouging", All),
        n("C HAND", "Drag Hand Cutting", All),
        n("C HFNC", "FineCut Hand Cutting", All),
        n("C FLUSH", "FlushCut Cutting", Powermax65_85_105),
    ]
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    #[test]
    fn uid_example() {
        // Response :0104104530303430314430303336464232354471 (LRC checked: 0x71).
        let data = [
            0x45, 0x30, 0x30, 0x34, 0x30, 0x31, 0x44, 0x30, 0x30, 0x33, 0x36, 0x46, 0x42, 0x32,
            0x35, 0x44,
        ];
        let uid = CartridgeUid::decode(Registers::BigEndian(&data)).unwrap();
        assert_eq!(uid.as_str(), Some("E00401D0036FB25D"));
        assert!(!uid.is_read_failure());
        assert!(CartridgeUid([0; 16]).is_read_failure());
        assert_eq!(
            CartridgeUid::decode(Registers::BigEndian(&data[..14])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn part_number_example() {
        // Response :010406343238393336B5 -> 428936 = Cut: 105 A cartridge.
        let pn = PartNumber::decode(Registers::BigEndian(&[0x34, 0x32, 0x38, 0x39, 0x33, 0x36]))
            .unwrap();
        assert_eq!(pn.as_str(), Some("428936"));
        let row = pn.cartridge_type().unwrap();
        assert_eq!(row.process, CartridgeProcess::Cut);
        assert_eq!(row.rated_amps, &[105]);
        assert!(!pn.is_read_failure());
        assert!(PartNumber([0; 6]).is_read_failure());
        assert!(PartNumber(*b"000000").is_read_failure());
        assert_eq!(PartNumber([0; 6]).cartridge_type(), None);
        assert_eq!(
            PartNumber::decode(Registers::Words(&[0x3432, 0x3839])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn part_number_table() {
        for row in CARTRIDGE_TYPES.iter() {
            let mut raw = [0u8; 6];
            raw.copy_from_slice(row.part_number.as_bytes());
            assert_eq!(PartNumber(raw).cartridge_type(), Some(row));
            assert!(row.description.contains(" A cartridge"));
            for amps in row.rated_amps {
                let mut buf = heapless::String::<8>::new();
                core::fmt::write(&mut buf, format_args!("{amps} A")).unwrap();
                assert!(
                    row.description.contains(buf.as_str()),
                    "{}",
                    row.description
                );
            }
        }
        let mut numbers: heapless::Vec<&str, 10> =
            CARTRIDGE_TYPES.iter().map(|r| r.part_number).collect();
        numbers.sort_unstable();
        assert!(numbers.windows(2).all(|w| w[0] != w[1]));
    }

    #[test]
    fn counters_example() {
        // Response :01040800D6000900D3098FA9: 214 starts, 9 s pilot arc, 211 transfers,
        // 2447 x 2 = 4894 s of transfer.
        let c = CartridgeCounters::decode(Registers::BigEndian(&[
            0x00, 0xD6, 0x00, 0x09, 0x00, 0xD3, 0x09, 0x8F,
        ]))
        .unwrap();
        assert_eq!(c.starts, 214);
        assert_eq!(c.pilot_arc_seconds, 9);
        assert_eq!(c.transfers, 211);
        assert_eq!(c.transfer_time_counts, 2447);
        assert_eq!(c.transfer_seconds(), 4894);
        assert_eq!(
            CartridgeCounters::decode(Registers::Words(&[1, 2, 3])),
            Err(Error::Truncated)
        );
    }

    #[test]
    fn name_example_and_table() {
        // Response as printed: :01040C43204D45434800000000000006F has one 0 too many (27
        // characters of data+LRC for 12 bytes + LRC); corrected, LRC verified:
        // :01040C43204D4543480000000000006F -> "C MECH" = Standard Mechanized Cutting.
        let data = [0x43, 0x20, 0x4D, 0x45, 0x43, 0x48, 0, 0, 0, 0, 0, 0];
        let name = CartridgeName::decode(Registers::BigEndian(&data)).unwrap();
        assert_eq!(name.as_str(), Some("C MECH"));
        assert_eq!(
            name.info().unwrap().description,
            "Standard Mechanized Cutting"
        );
        // Every Table 7 row, from its hex column.
        let hex_rows: [(&[u8; 12], &str); 7] = [
            (b"C MECH\0\0\0\0\0\0", "Standard Mechanized Cutting"),
            (b"C MFNC\0\0\0\0\0\0", "FineCut Mechanized Cutting"),
            (b"G CNTL\0\0\0\0\0\0", "Maximum Control Gouging"),
            (b"G RMVL\0\0\0\0\0\0", "Maximum Removal Gouging"),
            (b"C HAND\0\0\0\0\0\0", "Drag Hand Cutting"),
            (b"C HFNC\0\0\0\0\0\0", "FineCut Hand Cutting"),
            (b"C FLUSH\0\0\0\0\0", "FlushCut Cutting"),
        ];
        for (raw, description) in hex_rows {
            assert_eq!(CartridgeName(*raw).info().unwrap().description, description);
        }
        assert_eq!(
            CartridgeName(*b"G CNTL\0\0\0\0\0\0").info().unwrap().models,
            SyncModels::Powermax65_85_105
        );
        assert_eq!(CartridgeName([0; 12]).info(), None);
        assert_eq!(CartridgeName([0xFF; 12]).as_str(), None);
    }
}
