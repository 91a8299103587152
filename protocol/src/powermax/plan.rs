//! Read plans: which registers one request covers, and how to fall back when a unit refuses a
//! block that crosses undocumented addresses.
//!
//! Neither guide says whether a unit answers a read that spans addresses it does not document
//! (SYNC 0x3013-0x3017, 0x303D-0x303F; legacy 0x2095, 0x2097, 0x209B). A [`BlockRead`] names
//! the whole block and its documented parts: the link sends [`BlockRead::read`] first and, on
//! exception 02 (illegal data address), sends [`BlockRead::part_reads`] instead and copies each
//! reply into a block-shaped buffer with [`BlockRead::place`]. Decoders take the block-shaped
//! registers either way and never look at the undocumented positions.

use crate::modbus_ascii::{Registers, Request};
use crate::{Error, Result};

/// Consecutive registers read with function 04 (the SYNC guide recommends 04 for holding and
/// input registers alike; the legacy guide's samples use 04 too).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RegisterSpan {
    /// First register address.
    pub start: u16,
    /// Number of registers.
    pub quantity: u16,
}

impl RegisterSpan {
    /// A span of `quantity` registers from `start`.
    pub const fn new(start: u16, quantity: u16) -> Self {
        RegisterSpan { start, quantity }
    }

    /// Address of the last register.
    pub const fn last(self) -> u16 {
        self.start.wrapping_add(self.quantity).wrapping_sub(1)
    }

    /// True when `address` lies in the span.
    pub const fn contains(self, address: u16) -> bool {
        address >= self.start && address - self.start < self.quantity
    }

    /// The read request (function 04).
    pub const fn read(self) -> Request<'static> {
        Request::ReadInputRegisters {
            start: self.start,
            quantity: self.quantity,
        }
    }
}

/// A block read and the documented parts it is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlockRead {
    block: RegisterSpan,
    parts: &'static [RegisterSpan],
}

impl BlockRead {
    /// `block` covering `parts` (in address order, each inside the block).
    pub(super) const fn new(block: RegisterSpan, parts: &'static [RegisterSpan]) -> Self {
        BlockRead { block, parts }
    }

    /// The whole block.
    pub const fn block(&self) -> RegisterSpan {
        self.block
    }

    /// The documented parts; one part equal to the block when there is no gap.
    pub const fn parts(&self) -> &'static [RegisterSpan] {
        self.parts
    }

    /// Number of registers in the block (the size of the buffer [`BlockRead::place`] fills).
    pub const fn len(&self) -> usize {
        self.block.quantity as usize
    }

    /// True for an empty block (never for the plans in this crate).
    pub const fn is_empty(&self) -> bool {
        self.block.quantity == 0
    }

    /// True when the block crosses addresses no guide documents.
    pub fn has_gaps(&self) -> bool {
        let documented: u16 = self.parts.iter().map(|p| p.quantity).sum();
        documented != self.block.quantity
    }

    /// The single request for the whole block.
    pub const fn read(&self) -> Request<'static> {
        self.block.read()
    }

    /// The requests for the documented parts, in address order.
    pub fn part_reads(&self) -> impl Iterator<Item = Request<'static>> + 'static {
        self.parts.iter().map(|part| part.read())
    }

    /// Copies the reply to part `index` into `block` (a buffer of [`BlockRead::len`] words) at
    /// the part's position. Undocumented positions are left as they are.
    ///
    /// Errors: [`Error::Malformed`] for a bad index, [`Error::BufferTooSmall`] for a short
    /// buffer, [`Error::Truncated`] / [`Error::Mismatch`] when the reply holds fewer / more
    /// registers than the part.
    pub fn place(&self, index: usize, values: Registers<'_>, block: &mut [u16]) -> Result<()> {
        let part = self.parts.get(index).ok_or(Error::Malformed)?;
        let offset = usize::from(part.start.wrapping_sub(self.block.start));
        let quantity = usize::from(part.quantity);
        if values.len() < quantity {
            return Err(Error::Truncated);
        }
        if values.len() > quantity {
            return Err(Error::Mismatch);
        }
        let target = block
            .get_mut(offset..offset + quantity)
            .ok_or(Error::BufferTooSmall)?;
        for (slot, value) in target.iter_mut().zip(values.iter()) {
            *slot = value;
        }
        Ok(())
    }
}

/// Register `index` of a decoded block, or [`Error::Truncated`].
pub(super) fn word(registers: &Registers<'_>, index: usize) -> Result<u16> {
    registers.get(index).ok_or(Error::Truncated)
}

/// Fails with [`Error::Truncated`] unless at least `count` registers are present.
pub(super) fn need(registers: &Registers<'_>, count: usize) -> Result<()> {
    if registers.len() < count {
        Err(Error::Truncated)
    } else {
        Ok(())
    }
}

