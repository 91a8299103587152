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
        error_info(self.0).map(|e| e.name)
    }

    /// Description from section IV, if the manual lists this code.
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
    /// Description as printed.
    pub description: &'static str,
}

/// Section IV, in the manual's order (ascending code).
pub const ERROR_CODES: &[ErrorInfo] = &[
    ErrorInfo {
        code: 0,
        name: "NO ERROR",
        description: "System is ready to run",
    },
    ErrorInfo {
        code: 9,
        name: "FLOW SWITCH TEST",
        description: "When the pump is restarted after a pump timeout (30 minutes without a start signal) the system will test the flow switch to make sure there is sufficient flow before firing the torch.",
    },
    ErrorInfo {
        code: 12,
        name: "TEST IN PROGRESS",
        description: "One in the gas test modes is running",
    },
    ErrorInfo {
        code: 13,
        name: "TEST PASSED",
        description: "The test completed successfully",
    },
    ErrorInfo {
        code: 14,
        name: "CUT GAS CHANNEL #1 FAIL",
        description: "The gas pressure is dropping on channel #1, indicating a leak",
    },
    ErrorInfo {
        code: 15,
        name: "CUT GAS CHANNEL #2 FAIL",
        description: "The gas pressure is dropping on channel #2, indicating a leak",
    },
    ErrorInfo {
        code: 16,
        name: "PLASMA RAMPDOWN FAIL",
        description: "Plasma pressure did not decrease in the allotted time",
    },
    ErrorInfo {
        code: 17,
        name: "SHIELD RAMPDOWN FAIL",
        description: "Shield pressure did not decrease in the allotted time",
    },
    ErrorInfo {
        code: 18,
        name: "PUMP OVER PRESSURE",
        description: "Pump output has exceeded 200 psi",
    },
    ErrorInfo {
        code: 20,
        name: "NO PILOT ARC",
        description: "No current detected from choppers before 1-second timeout",
    },
    ErrorInfo {
        code: 21,
        name: "NO ARC TRANSFER",
        description: "No transfer signal detected before 300-msec timeout",
    },
    ErrorInfo {
        code: 24,
        name: "LOST CURRENT CH1",
        description: "After transfer lost chopper current signal",
    },
    ErrorInfo {
        code: 25,
        name: "LOST CURRENT CH2",
        description: "After transfer lost chopper current signal",
    },
    ErrorInfo {
        code: 26,
        name: "LOST TRANSFER",
        description: "After transfer lost the transfer signal",
    },
    ErrorInfo {
        code: 27,
        name: "LOST PHASE",
        description: "When main contactor is engaged no phase ok input",
    },
    ErrorInfo {
        code: 28,
        name: "LOST CURRENT CH3",
        description: "After transfer lost chopper current signal",
    },
    ErrorInfo {
        code: 30,
        name: "GAS SYSTEM ERROR",
        description: "A failure had a occurred in the gas system",
    },
    ErrorInfo {
        code: 31,
        name: "START LOST",
        description: "Start signal was removed before steady state operation",
    },
    ErrorInfo {
        code: 32,
        name: "HOLD TIMEOUT",
        description: "Hold signal was applied for longer than 60 seconds",
    },
    ErrorInfo {
        code: 33,
        name: "PRE CHARGE TIMEOUT",
        description: "Gas console was not able to charge the gas lines to the correct value",
    },
    ErrorInfo {
        code: 34,
        name: "LOST CURRENT CH4",
        description: "After transfer lost chopper current signal",
    },
    ErrorInfo {
        code: 42,
        name: "N2 PURGE LOW PRESSURE ERROR",
        description: "Low N2 gas pressure while purging because of switching from a fuel gas process to an oxidizing process or vice versa",
    },
    ErrorInfo {
        code: 44,
        name: "LOW PLASMA GAS PRESSURE",
        description: "Gas pressure under lower limit (15 psi preflow, 50 psi outflow)",
    },
    ErrorInfo {
        code: 45,
        name: "HIGH PLASMA GAS PRESSURE",
        description: "Gas pressure over upper limit (110 psi)",
    },
    ErrorInfo {
        code: 46,
        name: "LOW LINE VOLTAGE",
        description: "Line voltage is under lower limit (-15%)",
    },
    ErrorInfo {
        code: 47,
        name: "HIGH LINE VOLTAGE",
        description: "Line voltage is over upper limit (+15%)",
    },
    ErrorInfo {
        code: 48,
        name: "CAN ERROR",
        description: "An error occurred with the CAN communication system",
    },
    ErrorInfo {
        code: 50,
        name: "START ON AT INIT",
        description: "Start signal input is active during power up",
    },
    ErrorInfo {
        code: 53,
        name: "LOW SHIELD GAS PRESSURE",
        description: "Gas pressure is under lower limit (2 psi)",
    },
    ErrorInfo {
        code: 54,
        name: "HIGH SHIELD GAS PRESSURE",
        description: "Gas pressure is over upper limit (110 psi)",
    },
    ErrorInfo {
        code: 55,
        name: "MV 1 INLET PRESSURE",
        description: "Motor valve 1 inlet pressure is less than 90 psi or greater than 130 psi.",
    },
    ErrorInfo {
        code: 56,
        name: "MV 2 INLET PRESSURE",
        description: "Motor valve 2 inlet pressure is less than 90 psi or greater than 130 psi.",
    },
    ErrorInfo {
        code: 57,
        name: "CUT GAS 1 PRESSURE",
        description: "In the selection console, cut gas 1 outlet pressure is less than 90 psi or greater than 130 psi.",
    },
    ErrorInfo {
        code: 58,
        name: "CUT GAS 2 PRESSURE",
        description: "In the selection console, if cut gas 2 outlet pressure is less than 90 psi for non mixing or less than 20 psi when mixing or greater than 130 psi.",
    },
    ErrorInfo {
        code: 60,
        name: "LOW COOLANT FLOW",
        description: "Coolant flow is present but is less than the required 0.6 gpm",
    },
    ErrorInfo {
        code: 61,
        name: "NO PLASMA GAS TYPE",
        description: "Plasma gas has not been selected",
    },
    ErrorInfo {
        code: 62,
        name: "NO SHIELD GAS TYPE",
        description: "Shield gas has not been selected or system is in test mode",
    },
    ErrorInfo {
        code: 65,
        name: "CHOPPER1 OVERTEMP",
        description: "Chopper #1 overheated",
    },
    ErrorInfo {
        code: 66,
        name: "CHOPPER2 OVERTEMP",
        description: "Chopper #2 overheated",
    },
    ErrorInfo {
        code: 67,
        name: "MAGNETICS OVERTEMP",
        description: "Transformer has overheated",
    },
    ErrorInfo {
        code: 71,
        name: "COOLANT OVERTEMP",
        description: "Torch coolant has overheated",
    },
    ErrorInfo {
        code: 72,
        name: "AUTOMATIC GAS CONTROL BOARD OVERTEMP",
        description: "Control board has exceeded 90 degrees C",
    },
    ErrorInfo {
        code: 73,
        name: "CHOPPER3 OVERTEMP",
        description: "Chopper #3 overheated",
    },
    ErrorInfo {
        code: 74,
        name: "CHOPPER4 OVERTEMP",
        description: "Chopper #4 overheated",
    },
    ErrorInfo {
        code: 75,
        name: "LEM 3 CURRENT LOW",
        description: "Current is less than 10 amps during the chopper test",
    },
    ErrorInfo {
        code: 76,
        name: "LEM 4 CURRENT LOW",
        description: "Current is less than 10 amps during the chopper test",
    },
    ErrorInfo {
        code: 93,
        name: "NO COOLANT FLOW",
        description: "Coolant flow is less than 0.6 gpm or greater than 3.0 gpm",
    },
    ErrorInfo {
        code: 95,
        name: "LEM 4 CURRENT HIGH",
        description: "Current has exceeded 35 amps during chopper test",
    },
    ErrorInfo {
        code: 99,
        name: "CHOPPER1 OVERTEMP AT INIT",
        description: "Chopper #1 is indicating overtemp during powerup",
    },
    ErrorInfo {
        code: 100,
        name: "CHOPPER2 OVERTEMP AT INIT",
        description: "Chopper #2 is indicating overtemp during power up",
    },
    ErrorInfo {
        code: 101,
        name: "MAGNETICS OVERTEMP AT INIT",
        description: "Transformer is indicating overtemp during powerup",
    },
    ErrorInfo {
        code: 102,
        name: "LEM SENSOR A FAULT",
        description: "Chopper A current signal is invalid",
    },
    ErrorInfo {
        code: 103,
        name: "LEM 1 CURRENT HIGH",
        description: "Current has exceeded 35 amps during chopper test",
    },
    ErrorInfo {
        code: 104,
        name: "LEM 2 CURRENT HIGH",
        description: "Current has exceeded 35 amps during chopper test",
    },
    ErrorInfo {
        code: 105,
        name: "LEM 1 CURRENT LOW",
        description: "Current is less than 10 amps during the chopper test",
    },
    ErrorInfo {
        code: 106,
        name: "LEM 2 CURRENT LOW",
        description: "Current is less than 10 amps during the chopper test",
    },
    ErrorInfo {
        code: 107,
        name: "LEM 3 CURRENT HIGH",
        description: "Current has exceeded 35 amps during chopper test",
    },
    ErrorInfo {
        code: 108,
        name: "TRANSFER AT INIT",
        description: "The system has detected current on the work lead during power up",
    },
    ErrorInfo {
        code: 109,
        name: "COOLANT FLOW AT INIT",
        description: "Coolant flow is greater than 0.3 gpm when pump is off.",
    },
    ErrorInfo {
        code: 111,
        name: "COOLANT OVERTEMP AT INIT",
        description: "Coolant is indicating overtemp during powerup",
    },
    ErrorInfo {
        code: 116,
        name: "WATCHDOG INTERLOCK",
        description: "CAN communication error",
    },
    ErrorInfo {
        code: 123,
        name: "MV 1 ERROR",
        description: "Motor valve 1 did not move into position within 60 seconds",
    },
    ErrorInfo {
        code: 124,
        name: "MV 2 ERROR",
        description: "Motor valve 2 did not move into position within 60 seconds",
    },
    ErrorInfo {
        code: 133,
        name: "UNKNOWN GAS CONSOLE TYPE",
        description: "The power supply control board does not recognize the gas console installed or has not received a CAN message identifying the type of console installed",
    },
    ErrorInfo {
        code: 134,
        name: "CHOPPER 1 OVERCURRENT",
        description: "Chopper 1 current feedback has exceeded 160 amps",
    },
    ErrorInfo {
        code: 138,
        name: "CHOPPER 2 OVERCURRENT",
        description: "Chopper 2 current feedback has exceeded 160 amps",
    },
    ErrorInfo {
        code: 139,
        name: "PURGE TIMEOUT ERROR",
        description: "The purge cycle did not complete within 3 minutes",
    },
    ErrorInfo {
        code: 140,
        name: "PRESSURE TRANSDUCER #1 ERROR",
        description: "Selection Console - Motor Valve #1 inlet Metering Console - Plasma gas outlet",
    },
    ErrorInfo {
        code: 141,
        name: "PRESSURE TRANSDUCER #2 ERROR",
        description: "Selection Console - Motor Valve #2 inlet Metering Console - Shield gas outlet",
    },
    ErrorInfo {
        code: 142,
        name: "PRESSURE TRANSDUCER #3 ERROR",
        description: "Selection Console - Cut Gas 1 outlet Metering Console - Cut Gas 1 inlet",
    },
    ErrorInfo {
        code: 143,
        name: "PRESSURE TRANSDUCER #4 ERROR",
        description: "Selection Console - Cut Gas 2 outlet Metering Console - Cut Gas 2 inlet",
    },
    ErrorInfo {
        code: 144,
        name: "MANUAL GAS CONSOLE INTERNAL FLASH ERROR",
        description: "DSP memory is not working properly",
    },
    ErrorInfo {
        code: 145,
        name: "AUTO GAS CONSOLE INTERNAL FLASH ERROR",
        description: "DSP memory is not working properly",
    },
    ErrorInfo {
        code: 146,
        name: "CHOPPER #3 OVERTEMP AT INIT",
        description: "Chopper #3 is indicating over temp during power up",
    },
    ErrorInfo {
        code: 147,
        name: "CHOPPER #4 OVERTEMP AT INIT",
        description: "Chopper #4 is indicating over temp during power up",
    },
    ErrorInfo {
        code: 151,
        name: "SOFTWARE FAIL",
        description: "Software has detected an incorrect state or condition",
    },
    ErrorInfo {
        code: 152,
        name: "INTERNAL FLASH ERROR",
        description: "DSP memory is not working properly",
    },
    ErrorInfo {
        code: 153,
        name: "PS EEPROM ERROR",
        description: "EEPROM memory on power supply board not working",
    },
    ErrorInfo {
        code: 154,
        name: "CHOPPER 3 OVER CURRENT",
        description: "Chopper 3 current feedback has exceeded 160 amps",
    },
    ErrorInfo {
        code: 155,
        name: "CHOPPER 4 OVER CURRENT",
        description: "Chopper 4 current feedback has exceeded 160 amps",
    },
    ErrorInfo {
        code: 156,
        name: "CHOPPER 2 CURRENT AT INIT",
        description: "Chopper 2 current signal is active on powerup",
    },
    ErrorInfo {
        code: 157,
        name: "CHOPPER 3 CURRENT AT INIT",
        description: "Chopper 3 current signal is active on powerup",
    },
    ErrorInfo {
        code: 158,
        name: "CHOPPER 4 CURRENT AT INIT",
        description: "Chopper 4 current signal is active on powerup",
    },
    ErrorInfo {
        code: 159,
        name: "MOTOR DRIVE FAULT",
        description: "Motor drive board power module is indicating an alarm - This can be comparable to \"blowing a fuse\" - does not necessarily indicate a problem with the board.",
    },
    ErrorInfo {
        code: 160,
        name: "HPR COOLER CAN FAULT",
        description: "Communications between the control board and the pump/motor drive board was interrupted for greater than 1 second.",
    },
    ErrorInfo {
        code: 180,
        name: "SELECTION CONSOLE CAN TIMEOUT",
        description: "Power supply has not received a CAN message from the selection console within 1 second",
    },
    ErrorInfo {
        code: 181,
        name: "METERING CONSOLE CAN TIMEOUT",
        description: "Power supply has not received a CAN message from the metering console within 1 second",
    },
    ErrorInfo {
        code: 190,
        name: "LEM SENSOR B FAULT",
        description: "Chopper B current signal is invalid",
    },
];

/// The table row for `code`, if the manual lists it.
pub fn error_info(code: u16) -> Option<&'static ErrorInfo> {
    ERROR_CODES
        .binary_search_by_key(&code, |e| e.code)
        .ok()
        .and_then(|i| ERROR_CODES.get(i))
}

/// Name of error `code`, if the manual lists it.
pub fn error_name(code: u16) -> Option<&'static str> {
    error_info(code).map(|e| e.name)
}

/// Description of error `code`, if the manual lists it.
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
    fn lookups() {
        assert_eq!(error_name(0), Some("NO ERROR"));
        assert_eq!(ErrorCode(116).name(), Some("WATCHDOG INTERLOCK"));
        assert_eq!(error_name(50), Some("START ON AT INIT"));
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
