//! Error codes (manual section IV), as returned by 003 CURRENT_ERROR, 079 GET_PS_INFO and
//! 134 READ ERROR LOG.
//!
//! The table is complete as printed in the manual, including the codes revision N added for
//! the HPR400 (028, 034, 073-076, 095, 107, 146, 147, 154, 155, 157-160). Names and
//! descriptions are kept as printed.

/// An error code as the supply reports it (0 = no error).
///
/// Kept as a number so an unknown code from newer firmware still parses; [`name`](Self::name)
/// says whether the manual knows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorCode(pub u16);

impl ErrorCode {
    /// 000 NO ERROR.
    pub const NONE: ErrorCode = ErrorCode(0);

    /// Name from section IV, if the manual lists this code.
    pub fn name(self) -> Option<&'static str> {
        error_name(self.0)
    }

    /// Description from section IV, if the manual lists this code.
    #[cfg(feature = "descriptions")]
    pub fn description(self) -> Option<&'static str> {
        error_info(self.0).map(|e| e.description)
    }

    /// True for a code other than 0.
    pub fn is_error(self) -> bool {
        self.0 != 0
    }

    /// Codes 1-42: the ones 131 CLEAR WARNINGS clears ("error codes less than #43").
    pub fn is_warning(self) -> bool {
        (1..43).contains(&self.0)
    }

    /// Codes above 79: with state 14 (SHUTDOWN) this is the "shutdown error condition" in
    /// which an HPR accepts 068 SOFTWARE_RESET.
    pub fn is_shutdown_error(self) -> bool {
        self.0 > 79
    }
}

/// One row of the error table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ErrorInfo {
    /// Code number.
    pub code: u16,
    /// Name as printed.
    pub name: &'static str,
    /// Description as printed. Only host tools print it: the board shows the name, so its
    /// image leaves the ~5 KB of descriptions out (feature `descriptions`).
    #[cfg(feature = "descriptions")]
    pub description: &'static str,
}

/// A row; without the `descriptions` feature the text is dropped at compile time.
const fn row(code: u16, name: &'static str, description: &'static str) -> ErrorInfo {
    #[cfg(not(feature = "descriptions"))]
    let _ = description;
    ErrorInfo {
        code,
        name,
        #[cfg(feature = "descriptions")]
        description,
    }
}

/// The table, written once: the full rows ([`ERROR_CODES`], host tools) and a compact name
/// index for [`error_name`]. The board image keeps only the index: 4 bytes a row and the names
/// one after the other, instead of a 12-byte row with a string reference each.
macro_rules! error_table {
    ($(($code:literal, $name:literal, $description:literal $(,)?)),* $(,)?) => {
        /// Section IV, in the manual's order (ascending code).
        pub const ERROR_CODES: &[ErrorInfo] = &[$(row($code, $name, $description)),*];

        /// Every name, in table order.
        const NAMES: &str = concat!($($name),*);

        /// Each code with the end of its name in [`NAMES`] (the start is the row before's end).
        static NAME_ENDS: [(u16, u16); ERROR_CODES.len()] = crate::text_table::text_ends([$(($code, $name.len())),*]);
    };
}

