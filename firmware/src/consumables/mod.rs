//! Consumable life: one record per consumable set (SYNC: per cartridge), sans-IO.
//!
//! - A Powermax SYNC cartridge keeps its own counters (0x3040-0x3043, SYNC manual
//!   000_dd931256418ae627.txt lines 1464-1498): they are the source of its starts and arc
//!   seconds, and its UID names the set: another UID starts a new record by itself.
//! - On a legacy Powermax, an HPR and a MaxPro200 the bridge counts what it observes: a start
//!   is an arc transfer (MOTION on) or a start that ran into the transfer time-out; the arc
//!   seconds run from MOTION on to MOTION off. `CONSUMABLES NEW` starts a new set.
//! - Signs of wear are counted on every family: a 0-32-x fault (cartridge at end of life,
//!   SYNC manual fault table) and an HPR rampdown error, as its RAMPDOWN_ERROR output signals
//!   it ("Consumable life is affected", HPR manual 002_72b43a5685974c77.txt line 56).
//! - The 90 % and 100 % warnings are given once per set; which were given is part of the
//!   record, so a reset of the bridge does not repeat them.
//!
//! # Flash wear and what a power cut loses
//! The record is saved when it changed, only while the arc is off, and at most once per
//! [`SAVE_INTERVAL`]: a long day of short cuts writes one small record a minute at most. A
//! new set and a warning given are saved at once. A power cut loses at most the counts of
//! the last [`SAVE_INTERVAL`] before it (and the arc that was burning).

mod record;

use plasma_protocol::powermax::FaultCode;
use plasma_protocol::powermax::sync::Cartridge;
use plasma_protocol::time::{Duration, Instant};

/// The least time between two saves of a changed record.
pub const SAVE_INTERVAL: Duration = Duration::from_secs(60);

/// Share of life used at which the first warning is given, percent.
pub const WARN_PERCENT: u32 = 90;
/// Share of life used at which the second warning is given, percent.
pub const END_PERCENT: u32 = 100;

/// The limits of a consumable set (`CONFIG consumable_start_limit`,
/// `consumable_arc_limit_s`); `None` is OFF.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Limits {
    /// Starts a set lasts.
    pub starts: Option<u32>,
    /// Arc-on seconds a set lasts.
    pub arc_seconds: Option<u32>,
}

impl Limits {
    /// The highest limit `CONFIG` takes.
    pub const MAX: u32 = 1_000_000;
}

/// What survives a power cycle: the bridge's counts of one set and the warnings given.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConsumableSet {
    /// Starts the bridge counted.
    pub starts: u32,
    /// Arc-on time the bridge counted, milliseconds.
    pub arc_ms: u64,
    /// 0-32-x cartridge faults seen.
    pub wear_faults: u16,
    /// HPR rampdown errors seen.
    pub rampdown_errors: u16,
    /// The SYNC cartridge the set is (`None`: a set the operator names with
    /// `CONSUMABLES NEW`).
    pub uid: Option<[u8; 16]>,
    /// The 90 % warning was given.
    pub warned_90: bool,
    /// The 100 % warning was given.
    pub warned_100: bool,
}

/// Where the counts shown come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Source {
    /// The SYNC cartridge's own counters.
    Cartridge,
    /// The bridge's counts.
    Bridge,
}

/// The counts of the set in use, from their source.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Usage {
    /// Where they come from.
    pub source: Source,
    /// Starts.
    pub starts: u32,
    /// Arc-on seconds.
    pub arc_seconds: u32,
}

impl Usage {
    /// The share of life used, percent (the larger of starts and arc time against their
    /// limits), `None` with both limits OFF.
    pub fn used_percent(&self, limits: Limits) -> Option<u32> {
        let share =
            |used: u32, limit: Option<u32>| limit.filter(|&l| l > 0).map(|l| percent_of(used, l));
        match (
            share(self.starts, limits.starts),
            share(self.arc_seconds, limits.arc_seconds),
        ) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }
}

/// A warning due: the share of life it is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Warning {
    /// The threshold reached ([`WARN_PERCENT`] or [`END_PERCENT`]).
    pub threshold: u32,
    /// The share used now.
    pub used_percent: u32,
}

/// The consumable set in use, its counting and when to save it. See the module docs.
#[derive(Debug, Default)]
pub struct Consumables {
    set: ConsumableSet,
    /// MOTION came on at this time and has not gone off.
    arc_since: Option<Instant>,
    /// The record changed since it was last handed out to be saved.
    changed: bool,
    /// The change must not wait for [`SAVE_INTERVAL`] (a new set, a warning).
    urgent: bool,
    /// When the record was last handed out to be saved.
    saved_at: Option<Instant>,
}

