//! The CNC's wiring as `CONFIG` keys and as part of the stored record: every input's active
//! level and debounce, and the outputs a table may invert (see
//! [`OutputConfig`] for why only PS_HOLD and FAULT).
//!
//! Levels are the level at the bridge's pin: `LOW` is the reference board's default for the
//! inputs (the opto-coupler conducts when the signal is on) and `HIGH` for the outputs.

use plasma_protocol::cnc::ConfigKey;
use plasma_protocol::time::Duration;

use super::{Accepted, ConfigValue, SetError, parse_number};
use crate::io::{Input, InputConfig, IoConfig, MAX_DEBOUNCE, Output, OutputConfig, Polarity};

/// What a wiring key sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Wire {
    /// An input's active level.
    Active(Input),
    /// An input's debounce, ms.
    DebounceMs(Input),
    /// An output's active level.
    OutputActive(Output),
}

/// Every wiring key and what it sets: the one table the getter, the setter and the tests read.
const KEYS: [(ConfigKey, Wire); 18] = [
    (ConfigKey::TorchOnActive, Wire::Active(Input::TorchOn)),
    (
        ConfigKey::TorchOnDebounceMs,
        Wire::DebounceMs(Input::TorchOn),
    ),
    (ConfigKey::HoldActive, Wire::Active(Input::Hold)),
    (ConfigKey::HoldDebounceMs, Wire::DebounceMs(Input::Hold)),
    (
        ConfigKey::PierceCompleteActive,
        Wire::Active(Input::PierceComplete),
    ),
    (
        ConfigKey::PierceCompleteDebounceMs,
        Wire::DebounceMs(Input::PierceComplete),
    ),
    (
        ConfigKey::CornerCurrentActive,
        Wire::Active(Input::CornerCurrent),
    ),
    (
        ConfigKey::CornerCurrentDebounceMs,
        Wire::DebounceMs(Input::CornerCurrent),
    ),
    (ConfigKey::MotionActive, Wire::Active(Input::Motion)),
    (ConfigKey::MotionDebounceMs, Wire::DebounceMs(Input::Motion)),
    (ConfigKey::NotReadyActive, Wire::Active(Input::NotReady)),
    (
        ConfigKey::NotReadyDebounceMs,
        Wire::DebounceMs(Input::NotReady),
    ),
    (
        ConfigKey::RampdownErrorActive,
        Wire::Active(Input::RampdownError),
    ),
    (
        ConfigKey::RampdownErrorDebounceMs,
        Wire::DebounceMs(Input::RampdownError),
    ),
    (
        ConfigKey::SystemErrorActive,
        Wire::Active(Input::SystemError),
    ),
    (
        ConfigKey::SystemErrorDebounceMs,
        Wire::DebounceMs(Input::SystemError),
    ),
    (ConfigKey::PsHoldActive, Wire::OutputActive(Output::Hold)),
    (ConfigKey::FaultActive, Wire::OutputActive(Output::Fault)),
];

const LEVELS: &str = "HIGH|LOW";

fn wire(key: ConfigKey) -> Option<Wire> {
    KEYS.iter().find(|(k, _)| *k == key).map(|&(_, w)| w)
}

fn level_word(polarity: Polarity) -> ConfigValue {
    ConfigValue::Word(match polarity {
        Polarity::ActiveHigh => "HIGH",
        Polarity::ActiveLow => "LOW",
    })
}

/// The accepted debounce, ms.
pub(super) fn debounce_range() -> (u32, u32) {
    (
        0,
        u32::try_from(MAX_DEBOUNCE.as_millis()).unwrap_or(u32::MAX),
    )
}

/// The value of a wiring key (`None`: not one).
pub(super) fn get(io: &IoConfig, key: ConfigKey) -> Option<ConfigValue> {
    Some(match wire(key)? {
        Wire::Active(input) => level_word(io.inputs.get(input).polarity),
        Wire::DebounceMs(input) => ConfigValue::Number(
            u32::try_from(io.inputs.get(input).debounce.as_millis()).unwrap_or(u32::MAX),
        ),
        Wire::OutputActive(output) => level_word(io.outputs.get(output)),
    })
}

/// What a wiring key accepts (`None`: not one).
pub(super) fn accepted(key: ConfigKey) -> Option<Accepted> {
    Some(match wire(key)? {
        Wire::Active(_) | Wire::OutputActive(_) => Accepted::Words(LEVELS),
        Wire::DebounceMs(_) => {
            let (min, max) = debounce_range();
            Accepted::Range(min, max)
        }
    })
}

/// Set a wiring key (`None`: not one). Nothing changes when the value is refused.
pub(super) fn set<'a>(
    io: &mut IoConfig,
    key: ConfigKey,
    text: &'a str,
) -> Option<Result<(), SetError<'a>>> {
    let level = || {
        if text.eq_ignore_ascii_case("HIGH") {
            Ok(Polarity::ActiveHigh)
        } else if text.eq_ignore_ascii_case("LOW") {
            Ok(Polarity::ActiveLow)
        } else {
            Err(SetError::BadWord {
                key,
                expected: LEVELS,
            })
        }
    };
    Some(match wire(key)? {
        Wire::Active(input) => level().map(|p| io.inputs.set_polarity(input, p)),
        Wire::DebounceMs(input) => parse_number(key, text, debounce_range()).map(|v| {
            io.inputs
                .set_debounce(input, Duration::from_millis(u64::from(v)))
        }),
        // Only invertible outputs have a key, so the refusal cannot happen; keep it honest.
        Wire::OutputActive(output) => level().and_then(|p| {
            io.outputs.set(output, p).map_err(|_| SetError::BadWord {
                key,
                expected: "HIGH",
            })
        }),
    })
}

