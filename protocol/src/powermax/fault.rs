//! Fault codes: a decimal number shown as `X-YY-Z` (0x01F4 = 500 = 0-50-0).
//!
//! The SYNC guide calls the register a "10-bit effective unsigned binary number", but its own
//! table goes up to 3700 (12 bits), so the whole 16-bit value is kept.

use core::fmt;
use core::str::FromStr;

use super::fault_table::{LEGACY_FAULT_TEXTS, LEGACY_FAULTS, SYNC_FAULT_TEXTS, SYNC_FAULTS};
use crate::text_table::{Text, span};
use crate::{Error, Result};

/// A fault code as read from 0x301A, 0x3044-0x3047 (SYNC) or 0x2098 (legacy).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultCode(pub u16);

/// Whether the SYNC table says the operator must act to clear a fault
/// ("Steps Required to Remove?").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepsRequired {
    /// "Yes": cutting cannot continue until the cause is removed.
    Yes,
    /// "No, but recommended": a notification; cutting may continue.
    Recommended,
    /// "No".
    No,
}

/// Which SYNC models a table row applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SyncModels {
    /// Every Powermax SYNC.
    All,
    /// Powermax65/85/105 SYNC only.
    Powermax65_85_105,
    /// Powermax45 SYNC only.
    Powermax45,
}

/// One row of the SYNC fault table (Table 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultInfo {
    /// The fault code (X-YY-Z as a number). Kept in the row rather than beside it: a
    /// `(code, row)` pair would take 16 bytes of flash per row instead of 12.
    pub code: u16,
    /// The table's description (packed, see [`Text`]).
    pub text: Text,
    /// The table's "Steps Required to Remove?" column.
    pub steps: StepsRequired,
    /// Models the row is restricted to.
    pub models: SyncModels,
}

impl FaultInfo {
    /// True when the fault blocks cutting until someone acts ("Yes" in the table).
    pub const fn action_required(&self) -> bool {
        matches!(self.steps, StepsRequired::Yes)
    }
}

impl FaultCode {
    /// No active fault (0-00-0).
    pub const NONE: FaultCode = FaultCode(0);

    /// True for 0 (no fault).
    pub const fn is_none(self) -> bool {
        self.0 == 0
    }

    /// True for the SYNC table's "internal component faults" (1-00-0 and up).
    pub const fn is_internal_component(self) -> bool {
        self.0 >= 1000
    }

    /// The three displayed fields: `(X, YY, Z)` of `X-YY-Z`.
    pub const fn fields(self) -> (u16, u16, u16) {
        (self.0 / 1000, (self.0 / 10) % 100, self.0 % 10)
    }

    /// The row of the SYNC fault table (Table 6), including 0 = no fault.
    pub fn info(self) -> Option<FaultInfo> {
        let row = SYNC_FAULTS.iter().position(|row| row.code == self.0)?;
        let found = SYNC_FAULTS.get(row)?;
        Some(FaultInfo {
            code: found.code,
            text: span(
                &SYNC_FAULT_TEXTS,
                |row| SYNC_FAULTS.get(row).map(|r| r.end),
                row,
            )?,
            steps: found.steps,
            models: found.models,
        })
    }

    /// What it takes to clear the fault, for a code read from either register family: the
    /// SYNC table's "Steps Required to Remove?" (Table 6: Yes / No, but recommended / No).
    ///
    /// A deliberate choice for the codes the SYNC table does not list: [`StepsRequired::Yes`].
    /// That covers the three codes only the legacy list has (0-12-0 low input gas pressure,
    /// 0-19-0 power board hardware protection, 0-99-0 system hardware fault - service
    /// required), whose list has no action column and calls itself partial, and any code in
    /// neither table. A fault whose consequence no table states is taken to stop cutting, so
    /// the bridge refuses a start rather than fire into it; the SYNC rows nearest them agree
    /// for two of the three (0-19-9 "power PCB hardware protection": Yes; 0-22-0 "no gas
    /// supply input": Yes), and 0-99-0 says service is required.
    pub fn steps_required(self) -> StepsRequired {
        self.info().map_or(StepsRequired::Yes, |info| info.steps)
    }

