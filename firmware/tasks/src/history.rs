//! The history task: keeps the bridge's event history (`plasma_firmware::storage::history`)
//! in the board's history flash ([`Board::HistoryFlash`], every write and erase read back as
//! the settings' are), in thread mode below every task that matters for a cut.
//!
//! The bridge task hands drafts over through a bounded channel only while it has room
//! ([`BoardHistory`] as the supervisor's `HistoryKeeper`), so it never waits for a flash
//! write: while the channel is full the drafts wait in the bridge's own bounded queue, which
//! counts what it drops. START is driven by the I/O executor above thread mode and never
//! waits either. A `HISTORY` request and its answer go through signals.

use core::future::Future;
use core::ops::Range;

use defmt::{error, info, warn};
use embassy_futures::select::{Either3, select3};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::Timer;
use plasma_firmware::platform::supervisor::HistoryKeeper;
use plasma_firmware::platform::watchdog::TaskId;
use plasma_firmware::storage::history::{
    Draft, HistoryAnswer, HistoryRequest, HistoryStore, HistoryUnavailable, serve,
};
use plasma_firmware::storage::verified::VerifiedFlash;

use crate::Board;
use crate::progress::report;
use crate::settings::report_flash_errors;

/// The history over the board's history flash, read back after every write and erase.
pub type Store<B> = HistoryStore<VerifiedFlash<<B as Board>::HistoryFlash>>;

/// The store over `region` of `flash`, or `None` (logged) if the region does not suit it: a
/// mismatch between the board's region and the flash's page size, a build mistake.
pub fn open<B: Board>(flash: B::HistoryFlash, region: Range<u32>) -> Option<Store<B>> {
    match HistoryStore::new(VerifiedFlash::new(flash), region) {
        Ok(store) => Some(store),
        Err(_) => {
            error!("history region: not whole pages; the history will not be kept");
            None
        }
    }
}

/// Drafts on their way to the flash; more wait in the bridge.
const DRAFT_SLOTS: usize = 4;

/// Drafts (bridge → history task).
static DRAFTS: Channel<CriticalSectionRawMutex, Draft, DRAFT_SLOTS> = Channel::new();
/// A `HISTORY` command (bridge → history task).
static REQUEST: Signal<CriticalSectionRawMutex, HistoryRequest> = Signal::new();
/// Its answer (history task → bridge).
static ANSWER: Signal<CriticalSectionRawMutex, HistoryAnswer> = Signal::new();

/// The bridge task's handle on the history task.
pub struct BoardHistory;

impl HistoryKeeper for BoardHistory {
    fn has_room(&self) -> bool {
        !DRAFTS.is_full()
    }

    fn record(&mut self, draft: Draft) {
        // The supervisor asked `has_room` first, and only this task takes room away.
        let _ = DRAFTS.try_send(draft);
    }

    fn start(&mut self, request: HistoryRequest) {
        ANSWER.reset();
        REQUEST.signal(request);
    }

    fn finished(&mut self) -> impl Future<Output = HistoryAnswer> {
        ANSWER.wait()
    }
}

/// Reads the history at boot (its boot count and next sequence number), then writes the
/// drafts and serves `HISTORY`. The body of the board's history task. Nothing here can fail
/// the boot: an unreadable history is logged and `HISTORY` answers `ERR STORAGE`.
pub async fn run<B: Board>(mut store: Option<Store<B>>, progress: TaskId) {
    if let Some(history) = store.as_mut() {
        match history.scan().await {
            Ok(scan) => info!(
                "history: boot {}, {} entries ({} skipped, {} torn pages emptied)",
                scan.boot, scan.entries, scan.skipped, scan.pages_recovered
            ),
            Err(_) => {
                warn!("history: unreadable; not kept this boot");
                store = None;
            }
        }
        report_flash_errors::<B>();
    }
    let mut asked: Option<HistoryRequest> = None;
    loop {
        // A `HISTORY` is answered once the drafts handed over before it are written: the
        // answer shows them.
        if DRAFTS.is_empty()
            && let Some(request) = asked.take()
        {
            let answer = match store.as_mut() {
                Some(history) => serve(history, request).await,
                None => Err(HistoryUnavailable),
            };
            ANSWER.signal(answer);
        }
        let next = select3(DRAFTS.receive(), REQUEST.wait(), Timer::after_millis(250)).await;
        report(progress);
        match next {
            Either3::First(draft) => write::<B>(&mut store, draft).await,
            Either3::Second(request) => asked = Some(request),
            Either3::Third(()) => {}
        }
    }
}

/// Writes one draft (dropped when the history is not kept, and logged when the write failed).
async fn write<B: Board>(store: &mut Option<Store<B>>, draft: Draft) {
    let Some(history) = store.as_mut() else {
        return;
    };
    if history.record(draft).await.is_err() {
        warn!("history: an entry was not written");
        report_flash_errors::<B>();
    }
}
