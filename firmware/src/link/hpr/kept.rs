//! The HPR / MaxPro200 settings to keep and re-apply, and which earlier setting a new one
//! replaces.

use heapless::Vec;
use plasma_protocol::hpr::{Request, SystemId};

/// Kept settings requests (one per kind at most: see [`HprKept::keep`]).
pub(crate) const KEPT_CAPACITY: usize = 6;

/// What a settings request sets (bits), to tell which earlier requests a new one replaces.
const SETS_AMPS: u8 = 1;
const SETS_CORNER: u8 = 2;
const SETS_GASES: u8 = 4;
const SETS_PRESSURES: u8 = 8;

/// What `request` sets; 0 for a request that is no setting.
pub(super) fn sets(request: &Request) -> u8 {
    match request {
        Request::SetNominalAmps { .. } => SETS_AMPS,
        Request::SetCornerCurrent { .. } => SETS_CORNER,
        Request::SetInletGases(_) => SETS_GASES,
        // 137: "the plasma system will automatically set all system parameters, including the
        // gas pressures" (HPR manual line 275).
        Request::SetProcess { .. } | Request::SetAllParametersMaxPro200(_) => {
            SETS_AMPS | SETS_GASES | SETS_PRESSURES
        }
        Request::SetAllParameters(_) => SETS_AMPS | SETS_CORNER | SETS_GASES | SETS_PRESSURES,
        Request::SetAllGasFlows(_) | Request::SetAllGasFlowsMaxPro200(_) => SETS_PRESSURES,
        _ => 0,
    }
}

/// The nominal current `request` sets, if it sets one.
fn amps_of(request: &Request) -> Option<u16> {
    match request {
        Request::SetNominalAmps { amps } | Request::SetProcess { amps, .. } => Some(*amps),
        Request::SetAllParameters(p) => Some(p.amps),
        Request::SetAllParametersMaxPro200(p) => Some(p.amps),
        _ => None,
    }
}

/// The HPR / MaxPro200 settings the CNC asked for and the unit confirmed, oldest first. They
/// are kept across link-downs and re-applied (after 004 REMOTE_MODE) when the unit returns or
/// shows that it restarted, like the Powermax settings.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct HprKept {
    requests: Vec<Request, KEPT_CAPACITY>,
    /// The unit that confirmed them (another unit does not get them).
    system: Option<SystemId>,
}

impl HprKept {
    /// The kept requests, in the order they are re-applied.
    pub(crate) fn as_slice(&self) -> &[Request] {
        &self.requests
    }

    /// True when nothing is kept.
    pub(crate) fn is_empty(&self) -> bool {
        self.requests.is_empty()
    }

    /// The unit that confirmed the kept settings.
    pub(crate) fn system(&self) -> Option<SystemId> {
        self.system
    }

    /// Keep `request` (a setting `system` confirmed); earlier requests whose every setting
    /// it sets again are dropped, and so is everything another unit confirmed.
    pub(crate) fn keep(&mut self, system: SystemId, request: Request) {
        let new = sets(&request);
        if new == 0 {
            return;
        }
        if self.system != Some(system) {
            self.clear();
            self.system = Some(system);
        }
        self.requests.retain(|old| sets(old) & !new != 0);
        if self.requests.is_full() {
            // Drop the oldest. Rebuilt rather than `Vec::remove`, whose overlapping move is
            // the image's only other use of memmove (1.5 KB of flash), and pushed rather than
            // collected (`collect` carries a capacity panic that cannot happen here).
            let mut newer = Vec::new();
            for request in self.requests.iter().skip(1) {
                let _ = newer.push(*request);
            }
            self.requests = newer;
        }
        let _ = self.requests.push(request);
    }

    /// Forget everything kept.
    pub(crate) fn clear(&mut self) {
        self.requests.clear();
        self.system = None;
    }

    /// The nominal current the kept settings give, if they set one.
    pub(crate) fn amps(&self) -> Option<u16> {
        self.requests.iter().rev().find_map(amps_of)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use plasma_protocol::hpr::{self, GasCode, GasPair};

    const SYSTEM: SystemId = SystemId::MaxPro200;

    #[test]
    fn a_kept_setting_replaces_the_earlier_ones_it_sets_again() {
        let mut kept = HprKept::default();
        let gases = GasPair {
            plasma: GasCode(1),
            shield: GasCode(2),
        };
        kept.keep(SYSTEM, Request::SetNominalAmps { amps: 130 });
        kept.keep(SYSTEM, Request::SetCornerCurrent { percent: 70 });
        kept.keep(SYSTEM, Request::SetInletGases(gases));
        kept.keep(SYSTEM, Request::SetNominalAmps { amps: 200 });
        assert_eq!(
            kept.as_slice(),
            [
                Request::SetCornerCurrent { percent: 70 },
                Request::SetInletGases(gases),
                Request::SetNominalAmps { amps: 200 },
            ]
        );
        assert_eq!(kept.amps(), Some(200));
        // A process sets the current and the gases: it replaces both, not the corner current.
        let process = Request::SetProcess { amps: 150, gases };
        kept.keep(SYSTEM, process);
        assert_eq!(
            kept.as_slice(),
            [Request::SetCornerCurrent { percent: 70 }, process]
        );
        kept.keep(SYSTEM, Request::SetCornerCurrent { percent: 60 });
        assert_eq!(
            kept.as_slice(),
            [process, Request::SetCornerCurrent { percent: 60 }]
        );
        assert_eq!(kept.amps(), Some(150));
        // 078 sets the pressures only; a later 137 sets them too ("including the gas
        // pressures", HPR manual (002_72b43a5685974c77.txt) line 275) and replaces it.
        let flows = Request::SetAllGasFlowsMaxPro200(hpr::MaxProPressures {
            plasma: 50,
            shield: 58,
        });
        kept.keep(SYSTEM, flows);
        assert_eq!(
            kept.as_slice(),
            [process, Request::SetCornerCurrent { percent: 60 }, flows]
        );
        kept.keep(SYSTEM, process);
        assert_eq!(
            kept.as_slice(),
            [Request::SetCornerCurrent { percent: 60 }, process]
        );
        // 095 sets everything 137 and 078 set, and its current is the kept one.
        let all = Request::SetAllParametersMaxPro200(hpr::MaxProParameters {
            amps: 120,
            gases,
            pressures: hpr::MaxProPressures {
                plasma: 50,
                shield: 58,
            },
        });
        kept.keep(SYSTEM, flows);
        kept.keep(SYSTEM, all);
        assert_eq!(
            kept.as_slice(),
            [Request::SetCornerCurrent { percent: 60 }, all]
        );
        assert_eq!(kept.amps(), Some(120));
        kept.keep(SYSTEM, process);
        // Not settings: not kept.
        kept.keep(SYSTEM, Request::ClearWarnings);
        assert_eq!(kept.as_slice().len(), 2);
        // Settings another unit confirmed replace everything.
        let hpr130 = SystemId::Hpr {
            rating: hpr::HprRating::Hpr130,
            console: Some(hpr::GasConsole::Auto),
            xd: false,
        };
        kept.keep(hpr130, Request::SetNominalAmps { amps: 100 });
        assert_eq!(kept.as_slice(), [Request::SetNominalAmps { amps: 100 }]);
        assert_eq!(kept.system(), Some(hpr130));
    }
}
