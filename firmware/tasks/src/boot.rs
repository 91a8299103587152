//! The boot report for the CNC port: why the MCU started and how the settings loaded; the user
//! button, read once at boot.

use core::fmt::Write;

use heapless::String;
use plasma_firmware::platform::pins::USER_BUTTON;
use plasma_firmware::platform::safe_state::BootReport;
use plasma_firmware::storage::LoadOutcome;
use static_cell::StaticCell;

use crate::chip;
use crate::settings::outcome_word;

/// Whether the user button (B1, [`USER_BUTTON`]) is held now. Read once, at boot, before the
/// settings are applied ([`crate::settings::at_boot`]); the same registers on both boards.
pub fn user_button_held() -> bool {
    chip::enable_gpio_clocks(1 << USER_BUTTON.pin.port.index());
    USER_BUTTON.is_on(chip::read_pulled_up(USER_BUTTON.pin))
}

static BOOT_TEXT: StaticCell<String<64>> = StaticCell::new();

/// `<reset cause>,settings:<outcome>` for the CNC port (`ID ... reset=...`,
/// `!BOOT reason=...`). Call once, at boot.
pub fn boot_text(boot: &BootReport, outcome: LoadOutcome) -> &'static str {
    let text = BOOT_TEXT.init(String::new());
    // 64 bytes hold the longest cause and outcome; a cut text is still a report.
    let _ = write!(
        text,
        "{},settings:{}",
        boot.cause.as_str(),
        outcome_word(outcome)
    );
    text.as_str()
}
