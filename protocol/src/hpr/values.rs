//! Value types shared by requests and replies. Units are the manual's: amps, percent, psi,
//! tenths of a volt, all as integers.

use super::gas::GasCode;
use crate::powermax::TorchKind;
use crate::{Error, Result};

/// Check an inclusive range (used on both emit and parse so that the two agree).
pub(crate) fn in_range(value: u32, min: u32, max: u32) -> Result<u32> {
    if (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(Error::Malformed)
    }
}

/// Plasma and shield gas type codes (096, 098, 122, and part of 095/137).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GasPair {
    /// Plasma gas type code (table VI).
    pub plasma: GasCode,
    /// Shield gas type code (table VI).
    pub shield: GasCode,
}

/// HPR gas pressure setpoints in psi (078 SET_ALL_GAS_FLOWS, 099 GET_GAS_FLOWS, part of 095).
///
/// The four flows are 0-99 psi and the two mix setpoints 0-100 psi. The mix setpoints only
/// apply to mixed plasma gases (H35-N2); 0 closes the mixing valves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GasFlows {
    /// Plasma cutflow setpoint, psi.
    pub plasma_cutflow: u16,
    /// Plasma preflow setpoint, psi.
    pub plasma_preflow: u16,
    /// Shield cutflow setpoint, psi.
    pub shield_cutflow: u16,
    /// Shield preflow setpoint, psi.
    pub shield_preflow: u16,
    /// N2 mix setpoint, psi.
    pub n2_mix: u16,
    /// Gas 2 mix setpoint, psi.
    pub gas2_mix: u16,
}

/// Largest flow setpoint the manual allows (psi).
pub const MAX_FLOW_PSI: u16 = 99;
/// Largest mix setpoint the manual allows (psi).
pub const MAX_MIX_PSI: u16 = 100;

impl GasFlows {
    /// The six values in wire order.
    pub const fn to_array(&self) -> [u16; 6] {
        [
            self.plasma_cutflow,
            self.plasma_preflow,
            self.shield_cutflow,
            self.shield_preflow,
            self.n2_mix,
            self.gas2_mix,
        ]
    }

    /// From the six values in wire order.
    pub const fn from_array(v: [u16; 6]) -> Self {
        let [
            plasma_cutflow,
            plasma_preflow,
            shield_cutflow,
            shield_preflow,
            n2_mix,
            gas2_mix,
        ] = v;
        GasFlows {
            plasma_cutflow,
            plasma_preflow,
            shield_cutflow,
            shield_preflow,
            n2_mix,
            gas2_mix,
        }
    }

    /// Manual limit of the value at wire position `i`.
    pub const fn limit(i: usize) -> u16 {
        if i < 4 { MAX_FLOW_PSI } else { MAX_MIX_PSI }
    }
}

/// Measured HPR gas pressures in psi (094 READ_GAS_PRESSURES, part of the HPR 079 reply).
///
/// Cut gas 1/2 and the two mix inlets are not measured with a manual gas console.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GasPressures {
    /// Plasma cutflow pressure (`PC`).
    pub plasma_cutflow: u16,
    /// Plasma preflow pressure (`PP`).
    pub plasma_preflow: u16,
    /// Shield cutflow pressure (`SC`).
    pub shield_cutflow: u16,
    /// Shield preflow pressure (`SP`).
    pub shield_preflow: u16,
    /// Cut gas 1 pressure (first `CG`).
    pub cut_gas_1: u16,
    /// Cut gas 2 pressure (second `CG`).
    pub cut_gas_2: u16,
    /// N2 mix inlet pressure (first `MV`).
    pub n2_mix_inlet: u16,
    /// Gas 2 mix inlet pressure (second `MV`).
    pub gas2_mix_inlet: u16,
}

/// HPR parameters of 095 SET_ALL_PARAMETERS.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HprParameters {
    /// Current setpoint, amps (5-400; the model limits it to 130/260/400).
    pub amps: u16,
    /// Corner current, percent of cutting current (50-100).
    pub corner_percent: u8,
    /// Plasma and shield gas types.
    pub gases: GasPair,
    /// Pressure setpoints.
    pub flows: GasFlows,
}

/// MaxPro200 parameters of 095 SET_ALL_PARAMETERS (the manual recommends 137 instead).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MaxProParameters {
    /// Current setpoint, amps (0-200).
    pub amps: u16,
    /// Plasma and shield gas types.
    pub gases: GasPair,
    /// Plasma and shield pressure setpoints.
    pub pressures: MaxProPressures,
}

/// MaxPro200 pressure setpoints in psi, 0-99 (078, part of 095).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MaxProPressures {
    /// Plasma pressure setpoint, psi.
    pub plasma: u16,
    /// Shield pressure setpoint, psi.
    pub shield: u16,
}

/// 121 LEAK_CHECK_MODE modes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LeakCheckMode {
    /// 0: back to normal operation (required after a test).
    Run,
    /// 1: inlet leak check.
    InletLeak,
    /// 2: system leak check.
    SystemLeak,
    /// 3: Burkert valve flow check (automatic gas consoles only).
    BurkertFlow,
}

