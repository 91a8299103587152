//! The CNC text commands: one line in, one typed [`Command`] out.

use super::clock::{CLOCK_FORM, WallClock};
use super::error::ParseError;
use crate::hpr::{GasFlows, MAX_FLOW_PSI, MAX_MIX_PSI, MaxProPressures};
use crate::units::{self, Amps, Pressure, Psi, Rounding};

/// Lowest current any supported supply accepts (HPR: 5 A).
pub const AMPS_MIN: Amps = Amps::from_raw(5 * Amps::STEPS_PER_UNIT);
/// Highest current any supported supply accepts (HPR400: 400 A).
pub const AMPS_MAX: Amps = Amps::from_raw(400 * Amps::STEPS_PER_UNIT);
/// [`AMPS_MIN`]..[`AMPS_MAX`] as written in an error reply.
pub const AMPS_RANGE_TEXT: &str = "5..400";
/// The current argument's name in a [`ParseError`] (`what`), so a caller that knows the
/// unit's own range can tell this refusal apart and quote that range instead.
pub const AMPS_ARGUMENT: &str = "amps";

/// Lowest explicit pressure (0 means automatic on a Powermax: write `AUTO`).
pub const PSI_MIN: Psi = Psi::from_raw(Psi::STEPS_PER_UNIT);
/// Highest pressure accepted (above any supported supply's setpoint range).
pub const PSI_MAX: Psi = Psi::from_raw(150 * Psi::STEPS_PER_UNIT);
/// [`PSI_MIN`]..[`PSI_MAX`] as written in an error reply.
pub const PSI_RANGE_TEXT: &str = "1..150";

/// Power supply operating mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// Normal cutting.
    Cut,
    /// Continuous pilot arc (cutting expanded or perforated metal on supplies that call it so).
    Cpa,
    /// Expanded-metal mode.
    Expanded,
    /// Gouging.
    Gouge,
}

impl Mode {
    /// Every mode.
    pub const ALL: [Mode; 4] = [Mode::Cut, Mode::Cpa, Mode::Expanded, Mode::Gouge];
    /// The accepted words, as written in an error reply.
    pub const EXPECTED: &'static str = "CUT|CPA|EXPANDED|GOUGE";

    /// The word used in commands and replies.
    pub const fn name(self) -> &'static str {
        match self {
            Mode::Cut => "CUT",
            Mode::Cpa => "CPA",
            Mode::Expanded => "EXPANDED",
            Mode::Gouge => "GOUGE",
        }
    }

    /// The mode for a word, case-insensitive. No aliases: one word per mode.
    pub fn from_name(word: &str) -> Option<Mode> {
        Mode::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(word))
    }
}

/// Inlet gases of HPR / MaxPro200 supplies: the CNC-selectable entries of the HPR manual's
/// table VI (gas type codes). Codes 0 (no gas) and 9, 10, 12 (internal marking modes, "not
/// used by CNC") are left out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Gas {
    /// Oxygen, code 1.
    O2,
    /// Methane, code 2.
    Ch4,
    /// Argon-hydrogen, code 3.
    H35,
    /// H5, code 4.
    H5,
    /// Air, code 5.
    Air,
    /// Nitrogen, code 6.
    N2,
    /// Argon, code 7.
    Ar,
    /// N95, code 8.
    N95,
    /// F5, code 11.
    F5,
}

impl Gas {
    /// Every gas.
    pub const ALL: [Gas; 9] = [
        Gas::O2,
        Gas::Ch4,
        Gas::H35,
        Gas::H5,
        Gas::Air,
        Gas::N2,
        Gas::Ar,
        Gas::N95,
        Gas::F5,
    ];
    /// The accepted words, as written in an error reply.
    pub const EXPECTED: &'static str = "O2|CH4|H35|H5|AIR|N2|AR|N95|F5";

    /// The word used in commands and replies.
    pub const fn name(self) -> &'static str {
        match self {
            Gas::O2 => "O2",
            Gas::Ch4 => "CH4",
            Gas::H35 => "H35",
            Gas::H5 => "H5",
            Gas::Air => "AIR",
            Gas::N2 => "N2",
            Gas::Ar => "AR",
            Gas::N95 => "N95",
            Gas::F5 => "F5",
        }
    }

    /// The HPR gas type code (table VI).
    pub const fn hpr_code(self) -> u8 {
        match self {
            Gas::O2 => 1,
            Gas::Ch4 => 2,
            Gas::H35 => 3,
            Gas::H5 => 4,
            Gas::Air => 5,
            Gas::N2 => 6,
            Gas::Ar => 7,
            Gas::N95 => 8,
            Gas::F5 => 11,
        }
    }

    /// The gas for an HPR gas type code (`None` for 0, 9, 10, 12 and unknown codes).
    pub fn from_hpr_code(code: u8) -> Option<Gas> {
        Gas::ALL.into_iter().find(|g| g.hpr_code() == code)
    }

    /// The gas for a word, case-insensitive.
    pub fn from_name(word: &str) -> Option<Gas> {
        Gas::ALL
            .into_iter()
            .find(|g| g.name().eq_ignore_ascii_case(word))
    }
}

/// The HPR's two gas flow tests (HPR manual commands 064/065 and 066/067).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GasFlow {
    /// Preflow gases (064 start, 065 stop).
    Preflow,
    /// Cutflow gases (066 start, 067 stop).
    Cutflow,
}

impl GasFlow {
    /// The word after `GASTEST`, as in replies.
    pub const fn name(self) -> &'static str {
        match self {
            GasFlow::Preflow => GASTEST_WORDS[2],
            GasFlow::Cutflow => GASTEST_WORDS[3],
        }
    }
}

/// A setting of the bridge, read and written with `CONFIG`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[allow(missing_docs)] // each variant is documented by its `name()`
pub enum ConfigKey {
    Protocol,
    Address,
    Parity,
    StopBits,
    TimeoutMs,
    Retries,
    PollMs,
    ReapplyAfterPowerCycle,
    InterlockFault,
    InterlockLink,
    InterlockReady,
    ArcOkDebounceMs,
    TransferTimeoutMs,
    TransferTimeoutDropsStart,
    Events,
    HprId,
    PhoenixFormat,
    // The CNC's wiring: every input's active level and debounce, the invertible outputs.
    TorchOnActive,
    TorchOnDebounceMs,
    HoldActive,
    HoldDebounceMs,
    PierceCompleteActive,
    PierceCompleteDebounceMs,
    CornerCurrentActive,
    CornerCurrentDebounceMs,
    MotionActive,
    MotionDebounceMs,
    NotReadyActive,
    NotReadyDebounceMs,
    RampdownErrorActive,
    RampdownErrorDebounceMs,
    SystemErrorActive,
    SystemErrorDebounceMs,
    PsHoldActive,
    FaultActive,
    // The CNC port: node address and framing (as a Powermax, and for the text protocol).
    CncAddress,
    CncBaud,
    CncParity,
    CncStopBits,
    CncDataBits,
    // Consumable life: the limits of one set (OFF or a number).
    ConsumableStartLimit,
    ConsumableArcLimitS,
    // The units on the power-supply line.
    Units,
}