impl Consumables {
    /// The record kept in flash, as this boot starts with it.
    pub fn restore(&mut self, set: ConsumableSet) {
        self.set = set;
    }

    /// The record.
    pub fn set(&self) -> &ConsumableSet {
        &self.set
    }

    fn changed(&mut self) {
        self.changed = true;
    }

    /// The arc transferred (MOTION on): one start.
    pub fn arc_on(&mut self, now: Instant) {
        self.set.starts = self.set.starts.saturating_add(1);
        self.arc_since = Some(now);
        self.changed();
    }

    /// The arc went out (MOTION off): its time is added.
    pub fn arc_off(&mut self, now: Instant) {
        if let Some(since) = self.arc_since.take() {
            let ms = now.saturating_since(since).as_millis();
            self.set.arc_ms = self.set.arc_ms.saturating_add(ms);
            self.changed();
        }
    }

    /// A start ran into the transfer time-out: a start without an arc.
    pub fn start_without_transfer(&mut self) {
        self.set.starts = self.set.starts.saturating_add(1);
        self.changed();
    }

    /// A fault appeared: a 0-32-x (cartridge end of life) counts as a sign of wear.
    pub fn fault(&mut self, code: FaultCode) {
        if code.fields().1 == 32 {
            self.set.wear_faults = self.set.wear_faults.saturating_add(1);
            self.changed();
        }
    }

    /// An HPR rampdown error: a sign of wear.
    pub fn rampdown_error(&mut self) {
        self.set.rampdown_errors = self.set.rampdown_errors.saturating_add(1);
        self.changed();
    }

    /// A new set: the counts start from zero (`uid`: the SYNC cartridge it is).
    pub fn new_set(&mut self, now: Instant, uid: Option<[u8; 16]>) {
        self.set = ConsumableSet {
            uid,
            ..ConsumableSet::default()
        };
        // An arc burning through the change counts for the new set from now.
        if self.arc_since.is_some() {
            self.arc_since = Some(now);
        }
        self.changed();
        self.urgent = true;
    }

    /// A SYNC cartridge was read: a record for another cartridge (or none) starts anew for
    /// this one. True when it replaced another cartridge's record: the first cartridge a
    /// bridge sees is not a change of consumables.
    pub fn cartridge_seen(&mut self, now: Instant, uid: [u8; 16]) -> bool {
        if self.set.uid == Some(uid) {
            return false;
        }
        let replaced = self.set.uid.is_some();
        self.new_set(now, Some(uid));
        replaced
    }

    /// The counters of the record's cartridge as the unit last gave them: the record keeps
    /// them, so that they are shown (and survive a reset) while the link is down.
    pub fn cartridge_counts(&mut self, starts: u32, arc_seconds: u32) {
        let arc_ms = u64::from(arc_seconds) * 1000;
        if self.set.uid.is_some() && (self.set.starts, self.set.arc_ms) != (starts, arc_ms) {
            self.set.starts = starts;
            self.set.arc_ms = arc_ms;
            self.changed();
        }
    }

    /// The counts of the set in use: the cartridge's when one is read; for a cartridge's
    /// record without one (the link is down) its last counts, with the starts and arc time
    /// the bridge saw since; else the bridge's.
    pub fn usage(&self, now: Instant, cartridge: Option<&Cartridge>) -> Usage {
        if let Some(c) = cartridge {
            return Usage {
                source: Source::Cartridge,
                starts: u32::from(c.counters.starts),
                arc_seconds: c.counters.transfer_seconds(),
            };
        }
        let burning = self
            .arc_since
            .map_or(0, |since| now.saturating_since(since).as_millis());
        let ms = self.set.arc_ms.saturating_add(burning);
        // `div_rem_u16`: a 64-bit division would link the runtime's.
        let (seconds, _) = plasma_protocol::time::div_rem_u16(ms, 1000);
        Usage {
            source: match self.set.uid {
                Some(_) => Source::Cartridge,
                None => Source::Bridge,
            },
            starts: self.set.starts,
            arc_seconds: u32::try_from(seconds).unwrap_or(u32::MAX),
        }
    }

