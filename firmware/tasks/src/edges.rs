//! The input edges, by register, the same on both chips: every input's EXTI line armed for
//! both edges once at start and never masked again; the boards' EXTI interrupts call
//! [`on_interrupt`], which clears what is pending and notes the edge in [`EDGES`]
//! (`plasma_firmware::io::EdgeLatch`: why the lines stay armed). The I/O task waits on
//! [`EDGES`] and reads the levels.

use plasma_firmware::io::EdgeLatch;
use plasma_firmware::platform::pins;

use crate::chip;

/// Edges noted by the EXTI interrupts, taken by the I/O task.
pub static EDGES: EdgeLatch = EdgeLatch::new();

/// Routes every input pin with a line of its own (`pins::EDGE_INPUTS`, every unit set's) to
/// its EXTI line and arms it (both edges). Call once, after the pins are inputs and before the
/// EXTI interrupts are unmasked.
pub fn arm_inputs() {
    chip::enable_syscfg_clock();
    for pin in pins::EDGE_INPUTS {
        chip::arm_edge_line(pin);
    }
}

/// The body of every input EXTI interrupt: clears the pending lines, notes the edge; returns
/// the lines that were pending (the emulated board stamps TORCH_ON's for its probe).
pub fn on_interrupt() -> u32 {
    let pending = chip::take_pending_edges();
    EDGES.on_edge();
    pending
}
