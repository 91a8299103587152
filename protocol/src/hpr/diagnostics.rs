//! Typed replies of the diagnostic reads a technician uses: 100 GET_CONTROL_DATA (both forms),
//! 117 READ_GAS_INPUTS_FROM_PS, 132 READ COOLANT PRESSURE, 133 GET CONTROL DATA3 and the
//! MaxPro200's 141/142 GET MFG DATA1/2 (the two halves of its 100 reply).
//!
//! Every tagged field is a tag and four digits (`CAT0482`, `flow0100`), as the manual's
//! samples and field lists show them; the values are kept raw, in the unit the manual gives.
//!
//! Only host tools read most of these, so they are behind the `diagnostics` feature: the board
//! image leaves them out (1.6 KB of flash). 141 is the exception: the bridge reads the
//! MaxPro200's measured gas pressures from it (`GASTEST CHECK`).

use super::command::id;
use super::field::{DataWriter, Fields};
use crate::{Error, Result};

/// A diagnostic read request; none has data.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DiagnosticRead {
    /// 100 GET_CONTROL_DATA.
    #[cfg(feature = "diagnostics")]
    ControlData,
    /// 117 READ_GAS_INPUTS_FROM_PS.
    #[cfg(feature = "diagnostics")]
    GasInputs,
    /// 132 READ COOLANT PRESSURE (HPR260).
    #[cfg(feature = "diagnostics")]
    CoolantPressure,
    /// 133 GET CONTROL DATA3 (HPR400).
    #[cfg(feature = "diagnostics")]
    ControlData3,
    /// 141 GET MFG DATA1 (MaxPro200).
    MfgData1,
    /// 142 GET MFG DATA2 (MaxPro200).
    #[cfg(feature = "diagnostics")]
    MfgData2,
}

impl DiagnosticRead {
    /// The command id.
    pub const fn id(self) -> u16 {
        match self {
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::ControlData => id::GET_CONTROL_DATA,
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::GasInputs => id::READ_GAS_INPUTS_FROM_PS,
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::CoolantPressure => id::READ_COOLANT_PRESSURE,
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::ControlData3 => id::GET_CONTROL_DATA3,
            DiagnosticRead::MfgData1 => id::GET_MFG_DATA1,
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::MfgData2 => id::GET_MFG_DATA2,
        }
    }

    /// The read with command id `command`, if it is one.
    pub const fn from_id(command: u16) -> Option<Self> {
        Some(match command {
            #[cfg(feature = "diagnostics")]
            id::GET_CONTROL_DATA => DiagnosticRead::ControlData,
            #[cfg(feature = "diagnostics")]
            id::READ_GAS_INPUTS_FROM_PS => DiagnosticRead::GasInputs,
            #[cfg(feature = "diagnostics")]
            id::READ_COOLANT_PRESSURE => DiagnosticRead::CoolantPressure,
            #[cfg(feature = "diagnostics")]
            id::GET_CONTROL_DATA3 => DiagnosticRead::ControlData3,
            id::GET_MFG_DATA1 => DiagnosticRead::MfgData1,
            #[cfg(feature = "diagnostics")]
            id::GET_MFG_DATA2 => DiagnosticRead::MfgData2,
            _ => return None,
        })
    }
}

/// The reply to a [`DiagnosticRead`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DiagnosticReply {
    /// 100, HPR form: chopper, line and coolant readings.
    #[cfg(feature = "diagnostics")]
    ControlData(ControlData),
    /// 100, MaxPro200 form: 141's and 142's fields.
    #[cfg(feature = "diagnostics")]
    MaxProControlData(MaxProControlData),
    /// 117: the gas console's inputs.
    #[cfg(feature = "diagnostics")]
    GasConsoleInputs(GasConsoleInputs),
    /// 132: coolant pressure, raw A/D counts.
    #[cfg(feature = "diagnostics")]
    CoolantPressure(CoolantCounts),
    /// 133: the HPR400's third and fourth choppers.
    #[cfg(feature = "diagnostics")]
    ControlData3(ControlData3),
    /// 141: the first half of the MaxPro200's control data.
    MfgData1(MfgData1),
    /// 142: the second half of the MaxPro200's control data.
    #[cfg(feature = "diagnostics")]
    MfgData2(MfgData2),
}

