//! The settings task: loads the settings at boot and stores `CONFIG SAVE` off the bridge task,
//! so both serial ports keep being served while flash pages are erased. The flash behind it is
//! the board's ([`Board::SettingsFlash`]), every write and erase of it read back
//! ([`VerifiedFlash`]: embassy-stm32 0.6.0's L4 driver reports a failed program as done).

use core::future::Future;
use core::ops::Range;

use defmt::{debug, error, info, warn};
use embassy_futures::select::{Either, select};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::Timer;
use plasma_firmware::bridge::SaveRequest;
use plasma_firmware::consumables::ConsumableSet;
use plasma_firmware::platform::supervisor::SettingsSaver;
use plasma_firmware::platform::watchdog::TaskId;
use plasma_firmware::settings::{SaveError, Settings};
use plasma_firmware::storage::verified::VerifiedFlash;
use plasma_firmware::storage::{CONSUMABLES_KEY, LoadOutcome, LoadedSettings, SettingsStore};

use crate::Board;
use crate::progress::report;

/// The store over the board's settings flash, read back after every write and erase.
pub type Store<B> = SettingsStore<VerifiedFlash<<B as Board>::SettingsFlash>>;

/// The store over `region` of `flash`, or `None` (logged) if the region does not suit it: a
/// mismatch between the board's region and the flash's page size, a build mistake.
pub fn open<B: Board>(flash: B::SettingsFlash, region: Range<u32>) -> Option<Store<B>> {
    match SettingsStore::new(VerifiedFlash::new(flash), region) {
        Ok(store) => Some(store),
        Err(e) => {
            error!(
                "settings region: {=str}; settings will not be kept",
                e.as_str()
            );
            None
        }
    }
}

/// Logs flash read errors the board saw while the settings or the history were read (torn
/// writes).
pub(crate) fn report_flash_errors<B: Board>() {
    let errors = B::flash_errors_seen();
    if errors > 0 {
        warn!(
            "flash: {} double ECC error(s) read (torn writes), skipped",
            errors
        );
    }
}

/// Loads the settings at boot: the stored ones, or the defaults and why (logged).
pub async fn load<B: Board>(store: Option<&mut Store<B>>) -> LoadedSettings<Settings> {
    let loaded = match store {
        Some(store) => store.load_settings::<Settings>().await,
        None => LoadedSettings {
            settings: Settings::default(),
            outcome: LoadOutcome::FlashError,
        },
    };
    report_flash_errors::<B>();
    if loaded.outcome.is_problem() {
        warn!("settings: {}", loaded.outcome);
    } else {
        debug!("settings: {}", loaded.outcome);
    }
    loaded
}

/// Loads the consumable record at boot (`None` when none was kept: the bridge starts a new
/// set; a damaged one is logged).
pub async fn load_consumables<B: Board>(store: Option<&mut Store<B>>) -> Option<ConsumableSet> {
    let loaded = store?.load_record::<ConsumableSet>(CONSUMABLES_KEY).await;
    if loaded.outcome.is_problem() {
        warn!("consumable record: {}", loaded.outcome);
    }
    (!loaded.outcome.is_defaults()).then_some(loaded.settings)
}

/// The loaded settings as this boot runs them ([`Settings::at_boot`]): with the user button
/// held at reset, the CNC port's default framing, logged.
pub fn at_boot(loaded: Settings, user_button_held: bool) -> Settings {
    let settings = loaded.at_boot(user_button_held);
    if user_button_held {
        info!(
            "B1 held at reset: the CNC port runs its default framing {} (saved: {}); CONFIG SAVE keeps it",
            settings.cnc_port_config(),
            loaded.cnc_port_config()
        );
    }
    settings
}

/// One word for the boot report on the CNC port.
pub const fn outcome_word(outcome: LoadOutcome) -> &'static str {
    match outcome {
        LoadOutcome::Loaded => "loaded",
        LoadOutcome::Migrated { .. } => "migrated",
        LoadOutcome::Empty => "defaults",
        LoadOutcome::UnknownVersion { .. } => "defaults-unknown-version",
        LoadOutcome::Corrupted => "defaults-corrupted",
        LoadOutcome::FlashError => "defaults-flash-error",
    }
}

/// Settings or the consumable record to store (bridge → settings task).
static SAVE_REQUEST: Signal<CriticalSectionRawMutex, SaveRequest> = Signal::new();
/// How it went (settings task → bridge).
static SAVE_RESULT: Signal<CriticalSectionRawMutex, Result<(), SaveError>> = Signal::new();

/// The bridge task's handle on the settings task.
pub struct BoardSaver;

impl SettingsSaver<SaveRequest, SaveError> for BoardSaver {
    fn start(&mut self, request: SaveRequest) {
        SAVE_RESULT.reset();
        SAVE_REQUEST.signal(request);
    }

    fn finished(&mut self) -> impl Future<Output = Result<(), SaveError>> {
        SAVE_RESULT.wait()
    }
}

/// Writes settings to flash when the bridge asks (`CONFIG SAVE`), and the consumable record
/// when it is due. The body of the board's settings task.
pub async fn run<B: Board>(mut store: Option<Store<B>>, progress: TaskId) {
    loop {
        let request = select(SAVE_REQUEST.wait(), Timer::after_millis(250)).await;
        report(progress);
        let Either::First(request) = request else {
            continue;
        };
        let what = match request {
            SaveRequest::Settings(_) => "settings",
            SaveRequest::Consumables(_) => "consumable record",
        };
        let result = match store.as_mut() {
            Some(store) => match request {
                SaveRequest::Settings(settings) => store.save_settings(&settings).await,
                SaveRequest::Consumables(set) => store.save_record(CONSUMABLES_KEY, &set).await,
            }
            .map_err(SaveError::from),
            None => Err(SaveError::Flash),
        };
        match result {
            Ok(()) => debug!("{=str} saved", what),
            Err(e) => warn!("{=str} not saved: {}", what, defmt::Display2Format(&e)),
        }
        report_flash_errors::<B>();
        SAVE_RESULT.signal(result);
    }
}