impl ConfigKey {
    /// Every key, in the order `CONFIG` lists them.
    pub const ALL: [ConfigKey; 43] = [
        ConfigKey::Protocol,
        ConfigKey::Address,
        ConfigKey::Parity,
        ConfigKey::StopBits,
        ConfigKey::TimeoutMs,
        ConfigKey::Retries,
        ConfigKey::PollMs,
        ConfigKey::ReapplyAfterPowerCycle,
        ConfigKey::InterlockFault,
        ConfigKey::InterlockLink,
        ConfigKey::InterlockReady,
        ConfigKey::ArcOkDebounceMs,
        ConfigKey::TransferTimeoutMs,
        ConfigKey::TransferTimeoutDropsStart,
        ConfigKey::Events,
        ConfigKey::HprId,
        ConfigKey::PhoenixFormat,
        ConfigKey::TorchOnActive,
        ConfigKey::TorchOnDebounceMs,
        ConfigKey::HoldActive,
        ConfigKey::HoldDebounceMs,
        ConfigKey::PierceCompleteActive,
        ConfigKey::PierceCompleteDebounceMs,
        ConfigKey::CornerCurrentActive,
        ConfigKey::CornerCurrentDebounceMs,
        ConfigKey::MotionActive,
        ConfigKey::MotionDebounceMs,
        ConfigKey::NotReadyActive,
        ConfigKey::NotReadyDebounceMs,
        ConfigKey::RampdownErrorActive,
        ConfigKey::RampdownErrorDebounceMs,
        ConfigKey::SystemErrorActive,
        ConfigKey::SystemErrorDebounceMs,
        ConfigKey::PsHoldActive,
        ConfigKey::FaultActive,
        ConfigKey::CncAddress,
        ConfigKey::CncBaud,
        ConfigKey::CncParity,
        ConfigKey::CncStopBits,
        ConfigKey::CncDataBits,
        ConfigKey::ConsumableStartLimit,
        ConfigKey::ConsumableArcLimitS,
        ConfigKey::Units,
    ];

    /// The key as written in commands and replies (lower case, `snake_case`).
    pub const fn name(self) -> &'static str {
        match self {
            ConfigKey::Protocol => "protocol",
            ConfigKey::Address => "address",
            ConfigKey::Parity => "parity",
            ConfigKey::StopBits => "stop_bits",
            ConfigKey::TimeoutMs => "timeout_ms",
            ConfigKey::Retries => "retries",
            ConfigKey::PollMs => "poll_ms",
            ConfigKey::ReapplyAfterPowerCycle => "reapply_after_power_cycle",
            ConfigKey::InterlockFault => "interlock_fault",
            ConfigKey::InterlockLink => "interlock_link",
            ConfigKey::InterlockReady => "interlock_ready",
            ConfigKey::ArcOkDebounceMs => "arc_ok_debounce_ms",
            ConfigKey::TransferTimeoutMs => "transfer_timeout_ms",
            ConfigKey::TransferTimeoutDropsStart => "transfer_timeout_drops_start",
            ConfigKey::Events => "events",
            ConfigKey::HprId => "hpr_id",
            ConfigKey::PhoenixFormat => "phoenix_format",
            ConfigKey::TorchOnActive => "torch_on_active",
            ConfigKey::TorchOnDebounceMs => "torch_on_debounce_ms",
            ConfigKey::HoldActive => "hold_active",
            ConfigKey::HoldDebounceMs => "hold_debounce_ms",
            ConfigKey::PierceCompleteActive => "pierce_complete_active",
            ConfigKey::PierceCompleteDebounceMs => "pierce_complete_debounce_ms",
            ConfigKey::CornerCurrentActive => "corner_current_active",
            ConfigKey::CornerCurrentDebounceMs => "corner_current_debounce_ms",
            ConfigKey::MotionActive => "motion_active",
            ConfigKey::MotionDebounceMs => "motion_debounce_ms",
            ConfigKey::NotReadyActive => "not_ready_active",
            ConfigKey::NotReadyDebounceMs => "not_ready_debounce_ms",
            ConfigKey::RampdownErrorActive => "rampdown_error_active",
            ConfigKey::RampdownErrorDebounceMs => "rampdown_error_debounce_ms",
            ConfigKey::SystemErrorActive => "system_error_active",
            ConfigKey::SystemErrorDebounceMs => "system_error_debounce_ms",
            ConfigKey::PsHoldActive => "ps_hold_active",
            ConfigKey::FaultActive => "fault_active",
            ConfigKey::CncAddress => "cnc_address",
            ConfigKey::CncBaud => "cnc_baud",
            ConfigKey::CncParity => "cnc_parity",
            ConfigKey::CncStopBits => "cnc_stop_bits",
            ConfigKey::CncDataBits => "cnc_data_bits",
            ConfigKey::ConsumableStartLimit => "consumable_start_limit",
            ConfigKey::ConsumableArcLimitS => "consumable_arc_limit_s",
            ConfigKey::Units => "units",
        }
    }

    /// The key for a word, case-insensitive.
    pub fn from_name(word: &str) -> Option<ConfigKey> {
        ConfigKey::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(word))
    }
}

/// The forms of `CONFIG`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigCommand<'a> {
    /// `CONFIG`: list every setting.
    Show,
    /// `CONFIG <key>`: one setting.
    Get(ConfigKey),
    /// `CONFIG <key> <value>`: change one setting (the value is checked by the firmware).
    Set {
        /// The setting.
        key: ConfigKey,
        /// The value as typed (one word, original case).
        value: &'a str,
    },
    /// `CONFIG SAVE`: store the settings in flash.
    Save,
}

/// One command from the CNC. Borrowed text (`RAW`, `CONFIG` values) points into the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command<'a> {
    /// `HELP`: list the commands.
    Help,
    /// `ID`: identify the bridge and the power supply.
    Id,
    /// `STATUS`: state, setpoints, actual values.
    Status,
    /// `LIMITS`: the connected supply's setpoint ranges.
    Limits,
    /// `FAULT`: the current fault.
    Fault,
    /// `FAULTLOG`: recent faults.
    FaultLog,
    /// `COUNTERS`: arc-on time, starts, errors.
    Counters,
    /// `CARTRIDGE`: consumable cartridge data (Powermax SYNC).
    Cartridge,
    /// `SET MODE <mode>`.
    SetMode(Mode),
    /// `SET AMPS <A>`.
    SetAmps(Amps),
    /// `SET PSI <psi|AUTO>`.
    SetPsi(Pressure),
    /// `SET PROCESS <mode> <A> <psi|AUTO>`: all three in one remote-mode write.
    SetProcess {
        /// Operating mode.
        mode: Mode,
        /// Current.
        amps: Amps,
        /// Pressure.
        pressure: Pressure,
    },
    /// `SET HPR_PROCESS <A> <plasma> <shield>`: MaxPro200 137 SET PROCESS (current and
    /// gases; the unit sets the pressures).
    SetHprProcess {
        /// Current (whole amps on the unit).
        amps: Amps,
        /// Plasma gas.
        plasma: Gas,
        /// Shield gas.
        shield: Gas,
    },
    /// `SET HPR_PARAMETERS ...`: 095 SET_ALL_PARAMETERS, in the HPR's or the MaxPro200's form.
    SetHprParameters(AllParameters),
    /// `SET HPR_GAS_FLOWS ...`: 078 SET_ALL_GAS_FLOWS, in the HPR's or the MaxPro200's form.
    SetHprGasFlows(AllGasFlows),
    /// `REMOTE OFF`: hand control back to the supply's front panel.
    RemoteOff,
    /// `GASTEST ON|OFF`: the unit's gas test (HPR: preflow, MaxPro200: 143 test gas).
    GasTest(bool),
    /// `GASTEST CHECK`: run the gas test, read the pressure while the gas flows, compare it
    /// with the permitted range, end the test.
    GasCheck,
    /// `GASTEST PREFLOW|CUTFLOW ON|OFF`: one HPR gas flow test (064-067).
    GasFlowTest {
        /// Which flow.
        flow: GasFlow,
        /// Start or stop.
        on: bool,
    },
    /// `POWER ON|OFF`: the HPR's Remote Power input, wired to the bridge's REMOTE_POWER
    /// output ("used to turn the power on or off").
    Power(bool),
    /// `RESTART`: quick restart (Powermax SYNC).
    Restart,
    /// `GASES <plasma> <shield>` (HPR, MaxPro200).
    Gases {
        /// Plasma gas.
        plasma: Gas,
        /// Shield gas.
        shield: Gas,
    },
    /// `CORNER <percent>`: corner current, 50..=100 % (HPR).
    Corner(u8),
    /// `RESET`: clear a shutdown error (HPR software reset).
    Reset,
    /// `CLEARWARN`: acknowledge warnings.
    ClearWarn,
    /// `EVENTS ON|OFF`: unsolicited `!` event lines.
    Events(bool),
    /// `CONFIG ...`.
    Config(ConfigCommand<'a>),
    /// `RAW <frame>`: send a frame to the supply (checked against the allow-list by the
    /// firmware). The frame is the rest of the line, spaces included, original case.
    Raw(&'a str),
    /// `TORCH ON|OFF`: simulator only.
    Torch(bool),
    /// `HISTORY [N]`: the newest N entries of the event history; `HISTORY CLEAR` erases it.
    History(HistoryCommand),
    /// `CLOCK <YYYY-MM-DDTHH:MM:SS>` sets the wall clock (UTC); `CLOCK` alone reports it.
    Clock(Option<WallClock>),
    /// `CONSUMABLES`: the consumable set's life; `CONSUMABLES NEW`: a new set is fitted.
    Consumables(ConsumablesCommand),
    /// `UNITS`: every unit on the power-supply line and its state.
    Units,
}

/// The values of `SET HPR_PARAMETERS` (095 SET_ALL_PARAMETERS). The HPR and the MaxPro200
/// take different fields (HPR manual, 095); the second word tells the forms apart: a corner
/// percent (HPR) or a gas (MaxPro200). Pressure set points are whole psi.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AllParameters {
    /// HPR: `<A> <corner %> <plasma> <shield>` then the six set points of
    /// [`HPR_GAS_FLOW_WORDS`].
    Hpr {
        /// Current (whole amps on the unit).
        amps: Amps,
        /// Corner current, percent of the cutting current (50..100).
        corner: u8,
        /// Plasma gas.
        plasma: Gas,
        /// Shield gas.
        shield: Gas,
        /// Pressure set points.
        flows: GasFlows,
    },
    /// MaxPro200: `<A> <plasma> <shield> <plasma psi> <shield psi>`.
    MaxPro200 {
        /// Current (whole amps on the unit).
        amps: Amps,
        /// Plasma gas.
        plasma: Gas,
        /// Shield gas.
        shield: Gas,
        /// Pressure set points.
        pressures: MaxProPressures,
    },
}

