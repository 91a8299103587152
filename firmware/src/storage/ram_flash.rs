//! A RAM model of the STM32L4's internal flash, with power cuts.
//!
//! Modelled on RM0351: 2 KiB pages, erased bytes read 0xFF, programming is per 64-bit double
//! word, and a double word can be programmed only once after an erase (except with all
//! zeros). Every double-word program and every page erase is one *step*; a power cut can be
//! scheduled after any number of steps. The step it interrupts is left torn: a program has
//! applied only some of its 1-to-0 bits, an erase only some of its 0-to-1 bits, chosen by a
//! seeded noise source. After the cut every operation fails until [`RamFlash::power_cycle`].
//!
//! A silent failure can be scheduled too ([`RamFlash::fail_silently`]): steps that report
//! success and change nothing, as embassy-stm32 0.6.0's L4 driver reports a failed program
//! (its interrupt clears the error flags before they are read; docs/board.md).
//!
//! Real hardware can also leave an ECC error in a torn double word, which reads as an NMI on
//! the L4; this model returns the torn bits instead (see docs/board.md, settings store).
#![allow(
    clippy::indexing_slicing,
    reason = "a test model: every offset is bounds-checked by `range` before use"
)]

use embedded_storage_async::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// Erase granularity of the model (an L4 page).
pub const PAGE_SIZE: usize = 2048;

/// Program granularity of the model (an L4 double word).
pub const WORD_SIZE: usize = 8;

/// What went wrong in a [`RamFlash`] operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RamFlashError {
    /// Offset or length not a multiple of the word (program) or page (erase) size.
    NotAligned,
    /// Outside the flash.
    OutOfBounds,
    /// Programming a double word that is not erased (PROGERR on the L4).
    NotErased,
    /// The power was cut during or before this operation.
    PowerCut,
}

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            RamFlashError::NotAligned => NorFlashErrorKind::NotAligned,
            RamFlashError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            RamFlashError::NotErased | RamFlashError::PowerCut => NorFlashErrorKind::Other,
        }
    }
}

/// `SIZE` bytes of flash (a multiple of [`PAGE_SIZE`]), addressed from 0.
#[derive(Debug, Clone)]
pub struct RamFlash<const SIZE: usize> {
    bytes: [u8; SIZE],
    steps: u32,
    steps_before_cut: Option<u32>,
    dead: bool,
    noise: u32,
    /// Good steps before the silent failures start, and how many steps fail silently.
    silent: Option<(u32, u32)>,
}

impl<const SIZE: usize> Default for RamFlash<SIZE> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const SIZE: usize> RamFlash<SIZE> {
    /// Erased flash with the power on.
    pub const fn new() -> Self {
        assert!(
            SIZE.is_multiple_of(PAGE_SIZE) && SIZE > 0,
            "whole pages only"
        );
        RamFlash {
            bytes: [0xFF; SIZE],
            steps: 0,
            steps_before_cut: None,
            dead: false,
            noise: 1,
            silent: None,
        }
    }

    /// Schedules a power cut: `steps` more steps complete, the next one is torn using noise
    /// from `seed`, and everything after fails.
    pub fn cut_power_after(&mut self, steps: u32, seed: u32) {
        self.steps_before_cut = Some(steps);
        // xorshift must not start at zero.
        self.noise = seed | 1;
    }

    /// Schedules silent failures: `after` more steps work, then the next `steps` steps
    /// (`u32::MAX`: all of them) report success and leave the flash as it was.
    pub fn fail_silently(&mut self, after: u32, steps: u32) {
        self.silent = Some((after, steps));
    }

    /// Whether the coming step fails silently (and counts it).
    fn drops_step(&mut self) -> bool {
        match self.silent {
            Some((0, 0)) | None => false,
            Some((0, left)) => {
                self.silent = Some((0, left.saturating_sub(1)));
                true
            }
            Some((good, left)) => {
                self.silent = Some((good - 1, left));
                false
            }
        }
    }

    /// Power comes back: operations work again, the contents are what the cut left.
    pub fn power_cycle(&mut self) {
        self.dead = false;
        self.steps_before_cut = None;
    }

    /// Whether a scheduled cut has happened.
    pub fn power_was_cut(&self) -> bool {
        self.dead
    }

