//! The HardFault handler of every board, which must work when the stack is what failed.
//!
//! The stack fills SRAM2 alone and an overflow runs off its bottom into unmapped space
//! (memory.x): the push that overflows faults, the exception entry's own stacking faults
//! too (the core still enters the handler, the frame lost), and a handler that then pushes
//! anything on that stack faults at HardFault priority: lockup, with START as it was until
//! the IWDG resets a second later. So the vector ([`hard_fault_handler!`]) is a few
//! instructions that touch no memory: they note where the stack pointer was, move MSP back
//! to the top of the stack (nothing that was on it is needed again: the path ends in a
//! reset), and only then call Rust ([`on_hard_fault`]), which makes the outputs safe first.

use defmt::error;

use crate::Board;

// The stack's bounds (memory.x: `_stack_end` below, `_stack_start` above).
unsafe extern "C" {
    static _stack_end: u32;
    static _stack_start: u32;
}

/// An exception frame's size without the FPU state: r0-r3, r12, lr, pc, xPSR.
const FRAME_WORDS: usize = 8;
/// The stacked return address: the faulting instruction.
const FRAME_PC: usize = 6;

/// The faulting instruction's address, read from the exception frame at `sp` if the whole
/// frame lies in the stack; `None` when the stack pointer had left the stack (an overflow:
/// reading there would fault again).
fn stacked_pc(sp: usize) -> Option<u32> {
    let bottom = (&raw const _stack_end) as usize;
    let top = (&raw const _stack_start) as usize;
    let frame_end = sp.checked_add(FRAME_WORDS * 4)?;
    if sp < bottom || frame_end > top || !sp.is_multiple_of(4) {
        return None;
    }
    // SAFETY: an aligned word inside the stack region, which is RAM.
    Some(unsafe { ((sp as *const u32).add(FRAME_PC)).read_volatile() })
}

/// The Rust half of the HardFault handler, on a fresh stack: the board's fault path
/// (`crate::safe_state::fail`) with the faulting instruction's address, or, when the stack
/// pointer was outside the stack, the fact of an overflow.
///
/// # Safety
/// Only for the vector of [`hard_fault_handler!`], with `sp` the faulting context's stack
/// pointer.
pub unsafe extern "C" fn on_hard_fault<B: Board>(sp: usize) -> ! {
    let pc = stacked_pc(sp);
    crate::safe_state::fail(
        || match pc {
            Some(pc) => error!("hard fault at pc {=u32:#010x}", pc),
            None => error!("hard fault: stack overflow (sp {=usize:#010x})", sp),
        },
        B::drain_log,
    )
}

/// Defines the `HardFault` vector (in place of cortex-m-rt's `#[exception]`, whose handler
/// starts by pushing on the stack that may have failed) for `$board`: MSP or PSP per
/// EXC_RETURN into r0, MSP reset to the top of the stack, then
/// [`on_hard_fault`](crate::hard_fault::on_hard_fault).
#[macro_export]
macro_rules! hard_fault_handler {
    ($board:ty) => {
        ::core::arch::global_asm!(
            ".section .HardFault.user, \"ax\"",
            ".global HardFault",
            ".type HardFault,%function",
            ".thumb_func",
            "HardFault:",
            // EXC_RETURN bit 2: which stack the faulting context used.
            "tst lr, #4",
            "ite eq",
            "mrseq r0, MSP",
            "mrsne r0, PSP",
            "movw r1, :lower16:_stack_start",
            "movt r1, :upper16:_stack_start",
            "msr MSP, r1",
            "isb",
            "b {handler}",
            ".size HardFault, . - HardFault",
            handler = sym $crate::hard_fault::on_hard_fault::<$board>,
        );
    };
}