/// The values of `SET HPR_GAS_FLOWS` (078 SET_ALL_GAS_FLOWS): six set points on an HPR, two on
/// a MaxPro200 (told apart by their number), whole psi.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AllGasFlows {
    /// HPR: the six set points of [`HPR_GAS_FLOW_WORDS`].
    Hpr(GasFlows),
    /// MaxPro200: `<plasma psi> <shield psi>`.
    MaxPro200(MaxProPressures),
}

/// The HPR's pressure set points in the order 078 and 095 take them (and [`GasFlows`] holds
/// them): the names of their arguments in errors and of their fields in replies.
pub const HPR_GAS_FLOW_WORDS: [&str; 6] = [
    "plasma_cutflow_psi",
    "plasma_preflow_psi",
    "shield_cutflow_psi",
    "shield_preflow_psi",
    "n2_mix_psi",
    "gas2_mix_psi",
];
/// The MaxPro200's pressure set points in the order 078 and 095 take them (names as above).
pub const MAXPRO_GAS_FLOW_WORDS: [&str; 2] = ["plasma_psi", "shield_psi"];
/// `0..MAX_FLOW_PSI` and `0..MAX_MIX_PSI` as written in an error reply (a test ties them).
const FLOW_RANGE_TEXT: &str = "0..99";
const MIX_RANGE_TEXT: &str = "0..100";

/// The forms of `CONSUMABLES`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConsumablesCommand {
    /// `CONSUMABLES`: starts, arc seconds, limits and the share of life used.
    Show,
    /// `CONSUMABLES NEW`: the operator fitted a new set; the counts start from zero.
    New,
}

/// The forms of `HISTORY`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HistoryCommand {
    /// `HISTORY [N]`: the newest N entries ([`HISTORY_DEFAULT`] without N), newest first.
    Newest(u8),
    /// `HISTORY CLEAR`: erase the history.
    Clear,
}

/// Entries `HISTORY` lists without a count.
pub const HISTORY_DEFAULT: u8 = 10;
/// The most entries one `HISTORY` lists.
pub const HISTORY_MAX: u8 = 16;
/// `1..HISTORY_MAX` as written in an error reply (a test ties them).
const HISTORY_RANGE_TEXT: &str = "1..16";

/// Corner current bounds (HPR command 095: "corner current percent (50 - 100%)").
const CORNER_MIN: u8 = 50;
const CORNER_MAX: u8 = 100;

fn is_blank(c: char) -> bool {
    c == ' ' || c == '\t'
}

/// The words of a line, with access to the unsplit remainder.
struct Args<'a> {
    rest: &'a str,
}

impl<'a> Args<'a> {
    fn next(&mut self) -> Option<&'a str> {
        let s = self.rest.trim_start_matches(is_blank);
        if s.is_empty() {
            self.rest = s;
            return None;
        }
        // (`find` gives a char boundary: the checked split never fails, and has no panic path.)
        let (word, rest) = s
            .split_at_checked(s.find(is_blank).unwrap_or(s.len()))
            .unwrap_or((s, ""));
        self.rest = rest;
        Some(word)
    }

    fn expect(&mut self, what: &'static str) -> Result<&'a str, ParseError> {
        self.next().ok_or(ParseError::MissingArgument { what })
    }

    fn end(&mut self) -> Result<(), ParseError> {
        match self.next() {
            Some(_) => Err(ParseError::UnexpectedArgument),
            None => Ok(()),
        }
    }

    fn remainder(&mut self) -> &'a str {
        core::mem::take(&mut self.rest).trim_matches(is_blank)
    }
}

fn is(word: &str, keyword: &str) -> bool {
    word.eq_ignore_ascii_case(keyword)
}

fn on_off(args: &mut Args<'_>, what: &'static str) -> Result<bool, ParseError> {
    let word = args.expect(what)?;
    if is(word, "ON") {
        Ok(true)
    } else if is(word, "OFF") {
        Ok(false)
    } else {
        Err(ParseError::BadKeyword {
            what,
            expected: "ON|OFF",
        })
    }
}

fn mode(args: &mut Args<'_>) -> Result<Mode, ParseError> {
    Mode::from_name(args.expect("mode")?).ok_or(ParseError::BadKeyword {
        what: "mode",
        expected: Mode::EXPECTED,
    })
}

fn gas(args: &mut Args<'_>, what: &'static str) -> Result<Gas, ParseError> {
    Gas::from_name(args.expect(what)?).ok_or(ParseError::BadKeyword {
        what,
        expected: Gas::EXPECTED,
    })
}

/// A CNC number: unsigned decimal text, exactly `bits` fraction bits, with bounds checked by the
/// caller. Every refusal becomes the reply that says what was wrong.
fn number(
    word: &str,
    bits: u32,
    what: &'static str,
    range: &'static str,
    step: &'static str,
) -> Result<i16, ParseError> {
    // The CNC grammar has no sign (no setpoint is negative); `-5` is a syntax error, not a
    // value out of range.
    if word.starts_with('-') {
        return Err(ParseError::BadNumber { what });
    }
    units::parse_fixed(word, bits, Rounding::Exact).map_err(|e| match e {
        units::ParseError::Syntax => ParseError::BadNumber { what },
        units::ParseError::OutOfRange => ParseError::OutOfRange { what, range },
        // More than 30 significant fraction digits cannot be a multiple of 1/2^bits either
        // (those need at most `bits` digits).
        units::ParseError::Inexact | units::ParseError::TooManyDigits => {
            ParseError::NotMultiple { what, step }
        }
    })
}

