//! The settings store in the MCU's flash (bank 2, region from memory.x).

use core::future::Future;
use core::ops::Range;
use core::sync::atomic::Ordering;

use defmt::{debug, error, info, warn};
use embassy_futures::select::{Either, select};
use embassy_stm32::flash::{Async, Flash};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::Timer;
use plasma_firmware::settings::{SaveError, Settings};
use plasma_firmware::storage::{LoadOutcome, LoadedSettings, SettingsStore};
use plasma_firmware::supervisor::SettingsSaver;
use plasma_firmware::watchdog::TaskId;

use crate::fault::SETTINGS_ECC_ERRORS;
use crate::watchdog::report;

/// Start of flash in the address map.
pub const FLASH_BASE: u32 = 0x0800_0000;
/// Start of bank 2.
pub const FLASH_BANK2: u32 = 0x0808_0000;

/// The store over the on-chip flash.
pub type Store = SettingsStore<Flash<'static, Async>>;

/// The settings region from memory.x, as offsets from the start of flash.
pub fn settings_region() -> Range<u32> {
    unsafe extern "C" {
        static __settings_start: u8;
        static __settings_end: u8;
    }
    // Only the addresses of these linker symbols are used, never their contents.
    let start = (&raw const __settings_start) as u32;
    let end = (&raw const __settings_end) as u32;
    start - FLASH_BASE..end - FLASH_BASE
}

/// The store, or `None` (logged) if the region does not suit it; build.rs checks the region,
/// so that would be a mismatch between memory.x and the flash driver's page size.
pub fn open(flash: Flash<'static, Async>) -> Option<Store> {
    match SettingsStore::new(flash, settings_region()) {
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

/// Logs double ECC errors the NMI handler skipped while the store was read.
pub fn report_ecc_errors() {
    let ecc_errors = SETTINGS_ECC_ERRORS.swap(0, Ordering::Relaxed);
    if ecc_errors > 0 {
        warn!(
            "settings: {} double ECC error(s) read (torn writes), skipped",
            ecc_errors
        );
    }
}

/// Loads the settings at boot: the stored ones, or the defaults and why (logged).
pub async fn load(store: Option<&mut Store>) -> LoadedSettings<Settings> {
    let loaded = match store {
        Some(store) => store.load_settings::<Settings>().await,
        None => LoadedSettings {
            settings: Settings::default(),
            outcome: LoadOutcome::FlashError,
        },
    };
    report_ecc_errors();
    if loaded.outcome.is_problem() {
        warn!("settings: {}", loaded.outcome);
    } else {
        debug!("settings: {}", loaded.outcome);
    }
    loaded
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

/// Settings to store (bridge → settings task).
static SAVE_REQUEST: Signal<CriticalSectionRawMutex, Settings> = Signal::new();
/// How it went (settings task → bridge).
static SAVE_RESULT: Signal<CriticalSectionRawMutex, Result<(), SaveError>> = Signal::new();

/// The bridge task's handle on the settings task.
pub struct BoardSaver;

impl SettingsSaver<Settings, SaveError> for BoardSaver {
    fn start(&mut self, settings: Settings) {
        SAVE_RESULT.reset();
        SAVE_REQUEST.signal(settings);
    }

    fn finished(&mut self) -> impl Future<Output = Result<(), SaveError>> {
        SAVE_RESULT.wait()
    }
}

/// Writes settings to flash when the bridge asks (`CONFIG SAVE`), off the bridge task so both
/// serial ports keep being served while pages are erased.
#[embassy_executor::task]
pub async fn settings(mut store: Option<Store>, progress: TaskId) {
    loop {
        let request = select(SAVE_REQUEST.wait(), Timer::after_millis(250)).await;
        report(progress);
        let Either::First(settings) = request else {
            continue;
        };
        let result = match store.as_mut() {
            Some(store) => store
                .save_settings(&settings)
                .await
                .map_err(SaveError::from),
            None => Err(SaveError::Flash),
        };
        match result {
            Ok(()) => info!("settings saved"),
            Err(e) => warn!("settings not saved: {}", e),
        }
        report_ecc_errors();
        SAVE_RESULT.signal(result);
    }
}
