//! Settings store behaviour, power cuts at every step, and corrupted stores.

use super::ram_flash::{PAGE_SIZE, RamFlash, RamFlashError};
use super::*;
use embassy_futures::block_on;

/// Four L4 pages, as on the board.
const REGION: usize = 4 * PAGE_SIZE;
type Flash = RamFlash<REGION>;
type Store = SettingsStore<Flash>;

fn store(flash: Flash) -> Store {
    SettingsStore::new(flash, 0..REGION as u32).unwrap()
}

/// Settings whose every byte depends on a generation number, so a mix of two generations
/// or a garbled payload cannot decode as either.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
struct TestConfig {
    generation: u32,
    len: usize,
}

impl TestConfig {
    fn new(generation: u32, len: usize) -> Self {
        TestConfig { generation, len }
    }

    fn byte(&self, i: usize) -> u8 {
        (self.generation.wrapping_mul(31).wrapping_add(i as u32 * 7)) as u8
    }
}

impl Persistent for TestConfig {
    const VERSION: u8 = 2;

    fn encode(&self, out: &mut [u8]) -> usize {
        out[..4].copy_from_slice(&self.generation.to_le_bytes());
        for (i, b) in out.iter_mut().enumerate().take(self.len).skip(4) {
            *b = self.byte(i);
        }
        self.len.max(4)
    }

    fn decode(payload: &[u8]) -> Option<Self> {
        let generation = u32::from_le_bytes(payload.get(..4)?.try_into().ok()?);
        let config = TestConfig::new(generation, payload.len());
        (4..payload.len())
            .all(|i| payload[i] == config.byte(i))
            .then_some(config)
    }

    fn migrate(version: u8, payload: &[u8]) -> Option<Self> {
        // Version 1 stored only a u16 generation.
        match (version, payload) {
            (1, [lo, hi]) => Some(TestConfig::new(u16::from_le_bytes([*lo, *hi]).into(), 4)),
            _ => None,
        }
    }
}

fn load(store: &mut Store) -> LoadedSettings<TestConfig> {
    block_on(store.load_settings::<TestConfig>())
}

fn save(store: &mut Store, config: &TestConfig) -> Result<(), StoreError<RamFlashError>> {
    block_on(store.save_settings(config))
}

#[test]
fn first_boot_is_empty_defaults() {
    let mut s = store(Flash::new());
    let loaded = load(&mut s);
    assert_eq!(loaded.outcome, LoadOutcome::Empty);
    assert_eq!(loaded.settings, TestConfig::default());
    assert!(loaded.outcome.is_defaults() && !loaded.outcome.is_problem());
    assert_eq!(block_on(s.load()), Ok(None));
}

#[test]
fn save_then_load_survives_a_reboot() {
    let mut s = store(Flash::new());
    save(&mut s, &TestConfig::new(1, 40)).unwrap();
    save(&mut s, &TestConfig::new(2, 40)).unwrap();
    let mut rebooted = store(s.into_flash());
    let loaded = load(&mut rebooted);
    assert_eq!(loaded.outcome, LoadOutcome::Loaded);
    assert_eq!(loaded.settings, TestConfig::new(2, 40));
    let record = block_on(rebooted.load()).unwrap().unwrap();
    assert_eq!(record.version, TestConfig::VERSION);
    assert_eq!(record.payload.len(), 40);
}

#[test]
fn many_saves_wrap_around_the_pages() {
    let mut s = store(Flash::new());
    // ~270 bytes per item: 7 per page, so 200 saves go round the 4 pages many times.
    for generation in 0..200 {
        save(&mut s, &TestConfig::new(generation, MAX_PAYLOAD)).unwrap();
        assert_eq!(load(&mut s).settings.generation, generation);
    }
}

#[test]
fn payload_limits() {
    let mut s = store(Flash::new());
    assert_eq!(
        block_on(s.save(1, &[0; MAX_PAYLOAD + 1])),
        Err(StoreError::TooLarge)
    );
    block_on(s.save(1, &[0xA5; MAX_PAYLOAD])).unwrap();
    let record = block_on(s.load()).unwrap().unwrap();
    assert_eq!(record.payload, &[0xA5; MAX_PAYLOAD][..]);
    assert_eq!(record.sequence, 0);
    block_on(s.save(9, &[])).unwrap();
    assert_eq!(
        block_on(s.load()),
        Ok(Some(Record {
            version: 9,
            sequence: 1,
            payload: &[]
        }))
    );
}