fn amps(args: &mut Args<'_>) -> Result<Amps, ParseError> {
    const WHAT: &str = AMPS_ARGUMENT;
    let steps = number(
        args.expect(WHAT)?,
        Amps::FRACTION_BITS,
        WHAT,
        AMPS_RANGE_TEXT,
        "1/64",
    )?;
    let amps = Amps::from_raw(steps as u16);
    if amps < AMPS_MIN || amps > AMPS_MAX {
        return Err(ParseError::OutOfRange {
            what: WHAT,
            range: AMPS_RANGE_TEXT,
        });
    }
    Ok(amps)
}

fn pressure(args: &mut Args<'_>) -> Result<Pressure, ParseError> {
    const WHAT: &str = "psi";
    let word = args.expect(WHAT)?;
    if is(word, "AUTO") {
        return Ok(Pressure::Auto);
    }
    let steps =
        number(word, Psi::FRACTION_BITS, WHAT, PSI_RANGE_TEXT, "1/128").map_err(|e| match e {
            ParseError::BadNumber { what } => ParseError::BadKeyword {
                what,
                expected: "a number or AUTO",
            },
            other => other,
        })?;
    let psi = Psi::from_raw(steps as u16);
    if psi < PSI_MIN || psi > PSI_MAX {
        return Err(ParseError::OutOfRange {
            what: WHAT,
            range: PSI_RANGE_TEXT,
        });
    }
    Ok(Pressure::Set(psi))
}

const CORNER_WORD: &str = "percent";

fn corner(args: &mut Args<'_>) -> Result<u8, ParseError> {
    corner_of(args.expect(CORNER_WORD)?)
}

fn corner_of(word: &str) -> Result<u8, ParseError> {
    const WHAT: &str = CORNER_WORD;
    const RANGE: &str = "50..100";
    let percent = number(word, 0, WHAT, RANGE, "1")?;
    match u8::try_from(percent) {
        Ok(p) if (CORNER_MIN..=CORNER_MAX).contains(&p) => Ok(p),
        _ => Err(ParseError::OutOfRange {
            what: WHAT,
            range: RANGE,
        }),
    }
}

/// One pressure set point in whole psi, 0..`max`.
fn setpoint(args: &mut Args<'_>, what: &'static str, mix: bool) -> Result<u16, ParseError> {
    let (max, range) = if mix {
        (MAX_MIX_PSI, MIX_RANGE_TEXT)
    } else {
        (MAX_FLOW_PSI, FLOW_RANGE_TEXT)
    };
    let psi = number(args.expect(what)?, 0, what, range, "1")?;
    match u16::try_from(psi) {
        Ok(psi) if psi <= max => Ok(psi),
        _ => Err(ParseError::OutOfRange { what, range }),
    }
}

/// The HPR's six set points (the last two are the mix set points, 0..100).
fn hpr_flows(args: &mut Args<'_>) -> Result<GasFlows, ParseError> {
    let mut values = [0; 6];
    for (i, (value, what)) in values.iter_mut().zip(HPR_GAS_FLOW_WORDS).enumerate() {
        *value = setpoint(args, what, i >= 4)?;
    }
    Ok(GasFlows::from_array(values))
}

/// The MaxPro200's two set points, 0..99.
fn maxpro_pressures(args: &mut Args<'_>) -> Result<MaxProPressures, ParseError> {
    let [plasma, shield] = MAXPRO_GAS_FLOW_WORDS;
    Ok(MaxProPressures {
        plasma: setpoint(args, plasma, false)?,
        shield: setpoint(args, shield, false)?,
    })
}

/// `SET HPR_PARAMETERS`: the second word is a gas on a MaxPro200, the corner percent on an HPR.
fn all_parameters(args: &mut Args<'_>) -> Result<AllParameters, ParseError> {
    let amps = amps(args)?;
    let second = args.expect("corner percent or plasma gas")?;
    if let Some(plasma) = Gas::from_name(second) {
        return Ok(AllParameters::MaxPro200 {
            amps,
            plasma,
            shield: gas(args, "shield gas")?,
            pressures: maxpro_pressures(args)?,
        });
    }
    Ok(AllParameters::Hpr {
        amps,
        corner: corner_of(second)?,
        plasma: gas(args, "plasma gas")?,
        shield: gas(args, "shield gas")?,
        flows: hpr_flows(args)?,
    })
}

/// `SET HPR_GAS_FLOWS`: two set points on a MaxPro200, six on an HPR.
fn all_gas_flows(args: &mut Args<'_>) -> Result<AllGasFlows, ParseError> {
    let mut ahead = Args { rest: args.rest };
    let count = core::iter::from_fn(|| ahead.next()).take(3).count();
    Ok(if count == MAXPRO_GAS_FLOW_WORDS.len() {
        AllGasFlows::MaxPro200(maxpro_pressures(args)?)
    } else {
        AllGasFlows::Hpr(hpr_flows(args)?)
    })
}

fn set(args: &mut Args<'_>) -> Result<Command<'static>, ParseError> {
    const WHAT: &str = "SET parameter";
    const EXPECTED: &str = "MODE|AMPS|PSI|PROCESS|HPR_PROCESS|HPR_PARAMETERS|HPR_GAS_FLOWS";
    let [
        mode_word,
        amps_word,
        psi_word,
        process_word,
        hpr_process_word,
        hpr_parameters_word,
        hpr_gas_flows_word,
    ] = SET_WORDS;
    let word = args
        .next()
        .ok_or(ParseError::MissingArgument { what: WHAT })?;
    let command = if is(word, mode_word) {
        Command::SetMode(mode(args)?)
    } else if is(word, amps_word) {
        Command::SetAmps(amps(args)?)
    } else if is(word, psi_word) {
        Command::SetPsi(pressure(args)?)
    } else if is(word, process_word) {
        Command::SetProcess {
            mode: mode(args)?,
            amps: amps(args)?,
            pressure: pressure(args)?,
        }
    } else if is(word, hpr_process_word) {
        Command::SetHprProcess {
            amps: amps(args)?,
            plasma: gas(args, "plasma gas")?,
            shield: gas(args, "shield gas")?,
        }
    } else if is(word, hpr_parameters_word) {
        Command::SetHprParameters(all_parameters(args)?)
    } else if is(word, hpr_gas_flows_word) {
        Command::SetHprGasFlows(all_gas_flows(args)?)
    } else {
        return Err(ParseError::BadKeyword {
            what: WHAT,
            expected: EXPECTED,
        });
    };
    Ok(command)
}

fn config<'a>(args: &mut Args<'a>) -> Result<ConfigCommand<'a>, ParseError> {
    let Some(word) = args.next() else {
        return Ok(ConfigCommand::Show);
    };
    if is(word, "SAVE") {
        return Ok(ConfigCommand::Save);
    }
    let key = ConfigKey::from_name(word).ok_or(ParseError::BadKeyword {
        what: "config key",
        expected: "SAVE or a key listed by CONFIG",
    })?;
    Ok(match args.next() {
        None => ConfigCommand::Get(key),
        Some(value) => ConfigCommand::Set { key, value },
    })
}

fn history(args: &mut Args<'_>) -> Result<HistoryCommand, ParseError> {
    const WHAT: &str = "count";
    let Some(word) = args.next() else {
        return Ok(HistoryCommand::Newest(HISTORY_DEFAULT));
    };
    if is(word, "CLEAR") {
        return Ok(HistoryCommand::Clear);
    }
    let count = number(word, 0, WHAT, HISTORY_RANGE_TEXT, "1").map_err(|e| match e {
        ParseError::BadNumber { what } => ParseError::BadKeyword {
            what,
            expected: "a number or CLEAR",
        },
        other => other,
    })?;
    match u8::try_from(count) {
        Ok(n) if (1..=HISTORY_MAX).contains(&n) => Ok(HistoryCommand::Newest(n)),
        _ => Err(ParseError::OutOfRange {
            what: WHAT,
            range: HISTORY_RANGE_TEXT,
        }),
    }
}

