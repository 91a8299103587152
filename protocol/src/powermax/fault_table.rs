//! The fault tables, transcribed row by row.
//!
//! Texts are kept ASCII (they may be forwarded to a CNC terminal): typographic quotes and
//! dashes became ASCII, the check-mark symbol is spelled out. A model restriction printed as a
//! leading "(Powermax65/85/105 SYNC)" is moved to [`SyncModels`].

use super::fault::{StepsRequired, SyncModels};

/// A row of the SYNC table as the image stores it: the text is a span of
/// [`SYNC_FAULT_TEXTS`] ending at `end` (starting where the row before ends). Six bytes a row
/// instead of a 12-byte row with a string reference.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct SyncRow {
    pub code: u16,
    pub end: u16,
    pub steps: StepsRequired,
    pub models: SyncModels,
}

/// The SYNC table, written once: the row index and the texts back to back.
macro_rules! sync_faults {
    ($(($code:literal, $models:expr, $steps:expr, $text:literal $(,)?)),* $(,)?) => {
        /// Every text, in table order.
        pub(super) const SYNC_FAULT_TEXTS: &str = concat!($($text),*);

        /// SYNC guide, Table 6 "Fault codes and descriptions": all 66 rows, in table order.
        pub(super) static SYNC_FAULTS: [SyncRow; 66] =
            sync_rows([$(($code, $models, $steps, $text.len())),*]);
    };
}

/// The rows with running text ends (`(code, models, steps, length)` in).
const fn sync_rows<const N: usize>(
    rows: [(u16, SyncModels, StepsRequired, usize); N],
) -> [SyncRow; N] {
    let mut out = [SyncRow {
        code: 0,
        end: 0,
        steps: StepsRequired::No,
        models: SyncModels::All,
    }; N];
    let mut end = 0;
    let mut i = 0;
    while i < N {
        // Const evaluation only (the table), never input: an index out of range would fail
        // the build, not the bridge.
        #[allow(clippy::indexing_slicing)]
        {
            let (code, models, steps, len) = rows[i];
            end += len;
            out[i] = SyncRow {
                code,
                end: end as u16,
                steps,
                models,
            };
        }
        i += 1;
    }
    out
}

use StepsRequired::{No, Recommended, Yes};
use SyncModels::{All, Powermax45, Powermax65_85_105};

