//! Property tests of the HPR diagnostic reads (feature `diagnostics`): emit-then-parse round
//! trips of every request and reply form, and no diagnostic read is taken for another command.
#![cfg(feature = "diagnostics")]

use plasma_protocol::hpr::{
    ControlData, ControlData3, CoolantCounts, DiagnosticRead, DiagnosticReply, Frame,
    GasConsoleInputs, MAX_FRAME_LEN, MaxProControlData, MfgData1, MfgData2, Reply, Request,
};
use proptest::prelude::*;

fn read() -> impl Strategy<Value = DiagnosticRead> {
    prop::sample::select(vec![
        DiagnosticRead::ControlData,
        DiagnosticRead::GasInputs,
        DiagnosticRead::CoolantPressure,
        DiagnosticRead::ControlData3,
        DiagnosticRead::MfgData1,
        DiagnosticRead::MfgData2,
    ])
}

fn mfg_data1() -> impl Strategy<Value = MfgData1> {
    prop::array::uniform6(0u16..=9999).prop_map(|v| MfgData1 {
        plasma_pressure: v[0],
        shield_pressure: v[1],
        inlet_pressure: v[2],
        coolant_temp: v[3],
        chopper_temp: v[4],
        channel_a_current: v[5],
    })
}

fn mfg_data2() -> impl Strategy<Value = MfgData2> {
    prop::array::uniform6(0u16..=9999).prop_map(|v| MfgData2 {
        channel_b_current: v[0],
        transformer_temp: v[1],
        inductor_a_temp: v[2],
        inductor_b_temp: v[3],
        bus_voltage: v[4],
        coolant_flow: v[5],
    })
}

fn reply() -> impl Strategy<Value = DiagnosticReply> {
    prop_oneof![
        prop::array::uniform13(0u16..=9999).prop_map(|v| DiagnosticReply::ControlData(
            ControlData {
                chopper_a_temp: v[0],
                chopper_b_temp: v[1],
                line_voltage: v[2],
                coolant_flow: v[3],
                coolant_temp: v[4],
                transformer_temp: v[5],
                chopper_a_current: v[6],
                chopper_b_current: v[7],
                work_lead_current: v[8],
                chopper_a_setpoint: v[9],
                chopper_b_setpoint: v[10],
                pwm_chopper_a: v[11],
                pwm_chopper_b: v[12],
            }
        )),
        (mfg_data1(), mfg_data2()).prop_map(|(first, second)| {
            DiagnosticReply::MaxProControlData(MaxProControlData { first, second })
        }),
        prop::collection::vec(any::<bool>(), 7..=8).prop_map(|v| {
            DiagnosticReply::GasConsoleInputs(GasConsoleInputs::new(&v).unwrap())
        }),
        (0u16..=9999).prop_map(|v| DiagnosticReply::CoolantPressure(CoolantCounts(v))),
        prop::array::uniform4(0u16..=9999).prop_map(|v| DiagnosticReply::ControlData3(
            ControlData3 {
                chopper_c_temp: v[0],
                chopper_d_temp: v[1],
                chopper_c_current: v[2],
                chopper_d_current: v[3],
            }
        )),
        mfg_data1().prop_map(DiagnosticReply::MfgData1),
        mfg_data2().prop_map(DiagnosticReply::MfgData2),
    ]
}

proptest! {
    #[test]
    fn request_round_trip(read in read()) {
        let request = Request::ReadDiagnostic(read);
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = request.emit(&mut buf).unwrap();
        let frame = Frame::parse(&buf[..n]).unwrap();
        prop_assert_eq!(frame.id, read.id());
        prop_assert_eq!(Request::parse(&frame), Ok(request));
        prop_assert_eq!(DiagnosticRead::from_id(frame.id), Some(read));
    }

    #[test]
    fn reply_round_trip(diagnostic in reply()) {
        let reply = Reply::Diagnostic(diagnostic);
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = reply.emit(&mut buf).unwrap();
        let frame = Frame::parse(&buf[..n]).unwrap();
        prop_assert_eq!(frame.id, diagnostic.id());
        prop_assert_eq!(Reply::parse(&frame), Ok(reply));
        // A diagnostic reply carries data, so it is never its own request.
        prop_assert!(Request::parse(&frame).is_err());
    }

    #[test]
    fn other_ids_are_not_diagnostic_reads(command in 0u16..=999) {
        let known = [100, 117, 132, 133, 141, 142];
        prop_assert_eq!(DiagnosticRead::from_id(command).is_some(), known.contains(&command));
    }
}
