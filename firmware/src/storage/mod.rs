//! Settings in flash: versioned, power-cut safe, and honest about what it found.
//!
//! [`SettingsStore`] keeps the settings as one [`record`] in **two copies**, each in its own
//! [sequential-storage](sequential_storage) map over half of the region. Within a copy each
//! save appends a new item and the newest complete item wins (items carry CRCs). Two copies
//! are needed because a map alone does not survive a *torn page erase*: an erase cut by a
//! power loss leaves a page of random bits, which sequential-storage can mistake for its
//! newest page and then report the map as empty (found by the tests here, with a flash model
//! that tears erases the way NOR flash does). So a save first writes the copy that does not
//! hold the newest record and only then the other one, and a load takes the valid record with
//! the higher sequence number. Whatever step a power cut interrupts, one copy is untouched and
//! holds the old settings or the other holds the new ones (tested with [`ram_flash`] and a cut
//! at every step).
//!
//! What the settings *are* is not decided here: a type implementing [`Persistent`] encodes
//! itself into the payload, names its version, and may migrate older versions. Loading never
//! fails; it returns the settings to run with and a [`LoadOutcome`] saying whether they came
//! from flash or are the defaults, and why, so the supervisor can report it.
//!
//! ```
//! use embassy_futures::block_on;
//! use plasma_firmware::storage::{LoadOutcome, Persistent, SettingsStore, ram_flash::RamFlash};
//!
//! #[derive(Debug, Default, PartialEq)]
//! struct Config { node_address: u8 }
//!
//! impl Persistent for Config {
//!     const VERSION: u8 = 1;
//!     fn encode(&self, out: &mut [u8]) -> usize {
//!         out[0] = self.node_address;
//!         1
//!     }
//!     fn decode(payload: &[u8]) -> Option<Self> {
//!         match payload {
//!             [node_address] => Some(Config { node_address: *node_address }),
//!             _ => None,
//!         }
//!     }
//! }
//!
//! // Four 2 KiB pages: two per copy.
//! let flash = RamFlash::<8192>::new();
//! let mut store = SettingsStore::new(flash, 0..8192).unwrap();
//! block_on(async {
//!     let first = store.load_settings::<Config>().await;
//!     assert_eq!((first.settings, first.outcome), (Config::default(), LoadOutcome::Empty));
//!
//!     store.save_settings(&Config { node_address: 7 }).await.unwrap();
//!     let loaded = store.load_settings::<Config>().await;
//!     assert_eq!(loaded.outcome, LoadOutcome::Loaded);
//!     assert_eq!(loaded.settings.node_address, 7);
//! });
//! ```
#![allow(
    clippy::indexing_slicing,
    reason = "indices are the two copy slots (0 or 1) and lengths that `emit` wrote into the same buffer"
)]

pub mod history;
pub mod ram_flash;
mod record;
pub mod verified;

use core::ops::Range;

use embedded_storage_async::nor_flash::NorFlash;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

pub use record::{MAX_PAYLOAD, Record, RecordError};

/// The map key of the settings record.
pub const SETTINGS_KEY: u8 = 1;
/// The map key of the consumable record ([`crate::consumables`]), beside the settings in the
/// same two copies.
pub const CONSUMABLES_KEY: u8 = 2;
/// Every key the store keeps (a copy rebuilt after damage takes the others from its twin).
const KEYS: [u8; 2] = [SETTINGS_KEY, CONSUMABLES_KEY];

/// Work buffer for sequential-storage: key + largest record, rounded up to its largest word
/// size (32 bytes) so it suits any flash.
const WORK_BUFFER: usize = (1 + record::MAX_RECORD).next_multiple_of(32);

/// A settings encoding, defined by whoever owns the configuration.
pub trait Persistent: Default + Sized {
    /// The version of this encoding. Change it whenever the payload layout changes.
    const VERSION: u8;

    /// Writes the payload into `out` (which holds [`MAX_PAYLOAD`] bytes) and returns its
    /// length; a length over `out.len()` makes the save fail with [`StoreError::TooLarge`].
    fn encode(&self, out: &mut [u8]) -> usize;

    /// Reads a payload of [`Self::VERSION`]; `None` if it is not valid.
    fn decode(payload: &[u8]) -> Option<Self>;

    /// Reads a payload of an older (or newer) version, if this encoding knows how.
    fn migrate(version: u8, payload: &[u8]) -> Option<Self> {
        let _ = (version, payload);
        None
    }
}