    /// The warning due for `usage` under `limits`, once per threshold and set (it is then
    /// marked given, and the record saved soon).
    pub fn warning_due(&mut self, usage: &Usage, limits: Limits) -> Option<Warning> {
        let used_percent = usage.used_percent(limits)?;
        let threshold = if used_percent >= END_PERCENT && !self.set.warned_100 {
            self.set.warned_100 = true;
            // Past both at once: one warning, the later one.
            self.set.warned_90 = true;
            END_PERCENT
        } else if used_percent >= WARN_PERCENT && !self.set.warned_90 {
            self.set.warned_90 = true;
            WARN_PERCENT
        } else {
            return None;
        };
        self.changed();
        self.urgent = true;
        Some(Warning {
            threshold,
            used_percent,
        })
    }

    /// When a changed record will be due for saving (`None`: nothing to save, or only once
    /// the arc is off).
    pub fn save_at(&self) -> Option<Instant> {
        if !self.changed || self.arc_since.is_some() {
            return None;
        }
        match self.saved_at {
            Some(at) if !self.urgent => Some(at + SAVE_INTERVAL),
            _ => Some(Instant::ZERO),
        }
    }

    /// The save of the record last handed out failed: it is offered again after
    /// [`SAVE_INTERVAL`].
    pub fn save_failed(&mut self) {
        self.changed = true;
    }

    /// The record to save now, if one is due (see the module docs); handing it out counts
    /// as saved. A save that fails is not retried before the next change.
    pub fn take_save(&mut self, now: Instant) -> Option<ConsumableSet> {
        if self.save_at()? > now {
            return None;
        }
        self.changed = false;
        self.urgent = false;
        self.saved_at = Some(now);
        Some(self.set)
    }
}