impl LeakCheckMode {
    /// Wire value.
    pub const fn code(self) -> u8 {
        match self {
            LeakCheckMode::Run => 0,
            LeakCheckMode::InletLeak => 1,
            LeakCheckMode::SystemLeak => 2,
            LeakCheckMode::BurkertFlow => 3,
        }
    }

    /// From the wire value.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(LeakCheckMode::Run),
            1 => Some(LeakCheckMode::InletLeak),
            2 => Some(LeakCheckMode::SystemLeak),
            3 => Some(LeakCheckMode::BurkertFlow),
            _ => None,
        }
    }
}

/// 143 SET TEST MODE modes (MaxPro200, accepted in state 3 only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TestMode {
    /// 0: no test; gases stop flowing.
    None,
    /// 1: test gas, plasma and shield flow at set value.
    TestGas,
    /// 2: local display shows the software revision.
    ShowSoftwareRevision,
    /// 3: plasma leak check.
    PlasmaLeakCheck,
    /// 4: test gas at full pressure.
    TestGasFullPressure,
    /// 5: local display shows the torch id.
    ShowTorchId,
    /// 6: in-line valve test.
    InlineValveTest,
}

impl TestMode {
    /// Wire value.
    pub const fn code(self) -> u8 {
        match self {
            TestMode::None => 0,
            TestMode::TestGas => 1,
            TestMode::ShowSoftwareRevision => 2,
            TestMode::PlasmaLeakCheck => 3,
            TestMode::TestGasFullPressure => 4,
            TestMode::ShowTorchId => 5,
            TestMode::InlineValveTest => 6,
        }
    }

    /// From the wire value.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(TestMode::None),
            1 => Some(TestMode::TestGas),
            2 => Some(TestMode::ShowSoftwareRevision),
            3 => Some(TestMode::PlasmaLeakCheck),
            4 => Some(TestMode::TestGasFullPressure),
            5 => Some(TestMode::ShowTorchId),
            6 => Some(TestMode::InlineValveTest),
            _ => None,
        }
    }
}

/// Torch id of 145 READ TORCH ID (MaxPro200).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TorchId(pub u16);

/// The 145 table: torch id and meaning.
pub const TORCH_IDS: &[(u16, &str)] = &[
    (0, "No jumper detected"),
    (1, "100 Ft mechanized torch"),
    (2, "25 Ft mechanized torch"),
    (3, "75 Ft mechanized torch"),
    (4, "100 Ft hand torch"),
    (5, "reserved"),
    (6, "50 Ft mechanized torch"),
    (7, "reserved"),
    (8, "25 Ft hand torch"),
    (9, "50 Ft hand torch"),
    (10, "reserved"),
    (11, "reserved"),
    (12, "75 Ft hand torch"),
];

impl TorchId {
    /// Meaning from the manual's table.
    pub fn description(self) -> Option<&'static str> {
        TORCH_IDS.get(usize::from(self.0)).map(|&(_, d)| d)
    }

    /// The torch the id names: hand or mechanized, and its lead in feet (the table's "25 Ft
    /// mechanized torch"); `None` for 0 "No jumper detected", the reserved ids and ids past
    /// the table.
    pub const fn torch(self) -> Option<(TorchKind, u16)> {
        use TorchKind::{Hand, Machine};
        Some(match self.0 {
            1 => (Machine, 100),
            2 => (Machine, 25),
            3 => (Machine, 75),
            4 => (Hand, 100),
            6 => (Machine, 50),
            8 => (Hand, 25),
            9 => (Hand, 50),
            12 => (Hand, 75),
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_round_trip() {
        for c in 0..=3 {
            assert_eq!(
                LeakCheckMode::from_code(c).map(LeakCheckMode::code),
                Some(c)
            );
        }
        assert_eq!(LeakCheckMode::from_code(4), None);
        for c in 0..=6 {
            assert_eq!(TestMode::from_code(c).map(TestMode::code), Some(c));
        }
        assert_eq!(TestMode::from_code(7), None);
        assert!(
            TORCH_IDS
                .iter()
                .enumerate()
                .all(|(i, &(id, _))| usize::from(id) == i)
        );
        assert_eq!(TorchId(2).description(), Some("25 Ft mechanized torch"));
        assert_eq!(TorchId(13).description(), None);
        // `torch` says what the table's text says, row by row.
        for &(id, text) in TORCH_IDS {
            let torch = TorchId(id).torch();
            let feet = text.split(' ').next().and_then(|n| n.parse::<u16>().ok());
            assert_eq!(torch.map(|(_, f)| f), feet, "{text}");
            if let Some((kind, _)) = torch {
                assert_eq!(
                    kind == TorchKind::Hand,
                    text.ends_with("hand torch"),
                    "{text}"
                );
                assert_eq!(
                    kind == TorchKind::Machine,
                    text.ends_with("mechanized torch")
                );
            }
        }
        assert_eq!(TorchId(2).torch(), Some((TorchKind::Machine, 25)));
        assert_eq!(TorchId(13).torch(), None);
        let f = GasFlows::from_array([1, 2, 3, 4, 5, 6]);
        assert_eq!(f.to_array(), [1, 2, 3, 4, 5, 6]);
        assert_eq!(in_range(5, 5, 400), Ok(5));
        assert_eq!(in_range(4, 5, 400), Err(Error::Malformed));
    }
}
