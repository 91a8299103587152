//! A flash that checks its own work: every program and erase is read back and compared.
//!
//! Why: embassy-stm32 0.6.0's L4 flash interrupt clears PROGERR, PGSERR and WRPERR before its
//! `wait_ready` reads the status register, so a failed program or erase reports success
//! (docs/board.md, "Faults found in review"). Reading back catches that and any other silent
//! failure: the store's retry and the `CONFIG SAVE` reply then see an error, not a success
//! that the next boot would contradict.

use embedded_storage_async::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// Bytes compared per read-back step (stack space, not a limit on the write size).
const CHUNK: usize = 32;

/// What went wrong in a [`VerifiedFlash`] operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VerifyError<E> {
    /// The flash driver reported an error.
    Flash(E),
    /// The driver reported success, but the flash does not hold what was written (or erased).
    Mismatch,
}

impl<E: NorFlashError> NorFlashError for VerifyError<E> {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            VerifyError::Flash(e) => e.kind(),
            VerifyError::Mismatch => NorFlashErrorKind::Other,
        }
    }
}

/// `F`, with every write and erase read back.
#[derive(Debug)]
pub struct VerifiedFlash<F>(F);

impl<F> VerifiedFlash<F> {
    /// Wraps `flash`.
    pub const fn new(flash: F) -> Self {
        VerifiedFlash(flash)
    }

    /// The flash underneath (tests inspect a model through it).
    pub fn inner(&mut self) -> &mut F {
        &mut self.0
    }
}

impl<F: NorFlash> VerifiedFlash<F> {
    /// Whether `offset..offset + len` reads as `expected(i)` for every byte `i` of it.
    async fn holds(
        &mut self,
        offset: u32,
        len: usize,
        expected: impl Fn(usize) -> u8,
    ) -> Result<bool, VerifyError<F::Error>> {
        let mut buf = [0u8; CHUNK];
        let mut done = 0;
        while done < len {
            let n = (len - done).min(CHUNK);
            let at = offset + done as u32;
            let chunk = &mut buf[..n];
            self.0.read(at, chunk).await.map_err(VerifyError::Flash)?;
            if chunk
                .iter()
                .enumerate()
                .any(|(i, &b)| b != expected(done + i))
            {
                return Ok(false);
            }
            done += n;
        }
        Ok(true)
    }
}

impl<F: NorFlash> ErrorType for VerifiedFlash<F> {
    type Error = VerifyError<F::Error>;
}

impl<F: NorFlash> ReadNorFlash for VerifiedFlash<F> {
    const READ_SIZE: usize = F::READ_SIZE;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.0.read(offset, bytes).await.map_err(VerifyError::Flash)
    }

    fn capacity(&self) -> usize {
        self.0.capacity()
    }
}

impl<F: NorFlash> NorFlash for VerifiedFlash<F> {
    const WRITE_SIZE: usize = F::WRITE_SIZE;
    const ERASE_SIZE: usize = F::ERASE_SIZE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        self.0.erase(from, to).await.map_err(VerifyError::Flash)?;
        let len = to.saturating_sub(from) as usize;
        match self.holds(from, len, |_| 0xFF).await? {
            true => Ok(()),
            false => Err(VerifyError::Mismatch),
        }
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0
            .write(offset, bytes)
            .await
            .map_err(VerifyError::Flash)?;
        let expected = |i: usize| bytes.get(i).copied().unwrap_or(0xFF);
        match self.holds(offset, bytes.len(), expected).await? {
            true => Ok(()),
            false => Err(VerifyError::Mismatch),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::ram_flash::{PAGE_SIZE, RamFlash};
    use embassy_futures::block_on;

    type Flash = VerifiedFlash<RamFlash<{ 2 * PAGE_SIZE }>>;

    #[test]
    fn a_good_write_and_erase_pass() {
        let mut flash = Flash::new(RamFlash::new());
        block_on(async {
            flash.write(64, &[1, 2, 3, 4, 5, 6, 7, 8]).await.unwrap();
            flash.erase(0, PAGE_SIZE as u32).await.unwrap();
        });
    }

    #[test]
    fn a_program_that_stores_nothing_is_a_mismatch() {
        let mut flash = Flash::new(RamFlash::new());
        flash.inner().fail_silently(0, u32::MAX);
        let result = block_on(flash.write(64, &[1, 2, 3, 4, 5, 6, 7, 8]));
        assert_eq!(result, Err(VerifyError::Mismatch));
        // The bare model reports success for the same write: the fault being caught.
        let mut bare = RamFlash::<{ 2 * PAGE_SIZE }>::new();
        bare.fail_silently(0, u32::MAX);
        assert_eq!(block_on(bare.write(64, &[1, 2, 3, 4, 5, 6, 7, 8])), Ok(()));
    }

    #[test]
    fn an_erase_that_erases_nothing_is_a_mismatch() {
        let mut flash = Flash::new(RamFlash::new());
        block_on(flash.write(8, &[0; 8])).unwrap();
        flash.inner().fail_silently(0, 1);
        assert_eq!(
            block_on(flash.erase(0, PAGE_SIZE as u32)),
            Err(VerifyError::Mismatch)
        );
    }

    #[test]
    fn a_write_longer_than_a_read_back_chunk_is_checked_to_its_end() {
        let mut flash = Flash::new(RamFlash::new());
        let data = [0x5Au8; 3 * CHUNK];
        block_on(flash.write(0, &data)).unwrap();
        // The last byte turns out wrong: a mismatch, however far from the start.
        flash.inner().bytes_mut()[3 * CHUNK - 1] = 0x00;
        let mut check = [0u8; 3 * CHUNK];
        block_on(flash.read(0, &mut check)).unwrap();
        assert_eq!(check[3 * CHUNK - 1], 0);
        block_on(flash.erase(0, PAGE_SIZE as u32)).unwrap();
        // The third double word of the next write is dropped.
        flash.inner().fail_silently(2, 1);
        assert_eq!(block_on(flash.write(0, &data)), Err(VerifyError::Mismatch));
    }
}
