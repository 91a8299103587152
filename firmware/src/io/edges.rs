//! Input edges from the interrupt to the I/O task, without a gap.
//!
//! The EXTI lines stay armed all the time; the interrupt only notes that an edge came
//! ([`EdgeLatch::on_edge`]) and the I/O task waits for the note ([`EdgeLatch::wait`]), then
//! reads the levels of every pin. An edge at any moment, also while the task is busy between
//! its level read and its next wait, leaves the note set, so the next wait returns at once and
//! the task reads the pins again.
//!
//! Why not embassy-stm32 0.6.0's `ExtiInput::wait_for_any_edge`: its future arms the line when
//! it is created (which clears the line's pending flag) and masks it when dropped, and its
//! interrupt masks every line that fired. A task that builds the futures anew each loop misses
//! an edge between its level read and the re-arm: START could stay on for up to the task's
//! longest sleep (50 ms) after TORCH_ON dropped (docs/board.md, "Faults found in review").

use core::future::poll_fn;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::Poll;

use embassy_sync::waitqueue::AtomicWaker;

/// Edges noted by the interrupt and not yet taken by the task.
pub struct EdgeLatch {
    pending: AtomicBool,
    waker: AtomicWaker,
}

impl EdgeLatch {
    /// No edge noted.
    pub const fn new() -> Self {
        EdgeLatch {
            pending: AtomicBool::new(false),
            waker: AtomicWaker::new(),
        }
    }

    /// From the EXTI interrupt (after clearing the line's pending flag): an edge came.
    pub fn on_edge(&self) {
        self.pending.store(true, Ordering::Release);
        self.waker.wake();
    }

    /// Completes once an edge was noted since the last completion; at once if one is noted
    /// already. Cancel-safe: dropping it loses nothing.
    pub async fn wait(&self) {
        poll_fn(|cx| {
            self.waker.register(cx.waker());
            if self.pending.swap(false, Ordering::AcqRel) {
                Poll::Ready(())
            } else {
                Poll::Pending
            }
        })
        .await
    }
}

impl Default for EdgeLatch {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::pin::pin;
    use core::task::{Context, Waker};

    /// One poll of `future` with a no-op waker.
    fn ready<F: Future>(future: core::pin::Pin<&mut F>) -> bool {
        future
            .poll(&mut Context::from_waker(Waker::noop()))
            .is_ready()
    }

    #[test]
    fn an_edge_between_the_level_read_and_the_next_wait_is_not_lost() {
        // The I/O task's loop: wait for an edge, read the levels, drive, wait again.
        let latch = EdgeLatch::new();
        let mut first = pin!(latch.wait());
        assert!(!ready(first.as_mut()), "nothing happened yet");
        latch.on_edge(); // TORCH_ON pressed
        assert!(ready(first.as_mut()));
        // The task now reads the levels (TORCH_ON active) and drives START... and while it
        // does, TORCH_ON is released: the interrupt notes it before the task waits again.
        latch.on_edge();
        // The next wait (a new future, as the task builds one each loop) returns at once,
        // so the task reads the levels again and drops START without waiting for its
        // 50 ms sleep.
        let mut second = pin!(latch.wait());
        assert!(ready(second.as_mut()), "the edge in the window was lost");
        // Taken: the one after that waits for a new edge.
        let mut third = pin!(latch.wait());
        assert!(!ready(third.as_mut()));
    }

    #[test]
    fn a_dropped_wait_loses_no_edge() {
        let latch = EdgeLatch::new();
        {
            let mut waiting = pin!(latch.wait());
            assert!(!ready(waiting.as_mut()));
            // Another source woke the task (a timer), its wait is dropped...
        }
        // ...and an edge comes before the task waits again.
        latch.on_edge();
        assert!(ready(pin!(latch.wait())));
    }
}