fn consumables(args: &mut Args<'_>) -> Result<ConsumablesCommand, ParseError> {
    match args.next() {
        None => Ok(ConsumablesCommand::Show),
        Some(word) if is(word, "NEW") => Ok(ConsumablesCommand::New),
        Some(_) => Err(ParseError::BadKeyword {
            what: "CONSUMABLES argument",
            expected: "NEW",
        }),
    }
}

fn clock(args: &mut Args<'_>) -> Result<Option<WallClock>, ParseError> {
    let Some(word) = args.next() else {
        return Ok(None);
    };
    WallClock::parse(word)
        .map(Some)
        .ok_or(ParseError::BadKeyword {
            what: "clock",
            expected: CLOCK_FORM,
        })
}

/// The first word of every command a CNC program may send, in the order HELP lists them
/// (`TORCH`, which only the simulator runs, is listed apart by HELP).
pub const COMMAND_WORDS: [&str; 24] = [
    "HELP",
    "ID",
    "STATUS",
    "LIMITS",
    "FAULT",
    "FAULTLOG",
    "COUNTERS",
    "CARTRIDGE",
    "SET",
    "REMOTE",
    "GASTEST",
    "POWER",
    "RESTART",
    "GASES",
    "CORNER",
    "RESET",
    "CLEARWARN",
    "EVENTS",
    "CONFIG",
    "HISTORY",
    "CLOCK",
    "CONSUMABLES",
    "UNITS",
    "RAW",
];

/// The words that may follow `SET`.
pub const SET_WORDS: [&str; 7] = [
    "MODE",
    "AMPS",
    "PSI",
    "PROCESS",
    "HPR_PROCESS",
    "HPR_PARAMETERS",
    "HPR_GAS_FLOWS",
];

/// The words that may follow `GASTEST`.
pub const GASTEST_WORDS: [&str; 5] = ["ON", "OFF", "PREFLOW", "CUTFLOW", "CHECK"];

