//! The links of a line: never empty, so the first unit's link is always there.
//!
//! The storage is fixed (one slot per possible unit): a line is made with its first link
//! alone, and a set of units is filled in place, one link at a time, never built whole in a
//! local and moved: four links are 15 KB, and the board's stack is 32 KB.

use super::MAX_UNITS;
use crate::link::{LinkConfig, PowermaxProcess, PsLink};
use plasma_protocol::time::Instant;

/// One link per unit, the first always present (a [`SharedLine`](super::SharedLine) is
/// refused without units), so a unit index out of range can fall back to it without a
/// panic path. The others are contiguous: slot `i` is unit `i + 1`.
#[derive(Debug)]
pub(super) struct Links {
    first: PsLink,
    // Named slots, not an array: a struct literal's fields are each built in place, where
    // an array literal of calls was built on the stack and copied (10 KB).
    second: Option<PsLink>,
    third: Option<PsLink>,
    fourth: Option<PsLink>,
}

const _: () = assert!(MAX_UNITS == 4, "one slot per unit");

/// How the links of a set are made: their configurations (at least one), whether they share
/// the line, and the process the first one restores.
#[derive(Clone, Copy)]
pub(super) struct Making<'a> {
    pub(super) base: LinkConfig,
    pub(super) configs: &'a [LinkConfig],
    pub(super) process: Option<PowermaxProcess>,
    pub(super) now: Instant,
}

impl Making<'_> {
    fn shared(&self) -> bool {
        self.configs.len() > 1
    }

    /// Unit `index`'s link, if the set has one.
    fn link(&self, index: usize) -> Option<PsLink> {
        let config = *self.configs.get(index)?;
        let mut link = PsLink::new(config, self.now);
        if self.shared() {
            link.share_line();
        }
        if let (0, Some(process)) = (index, self.process) {
            link.restore(process);
        }
        Some(link)
    }

    /// A unit alone's link: `base` as it is, restoring `process`.
    pub(super) fn first_alone(
        base: LinkConfig,
        process: Option<PowermaxProcess>,
        now: Instant,
    ) -> PsLink {
        let mut link = PsLink::new(base, now);
        if let Some(process) = process {
            link.restore(process);
        }
        link
    }

    /// The first unit's link (with `base` should there be no configuration).
    fn first(&self) -> PsLink {
        match self.link(0) {
            Some(link) => link,
            None => PsLink::new(self.base, self.now),
        }
    }
}

impl Links {
    /// One link alone (the others are built in place, [`Links::refill`]).
    pub(super) fn alone(first: PsLink) -> Links {
        Links {
            first,
            second: None,
            third: None,
            fourth: None,
        }
    }

    /// The links anew, in place, one at a time.
    pub(super) fn refill(&mut self, making: Making<'_>) {
        self.first = making.first();
        self.second = making.link(1);
        self.third = making.link(2);
        self.fourth = making.link(3);
    }

    fn rest(&self) -> [&Option<PsLink>; MAX_UNITS - 1] {
        [&self.second, &self.third, &self.fourth]
    }

    pub(super) fn len(&self) -> usize {
        1 + self.rest().iter().take_while(|slot| slot.is_some()).count()
    }

    pub(super) fn first(&self) -> &PsLink {
        &self.first
    }

    pub(super) fn get(&self, index: usize) -> Option<&PsLink> {
        match index {
            0 => Some(&self.first),
            1 => self.second.as_ref(),
            2 => self.third.as_ref(),
            3 => self.fourth.as_ref(),
            _ => None,
        }
    }

    pub(super) fn get_mut(&mut self, index: usize) -> Option<&mut PsLink> {
        match index {
            0 => Some(&mut self.first),
            1 => self.second.as_mut(),
            2 => self.third.as_mut(),
            3 => self.fourth.as_mut(),
            _ => None,
        }
    }

    /// Unit `index`'s link, or the first unit's for an index out of range.
    pub(super) fn get_or_first_mut(&mut self, index: usize) -> &mut PsLink {
        let slot = match index {
            1 => self.second.as_mut(),
            2 => self.third.as_mut(),
            3 => self.fourth.as_mut(),
            _ => None,
        };
        match slot {
            Some(link) => link,
            None => &mut self.first,
        }
    }

    pub(super) fn iter(&self) -> impl Iterator<Item = &PsLink> {
        let rest = [&self.second, &self.third, &self.fourth];
        core::iter::once(&self.first).chain(rest.into_iter().map_while(Option::as_ref))
    }

    pub(super) fn iter_mut(&mut self) -> impl Iterator<Item = &mut PsLink> {
        let rest = [&mut self.second, &mut self.third, &mut self.fourth];
        core::iter::once(&mut self.first).chain(rest.into_iter().map_while(Option::as_mut))
    }
}