#[test]
fn unknown_version_gives_defaults_and_says_so() {
    let mut s = store(Flash::new());
    block_on(s.save(TestConfig::VERSION + 1, &[1, 2, 3, 4])).unwrap();
    let loaded = load(&mut s);
    assert_eq!(loaded.settings, TestConfig::default());
    assert_eq!(
        loaded.outcome,
        LoadOutcome::UnknownVersion {
            found: TestConfig::VERSION + 1
        }
    );
    assert!(loaded.outcome.is_problem());
}

#[test]
fn older_version_is_migrated() {
    let mut s = store(Flash::new());
    block_on(s.save(1, &[0x34, 0x12])).unwrap();
    let loaded = load(&mut s);
    assert_eq!(loaded.outcome, LoadOutcome::Migrated { from: 1 });
    assert_eq!(loaded.settings, TestConfig::new(0x1234, 4));
    // A version-1 record the migration cannot read.
    block_on(s.save(1, &[1, 2, 3])).unwrap();
    assert_eq!(
        load(&mut s).outcome,
        LoadOutcome::UnknownVersion { found: 1 }
    );
}

#[test]
fn undecodable_payload_is_corrupted() {
    let mut s = store(Flash::new());
    block_on(s.save(TestConfig::VERSION, &[1, 0, 0, 0, 0xEE])).unwrap();
    let loaded = load(&mut s);
    assert_eq!(loaded.outcome, LoadOutcome::Corrupted);
    assert_eq!(loaded.settings, TestConfig::default());
}

#[test]
fn foreign_record_is_corrupted() {
    // Items under the settings key that do not start with RECORD_FORMAT, in both copies.
    let mut flash = Flash::new();
    block_on(async {
        for copy in [0..REGION as u32 / 2, REGION as u32 / 2..REGION as u32] {
            let mut map = MapStorage::<u8, _, _>::new(
                &mut flash,
                MapConfig::new(copy),
                Cache::new_uncached(),
            );
            let mut buf = [0u8; 64];
            let foreign: &[u8] = &[0x42, 2, 0, 0, 0, 0];
            map.store_item(&mut buf, &SETTINGS_KEY, &foreign)
                .await
                .unwrap();
        }
    });
    let mut s = store(flash);
    assert_eq!(block_on(s.load()), Err(StoreError::Corrupted));
    assert_eq!(load(&mut s).outcome, LoadOutcome::Corrupted);
    // And the next save still lands.
    save(&mut s, &TestConfig::new(5, 10)).unwrap();
    assert_eq!(load(&mut s).settings, TestConfig::new(5, 10));
}

#[test]
fn one_damaged_copy_is_outvoted_by_the_other() {
    let mut s = store(Flash::new());
    save(&mut s, &TestConfig::new(1, 16)).unwrap();
    save(&mut s, &TestConfig::new(2, 16)).unwrap();
    // Scribble over the whole first copy.
    let mut flash = s.into_flash();
    flash.bytes_mut()[..REGION / 2].fill(0x5A);
    let mut s = store(flash);
    let loaded = load(&mut s);
    assert_eq!(loaded.outcome, LoadOutcome::Loaded);
    assert_eq!(loaded.settings, TestConfig::new(2, 16));
    // The next save repairs the damaged copy; then the other copy can be lost too.
    save(&mut s, &TestConfig::new(3, 16)).unwrap();
    let mut flash = s.into_flash();
    flash.bytes_mut()[REGION / 2..].fill(0xA5);
    assert_eq!(load(&mut store(flash)).settings, TestConfig::new(3, 16));
}

#[test]
fn bad_regions_are_refused() {
    // Each of the two copies needs two pages.
    assert!(matches!(
        SettingsStore::new(Flash::new(), 0..3 * PAGE_SIZE as u32),
        Err(StoreError::BadRegion)
    ));
    assert!(matches!(
        SettingsStore::new(Flash::new(), 100..REGION as u32),
        Err(StoreError::BadRegion)
    ));
}

#[test]
fn flash_errors_are_reported_as_such() {
    let mut flash = Flash::new();
    flash.cut_power_after(0, 1);
    // Tear a write so the flash is dead, then load without power-cycling.
    let mut s = store(flash);
    assert!(save(&mut s, &TestConfig::new(1, 8)).is_err());
    assert_eq!(load(&mut s).outcome, LoadOutcome::FlashError);
}

/// Saves generations `0..count` into fresh flash.
fn flash_after_saves(count: u32, len: usize) -> Flash {
    let mut s = store(Flash::new());
    for generation in 0..count {
        save(&mut s, &TestConfig::new(generation, len)).unwrap();
    }
    s.into_flash()
}

/// The steps one more save takes from this state.
fn steps_of_next_save(flash: &Flash, config: &TestConfig) -> u32 {
    let mut s = store(flash.clone());
    let before = s.flash().steps();
    save(&mut s, config).unwrap();
    s.flash().steps() - before
}

