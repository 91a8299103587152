//! Command ids of the manual's command table (000-147) and how safe each one is to send.
//!
//! The bridge sends only [`Class::Normal`] commands unless a person explicitly unlocks more
//! ([`is_allowed`] is its allow-list). The class of each command is decided from the manual
//! text; the reason is in a comment on its row. Ids that are not in the table (for example
//! 114, which revision N mentions but whose table entry is missing from this copy of the
//! manual) classify as `None` and are never allowed.

/// How a command may be used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Class {
    /// Meant for a CNC: queries, setpoints, and tests the supply runs under its own control
    /// (it refuses them while cutting or outside the required state).
    Normal,
    /// Marked "factory testing only" (or manufacturing-only) in the manual, with no direct
    /// effect on valves, contactors or interlocks.
    FactoryTestingOnly,
    /// Directly drives valves, relays, contactors, the pump or the chopper output, or
    /// defeats interlocks or closed-loop control.
    Dangerous,
}

/// One row of the command table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommandInfo {
    /// Command id.
    pub id: u16,
    /// Name as printed in the manual. Only host tools print it (feature `descriptions`); the
    /// board needs the class alone.
    #[cfg(feature = "descriptions")]
    pub name: &'static str,
    /// How the bridge treats it.
    pub class: Class,
    /// The systems the manual's "System" column names for it.
    pub systems: Systems,
}

/// The systems a command works on: the manual's "System" column (Manual Gas System, Auto
/// Gas System, MaxPro200) as bits. A manual gas console HPR answers 501 to what its column
/// does not name (058 SET_NOMINAL_AMPS: "Auto Gas System MaxPro200", line 149).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Systems(u8);

impl Systems {
    /// "Manual Gas System": an HPR with a manual gas console.
    pub const MANUAL_GAS: Systems = Systems(1);
    /// "Auto Gas System": an HPR with an automatic gas console.
    pub const AUTO_GAS: Systems = Systems(2);
    /// "MaxPro200".
    pub const MAXPRO200: Systems = Systems(4);

    /// True when every system of `other` is named.
    pub const fn contains(self, other: Systems) -> bool {
        other.0 != 0 && self.0 & other.0 == other.0
    }

    /// True when any system of `other` is named.
    pub const fn intersects(self, other: Systems) -> bool {
        self.0 & other.0 != 0
    }

    const fn or(self, other: Systems) -> Systems {
        Systems(self.0 | other.0)
    }
}

/// The systems `system` may be: its console when HELLO names one; an HPR whose identity names
/// none (`HYPERFORMANCE400XD`) may have either console.
pub const fn systems_of(system: &SystemId) -> Systems {
    match system {
        SystemId::MaxPro200 => Systems::MAXPRO200,
        SystemId::Hpr {
            console: Some(GasConsole::Manual),
            ..
        } => Systems::MANUAL_GAS,
        SystemId::Hpr {
            console: Some(GasConsole::Auto | GasConsole::AutoMix),
            ..
        } => Systems::AUTO_GAS,
        SystemId::Hpr { console: None, .. } => Systems::MANUAL_GAS.or(Systems::AUTO_GAS),
    }
}

/// True unless the manual says `system` does not take command `id`: the command's "System"
/// column names the system (for an HPR of unknown console, either console). Ids not in the
/// table are false.
pub fn accepts(id: u16, system: &SystemId) -> bool {
    command_info(id).is_some_and(|c| c.systems.intersects(systems_of(system)))
}

