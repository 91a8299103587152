//! What the arbiter needs of a [`PsLink`] that waits for its turn on a shared line. A link
//! alone never calls these: its behaviour is unchanged.

use plasma_protocol::time::Instant;

use crate::link::PsLink;
use crate::link::hpr::HprPurpose;
use crate::link::phase::Phase;
use crate::link::schedule::Tag;

impl PsLink {
    /// True while an attempt of this link is on the wire (its reply, or the quiet after a
    /// request nothing answers, is awaited): the line is this link's.
    pub(super) fn holds_line(&self) -> bool {
        self.txn.as_ref().is_some_and(|txn| txn.is_on_wire())
    }

    /// The frame of the attempt on the wire, as [`PsLink::poll_transmit`] handed it out.
    pub(super) fn frame_on_wire(&self) -> Option<&[u8]> {
        self.txn
            .as_ref()
            .filter(|txn| txn.is_on_wire())
            .map(|txn| txn.frame())
    }

    /// Time passes for a link that waits for its turn or its reply: the reply time-out of an
    /// attempt on the wire is checked, nothing new is started. Waiting for the line is no
    /// silence: only an attempt that went out can time out.
    pub(super) fn handle_time(&mut self, now: Instant) {
        self.now = now;
        self.handle_timeout(now);
        self.core.status.update_ready(now);
    }

    /// The line has been heard echoing this link's requests.
    pub(super) fn hears_line_echo(&self) -> bool {
        self.line_echoes
    }

    /// The line echoes our requests (heard by the arbiter or another unit's link): a reply
    /// that repeats its request is then the second copy from the first attempt on.
    pub(super) fn learn_line_echo(&mut self) {
        self.line_echoes = true;
    }

    /// The link shares its line with other units: its polls favour the short fault read
    /// (the HPR driver's `SHARED_LINE_FULL_POLL_EVERY`), so each unit's turn is short.
    pub(super) fn share_line(&mut self) {
        self.core.shared_line = true;
    }

    /// Whether a long attempt (a full status poll, slow data) may go out in this turn (see
    /// [`PsLink::share_line`]).
    pub(super) fn allow_long(&mut self, allowed: bool) {
        self.core.long_allowed = allowed;
    }

    /// True when this unit's last attempt was an answered poll of an HPR: its next one may be
    /// its slow data, at once in the same turn (no switch, and no second time-out of a unit
    /// that stopped answering).
    pub(super) fn polled_last(&self) -> bool {
        self.txn.is_none()
            && self.consecutive_failures == 0
            && matches!(&self.phase, Phase::Hpr(driver) if driver.polled_last())
    }

    /// The unit's START output is on (`true`) or off: from START on, its state is polled in
    /// full every turn (see [`Core::start_on`](crate::link::core::Core)).
    pub(super) fn follow_start(&mut self, on: bool) {
        self.core.start_on = on;
    }

    /// The end of this unit's HF-ignition quiet (an HPR in pilot arc), if one is under way:
    /// the whole line keeps it, as every unit's traffic crosses the noise.
    pub(super) fn ignition_quiet_until(&self, now: Instant) -> Option<Instant> {
        match &self.phase {
            Phase::Hpr(driver) => driver.quiet_until(now),
            _ => None,
        }
    }

    /// True when the attempt on the wire is a long one: a full status poll (an HPR's 079
    /// GET_PS_INFO) or slow data.
    pub(super) fn long_on_wire(&self) -> bool {
        use HprPurpose::*;
        self.txn.as_ref().is_some_and(|txn| {
            matches!(
                txn.tag(),
                Tag::Hpr(
                    Poll | SlowErrorLog
                        | SlowTimers
                        | SlowGases
                        | SlowInletGases
                        | SlowVersion
                        | SlowTorch,
                    _
                )
            )
        })
    }
}