/// Copies an encoded `payload` into [`Persistent::encode`]'s `out` and returns what `encode`
/// returns: its length, or, when `out` is too small, a length over `out.len()` that the store
/// refuses.
pub(crate) fn write_payload(out: &mut [u8], payload: &[u8]) -> usize {
    match out.get_mut(..payload.len()) {
        Some(slot) => {
            slot.copy_from_slice(payload);
            payload.len()
        }
        None => out.len().saturating_add(1),
    }
}

/// Where the settings a load returned came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadOutcome {
    /// Read from flash, current version.
    Loaded,
    /// Read from flash and converted from an older version.
    Migrated {
        /// The stored version.
        from: u8,
    },
    /// Nothing stored yet: defaults (the normal first boot).
    Empty,
    /// A record of a version this firmware cannot read: defaults.
    UnknownVersion {
        /// The stored version.
        found: u8,
    },
    /// The store or the record is damaged: defaults.
    Corrupted,
    /// The flash could not be read: defaults.
    FlashError,
}

impl LoadOutcome {
    /// Whether the defaults are in use.
    pub const fn is_defaults(self) -> bool {
        !matches!(self, LoadOutcome::Loaded | LoadOutcome::Migrated { .. })
    }

    /// Whether an operator should hear about it (settings were lost, not just never saved).
    pub const fn is_problem(self) -> bool {
        matches!(
            self,
            LoadOutcome::UnknownVersion { .. } | LoadOutcome::Corrupted | LoadOutcome::FlashError
        )
    }
}

log_texts!(LoadOutcome {
    LoadOutcome::Loaded => "settings loaded",
    LoadOutcome::Migrated { .. } => "settings migrated from an older version",
    LoadOutcome::Empty => "no settings stored, using defaults",
    LoadOutcome::UnknownVersion { .. } => "settings of an unknown version, using defaults",
    LoadOutcome::Corrupted => "settings corrupted, using defaults",
    LoadOutcome::FlashError => "settings unreadable (flash error), using defaults",
});

/// The settings to run with and where they came from.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoadedSettings<S> {
    /// Loaded, migrated or default settings.
    pub settings: S,
    /// Where they came from.
    pub outcome: LoadOutcome,
}

/// A store operation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StoreError<E> {
    /// The flash driver failed.
    Flash(E),
    /// The stored data is damaged beyond sequential-storage's repair, or the record is not
    /// one this code wrote.
    Corrupted,
    /// The payload is larger than [`MAX_PAYLOAD`].
    TooLarge,
    /// The region is not at least two whole erase pages of the flash.
    BadRegion,
    /// sequential-storage reported a condition that should not happen with one small record
    /// (full storage, buffer sizes, its own logic bug).
    Internal,
}

impl<E> StoreError<E> {
    /// A short text for the log.
    pub const fn as_str(&self) -> &'static str {
        match self {
            StoreError::Flash(_) => "flash error",
            StoreError::Corrupted => "corrupted",
            StoreError::TooLarge => "record too large",
            StoreError::BadRegion => "region is not two pairs of whole flash pages",
            StoreError::Internal => "storage layer error",
        }
    }
}

impl<E> From<sequential_storage::Error<E>> for StoreError<E> {
    fn from(e: sequential_storage::Error<E>) -> Self {
        match e {
            sequential_storage::Error::Storage { value, .. } => StoreError::Flash(value),
            sequential_storage::Error::Corrupted { .. } => StoreError::Corrupted,
            sequential_storage::Error::ItemTooBig => StoreError::TooLarge,
            _ => StoreError::Internal,
        }
    }
}

/// Word-aligned work buffer: some internal flash drivers want aligned source data.
#[repr(align(8))]
struct WorkBuffer([u8; WORK_BUFFER]);

/// The newest record of one copy, copied out of the work buffer.
#[derive(Clone, Copy)]
struct CopyContent {
    bytes: [u8; record::MAX_RECORD],
    len: usize,
}

impl CopyContent {
    fn record(&self) -> Option<Record<'_>> {
        Record::parse(self.bytes.get(..self.len)?).ok()
    }
}

/// What reading one copy gave.
#[derive(Clone, Copy, PartialEq, Eq)]
enum CopyState<E> {
    Empty,
    /// A valid record with this sequence number (content in `SettingsStore::content`).
    Valid(u32),
    Damaged(StoreError<E>),
}

/// One copy's map: borrows the flash for one operation.
type CopyMap<'a, F> = MapStorage<u8, &'a mut F, Cache<Uncached, Uncached, Uncached, u8>>;