error_table![
    (0, "NO ERROR", "System is ready to run"),
    (
        9,
        "FLOW SWITCH TEST",
        "When the pump is restarted after a pump timeout (30 minutes without a start signal) the system will test the flow switch to make sure there is sufficient flow before firing the torch.",
    ),
    (
        12,
        "TEST IN PROGRESS",
        "One in the gas test modes is running",
    ),
    (13, "TEST PASSED", "The test completed successfully"),
    (
        14,
        "CUT GAS CHANNEL #1 FAIL",
        "The gas pressure is dropping on channel #1, indicating a leak",
    ),
    (
        15,
        "CUT GAS CHANNEL #2 FAIL",
        "The gas pressure is dropping on channel #2, indicating a leak",
    ),
    (
        16,
        "PLASMA RAMPDOWN FAIL",
        "Plasma pressure did not decrease in the allotted time",
    ),
    (
        17,
        "SHIELD RAMPDOWN FAIL",
        "Shield pressure did not decrease in the allotted time",
    ),
    (18, "PUMP OVER PRESSURE", "Pump output has exceeded 200 psi"),
    (
        20,
        "NO PILOT ARC",
        "No current detected from choppers before 1-second timeout",
    ),
    (
        21,
        "NO ARC TRANSFER",
        "No transfer signal detected before 300-msec timeout",
    ),
    (
        24,
        "LOST CURRENT CH1",
        "After transfer lost chopper current signal",
    ),
    (
        25,
        "LOST CURRENT CH2",
        "After transfer lost chopper current signal",
    ),
    (
        26,
        "LOST TRANSFER",
        "After transfer lost the transfer signal",
    ),
    (
        27,
        "LOST PHASE",
        "When main contactor is engaged no phase ok input",
    ),
    (
        28,
        "LOST CURRENT CH3",
        "After transfer lost chopper current signal",
    ),
    (
        30,
        "GAS SYSTEM ERROR",
        "A failure had a occurred in the gas system",
    ),
    (
        31,
        "START LOST",
        "Start signal was removed before steady state operation",
    ),
    (
        32,
        "HOLD TIMEOUT",
        "Hold signal was applied for longer than 60 seconds",
    ),
    (
        33,
        "PRE CHARGE TIMEOUT",
        "Gas console was not able to charge the gas lines to the correct value",
    ),
    (
        34,
        "LOST CURRENT CH4",
        "After transfer lost chopper current signal",
    ),
    (
        42,
        "N2 PURGE LOW PRESSURE ERROR",
        "Low N2 gas pressure while purging because of switching from a fuel gas process to an oxidizing process or vice versa",
    ),
    (
        44,
        "LOW PLASMA GAS PRESSURE",
        "Gas pressure under lower limit (15 psi preflow, 50 psi outflow)",
    ),
    (
        45,
        "HIGH PLASMA GAS PRESSURE",
        "Gas pressure over upper limit (110 psi)",
    ),
    (
        46,
        "LOW LINE VOLTAGE",
        "Line voltage is under lower limit (-15%)",
    ),
    (
        47,
        "HIGH LINE VOLTAGE",
        "Line voltage is over upper limit (+15%)",
    ),
    (
        48,
        "CAN ERROR",
        "An error occurred with the CAN communication system",
    ),
    (
        50,
        "START ON AT INIT",
        "Start signal input is active during power up",
    ),
    (
        53,
        "LOW SHIELD GAS PRESSURE",
        "Gas pressure is under lower limit (2 psi)",
    ),
    (
        54,
        "HIGH SHIELD GAS PRESSURE",
        "Gas pressure is over upper limit (110 psi)",
    ),
    (
        55,
        "MV 1 INLET PRESSURE",
        "Motor valve 1 inlet pressure is less than 90 psi or greater than 130 psi.",
    ),
    (
        56,
        "MV 2 INLET PRESSURE",
        "Motor valve 2 inlet pressure is less than 90 psi or greater than 130 psi.",
    ),
    (
        57,
        "CUT GAS 1 PRESSURE",
        "In the selection console, cut gas 1 outlet pressure is less than 90 psi or greater than 130 psi.",
    ),
    (
        58,
        "CUT GAS 2 PRESSURE",
        "In the selection console, if cut gas 2 outlet pressure is less than 90 psi for non mixing or less than 20 psi when mixing or greater than 130 psi.",
    ),
    (
        60,
        "LOW COOLANT FLOW",
        "Coolant flow is present but is less than the required 0.6 gpm",
    ),
    (61, "NO PLASMA GAS TYPE", "Plasma gas has not been selected"),
    (
        62,
        "NO SHIELD GAS TYPE",
        "Shield gas has not been selected or system is in test mode",
    ),
    (65, "CHOPPER1 OVERTEMP", "Chopper #1 overheated"),
    (66, "CHOPPER2 OVERTEMP", "Chopper #2 overheated"),
    (67, "MAGNETICS OVERTEMP", "Transformer has overheated"),
    (71, "COOLANT OVERTEMP", "Torch coolant has overheated"),
    (
        72,
        "AUTOMATIC GAS CONTROL BOARD OVERTEMP",
        "Control board has exceeded 90 degrees C",
    ),
    (73, "CHOPPER3 OVERTEMP", "Chopper #3 overheated"),
    (74, "CHOPPER4 OVERTEMP", "Chopper #4 overheated"),
    (
        75,
        "LEM 3 CURRENT LOW",
        "Current is less than 10 amps during the chopper test",
    ),
    (
        76,
        "LEM 4 CURRENT LOW",
        "Current is less than 10 amps during the chopper test",
    ),
    (
        93,
        "NO COOLANT FLOW",
        "Coolant flow is less than 0.6 gpm or greater than 3.0 gpm",
    ),
    (
        95,
        "LEM 4 CURRENT HIGH",
        "Current has exceeded 35 amps during chopper test",
    ),
    (
        99,
        "CHOPPER1 OVERTEMP AT INIT",
        "Chopper #1 is indicating overtemp during powerup",
    ),
    (
        100,
        "CHOPPER2 OVERTEMP AT INIT",
        "Chopper #2 is indicating overtemp during power up",
    ),
    (
        101,
        "MAGNETICS OVERTEMP AT INIT",
        "Transformer is indicating overtemp during powerup",
    ),
    (
        102,
        "LEM SENSOR A FAULT",
        "Chopper A current signal is invalid",
    ),
    (
        103,
        "LEM 1 CURRENT HIGH",
        "Current has exceeded 35 amps during chopper test",
    ),
    (
        104,
        "LEM 2 CURRENT HIGH",
        "Current has exceeded 35 amps during chopper test",
    ),
    (
        105,
        "LEM 1 CURRENT LOW",
        "Current is less than 10 amps during the chopper test",
    ),
    (
        106,
        "LEM 2 CURRENT LOW",
        "Current is less than 10 amps during the chopper test",
    ),
    (
        107,
        "LEM 3 CURRENT HIGH",
        "Current has exceeded 35 amps during chopper test",
    ),
    (
        108,
        "TRANSFER AT INIT",
        "The system has detected current on the work lead during power up",
    ),
    (
        109,
        "COOLANT FLOW AT INIT",
        "Coolant flow is greater than 0.3 gpm when pump is off.",
    ),
    (
        111,
        "COOLANT OVERTEMP AT INIT",
        "Coolant is indicating overtemp during powerup",
    ),
    (116, "WATCHDOG INTERLOCK", "CAN communication error"),
    (
        123,
        "MV 1 ERROR",
        "Motor valve 1 did not move into position within 60 seconds",
    ),
    (
        124,
        "MV 2 ERROR",
        "Motor valve 2 did not move into position within 60 seconds",
    ),
    (
        133,
        "UNKNOWN GAS CONSOLE TYPE",
        "The power supply control board does not recognize the gas console installed or has not received a CAN message identifying the type of console installed",
    ),
    (
        134,
        "CHOPPER 1 OVERCURRENT",
        "Chopper 1 current feedback has exceeded 160 amps",
    ),
    (
        138,
        "CHOPPER 2 OVERCURRENT",
        "Chopper 2 current feedback has exceeded 160 amps",
    ),
    (
        139,
        "PURGE TIMEOUT ERROR",
        "The purge cycle did not complete within 3 minutes",
    ),
    (
        140,
        "PRESSURE TRANSDUCER #1 ERROR",
        "Selection Console - Motor Valve #1 inlet Metering Console - Plasma gas outlet",
    ),
    (
        141,
        "PRESSURE TRANSDUCER #2 ERROR",
        "Selection Console - Motor Valve #2 inlet Metering Console - Shield gas outlet",
    ),
    (
        142,
        "PRESSURE TRANSDUCER #3 ERROR",
        "Selection Console - Cut Gas 1 outlet Metering Console - Cut Gas 1 inlet",
    ),
    (
        143,
        "PRESSURE TRANSDUCER #4 ERROR",
        "Selection Console - Cut Gas 2 outlet Metering Console - Cut Gas 2 inlet",
    ),
    (
        144,
        "MANUAL GAS CONSOLE INTERNAL FLASH ERROR",
        "DSP memory is not working properly",
    ),
    (
        145,
        "AUTO GAS CONSOLE INTERNAL FLASH ERROR",
        "DSP memory is not working properly",
    ),
    (
        146,
        "CHOPPER #3 OVERTEMP AT INIT",
        "Chopper #3 is indicating over temp during power up",
    ),
    (
        147,
        "CHOPPER #4 OVERTEMP AT INIT",
        "Chopper #4 is indicating over temp during power up",
    ),
    (
        151,
        "SOFTWARE FAIL",
        "Software has detected an incorrect state or condition",
    ),
    (
        152,
        "INTERNAL FLASH ERROR",
        "DSP memory is not working properly",
    ),
    (
        153,
        "PS EEPROM ERROR",
        "EEPROM memory on power supply board not working",
    ),
    (
        154,
        "CHOPPER 3 OVER CURRENT",
        "Chopper 3 current feedback has exceeded 160 amps",
    ),
    (
        155,
        "CHOPPER 4 OVER CURRENT",
        "Chopper 4 current feedback has exceeded 160 amps",
    ),
    (
        156,
        "CHOPPER 2 CURRENT AT INIT",
        "Chopper 2 current signal is active on powerup",
    ),
    (
        157,
        "CHOPPER 3 CURRENT AT INIT",
        "Chopper 3 current signal is active on powerup",
    ),
    (
        158,
        "CHOPPER 4 CURRENT AT INIT",
        "Chopper 4 current signal is active on powerup",
    ),
    (
        159,
        "MOTOR DRIVE FAULT",
        "Motor drive board power module is indicating an alarm - This can be comparable to \"blowing a fuse\" - does not necessarily indicate a problem with the board.",
    ),
    (
        160,
        "HPR COOLER CAN FAULT",
        "Communications between the control board and the pump/motor drive board was interrupted for greater than 1 second.",
    ),
    (
        180,
        "SELECTION CONSOLE CAN TIMEOUT",
        "Power supply has not received a CAN message from the selection console within 1 second",
    ),
    (
        181,
        "METERING CONSOLE CAN TIMEOUT",
        "Power supply has not received a CAN message from the metering console within 1 second",
    ),
    (
        190,
        "LEM SENSOR B FAULT",
        "Chopper B current signal is invalid",
    ),
];

