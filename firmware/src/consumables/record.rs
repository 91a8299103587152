//! The consumable record the store keeps under [`CONSUMABLES_KEY`](crate::storage::CONSUMABLES_KEY):
//! a fixed layout, version 1. Decoding is strict: a wrong length or a reserved bit set gives
//! `None`, and the bridge starts a new set.

use super::ConsumableSet;
use crate::storage::{self, Persistent};

// --- record layout, version 1 ------------------------------------------------------------
// 0-3 starts (LE) | 4-11 arc ms (LE) | 12-13 wear faults (LE) | 14-15 rampdown errors (LE)
// 16 flags | 17-32 cartridge UID (zeros without one)

/// Length of the version-1 record.
pub const RECORD_LEN: usize = 33;

const FLAG_UID: u8 = 1 << 0;
const FLAG_WARNED_90: u8 = 1 << 1;
const FLAG_WARNED_100: u8 = 1 << 2;
const FLAGS_KNOWN: u8 = 0x07;

impl Persistent for ConsumableSet {
    const VERSION: u8 = 1;

    fn encode(&self, out: &mut [u8]) -> usize {
        let mut r = [0u8; RECORD_LEN];
        let flag = |on: bool, bit: u8| if on { bit } else { 0 };
        r[0..4].copy_from_slice(&self.starts.to_le_bytes());
        r[4..12].copy_from_slice(&self.arc_ms.to_le_bytes());
        r[12..14].copy_from_slice(&self.wear_faults.to_le_bytes());
        r[14..16].copy_from_slice(&self.rampdown_errors.to_le_bytes());
        r[16] = flag(self.uid.is_some(), FLAG_UID)
            | flag(self.warned_90, FLAG_WARNED_90)
            | flag(self.warned_100, FLAG_WARNED_100);
        r[17..].copy_from_slice(&self.uid.unwrap_or([0; 16]));
        storage::write_payload(out, &r)
    }

    fn decode(payload: &[u8]) -> Option<Self> {
        let r: &[u8; RECORD_LEN] = payload.try_into().ok()?;
        let (starts, rest) = r.split_first_chunk::<4>()?;
        let (arc_ms, rest) = rest.split_first_chunk::<8>()?;
        let (wear_faults, rest) = rest.split_first_chunk::<2>()?;
        let (rampdown_errors, rest) = rest.split_first_chunk::<2>()?;
        let (&flags, uid) = rest.split_first()?;
        let uid: [u8; 16] = uid.try_into().ok()?;
        if flags & !FLAGS_KNOWN != 0 || (flags & FLAG_UID == 0 && uid != [0; 16]) {
            return None;
        }
        Some(ConsumableSet {
            starts: u32::from_le_bytes(*starts),
            arc_ms: u64::from_le_bytes(*arc_ms),
            wear_faults: u16::from_le_bytes(*wear_faults),
            rampdown_errors: u16::from_le_bytes(*rampdown_errors),
            uid: (flags & FLAG_UID != 0).then_some(uid),
            warned_90: flags & FLAG_WARNED_90 != 0,
            warned_100: flags & FLAG_WARNED_100 != 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encoded(set: &ConsumableSet) -> [u8; RECORD_LEN] {
        let mut out = [0u8; crate::storage::MAX_PAYLOAD];
        assert_eq!(set.encode(&mut out), RECORD_LEN);
        out[..RECORD_LEN].try_into().unwrap()
    }

    #[test]
    fn a_set_comes_back_as_it_was_written() {
        let sets = [
            ConsumableSet::default(),
            ConsumableSet {
                starts: 70_000,
                arc_ms: 5_000_000_123,
                wear_faults: 2,
                rampdown_errors: 513,
                uid: Some(*b"E00401D0036FB25D"),
                warned_90: true,
                warned_100: false,
            },
        ];
        for set in sets {
            assert_eq!(ConsumableSet::decode(&encoded(&set)), Some(set));
        }
    }

    #[test]
    fn the_layout_is_the_documented_one() {
        let set = ConsumableSet {
            starts: 0x0403_0201,
            arc_ms: 0x0C0B_0A09_0807_0605,
            wear_faults: 0x0E0D,
            rampdown_errors: 0x100F,
            uid: Some([0x41; 16]),
            warned_90: false,
            warned_100: true,
        };
        let r = encoded(&set);
        assert_eq!(
            r[..16],
            [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]
        );
        assert_eq!(r[16], FLAG_UID | FLAG_WARNED_100);
        assert_eq!(r[17..], [0x41; 16]);
    }

    #[test]
    fn decode_is_strict() {
        let r = encoded(&ConsumableSet::default());
        assert_eq!(ConsumableSet::decode(&r[..RECORD_LEN - 1]), None, "short");
        let mut bad = r;
        bad[16] = 0x08;
        assert_eq!(ConsumableSet::decode(&bad), None, "reserved flag");
        let mut bad = r;
        bad[20] = 1;
        assert_eq!(ConsumableSet::decode(&bad), None, "a UID without its flag");
    }
}