/// The settings store over a region of a NOR flash.
pub struct SettingsStore<F: NorFlash> {
    flash: F,
    copies: [Range<u32>; 2],
    work: WorkBuffer,
    content: [CopyContent; 2],
}

impl<F: NorFlash> SettingsStore<F> {
    /// A store in `region` (flash offsets, whole erase pages, at least four: each copy needs
    /// two). Nothing is read or written yet.
    pub fn new(flash: F, region: Range<u32>) -> Result<Self, StoreError<F::Error>> {
        let page = u32::try_from(F::ERASE_SIZE).map_err(|_| StoreError::BadRegion)?;
        let pages = region
            .end
            .checked_sub(region.start)
            .ok_or(StoreError::BadRegion)?
            / page;
        let half = (pages / 2) * page;
        let middle = region.start + half;
        let copies = [region.start..middle, middle..middle + half];
        for copy in &copies {
            MapConfig::<&mut F>::try_new(copy.clone()).map_err(|_| StoreError::BadRegion)?;
        }
        Ok(SettingsStore {
            flash,
            copies,
            work: WorkBuffer([0; WORK_BUFFER]),
            content: [CopyContent {
                bytes: [0; record::MAX_RECORD],
                len: 0,
            }; 2],
        })
    }

    fn map(flash: &mut F, copy: Range<u32>) -> CopyMap<'_, F> {
        // Validated in `new`; an uncached map costs nothing to build.
        MapStorage::new(flash, MapConfig::new(copy), Cache::new_uncached())
    }

    async fn read_copy(&mut self, copy: usize, key: u8) -> CopyState<F::Error> {
        let fetched = Self::map(&mut self.flash, self.copies[copy].clone())
            .fetch_item::<&[u8]>(&mut self.work.0, &key)
            .await;
        match fetched {
            Ok(None) => CopyState::Empty,
            Ok(Some(bytes)) => {
                let content = &mut self.content[copy];
                match (Record::parse(bytes), content.bytes.get_mut(..bytes.len())) {
                    (Ok(record), Some(slot)) => {
                        slot.copy_from_slice(bytes);
                        content.len = bytes.len();
                        CopyState::Valid(record.sequence)
                    }
                    _ => CopyState::Damaged(StoreError::Corrupted),
                }
            }
            Err(e) => CopyState::Damaged(e.into()),
        }
    }

    /// Reads `key` in both copies: their states and the index of the newest valid one.
    async fn read_copies(&mut self, key: u8) -> ([CopyState<F::Error>; 2], Option<usize>) {
        let states = [self.read_copy(0, key).await, self.read_copy(1, key).await];
        let newest = match states {
            [CopyState::Valid(a), CopyState::Valid(b)] => Some(if b > a { 1 } else { 0 }),
            [CopyState::Valid(_), _] => Some(0),
            [_, CopyState::Valid(_)] => Some(1),
            _ => None,
        };
        (states, newest)
    }

    /// The newest stored record, if any. If neither copy holds a valid record and one is
    /// damaged, that damage is the error ([`StoreError::Corrupted`] for a record this code
    /// did not write, [`StoreError::Flash`] if the flash failed).
    pub async fn load(&mut self) -> Result<Option<Record<'_>>, StoreError<F::Error>> {
        self.load_key(SETTINGS_KEY).await
    }

    /// [`SettingsStore::load`] of the record under `key`.
    pub async fn load_key(&mut self, key: u8) -> Result<Option<Record<'_>>, StoreError<F::Error>> {
        let (states, newest) = self.read_copies(key).await;
        match newest {
            Some(copy) => Ok(self.content[copy].record()),
            None => match states {
                [CopyState::Damaged(e), _] | [_, CopyState::Damaged(e)] => Err(e),
                _ => Ok(None),
            },
        }
    }

    /// Stores `payload` as settings of `version`, replacing the previous record.
    ///
    /// The copy that does not hold the newest record is written first, then the other. A copy
    /// that cannot be written (damaged beyond sequential-storage's repair, or a flash error)
    /// is erased and written again once: at that moment the other copy holds the newest
    /// settings, old or new, so nothing is lost.
    pub async fn save(&mut self, version: u8, payload: &[u8]) -> Result<(), StoreError<F::Error>> {
        self.save_key(SETTINGS_KEY, version, payload).await
    }

    /// [`SettingsStore::save`] of the record under `key`.
    pub async fn save_key(
        &mut self,
        key: u8,
        version: u8,
        payload: &[u8],
    ) -> Result<(), StoreError<F::Error>> {
        if payload.len() > MAX_PAYLOAD {
            return Err(StoreError::TooLarge);
        }
        let (states, newest) = self.read_copies(key).await;
        let sequence = match newest {
            Some(copy) => match states[copy] {
                CopyState::Valid(sequence) => sequence.wrapping_add(1),
                _ => 0,
            },
            None => 0,
        };
        let mut bytes = [0u8; record::MAX_RECORD];
        let len = Record {
            version,
            sequence,
            payload,
        }
        .emit(&mut bytes)
        .map_err(|_| StoreError::TooLarge)?;
        let record = &bytes[..len];

        let first = match newest {
            Some(copy) => 1 - copy,
            None => 0,
        };
        self.write_copy(first, key, record).await?;
        self.write_copy(1 - first, key, record).await
    }

    async fn write_copy(
        &mut self,
        copy: usize,
        key: u8,
        record: &[u8],
    ) -> Result<(), StoreError<F::Error>> {
        let mut map = Self::map(&mut self.flash, self.copies[copy].clone());
        if map
            .store_item(&mut self.work.0, &key, &record)
            .await
            .is_ok()
        {
            return Ok(());
        }
        map.erase_all().await?;
        map.store_item(&mut self.work.0, &key, &record).await?;
        // The erase took the other keys' records of this copy: they come back from the twin,
        // so that each record is in both copies again before the twin is written.
        for other in KEYS.into_iter().filter(|&k| k != key) {
            if let CopyState::Valid(_) = self.read_copy(1 - copy, other).await {
                let content = self.content[1 - copy];
                if let Some(bytes) = content.bytes.get(..content.len) {
                    Self::map(&mut self.flash, self.copies[copy].clone())
                        .store_item(&mut self.work.0, &other, &bytes)
                        .await?;
                }
            }
        }
        Ok(())
    }

    /// Erases the whole region: the next load finds nothing.
    pub async fn wipe(&mut self) -> Result<(), StoreError<F::Error>> {
        for copy in self.copies.clone() {
            Self::map(&mut self.flash, copy).erase_all().await?;
        }
        Ok(())
    }

    /// Loads settings of type `S`, falling back to `S::default()` and saying why.
    pub async fn load_settings<S: Persistent>(&mut self) -> LoadedSettings<S> {
        self.load_record(SETTINGS_KEY).await
    }

    /// [`SettingsStore::load_settings`] of the record under `key`.
    pub async fn load_record<S: Persistent>(&mut self, key: u8) -> LoadedSettings<S> {
        let (settings, outcome) = match self.load_key(key).await {
            Ok(None) => (None, LoadOutcome::Empty),
            Ok(Some(record)) if record.version == S::VERSION => {
                (S::decode(record.payload), LoadOutcome::Loaded)
            }
            Ok(Some(record)) => match S::migrate(record.version, record.payload) {
                Some(settings) => (
                    Some(settings),
                    LoadOutcome::Migrated {
                        from: record.version,
                    },
                ),
                None => (
                    None,
                    LoadOutcome::UnknownVersion {
                        found: record.version,
                    },
                ),
            },
            Err(StoreError::Flash(_)) => (None, LoadOutcome::FlashError),
            Err(_) => (None, LoadOutcome::Corrupted),
        };
        match settings {
            Some(settings) => LoadedSettings { settings, outcome },
            None => LoadedSettings {
                settings: S::default(),
                // A current-version record that does not decode is damaged.
                outcome: match outcome {
                    LoadOutcome::Loaded => LoadOutcome::Corrupted,
                    other => other,
                },
            },
        }
    }

    /// Saves `settings` with its version.
    pub async fn save_settings<S: Persistent>(
        &mut self,
        settings: &S,
    ) -> Result<(), StoreError<F::Error>> {
        self.save_record(SETTINGS_KEY, settings).await
    }

    /// [`SettingsStore::save_settings`] under `key`.
    pub async fn save_record<S: Persistent>(
        &mut self,
        key: u8,
        settings: &S,
    ) -> Result<(), StoreError<F::Error>> {
        let mut payload = [0u8; MAX_PAYLOAD];
        let len = settings.encode(&mut payload);
        let payload = payload.get(..len).ok_or(StoreError::TooLarge)?;
        self.save_key(key, S::VERSION, payload).await
    }

    /// The flash, to use it for something else.
    pub fn into_flash(self) -> F {
        self.flash
    }

    /// The flash, e.g. to inspect a model in tests.
    pub fn flash(&mut self) -> &mut F {
        &mut self.flash
    }
}

#[cfg(test)]
mod tests;
