//! A progress monitor that decides when the hardware watchdog may be fed.
//!
//! Feeding the watchdog from a timer or the idle loop only proves that *something* runs. Here
//! every task that matters registers with the longest silence it is allowed, reports progress
//! as it works, and the watchdog is fed only while every task has reported within its own
//! deadline. The first stall is latched: feeding stops for good, the board resets, and the
//! name of the task that stalled is there to log before it does.
//!
//! ```
//! use plasma_protocol::time::{Duration, Instant};
//! use plasma_firmware::platform::watchdog::ProgressMonitor;
//!
//! let t0 = Instant::ZERO;
//! let mut monitor = ProgressMonitor::<4>::new();
//! let ps_link = monitor.register("ps-link", Duration::from_millis(500), t0).unwrap();
//! let cnc = monitor.register("cnc", Duration::from_millis(200), t0).unwrap();
//!
//! monitor.report(ps_link, Instant::from_millis(400));
//! monitor.report(cnc, Instant::from_millis(150));
//! assert!(monitor.should_feed(Instant::from_millis(340)));
//!
//! // The CNC session went quiet for more than 200 ms.
//! assert!(!monitor.should_feed(Instant::from_millis(351)));
//! assert_eq!(monitor.stalled().unwrap().name, "cnc");
//! ```

use plasma_protocol::time::{Duration, Instant};

/// Handle of a registered task.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TaskId(u8);

/// No free slot: the monitor was built with fewer slots than there are tasks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MonitorFull;

/// The task that stalled first, for the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stall {
    /// The stalled task.
    pub task: TaskId,
    /// Its name, as registered.
    pub name: &'static str,
    /// Its allowed silence.
    pub deadline: Duration,
    /// How long it had been silent when the stall was seen.
    pub silent_for: Duration,
}

#[derive(Debug, Clone, Copy)]
struct Slot {
    name: &'static str,
    deadline: Duration,
    last_report: Instant,
}

/// Watches up to `N` tasks.
#[derive(Debug, Clone)]
pub struct ProgressMonitor<const N: usize> {
    slots: [Option<Slot>; N],
    stall: Option<Stall>,
}

impl<const N: usize> Default for ProgressMonitor<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ProgressMonitor<N> {
    /// A monitor with no tasks (`N` must fit the `u8` task ids).
    pub const fn new() -> Self {
        assert!(N <= u8::MAX as usize, "at most 255 tasks");
        ProgressMonitor {
            slots: [None; N],
            stall: None,
        }
    }

    /// Registers a task that must report at least every `deadline`. It counts as having
    /// reported at `now`, so it has one full deadline to start up.
    pub fn register(
        &mut self,
        name: &'static str,
        deadline: Duration,
        now: Instant,
    ) -> Result<TaskId, MonitorFull> {
        let (index, slot) = self
            .slots
            .iter_mut()
            .enumerate()
            .find(|(_, slot)| slot.is_none())
            .ok_or(MonitorFull)?;
        *slot = Some(Slot {
            name,
            deadline,
            last_report: now,
        });
        // `new` bounds N to u8, so the index fits.
        Ok(TaskId(index as u8))
    }

    /// Records that `task` made progress at `now`. Reports after a stall was latched, and
    /// reports with an earlier `now` than the last one, change nothing.
    pub fn report(&mut self, task: TaskId, now: Instant) {
        if self.stall.is_some() {
            return;
        }
        if let Some(Some(slot)) = self.slots.get_mut(usize::from(task.0)) {
            slot.last_report = slot.last_report.max(now);
        }
    }

    /// Whether the watchdog may be fed at `now`: true while every registered task has
    /// reported within its deadline (also true with no task registered). The first time a
    /// task is found late the stall is latched and this returns false from then on.
    pub fn should_feed(&mut self, now: Instant) -> bool {
        if self.stall.is_none() {
            self.stall = self.late_task(now);
        }
        self.stall.is_none()
    }

    /// The latched stall, if there was one.
    pub fn stalled(&self) -> Option<Stall> {
        self.stall
    }

