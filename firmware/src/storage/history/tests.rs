//! History store behaviour, power cuts at every step, damaged pages.

use embassy_futures::block_on;
use sequential_storage::cache::Cache;
use sequential_storage::queue::{QueueConfig, QueueStorage};

use super::*;
use crate::storage::ram_flash::{PAGE_SIZE, RamFlash};

/// Three L4 pages: small enough to fill quickly, the smallest region where dropping the
/// oldest page still leaves older entries.
const REGION: usize = 3 * PAGE_SIZE;
type Flash = RamFlash<REGION>;
type Store = HistoryStore<Flash>;

fn boot(flash: Flash) -> (Store, BootScan) {
    let mut store = HistoryStore::new(flash, 0..REGION as u32).unwrap();
    let scan = block_on(store.scan()).unwrap();
    (store, scan)
}

fn draft(n: u32) -> Draft {
    Draft {
        stamp: Stamp {
            uptime_ms: n * 10,
            clock_at_boot: None,
            unit: Unit::default(),
        },
        event: Event::ProcessChanged {
            from: n as u16,
            to: n as u16 + 1,
            by: ChangedBy::Text,
        },
    }
}

fn record(store: &mut Store, n: u32) -> Entry {
    block_on(store.record(draft(n))).unwrap()
}

/// Every entry, oldest first.
fn all(store: &mut Store) -> (heapless::Vec<Entry, 400>, u32) {
    let newest = block_on(store.newest::<400>()).unwrap();
    let mut entries = newest.entries;
    entries.reverse();
    (entries, newest.skipped)
}

/// Entries per page, measured: how many fit before the first page is dropped.
fn fill_until_drop(store: &mut Store) -> u32 {
    let mut n = 0;
    loop {
        record(store, n);
        n += 1;
        let (entries, _) = all(store);
        if entries.first().map(|e| e.sequence) != Some(0) {
            return n;
        }
    }
}

#[test]
fn entries_come_back_newest_first_and_boots_count() {
    let (mut store, scan) = boot(Flash::new());
    assert_eq!(scan.entries, 0);
    for n in 0..5 {
        assert_eq!(record(&mut store, n).sequence, n);
    }
    let newest = block_on(store.newest::<3>()).unwrap();
    let sequences: heapless::Vec<u32, 3> = newest.entries.iter().map(|e| e.sequence).collect();
    assert_eq!(sequences.as_slice(), &[4, 3, 2]);
    assert_eq!(newest.entries[0].event, draft(4).event);

    let (mut store, scan) = boot(store.into_flash());
    assert_eq!(
        scan,
        BootScan {
            boot: 1,
            next_sequence: 5,
            entries: 5,
            skipped: 0,
            pages_recovered: 0
        }
    );
    let entry = record(&mut store, 5);
    assert_eq!((entry.sequence, entry.boot), (5, 1));
    let (_, scan) = boot(store.into_flash());
    assert_eq!((scan.boot, scan.next_sequence), (2, 6));
}

#[test]
fn a_full_history_drops_its_oldest_page_and_the_size_is_as_documented() {
    let (mut store, _) = boot(Flash::new());
    let written = fill_until_drop(&mut store);
    // Three full pages before the first is dropped: the module docs' 50 per page.
    assert_eq!(written - 1, 3 * 50);
    let (entries, _) = all(&mut store);
    assert_eq!(entries.first().map(|e| e.sequence), Some(50));
    assert_eq!(entries.last().map(|e| e.sequence), Some(written - 1));
    for n in written..written + 300 {
        record(&mut store, n);
    }
    let (entries, skipped) = all(&mut store);
    assert_eq!(skipped, 0);
    assert!(entries.len() >= 100);
    assert!(
        entries
            .windows(2)
            .all(|w| w[1].sequence == w[0].sequence + 1)
    );
}

#[test]
fn clear_leaves_one_entry_and_keeps_counting() {
    let (mut store, _) = boot(Flash::new());
    for n in 0..3 {
        record(&mut store, n);
    }
    let cleared = block_on(store.clear(Stamp::default())).unwrap();
    assert_eq!((cleared.sequence, cleared.event), (3, Event::Cleared));
    let (entries, _) = all(&mut store);
    assert_eq!(entries.as_slice(), &[cleared]);
    let (_, scan) = boot(store.into_flash());
    assert_eq!((scan.boot, scan.next_sequence), (1, 4));
}