impl DiagnosticReply {
    /// The command id the reply echoes.
    pub const fn id(&self) -> u16 {
        match self {
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::ControlData(_) | DiagnosticReply::MaxProControlData(_) => {
                id::GET_CONTROL_DATA
            }
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::GasConsoleInputs(_) => id::READ_GAS_INPUTS_FROM_PS,
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::CoolantPressure(_) => id::READ_COOLANT_PRESSURE,
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::ControlData3(_) => id::GET_CONTROL_DATA3,
            DiagnosticReply::MfgData1(_) => id::GET_MFG_DATA1,
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::MfgData2(_) => id::GET_MFG_DATA2,
        }
    }

    /// The reply of `command` from its `data` (whose fields `f` reads); the caller checks
    /// that every field was used. [`Error::Unsupported`] for another command.
    pub(super) fn parse(command: u16, data: &[u8], f: &mut Fields<'_>) -> Result<Self> {
        #[cfg(not(feature = "diagnostics"))]
        let _ = data;
        let read = DiagnosticRead::from_id(command).ok_or(Error::Unsupported)?;
        Ok(match read {
            #[cfg(feature = "diagnostics")]
            // Told apart like 079: the MaxPro200's tags are lower case.
            DiagnosticRead::ControlData if data.first().is_some_and(u8::is_ascii_lowercase) => {
                DiagnosticReply::MaxProControlData(MaxProControlData::parse(f)?)
            }
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::ControlData => DiagnosticReply::ControlData(ControlData::parse(f)?),
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::GasInputs => {
                DiagnosticReply::GasConsoleInputs(GasConsoleInputs::parse(f)?)
            }
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::CoolantPressure => {
                DiagnosticReply::CoolantPressure(CoolantCounts(f.number(4, 0, 9999)?))
            }
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::ControlData3 => DiagnosticReply::ControlData3(ControlData3::parse(f)?),
            DiagnosticRead::MfgData1 => DiagnosticReply::MfgData1(MfgData1::parse(f)?),
            #[cfg(feature = "diagnostics")]
            DiagnosticRead::MfgData2 => DiagnosticReply::MfgData2(MfgData2::parse(f)?),
        })
    }

    pub(super) fn write(&self, w: &mut DataWriter) -> Result<()> {
        match self {
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::ControlData(d) => d.write(w),
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::MaxProControlData(d) => d.write(w),
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::GasConsoleInputs(inputs) => inputs.write(w),
            #[cfg(feature = "diagnostics")]
            // Unpadded, as the sample `>13280FE<` (80 counts).
            DiagnosticReply::CoolantPressure(counts) => w.field(counts.0.into(), 1, 4),
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::ControlData3(d) => d.write(w),
            DiagnosticReply::MfgData1(d) => d.write(w),
            #[cfg(feature = "diagnostics")]
            DiagnosticReply::MfgData2(d) => d.write(w),
        }
    }
}