    /// The first task (in registration order) that is late at `now`, without latching.
    pub fn late_task(&self, now: Instant) -> Option<Stall> {
        self.slots.iter().enumerate().find_map(|(index, slot)| {
            let slot = slot.as_ref()?;
            let silent_for = now.saturating_since(slot.last_report);
            (silent_for > slot.deadline).then_some(Stall {
                task: TaskId(index as u8),
                name: slot.name,
                deadline: slot.deadline,
                silent_for,
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn ms(v: u64) -> Instant {
        Instant::from_millis(v)
    }

    #[test]
    fn feeds_with_no_tasks() {
        let mut m = ProgressMonitor::<2>::new();
        assert!(m.should_feed(ms(1_000_000)));
        assert_eq!(m.stalled(), None);
    }

    #[test]
    fn each_task_has_its_own_deadline() {
        let mut m = ProgressMonitor::<3>::new();
        let fast = m
            .register("fast", Duration::from_millis(100), ms(0))
            .unwrap();
        let slow = m.register("slow", Duration::from_secs(2), ms(0)).unwrap();
        for t in (0..=1900).step_by(50) {
            m.report(fast, ms(t));
            assert!(m.should_feed(ms(t)), "at {t} ms");
        }
        // slow never reported: exactly at its deadline it is still on time, just after it is not.
        assert!(m.should_feed(ms(2000)));
        m.report(fast, ms(2000));
        assert!(m.should_feed(ms(2000)));
        assert!(!m.should_feed(ms(2001)));
        let stall = m.stalled().unwrap();
        assert_eq!(stall.task, slow);
        assert_eq!(stall.name, "slow");
        assert_eq!(stall.silent_for, Duration::from_millis(2001));
        assert_eq!(stall.deadline, Duration::from_secs(2));
    }

    #[test]
    fn a_stall_is_latched_even_if_the_task_recovers() {
        let mut m = ProgressMonitor::<1>::new();
        let t = m.register("t", Duration::from_millis(10), ms(0)).unwrap();
        assert!(!m.should_feed(ms(11)));
        m.report(t, ms(12));
        assert!(!m.should_feed(ms(12)));
        assert_eq!(m.stalled().unwrap().silent_for, Duration::from_millis(11));
    }

    #[test]
    fn registration_gives_a_full_deadline_from_now() {
        let mut m = ProgressMonitor::<2>::new();
        m.register("early", Duration::from_millis(50), ms(0))
            .unwrap();
        let late = m
            .register("late", Duration::from_millis(50), ms(40))
            .unwrap();
        assert_eq!(m.late_task(ms(60)).unwrap().name, "early");
        m.report(TaskId(0), ms(60));
        assert_eq!(m.late_task(ms(90)), None);
        assert_eq!(m.late_task(ms(91)).unwrap().task, late);
    }

    #[test]
    fn full_monitor_and_unknown_ids_are_harmless() {
        let mut m = ProgressMonitor::<1>::new();
        m.register("a", Duration::from_millis(5), ms(0)).unwrap();
        assert_eq!(
            m.register("b", Duration::from_millis(5), ms(0)),
            Err(MonitorFull)
        );
        // An id from a bigger monitor: ignored, not a panic.
        m.report(TaskId(7), ms(3));
        assert!(m.should_feed(ms(5)));
        assert!(!m.should_feed(ms(6)));
    }

    #[test]
    fn time_going_backwards_does_not_rewind_progress() {
        let mut m = ProgressMonitor::<1>::new();
        let t = m.register("t", Duration::from_millis(10), ms(100)).unwrap();
        m.report(t, ms(50));
        assert!(m.should_feed(ms(105)));
        assert!(m.should_feed(ms(110)));
        assert!(!m.should_feed(ms(111)));
    }

    proptest! {
        /// Against a direct model: feed iff no task's gap since its last report (or
        /// registration) exceeds its deadline at any check so far.
        #[test]
        fn agrees_with_a_model(
            deadlines in prop::collection::vec(1u64..50, 1..4),
            events in prop::collection::vec((0usize..4, 0u64..30, any::<bool>()), 0..60),
        ) {
            let mut m = ProgressMonitor::<4>::new();
            let ids: Vec<TaskId> = deadlines
                .iter()
                .map(|&d| m.register("t", Duration::from_millis(d), ms(0)).unwrap())
                .collect();
            let mut last = vec![0u64; ids.len()];
            let mut now = 0u64;
            let mut tripped = false;
            for (task, step, is_report) in events {
                now += step;
                if is_report {
                    if let Some(&id) = ids.get(task) {
                        if !tripped {
                            last[task] = now;
                        }
                        m.report(id, ms(now));
                    }
                } else {
                    let late = last.iter().zip(&deadlines).any(|(&l, &d)| now - l > d);
                    tripped |= late;
                    prop_assert_eq!(m.should_feed(ms(now)), !tripped);
                }
            }
        }
    }
}