#[test]
fn undecodable_entries_are_skipped_and_counted() {
    let (mut store, _) = boot(Flash::new());
    record(&mut store, 0);
    let mut queue = QueueStorage::new(
        store.flash(),
        QueueConfig::new(0..REGION as u32),
        Cache::new_uncached(),
    );
    block_on(queue.push(&[9, 1, 2, 3], false)).unwrap();
    block_on(queue.push(&[], false)).unwrap();
    // A well-formed entry but for byte 18: a fifth unit on the line.
    let mut fifth_unit = [0u8; MAX_ENTRY];
    let len = Entry {
        sequence: 1,
        boot: 0,
        uptime_ms: 0,
        clock_at_boot: None,
        unit: Unit::default(),
        event: Event::LinkLost,
    }
    .emit(&mut fifth_unit)
    .unwrap();
    fifth_unit[18] = 0x41;
    block_on(queue.push(&fifth_unit[..len], false)).unwrap();
    record(&mut store, 1);
    let (entries, skipped) = all(&mut store);
    assert_eq!(skipped, 3);
    assert_eq!(entries.len(), 2);
    let (_, scan) = boot(store.into_flash());
    assert_eq!((scan.entries, scan.skipped, scan.next_sequence), (2, 3, 2));
}

/// Starts from `before`, cuts the power at every step of `operation` in turn, boots again
/// and checks the history: the entries before are all there (except those `may_lose`
/// says a drop of the oldest page may take), nothing else but `new` appears, the boot scan
/// does not fail and (if `keeps_counting`) the sequence does not go backwards, and the store
/// records again.
fn cut_at_every_step(
    before: &Flash,
    operation: impl Fn(&mut Store),
    may_lose: impl Fn(u32) -> bool,
    new: &[Event],
    keeps_counting: bool,
) -> u32 {
    let (mut reference, scan_before) = boot(before.clone());
    let (old, _) = all(&mut reference);
    let mut cuts = 0;
    for step in 0.. {
        for seed in [1, 0xDEAD_BEEF, 0x1234_5678] {
            let mut flash = before.clone();
            let (mut store, _) = boot(flash.clone());
            store.flash().cut_power_after(step, seed);
            operation(&mut store);
            if !store.flash().power_was_cut() {
                assert!(step > 0 && seed == 1, "the operation took no flash steps");
                return cuts;
            }
            cuts += 1;
            flash = store.into_flash();
            flash.power_cycle();
            let (mut store, scan) = boot(flash);
            if keeps_counting {
                assert!(
                    scan.next_sequence >= scan_before.next_sequence,
                    "step {step}"
                );
            }
            let (entries, _) = all(&mut store);
            for e in &old {
                assert!(
                    may_lose(e.sequence) || entries.contains(e),
                    "step {step} seed {seed:#x}: lost {e:?}, {} left",
                    entries.len()
                );
            }
            for e in entries.iter().filter(|e| !old.contains(e)) {
                assert!(new.contains(&e.event), "step {step}: {e:?} appeared");
            }
            // The store still works after the cut.
            let entry = record(&mut store, 999);
            let (entries, _) = all(&mut store);
            assert_eq!(entries.last(), Some(&entry), "step {step}");
        }
    }
    unreachable!()
}

#[test]
fn a_power_cut_at_any_step_of_a_push_loses_at_most_that_entry() {
    let (mut store, _) = boot(Flash::new());
    for n in 0..10 {
        record(&mut store, n);
    }
    let before = store.into_flash();
    let cuts = cut_at_every_step(
        &before,
        |store| {
            let _ = block_on(store.record(draft(10)));
        },
        |_| false,
        &[draft(10).event],
        true,
    );
    assert!(cuts >= 4);
}

#[test]
fn a_power_cut_at_any_step_of_a_push_that_drops_the_oldest_page() {
    let (mut store, _) = boot(Flash::new());
    let written = fill_until_drop(&mut store);
    // Fill up to the brim again: the next push has to erase the oldest page.
    let mut n = written;
    while {
        let (entries, _) = all(&mut store);
        entries.len() < 150
    } {
        record(&mut store, n);
        n += 1;
        if n > written + 200 {
            break;
        }
    }
    let (entries, _) = all(&mut store);
    let oldest_page_end = entries[0].sequence + 50;
    let before = store.into_flash();
    let next = n;
    let (mut uncut, _) = boot(before.clone());
    record(&mut uncut, next);
    assert_eq!(
        all(&mut uncut).0[0].sequence,
        oldest_page_end,
        "the push dropped a page"
    );
    cut_at_every_step(
        &before,
        |store| {
            let _ = block_on(store.record(draft(next)));
        },
        |sequence| sequence < oldest_page_end,
        &[draft(next).event],
        true,
    );
}