/// `N` bytes (N even) from registers starting at `index`, high byte first in each register.
pub(super) fn bytes<const N: usize>(registers: &Registers<'_>, index: usize) -> Result<[u8; N]> {
    let mut out = [0u8; N];
    for (i, pair) in out.chunks_mut(2).enumerate() {
        let value = word(registers, index + i)?.to_be_bytes();
        for (slot, byte) in pair.iter_mut().zip(value) {
            *slot = byte;
        }
    }
    Ok(out)
}

/// A 32-bit counter stored low word first (SYNC 0x3028-0x302F, legacy 0x209E/0x209F).
pub(super) fn u32_low_first(registers: &Registers<'_>, index: usize) -> Result<u32> {
    let low = word(registers, index)?;
    let high = word(registers, index + 1)?;
    Ok(u32::from(high) << 16 | u32::from(low))
}

/// State of two status coils read together: Start input and Motion (transfer) output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Signals {
    /// Start input is on: pilot arc or transferred arc (SYNC 0x3100, legacy 0x0810).
    pub start: bool,
    /// Motion output is on: the arc has transferred (SYNC 0x3101, legacy 0x0811).
    pub motion: bool,
}

impl Signals {
    /// Decodes the reply bits of a two-coil read (first coil is bit 0).
    pub fn decode(bits: &[u8]) -> Result<Self> {
        let byte = bits.first().ok_or(Error::Truncated)?;
        Ok(Signals {
            start: byte & 0b01 != 0,
            motion: byte & 0b10 != 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static PARTS: [RegisterSpan; 2] = [RegisterSpan::new(0x10, 3), RegisterSpan::new(0x18, 3)];
    const PLAN: BlockRead = BlockRead::new(RegisterSpan::new(0x10, 11), &PARTS);

    #[test]
    fn span() {
        let span = RegisterSpan::new(0x3010, 3);
        assert_eq!(span.last(), 0x3012);
        assert!(span.contains(0x3010) && span.contains(0x3012));
        assert!(!span.contains(0x3013) && !span.contains(0x300F));
        assert_eq!(
            span.read(),
            Request::ReadInputRegisters {
                start: 0x3010,
                quantity: 3
            }
        );
    }

    #[test]
    fn place_parts() {
        let mut buf = [0xEEEEu16; 11];
        PLAN.place(0, Registers::Words(&[1, 2, 3]), &mut buf)
            .unwrap();
        PLAN.place(1, Registers::BigEndian(&[0, 4, 0, 5, 0, 6]), &mut buf)
            .unwrap();
        assert_eq!(
            buf,
            [1, 2, 3, 0xEEEE, 0xEEEE, 0xEEEE, 0xEEEE, 0xEEEE, 4, 5, 6]
        );
        assert_eq!(
            PLAN.place(0, Registers::Words(&[1, 2]), &mut buf),
            Err(Error::Truncated)
        );
        assert_eq!(
            PLAN.place(0, Registers::Words(&[1, 2, 3, 4]), &mut buf),
            Err(Error::Mismatch)
        );
        assert_eq!(
            PLAN.place(2, Registers::Words(&[1]), &mut buf),
            Err(Error::Malformed)
        );
        let mut short = [0u16; 10];
        assert_eq!(
            PLAN.place(1, Registers::Words(&[1, 2, 3]), &mut short),
            Err(Error::BufferTooSmall)
        );
        assert!(PLAN.has_gaps());
        assert_eq!(PLAN.part_reads().count(), 2);
    }

    #[test]
    fn signals() {
        // SYNC guide: :01010100FD = both off; :01010103FA = Start and Motion on.
        assert_eq!(
            Signals::decode(&[0x00]),
            Ok(Signals {
                start: false,
                motion: false
            })
        );
        assert_eq!(
            Signals::decode(&[0x03]),
            Ok(Signals {
                start: true,
                motion: true
            })
        );
        assert_eq!(
            Signals::decode(&[0x01]),
            Ok(Signals {
                start: true,
                motion: false
            })
        );
        assert_eq!(Signals::decode(&[]), Err(Error::Truncated));
    }

    #[test]
    fn helpers() {
        let regs = Registers::Words(&[0x3432, 0x3839, 0xD1B6, 0x0006]);
        assert_eq!(bytes::<4>(&regs, 0), Ok(*b"4289"));
        assert_eq!(bytes::<4>(&regs, 1), Ok([0x38, 0x39, 0xD1, 0xB6]));
        assert_eq!(bytes::<4>(&regs, 3), Err(Error::Truncated));
        assert_eq!(u32_low_first(&regs, 2), Ok(0x0006_D1B6));
        assert_eq!(u32_low_first(&regs, 3), Err(Error::Truncated));
        assert_eq!(need(&regs, 4), Ok(()));
        assert_eq!(need(&regs, 5), Err(Error::Truncated));
    }
}
