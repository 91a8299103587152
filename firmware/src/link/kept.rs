//! The one owner of "the process to re-apply": which settings the link applies again, and
//! when.
//!
//! # Why here
//! Only the link sees the moments a re-apply is due: the unit answers again after a link-down,
//! a Powermax reads back other settings while the bridge holds remote control, an HPR shows a
//! restart (the last two, and a return without the kept settings, are the unit's own power
//! cycle: see "Power cycle or lost link"). So the link keeps what it re-applies, for every
//! family, in this one place, and the others hold no decision:
//! - the CNC session submits commands; what the unit confirms the link keeps here;
//! - [`Settings::process`](crate::settings::Settings) is only the persisted copy of the
//!   confirmed Powermax process, so that it survives the bridge's own power cycle;
//! - at start-up the bridge hands that copy to the link ([`PsLink::restore`]); the link
//!   applies it once a Powermax with known limits answers, unless the CNC set a process
//!   first. It is one attempt, like a command: a process outside the unit's limits is
//!   reported ([`LinkEvent::RestoreRefused`]) and dropped, not tried again.
//!
//!
//! # Power cycle or lost link
//! Switching a Powermax off and waiting about a minute is how an operator takes it back from
//! remote control (SYNC manual, "Exit remote control mode"), so the bridge must not take it
//! again on its own after the unit's power cycle; after a lost link (a cable pulled, noise)
//! it re-applies as before. The wire shows the two the same way (silence, then answers), so
//! the unit's first answers after it returns decide:
//! - a Powermax (SYNC or legacy) whose settings (0x3010-0x3012; the legacy force registers
//!   0x2093-0x2096, which read 0 outside remote control) still show the kept ones kept
//!   remote control: the link was lost. Other settings: it was switched off and on (a
//!   Powermax powers up in local control, on its front-panel settings).
//! - an HPR / MaxPro200 in a power-up state (0, MaxPro200 0 and 1) or purging (2, what it
//!   does after power-up), or with another current set point than the kept one, restarted;
//!   one in any other state with the kept set point kept running: the link was lost.
//!
//! The same signs while the link stays up (a power blip shorter than a link-down) count as a
//! power cycle too. Then `Core::unit_power_cycled` tells the CNC
//! ([`LinkEvent::UnitPowerCycled`]), and the kept settings are forgotten (the CNC sets them
//! again when it wants remote control back) unless [`LinkConfig::reapply_after_power_cycle`]
//! is on.
//!
//! Limits: a unit whose front-panel settings happen to equal the kept ones (or an HPR back in
//! state 3 with the same set point) looks like a lost link, and is re-applied; a legacy unit
//! that refuses to read its force registers cannot tell, and is re-applied as after a lost
//! link.
//!
//! [`PsLink::restore`]: crate::link::PsLink::restore
//! [`LinkEvent::RestoreRefused`]: crate::link::LinkEvent::RestoreRefused
//! [`LinkEvent::UnitPowerCycled`]: crate::link::LinkEvent::UnitPowerCycled
//! [`LinkConfig::reapply_after_power_cycle`]: crate::link::LinkConfig::reapply_after_power_cycle

use plasma_protocol::hpr::Request;

use crate::link::hpr::kept::HprKept;
use crate::link::status::PowermaxProcess;

/// The settings the link re-applies. See the module docs.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Kept {
    /// Powermax: the settings the unit confirmed last (`None` after `ExitRemote`).
    powermax: Option<PowermaxProcess>,
    /// Powermax: the persisted process to apply once after the bridge started.
    restore: Option<PowermaxProcess>,
    /// HPR / MaxPro200: the setting requests the unit confirmed.
    pub(crate) hpr: HprKept,
}

/// Which kind of Powermax re-apply is due.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Reapply {
    /// Confirmed settings again, after a link return or a power cycle of the unit.
    Kept(PowermaxProcess),
    /// The persisted process, once after the bridge started.
    Restore(PowermaxProcess),
}

impl Kept {
    /// The Powermax settings the unit confirmed last: re-applied after it returns or
    /// power-cycles.
    pub fn powermax(&self) -> Option<PowermaxProcess> {
        self.powermax
    }

    /// The HPR / MaxPro200 settings the unit confirmed, in the order they are re-applied
    /// (after 004 REMOTE_MODE).
    pub fn hpr_requests(&self) -> &[Request] {
        self.hpr.as_slice()
    }

    /// What a Powermax that just answered gets applied: its confirmed settings, or failing
    /// those the persisted process.
    pub(crate) fn powermax_due(&self) -> Option<Reapply> {
        match (self.powermax, self.restore) {
            (Some(settings), _) => Some(Reapply::Kept(settings)),
            (None, Some(settings)) => Some(Reapply::Restore(settings)),
            (None, None) => None,
        }
    }

    /// Apply `settings` once when a Powermax answers (see the module docs).
    pub(crate) fn restore(&mut self, settings: PowermaxProcess) {
        self.restore = Some(settings);
    }

    /// The restore was started or refused: it is not tried again.
    pub(crate) fn restore_done(&mut self) {
        self.restore = None;
    }

    /// The unit confirmed `settings`: they are what is re-applied from now on (a restore not
    /// yet done is superseded).
    pub(crate) fn confirmed(&mut self, settings: PowermaxProcess) {
        self.powermax = Some(settings);
        self.restore = None;
    }

    /// The unit left remote control: nothing is re-applied.
    pub(crate) fn forget_powermax(&mut self) {
        self.powermax = None;
    }
}