sync_faults![
    // Operational faults
    (0, All, No, "There is no active fault."),
    (
        110,
        All,
        Recommended,
        "The operating mode is incorrect or not permitted for the installed cartridge.",
    ),
    (
        111,
        All,
        Recommended,
        "The output current (A) is incorrect or not permitted for the installed cartridge.",
    ),
    // The "Steps Required to Remove?" cell of 0-11-2 is empty in the source; its siblings
    // 0-11-0 and 0-11-1 (the same remote-setting check) read "No, but recommended".
    (
        112,
        All,
        Recommended,
        "The gas pressure is incorrect or not permitted. The permitted gas pressure relates to the selected process and operating mode, and to the installed torch, torch lead, and cartridge.",
    ),
    (121, All, Recommended, "The gas pressure output is low."),
    (122, All, Recommended, "The gas pressure output is high."),
    (
        123,
        All,
        Recommended,
        "The gas pressure output is not stable.",
    ),
    (
        130,
        All,
        Recommended,
        "The alternating current (AC) input power is not stable.",
    ),
    (
        140,
        All,
        Yes,
        "There is a problem with the cartridge installation. The cartridge cannot send data to the plasma power supply.",
    ),
    (141, All, Recommended, "The cartridge is not recognized."),
    (
        199,
        All,
        Yes,
        "The input power stopped. Or, power PCB hardware protection occurred for components in the plasma power supply.",
    ),
    (
        200,
        All,
        Recommended,
        "The gas pressure is lower than the minimum pressure for the selected process, operating mode, torch, lead length, and cartridge type.",
    ),
    (
        210,
        Powermax65_85_105,
        Yes,
        "The gas flow stopped during cutting (an excessive change to arc voltage occurred).",
    ),
    (220, All, Yes, "There is no gas supply input."),
    (
        300,
        All,
        Yes,
        "There is a torch stuck open (TSO) condition.",
    ),
    (
        301,
        All,
        Yes,
        "There is a torch stuck closed (TSC) condition.",
    ),
    (
        320,
        Powermax65_85_105,
        Yes,
        "The system sensed that the cartridge in use is at end-of-life.",
    ),
    (
        321,
        All,
        Recommended,
        "A cartridge is installed that had the 0-32-0 fault before and is at end-of-life.",
    ),
    (
        400,
        All,
        Yes,
        "The boost power-factor correction insulated-gate bipolar-transistor (PFC IGBT) is too cold. This is applicable to CSA and CE/CCC 230 V - 400 V models only.",
    ),
    (
        401,
        All,
        Yes,
        "The boost PFC IGBT is too hot. This is applicable to CSA and CE/CCC 230 V - 400 V models only.",
    ),
    (402, All, Yes, "The inverter IGBT is too cold."),
    (403, All, Yes, "The inverter IGBT is too hot."),
    (
        404,
        Powermax45,
        Yes,
        "An internal temperature communication failure occurred.",
    ),
    (405, Powermax45, Yes, "Duty cycle exceeded."),
    (
        500,
        All,
        Yes,
        "The cartridge is off, the torch was disconnected when you set the plasma power supply to ON (I), or the torch was in the yellow lock (X) position during a restart.",
    ),
    (
        501,
        All,
        Yes,
        "The torch-lock switch is set to the yellow lock (X) position.",
    ),
    // OCR moved the check-mark symbol to the end of the sentence; it belongs in the brackets.
    (
        502,
        All,
        No,
        "The torch-lock switch is set to the green \"ready to fire\" (check mark) position, but the torch is not prepared to fire.",
    ),
    (
        503,
        All,
        No,
        "This code shows momentarily while the system reads data from the cartridge.",
    ),
    (
        510,
        All,
        Yes,
        "The plasma power supply was receiving a signal to start cutting at the same time that the power switch was set to ON (I). This is sometimes referred to as a \"stuck start.\"",
    ),
    (520, All, Yes, "The torch is not connected."),
    (600, All, Yes, "An AC input voltage phase loss occurred."),
    (601, All, Yes, "The AC input voltage is too low."),
    (602, All, Yes, "The AC input voltage is too high."),
    (610, All, Yes, "The AC input is not stable."),
    (
        980,
        Powermax65_85_105,
        Recommended,
        "An internal communication failure occurred between the LCD/control PCB and the DSP PCB.",
    ),
    (
        981,
        All,
        Recommended,
        "A radio frequency (RF) communication failure occurred between the cartridge and the torch.",
    ),
    (
        982,
        All,
        Recommended,
        "A communication failure occurred between the torch and the plasma power supply.",
    ),
    // Internal component faults
    (
        1000,
        All,
        Yes,
        "A digital-signal processor (DSP) PCB fault occurred.",
    ),
    (1200, All, Yes, "An input/output (I/O) fault occurred."),
    (
        1300,
        Powermax65_85_105,
        Yes,
        "A flash memory fault occurred.",
    ),
    (
        2000,
        All,
        Yes,
        "The analog-to-digital converter (ADC) value is out of range.",
    ),
    (
        2010,
        Powermax65_85_105,
        Yes,
        "The auxiliary switch is disconnected.",
    ),
    (
        2100,
        All,
        Yes,
        "The inverter IGBT temperature sensor is open.",
    ),
    (
        2101,
        All,
        Yes,
        "The inverter IGBT temperature sensor short-circuited.",
    ),
    (2110, All, Yes, "The pressure sensor is open."),
    (2111, All, Yes, "The pressure sensor short-circuited."),
    (
        2200,
        Powermax65_85_105,
        Yes,
        "The DSP PCB does not recognize the torch.",
    ),
    (3000, All, Yes, "The DC bus voltage (VBUS) is out of range."),
    (
        3100,
        All,
        Yes,
        "The fan speed is less than the minimum speed.",
    ),
    (3101, All, Yes, "A fan fault occurred."),
    (3110, All, Yes, "The PFC IGBT temperature sensor is open."),
    (
        3111,
        All,
        Yes,
        "The PFC IGBT temperature sensor short-circuited.",
    ),
    (
        3112,
        All,
        Yes,
        "There is a PFC IGBT temperature sensor circuit fault.",
    ),
    (
        3200,
        Powermax65_85_105,
        Yes,
        "The fill valve is not connected.",
    ),
    (
        3201,
        Powermax65_85_105,
        Yes,
        "The dump valve is not connected.",
    ),
    (
        3202,
        Powermax65_85_105,
        Yes,
        "The plasma power supply does not recognize the solenoid valve electronic regulator.",
    ),
    (
        3203,
        Powermax65_85_105,
        Yes,
        "The solenoid valve electronic regulator is not receiving power.",
    ),
    (
        3410,
        Powermax65_85_105,
        Yes,
        "A driver integrated circuit (IC) fault occurred.",
    ),
    (
        3420,
        Powermax65_85_105,
        Yes,
        "The 5 VDC or 24 VDC supply is out of range.",
    ),
    (
        3421,
        Powermax65_85_105,
        Yes,
        "The 18 VDC supply is out of range.",
    ),
    (
        3430,
        Powermax65_85_105,
        Yes,
        "The inverter capacitors are not balanced.",
    ),
    (
        3441,
        Powermax65_85_105,
        Yes,
        "The PFC IGBT current is too high.",
    ),
    (
        3511,
        All,
        Yes,
        "An inverter IGBT saturation fault occurred. The inverter current is too high.",
    ),
    (
        3520,
        All,
        Yes,
        "A short-circuit caused high-current distortion in the inverter IGBT. This is sometimes referred to as a shoot-through.",
    ),
    (
        3600,
        All,
        Yes,
        "The DSP PCB does not recognize the power PCB.",
    ),
    (
        3700,
        Powermax65_85_105,
        Yes,
        "There is an internal serial communications fault between the DSP PCB and power PCB.",
    ),
];

