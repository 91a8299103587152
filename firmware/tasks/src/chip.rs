//! The few STM32L4 registers the tasks touch themselves, the same on the STM32L476RG and the
//! emulated STM32L475VG (RM0351): the GPIO ports' mode and set/reset registers, for the safe
//! state before any driver exists and in the fault handlers, RCC's clock enables, clock tree
//! and reset flags, and the EXTI lines of the inputs (SYSCFG routing, edge triggers, mask, pending). Addresses of the GPIO ports come from the pin table
//! (`plasma_firmware::platform::pins::Port::register_block`).

use plasma_firmware::platform::pins::Pin;

use crate::clock_tree::RccSnapshot;

const RCC: usize = 0x4002_1000;
/// The clock tree's registers ([`rcc_snapshot`]).
const RCC_CR: usize = RCC;
const RCC_CFGR: usize = RCC + 0x08;
const RCC_PLLCFGR: usize = RCC + 0x0C;
const RCC_CCIPR: usize = RCC + 0x88;
/// RCC_AHB2ENR: GPIOxEN is bit `port index`.
const RCC_AHB2ENR: usize = RCC + 0x4C;
/// RCC_CSR: the reset flags (bits 24..31) and RMVF (bit 23, write 1 to clear them).
const RCC_CSR: usize = RCC + 0x94;
const RCC_CSR_RMVF: u32 = 1 << 23;

/// RCC_APB2ENR: SYSCFGEN is bit 0.
const RCC_APB2ENR: usize = RCC + 0x60;
const RCC_APB2ENR_SYSCFGEN: u32 = 1;

/// SYSCFG_EXTICR1..4: four bits per line, the port index.
const SYSCFG_EXTICR1: usize = 0x4001_0008;

const EXTI: usize = 0x4001_0400;
/// EXTI_IMR1, RTSR1, FTSR1, PR1: one bit per line (lines 0..15 are the GPIO pins).
const EXTI_IMR1: usize = EXTI;
const EXTI_RTSR1: usize = EXTI + 0x08;
const EXTI_FTSR1: usize = EXTI + 0x0C;
const EXTI_PR1: usize = EXTI + 0x14;
/// The GPIO lines of PR1.
const GPIO_LINES: u32 = 0xFFFF;

const GPIO_MODER: usize = 0x00;
const GPIO_PUPDR: usize = 0x0C;
const GPIO_IDR: usize = 0x10;
const GPIO_BSRR: usize = 0x18;
const MODER_OUTPUT: u32 = 0b01;
const PUPDR_PULL_UP: u32 = 0b01;
/// Time for a pull-up to charge the pin before it is read: the Nucleo's B1 has a 100 nF
/// debounce capacitor behind 4.7 kΩ (0.5 ms); 100 000 cycles are 1.25 ms at 80 MHz, more at
/// any slower clock.
const PULL_UP_SETTLE_CYCLES: u32 = 100_000;

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
/// [`plasma_firmware::platform::pins::Port::index`].
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

/// Makes `pin` an input with its pull-up, lets the pull-up settle and reads it: `true` = high.
/// Read-modify-writes the port's mode and pull registers: call before the tasks start, with
/// the port's clock on.
pub fn read_pulled_up(pin: Pin) -> bool {
    let block = pin.port.register_block() as usize;
    let n = u32::from(pin.number);
    let pupdr = read(block + GPIO_PUPDR);
    write(
        block + GPIO_PUPDR,
        (pupdr & !(0b11 << (2 * n))) | (PUPDR_PULL_UP << (2 * n)),
    );
    write(
        block + GPIO_MODER,
        read(block + GPIO_MODER) & !(0b11 << (2 * n)),
    );
    cortex_m::asm::delay(PULL_UP_SETTLE_CYCLES);
    read(block + GPIO_IDR) & pin.mask() != 0
}

/// Turns on SYSCFG's clock (it routes the pins to the EXTI lines).
pub fn enable_syscfg_clock() {
    write(RCC_APB2ENR, read(RCC_APB2ENR) | RCC_APB2ENR_SYSCFGEN);
}

/// Routes `pin` to its EXTI line and arms the line for both edges. Read-modify-writes: call
/// before the EXTI interrupts are unmasked, from one place.
pub fn arm_edge_line(pin: Pin) {
    let n = usize::from(pin.number);
    let exticr = SYSCFG_EXTICR1 + 4 * (n / 4);
    let shift = 4 * (n % 4);
    let port = u32::from(pin.port.index());
    write(exticr, (read(exticr) & !(0xF << shift)) | (port << shift));
    let line = pin.mask();
    write(EXTI_RTSR1, read(EXTI_RTSR1) | line);
    write(EXTI_FTSR1, read(EXTI_FTSR1) | line);
    // An edge from before the arming is stale: the task reads the levels at start anyway.
    write(EXTI_PR1, line);
    write(EXTI_IMR1, read(EXTI_IMR1) | line);
}

/// The GPIO lines pending in EXTI_PR1, cleared (write 1 to clear, only those seen).
pub fn take_pending_edges() -> u32 {
    let pending = read(EXTI_PR1) & GPIO_LINES;
    write(EXTI_PR1, pending);
    pending
}

/// The RCC's clock registers as they are now, for [`RccSnapshot`]'s frequencies.
pub fn rcc_snapshot() -> RccSnapshot {
    RccSnapshot {
        cr: read(RCC_CR),
        cfgr: read(RCC_CFGR),
        pllcfgr: read(RCC_PLLCFGR),
        ccipr: read(RCC_CCIPR),
        csr: read(RCC_CSR),
    }
}

/// RCC_CSR as it is now.
pub fn reset_flags() -> u32 {
    read(RCC_CSR)
}

/// Clears the reset flags for the next boot.
pub fn clear_reset_flags() {
    write(RCC_CSR, read(RCC_CSR) | RCC_CSR_RMVF);
}