    /// The description in the legacy Powermax65/85 fault list; 0 reads as "No fault" (the
    /// legacy list has no row for it, the value is the SYNC table's "no active fault").
    pub fn legacy_info(self) -> Option<Text> {
        if self.is_none() {
            return Some(Text::plain("No fault"));
        }
        crate::text_table::text_of(&LEGACY_FAULT_TEXTS, &LEGACY_FAULTS, self.0)
    }
}

impl From<u16> for FaultCode {
    fn from(raw: u16) -> Self {
        FaultCode(raw)
    }
}

impl fmt::Display for FaultCode {
    /// `X-YY-Z`, e.g. `0-50-0`; no fault prints `0-00-0` as the guide writes it.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (x, yy, z) = self.fields();
        write!(f, "{x}-{yy:02}-{z}")
    }
}

impl FromStr for FaultCode {
    type Err = Error;

    /// Parses `X-YY-Z`: X one or more digits, YY exactly two, Z exactly one.
    fn from_str(text: &str) -> Result<Self> {
        let mut parts = text.split('-');
        let (Some(x), Some(yy), Some(z), None) =
            (parts.next(), parts.next(), parts.next(), parts.next())
        else {
            return Err(Error::Malformed);
        };
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        if !digits(x) || yy.len() != 2 || !digits(yy) || z.len() != 1 || !digits(z) {
            return Err(Error::Malformed);
        }
        let mut value: u32 = 0;
        for b in x.bytes() {
            value = value
                .checked_mul(10)
                .and_then(|v| v.checked_add(u32::from(b - b'0')))
                .filter(|&v| v <= 65)
                .ok_or(Error::Malformed)?;
        }
        for b in yy.bytes().chain(z.bytes()) {
            value = value * 10 + u32::from(b - b'0');
        }
        u16::try_from(value)
            .map(FaultCode)
            .map_err(|_| Error::Malformed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::fmt::Write;
    use heapless::String;

    fn text(code: FaultCode) -> String<16> {
        let mut s = String::new();
        write!(s, "{code}").unwrap();
        s
    }

    #[test]
    fn manual_examples() {
        // SYNC 0x301A example: 0x01F4 = 500 = 0-50-0.
        let code = FaultCode(0x01F4);
        assert_eq!(text(code).as_str(), "0-50-0");
        assert_eq!(code.fields(), (0, 50, 0));
        assert!(code.info().unwrap().action_required());
        // Fault log example: 0x0079 = 121 = 0-12-1 "output gas pressure is low".
        let code = FaultCode(0x0079);
        assert_eq!(text(code).as_str(), "0-12-1");
        let info = code.info().unwrap();
        assert_eq!(info.text, "The gas pressure output is low.");
        assert_eq!(info.steps, StepsRequired::Recommended);
        assert!(!info.action_required());
        // Legacy 0x2098 example: 0x006F = 111 = 0-11-1.
        assert_eq!(text(FaultCode(0x006F)).as_str(), "0-11-1");
        assert_eq!(
            FaultCode(0x006F).legacy_info().unwrap(),
            "Current setting value is out of range"
        );
        assert_eq!(text(FaultCode::NONE).as_str(), "0-00-0");
        assert_eq!(text(FaultCode(3700)).as_str(), "3-70-0");
    }

    #[test]
    fn steps_required_keeps_the_tables_three_values() {
        // SYNC guide (000_dd931256418ae627.txt) line 945: 0-12-1 "No, but recommended";
        // line 948: 0-14-0 "Yes"; line 941: no fault "No".
        assert_eq!(FaultCode(121).steps_required(), StepsRequired::Recommended);
        assert_eq!(FaultCode(140).steps_required(), StepsRequired::Yes);
        assert_eq!(FaultCode(0).steps_required(), StepsRequired::No);
        // Legacy guide (001_0bf4bbd6620a48c8.txt) lines 281, 283 and 295: codes only the
        // legacy list has are taken as Yes (the choice documented on `steps_required`).
        for legacy_only in [120, 190, 990] {
            let code = FaultCode(legacy_only);
            assert!(code.info().is_none() && code.legacy_info().is_some());
            assert_eq!(code.steps_required(), StepsRequired::Yes);
        }
        // A code in neither table.
        assert_eq!(FaultCode(4321).steps_required(), StepsRequired::Yes);
    }

    #[test]
    fn sync_table_complete_and_consistent() {
        assert_eq!(SYNC_FAULTS.len(), 66);
        let mut previous = None;
        for row in SYNC_FAULTS.iter() {
            let code = row.code;
            // Sorted, unique, every row reachable through `info`.
            assert!(previous < Some(code), "{code}");
            previous = Some(code);
            let info = FaultCode(code).info().unwrap();
            assert_eq!(
                (info.code, info.steps, info.models),
                (code, row.steps, row.models)
            );
            assert!(info.text.bytes().all(|b| b.is_ascii()) && !info.text.is_empty());
        }
        assert_eq!(usize::from(SYNC_FAULTS[65].end), SYNC_FAULT_TEXTS.len());
        // First, a middle and the last text, whole.
        assert_eq!(
            FaultCode(0).info().unwrap().text,
            "There is no active fault."
        );
        assert_eq!(
            FaultCode(121).info().unwrap().text,
            "The gas pressure output is low."
        );
        assert_eq!(
            FaultCode(3700).info().unwrap().text,
            "There is an internal serial communications fault between the DSP PCB and power PCB."
        );
        // Hex column spot checks from Table 6.
        for (hex, field) in [
            (0x006E, "0-11-0"),
            (0x00C7, "0-19-9"),
            (0x01FE, "0-51-0"),
            (0x03D6, "0-98-2"),
            (0x07DA, "2-01-0"),
            (0x0D71, "3-44-1"),
            (0x0E74, "3-70-0"),
        ] {
            assert_eq!(field.parse::<FaultCode>(), Ok(FaultCode(hex)));
            assert!(FaultCode(hex).info().is_some());
        }
        assert_eq!(FaultCode(0).info().unwrap().steps, StepsRequired::No);
        assert_eq!(FaultCode(503).info().unwrap().steps, StepsRequired::No);
        assert_eq!(FaultCode(140).info().unwrap().steps, StepsRequired::Yes);
        assert_eq!(
            FaultCode(320).info().unwrap().models,
            SyncModels::Powermax65_85_105
        );
        assert_eq!(
            FaultCode(405).info().unwrap().models,
            SyncModels::Powermax45
        );
        assert_eq!(FaultCode(120).info(), None); // legacy-only code
        assert_eq!(FaultCode(999).info(), None);
    }

    #[test]
    fn legacy_table_complete() {
        assert_eq!(LEGACY_FAULTS.len(), 18);
        let mut previous = None;
        for &(code, _) in LEGACY_FAULTS.iter() {
            assert!(previous < Some(code), "{code}");
            previous = Some(code);
            let text = FaultCode(code).legacy_info().unwrap();
            assert!(
                text.bytes().all(|b| b.is_ascii()) && !text.is_empty(),
                "{code}"
            );
        }
        assert_eq!(usize::from(LEGACY_FAULTS[17].1), LEGACY_FAULT_TEXTS.len());
        assert_eq!(
            FaultCode(110).legacy_info().unwrap(),
            "Invalid cut mode setting"
        );
        assert_eq!(
            FaultCode(990).legacy_info().unwrap(),
            "System hardware fault - service required"
        );
        assert_eq!(
            FaultCode(610).legacy_info().unwrap(),
            "AC input unstable, shutdown"
        );
        assert_eq!(FaultCode(0).legacy_info().unwrap(), "No fault");
        assert_eq!(FaultCode(199).legacy_info(), None);
    }

    #[test]
    fn parse() {
        assert_eq!("0-50-0".parse(), Ok(FaultCode(500)));
        assert_eq!("3-70-0".parse(), Ok(FaultCode(3700)));
        assert_eq!("65-53-5".parse(), Ok(FaultCode(u16::MAX)));
        assert_eq!("065-53-5".parse(), Ok(FaultCode(u16::MAX)));
        for bad in [
            "", "0-50", "0-5-0", "0-500-0", "0-50-00", "-50-0", "0-50-0-1", "a-50-0", "65-53-6",
            "66-00-0", "0-5a-0", "0 -50-0",
        ] {
            assert_eq!(bad.parse::<FaultCode>(), Err(Error::Malformed), "{bad}");
        }
    }

    /// Code and hex columns of every Table 6 row (extracted from the guide's text), checked
    /// against the transcribed table.
    #[test]
    fn every_table_6_code() {
        let columns: [(&str, u16); 65] = [
            ("0-11-0", 0x006E),
            ("0-11-1", 0x006F),
            ("0-11-2", 0x0070),
            ("0-12-1", 0x0079),
            ("0-12-2", 0x007A),
            ("0-12-3", 0x007B),
            ("0-13-0", 0x0082),
            ("0-14-0", 0x008C),
            ("0-14-1", 0x008D),
            ("0-19-9", 0x00C7),
            ("0-20-0", 0x00C8),
            ("0-21-0", 0x00D2),
            ("0-22-0", 0x00DC),
            ("0-30-0", 0x012C),
            ("0-30-1", 0x012D),
            ("0-32-0", 0x0140),
            ("0-32-1", 0x0141),
            ("0-40-0", 0x0190),
            ("0-40-1", 0x0191),
            ("0-40-2", 0x0192),
            ("0-40-3", 0x0193),
            ("0-40-4", 0x0194),
            ("0-40-5", 0x0195),
            ("0-50-0", 0x01F4),
            ("0-50-1", 0x01F5),
            ("0-50-2", 0x01F6),
            ("0-50-3", 0x01F7),
            ("0-51-0", 0x01FE),
            ("0-52-0", 0x0208),
            ("0-60-0", 0x0258),
            ("0-60-1", 0x0259),
            ("0-60-2", 0x025A),
            ("0-61-0", 0x0262),
            ("0-98-0", 0x03D4),
            ("0-98-1", 0x03D5),
            ("0-98-2", 0x03D6),
            ("1-00-0", 0x03E8),
            ("1-20-0", 0x04B0),
            ("1-30-0", 0x0514),
            ("2-00-0", 0x07D0),
            ("2-01-0", 0x07DA),
            ("2-10-0", 0x0834),
            ("2-10-1", 0x0835),
            ("2-11-0", 0x083E),
            ("2-11-1", 0x083F),
            ("2-20-0", 0x0898),
            ("3-00-0", 0x0BB8),
            ("3-10-0", 0x0C1C),
            ("3-10-1", 0x0C1D),
            ("3-11-0", 0x0C26),
            ("3-11-1", 0x0C27),
            ("3-11-2", 0x0C28),
            ("3-20-0", 0x0C80),
            ("3-20-1", 0x0C81),
            ("3-20-2", 0x0C82),
            ("3-20-3", 0x0C83),
            ("3-41-0", 0x0D52),
            ("3-42-0", 0x0D5C),
            ("3-42-1", 0x0D5D),
            ("3-43-0", 0x0D66),
            ("3-44-1", 0x0D71),
            ("3-51-1", 0x0DB7),
            ("3-52-0", 0x0DC0),
            ("3-60-0", 0x0E10),
            ("3-70-0", 0x0E74),
        ];
        for (text, hex) in columns {
            let code: FaultCode = text.parse().unwrap();
            assert_eq!(code, FaultCode(hex), "{text}");
            assert!(code.info().is_some(), "{text}");
        }
    }
}
