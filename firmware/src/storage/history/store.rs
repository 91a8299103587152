//! [`HistoryStore`]: the entries in a sequential-storage queue over their own flash region.

use core::ops::Range;

use embedded_storage_async::nor_flash::NorFlash;
use heapless::{Deque, Vec};
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::queue::{QueueConfig, QueueStorage};

use super::entry::{Entry, Event, MAX_ENTRY};
use super::pending::{Draft, Stamp};
use crate::storage::StoreError;

/// Read buffer: the largest entry rounded up to sequential-storage's largest word (32 bytes).
const READ_BUFFER: usize = MAX_ENTRY.next_multiple_of(32);

/// Word-aligned buffer: some internal flash drivers want aligned source data.
#[repr(align(8))]
struct Buffer([u8; READ_BUFFER]);

type Queue<'a, F> = QueueStorage<&'a mut F, Cache<Uncached, Uncached, Uncached, ()>>;

/// What the boot scan found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BootScan {
    /// This boot's count (one more than the newest entry's; 0 on an empty history).
    pub boot: u32,
    /// The sequence number the next entry gets.
    pub next_sequence: u32,
    /// Entries read.
    pub entries: u32,
    /// Entries that could not be decoded (a version or kind this firmware does not know)
    /// and were skipped. Items torn by a power cut fail sequential-storage's CRC and are not
    /// seen at all.
    pub skipped: u32,
    /// Pages emptied because a torn erase had left them as random bits (see
    /// [`HistoryStore::scan`]).
    pub pages_recovered: u32,
}

/// The newest entries, newest first, and how many undecodable entries were skipped.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Newest<const N: usize> {
    /// Newest first.
    pub entries: Vec<Entry, N>,
    /// Entries skipped because they could not be decoded.
    pub skipped: u32,
}

/// The history over a region of a NOR flash.
pub struct HistoryStore<F: NorFlash> {
    flash: F,
    region: Range<u32>,
    buffer: Buffer,
    boot: u32,
    next_sequence: u32,
}

/// The counters and the region (not the flash's contents).
impl<F: NorFlash> core::fmt::Debug for HistoryStore<F> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("HistoryStore")
            .field("region", &self.region)
            .field("boot", &self.boot)
            .field("next_sequence", &self.next_sequence)
            .finish()
    }
}

impl<F: NorFlash> HistoryStore<F> {
    /// A store in `region` (flash offsets, whole erase pages, at least two). Nothing is read
    /// yet: call [`Self::scan`] once at boot before recording.
    pub fn new(flash: F, region: Range<u32>) -> Result<Self, StoreError<F::Error>> {
        let pages = region.end.saturating_sub(region.start) / F::ERASE_SIZE as u32;
        if pages < 2 {
            return Err(StoreError::BadRegion);
        }
        QueueConfig::<&mut F>::try_new(region.clone()).map_err(|_| StoreError::BadRegion)?;
        Ok(HistoryStore {
            flash,
            region,
            buffer: Buffer([0; READ_BUFFER]),
            boot: 0,
            next_sequence: 0,
        })
    }

