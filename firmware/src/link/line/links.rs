//! The links of a line: never empty, so the first unit's link is always there.

use heapless::Vec;

use super::MAX_UNITS;
use crate::link::PsLink;

/// One link per unit, the first always present (a [`SharedLine`](super::SharedLine) is
/// refused without units), so a unit index out of range can fall back to it without a
/// panic path.
#[derive(Debug)]
pub(super) struct Links {
    first: PsLink,
    rest: Vec<PsLink, { MAX_UNITS - 1 }>,
}

impl Links {
    /// `first`, then up to three more (those beyond are dropped: the configuration was
    /// checked against [`MAX_UNITS`] before).
    pub(super) fn new(first: PsLink, rest: impl IntoIterator<Item = PsLink>) -> Links {
        let mut others = Vec::new();
        for link in rest {
            let _ = others.push(link);
        }
        Links {
            first,
            rest: others,
        }
    }

    pub(super) fn len(&self) -> usize {
        1 + self.rest.len()
    }

    pub(super) fn first(&self) -> &PsLink {
        &self.first
    }

    pub(super) fn get(&self, index: usize) -> Option<&PsLink> {
        match index {
            0 => Some(&self.first),
            _ => self.rest.get(index - 1),
        }
    }

    pub(super) fn get_mut(&mut self, index: usize) -> Option<&mut PsLink> {
        match index {
            0 => Some(&mut self.first),
            _ => self.rest.get_mut(index - 1),
        }
    }

    /// Unit `index`'s link, or the first unit's for an index out of range.
    pub(super) fn get_or_first_mut(&mut self, index: usize) -> &mut PsLink {
        match index.checked_sub(1).and_then(|i| self.rest.get_mut(i)) {
            Some(link) => link,
            None => &mut self.first,
        }
    }

    pub(super) fn iter(&self) -> impl Iterator<Item = &PsLink> {
        core::iter::once(&self.first).chain(self.rest.iter())
    }

    pub(super) fn iter_mut(&mut self) -> impl Iterator<Item = &mut PsLink> {
        core::iter::once(&mut self.first).chain(self.rest.iter_mut())
    }
}