/// The legacy list, written once: the texts back to back and a (code, end) index, 4 bytes a
/// row instead of a 12-byte (code, text) pair.
macro_rules! legacy_faults {
    ($(($code:literal, $text:literal)),* $(,)?) => {
        /// Every text, in list order.
        pub(super) const LEGACY_FAULT_TEXTS: &str = concat!($($text),*);

        /// Legacy Powermax65/85 guide (807220), "Fault Codes": all 18 rows, in table order,
        /// each code with the end of its text in [`LEGACY_FAULT_TEXTS`]. The guide calls the
        /// list partial ("summarizes some fault codes") and has no action column.
        pub(super) static LEGACY_FAULTS: [(u16, u16); 18] =
            crate::text_table::text_ends([$(($code, $text.len())),*]);
    };
}

legacy_faults![
    (110, "Invalid cut mode setting"),
    (111, "Current setting value is out of range"),
    (112, "Gas pressure setting value is out of range"),
    (120, "Low input gas pressure"),
    (130, "AC input unstable warning"),
    (190, "Power board hardware protection"),
    (200, "Low gas pressure"),
    (210, "Gas flow lost while cutting"),
    (220, "No gas input"),
    (300, "Torch consumables stuck"),
    (400, "Over temperature"),
    (500, "Retaining cap off"),
    (510, "Start/trigger signal on at power-up"),
    (520, "No torch connected to the power supply."),
    (600, "AC input voltage error"),
    // The source reads "Arc input unstable, shutdown": an OCR slip for "AC", as the
    // neighbouring 0-60-0 and the SYNC table's 0-61-0 ("The AC input is not stable") show.
    (610, "AC input unstable, shutdown"),
    (980, "Internal communication error"),
    (990, "System hardware fault - service required"),
];