/// A reply of tagged four-digit fields, written once: the struct, its tags in wire order, and
/// the parse/write pair.
macro_rules! tagged_reply {
    (
        $(#[$doc:meta])*
        $name:ident { $($(#[$field_doc:meta])* $field:ident: $tag:literal),* $(,)? }
    ) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $name {
            $($(#[$field_doc])* pub $field: u16,)*
        }

        impl $name {
            /// The fields' tags, in wire order.
            pub const TAGS: &'static [&'static str] = &[$($tag),*];

            pub(super) fn parse(f: &mut Fields<'_>) -> Result<Self> {
                Ok($name { $($field: f.tagged($tag.as_bytes(), 4)?,)* })
            }

            pub(super) fn write(&self, w: &mut DataWriter) -> Result<()> {
                $(w.tagged($tag.as_bytes(), self.$field.into(), 4)?;)*
                Ok(())
            }
        }
    };
}

#[cfg(feature = "diagnostics")]
tagged_reply! {
    /// 100 GET_CONTROL_DATA reply, HPR form (the same for an HPR130 and an HPR260; chopper B
    /// can be ignored on an HPR130). Units as the manual's field list gives them.
    ControlData {
        /// Chopper A temperature, raw A/D (0-1023).
        chopper_a_temp: "CAT",
        /// Chopper B temperature, raw A/D (0-1023).
        chopper_b_temp: "CBT",
        /// Line voltage, tenths of a volt (0-2400 = 240.0 V AC).
        line_voltage: "LVO",
        /// Coolant flow, hundredths of a gpm (0-440 = 4.40 gpm).
        coolant_flow: "CFL",
        /// Coolant temperature, raw A/D (0-1023).
        coolant_temp: "CTP",
        /// Transformer temperature, raw A/D (0-1023).
        transformer_temp: "TTP",
        /// Chopper A current, amps.
        chopper_a_current: "CAC",
        /// Chopper B current, amps.
        chopper_b_current: "CBC",
        /// Work lead current, amps.
        work_lead_current: "WLC",
        /// Chopper A setpoint, amps.
        chopper_a_setpoint: "CAS",
        /// Chopper B setpoint, amps.
        chopper_b_setpoint: "CBS",
        /// Chopper A PWM, 1070 = 100 %.
        pwm_chopper_a: "PWMA",
        /// Chopper B PWM, 1070 = 100 %.
        pwm_chopper_b: "PWMB",
    }
}

#[cfg(feature = "diagnostics")]
tagged_reply! {
    /// 133 GET CONTROL DATA3 reply (HPR400): the third and fourth choppers.
    ControlData3 {
        /// Chopper C temperature, raw A/D.
        chopper_c_temp: "CCT",
        /// Chopper D temperature, raw A/D.
        chopper_d_temp: "CDT",
        /// Chopper C current, amps.
        chopper_c_current: "CCC",
        /// Chopper D current, amps.
        chopper_d_current: "CDC",
    }
}

tagged_reply! {
    /// 141 GET MFG DATA1 reply (MaxPro200): the first half of its 100 reply.
    MfgData1 {
        /// Plasma actual pressure, psi.
        plasma_pressure: "plap",
        /// Shield actual pressure, psi.
        shield_pressure: "shap",
        /// Inlet pressure: psi in the 100 list, ADC counts in the 141 list (the manual
        /// differs; the value is kept as sent).
        inlet_pressure: "icrp",
        /// Coolant temperature, ADC counts.
        coolant_temp: "colt",
        /// Chopper temperature, ADC counts.
        chopper_temp: "chpt",
        /// Channel A current, amps.
        channel_a_current: "chac",
    }
}

#[cfg(feature = "diagnostics")]
tagged_reply! {
    /// 142 GET MFG DATA2 reply (MaxPro200): the second half of its 100 reply.
    MfgData2 {
        /// Channel B current, amps.
        channel_b_current: "chbc",
        /// Transformer temperature, counts.
        transformer_temp: "xfmr",
        /// Inductor A temperature, ADC counts.
        inductor_a_temp: "inat",
        /// Inductor B temperature, ADC counts.
        inductor_b_temp: "inbt",
        /// Bus voltage, volts.
        bus_voltage: "busv",
        /// Coolant flow, hundredths of a gpm (`flow0100` = 1.00 gpm).
        coolant_flow: "flow",
    }
}

#[cfg(feature = "diagnostics")]
/// 100 GET_CONTROL_DATA reply, MaxPro200 form: 141's fields then 142's ("Command #ID 100
/// was split into 2 parts (ID# 141,142)").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MaxProControlData {
    /// The fields 141 returns.
    pub first: MfgData1,
    /// The fields 142 returns.
    pub second: MfgData2,
}

#[cfg(feature = "diagnostics")]
impl MaxProControlData {
    pub(super) fn parse(f: &mut Fields<'_>) -> Result<Self> {
        Ok(MaxProControlData {
            first: MfgData1::parse(f)?,
            second: MfgData2::parse(f)?,
        })
    }

    pub(super) fn write(&self, w: &mut DataWriter) -> Result<()> {
        self.first.write(w)?;
        self.second.write(w)
    }
}

#[cfg(feature = "diagnostics")]
/// 117 READ_GAS_INPUTS_FROM_PS reply: the gas console's inputs, one `1` (on) or `0` (off)
/// each, in the manual's order (first character = first input listed).
///
/// The manual lists seven inputs for a manual gas console ([`MANUAL_CONSOLE_INPUTS`]) and
/// eight for an automatic one ([`AUTO_CONSOLE_INPUTS`]); its sample has seven digits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GasConsoleInputs {
    /// Input `i` is bit `i` (bit 0 = first character).
    bits: u8,
    /// Number of inputs in the reply: 7 or 8.
    count: u8,
}

#[cfg(feature = "diagnostics")]
/// The manual's input list for a manual gas console, in reply order.
pub const MANUAL_CONSOLE_INPUTS: [&str; 7] = [
    "error select",
    "status select",
    "test preflow",
    "test cutflow",
    "serial ID bit 0",
    "serial ID bit 1",
    "serial ID bit 2",
];

#[cfg(feature = "diagnostics")]
/// The manual's input list for an automatic gas console, in reply order.
pub const AUTO_CONSOLE_INPUTS: [&str; 8] = [
    "metering dipswitch 2",
    "metering dipswitch 3",
    "metering dipswitch 4",
    "select dipswitch 1",
    "select dipswitch 2",
    "select dipswitch 3",
    "select dipswitch 4",
    "metering dipswitch 1",
];

#[cfg(feature = "diagnostics")]
impl GasConsoleInputs {
    /// From the inputs in reply order; [`Error::Malformed`] unless there are 7 or 8.
    pub fn new(inputs: &[bool]) -> Result<Self> {
        let count = match inputs.len() {
            7 => 7,
            8 => 8,
            _ => return Err(Error::Malformed),
        };
        let bits = inputs
            .iter()
            .rev()
            .fold(0u8, |acc, &on| acc << 1 | u8::from(on));
        Ok(GasConsoleInputs { bits, count })
    }

    /// Number of inputs the reply carries (7: manual console list, 8: automatic).
    pub const fn count(&self) -> usize {
        self.count as usize
    }

    /// Input `index` (0 = first listed); `None` past the end.
    pub const fn input(&self, index: usize) -> Option<bool> {
        if index < self.count() {
            Some(self.bits >> index & 1 == 1)
        } else {
            None
        }
    }

    /// The names of the inputs, by their count: the manual-console list for 7, the
    /// automatic-console list for 8.
    pub const fn names(&self) -> &'static [&'static str] {
        if self.count == 7 {
            &MANUAL_CONSOLE_INPUTS
        } else {
            &AUTO_CONSOLE_INPUTS
        }
    }

    pub(super) fn parse(f: &mut Fields<'_>) -> Result<Self> {
        let digits = f.next_field()?;
        if !matches!(digits.len(), 7 | 8) {
            return Err(Error::Malformed);
        }
        let mut bits = 0u8;
        for (i, &d) in digits.iter().enumerate() {
            match d {
                b'0' => {}
                b'1' => bits |= 1 << i,
                _ => return Err(Error::Malformed),
            }
        }
        Ok(GasConsoleInputs {
            bits,
            // 7 or 8, checked above.
            count: digits.len() as u8,
        })
    }

    pub(super) fn write(&self, w: &mut DataWriter) -> Result<()> {
        (0..self.count())
            .try_for_each(|i| w.byte(if self.bits >> i & 1 == 1 { b'1' } else { b'0' }))
    }
}

#[cfg(feature = "diagnostics")]
/// 132 READ COOLANT PRESSURE reply (HPR260): the raw A/D value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CoolantCounts(pub u16);

#[cfg(feature = "diagnostics")]
impl CoolantCounts {
    /// The pressure in tenths of a psi, on the line through the manual's two points "83
    /// counts = 225 psi, 73 counts = 200 psi" (2.5 psi a count, 17.5 psi at 0 counts). The
    /// manual gives no other points: the sensor is taken to be linear.
    pub const fn psi_tenths(self) -> u32 {
        self.0 as u32 * 25 + 175
    }
}

#[cfg(all(test, feature = "diagnostics"))]
mod tests {
    use super::*;

    #[test]
    fn coolant_pressure_meets_the_manuals_points() {
        // HPR manual (002_72b43a5685974c77.txt) line 266: "83 counts = 225 psi 73 counts =
        // 200 psi".
        assert_eq!(CoolantCounts(83).psi_tenths(), 2250);
        assert_eq!(CoolantCounts(73).psi_tenths(), 2000);
        // Its sample reply, 80 counts.
        assert_eq!(CoolantCounts(80).psi_tenths(), 2175);
        assert_eq!(CoolantCounts(u16::MAX).psi_tenths(), 1_638_550);
    }

    #[test]
    fn gas_console_inputs_keep_order_and_count() {
        let mut on = [false; 8];
        on[0] = true;
        on[7] = true;
        let inputs = GasConsoleInputs::new(&on).unwrap();
        assert_eq!(inputs.count(), 8);
        assert_eq!(inputs.input(0), Some(true));
        assert_eq!(inputs.input(1), Some(false));
        assert_eq!(inputs.input(7), Some(true));
        assert_eq!(inputs.input(8), None);
        assert_eq!(inputs.names()[7], "metering dipswitch 1");
        let mut w = DataWriter::new();
        inputs.write(&mut w).unwrap();
        assert_eq!(w.as_bytes(), b"10000001");
        assert_eq!(
            GasConsoleInputs::parse(&mut Fields::new(b"10000001")),
            Ok(inputs)
        );
        assert_eq!(GasConsoleInputs::new(&[true; 6]), Err(Error::Malformed));
        for bad in [&b"000000"[..], b"000000000", b"0000002", b"0000000 1"] {
            let mut f = Fields::new(bad);
            let parsed = GasConsoleInputs::parse(&mut f).and_then(|_| f.end());
            assert_eq!(parsed, Err(Error::Malformed), "{bad:?}");
        }
    }
}
