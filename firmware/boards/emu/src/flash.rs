//! Settings "flash" in RAM. QEMU models no FLASH controller, so the store runs on the
//! library's model of the L4 flash (`plasma_firmware::storage::ram_flash`, 2 KiB pages,
//! double-word programming), the size of the Nucleo's settings region. `CONFIG SAVE` works
//! and is read back; the settings last until the board resets (RAM is cleared at boot) or
//! QEMU exits.

use plasma_firmware::storage::ram_flash::RamFlash;

/// The Nucleo's settings region: 8 KiB (memory.x).
pub const SETTINGS_SIZE: usize = 8192;

/// The flash the settings store writes.
pub type SettingsFlash = RamFlash<SETTINGS_SIZE>;
