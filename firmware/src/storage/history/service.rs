//! What the bridge asks of the history and what it gets back: the one exchange between the
//! sans-IO [`Bridge`](crate::bridge::Bridge) and whoever owns the [`HistoryStore`] (the
//! board's history task, the host harness, pbtool), and [`serve`], the one answer to it.

use embedded_storage_async::nor_flash::NorFlash;
use heapless::Vec;
use plasma_protocol::cnc::HISTORY_MAX;

use super::entry::Entry;
use super::pending::Stamp;
use super::store::HistoryStore;

/// Entries one answer holds at most (`HISTORY 16`).
pub const ANSWER_CAPACITY: usize = HISTORY_MAX as usize;

/// A `HISTORY` command for the store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HistoryRequest {
    /// The newest `n` entries (at most [`ANSWER_CAPACITY`]).
    Newest(u8),
    /// Erase the history; its first entry then says so, with this stamp.
    Clear(Stamp),
}

/// The store's answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HistoryPage {
    /// The boot count of the running boot: its entries may be shown with the clock set
    /// since they were written.
    pub boot: u32,
    /// Newest first (empty for a clear).
    pub entries: Vec<Entry, ANSWER_CAPACITY>,
    /// Entries that could not be decoded and were skipped.
    pub skipped: u32,
}

/// The history could not be read or erased (the flash failed, or no history region).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HistoryUnavailable;

/// The answer to a [`HistoryRequest`].
pub type HistoryAnswer = Result<HistoryPage, HistoryUnavailable>;

/// Carries out `request` on `store`.
pub async fn serve<F: NorFlash>(
    store: &mut HistoryStore<F>,
    request: HistoryRequest,
) -> HistoryAnswer {
    let boot = store.boot();
    match request {
        HistoryRequest::Newest(n) => {
            let newest = store
                .newest::<ANSWER_CAPACITY>()
                .await
                .map_err(|_| HistoryUnavailable)?;
            let mut entries = newest.entries;
            entries.truncate(usize::from(n));
            Ok(HistoryPage {
                boot,
                entries,
                skipped: newest.skipped,
            })
        }
        HistoryRequest::Clear(stamp) => {
            store.clear(stamp).await.map_err(|_| HistoryUnavailable)?;
            Ok(HistoryPage {
                boot,
                entries: Vec::new(),
                skipped: 0,
            })
        }
    }
}