/// `GASTEST ON|OFF|CHECK` or `GASTEST PREFLOW|CUTFLOW ON|OFF`.
fn gas_test(args: &mut Args<'_>) -> Result<Command<'static>, ParseError> {
    const WHAT: &str = "GASTEST argument";
    let [on_word, off_word, preflow, cutflow, check] = GASTEST_WORDS;
    let word = args.expect(WHAT)?;
    let flow = if is(word, on_word) || is(word, off_word) {
        return Ok(Command::GasTest(is(word, on_word)));
    } else if is(word, check) {
        return Ok(Command::GasCheck);
    } else if is(word, preflow) {
        GasFlow::Preflow
    } else if is(word, cutflow) {
        GasFlow::Cutflow
    } else {
        return Err(ParseError::BadKeyword {
            what: WHAT,
            expected: "ON|OFF|PREFLOW|CUTFLOW|CHECK",
        });
    };
    let on = on_off(args, WHAT)?;
    Ok(Command::GasFlowTest { flow, on })
}

/// Commands that take no argument.
const PLAIN_COMMANDS: [(&str, Command<'static>); 11] = [
    ("HELP", Command::Help),
    ("ID", Command::Id),
    ("STATUS", Command::Status),
    ("LIMITS", Command::Limits),
    ("FAULT", Command::Fault),
    ("FAULTLOG", Command::FaultLog),
    ("COUNTERS", Command::Counters),
    ("CARTRIDGE", Command::Cartridge),
    ("RESTART", Command::Restart),
    ("RESET", Command::Reset),
    ("CLEARWARN", Command::ClearWarn),
];

impl<'a> Command<'a> {
    /// Parse one line (without its terminator). Keywords are case-insensitive; words are
    /// separated by spaces or tabs.
    ///
    /// ```
    /// use plasma_protocol::cnc::command::{Command, Mode};
    /// use plasma_protocol::cnc::{ErrorCode, ParseError};
    ///
    /// let cmd = Command::parse("set process cut 55.5 auto")?;
    /// let Command::SetProcess { mode, amps, .. } = cmd else { unreachable!() };
    /// assert_eq!(mode, Mode::Cut);
    /// assert_eq!(amps.raw(), 3552); // 55.5 A x 64, exactly
    ///
    /// let err = Command::parse("SET AMPS 500").unwrap_err();
    /// assert_eq!(err.code(), ErrorCode::Range);
    /// # Ok::<(), ParseError>(())
    /// ```
    pub fn parse(line: &'a str) -> Result<Command<'a>, ParseError> {
        let mut args = Args { rest: line };
        let word = args.next().ok_or(ParseError::Empty)?;
        if let Some((_, command)) = PLAIN_COMMANDS.iter().find(|(name, _)| is(word, name)) {
            args.end()?;
            return Ok(*command);
        }
        let command = if is(word, "SET") {
            set(&mut args)?
        } else if is(word, "REMOTE") {
            let what = "REMOTE argument";
            let arg = args.expect(what)?;
            if !is(arg, "OFF") {
                return Err(ParseError::BadKeyword {
                    what,
                    expected: "OFF",
                });
            }
            Command::RemoteOff
        } else if is(word, "GASTEST") {
            gas_test(&mut args)?
        } else if is(word, "POWER") {
            Command::Power(on_off(&mut args, "POWER argument")?)
        } else if is(word, "EVENTS") {
            Command::Events(on_off(&mut args, "EVENTS argument")?)
        } else if is(word, "TORCH") {
            Command::Torch(on_off(&mut args, "TORCH argument")?)
        } else if is(word, "GASES") {
            Command::Gases {
                plasma: gas(&mut args, "plasma gas")?,
                shield: gas(&mut args, "shield gas")?,
            }
        } else if is(word, "CORNER") {
            Command::Corner(corner(&mut args)?)
        } else if is(word, "CONFIG") {
            Command::Config(config(&mut args)?)
        } else if is(word, "HISTORY") {
            Command::History(history(&mut args)?)
        } else if is(word, "CLOCK") {
            Command::Clock(clock(&mut args)?)
        } else if is(word, "CONSUMABLES") {
            Command::Consumables(consumables(&mut args)?)
        } else if is(word, "UNITS") {
            Command::Units
        } else if is(word, "RAW") {
            let frame = args.remainder();
            if frame.is_empty() {
                return Err(ParseError::MissingArgument { what: "frame" });
            }
            return Ok(Command::Raw(frame));
        } else {
            return Err(ParseError::UnknownCommand);
        };
        args.end()?;
        Ok(command)
    }
}

#[cfg(test)]
mod tests {
    use super::super::ErrorCode;
    use super::*;
    use core::fmt::Write;

    fn amps(a: f64) -> Amps {
        Amps::from_raw((a * 64.0) as u16)
    }

    fn psi(p: f64) -> Pressure {
        Pressure::Set(Psi::from_raw((p * 128.0) as u16))
    }

    fn err(line: &str) -> ParseError {
        Command::parse(line).unwrap_err()
    }

    fn text(e: ParseError) -> heapless::String<96> {
        let mut s = heapless::String::new();
        write!(s, "{} {}", e.code(), e).unwrap();
        s
    }

    #[test]
    fn plain_commands_in_any_case() {
        let cases = [
            ("HELP", Command::Help),
            ("id", Command::Id),
            ("Status", Command::Status),
            ("LIMITS", Command::Limits),
            ("fault", Command::Fault),
            ("FaultLog", Command::FaultLog),
            ("COUNTERS", Command::Counters),
            ("cartridge", Command::Cartridge),
            ("RESTART", Command::Restart),
            ("reset", Command::Reset),
            ("ClearWarn", Command::ClearWarn),
            ("  status\t", Command::Status),
        ];
        for (line, command) in cases {
            assert_eq!(Command::parse(line), Ok(command), "{line}");
        }
        for line in [
            "HELP me",
            "id 1",
            "STATUS x",
            "restart now",
            "CLEARWARN all",
        ] {
            assert_eq!(err(line), ParseError::UnexpectedArgument, "{line}");
        }
    }

    #[test]
    fn unknown_and_empty() {
        assert_eq!(err("FLY"), ParseError::UnknownCommand);
        assert_eq!(err("STATUSX"), ParseError::UnknownCommand);
        assert_eq!(err("   "), ParseError::Empty);
        assert_eq!(err(""), ParseError::Empty);
        assert_eq!(err("\u{e9}tat"), ParseError::UnknownCommand);
        assert_eq!(
            text(err("FLY")),
            "SYNTAX unknown command (HELP lists the commands)"
        );
    }

    #[test]
    fn help_lists_words_a_person_can_type() {
        for word in COMMAND_WORDS {
            assert_ne!(
                Command::parse(word),
                Err(ParseError::UnknownCommand),
                "{word}"
            );
        }
        for word in GASTEST_WORDS {
            let mut line = heapless::String::<24>::new();
            write!(line, "GASTEST {word}").unwrap();
            assert!(
                !matches!(Command::parse(&line), Err(ParseError::BadKeyword { .. })),
                "{line}"
            );
        }
        for word in SET_WORDS {
            let mut line = heapless::String::<24>::new();
            write!(line, "SET {word}").unwrap();
            assert!(
                !matches!(Command::parse(&line), Err(ParseError::BadKeyword { .. })),
                "{line}"
            );
        }
        // Every line that parses starts with a listed word (TORCH is listed apart).
        let lines = [
            "HELP",
            "ID",
            "STATUS",
            "LIMITS",
            "FAULT",
            "FAULTLOG",
            "COUNTERS",
            "CARTRIDGE",
            "SET MODE CUT",
            "SET AMPS 45",
            "SET PSI AUTO",
            "SET PROCESS CUT 45 AUTO",
            "REMOTE OFF",
            "GASTEST ON",
            "POWER ON",
            "RESTART",
            "GASES AIR AIR",
            "CORNER 50",
            "RESET",
            "CLEARWARN",
            "EVENTS ON",
            "CONFIG",
            "CONFIG SAVE",
            "HISTORY 5",
            "CLOCK 2026-11-26T07:30:00",
            "CONSUMABLES NEW",
            "RAW 01030000",
            "TORCH ON",
        ];
        for line in lines {
            assert!(Command::parse(line).is_ok(), "{line}");
            let first = line.split(' ').next().unwrap_or(line);
            assert!(COMMAND_WORDS.contains(&first) || first == "TORCH", "{line}");
        }
    }

    #[test]
    fn consumables() {
        assert_eq!(
            Command::parse("CONSUMABLES"),
            Ok(Command::Consumables(ConsumablesCommand::Show))
        );
        assert_eq!(
            Command::parse("consumables new"),
            Ok(Command::Consumables(ConsumablesCommand::New))
        );
        assert_eq!(
            text(err("CONSUMABLES RESET")),
            "SYNTAX CONSUMABLES argument: expected NEW"
        );
        assert_eq!(err("CONSUMABLES NEW 2"), ParseError::UnexpectedArgument);
    }

    #[test]
    fn history_and_clock() {
        use HistoryCommand::{Clear, Newest};
        let cases = [
            ("HISTORY", Command::History(Newest(HISTORY_DEFAULT))),
            ("history 1", Command::History(Newest(1))),
            ("HISTORY 16", Command::History(Newest(HISTORY_MAX))),
            ("History clear", Command::History(Clear)),
            ("CLOCK", Command::Clock(None)),
            (
                "clock 2026-11-26T07:30:00",
                Command::Clock(WallClock::parse("2026-11-26T07:30:00")),
            ),
        ];
        for (line, command) in cases {
            assert_eq!(Command::parse(line), Ok(command), "{line}");
        }
        let range = ParseError::OutOfRange {
            what: "count",
            range: HISTORY_RANGE_TEXT,
        };
        assert_eq!(err("HISTORY 0"), range);
        assert_eq!(err("HISTORY 17"), range);
        assert_eq!(err("HISTORY 300"), range);
        assert_eq!(text(err("HISTORY 17")), "RANGE count out of range 1..16");
        assert_eq!(
            text(err("HISTORY ALL")),
            "SYNTAX count: expected a number or CLEAR"
        );
        assert_eq!(err("HISTORY 5 6"), ParseError::UnexpectedArgument);
        assert_eq!(
            text(err("CLOCK 2026-11-26")),
            "SYNTAX clock: expected YYYY-MM-DDTHH:MM:SS"
        );
        let mut written = heapless::String::<8>::new();
        write!(written, "1..{HISTORY_MAX}").unwrap();
        assert_eq!(written, HISTORY_RANGE_TEXT);
    }

    #[test]
    fn set_mode() {
        assert_eq!(
            Command::parse("SET MODE CUT"),
            Ok(Command::SetMode(Mode::Cut))
        );
        assert_eq!(
            Command::parse("set mode cpa"),
            Ok(Command::SetMode(Mode::Cpa))
        );
        assert_eq!(
            Command::parse("SET MODE Expanded"),
            Ok(Command::SetMode(Mode::Expanded))
        );
        assert_eq!(
            Command::parse("SET MODE GOUGE"),
            Ok(Command::SetMode(Mode::Gouge))
        );
        assert_eq!(
            err("SET MODE"),
            ParseError::MissingArgument { what: "mode" }
        );
        assert_eq!(
            text(err("SET MODE MARK")),
            "SYNTAX mode: expected CUT|CPA|EXPANDED|GOUGE"
        );
        assert_eq!(err("SET MODE CUT GOUGE"), ParseError::UnexpectedArgument);
        assert_eq!(text(err("SET")), "SYNTAX missing SET parameter");
        assert_eq!(
            text(err("SET VOLTS 5")),
            "SYNTAX SET parameter: expected \
             MODE|AMPS|PSI|PROCESS|HPR_PROCESS|HPR_PARAMETERS|HPR_GAS_FLOWS"
        );
        assert_eq!(
            Command::parse("set hpr_process 200 o2 air"),
            Ok(Command::SetHprProcess {
                amps: amps(200.0),
                plasma: Gas::O2,
                shield: Gas::Air
            })
        );
        assert_eq!(
            text(err("SET HPR_PROCESS 200 O2")),
            "SYNTAX missing shield gas"
        );
        assert_eq!(err("SET HPR_PROCESS 4 O2 AIR").code(), ErrorCode::Range);
    }

    /// The values of the HPR manual's 095 and 078 samples (002_72b43a5685974c77.txt line 180,
    /// `>095100 75 1 6 55 45 35 25 00 0084<`: gas codes 1 and 6 are O2 and N2; line 165,
    /// `>07855 45 35 25 50 50AB<`; the MaxPro200 078 set points "0050" and "0058").
    #[test]
    fn set_hpr_parameters_and_gas_flows_in_both_forms() {
        assert_eq!(
            Command::parse("SET HPR_PARAMETERS 100 75 O2 N2 55 45 35 25 0 0"),
            Ok(Command::SetHprParameters(AllParameters::Hpr {
                amps: amps(100.0),
                corner: 75,
                plasma: Gas::O2,
                shield: Gas::N2,
                flows: GasFlows::from_array([55, 45, 35, 25, 0, 0]),
            }))
        );
        assert_eq!(
            Command::parse("set hpr_parameters 200 o2 air 50 58"),
            Ok(Command::SetHprParameters(AllParameters::MaxPro200 {
                amps: amps(200.0),
                plasma: Gas::O2,
                shield: Gas::Air,
                pressures: MaxProPressures {
                    plasma: 50,
                    shield: 58
                },
            }))
        );
        assert_eq!(
            Command::parse("SET HPR_GAS_FLOWS 55 45 35 25 50 50"),
            Ok(Command::SetHprGasFlows(AllGasFlows::Hpr(
                GasFlows::from_array([55, 45, 35, 25, 50, 50])
            )))
        );
        assert_eq!(
            Command::parse("SET HPR_GAS_FLOWS 50 58"),
            Ok(Command::SetHprGasFlows(AllGasFlows::MaxPro200(
                MaxProPressures {
                    plasma: 50,
                    shield: 58
                }
            )))
        );
        // The flows are 0..99 psi, the two mix set points 0..100 (lines 165 and 180).
        assert!(Command::parse("SET HPR_GAS_FLOWS 99 45 35 25 100 100").is_ok());
        assert_eq!(
            text(err("SET HPR_GAS_FLOWS 55 45 35 25 100 101")),
            "RANGE gas2_mix_psi out of range 0..100"
        );
        assert_eq!(
            text(err("SET HPR_GAS_FLOWS 55 100 35 25 0 0")),
            "RANGE plasma_preflow_psi out of range 0..99"
        );
        assert_eq!(
            text(err("SET HPR_GAS_FLOWS 50 100")),
            "RANGE shield_psi out of range 0..99"
        );
        assert_eq!(
            text(err("SET HPR_GAS_FLOWS 55 45 35")),
            "SYNTAX missing shield_preflow_psi"
        );
        assert_eq!(
            err("SET HPR_GAS_FLOWS 55 45 35 25 0 0 0"),
            ParseError::UnexpectedArgument
        );
        assert_eq!(
            text(err("SET HPR_PARAMETERS 100 75 O2 N2 55 45 35 25 0")),
            "SYNTAX missing gas2_mix_psi"
        );
        assert_eq!(
            text(err("SET HPR_PARAMETERS 100 40 O2 N2 55 45 35 25 0 0")),
            "RANGE percent out of range 50..100"
        );
        assert_eq!(
            text(err("SET HPR_PARAMETERS 100 O2 N2 55")),
            "SYNTAX missing shield_psi"
        );
        assert_eq!(
            text(err("SET HPR_PARAMETERS 100")),
            "SYNTAX missing corner percent or plasma gas"
        );
        assert_eq!(
            err("SET HPR_PARAMETERS 401 O2 N2 55 45").code(),
            ErrorCode::Range
        );
        assert_eq!(
            err("SET HPR_PARAMETERS 200 O2 N2 55 45 35").code(),
            ErrorCode::Syntax
        );
        let upper = |range: &str| {
            range
                .strip_prefix("0..")
                .and_then(|n| n.parse::<u16>().ok())
        };
        assert_eq!(upper(FLOW_RANGE_TEXT), Some(MAX_FLOW_PSI));
        assert_eq!(upper(MIX_RANGE_TEXT), Some(MAX_MIX_PSI));
    }

    #[test]
    fn set_amps_exact_decimals_and_bounds() {
        assert_eq!(
            Command::parse("SET AMPS 45"),
            Ok(Command::SetAmps(amps(45.0)))
        );
        assert_eq!(
            Command::parse("set amps 55.5"),
            Ok(Command::SetAmps(amps(55.5)))
        );
        assert_eq!(
            Command::parse("SET AMPS 45.5"),
            Ok(Command::SetAmps(Amps::from_raw(2912)))
        );
        assert_eq!(Command::parse("SET AMPS 5"), Ok(Command::SetAmps(AMPS_MIN)));
        assert_eq!(
            Command::parse("SET AMPS 400.0"),
            Ok(Command::SetAmps(AMPS_MAX))
        );
        assert_eq!(
            text(err("SET AMPS 400.015625")),
            "RANGE amps out of range 5..400"
        );
        assert_eq!(
            text(err("SET AMPS 4.984375")),
            "RANGE amps out of range 5..400"
        );
        assert_eq!(
            text(err("SET AMPS 99999999")),
            "RANGE amps out of range 5..400"
        );
        assert_eq!(text(err("SET AMPS 1024")), "RANGE amps out of range 5..400");
        assert_eq!(
            text(err("SET AMPS 45.1")),
            "RANGE amps must be a multiple of 1/64"
        );
        assert_eq!(text(err("SET AMPS -5")), "SYNTAX amps: not a number");
        assert_eq!(text(err("SET AMPS AUTO")), "SYNTAX amps: not a number");
        assert_eq!(text(err("SET AMPS")), "SYNTAX missing amps");
        assert_eq!(err("SET AMPS 45 46"), ParseError::UnexpectedArgument);
    }

    #[test]
    fn set_psi() {
        assert_eq!(
            Command::parse("SET PSI AUTO"),
            Ok(Command::SetPsi(Pressure::Auto))
        );
        assert_eq!(
            Command::parse("set psi auto"),
            Ok(Command::SetPsi(Pressure::Auto))
        );
        assert_eq!(
            Command::parse("SET PSI 72.5"),
            Ok(Command::SetPsi(psi(72.5)))
        );
        assert_eq!(
            Command::parse("SET PSI 0.9921875"),
            Err(ParseError::OutOfRange {
                what: "psi",
                range: "1..150"
            })
        );
        assert_eq!(text(err("SET PSI 0")), "RANGE psi out of range 1..150");
        assert_eq!(text(err("SET PSI 150.5")), "RANGE psi out of range 1..150");
        assert_eq!(
            text(err("SET PSI 72.001")),
            "RANGE psi must be a multiple of 1/128"
        );
        assert_eq!(
            text(err("SET PSI high")),
            "SYNTAX psi: expected a number or AUTO"
        );
        assert_eq!(text(err("SET PSI")), "SYNTAX missing psi");
    }

    #[test]
    fn set_process() {
        assert_eq!(
            Command::parse("SET PROCESS CUT 45 AUTO"),
            Ok(Command::SetProcess {
                mode: Mode::Cut,
                amps: amps(45.0),
                pressure: Pressure::Auto
            })
        );
        assert_eq!(
            Command::parse("set process gouge 55.5 68.25"),
            Ok(Command::SetProcess {
                mode: Mode::Gouge,
                amps: amps(55.5),
                pressure: psi(68.25)
            })
        );
        assert_eq!(text(err("SET PROCESS CUT 45")), "SYNTAX missing psi");
        assert_eq!(text(err("SET PROCESS CUT")), "SYNTAX missing amps");
        assert_eq!(text(err("SET PROCESS")), "SYNTAX missing mode");
        assert_eq!(
            text(err("SET PROCESS 45 CUT AUTO")),
            "SYNTAX mode: expected CUT|CPA|EXPANDED|GOUGE"
        );
        assert_eq!(
            text(err("SET PROCESS CUT 401 AUTO")),
            "RANGE amps out of range 5..400"
        );
        assert_eq!(
            err("SET PROCESS CUT 45 AUTO X"),
            ParseError::UnexpectedArgument
        );
    }

    #[test]
    fn switches() {
        assert_eq!(Command::parse("REMOTE OFF"), Ok(Command::RemoteOff));
        assert_eq!(Command::parse("remote off"), Ok(Command::RemoteOff));
        assert_eq!(
            text(err("REMOTE ON")),
            "SYNTAX REMOTE argument: expected OFF"
        );
        assert_eq!(text(err("REMOTE")), "SYNTAX missing REMOTE argument");
        assert_eq!(err("REMOTE OFF NOW"), ParseError::UnexpectedArgument);
        assert_eq!(Command::parse("gastest on"), Ok(Command::GasTest(true)));
        assert_eq!(Command::parse("GASTEST OFF"), Ok(Command::GasTest(false)));
        assert_eq!(Command::parse("gastest check"), Ok(Command::GasCheck));
        assert_eq!(err("GASTEST CHECK NOW"), ParseError::UnexpectedArgument);
        assert_eq!(
            Command::parse("GASTEST cutflow ON"),
            Ok(Command::GasFlowTest {
                flow: GasFlow::Cutflow,
                on: true
            })
        );
        assert_eq!(
            Command::parse("GASTEST PREFLOW off"),
            Ok(Command::GasFlowTest {
                flow: GasFlow::Preflow,
                on: false
            })
        );
        assert_eq!(
            text(err("GASTEST maybe")),
            "SYNTAX GASTEST argument: expected ON|OFF|PREFLOW|CUTFLOW|CHECK"
        );
        assert_eq!(
            text(err("GASTEST CUTFLOW")),
            "SYNTAX missing GASTEST argument"
        );
        assert_eq!(err("GASTEST ON ON"), ParseError::UnexpectedArgument);
        for (word, make) in [
            ("EVENTS", Command::Events as fn(bool) -> Command<'static>),
            ("POWER", Command::Power),
            ("TORCH", Command::Torch),
        ] {
            let mut line = heapless::String::<32>::new();
            write!(line, "{word} on").unwrap();
            assert_eq!(Command::parse(&line), Ok(make(true)));
            line.clear();
            write!(line, "{word} OFF").unwrap();
            assert_eq!(Command::parse(&line), Ok(make(false)));
            line.clear();
            write!(line, "{word} maybe").unwrap();
            assert!(matches!(
                err(&line),
                ParseError::BadKeyword {
                    expected: "ON|OFF",
                    ..
                }
            ));
            assert!(matches!(err(word), ParseError::MissingArgument { .. }));
        }
        assert_eq!(
            text(err("GASTEST CUTFLOW 1")),
            "SYNTAX GASTEST argument: expected ON|OFF"
        );
        assert_eq!(err("TORCH ON ON"), ParseError::UnexpectedArgument);
    }

    #[test]
    fn gases_and_corner() {
        assert_eq!(
            Command::parse("GASES O2 AIR"),
            Ok(Command::Gases {
                plasma: Gas::O2,
                shield: Gas::Air
            })
        );
        assert_eq!(
            Command::parse("gases h35 n2"),
            Ok(Command::Gases {
                plasma: Gas::H35,
                shield: Gas::N2
            })
        );
        assert_eq!(text(err("GASES O2")), "SYNTAX missing shield gas");
        assert_eq!(text(err("GASES")), "SYNTAX missing plasma gas");
        assert_eq!(
            text(err("GASES CO2 AIR")),
            "SYNTAX plasma gas: expected O2|CH4|H35|H5|AIR|N2|AR|N95|F5"
        );
        assert_eq!(err("GASES O2 AIR N2"), ParseError::UnexpectedArgument);
        assert_eq!(Command::parse("CORNER 75"), Ok(Command::Corner(75)));
        assert_eq!(Command::parse("corner 50"), Ok(Command::Corner(50)));
        assert_eq!(Command::parse("CORNER 100"), Ok(Command::Corner(100)));
        assert_eq!(text(err("CORNER 49")), "RANGE percent out of range 50..100");
        assert_eq!(
            text(err("CORNER 300")),
            "RANGE percent out of range 50..100"
        );
        assert_eq!(
            text(err("CORNER 75.5")),
            "RANGE percent must be a multiple of 1"
        );
        assert_eq!(text(err("CORNER x")), "SYNTAX percent: not a number");
        assert_eq!(text(err("CORNER")), "SYNTAX missing percent");
    }

    #[test]
    fn gas_table_matches_hpr_table_vi() {
        let codes: [(Gas, u8); 9] = [
            (Gas::O2, 1),
            (Gas::Ch4, 2),
            (Gas::H35, 3),
            (Gas::H5, 4),
            (Gas::Air, 5),
            (Gas::N2, 6),
            (Gas::Ar, 7),
            (Gas::N95, 8),
            (Gas::F5, 11),
        ];
        for (gas, code) in codes {
            assert_eq!(gas.hpr_code(), code);
            assert_eq!(Gas::from_hpr_code(code), Some(gas));
            assert_eq!(Gas::from_name(gas.name()), Some(gas));
        }
        for code in [0, 9, 10, 12, 13, 255] {
            assert_eq!(Gas::from_hpr_code(code), None);
        }
    }

    #[test]
    fn config_forms() {
        assert_eq!(
            Command::parse("CONFIG"),
            Ok(Command::Config(ConfigCommand::Show))
        );
        assert_eq!(
            Command::parse("config save"),
            Ok(Command::Config(ConfigCommand::Save))
        );
        assert_eq!(
            Command::parse("CONFIG TIMEOUT_MS"),
            Ok(Command::Config(ConfigCommand::Get(ConfigKey::TimeoutMs)))
        );
        assert_eq!(
            Command::parse("config parity Even"),
            Ok(Command::Config(ConfigCommand::Set {
                key: ConfigKey::Parity,
                value: "Even"
            }))
        );
        assert_eq!(
            text(err("CONFIG colour red")),
            "SYNTAX config key: expected SAVE or a key listed by CONFIG"
        );
        assert_eq!(err("CONFIG address 1 2"), ParseError::UnexpectedArgument);
        assert_eq!(err("CONFIG SAVE NOW"), ParseError::UnexpectedArgument);
        for key in ConfigKey::ALL {
            assert_eq!(ConfigKey::from_name(key.name()), Some(key));
            let mut line = heapless::String::<64>::new();
            write!(line, "CONFIG {} 7", key.name().to_ascii_uppercase_str()).unwrap();
            assert_eq!(
                Command::parse(&line),
                Ok(Command::Config(ConfigCommand::Set { key, value: "7" }))
            );
        }
    }

    trait Upper {
        fn to_ascii_uppercase_str(&self) -> heapless::String<32>;
    }
    impl Upper for str {
        fn to_ascii_uppercase_str(&self) -> heapless::String<32> {
            self.chars().map(|c| c.to_ascii_uppercase()).collect()
        }
    }

    #[test]
    fn raw_keeps_the_rest_of_the_line() {
        assert_eq!(Command::parse("RAW >00494<"), Ok(Command::Raw(">00494<")));
        assert_eq!(
            Command::parse("raw   >07855 45 35 25 50 50AB<  "),
            Ok(Command::Raw(">07855 45 35 25 50 50AB<"))
        );
        assert_eq!(
            Command::parse("RAW :0103209400037A"),
            Ok(Command::Raw(":0103209400037A"))
        );
        assert_eq!(text(err("RAW")), "SYNTAX missing frame");
        assert_eq!(text(err("RAW \t ")), "SYNTAX missing frame");
    }

    #[test]
    fn codes() {
        assert_eq!(ParseError::TooLong.code(), ErrorCode::TooLong);
        assert_eq!(ParseError::Binary.code(), ErrorCode::Binary);
        assert_eq!(
            text(ParseError::TooLong),
            "TOOLONG line longer than 128 characters"
        );
        assert_eq!(
            text(ParseError::Binary),
            "BINARY non-printable byte in line"
        );
        let words: heapless::Vec<&str, 11> = ErrorCode::ALL.iter().map(|c| c.as_str()).collect();
        assert_eq!(
            &words[..],
            &[
                "SYNTAX",
                "RANGE",
                "TOOLONG",
                "BINARY",
                "STATE",
                "LINK",
                "UNSUPPORTED",
                "DENIED",
                "BUSY",
                "REFUSED",
                "STORAGE"
            ]
        );
    }
}