/// Command ids as constants.
#[allow(missing_docs)] // each name is the manual's command name
pub mod id {
    pub const HELLO: u16 = 0;
    pub const VERSION: u16 = 1;
    pub const GET_STATE: u16 = 2;
    pub const CURRENT_ERROR: u16 = 3;
    pub const REMOTE_MODE: u16 = 4;
    pub const READ_PLASMA_AMPS: u16 = 28;
    pub const SET_NOMINAL_AMPS: u16 = 58;
    pub const GAS_PREFLOW_TEST_START: u16 = 64;
    pub const GAS_PREFLOW_TEST_STOP: u16 = 65;
    pub const GAS_CUTFLOW_TEST_START: u16 = 66;
    pub const GAS_CUTFLOW_TEST_STOP: u16 = 67;
    pub const SOFTWARE_RESET: u16 = 68;
    pub const SET_CORNER_CURRENT: u16 = 70;
    pub const MANUAL_PUMP_CONTROL: u16 = 71;
    pub const GET_CONTROL_VOLTAGE: u16 = 72;
    pub const GET_IO_STATUS: u16 = 74;
    pub const SET_ALL_GAS_FLOWS: u16 = 78;
    pub const GET_PS_INFO: u16 = 79;
    pub const DOWNLOAD_SOFTWARE: u16 = 84;
    pub const WAKE: u16 = 85;
    pub const SLEEP: u16 = 86;
    pub const BROADCAST_MODE: u16 = 87;
    pub const READ_GAS_PRESSURES: u16 = 94;
    pub const SET_ALL_PARAMETERS: u16 = 95;
    pub const SET_INLET_GASES: u16 = 96;
    pub const READ_CORNER_CURRENT: u16 = 97;
    pub const GET_INLET_GASES: u16 = 98;
    pub const GET_GAS_FLOWS: u16 = 99;
    pub const GET_CONTROL_DATA: u16 = 100;
    pub const SET_IO_STATUS: u16 = 101;
    pub const SET_GAS_IO_FROM_PS: u16 = 102;
    pub const STOP_SENDING_CAN: u16 = 103;
    pub const SEND_CAN_REGSTATE: u16 = 104;
    pub const SEND_CAN_REGERROR: u16 = 105;
    pub const SEND_CAN_REG1FEEDBACK: u16 = 106;
    pub const SEND_CAN_PSWATCHDOG: u16 = 107;
    pub const SEND_CAN_PSERROR: u16 = 108;
    pub const SEND_CAN_PSSTATE: u16 = 109;
    pub const SEND_CAN_PS1SETPOINT: u16 = 110;
    pub const SEND_CAN_PS2SETPOINT: u16 = 111;
    pub const START_SENDING_CAN: u16 = 112;
    pub const SEND_CAN_PSFEEDBACK: u16 = 113;
    pub const GET_CONTROL1: u16 = 115;
    pub const GET_CONTROL2: u16 = 116;
    pub const READ_GAS_INPUTS_FROM_PS: u16 = 117;
    pub const GAS_DISPLAY_TEST_MODE: u16 = 118;
    pub const PS_ONLY_TEST_MODE: u16 = 119;
    pub const IGNORE_ALL_INTERLOCKS: u16 = 120;
    pub const LEAK_CHECK_MODE: u16 = 121;
    pub const READ_GAS_SWITCH: u16 = 122;
    pub const OVERRIDE_CURRENT: u16 = 123;
    pub const INDEX_MOTORVALVES: u16 = 124;
    pub const GET_TIMER_COUNTER: u16 = 125;
    pub const GET_INFO2: u16 = 126;
    pub const GET_INFO3: u16 = 127;
    pub const SEND_AUTO_GAS_CAN_MESSAGE: u16 = 128;
    pub const MOTOR_VALVES_IN_MAINT: u16 = 129;
    pub const SEND_METERING_CAN_MESSAGE: u16 = 130;
    pub const CLEAR_WARNINGS: u16 = 131;
    pub const READ_COOLANT_PRESSURE: u16 = 132;
    pub const GET_CONTROL_DATA3: u16 = 133;
    pub const READ_ERROR_LOG: u16 = 134;
    pub const CAN_LOOPBACK_TEST: u16 = 135;
    pub const SERIAL_RESPONSE_DELAY: u16 = 136;
    pub const SET_PROCESS: u16 = 137;
    pub const IS_SYSTEM_READY_FOR_START: u16 = 138;
    pub const SET_MFG_TEST_MODE: u16 = 139;
    pub const GET_MFG_TEST_MODE: u16 = 140;
    pub const GET_MFG_DATA1: u16 = 141;
    pub const GET_MFG_DATA2: u16 = 142;
    pub const SET_TEST_MODE: u16 = 143;
    pub const SET_MAINTENANCE_MODE: u16 = 144;
    pub const READ_TORCH_ID: u16 = 145;
    pub const FRONT_PANEL_LED_TEST: u16 = 146;
    pub const SET_REDCART_MODE: u16 = 147;
    /// Reply id: the command had a bad checksum (section III.d).
    pub const BAD_CHECKSUM: u16 = 500;
    /// Reply id: the command id is unknown (section III.d).
    pub const UNKNOWN_COMMAND: u16 = 501;
}

use super::identity::{GasConsole, SystemId};
use Class::{Dangerous, FactoryTestingOnly, Normal};

