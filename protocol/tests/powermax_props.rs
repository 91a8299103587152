//! Property tests of the Powermax register layer: exact scaling, total decoders, fault codes.

use plasma_protocol::Error;
use plasma_protocol::modbus_ascii::Registers;
use plasma_protocol::powermax::{
    Amps, CartridgeCounters, CartridgeName, CartridgeUid, FaultCode, LeadLength, PartNumber,
    Pressure, Psi, Signals, device_id, legacy, sync,
};
use proptest::prelude::*;

proptest! {
    #[test]
    fn amps_text_round_trip(raw in any::<u16>()) {
        let a = Amps::from_raw(raw);
        let text = a.to_string();
        prop_assert_eq!(text.parse::<Amps>(), Ok(a));
        prop_assert_eq!(Amps::parse_exact(&text), Ok(a));
        // Shortest form: no trailing zero after a decimal point.
        prop_assert!(!text.ends_with('0') || !text.contains('.'));
    }

    #[test]
    fn psi_text_round_trip(raw in any::<u16>()) {
        let p = Psi::from_raw(raw);
        let text = p.to_string();
        prop_assert_eq!(text.parse::<Psi>(), Ok(p));
        prop_assert_eq!(Psi::parse_exact(&text), Ok(p));
        let pressure = Pressure::from_raw(raw);
        prop_assert_eq!(pressure.to_string().parse::<Pressure>(), Ok(pressure));
        prop_assert_eq!(pressure.raw(), raw);
    }

    /// Parsing picks the nearest step: |raw - value x 64| <= 1/2.
    #[test]
    fn amps_parse_is_nearest(whole in 0u32..511, fraction in "[0-9]{0,12}") {
        let text = if fraction.is_empty() {
            whole.to_string()
        } else {
            format!("{whole}.{fraction}")
        };
        let a: Amps = text.parse().unwrap();
        let digits = fraction.len() as u32;
        let scale = 10u128.pow(digits);
        let value_scaled: u128 =
            u128::from(whole) * scale + fraction.parse::<u128>().unwrap_or(0);
        let exact = value_scaled * 64; // value x 64 x 10^digits
        let got = a.raw() as u128 * scale;
        let diff = got.abs_diff(exact);
        prop_assert!(diff * 2 <= scale, "{} -> {}", text, a.raw());
        // Ties go up (away from zero).
        if diff * 2 == scale {
            prop_assert!(got > exact);
        }
    }

    #[test]
    fn scaling_parse_never_panics(text in "\\PC{0,40}") {
        let _ = text.parse::<Amps>();
        let _ = text.parse::<Psi>();
        let _ = text.parse::<Pressure>();
        let _ = Amps::parse_exact(&text);
        let _ = text.parse::<FaultCode>();
    }

    #[test]
    fn numeric_text_never_panics(text in "-?[0-9]{0,8}(\\.[0-9]{0,40})?") {
        match text.parse::<Amps>() {
            Ok(_) | Err(Error::Malformed) | Err(Error::Overlong) => {}
            Err(e) => prop_assert!(false, "unexpected {:?}", e),
        }
    }

    #[test]
    fn whole_and_tenths_agree(units in 0u16..=511) {
        let whole = Amps::from_whole(units).unwrap();
        prop_assert_eq!(Amps::from_tenths(units * 10), Some(whole));
        prop_assert_eq!(whole.to_string(), units.to_string());
        if units <= 255 {
            prop_assert_eq!(Psi::from_hundredths(units * 100), Psi::from_whole(units));
        }
    }

    #[test]
    fn fault_code_round_trip(raw in any::<u16>()) {
        let code = FaultCode(raw);
        let text = code.to_string();
        prop_assert_eq!(text.parse::<FaultCode>(), Ok(code));
        let (x, yy, z) = code.fields();
        prop_assert_eq!(x * 1000 + yy * 10 + z, raw);
        let _ = code.info();
        let _ = code.legacy_info();
    }

    #[test]
    fn decoders_are_total_on_words(words in proptest::collection::vec(any::<u16>(), 0..40)) {
        check_decoders(Registers::Words(&words));
    }

    #[test]
    fn decoders_are_total_on_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..80)) {
        check_decoders(Registers::BigEndian(&bytes));
    }

    #[test]
    fn coil_and_object_decoders_are_total(bytes in proptest::collection::vec(any::<u8>(), 0..40)) {
        prop_assert_eq!(Signals::decode(&bytes).is_err(), bytes.is_empty());
        match LeadLength::from_legacy_coils(&bytes) {
            Ok(_) => {}
            Err(Error::Truncated) => prop_assert!(bytes.is_empty()),
            Err(Error::Malformed) => prop_assert_eq!(bytes[0] & 3, 3),
            Err(e) => prop_assert!(false, "unexpected {:?}", e),
        }
        for id in [0u8, 1, 2, 0xFF] {
            match device_id::find_object(&bytes, id) {
                Ok(_) | Err(Error::Truncated) => {}
                Err(e) => prop_assert!(false, "unexpected {:?}", e),
            }
        }
        let _ = device_id::model_from_product_code(&bytes);
    }

    #[test]
    fn block_place_is_total(
        part in 0usize..6,
        values in proptest::collection::vec(any::<u16>(), 0..20),
        buf_len in 0usize..20,
    ) {
        let mut buf = vec![0u16; buf_len];
        for plan in [sync::STATUS_BLOCK, sync::CARTRIDGE_BLOCK, legacy::STATUS_BLOCK, legacy::FULL_BLOCK] {
            let _ = plan.place(part, Registers::Words(&values), &mut buf);
        }
    }
}

