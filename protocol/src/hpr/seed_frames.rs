//! Manual sample frames of commands that have no typed request or reply (factory-only,
//! dangerous, or diagnostic reads): each is decoded, checked field by field, re-emitted byte
//! for byte, and its command's class checked. Samples whose checksum is wrong as printed
//! are tested as rejected, with the reason.

use super::command::{Class, classify};
use super::frame::Frame;
use crate::Error;

/// (frame as printed, id, data, class of the id).
const VALID: &[(&[u8], u16, &[u8], Class)] = &[
    // 071 MANUAL_PUMP_CONTROL: request "1" (force the pump on), reply 1 = accepted.
    (b">0711C9<", 71, b"1", Class::Dangerous),
    // 101 SET_IO_STATUS reply.
    (b">1011C3<", 101, b"1", Class::Dangerous),
    // 102 SET_GAS_IO_FROM_PS reply.
    (b">1021C4<", 102, b"1", Class::Dangerous),
    // 103-113: factory CAN tests, request without data and reply 1.
    (b">10394<", 103, b"", Class::FactoryTestingOnly),
    (b">1031C5<", 103, b"1", Class::FactoryTestingOnly),
    (b">10495<", 104, b"", Class::FactoryTestingOnly),
    (b">1041C6<", 104, b"1", Class::FactoryTestingOnly),
    (b">10596<", 105, b"", Class::FactoryTestingOnly),
    (b">1051C7<", 105, b"1", Class::FactoryTestingOnly),
    (b">10697<", 106, b"", Class::FactoryTestingOnly),
    (b">1061C8<", 106, b"1", Class::FactoryTestingOnly),
    (b">10798<", 107, b"", Class::FactoryTestingOnly),
    (b">1071C9<", 107, b"1", Class::FactoryTestingOnly),
    // Section III.e's second checksum example ("READ INPUTS power supply response").
    (b">107000058<", 107, b"0000", Class::FactoryTestingOnly),
    (b">10899<", 108, b"", Class::FactoryTestingOnly),
    (b">1081CA<", 108, b"1", Class::FactoryTestingOnly),
    (b">1099A<", 109, b"", Class::FactoryTestingOnly),
    (b">1091CB<", 109, b"1", Class::FactoryTestingOnly),
    (b">11092<", 110, b"", Class::FactoryTestingOnly),
    (b">1101C3<", 110, b"1", Class::FactoryTestingOnly),
    (b">11193<", 111, b"", Class::FactoryTestingOnly),
    (b">1111C4<", 111, b"1", Class::FactoryTestingOnly),
    (b">11294<", 112, b"", Class::FactoryTestingOnly),
    (b">1121C5<", 112, b"1", Class::FactoryTestingOnly),
    (b">11395<", 113, b"", Class::FactoryTestingOnly),
    (b">1131C6<", 113, b"1", Class::FactoryTestingOnly),
    (b">11597<", 115, b"", Class::FactoryTestingOnly),
    (b">11698<", 116, b"", Class::FactoryTestingOnly),
    // 118 GAS_DISPLAY_TEST_MODE: request mode 0, reply 1.
    (b">1180CA<", 118, b"0", Class::FactoryTestingOnly),
    (b">1181CB<", 118, b"1", Class::FactoryTestingOnly),
    // 124 INDEX_MOTORVALVES: open motor valve 1 by 30 counts, reply 1.
    (b">1241 1 36C<", 124, b"1 1 3", Class::Dangerous),
    (b">1241C8<", 124, b"1", Class::Dangerous),
    // 135 CAN LOOPBACK TEST.
    (b">13599<", 135, b"", Class::FactoryTestingOnly),
    (b">1351CA<", 135, b"1", Class::FactoryTestingOnly),
    // 139 SET MFG TEST MODE: the sample request carries no mode; reply 0.
    (b">1399D<", 139, b"", Class::Dangerous),
    (b">1390CD<", 139, b"0", Class::Dangerous),
    // 140 GET MFG TEST MODE: reply 0 (no test selected).
    (b">14095<", 140, b"", Class::Normal),
    (b">1400C5<", 140, b"0", Class::Normal),
    // 144 SET MAINTENANCE MODE.
    (b">14499<", 144, b"", Class::Dangerous),
    (b">1441CA<", 144, b"1", Class::Dangerous),
    // 146 FRONT PANEL LED TEST: LEDs on, echoed.
    (b">1461CC<", 146, b"1", Class::Normal),
    // 147 SET REDCART MODE.
    (b">1479C<", 147, b"", Class::Dangerous),
    (b">1471CD<", 147, b"1", Class::Dangerous),
];

/// Samples whose printed checksum does not match their printed bytes, with the checksum
/// computed over the bytes as printed. None can be corrected with confidence: each is a
/// long run of identical digits or fields where a lost or extra character and a wrong
/// checksum digit are equally likely.
const REJECTED: &[(&[u8], u8, u8)] = &[
    // 101, "All outputs on": the HPR list has 12 outputs, the sample neither 12 ones nor a
    // matching checksum for any count of ones near it.
    (b">101111111111111110D<", 0x40, 0x0D),
    // 101, manual gas console outputs.
    (b">10111111111111111111111111111111111166<", 0xE3, 0x66),
    // 102, gas valves.
    (b">1021111111111111111111111111111167<", 0x20, 0x67),
    // 115 reply: ends "CAC00FF"; several two-digit completions of CAC00 fit, none is certain.
    (
        b">115CAT0482 CBT0021 LVO0118 CFL0009 CTP0481 TTP0481 CAC00FF<",
        0x92,
        0xFF,
    ),
    // 116 reply.
    (
        b">116CBC0014 WLC0005 CAS0000 CBS0534 PWMA0000 PWMB0000 PRSA0000 PRSB000041<",
        0xC3,
        0x41,
    ),
];

#[test]
fn untyped_seed_frames_round_trip() {
    for &(bytes, id, data, class) in VALID {
        let f = Frame::parse(bytes).unwrap();
        assert_eq!((f.id, f.data), (id, data), "{bytes:?}");
        assert_eq!(classify(id), Some(class), "{id}");
        let mut out = [0u8; 128];
        let n = Frame::new(id, data).emit(&mut out).unwrap();
        assert_eq!(&out[..n], bytes);
    }
}

#[test]
fn damaged_seed_frames_are_rejected() {
    for &(bytes, expected, found) in REJECTED {
        assert_eq!(
            Frame::parse(bytes),
            Err(Error::BadChecksum { expected, found }),
            "{bytes:?}"
        );
    }
}