/// A row; without the `descriptions` feature the name is dropped at compile time.
const fn cmd(id: u16, name: &'static str, class: Class, systems: Systems) -> CommandInfo {
    #[cfg(not(feature = "descriptions"))]
    let _ = name;
    CommandInfo {
        id,
        #[cfg(feature = "descriptions")]
        name,
        class,
        systems,
    }
}

// The "System" column's combinations.
const ALL: Systems = Systems::MANUAL_GAS
    .or(Systems::AUTO_GAS)
    .or(Systems::MAXPRO200);
const HPR: Systems = Systems::MANUAL_GAS.or(Systems::AUTO_GAS);
const AUTO_MAXPRO: Systems = Systems::AUTO_GAS.or(Systems::MAXPRO200);
const AUTO: Systems = Systems::AUTO_GAS;
const MANUAL: Systems = Systems::MANUAL_GAS;
const MAXPRO: Systems = Systems::MAXPRO200;
/// 084 DOWNLOAD_SOFTWARE: "TBD", implemented on no system.
const NONE: Systems = Systems(0);

/// Every command in the manual's table, ascending id, with its class and the systems of its
/// "System" column (the board-level factory commands 103-113 by the boards they name: power
/// supply and manual console boards as HPR, manual gas control board as MANUAL; 132, 133,
/// 135 and 136, named for one HPR model, as HPR).
pub const COMMANDS: &[CommandInfo] = &[
    cmd(id::HELLO, "HELLO", Normal, ALL),
    cmd(id::VERSION, "VERSION", Normal, ALL),
    cmd(id::GET_STATE, "GET_STATE", Normal, ALL),
    cmd(id::CURRENT_ERROR, "CURRENT_ERROR", Normal, ALL),
    cmd(id::REMOTE_MODE, "REMOTE_MODE", Normal, ALL),
    cmd(id::READ_PLASMA_AMPS, "READ_PLASMA_AMPS", Normal, HPR),
    cmd(
        id::SET_NOMINAL_AMPS,
        "SET_NOMINAL_AMPS",
        Normal,
        AUTO_MAXPRO,
    ),
    // 064-067: gas tests the CNC's test buttons use; the supply runs them and refuses them
    // while cutting ("Not allowed when cutting").
    cmd(
        id::GAS_PREFLOW_TEST_START,
        "GAS_PREFLOW_TEST_START",
        Normal,
        HPR,
    ),
    cmd(
        id::GAS_PREFLOW_TEST_STOP,
        "GAS_PREFLOW_TEST_STOP",
        Normal,
        HPR,
    ),
    cmd(
        id::GAS_CUTFLOW_TEST_START,
        "GAS_CUTFLOW_TEST_START",
        Normal,
        HPR,
    ),
    cmd(
        id::GAS_CUTFLOW_TEST_STOP,
        "GAS_CUTFLOW_TEST_STOP",
        Normal,
        HPR,
    ),
    // Clears errors; "not active when the arc is on".
    cmd(id::SOFTWARE_RESET, "SOFTWARE_RESET", Normal, ALL),
    cmd(id::SET_CORNER_CURRENT, "SET_CORNER_CURRENT", Normal, HPR),
    // Overrides the software's control of the coolant pump motor.
    cmd(
        id::MANUAL_PUMP_CONTROL,
        "MANUAL_PUMP_CONTROL",
        Dangerous,
        HPR,
    ),
    cmd(id::GET_CONTROL_VOLTAGE, "GET_CONTROL_VOLTAGE", Normal, HPR),
    cmd(id::GET_IO_STATUS, "GET_IO_STATUS", Normal, HPR),
    // Setpoints; the supply's own control loop drives the valves.
    cmd(
        id::SET_ALL_GAS_FLOWS,
        "SET_ALL_GAS_FLOWS",
        Normal,
        AUTO_MAXPRO,
    ),
    cmd(id::GET_PS_INFO, "GET_PS_INFO", Normal, ALL),
    // Replaces the supply's firmware (not implemented on HPR; data format "TBD").
    cmd(id::DOWNLOAD_SOFTWARE, "DOWNLOAD_SOFTWARE", Dangerous, NONE),
    // 085-087: multi-drop line control.
    cmd(id::WAKE, "WAKE", Normal, HPR),
    cmd(id::SLEEP, "SLEEP", Normal, HPR),
    cmd(id::BROADCAST_MODE, "BROADCAST MODE", Normal, HPR),
    cmd(id::READ_GAS_PRESSURES, "READ_GAS_PRESSURES", Normal, HPR),
    // Refused while cutting (states 4-10); a gas change makes the supply purge.
    cmd(
        id::SET_ALL_PARAMETERS,
        "SET_ALL_PARAMETERS",
        Normal,
        AUTO_MAXPRO,
    ),
    cmd(id::SET_INLET_GASES, "SET_INLET_GASES", Normal, AUTO_MAXPRO),
    cmd(id::READ_CORNER_CURRENT, "READ_CORNER_CURRENT", Normal, HPR),
    cmd(id::GET_INLET_GASES, "GET_INLET_GASES", Normal, ALL),
    cmd(id::GET_GAS_FLOWS, "GET_GAS_FLOWS", Normal, AUTO),
    // Read-only diagnostics, not marked factory-only.
    cmd(id::GET_CONTROL_DATA, "GET_CONTROL_DATA", Normal, ALL),
    // Turns each output on or off: pilot arc relay, igniter contactor, pump, (factory data)
    // every gas solenoid and motor valve.
    cmd(id::SET_IO_STATUS, "SET_IO_STATUS", Dangerous, ALL),
    // Gas valves directly; the manual warns fuel and oxidizer can be mixed.
    cmd(id::SET_GAS_IO_FROM_PS, "SET_GAS_IO_FROM_PS", Dangerous, HPR),
    // 103-113: "Factory testing only" CAN bus board tests.
    cmd(
        id::STOP_SENDING_CAN,
        "STOP_SENDING_CAN",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::SEND_CAN_REGSTATE,
        "SEND_CAN_REGSTATE",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::SEND_CAN_REGERROR,
        "SEND_CAN_REGERROR",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::SEND_CAN_REG1FEEDBACK,
        "SEND_CAN_REG1FEEDBACK",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::SEND_CAN_PSWATCHDOG,
        "SEND_CAN_PSWATCHDOG",
        FactoryTestingOnly,
        MANUAL,
    ),
    cmd(
        id::SEND_CAN_PSERROR,
        "SEND_CAN_PSERROR",
        FactoryTestingOnly,
        MANUAL,
    ),
    cmd(
        id::SEND_CAN_PSSTATE,
        "SEND_CAN_PSSTATE",
        FactoryTestingOnly,
        MANUAL,
    ),
    cmd(
        id::SEND_CAN_PS1SETPOINT,
        "SEND_CAN_PS1SETPOINT",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::SEND_CAN_PS2SETPOINT,
        "SEND_CAN_PS2SETPOINT",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::START_SENDING_CAN,
        "START_SENDING_CAN",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::SEND_CAN_PSFEEDBACK,
        "SEND_CAN_PSFEEDBACK",
        FactoryTestingOnly,
        MANUAL,
    ),
    // 115/116: "Factory testing only" reads.
    cmd(id::GET_CONTROL1, "GET_CONTROL1", FactoryTestingOnly, HPR),
    cmd(id::GET_CONTROL2, "GET_CONTROL2", FactoryTestingOnly, HPR),
    // Read-only gas console inputs, not marked factory-only.
    cmd(
        id::READ_GAS_INPUTS_FROM_PS,
        "READ_GAS_INPUTS_FROM_PS",
        Normal,
        HPR,
    ),
    // Factory testing only; display test patterns, no power or gas.
    cmd(
        id::GAS_DISPLAY_TEST_MODE,
        "GAS_DISPLAY_TEST_MODE",
        FactoryTestingOnly,
        MANUAL,
    ),
    // Factory testing only AND "will force the system to ignore all interlocks".
    cmd(id::PS_ONLY_TEST_MODE, "PS_ONLY_TEST_MODE", Dangerous, HPR),
    // Ignores all power supply errors; only re-powering clears it.
    cmd(
        id::IGNORE_ALL_INTERLOCKS,
        "IGNORE_ALL_INTERLOCKS",
        Dangerous,
        HPR,
    ),
    // Supply-run leak test, accepted only in IDLE2 (state 3).
    cmd(id::LEAK_CHECK_MODE, "LEAK_CHECK_MODE", Normal, HPR),
    cmd(id::READ_GAS_SWITCH, "READ_GAS_SWITCH", Normal, MANUAL),
    // Factory testing only; overrides the arc current setting, format and limits undocumented.
    cmd(id::OVERRIDE_CURRENT, "OVERRIDE_CURRENT", Dangerous, HPR),
    // Moves a motor valve directly by ADC counts.
    cmd(id::INDEX_MOTORVALVES, "INDEX_MOTORVALVES", Dangerous, AUTO),
    cmd(id::GET_TIMER_COUNTER, "GET_TIMER_COUNTER", Normal, HPR),
    // 126/127: the auto gas control board split of 079's "For Factory Testing Only" block.
    cmd(id::GET_INFO2, "GET_INFO2", FactoryTestingOnly, AUTO),
    cmd(id::GET_INFO3, "GET_INFO3", FactoryTestingOnly, AUTO),
    // "FOR FACTORY USE ONLY": raw CAN frame to the selection console.
    cmd(
        id::SEND_AUTO_GAS_CAN_MESSAGE,
        "SEND AUTO GAS CAN MESSAGE",
        FactoryTestingOnly,
        AUTO,
    ),
    // Factory only AND switches off closed-loop motor valve control. (Printed "VAVLES".)
    cmd(
        id::MOTOR_VALVES_IN_MAINT,
        "MOTOR VALVES IN MAINT",
        Dangerous,
        AUTO,
    ),
    // "FOR FACTORY USE ONLY": raw CAN frame to the metering console.
    cmd(
        id::SEND_METERING_CAN_MESSAGE,
        "SEND METERING CAN MESSAGE",
        FactoryTestingOnly,
        AUTO,
    ),
    cmd(id::CLEAR_WARNINGS, "CLEAR WARNINGS", Normal, HPR),
    // Read-only (HPR260).
    cmd(
        id::READ_COOLANT_PRESSURE,
        "READ COOLANT PRESSURE",
        Normal,
        HPR,
    ),
    // Read-only (HPR400).
    cmd(id::GET_CONTROL_DATA3, "GET CONTROL DATA3", Normal, HPR),
    cmd(id::READ_ERROR_LOG, "READ ERROR LOG", Normal, HPR),
    // Factory testing only: needs the manufacturing loopback fixture.
    cmd(
        id::CAN_LOOPBACK_TEST,
        "CAN LOOPBACK TEST",
        FactoryTestingOnly,
        HPR,
    ),
    cmd(
        id::SERIAL_RESPONSE_DELAY,
        "SERIAL RESPONSE DELAY",
        Normal,
        HPR,
    ),
    // Accepted only in state 2 or 3.
    cmd(id::SET_PROCESS, "SET PROCESS", Normal, MAXPRO),
    cmd(
        id::IS_SYSTEM_READY_FOR_START,
        "IS SYSTEM READY FOR START",
        Normal,
        MAXPRO,
    ),
    // Manufacturing tests that power the choppers (power-up, pilot arc, full power).
    cmd(
        id::SET_MFG_TEST_MODE,
        "SET MFG TEST MODE",
        Dangerous,
        MAXPRO,
    ),
    // 140-142: read-only manufacturing data, not marked factory-only.
    cmd(id::GET_MFG_TEST_MODE, "GET MFG TEST MODE", Normal, MAXPRO),
    cmd(id::GET_MFG_DATA1, "GET MFG DATA1", Normal, MAXPRO),
    cmd(id::GET_MFG_DATA2, "GET MFG DATA2", Normal, MAXPRO),
    // Supply-run gas tests, accepted only in state 3 (READY FOR START).
    cmd(id::SET_TEST_MODE, "SET TEST MODE", Normal, MAXPRO),
    // Maintenance mode is what lets 101 SET_IO_STATUS drive the outputs.
    cmd(
        id::SET_MAINTENANCE_MODE,
        "SET MAINTENANCE MODE",
        Dangerous,
        MAXPRO,
    ),
    cmd(id::READ_TORCH_ID, "READ TORCH ID", Normal, MAXPRO),
    // Front panel LEDs only (and only in maintenance mode).
    cmd(
        id::FRONT_PANEL_LED_TEST,
        "FRONT PANEL LED TEST",
        Normal,
        MAXPRO,
    ),
    // "Similar to maintenance mode (id #144)" with the user interface still enabled.
    cmd(id::SET_REDCART_MODE, "SET REDCART MODE", Dangerous, MAXPRO),
];