#[test]
fn a_power_cut_at_any_step_of_clear_never_fails_the_boot() {
    let (mut store, _) = boot(Flash::new());
    for n in 0..120 {
        record(&mut store, n);
    }
    let before = store.into_flash();
    cut_at_every_step(
        &before,
        |store| {
            let _ = block_on(store.clear(Stamp::default()));
        },
        |_| true,
        &[Event::Cleared],
        // Cut after the last erase and before the Cleared entry, nothing is left to count
        // from: the sequence and boot count start again at 0 (documented on `clear`).
        false,
    );
}

#[test]
fn a_page_of_random_bits_costs_that_page_not_the_history() {
    let (mut store, _) = boot(Flash::new());
    for n in 0..120 {
        record(&mut store, n);
    }
    let mut flash = store.into_flash();
    tear_erase_of_middle_page(&mut flash);
    let (mut store, scan) = boot(flash);
    assert_eq!(scan.pages_recovered, 1);
    let (entries, _) = all(&mut store);
    assert_eq!(entries.len(), 70, "{scan:?}");
    record(&mut store, 500);
}

/// What an erase of the middle page torn by a power cut leaves: random bits set.
fn tear_erase_of_middle_page(flash: &mut Flash) {
    let mut noise = 0x2545_F491u32;
    for b in &mut flash.bytes_mut()[PAGE_SIZE..2 * PAGE_SIZE] {
        noise ^= noise << 13;
        noise ^= noise >> 17;
        noise ^= noise << 5;
        *b |= noise as u8;
    }
}

#[test]
fn a_page_damaged_after_boot_does_not_stop_recording() {
    let (mut store, _) = boot(Flash::new());
    for n in 0..120 {
        record(&mut store, n);
    }
    tear_erase_of_middle_page(store.flash());
    let entry = record(&mut store, 500);
    let (entries, _) = all(&mut store);
    assert_eq!(entries.last(), Some(&entry));
}

#[test]
fn a_storm_through_the_pending_queue_is_recorded_with_its_loss() {
    let (mut store, _) = boot(Flash::new());
    let mut pending = Pending::<8>::new();
    for n in 0..50 {
        pending.push(draft(n));
    }
    while let Some(d) = pending.take() {
        block_on(store.record(d)).unwrap();
    }
    pending.push(draft(50));
    while let Some(d) = pending.take() {
        block_on(store.record(d)).unwrap();
    }
    let newest = block_on(store.newest::<2>()).unwrap();
    assert_eq!(newest.entries[0].event, draft(50).event);
    assert_eq!(newest.entries[1].event, Event::EntriesDropped { count: 42 });
}

#[test]
fn the_ram_figures_in_the_module_docs_hold() {
    assert!(core::mem::size_of::<Draft>() <= 24);
    assert!(core::mem::size_of::<Store>() - core::mem::size_of::<Flash>() <= 64);
}

#[test]
fn a_region_of_less_than_two_whole_pages_is_refused() {
    let page = PAGE_SIZE as u32;
    for region in [0..page, 0..page + 8, 8..2 * page + 8, page..0] {
        assert!(matches!(
            HistoryStore::new(Flash::new(), region.clone()),
            Err(crate::storage::StoreError::BadRegion)
        ));
    }
    assert!(HistoryStore::new(Flash::new(), page..3 * page).is_ok());
}

/// Many boots, each cut at a pseudo-random step of a run of pushes: the history always
/// boots, stays in order, and keeps every entry a completed push wrote (but those of the
/// pages a full history drops).
#[test]
fn many_cuts_at_random_steps_keep_the_history_in_order() {
    let mut flash = Flash::new();
    let mut noise = 0x9E37_79B9u32;
    let mut last_kept: Option<Entry> = None;
    for round in 0..1000 {
        noise ^= noise << 13;
        noise ^= noise >> 17;
        noise ^= noise << 5;
        let (mut store, _) = boot(flash);
        let (entries, skipped) = all(&mut store);
        assert_eq!(skipped, 0);
        assert!(
            entries.windows(2).all(|w| w[0].sequence < w[1].sequence),
            "round {round}: out of order"
        );
        if let Some(kept) = last_kept {
            assert!(entries.contains(&kept), "round {round}: lost {kept:?}");
        }
        store.flash().cut_power_after(noise % 40, noise);
        for n in 0..10 {
            match block_on(store.record(draft(round * 10 + n))) {
                Ok(entry) => last_kept = Some(entry),
                Err(_) if store.flash().power_was_cut() => break,
                Err(e) => panic!("round {round}: {e:?} without a cut"),
            }
        }
        flash = store.into_flash();
        flash.power_cycle();
    }
}
