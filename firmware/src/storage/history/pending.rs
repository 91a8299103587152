//! The bounded RAM queue between the code that sees events and the task that writes them.

use heapless::Deque;

use super::entry::{Event, Unit};

/// When and about what an event happened: the parts of an entry its writer knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stamp {
    /// Milliseconds since boot.
    pub uptime_ms: u32,
    /// Unix seconds at boot, if the CNC has set the clock.
    pub clock_at_boot: Option<u32>,
    /// The unit on the line.
    pub unit: Unit,
}

/// An event waiting to be written; the store adds the sequence number and the boot count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Draft {
    /// When.
    pub stamp: Stamp,
    /// What.
    pub event: Event,
}

/// Up to `N` drafts. Pushing never blocks and never grows: when full, the draft is dropped
/// and counted, and the count goes into the queue as [`Event::EntriesDropped`] as soon as
/// there is room for it and the next draft.
#[derive(Debug, Default)]
pub struct Pending<const N: usize> {
    drafts: Deque<Draft, N>,
    dropped: u32,
}

impl<const N: usize> Pending<N> {
    /// An empty queue.
    pub const fn new() -> Self {
        Pending {
            drafts: Deque::new(),
            dropped: 0,
        }
    }

    /// Queues `draft`; returns false if it was dropped (the queue is full).
    pub fn push(&mut self, draft: Draft) -> bool {
        let free = N - self.drafts.len();
        if self.dropped > 0 && free >= 2 {
            let lost = Draft {
                // The lost entries may be about any unit: the count is the whole bridge's.
                stamp: Stamp {
                    unit: Unit::default(),
                    ..draft.stamp
                },
                event: Event::EntriesDropped {
                    count: self.dropped,
                },
            };
            if self.drafts.push_back(lost).is_ok() {
                self.dropped = 0;
            }
        }
        if self.dropped == 0 && self.drafts.push_back(draft).is_ok() {
            return true;
        }
        self.dropped = self.dropped.saturating_add(1);
        false
    }

    /// The oldest draft, to write it.
    pub fn take(&mut self) -> Option<Draft> {
        self.drafts.pop_front()
    }

    /// Drafts waiting.
    pub fn len(&self) -> usize {
        self.drafts.len()
    }

    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.drafts.is_empty()
    }

    /// Drafts dropped since the last [`Event::EntriesDropped`] was queued.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A link loss of the second unit on the line.
    fn draft(uptime_ms: u32) -> Draft {
        Draft {
            stamp: Stamp {
                uptime_ms,
                clock_at_boot: None,
                unit: Unit {
                    family: Some(crate::link::Family::Hpr),
                    model: 9,
                    line_index: 1,
                },
            },
            event: Event::LinkLost,
        }
    }

    #[test]
    fn a_storm_stays_bounded_and_the_loss_is_queued_when_room_returns() {
        let mut pending = Pending::<4>::new();
        for t in 0..100 {
            let kept = pending.push(draft(t));
            assert_eq!(kept, t < 4);
            assert!(pending.len() <= 4);
        }
        assert_eq!(pending.dropped(), 96);
        // One slot free is not enough for the count and the next draft: both wait.
        assert_eq!(pending.take(), Some(draft(0)));
        assert!(!pending.push(draft(100)));
        assert_eq!(pending.dropped(), 97);
        assert_eq!(pending.take(), Some(draft(1)));
        assert!(pending.push(draft(101)));
        assert_eq!(pending.dropped(), 0);
        let order: heapless::Vec<Draft, 4> = core::iter::from_fn(|| pending.take()).collect();
        assert_eq!(
            order.as_slice(),
            &[
                draft(2),
                draft(3),
                // The whole bridge's count: no unit's.
                Draft {
                    stamp: Stamp {
                        unit: Unit::default(),
                        ..draft(101).stamp
                    },
                    event: Event::EntriesDropped { count: 97 }
                },
                draft(101),
            ]
        );
        assert!(pending.is_empty());
    }
}
