//! The reset flags (RCC_CSR bits 24..31) the emulated board's boot report reads. QEMU's RCC
//! model shows the power-on flags (BORRSTF, PINRSTF) after every reset, the guest's own
//! SYSRESETREQ included, so a panic's reset would read as a power-up and the boot report
//! could never say `panic`. So the board keeps the flags its next boot should see, as the
//! silicon's RCC_CSR would hold them, in a RAM word the reset does not clear (`.uninit`:
//! QEMU keeps RAM across a reset and zeroes it only when it starts).
//!
//! Every boot arms the word with SFTRSTF (and PINRSTF, which every internal reset sets): under
//! QEMU the guest resets itself only by SYSRESETREQ, on the fault path
//! (`plasma_tasks::safe_state::fail`) or from the watchdog, which arms IWDGRSTF instead, as
//! the Nucleo's IWDG would set it. A word that is not armed (QEMU just started) leaves QEMU's
//! own flags: power-on.

use core::mem::MaybeUninit;

use plasma_firmware::platform::safe_state::ResetFlags;

/// The upper bytes of an armed word ("RST"); the flags are its low byte.
const ARMED: u32 = 0x5253_5400;

#[unsafe(link_section = ".uninit.EMU_RESET_FLAGS")]
static mut WORD: MaybeUninit<u32> = MaybeUninit::uninit();

fn word() -> *mut u32 {
    (&raw mut WORD).cast()
}

/// The RCC_CSR value of this boot: the flags the previous run armed, or QEMU's; then arms
/// a software reset for the next boot. Call once, first thing at boot.
pub fn take() -> u32 {
    // SAFETY: a word-aligned static only this module touches, before the executors start;
    // volatile because the previous run wrote it.
    let armed = unsafe { word().read_volatile() };
    let csr = if armed & !0xFF == ARMED {
        (armed & 0xFF) << 24
    } else {
        plasma_tasks::chip::reset_flags()
    };
    arm(ResetFlags::SOFTWARE);
    csr
}

/// The flags the next boot reports: `cause` and PINRSTF. Call with nothing else writing the
/// word (at boot, or just before the reset).
pub fn arm(cause: ResetFlags) {
    let flags = u32::from(cause.bits() | ResetFlags::PIN.bits());
    // SAFETY: as in `take`; one aligned word write.
    unsafe { word().write_volatile(ARMED | flags) };
}
