//! The fault and event history: what happened, kept in flash across power cuts.
//!
//! - [`entry`]: one [`Entry`] (sequence number, boot count, time, unit, [`Event`]) and its
//!   versioned encoding.
//! - [`pending`]: the bounded RAM queue ([`Pending`]) the event sources push into without
//!   waiting; a background task takes [`Draft`]s from it and records them.
//! - [`HistoryStore`]: a sequential-storage **queue** over the history's own flash region.
//!   When the region is full, pushing erases the oldest page (sequential-storage's
//!   overwrite mode: the STM32L4 flash cannot clear a popped item's bits again, so popping
//!   single entries is not available). An entry torn by a power cut fails its CRC and is not
//!   seen; one this firmware cannot decode is skipped and counted; a page that makes the
//!   whole queue unreadable is erased at boot ([`HistoryStore::scan`]).
//!
//! Size: an entry is 21 to [`MAX_ENTRY`] (29) bytes, 32 in flash with sequential-storage's
//! 8-byte item header, padded to 8-byte words: 40 bytes. A 2 KiB page holds 50 entries after
//! its two page-state words, so the proposed region of 8 pages (16 KiB, in bank 2 just below
//! the settings) keeps at least the newest 350 entries (one page is erased to make room).
//! RAM: the store takes at most 64 bytes beside its flash driver (a 32-byte read buffer,
//! the region and the counters); a [`Pending`] of `N` drafts at most `N * 24` bytes plus 8
//! (both tied by a test).
//!
//! ```
//! use embassy_futures::block_on;
//! use plasma_firmware::storage::history::{Draft, Event, HistoryStore, Stamp};
//! use plasma_firmware::storage::ram_flash::RamFlash;
//!
//! let mut history = HistoryStore::new(RamFlash::<8192>::new(), 0..8192).unwrap();
//! block_on(async {
//!     let boot = history.scan().await.unwrap();
//!     assert_eq!((boot.boot, boot.next_sequence), (0, 0));
//!     let stamp = Stamp { uptime_ms: 1500, ..Stamp::default() };
//!     history.record(Draft { stamp, event: Event::LinkLost }).await.unwrap();
//!     history.record(Draft { stamp, event: Event::LinkBack }).await.unwrap();
//!     let newest = history.newest::<1>().await.unwrap();
//!     assert_eq!(newest.entries[0].event, Event::LinkBack);
//!     assert_eq!(newest.entries[0].sequence, 1);
//! });
//! ```

pub mod entry;
pub mod pending;
pub mod service;
mod store;

pub use entry::{ChangedBy, Entry, EntryError, Event, MAX_ENTRY, Unit};
pub use pending::{Draft, Pending, Stamp};
pub use service::{HistoryAnswer, HistoryPage, HistoryRequest, HistoryUnavailable, serve};
pub use store::{BootScan, HistoryStore, Newest};

#[cfg(test)]
mod tests;