/// From `base` (holding generations `0..prior`), a save of generation `prior` is cut after
/// every possible number of steps. After each cut and a reboot the load must give the old
/// settings (or defaults if there were none) or the new ones, and a further save must work.
fn cut_every_step(base: &Flash, prior: u32, len: usize, seed: u32) {
    let next = TestConfig::new(prior, len);
    let total = steps_of_next_save(base, &next);
    for cut in 0..=total {
        let mut flash = base.clone();
        flash.cut_power_after(cut, seed.wrapping_add(cut));
        let mut s = store(flash);
        let result = save(&mut s, &next);
        assert_eq!(
            result.is_ok(),
            cut == total,
            "prior {prior}, cut after {cut}/{total}"
        );

        let mut flash = s.into_flash();
        flash.power_cycle();
        let mut rebooted = store(flash);
        let loaded = load(&mut rebooted);
        match loaded.outcome {
            LoadOutcome::Loaded => {
                let generation = loaded.settings.generation;
                assert!(
                    generation == prior || (prior > 0 && generation == prior - 1),
                    "prior {prior}, cut after {cut}/{total}: loaded generation {generation}"
                );
                assert_eq!(loaded.settings.len, len);
            }
            LoadOutcome::Empty => assert_eq!(prior, 0, "settings lost, cut after {cut}/{total}"),
            other => panic!("prior {prior}, cut after {cut}/{total}: {other:?}"),
        }

        // The store keeps working after the cut.
        let after = TestConfig::new(prior + 1000, len);
        save(&mut rebooted, &after).unwrap();
        assert_eq!(load(&mut rebooted).settings, after);
    }
}

#[test]
fn power_cut_at_every_step_of_every_save_small_records() {
    // 40-byte payloads: ~35 items per page; 150 saves cross every page boundary and the
    // garbage collection of each page at least once.
    let mut base = Flash::new();
    for prior in 0..150 {
        cut_every_step(&base, prior, 40, prior * 7919);
        let mut s = store(base);
        save(&mut s, &TestConfig::new(prior, 40)).unwrap();
        base = s.into_flash();
    }
}

#[test]
fn power_cut_at_every_step_of_every_save_large_records() {
    // Full-size payloads: 7 items per page, so page migrations happen every few saves.
    let mut base = Flash::new();
    for prior in 0..60 {
        cut_every_step(&base, prior, MAX_PAYLOAD, 0xDEAD_BEEF ^ prior);
        let mut s = store(base);
        save(&mut s, &TestConfig::new(prior, MAX_PAYLOAD)).unwrap();
        base = s.into_flash();
    }
}

#[test]
fn power_cut_during_the_first_erase_of_a_used_store() {
    // A wipe torn half-way, then a load: defaults or the old settings, never garbage.
    for cut in 0..4 {
        let mut flash = flash_after_saves(20, 100);
        flash.cut_power_after(cut, 77 + cut);
        let mut s = store(flash);
        assert!(block_on(s.wipe()).is_err());
        let mut flash = s.into_flash();
        flash.power_cycle();
        let mut s = store(flash);
        let loaded = load(&mut s);
        assert!(
            matches!(
                loaded.outcome,
                LoadOutcome::Loaded | LoadOutcome::Empty | LoadOutcome::Corrupted
            ),
            "{:?}",
            loaded.outcome
        );
        if loaded.outcome == LoadOutcome::Loaded {
            assert_eq!(loaded.settings, TestConfig::new(19, 100));
        }
        save(&mut s, &TestConfig::new(42, 100)).unwrap();
        assert_eq!(load(&mut s).settings, TestConfig::new(42, 100));
    }
}

/// xorshift for corrupting flash deterministically.
fn noise(state: &mut u32) -> u32 {
    *state ^= *state << 13;
    *state ^= *state >> 17;
    *state ^= *state << 5;
    *state
}

#[test]
fn random_garbage_never_loads_as_settings_and_is_recovered_by_a_save() {
    for seed in 1..200u32 {
        let mut state = seed;
        let mut flash = Flash::new();
        for b in flash.bytes_mut() {
            *b = noise(&mut state) as u8;
        }
        let mut s = store(flash);
        let loaded = load(&mut s);
        assert!(
            matches!(loaded.outcome, LoadOutcome::Empty | LoadOutcome::Corrupted),
            "seed {seed}: {:?}",
            loaded.outcome
        );
        assert_eq!(loaded.settings, TestConfig::default());
        save(&mut s, &TestConfig::new(seed, 64)).unwrap();
        assert_eq!(
            load(&mut s).settings,
            TestConfig::new(seed, 64),
            "seed {seed}"
        );
    }
}