    /// Steps completed since creation (programmed double words plus erased pages).
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// The contents.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The contents, to corrupt them on purpose.
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.bytes
    }

    fn next_noise(&mut self) -> u32 {
        let mut x = self.noise;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.noise = x;
        x
    }

    /// Starts a step: `Ok(false)` to do it fully, `Ok(true)` to tear it (the power dies now).
    fn begin_step(&mut self) -> Result<bool, RamFlashError> {
        if self.dead {
            return Err(RamFlashError::PowerCut);
        }
        match self.steps_before_cut {
            Some(0) => {
                self.dead = true;
                Ok(true)
            }
            Some(n) => {
                self.steps_before_cut = Some(n - 1);
                self.steps += 1;
                Ok(false)
            }
            None => {
                self.steps += 1;
                Ok(false)
            }
        }
    }

    fn range(&self, offset: u32, len: usize) -> Result<core::ops::Range<usize>, RamFlashError> {
        let start = usize::try_from(offset).map_err(|_| RamFlashError::OutOfBounds)?;
        let end = start.checked_add(len).ok_or(RamFlashError::OutOfBounds)?;
        if end > SIZE {
            return Err(RamFlashError::OutOfBounds);
        }
        Ok(start..end)
    }

    fn program_word(&mut self, at: usize, value: &[u8]) -> Result<(), RamFlashError> {
        let erased = self.bytes[at..at + WORD_SIZE].iter().all(|&b| b == 0xFF);
        let zeros = value.iter().all(|&b| b == 0);
        if !erased && !zeros {
            return Err(RamFlashError::NotErased);
        }
        let torn = self.begin_step()?;
        if self.drops_step() {
            return Ok(());
        }
        for (i, &v) in value.iter().enumerate() {
            // Programming only clears bits; a torn program clears a random subset of them.
            let applied = if torn { v | self.next_noise() as u8 } else { v };
            self.bytes[at + i] &= applied;
        }
        if torn {
            Err(RamFlashError::PowerCut)
        } else {
            Ok(())
        }
    }

    fn erase_page(&mut self, at: usize) -> Result<(), RamFlashError> {
        let torn = self.begin_step()?;
        if self.drops_step() {
            return Ok(());
        }
        for i in at..at + PAGE_SIZE {
            // Erasing only sets bits; a torn erase sets a random subset of them.
            self.bytes[i] |= if torn { self.next_noise() as u8 } else { 0xFF };
        }
        if torn {
            Err(RamFlashError::PowerCut)
        } else {
            Ok(())
        }
    }
}

impl<const SIZE: usize> ErrorType for RamFlash<SIZE> {
    type Error = RamFlashError;
}

impl<const SIZE: usize> ReadNorFlash for RamFlash<SIZE> {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        if self.dead {
            return Err(RamFlashError::PowerCut);
        }
        let range = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.bytes[range]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        SIZE
    }
}

impl<const SIZE: usize> NorFlash for RamFlash<SIZE> {
    const WRITE_SIZE: usize = WORD_SIZE;
    const ERASE_SIZE: usize = PAGE_SIZE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let len = to.checked_sub(from).ok_or(RamFlashError::OutOfBounds)? as usize;
        let range = self.range(from, len)?;
        if range.start % PAGE_SIZE != 0 || range.end % PAGE_SIZE != 0 {
            return Err(RamFlashError::NotAligned);
        }
        for page in range.step_by(PAGE_SIZE) {
            self.erase_page(page)?;
        }
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let range = self.range(offset, bytes.len())?;
        if !range.start.is_multiple_of(WORD_SIZE) || !bytes.len().is_multiple_of(WORD_SIZE) {
            return Err(RamFlashError::NotAligned);
        }
        for (i, word) in bytes.chunks_exact(WORD_SIZE).enumerate() {
            self.program_word(range.start + i * WORD_SIZE, word)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embassy_futures::block_on;

    type Flash = RamFlash<{ 2 * PAGE_SIZE }>;

    #[test]
    fn program_and_erase_like_the_l4() {
        let mut f = Flash::new();
        block_on(async {
            f.write(8, &[1, 2, 3, 4, 5, 6, 7, 8]).await.unwrap();
            let mut out = [0u8; 10];
            f.read(7, &mut out).await.unwrap();
            assert_eq!(out, [0xFF, 1, 2, 3, 4, 5, 6, 7, 8, 0xFF]);
            // Once per erase, except all zeros.
            assert_eq!(f.write(8, &[0xFF; 8]).await, Err(RamFlashError::NotErased));
            f.write(8, &[0; 8]).await.unwrap();
            assert_eq!(f.write(4, &[0; 8]).await, Err(RamFlashError::NotAligned));
            assert_eq!(f.write(8, &[0; 4]).await, Err(RamFlashError::NotAligned));
            assert_eq!(
                f.write(2 * PAGE_SIZE as u32, &[0; 8]).await,
                Err(RamFlashError::OutOfBounds)
            );
            assert_eq!(f.erase(0, 100).await, Err(RamFlashError::NotAligned));
            f.erase(0, PAGE_SIZE as u32).await.unwrap();
            assert!(f.bytes()[..PAGE_SIZE].iter().all(|&b| b == 0xFF));
        });
        assert_eq!(f.steps(), 3);
    }

    #[test]
    fn a_cut_tears_one_step_and_stops_the_rest() {
        let mut f = Flash::new();
        f.cut_power_after(1, 0x1234_5678);
        block_on(async {
            let value = [0u8; 24];
            assert_eq!(f.write(0, &value).await, Err(RamFlashError::PowerCut));
            assert!(f.power_was_cut());
            // First word complete, second torn (some bits cleared, not all), third untouched.
            assert_eq!(&f.bytes()[..8], &[0; 8]);
            assert!(f.bytes()[8..16].iter().any(|&b| b != 0));
            assert!(f.bytes()[8..16].iter().any(|&b| b != 0xFF));
            assert_eq!(&f.bytes()[16..24], &[0xFF; 8]);
            let mut out = [0u8; 1];
            assert_eq!(f.read(0, &mut out).await, Err(RamFlashError::PowerCut));
            f.power_cycle();
            f.read(0, &mut out).await.unwrap();
        });
    }

    #[test]
    fn a_torn_erase_leaves_a_mix() {
        let mut f = Flash::new();
        f.bytes_mut().fill(0);
        f.cut_power_after(0, 99);
        assert_eq!(
            block_on(f.erase(0, PAGE_SIZE as u32)),
            Err(RamFlashError::PowerCut)
        );
        let page = &f.bytes()[..PAGE_SIZE];
        assert!(page.iter().any(|&b| b != 0xFF) && page.iter().any(|&b| b != 0));
    }
}