    fn queue(flash: &mut F, region: Range<u32>) -> Queue<'_, F> {
        // Validated in `new`.
        QueueStorage::new(flash, QueueConfig::new(region), Cache::new_uncached())
    }

    /// Calls `each` with every decodable entry, oldest first; returns how many were skipped.
    /// `dyn`: one copy of the read loop in the image for every caller.
    async fn for_each(&mut self, each: &mut dyn FnMut(Entry)) -> Result<u32, StoreError<F::Error>> {
        let mut queue = Self::queue(&mut self.flash, self.region.clone());
        let mut items = queue.iter().await?;
        let mut skipped = 0u32;
        while let Some(item) = items.next(&mut self.buffer.0).await? {
            match Entry::parse(&item) {
                Ok(entry) => each(entry),
                Err(_) => skipped = skipped.saturating_add(1),
            }
        }
        Ok(skipped)
    }

    /// Boot: finds the next sequence number and this boot's count.
    ///
    /// First every page that an erase torn by a power cut left as random bits is emptied:
    /// sequential-storage reads such a page as a valid state and then hides, or writes
    /// after, the wrong pages (found by the tests: entries recorded after a cut during
    /// [`Self::clear`] were not read back). The history loses that page, not the rest.
    pub async fn scan(&mut self) -> Result<BootScan, StoreError<F::Error>> {
        let pages_recovered = self.erase_torn_pages().await?;
        let mut scan = self.read_counters().await?;
        scan.pages_recovered = pages_recovered;
        self.boot = scan.boot;
        self.next_sequence = scan.next_sequence;
        Ok(scan)
    }

    async fn read_counters(&mut self) -> Result<BootScan, StoreError<F::Error>> {
        let mut newest: Option<(u32, u32)> = None;
        let mut entries = 0u32;
        let skipped = self
            .for_each(&mut |entry| {
                entries = entries.saturating_add(1);
                let (sequence, boot) = newest.unwrap_or((0, 0));
                newest = Some((sequence.max(entry.sequence), boot.max(entry.boot)));
            })
            .await?;
        let (next_sequence, boot) = match newest {
            Some((sequence, boot)) => (sequence.wrapping_add(1), boot.wrapping_add(1)),
            None => (0, 0),
        };
        Ok(BootScan {
            boot,
            next_sequence,
            entries,
            skipped,
            pages_recovered: 0,
        })
    }

    /// The two page-state words of `page` (its first and last word, which sequential-storage
    /// programs to all zeros): whether each is plausible (erased or programmed, not a mix).
    async fn page_markers(&mut self, page: u32) -> Result<[bool; 2], StoreError<F::Error>> {
        let word = F::WRITE_SIZE.clamp(1, 8) as u32;
        let mut plausible = [true; 2];
        for (slot, at) in plausible
            .iter_mut()
            .zip([page, page + F::ERASE_SIZE as u32 - word])
        {
            let mut marker = [0u8; 8];
            let marker = marker.get_mut(..word as usize).unwrap_or_default();
            self.flash
                .read(at, marker)
                .await
                .map_err(StoreError::Flash)?;
            *slot = marker.iter().all(|&b| b == 0xFF) || marker.iter().all(|&b| b == 0);
        }
        Ok(plausible)
    }

    fn pages(&self) -> impl Iterator<Item = u32> + use<F> {
        (self.region.start..self.region.end).step_by(F::ERASE_SIZE)
    }

    /// Empties every page whose two page-state words are both a mix of bits: what an erase
    /// torn by a power cut leaves of a closed page (a torn marker program changes one word,
    /// which sequential-storage itself reads correctly). Returns how many.
    async fn erase_torn_pages(&mut self) -> Result<u32, StoreError<F::Error>> {
        let mut erased = 0;
        for page in self.pages() {
            if self.page_markers(page).await? == [false, false] {
                self.empty_page(page).await?;
                erased += 1;
            }
        }
        Ok(erased)
    }

    /// Erases `page` and marks it closed: an empty page in the middle of the queue. A page
    /// that is only erased would read as the free page after the newest, and the queue would
    /// lose its pages after it (and count sequence numbers again from before them).
    async fn empty_page(&mut self, page: u32) -> Result<(), StoreError<F::Error>> {
        self.erase_page(page).await?;
        let zeros = [0u8; 32];
        let word = zeros.get(..F::WRITE_SIZE).ok_or(StoreError::Internal)?;
        for at in [page, page + F::ERASE_SIZE as u32 - word.len() as u32] {
            self.flash
                .write(at, word)
                .await
                .map_err(StoreError::Flash)?;
        }
        Ok(())
    }

    async fn erase_page(&mut self, page: u32) -> Result<(), StoreError<F::Error>> {
        self.flash
            .erase(page, page + F::ERASE_SIZE as u32)
            .await
            .map_err(StoreError::Flash)
    }

    /// This boot's count (valid after [`Self::scan`]).
    pub fn boot(&self) -> u32 {
        self.boot
    }

    /// Writes one entry; when the region is full the oldest page of entries is dropped to
    /// make room. Returns the entry as written.
    pub async fn record(&mut self, draft: Draft) -> Result<Entry, StoreError<F::Error>> {
        let entry = Entry {
            sequence: self.next_sequence,
            boot: self.boot,
            uptime_ms: draft.stamp.uptime_ms,
            clock_at_boot: draft.stamp.clock_at_boot,
            unit: draft.stamp.unit,
            event: draft.event,
        };
        // A sequence number is used once, even by an entry a power cut tore.
        self.next_sequence = self.next_sequence.wrapping_add(1);
        let mut bytes = [0u8; MAX_ENTRY];
        let len = entry.emit(&mut bytes).map_err(|_| StoreError::TooLarge)?;
        Self::queue(&mut self.flash, self.region.clone())
            .push(&bytes[..len], true)
            .await?;
        Ok(entry)
    }

    /// The newest `N` entries, newest first.
    pub async fn newest<const N: usize>(&mut self) -> Result<Newest<N>, StoreError<F::Error>> {
        let mut window: Deque<Entry, N> = Deque::new();
        let skipped = self
            .for_each(&mut |entry| {
                if window.is_full() {
                    window.pop_front();
                }
                // Cannot fail: a slot was just freed (and N = 0 keeps nothing).
                let _ = window.push_back(entry);
            })
            .await?;
        // Popped one by one, not `iter().rev().collect()`: that copy compiles to the
        // image's only memmove call, and memmove's code is 1.5 KB of flash.
        let mut entries = Vec::new();
        while let Some(entry) = window.pop_back() {
            // Cannot fail: `entries` holds as many as `window`.
            let _ = entries.push(entry);
        }
        Ok(Newest { entries, skipped })
    }

    /// Erases the history; its first entry then says it was cleared (and keeps the sequence
    /// and boot count going). A power cut between the erase and that entry leaves an empty
    /// history, whose next boot starts counting at 0 again.
    pub async fn clear(&mut self, stamp: Stamp) -> Result<Entry, StoreError<F::Error>> {
        Self::queue(&mut self.flash, self.region.clone())
            .erase_all()
            .await?;
        self.record(Draft {
            stamp,
            event: Event::Cleared,
        })
        .await
    }

    /// The flash, e.g. to inspect a model in tests.
    pub fn flash(&mut self) -> &mut F {
        &mut self.flash
    }

    /// The flash, to use it for something else.
    pub fn into_flash(self) -> F {
        self.flash
    }
}