#[test]
fn flipped_bits_in_a_used_store_never_give_wrong_settings() {
    let base = flash_after_saves(30, 64);
    for seed in 1..300u32 {
        let mut state = seed;
        let mut flash = base.clone();
        // Clear a few random bits anywhere (flash decays towards programmed zeros too).
        for _ in 0..(1 + seed % 4) {
            let at = noise(&mut state) as usize % REGION;
            flash.bytes_mut()[at] &= !(1 << (noise(&mut state) % 8));
        }
        let mut s = store(flash);
        let loaded = load(&mut s);
        match loaded.outcome {
            // The newest record, or an older intact one if the newest was hit.
            LoadOutcome::Loaded => {
                assert!(loaded.settings.generation < 30, "seed {seed}");
                assert_eq!(loaded.settings.len, 64, "seed {seed}");
            }
            LoadOutcome::Empty | LoadOutcome::Corrupted => {}
            other => panic!("seed {seed}: {other:?}"),
        }
        save(&mut s, &TestConfig::new(99, 64)).unwrap();
        assert_eq!(
            load(&mut s).settings,
            TestConfig::new(99, 64),
            "seed {seed}"
        );
    }
}

/// A store over flash that reads its writes back, as on the boards.
fn verified_store(flash: Flash) -> SettingsStore<super::verified::VerifiedFlash<Flash>> {
    SettingsStore::new(super::verified::VerifiedFlash::new(flash), 0..REGION as u32).unwrap()
}

#[test]
fn a_program_dropped_silently_is_retried_and_the_save_holds() {
    let mut store = verified_store(Flash::new());
    block_on(store.save_settings(&TestConfig::new(1, 40))).unwrap();
    // The next program reports success and stores nothing (embassy-stm32 0.6.0's L4 driver
    // after a PROGERR): the read-back sees it, the store erases the copy and writes again.
    store.flash().inner().fail_silently(0, 1);
    block_on(store.save_settings(&TestConfig::new(2, 40))).unwrap();
    let mut reopened = verified_store(store.into_flash().inner().clone());
    let loaded = block_on(reopened.load_settings::<TestConfig>());
    assert_eq!(loaded.outcome, LoadOutcome::Loaded);
    assert_eq!(loaded.settings, TestConfig::new(2, 40));
}

#[test]
fn a_flash_that_stores_nothing_fails_the_save() {
    let mut store = verified_store(Flash::new());
    store.flash().inner().fail_silently(0, u32::MAX);
    assert!(matches!(
        block_on(store.save_settings(&TestConfig::new(1, 40))),
        Err(StoreError::Flash(super::verified::VerifyError::Mismatch))
    ));
}

/// The consumable record under its own key, saved many times beside the settings: a cut at
/// every step of every consumable save leaves the settings as they were, and the record
/// old or new.
#[test]
fn power_cut_at_every_step_of_consumable_saves_keeps_the_settings() {
    use super::CONSUMABLES_KEY;
    use crate::consumables::ConsumableSet;
    let settings = TestConfig::new(7, 100);
    let set = |starts: u32| ConsumableSet {
        starts,
        ..ConsumableSet::default()
    };
    let mut s = store(Flash::new());
    save(&mut s, &settings).unwrap();
    let mut base = s.into_flash();
    // 48-byte records: the pages of both copies fill and are collected several times.
    for prior in 0..120u32 {
        let mut probe = store(base.clone());
        let before = probe.flash().steps();
        block_on(probe.save_record(CONSUMABLES_KEY, &set(prior))).unwrap();
        let total = probe.flash().steps() - before;
        for cut in 0..total {
            let mut flash = base.clone();
            flash.cut_power_after(cut, prior.wrapping_mul(31).wrapping_add(cut));
            let mut s = store(flash);
            assert!(block_on(s.save_record(CONSUMABLES_KEY, &set(prior))).is_err());
            let mut flash = s.into_flash();
            flash.power_cycle();
            let mut rebooted = store(flash);
            let loaded = load(&mut rebooted);
            assert_eq!(
                (loaded.outcome, &loaded.settings),
                (LoadOutcome::Loaded, &settings),
                "prior {prior}, cut after {cut}/{total}"
            );
            let record = block_on(rebooted.load_record::<ConsumableSet>(CONSUMABLES_KEY));
            let starts = record.settings.starts;
            let old = if prior == 0 { 0 } else { prior - 1 };
            assert!(
                starts == prior || starts == old,
                "prior {prior}, cut after {cut}/{total}: {starts} starts ({:?})",
                record.outcome
            );
        }
        let mut s = store(base);
        block_on(s.save_record(CONSUMABLES_KEY, &set(prior))).unwrap();
        base = s.into_flash();
    }
}