/// The table row for `id`, if the manual's command table has it.
pub fn command_info(id: u16) -> Option<&'static CommandInfo> {
    COMMANDS
        .binary_search_by_key(&id, |c| c.id)
        .ok()
        .and_then(|i| COMMANDS.get(i))
}

/// Class of command `id`; `None` for ids not in the manual's command table.
pub fn classify(id: u16) -> Option<Class> {
    command_info(id).map(|c| c.class)
}

/// Name of command `id` as printed in the manual.
#[cfg(feature = "descriptions")]
pub fn command_name(id: u16) -> Option<&'static str> {
    command_info(id).map(|c| c.name)
}

/// The bridge's default allow-list: only [`Class::Normal`] commands.
pub fn is_allowed(id: u16) -> bool {
    classify(id) == Some(Class::Normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_sorted_and_sized() {
        assert!(COMMANDS.windows(2).all(|w| w[0].id < w[1].id));
        assert_eq!(COMMANDS.first().map(|c| c.id), Some(0));
        assert_eq!(COMMANDS.last().map(|c| c.id), Some(147));
        assert_eq!(COMMANDS.len(), 75);
    }

    #[test]
    fn dangerous_commands_are_never_allowed() {
        for id in [71, 84, 101, 102, 119, 120, 123, 124, 129, 139, 144, 147] {
            assert_eq!(classify(id), Some(Class::Dangerous), "{id}");
            assert!(!is_allowed(id));
        }
        for id in 103..=113 {
            assert_eq!(classify(id), Some(Class::FactoryTestingOnly), "{id}");
        }
        for id in [115, 116, 118, 126, 127, 128, 130, 135] {
            assert_eq!(classify(id), Some(Class::FactoryTestingOnly), "{id}");
        }
    }

    #[test]
    fn unknown_ids() {
        for id in [5, 27, 114, 148, 500, 501, 999, 1000, u16::MAX] {
            assert_eq!(classify(id), None, "{id}");
            assert!(!is_allowed(id));
        }
        #[cfg(feature = "descriptions")]
        assert_eq!(command_name(120), Some("IGNORE_ALL_INTERLOCKS"));
    }

    /// HPR manual (002_72b43a5685974c77.txt), the "System" column: line 148 (028: Manual Gas
    /// System Auto Gas System), 149 (058: Auto Gas System MaxPro200), 165 (078: Auto Gas
    /// System MaxPro200), 168 (079: all three), 180 (095: Auto Gas System MaxPro200), 185
    /// (099: Auto Gas System), 192 (100: HPR Manual, HPR Auto, MaxPro200), 252 (122: Manual
    /// Gas System), 275 (137: MaxPro200).
    #[test]
    fn the_system_column() {
        let (m, a, x) = (Systems::MANUAL_GAS, Systems::AUTO_GAS, Systems::MAXPRO200);
        let names = |id| {
            let s = command_info(id).map(|c| c.systems).unwrap();
            [m, a, x].map(|one| s.contains(one))
        };
        assert_eq!(names(28), [true, true, false]);
        assert_eq!(names(58), [false, true, true]);
        assert_eq!(names(78), [false, true, true]);
        assert_eq!(names(79), [true, true, true]);
        assert_eq!(names(95), [false, true, true]);
        assert_eq!(names(99), [false, true, false]);
        assert_eq!(names(100), [true, true, true]);
        assert_eq!(names(122), [true, false, false]);
        assert_eq!(names(137), [false, false, true]);
        assert_eq!(names(84), [false, false, false]);
        let manual = SystemId::parse(b"HYPERFORMANCE130MANUAL").unwrap();
        let auto = SystemId::parse(b"HYPERFORMANCE260AUTOMIX").unwrap();
        let unknown = SystemId::parse(b"HYPERFORMANCE400XD").unwrap();
        assert!(!accepts(id::SET_NOMINAL_AMPS, &manual));
        assert!(accepts(id::SET_NOMINAL_AMPS, &auto));
        assert!(accepts(id::SET_NOMINAL_AMPS, &unknown));
        assert!(accepts(id::SET_NOMINAL_AMPS, &SystemId::MaxPro200));
        assert!(accepts(id::READ_GAS_SWITCH, &manual));
        assert!(!accepts(id::READ_GAS_SWITCH, &auto));
        assert!(!accepts(id::READ_PLASMA_AMPS, &SystemId::MaxPro200));
        assert!(!accepts(id::SET_PROCESS, &unknown));
        assert!(!accepts(999, &auto));
        // Every command a CNC uses is taken by some system.
        assert!(
            COMMANDS
                .iter()
                .all(|c| c.id == id::DOWNLOAD_SOFTWARE || c.systems != NONE)
        );
    }

    #[test]
    fn cnc_commands_are_allowed() {
        for id in [
            0, 1, 2, 3, 4, 28, 58, 64, 65, 66, 67, 68, 70, 72, 74, 78, 79, 85, 86, 87, 94, 95, 96,
            97, 98, 99, 121, 122, 125, 131, 134, 136, 137, 138, 143, 145,
        ] {
            assert!(is_allowed(id), "{id}");
        }
    }
}