/// `used × 100 / limit` rounded down, saturated at `u32::MAX`: a binary long division of
/// the 39-bit product, so the board image has no 64-bit division routine (1 KB of flash).
fn percent_of(used: u32, limit: u32) -> u32 {
    let product = u64::from(used) * 100;
    let divisor = u64::from(limit);
    let (mut quotient, mut remainder) = (0u64, 0u64);
    // `used × 100` < 2^39: the bits above are zero.
    for bit in (0..39).rev() {
        remainder = (remainder << 1) | ((product >> bit) & 1);
        quotient <<= 1;
        if remainder >= divisor {
            remainder -= divisor;
            quotient |= 1;
        }
    }
    u32::try_from(quotient).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::powermax::{CartridgeCounters, CartridgeUid, PartNumber};

    fn at(ms: u64) -> Instant {
        Instant::from_millis(ms)
    }

    fn cut(c: &mut Consumables, from_ms: u64, arc_ms: u64) {
        c.arc_on(at(from_ms));
        c.arc_off(at(from_ms + arc_ms));
    }

    #[test]
    fn starts_and_arc_time_are_counted() {
        let mut c = Consumables::default();
        cut(&mut c, 1000, 2500);
        cut(&mut c, 5000, 1600);
        c.start_without_transfer();
        let usage = c.usage(at(10_000), None);
        assert_eq!(
            usage,
            Usage {
                source: Source::Bridge,
                starts: 3,
                arc_seconds: 4
            }
        );
        assert_eq!(c.set().arc_ms, 4100);
        // A burning arc shows in the seconds before it goes out.
        c.arc_on(at(20_000));
        assert_eq!(c.usage(at(23_000), None).arc_seconds, 7);
    }

    #[test]
    fn wear_signs_are_a_0_32_x_fault_and_a_rampdown_error() {
        let mut c = Consumables::default();
        c.fault(FaultCode(320));
        c.fault(FaultCode(321));
        c.fault(FaultCode(500));
        c.rampdown_error();
        assert_eq!((c.set().wear_faults, c.set().rampdown_errors), (2, 1));
    }

    #[test]
    fn the_used_share_is_the_larger_of_the_two_limits() {
        let usage = Usage {
            source: Source::Bridge,
            starts: 45,
            arc_seconds: 270,
        };
        let limits = |starts, arc_seconds| Limits {
            starts,
            arc_seconds,
        };
        assert_eq!(usage.used_percent(limits(None, None)), None);
        assert_eq!(usage.used_percent(limits(Some(50), None)), Some(90));
        assert_eq!(usage.used_percent(limits(None, Some(300))), Some(90));
        assert_eq!(usage.used_percent(limits(Some(100), Some(200))), Some(135));
    }

    #[test]
    fn each_warning_is_given_once_per_set() {
        let mut c = Consumables::default();
        let limits = Limits {
            starts: Some(10),
            arc_seconds: None,
        };
        for start in 0..8 {
            cut(&mut c, start * 1000, 100);
        }
        let warn = |c: &mut Consumables| {
            let usage = c.usage(at(100_000), None);
            c.warning_due(&usage, limits).map(|w| w.threshold)
        };
        assert_eq!(warn(&mut c), None);
        cut(&mut c, 20_000, 100);
        assert_eq!(warn(&mut c), Some(90));
        assert_eq!(warn(&mut c), None);
        cut(&mut c, 30_000, 100);
        assert_eq!(warn(&mut c), Some(100));
        cut(&mut c, 40_000, 100);
        assert_eq!(warn(&mut c), None);
        c.new_set(at(50_000), None);
        assert_eq!(c.set(), &ConsumableSet::default());
        for start in 0..11 {
            cut(&mut c, 60_000 + start * 1000, 100);
        }
        // Past both at once: only the later warning.
        assert_eq!(warn(&mut c), Some(100));
        assert_eq!(warn(&mut c), None);
    }

    #[test]
    fn a_cartridge_gives_the_counts_and_its_uid_names_the_set() {
        let mut c = Consumables::default();
        cut(&mut c, 0, 1000);
        c.fault(FaultCode(320));
        let cartridge = Cartridge {
            uid: CartridgeUid(*b"E00401D0036FB25D"),
            part_number: PartNumber(*b"428936"),
            revision: 3,
            nominal_current_raw: 45 * 64,
            // The SYNC manual's example reply, 000_dd931256418ae627.txt lines 1536-1541.
            counters: CartridgeCounters {
                starts: 214,
                pilot_arc_seconds: 9,
                transfers: 211,
                transfer_time_counts: 2447,
            },
        };
        assert!(
            !c.cartridge_seen(at(5000), cartridge.uid.0),
            "the first one"
        );
        assert_eq!(c.set().wear_faults, 0, "a new set");
        assert_eq!(c.set().uid, Some(cartridge.uid.0));
        assert!(!c.cartridge_seen(at(6000), cartridge.uid.0));
        assert!(
            c.cartridge_seen(at(7000), *b"E00401D0036FB25E"),
            "another one"
        );
        assert_eq!(c.usage(at(7000), None).starts, 0);
        assert!(!c.cartridge_seen(at(8000), *b"E00401D0036FB25E"));
        let read = Usage {
            source: Source::Cartridge,
            starts: 214,
            arc_seconds: 4894,
        };
        assert_eq!(c.usage(at(6000), Some(&cartridge)), read);
        // Without the cartridge (the link down): its last counts, kept in the record.
        c.cartridge_counts(read.starts, read.arc_seconds);
        assert_eq!(c.usage(at(6000), None), read);
        assert_eq!((c.set().starts, c.set().arc_ms), (214, 4_894_000));
    }

    #[test]
    fn saves_wait_for_the_arc_to_go_out_and_come_at_most_once_a_minute() {
        let mut c = Consumables::default();
        assert_eq!(c.take_save(at(0)), None, "nothing changed");
        c.arc_on(at(1000));
        assert_eq!(c.save_at(), None, "not while the arc burns");
        c.arc_off(at(3000));
        assert_eq!(c.take_save(at(3000)).map(|s| s.starts), Some(1));
        cut(&mut c, 4000, 1000);
        let due = at(3000) + SAVE_INTERVAL;
        assert_eq!(c.save_at(), Some(due));
        assert_eq!(c.take_save(due - Duration::from_millis(1)), None);
        assert_eq!(c.take_save(due).map(|s| s.starts), Some(2));
        // A new set does not wait.
        c.new_set(at(64_000), None);
        assert_eq!(c.take_save(at(64_000)), Some(ConsumableSet::default()));
    }

    #[test]
    fn percent_of_is_the_exact_quotient_rounded_down() {
        for (used, limit) in [
            (0, 1),
            (1, 3),
            (89, 99),
            (999_999, 1_000_000),
            (1_000_000, 1_000_000),
            (u32::MAX, 1),
            (u32::MAX, u32::MAX),
            (u32::MAX - 1, u32::MAX),
            (123_456_789, 987_654),
        ] {
            let exact = u64::from(used) * 100 / u64::from(limit);
            assert_eq!(
                percent_of(used, limit),
                u32::try_from(exact).unwrap_or(u32::MAX),
                "{used} / {limit}"
            );
        }
    }
}