/// Bytes of the wiring in the record from version 2: input active-high bits (SYSTEM_ERROR's
/// is bit 7, unused before version 3), the first seven inputs' debounce times (ms),
/// inverted-output bits.
pub(super) const RECORD_LEN: usize = 9;
/// Bytes of the wiring appended in version 3: SYSTEM_ERROR's debounce time (ms).
pub(super) const TAIL_LEN: usize = 1;
/// The tail of a record older than version 3: the reference board's debounce.
pub(super) const DEFAULT_TAIL: [u8; TAIL_LEN] = {
    let (_, debounce) = InputConfig::REFERENCE.to_stored();
    [debounce[7]]
};

/// The wiring's part of the record and its version-3 tail.
pub(super) fn encode(io: &IoConfig) -> ([u8; RECORD_LEN], [u8; TAIL_LEN]) {
    let (high, [a, b, c, d, e, f, g, system_error]) = io.inputs.to_stored();
    (
        [high, a, b, c, d, e, f, g, io.outputs.bits()],
        [system_error],
    )
}

/// The wiring from its part of the record and its tail; `None` if a bit or a time is out of
/// range.
pub(super) fn decode(
    bytes: &[u8; RECORD_LEN],
    tail: [u8; TAIL_LEN],
) -> Option<(InputConfig, OutputConfig)> {
    let [high, a, b, c, d, e, f, g, outputs] = *bytes;
    let [system_error] = tail;
    Some((
        InputConfig::from_stored(high, [a, b, c, d, e, f, g, system_error])?,
        OutputConfig::from_bits(outputs)?,
    ))
}

/// The wiring of a version-2 record: SYSTEM_ERROR at the reference board's settings. Its
/// active-high bit was unused then, so a record that sets it is not one version 2 wrote.
pub(super) fn decode_v2(bytes: &[u8; RECORD_LEN]) -> Option<(InputConfig, OutputConfig)> {
    let [high, ..] = *bytes;
    if high & 1 << 7 != 0 {
        return None;
    }
    decode(bytes, DEFAULT_TAIL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_wiring_key_is_in_the_table_once() {
        let named: Vec<ConfigKey> = ConfigKey::ALL
            .into_iter()
            .filter(|k| k.name().ends_with("_active") || k.name().ends_with("_debounce_ms"))
            .filter(|&k| k != ConfigKey::ArcOkDebounceMs)
            .collect();
        assert_eq!(named, KEYS.map(|(k, _)| k));
        for input in Input::ALL {
            assert!(KEYS.contains(&(
                ConfigKey::from_name(&format!("{}_active", input.as_str().to_lowercase())).unwrap(),
                Wire::Active(input)
            )));
        }
        for output in Output::ALL {
            let has_key = KEYS.iter().any(|(_, w)| *w == Wire::OutputActive(output));
            assert_eq!(has_key, OutputConfig::may_invert(output), "{output}");
        }
    }

    #[test]
    fn wiring_bytes_round_trip_and_decode_strictly() {
        let mut io = IoConfig::default();
        for (key, value) in [
            (ConfigKey::TorchOnActive, "high"),
            (ConfigKey::TorchOnDebounceMs, "7"),
            (ConfigKey::RampdownErrorActive, "HIGH"),
            (ConfigKey::MotionDebounceMs, "100"),
            (ConfigKey::FaultActive, "low"),
        ] {
            set(&mut io, key, value).unwrap().unwrap();
        }
        set(&mut io, ConfigKey::SystemErrorActive, "HIGH")
            .unwrap()
            .unwrap();
        set(&mut io, ConfigKey::SystemErrorDebounceMs, "20")
            .unwrap()
            .unwrap();
        let (bytes, tail) = encode(&io);
        assert_eq!(tail, [20]);
        assert_eq!(decode(&bytes, tail), Some((io.inputs, io.outputs)));
        assert_eq!(
            decode_v2(&bytes),
            None,
            "SYSTEM_ERROR's bit in a version-2 record"
        );
        assert_eq!(
            get(&io, ConfigKey::TorchOnActive),
            Some(ConfigValue::Word("HIGH"))
        );
        assert_eq!(
            get(&io, ConfigKey::PsHoldActive),
            Some(ConfigValue::Word("HIGH"))
        );
        assert_eq!(
            get(&io, ConfigKey::FaultActive),
            Some(ConfigValue::Word("LOW"))
        );
        assert_eq!(get(&io, ConfigKey::Events), None);
        let corrupt = |i: usize, v: u8| {
            let mut b = bytes;
            b[i] = v;
            decode(&b, tail)
        };
        assert_eq!(
            decode(&bytes, [101]),
            None,
            "SYSTEM_ERROR debounce above 100 ms"
        );
        assert_eq!(corrupt(3, 101), None, "debounce above 100 ms");
        assert_eq!(corrupt(8, 1), None, "START inverted");
    }

    #[test]
    fn refused_values_change_nothing() {
        let mut io = IoConfig::default();
        let before = io;
        assert!(set(&mut io, ConfigKey::HoldActive, "up").unwrap().is_err());
        assert!(
            set(&mut io, ConfigKey::HoldDebounceMs, "101")
                .unwrap()
                .is_err()
        );
        assert!(set(&mut io, ConfigKey::FaultActive, "1").unwrap().is_err());
        assert_eq!(io, before);
        assert_eq!(set(&mut io, ConfigKey::Events, "on"), None);
    }
}