/// Every decoder: `Ok` with enough registers, `Err(Truncated)` with too few, never a panic.
fn check_decoders(regs: Registers<'_>) {
    fn expect<T: core::fmt::Debug>(result: Result<T, Error>, needed: usize, have: usize) {
        if have >= needed {
            assert!(
                result.is_ok(),
                "{needed} needed, {have} present: {result:?}"
            );
        } else {
            assert_eq!(
                result.err(),
                Some(Error::Truncated),
                "{needed} needed, {have} present"
            );
        }
    }
    let n = regs.len();
    expect(sync::Identification::decode(regs), 1, n);
    expect(sync::PermittedSettings::decode(regs), 5, n);
    expect(sync::Process::decode(regs), 3, n);
    expect(sync::ActualOutputs::decode(regs), 2, n);
    expect(sync::decode_active_fault(regs), 1, n);
    expect(sync::StatusBlock::decode(regs), 11, n);
    expect(sync::PsCounters::decode(regs), 8, n);
    expect(sync::Cartridge::decode(regs), 20, n);
    expect(sync::FaultLog::decode(regs), 4, n);
    expect(CartridgeUid::decode(regs), 8, n);
    expect(PartNumber::decode(regs), 3, n);
    expect(CartridgeCounters::decode(regs), 4, n);
    expect(CartridgeName::decode(regs), 6, n);
    expect(legacy::decode_fault(regs), 1, n);
    expect(legacy::decode_current(regs), 1, n);
    expect(legacy::decode_pressure(regs), 1, n);
    expect(legacy::decode_arc_time(regs), 2, n);
    expect(legacy::LegacyStatus::decode(regs), 8, n);
    expect(legacy::LegacyFullStatus::decode(regs), 13, n);
    if let Ok(name) = CartridgeName::decode(regs) {
        let _ = name.info();
    }
    if let Ok(pn) = PartNumber::decode(regs) {
        let _ = (pn.cartridge_type(), pn.as_str(), pn.is_read_failure());
    }
}

#[test]
fn every_raw_value_round_trips() {
    for raw in 0..=u16::MAX {
        let a = Amps::from_raw(raw);
        assert_eq!(a.to_string().parse::<Amps>(), Ok(a));
        let p = Psi::from_raw(raw);
        assert_eq!(p.to_string().parse::<Psi>(), Ok(p));
        let f = FaultCode(raw);
        assert_eq!(f.to_string().parse::<FaultCode>(), Ok(f));
    }
}
