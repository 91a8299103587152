//! Test images only (feature `test-hooks`, which only the QEMU harness's image build turns on;
//! `cargo emu-fw` and the Nucleo image are built without it): ways to make the firmware fail
//! on purpose, to test the watchdog's fail-safe and the fault path end to end.
//!
//! Each hook has a pin of the one pin table (`plasma_firmware::platform::pins::TEST_HOOKS`); pulling it
//! low asks for its failure, in thread mode, where the tasks run:
//!
//! - `TEST_STALL` (PC13, the user button): thread mode spins for good. The bridge, settings
//!   and heartbeat tasks stop reporting progress while the I/O task (its own interrupt
//!   executor) runs on, exactly the case the fail-safe latch exists for.
//! - `TEST_PANIC` (PC11): a panic, as an `unwrap` on a bad value in a task would.
//! - `TEST_HARD_FAULT` (PC12): an undefined instruction (`udf`). UsageFault is not enabled
//!   (SHCSR), so it escalates to HardFault. Chosen over a read from an address that faults:
//!   `udf` is undefined on every Armv7-M core by definition, whereas which addresses fault
//!   depends on the memory map as modelled (QEMU's STM32L4x5 backs many unmodelled
//!   peripherals with registers that read as zero), so the hook would test the model.
//! - `TEST_STACK_OVERFLOW` (PC9): a recursion that runs the stack off the bottom of SRAM2
//!   (memory.x), where nothing is mapped: the push faults, and so does the stacking of the
//!   HardFault's own frame, so the handler starts with the stack pointer outside the stack
//!   (`plasma_tasks::hard_fault`).
//!
//! The pins' EXTI lines (on the inputs' EXTI15_10 interrupt) wake the hook task, so it costs
//! no wake-ups while unused (the idle figures stay those of the plain image).

use defmt::warn;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use plasma_firmware::platform::pins::{
    Pin, TEST_HARD_FAULT, TEST_HOOKS, TEST_PANIC, TEST_STACK_OVERFLOW,
};
use stm32_metapac::gpio::vals::{Idr, Moder, Pupdr};

use crate::gpio::gpio;

/// The pin of the hook asked for.
static REQUESTED: Signal<CriticalSectionRawMutex, Pin> = Signal::new();

/// From the EXTI interrupt: `pending` lines were cleared; a hook is asked for if its line is
/// among them and its pin is low (the harness pulled it; the rising edge of a release asks
/// for nothing).
pub fn on_edges(pending: u32) {
    for pin in TEST_HOOKS {
        if pending & pin.mask() != 0 && is_low(pin) {
            REQUESTED.signal(pin);
        }
    }
}

fn is_low(pin: Pin) -> bool {
    gpio(pin.port).idr().read().idr(pin.number as usize) == Idr::LOW
}

/// Waits for a hook's pin to be pulled low; then fails as that hook says.
#[embassy_executor::task]
pub async fn fail_on_request() {
    for pin in TEST_HOOKS {
        // Routed to its EXTI line before the pull-up raises it: QEMU's SYSCFG passes on only
        // the changes of the port a line is routed to, and its EXTI finds edges by comparing
        // with the last level passed on, so a pin raised before the routing would have its
        // first fall taken for no change. (The rise is an edge like any other: the pin is
        // not low, so it asks for nothing.)
        plasma_tasks::chip::arm_edge_line(pin);
        let (port, n) = (gpio(pin.port), pin.number as usize);
        port.pupdr().modify(|w| w.set_pupdr(n, Pupdr::PULL_UP));
        port.moder().modify(|w| w.set_moder(n, Moder::INPUT));
    }
    match REQUESTED.wait().await {
        TEST_PANIC => panic!("test hook: panic on request"),
        TEST_HARD_FAULT => {
            warn!("test hook: undefined instruction now");
            cortex_m::asm::udf()
        }
        TEST_STACK_OVERFLOW => {
            warn!("test hook: stack overflow now");
            overflow_the_stack(0);
        }
        _ => {
            warn!("test hook: thread mode stalls now");
            loop {
                cortex_m::asm::nop();
            }
        }
    }
}

/// Recurses for good, 256 bytes of stack a call (`black_box` keeps the frames real): the
/// 32 KiB stack overflows after about 128 calls.
#[allow(unconditional_recursion)]
#[inline(never)]
fn overflow_the_stack(depth: u32) -> u32 {
    let frame = core::hint::black_box([depth; 64]);
    overflow_the_stack(frame[0] + 1).wrapping_add(frame[63])
}
