//! Which pin level each output drives for "on", as settings: some tables want inverted logic.
//!
//! Only outputs whose ON state is the safe side may be inverted: **PS_HOLD** (the supply holds
//! ignition) and **FAULT** (the CNC stops). The reason is the time no setting can reach: from
//! reset until the I/O task runs, and after a panic or a stalled task, the pins are
//! high-impedance (held by the board's pull-downs) or driven by the register-level safe state,
//! which knows only the pin table ([`pins::SAFE_STATE`]). An inverted
//! output reads ON there. For PS_HOLD and FAULT that is the fail-safe reading; for START it
//! would fire the torch, for ARC_OK it would start motion without an arc, for READY it would
//! report a bridge that is not there, for REMOTE_POWER it would power the unit on. Those keep
//! the table's polarity, always.
//!
//! ```
//! use plasma_firmware::io::{Output, OutputConfig, Outputs, Polarity};
//!
//! let mut config = OutputConfig::default();
//! config.set(Output::Fault, Polarity::ActiveLow).unwrap();
//! assert!(config.set(Output::Start, Polarity::ActiveLow).is_err());
//! // FAULT off: the board, driving from its active-high table, is told "on" (pin high).
//! assert!(config.for_table(Outputs::OFF).fault);
//! ```

use super::input_config::Polarity;
use super::signals::{Output, Outputs};
use crate::platform::pins;

/// An output that must keep the pin table's polarity (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NotInvertible(pub Output);

/// The active level of every output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OutputConfig {
    /// One bit per output ([`bit`]): its level is the opposite of the pin table's.
    inverted: u8,
}

/// An output's bit, in [`Output::ALL`] order.
const fn bit(output: Output) -> u8 {
    1 << match output {
        Output::Start => 0,
        Output::Hold => 1,
        Output::PierceComplete => 2,
        Output::CornerCurrent => 3,
        Output::ArcOk => 4,
        Output::Ready => 5,
        Output::Fault => 6,
        Output::RemotePower => 7,
    }
}

impl OutputConfig {
    /// Whether `output` may be inverted: its ON state is the safe side, so the table's
    /// inactive level at reset and in the safe state showing it ON is fail-safe.
    pub const fn may_invert(output: Output) -> bool {
        matches!(output, Output::Hold | Output::Fault)
    }

    /// The outputs' bits that may be set (for a stored record).
    pub(crate) const INVERTIBLE: u8 = bit(Output::Hold) | bit(Output::Fault);

    /// The active level of `output`.
    pub const fn get(&self, output: Output) -> Polarity {
        let table = pins::output(output).active;
        match (self.inverted & bit(output) != 0, table) {
            (false, table) => table,
            (true, Polarity::ActiveHigh) => Polarity::ActiveLow,
            (true, Polarity::ActiveLow) => Polarity::ActiveHigh,
        }
    }

    /// Make `polarity` the active level of `output`; refused for an output that must keep the
    /// table's (nothing changes then).
    pub fn set(&mut self, output: Output, polarity: Polarity) -> Result<(), NotInvertible> {
        let invert = polarity != pins::output(output).active;
        if invert && !Self::may_invert(output) {
            return Err(NotInvertible(output));
        }
        if invert {
            self.inverted |= bit(output);
        } else {
            self.inverted &= !bit(output);
        }
        Ok(())
    }

    /// The stored form: one bit per inverted output.
    pub(crate) const fn bits(&self) -> u8 {
        self.inverted
    }

    /// From the stored form; `None` if it inverts an output that may not be.
    pub(crate) const fn from_bits(bits: u8) -> Option<Self> {
        if bits & !Self::INVERTIBLE != 0 {
            return None;
        }
        Some(OutputConfig { inverted: bits })
    }

    /// The levels to hand a board that drives its pins from the pin table: each inverted
    /// output flipped, so its pin gets the configured level. Only the invertible ones can be:
    /// START passes untouched.
    pub fn for_table(&self, outputs: Outputs) -> Outputs {
        let flip = |output: Output| self.inverted & bit(output) != 0;
        Outputs {
            hold: outputs.hold ^ flip(Output::Hold),
            fault: outputs.fault ^ flip(Output::Fault),
            ..outputs
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_safe_side_outputs_invert() {
        let mut config = OutputConfig::default();
        for output in Output::ALL {
            assert_eq!(config.get(output), pins::output(output).active, "{output}");
            let inverted = match pins::output(output).active {
                Polarity::ActiveHigh => Polarity::ActiveLow,
                Polarity::ActiveLow => Polarity::ActiveHigh,
            };
            let before = config;
            let result = config.set(output, inverted);
            assert_eq!(result.is_ok(), OutputConfig::may_invert(output), "{output}");
            if result.is_err() {
                assert_eq!(config, before, "a refusal changes nothing");
            } else {
                assert_eq!(config.get(output), inverted);
            }
        }
        assert_eq!(config.bits(), OutputConfig::INVERTIBLE);
        assert_eq!(OutputConfig::from_bits(config.bits()), Some(config));
        assert_eq!(OutputConfig::from_bits(bit(Output::Start)), None);
    }

    #[test]
    fn start_is_never_driven_by_an_inversion() {
        // Whatever is stored and set: START reaches the table as the logic has it.
        for bits in 0..=u8::MAX {
            if let Some(config) = OutputConfig::from_bits(bits) {
                for start in [false, true] {
                    let outputs = Outputs {
                        start,
                        ..Outputs::OFF
                    };
                    assert_eq!(config.for_table(outputs).start, start);
                }
            }
        }
    }

    #[test]
    fn an_inverted_output_reads_on_in_the_safe_state() {
        // The safe state drives the table's inactive level; under an inversion that is ON,
        // which is why only PS_HOLD and FAULT may be inverted.
        let mut config = OutputConfig::default();
        config.set(Output::Fault, Polarity::ActiveLow).unwrap();
        let fault = pins::output(Output::Fault);
        let safe_level = fault.level(false);
        assert!(config.get(Output::Fault).is_active(safe_level));
        // Logical FAULT off drives the pin to the configured inactive level (high).
        let table = config.for_table(Outputs::OFF);
        assert!(fault.level(table.fault));
        assert!(!config.for_table(Outputs::OFF).start);
    }
}
