//! The units the settings name, as the links take them: the persisted process in the unit's
//! terms, and the units started afresh (at the bridge's start and after `CONFIG units`).

use plasma_protocol::time::Instant;

use crate::link::{PowermaxProcess, Units};
use crate::settings::{Process, Settings};

/// The units `settings` name start afresh in `units`, in place, the persisted process
/// restored to the first (`CONFIG units`). Settings that cannot name them were refused when
/// typed; should they get here, the bridge drives one unit rather than none.
pub(crate) fn restart_units(units: &mut Units, settings: &Settings, now: Instant) {
    let process = settings.process.as_ref().map(unit_process);
    let named = settings.units.as_slice();
    if units.rebuild(settings.link, named, process, now).is_err() {
        let _ = units.rebuild(settings.link, &[], process, now);
    }
}

/// A persisted process in the unit's terms (`CPA` and `EXPANDED` are one mode).
pub(crate) fn unit_process(process: &Process) -> PowermaxProcess {
    PowermaxProcess {
        mode: Some(super::unit_mode(process.mode)),
        current: process.amps,
        pressure: process.pressure,
    }
}
