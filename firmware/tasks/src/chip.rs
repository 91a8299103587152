//! The few STM32L4 registers the tasks touch themselves, the same on the STM32L476RG and the
//! emulated STM32L475VG (RM0351): the GPIO ports' mode and set/reset registers, for the safe
//! state before any driver exists and in the fault handlers, and RCC's clock enables and
//! reset flags. Addresses of the GPIO ports come from the pin table
//! (`plasma_firmware::pins::Port::register_block`).

use plasma_firmware::pins::Pin;

const RCC: usize = 0x4002_1000;
/// RCC_AHB2ENR: GPIOxEN is bit `port index`.
const RCC_AHB2ENR: usize = RCC + 0x4C;
/// RCC_CSR: the reset flags (bits 24..31) and RMVF (bit 23, write 1 to clear them).
const RCC_CSR: usize = RCC + 0x94;
const RCC_CSR_RMVF: u32 = 1 << 23;

const GPIO_MODER: usize = 0x00;
const GPIO_BSRR: usize = 0x18;
const MODER_OUTPUT: u32 = 0b01;

fn read(address: usize) -> u32 {
    // SAFETY: only called with the addresses above, word-aligned registers that exist on
    // both chips; a read has no side effect on them.
    unsafe { (address as *const u32).read_volatile() }
}

fn write(address: usize, value: u32) {
    // SAFETY: as in `read`; every caller writes a value the register documents.
    unsafe { (address as *mut u32).write_volatile(value) }
}

/// Turns on the clocks of the GPIO ports in `ports`, one bit per
/// [`plasma_firmware::pins::Port::index`].
pub fn enable_gpio_clocks(ports: u32) {
    write(RCC_AHB2ENR, read(RCC_AHB2ENR) | ports);
}

/// Drives `pin` to `high` and then makes it an output: the pin never drives the wrong level.
/// The set/reset write is atomic; the mode write is a read-modify-write, so the caller must
/// keep other writers of the port's MODER away (interrupts off, or before the tasks start).
pub fn drive_as_output(pin: Pin, high: bool) {
    let block = pin.port.register_block() as usize;
    let n = u32::from(pin.number);
    write(block + GPIO_BSRR, if high { 1 << n } else { 1 << (n + 16) });
    let moder = read(block + GPIO_MODER);
    write(
        block + GPIO_MODER,
        (moder & !(0b11 << (2 * n))) | (MODER_OUTPUT << (2 * n)),
    );
}

/// RCC_CSR as it is now.
pub fn reset_flags() -> u32 {
    read(RCC_CSR)
}

/// Clears the reset flags for the next boot.
pub fn clear_reset_flags() {
    write(RCC_CSR, read(RCC_CSR) | RCC_CSR_RMVF);
}