/// The table row for `code`, if the manual lists it.
pub fn error_info(code: u16) -> Option<&'static ErrorInfo> {
    ERROR_CODES
        .binary_search_by_key(&code, |e| e.code)
        .ok()
        .and_then(|i| ERROR_CODES.get(i))
}

/// Name of error `code`, if the manual lists it (from the compact index, see [`error_table`]).
pub fn error_name(code: u16) -> Option<&'static str> {
    crate::text_table::text_of(NAMES, &NAME_ENDS, code)
}

/// Description of error `code`, if the manual lists it.
#[cfg(feature = "descriptions")]
pub fn error_description(code: u16) -> Option<&'static str> {
    error_info(code).map(|e| e.description)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_sorted_and_complete() {
        assert!(ERROR_CODES.windows(2).all(|w| w[0].code < w[1].code));
        assert_eq!(ERROR_CODES.len(), 88);
        // Codes added in revision N (HPR400) are all present.
        for code in [
            28, 34, 73, 74, 75, 76, 95, 107, 146, 147, 154, 155, 157, 158, 159, 160,
        ] {
            assert!(error_name(code).is_some(), "{code}");
        }
    }

    #[test]
    fn name_index_matches_the_rows() {
        assert_eq!(NAME_ENDS.len(), ERROR_CODES.len());
        for info in ERROR_CODES {
            assert_eq!(error_name(info.code), Some(info.name), "{}", info.code);
        }
        assert_eq!(usize::from(NAME_ENDS[NAME_ENDS.len() - 1].1), NAMES.len());
    }

    #[test]
    fn lookups() {
        assert_eq!(error_name(0), Some("NO ERROR"));
        assert_eq!(ErrorCode(116).name(), Some("WATCHDOG INTERLOCK"));
        assert_eq!(error_name(50), Some("START ON AT INIT"));
        #[cfg(feature = "descriptions")]
        assert_eq!(
            error_description(190),
            Some("Chopper B current signal is invalid")
        );
        assert_eq!(error_name(1), None);
        assert_eq!(error_name(999), None);
        assert!(ErrorCode(42).is_warning() && !ErrorCode(43).is_warning());
        assert!(!ErrorCode(0).is_warning() && !ErrorCode(0).is_error());
        assert!(ErrorCode(80).is_shutdown_error() && !ErrorCode(79).is_shutdown_error());
    }
}
