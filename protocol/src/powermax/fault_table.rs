//! The fault tables, transcribed row by row.
//!
//! Texts are kept ASCII (they may be forwarded to a CNC terminal): typographic quotes and
//! dashes became ASCII, the check-mark symbol is spelled out. A model restriction printed as a
//! leading "(Powermax65/85/105 SYNC)" is moved to [`SyncModels`].

use super::fault::{FaultInfo, StepsRequired, SyncModels};

const fn row(code: u16, models: SyncModels, steps: StepsRequired, text: &'static str) -> FaultInfo {
    FaultInfo {
        code,
        text,
        steps,
        models,
    }
}

use StepsRequired::{No, Recommended, Yes};
use SyncModels::{All, Powermax45, Powermax65_85_105};

/// SYNC guide, Table 6 "Fault codes and descriptions": all 66 rows, in table order.
pub(super) static SYNC_FAULTS: [FaultInfo; 66] = [
    // Operational faults
    row(0, All, No, "There is no active fault."),
    row(
        110,
        All,
        Recommended,
        "The operating mode is incorrect or not permitted for the installed cartridge.",
    ),
    row(
        111,
        All,
        Recommended,
        "The output current (A) is incorrect or not permitted for the installed cartridge.",
    ),
    // The "Steps Required to Remove?" cell of 0-11-2 is empty in the source; its siblings
    // 0-11-0 and 0-11-1 (the same remote-setting check) read "No, but recommended".
    row(
        112,
        All,
        Recommended,
        "The gas pressure is incorrect or not permitted. The permitted gas pressure relates to the selected process and operating mode, and to the installed torch, torch lead, and cartridge.",
    ),
    row(121, All, Recommended, "The gas pressure output is low."),
    row(122, All, Recommended, "The gas pressure output is high."),
    row(
        123,
        All,
        Recommended,
        "The gas pressure output is not stable.",
    ),
    row(
        130,
        All,
        Recommended,
        "The alternating current (AC) input power is not stable.",
    ),
    row(
        140,
        All,
        Yes,
        "There is a problem with the cartridge installation. The cartridge cannot send data to the plasma power supply.",
    ),
    row(141, All, Recommended, "The cartridge is not recognized."),
    row(
        199,
        All,
        Yes,
        "The input power stopped. Or, power PCB hardware protection occurred for components in the plasma power supply.",
    ),
    row(
        200,
        All,
        Recommended,
        "The gas pressure is lower than the minimum pressure for the selected process, operating mode, torch, lead length, and cartridge type.",
    ),
    row(
        210,
        Powermax65_85_105,
        Yes,
        "The gas flow stopped during cutting (an excessive change to arc voltage occurred).",
    ),
    row(220, All, Yes, "There is no gas supply input."),
    row(
        300,
        All,
        Yes,
        "There is a torch stuck open (TSO) condition.",
    ),
    row(
        301,
        All,
        Yes,
        "There is a torch stuck closed (TSC) condition.",
    ),
    row(
        320,
        Powermax65_85_105,
        Yes,
        "The system sensed that the cartridge in use is at end-of-life.",
    ),
    row(
        321,
        All,
        Recommended,
        "A cartridge is installed that had the 0-32-0 fault before and is at end-of-life.",
    ),
    row(
        400,
        All,
        Yes,
        "The boost power-factor correction insulated-gate bipolar-transistor (PFC IGBT) is too cold. This is applicable to CSA and CE/CCC 230 V - 400 V models only.",
    ),
    row(
        401,
        All,
        Yes,
        "The boost PFC IGBT is too hot. This is applicable to CSA and CE/CCC 230 V - 400 V models only.",
    ),
    row(402, All, Yes, "The inverter IGBT is too cold."),
    row(403, All, Yes, "The inverter IGBT is too hot."),
    row(
        404,
        Powermax45,
        Yes,
        "An internal temperature communication failure occurred.",
    ),
    row(405, Powermax45, Yes, "Duty cycle exceeded."),
    row(
        500,
        All,
        Yes,
        "The cartridge is off, the torch was disconnected when you set the plasma power supply to ON (I), or the torch was in the yellow lock (X) position during a restart.",
    ),
    row(
        501,
        All,
        Yes,
        "The torch-lock switch is set to the yellow lock (X) position.",
    ),
    // OCR moved the check-mark symbol to the end of the sentence; it belongs in the brackets.
    row(
        502,
        All,
        No,
        "The torch-lock switch is set to the green \"ready to fire\" (check mark) position, but the torch is not prepared to fire.",
    ),
    row(
        503,
        All,
        No,
        "This code shows momentarily while the system reads data from the cartridge.",
    ),
    row(
        510,
        All,
        Yes,
        "The plasma power supply was receiving a signal to start cutting at the same time that the power switch was set to ON (I). This is sometimes referred to as a \"stuck start.\"",
    ),
    row(520, All, Yes, "The torch is not connected."),
    row(600, All, Yes, "An AC input voltage phase loss occurred."),
    row(601, All, Yes, "The AC input voltage is too low."),
    row(602, All, Yes, "The AC input voltage is too high."),
    row(610, All, Yes, "The AC input is not stable."),
    row(
        980,
        Powermax65_85_105,
        Recommended,
        "An internal communication failure occurred between the LCD/control PCB and the DSP PCB.",
    ),
    row(
        981,
        All,
        Recommended,
        "A radio frequency (RF) communication failure occurred between the cartridge and the torch.",
    ),
    row(
        982,
        All,
        Recommended,
        "A communication failure occurred between the torch and the plasma power supply.",
    ),
    // Internal component faults
    row(
        1000,
        All,
        Yes,
        "A digital-signal processor (DSP) PCB fault occurred.",
    ),
    row(1200, All, Yes, "An input/output (I/O) fault occurred."),
    row(
        1300,
        Powermax65_85_105,
        Yes,
        "A flash memory fault occurred.",
    ),
    row(
        2000,
        All,
        Yes,
        "The analog-to-digital converter (ADC) value is out of range.",
    ),
    row(
        2010,
        Powermax65_85_105,
        Yes,
        "The auxiliary switch is disconnected.",
    ),
    row(
        2100,
        All,
        Yes,
        "The inverter IGBT temperature sensor is open.",
    ),
    row(
        2101,
        All,
        Yes,
        "The inverter IGBT temperature sensor short-circuited.",
    ),
    row(2110, All, Yes, "The pressure sensor is open."),
    row(2111, All, Yes, "The pressure sensor short-circuited."),
    row(
        2200,
        Powermax65_85_105,
        Yes,
        "The DSP PCB does not recognize the torch.",
    ),
    row(3000, All, Yes, "The DC bus voltage (VBUS) is out of range."),
    row(
        3100,
        All,
        Yes,
        "The fan speed is less than the minimum speed.",
    ),
    row(3101, All, Yes, "A fan fault occurred."),
    row(3110, All, Yes, "The PFC IGBT temperature sensor is open."),
    row(
        3111,
        All,
        Yes,
        "The PFC IGBT temperature sensor short-circuited.",
    ),
    row(
        3112,
        All,
        Yes,
        "There is a PFC IGBT temperature sensor circuit fault.",
    ),
    row(
        3200,
        Powermax65_85_105,
        Yes,
        "The fill valve is not connected.",
    ),
    row(
        3201,
        Powermax65_85_105,
        Yes,
        "The dump valve is not connected.",
    ),
    row(
        3202,
        Powermax65_85_105,
        Yes,
        "The plasma power supply does not recognize the solenoid valve electronic regulator.",
    ),
    row(
        3203,
        Powermax65_85_105,
        Yes,
        "The solenoid valve electronic regulator is not receiving power.",
    ),
    row(
        3410,
        Powermax65_85_105,
        Yes,
        "A driver integrated circuit (IC) fault occurred.",
    ),
    row(
        3420,
        Powermax65_85_105,
        Yes,
        "The 5 VDC or 24 VDC supply is out of range.",
    ),
    row(
        3421,
        Powermax65_85_105,
        Yes,
        "The 18 VDC supply is out of range.",
    ),
    row(
        3430,
        Powermax65_85_105,
        Yes,
        "The inverter capacitors are not balanced.",
    ),
    row(
        3441,
        Powermax65_85_105,
        Yes,
        "The PFC IGBT current is too high.",
    ),
    row(
        3511,
        All,
        Yes,
        "An inverter IGBT saturation fault occurred. The inverter current is too high.",
    ),
    row(
        3520,
        All,
        Yes,
        "A short-circuit caused high-current distortion in the inverter IGBT. This is sometimes referred to as a shoot-through.",
    ),
    row(
        3600,
        All,
        Yes,
        "The DSP PCB does not recognize the power PCB.",
    ),
    row(
        3700,
        Powermax65_85_105,
        Yes,
        "There is an internal serial communications fault between the DSP PCB and power PCB.",
    ),
];

/// Legacy Powermax65/85 guide (807220), "Fault Codes": all 18 rows, in table order. The guide
/// calls the list partial ("summarizes some fault codes") and has no action column.
pub(super) static LEGACY_FAULTS: [(u16, &str); 18] = [
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
