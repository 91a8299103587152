//! The coils the bridge serves as a Powermax, behind a SYNC or legacy Powermax (an HPR or
//! MaxPro200 has none: exception 02).
//!
//! | coil | function | value |
//! |---|---|---|
//! | 0x0808 / 0x0809 | 01 | torch lead length, bit 0 / bit 1 (00 15-25 ft, 01 35-50 ft, 10 75 ft): a SYNC unit's from 0x3000 (Table 3), a legacy unit's own coils (slow data) |
//! | 0x080A-0x080F | 01 | 0 (undocumented, inside the block so 0x0808-0x0811 reads whole) |
//! | 0x0810, 0x3100 | 01 | Start: the START output the bridge drives to the unit |
//! | 0x0811, 0x3101 | 01 | Motion: the unit's MOTION (arc transfer) output as the bridge reads it |
//! | 0x0832, 0x3180 | 05 | gas test on (0xFF00) / off (0x0000), carried out by the link |
//!
//! The 0x31xx coils only behind a SYNC unit (as its registers). The lead coils are exception
//! 02 until the link has read the lead (and for a unit that refused its own coils, as that
//! unit answers), so a CNC never loads the cut chart of a lead it was not told.

use plasma_protocol::modbus_ascii::ExceptionCode;
use plasma_protocol::powermax::{legacy, sync};

use crate::io::{Inputs, Outputs};
use crate::link::{Family, UnitStatus};

/// The most coils one read can cover: the legacy block 0x0808-0x0811.
pub(super) const MAX_COILS: usize =
    (legacy::MOTION_SIGNAL_COIL - legacy::TORCH_LEAD_BIT0_COIL + 1) as usize;
/// Bytes of coil bits for [`MAX_COILS`].
pub(super) const MAX_COIL_BYTES: usize = MAX_COILS.div_ceil(8);

/// What the coils read from.
pub(super) struct Coils<'a> {
    /// The link's latest picture of the unit.
    pub status: &'a UnitStatus,
    /// The last discrete-I/O snapshot (none yet: every signal off).
    pub io: Option<(Inputs, Outputs)>,
}

impl Coils<'_> {
    /// The family when it has coils (a Powermax).
    fn family(&self) -> Option<Family> {
        self.status.family.filter(|f| f.is_modbus())
    }

    /// The state of coil `address`; `None` when it is not served (or not known yet).
    pub(super) fn read(&self, address: u16) -> Option<bool> {
        let family = self.family()?;
        let sync_unit = family == Family::PowermaxSync;
        let (inputs, outputs) = self.io.unwrap_or((Inputs::NONE, Outputs::OFF));
        let lead_bit = |bit: u8| {
            self.status
                .torch_lead()
                .map(|l| l.legacy_coils() >> bit & 1 == 1)
        };
        match address {
            legacy::TORCH_LEAD_BIT0_COIL => lead_bit(0),
            legacy::TORCH_LEAD_BIT1_COIL => lead_bit(1),
            legacy::START_SIGNAL_COIL => Some(outputs.start),
            legacy::MOTION_SIGNAL_COIL => Some(inputs.motion),
            a if a > legacy::TORCH_LEAD_BIT1_COIL && a < legacy::START_SIGNAL_COIL => Some(false),
            sync::START_SIGNAL_COIL if sync_unit => Some(outputs.start),
            sync::MOTION_SIGNAL_COIL if sync_unit => Some(inputs.motion),
            _ => None,
        }
    }

    /// `quantity` coils from `start`, packed LSB first into `bits`; the number of bytes.
    pub(super) fn read_many(
        &self,
        start: u16,
        quantity: u16,
        bits: &mut [u8; MAX_COIL_BYTES],
    ) -> Result<usize, ExceptionCode> {
        let n = usize::from(quantity);
        if n > MAX_COILS {
            return Err(ExceptionCode::IllegalDataAddress);
        }
        *bits = [0; MAX_COIL_BYTES];
        for i in 0..n {
            let on = start
                .checked_add(i as u16)
                .and_then(|address| self.read(address))
                .ok_or(ExceptionCode::IllegalDataAddress)?;
            if let Some(byte) = bits.get_mut(i / 8) {
                *byte |= u8::from(on) << (i % 8);
            }
        }
        Ok(n.div_ceil(8))
    }

    /// True for the gas-test coil of the unit behind the bridge (the only coil written).
    pub(super) fn is_gas_test(&self, address: u16) -> bool {
        match self.family() {
            Some(Family::PowermaxSync) => {
                address == sync::GAS_TEST_COIL || address == legacy::GAS_TEST_COIL
            }
            Some(_) => address == legacy::GAS_TEST_COIL,
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::modbus_ascii::Registers;
    use plasma_protocol::powermax::sync::Identification;

    fn sync_status(identification: u16) -> UnitStatus {
        UnitStatus {
            family: Some(Family::PowermaxSync),
            link_up: true,
            identification: Identification::decode(Registers::Words(&[identification])).ok(),
            ..UnitStatus::default()
        }
    }

    /// SYNC manual (000_dd931256418ae627.txt) lines 607 and 619-620: 0x05 in 0x3000's high byte
    /// is a machine torch with a 35-50 ft lead, 0x06 with a 75 ft lead; legacy guide
    /// (001_0bf4bbd6620a48c8.txt) lines 264-271: those leads' coils read 01 and 10.
    #[test]
    fn the_lead_coils_of_a_sync_unit_come_from_0x3000() {
        let status = sync_status(0x0508);
        let coils = Coils {
            status: &status,
            io: None,
        };
        let mut bits = [0; MAX_COIL_BYTES];
        assert_eq!(coils.read_many(0x0808, 2, &mut bits), Ok(1));
        assert_eq!(bits[0], 0x01);
        // The whole legacy block: lead 01, six gaps, Start and Motion off.
        assert_eq!(coils.read_many(0x0808, 10, &mut bits), Ok(2));
        assert_eq!(bits, [0x01, 0x00]);
        assert_eq!(
            coils.read_many(0x0808, 11, &mut bits),
            Err(ExceptionCode::IllegalDataAddress)
        );
        // 0x06: 75 ft lead, bits 10.
        let status = sync_status(0x0608);
        let coils = Coils {
            status: &status,
            io: None,
        };
        assert_eq!(coils.read_many(0x0808, 2, &mut bits), Ok(1));
        assert_eq!(bits[0], 0x02);
    }

    #[test]
    fn no_lead_known_no_lead_coils_and_no_coils_behind_an_hpr() {
        let legacy = UnitStatus {
            family: Some(Family::PowermaxLegacy),
            link_up: true,
            ..UnitStatus::default()
        };
        let coils = Coils {
            status: &legacy,
            io: None,
        };
        assert_eq!(coils.read(0x0808), None);
        assert_eq!(coils.read(0x0810), Some(false));
        assert_eq!(coils.read(0x3100), None, "a SYNC coil");
        assert!(coils.is_gas_test(0x0832) && !coils.is_gas_test(0x3180));
        let hpr = UnitStatus {
            family: Some(Family::Hpr),
            link_up: true,
            ..UnitStatus::default()
        };
        let coils = Coils {
            status: &hpr,
            io: None,
        };
        assert_eq!(coils.read(0x0810), None);
        assert!(!coils.is_gas_test(0x0832));
    }
}
