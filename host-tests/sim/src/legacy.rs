//! Legacy Powermax (45 XP, 65, 85, 105, 125): the 0x2xxx registers and 0x08xx coils, written
//! from the *Powermax65/85 Serial Communication Protocol* (seed 001) and the "old address"
//! column of the SYNC guide (seed 000, Table 1), which SYNC units answer as well. The unit itself
//! is [`Powermax`].
//!
//! | address | content |
//! |---|---|
//! | 0x204C | actual gas pressure, psi x 128 (SYNC Table 1) |
//! | 0x2093 | cut_mode_force: 1 normal, 2 CPA, 3 gouge (write 06; reads back the force value) |
//! | 0x2094 | current_set_force, A x 64 |
//! | 0x2096 | pressure_set_force, psi x 128, 0 = automatic |
//! | 0x2098 | fault_code (decimal, 0-11-1 = 111) |
//! | 0x2099 / 0x209A | current_set min / max, A x 64 |
//! | 0x209C / 0x209D | pressure_set min / max, psi x 128 |
//! | 0x209E / 0x209F | arc time in seconds, low word / high word (SYNC: its 0x302A/0x302B pilot arc time) |
//! | coils 0x0808 / 0x0809 | torch lead length, bit 0 / bit 1 (00 <= 25 ft, 01 <= 50 ft, 10 75 ft) |
//! | coils 0x0810 / 0x0811 | Start input / Motion output (SYNC Table 1) |
//! | coil 0x0832 | write: gas test (SYNC Table 1) |
//!
//! 0x2095, 0x2097 and 0x209B lie between documented registers and are not documented; the
//! coils 0x080A-0x080F likewise.
//!
//! Remote mode: "To put the power supply into remote control mode, the CNC needs to write to
//! all three force registers together, once, with correct non-zero values... Afterward, the CNC
//! can write to the force registers one at a time as needed. To return the power supply to
//! manual control, all force registers must be set to zero." The samples use function 06, so
//! the unit enters remote mode when all three have been written; a function 0x10 write over
//! 0x2093-0x2096 does the same (its 0x2095 word follows the undocumented-address setting).
//!
//! Current ranges (not in the seed; Hypertherm's published specifications, consistent with the
//! guide's 20 A / 65 A example for a Powermax65): 45 XP 10-45 A, 65 20-65 A, 85 25-85 A,
//! 105 30-105 A, 125 30-125 A. Pressure limits default to the guide's example, 63-78 psi.

use plasma_protocol::modbus_ascii::ExceptionCode;

use super::powermax::{Cell, Powermax, UndocumentedAddresses};
use super::{Family, Model, SimulatedUnit};

/// Output current range, amps.
pub fn current_range(model: Model) -> (u16, u16) {
    match model {
        Model::Pm45Xp => (10, 45),
        Model::Pm65 => (20, 65),
        Model::Pm85 => (25, 85),
        Model::Pm105 => (30, 105),
        _ => (30, 125),
    }
}

/// Read Device Identification product code (SYNC guide Table 2).
pub fn product_code(model: Model) -> &'static str {
    match model {
        Model::Pm45Xp => "081288",
        Model::Pm125 => "081251",
        _ => "081223",
    }
}

/// Force register index (0 mode, 1 current, 2 pressure) of an old address.
pub(crate) fn force_index(address: u16) -> Option<usize> {
    match address {
        0x2093 => Some(0),
        0x2094 => Some(1),
        0x2096 => Some(2),
        _ => None,
    }
}

/// Reads one 0x2xxx register.
pub(crate) fn register(unit: &Powermax, address: u16) -> Cell {
    let limits = unit.limits();
    let force = unit.force_registers();
    let counters = unit.counters();
    let arc_secs = if unit.config().model.family() == Family::Sync {
        counters.pilot.secs()
    } else {
        unit.total_arc_secs()
    };
    let value = match address {
        0x204C => unit.actual_pressure(),
        0x2093 => force.mode,
        0x2094 => force.current,
        0x2095 | 0x2097 | 0x209B => return Cell::Gap,
        0x2096 => force.pressure,
        0x2098 => unit.active_fault(),
        0x2099 => limits.current.0,
        0x209A => limits.current.1,
        0x209C => limits.pressure.0,
        0x209D => limits.pressure.1,
        0x209E => (arc_secs & 0xFFFF) as u16,
        0x209F => ((arc_secs >> 16) & 0xFFFF) as u16,
        _ => return Cell::Unknown,
    };
    Cell::Value(value)
}

/// Reads one 0x08xx coil.
pub(crate) fn coil(unit: &Powermax, address: u16) -> Cell {
    let lead = unit.config().torch_id & 0x03;
    match address {
        0x0808 => Cell::Value(u16::from(lead & 1)),
        0x0809 => Cell::Value(u16::from(lead >> 1 & 1)),
        0x080A..=0x080F => Cell::Gap,
        0x0810 => Cell::Value(unit.start_input().into()),
        0x0811 => Cell::Value(unit.motion().into()),
        _ => Cell::Unknown,
    }
}

/// Function 0x10 over the force registers 0x2093-0x2096.
pub(crate) fn write_multiple(
    unit: &mut Powermax,
    start: u16,
    values: &[u16],
) -> Result<(), ExceptionCode> {
    let end = u32::from(start) + values.len() as u32;
    if end > 0x2097 {
        return Err(ExceptionCode::IllegalDataAddress);
    }
    let mut writes = Vec::new();
    for (i, &v) in values.iter().enumerate() {
        let address = start + i as u16;
        match force_index(address) {
            Some(index) => writes.push((index, v)),
            None if unit.config().undocumented == UndocumentedAddresses::Accept => {}
            None => return Err(ExceptionCode::IllegalDataAddress),
        }
    }
    unit.write_force(&writes, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SimulatedUnit;
    use crate::clock::Accumulator;
    use crate::powermax::testing::*;
    use crate::powermax::{Counters, DeviceIdSupport, PowermaxConfig};
    use plasma_protocol::time::{Duration, Instant};

    fn unit(model: Model) -> Powermax {
        Powermax::new(PowermaxConfig::for_model(model))
    }

    fn ms(t: u64) -> Instant {
        Instant::from_millis(t)
    }

    fn talk(unit: &mut Powermax, now: Instant, frame: &str) -> Option<String> {
        let mut bytes = frame.as_bytes().to_vec();
        bytes.extend_from_slice(b"\r\n");
        exchange(unit, now, &bytes).map(|r| String::from_utf8(r[..r.len() - 2].to_vec()).unwrap())
    }

    #[test]
    fn force_register_samples_echo_like_the_guide() {
        let mut u = unit(Model::Pm85);
        for frame in [
            ":01062093000145",
            ":01062093000244",
            ":01062093000343",
            ":010620940A003B",
            // The guide's 45 A sample ":0106209400B40FA" has a stray '0': 0x0B40, LRC FA.
            ":010620940B40FA",
            ":010620941040F5",
            ":010620941540F0",
            ":010620940DE058",
            ":010620961680AD",
            ":01062096230020",
        ] {
            assert_eq!(talk(&mut u, ms(0), frame).unwrap(), frame);
        }
    }

    #[test]
    fn remote_mode_needs_all_three_force_registers_and_ends_when_all_are_zero() {
        let mut u = unit(Model::Pm65);
        talk(&mut u, ms(0), ":01062093000145").unwrap(); // normal
        assert!(!u.in_remote_mode());
        talk(&mut u, ms(1), ":010620941040F5").unwrap(); // 65 A
        assert!(!u.in_remote_mode());
        assert_eq!(u.active_fault(), 0);
        talk(&mut u, ms(2), ":010620961680AD").unwrap(); // 45 psi... below 63 psi
        assert!(!u.in_remote_mode());
        assert_eq!(u.active_fault(), 112);
        talk(&mut u, ms(3), ":01062096230020").unwrap(); // 70 psi
        assert!(u.in_remote_mode());
        assert_eq!(u.active_fault(), 0);
        // Afterwards one at a time: 40 A.
        talk(&mut u, ms(4), ":010620940A003B").unwrap();
        assert_eq!(u.settings().current, 40 * 64);
        // Back to manual: all three zero.
        exchange(&mut u, ms(5), &request(1, &[0x06, 0x20, 0x93, 0, 0])).unwrap();
        assert!(u.in_remote_mode());
        exchange(&mut u, ms(6), &request(1, &[0x06, 0x20, 0x94, 0, 0])).unwrap();
        exchange(&mut u, ms(7), &request(1, &[0x06, 0x20, 0x96, 0, 0])).unwrap();
        assert!(!u.in_remote_mode());
    }

    #[test]
    fn out_of_range_current_reads_as_fault_0_11_1() {
        let mut u = unit(Model::Pm65);
        for f in [":01062093000145", ":010620941040F5", ":01062096230020"] {
            talk(&mut u, ms(0), f).unwrap();
        }
        // 85 A on a Powermax65.
        talk(&mut u, ms(1), ":010620941540F0").unwrap();
        assert_eq!(
            talk(&mut u, ms(2), ":01042098000142").unwrap(),
            ":010402006F8A"
        );
        assert_eq!(u.settings().current, 65 * 64);
    }

    #[test]
    fn limits_match_the_guide_samples() {
        let mut u = unit(Model::Pm65);
        assert_eq!(
            talk(&mut u, ms(0), ":01042099000141").unwrap(),
            ":0104020500F4"
        );
        assert_eq!(
            talk(&mut u, ms(0), ":0104209A000140").unwrap(),
            ":0104021040A9"
        );
        assert_eq!(
            talk(&mut u, ms(0), ":0104209C00013E").unwrap(),
            ":0104021F805A"
        );
        assert_eq!(
            talk(&mut u, ms(0), ":0104209D00013D").unwrap(),
            ":0104022700D2"
        );
    }

    #[test]
    fn arc_time_comes_low_word_first() {
        let mut u = unit(Model::Pm85);
        for (secs, reply) in [
            (1, ":01040400010000F6"),
            (60, ":010404003C0000BB"),
            (3600, ":0104040E100000D9"),
            (360_000, ":0104047E40000534"),
        ] {
            u.set_counters(Counters {
                transfer: Accumulator::from_secs(secs),
                ..Counters::default()
            });
            assert_eq!(talk(&mut u, ms(0), ":0104209E00023B").unwrap(), reply);
        }
    }

    #[test]
    fn arc_time_counts_while_cutting() {
        let mut u = unit(Model::Pm105);
        u.set_start(ms(0), true);
        u.advance(ms(3_000));
        assert!(u.motion());
        u.set_start(ms(3_000), false);
        assert_eq!(read(&mut u, ms(3_100), 0x209E, 2), vec![3, 0]);
    }

    #[test]
    fn torch_lead_length_coils() {
        let mut u = unit(Model::Pm65);
        assert_eq!(
            talk(&mut u, ms(0), ":010108080002EC").unwrap(),
            ":01010100FD"
        );
        u.config_mut().torch_id = 0x05;
        assert_eq!(
            talk(&mut u, ms(0), ":010108080002EC").unwrap(),
            ":01010101FC"
        );
        u.config_mut().torch_id = 0x06;
        assert_eq!(
            talk(&mut u, ms(0), ":010108080002EC").unwrap(),
            ":01010102FB"
        );
    }

    #[test]
    fn block_reads_over_0x2095_and_0x2097_follow_the_flag() {
        let mut u = unit(Model::Pm125);
        assert_eq!(read(&mut u, ms(0), 0x2093, 13).len(), 13);
        u.config_mut().undocumented = UndocumentedAddresses::Refuse;
        let r =
            pdu(&exchange(&mut u, ms(1), &request(1, &[0x04, 0x20, 0x93, 0x00, 0x0D])).unwrap());
        assert_eq!(r, [0x84, 0x02]);
        assert_eq!(read(&mut u, ms(2), 0x2098, 3).len(), 3);
        assert_eq!(read(&mut u, ms(3), 0x209C, 4).len(), 4);
        // A 0x10 write across 0x2095 is refused too.
        let r = pdu(&exchange(
            &mut u,
            ms(4),
            &request(1, &write_multiple_pdu(0x2093, &[1, 40 * 64, 0, 0])),
        )
        .unwrap());
        assert_eq!(r, [0x90, 0x02]);
        u.config_mut().undocumented = UndocumentedAddresses::Accept;
        let r = pdu(&exchange(
            &mut u,
            ms(5),
            &request(1, &write_multiple_pdu(0x2093, &[1, 40 * 64, 0, 0])),
        )
        .unwrap());
        assert_eq!(r[0], 0x10);
        assert!(u.in_remote_mode());
    }

    #[test]
    fn legacy_units_have_no_0x3xxx_registers() {
        let mut u = unit(Model::Pm65);
        let r =
            pdu(&exchange(&mut u, ms(0), &request(1, &[0x04, 0x30, 0x00, 0x00, 0x01])).unwrap());
        assert_eq!(r, [0x84, 0x02]);
        let r = pdu(&exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x308E, &[0x0404, 0x0618])),
        )
        .unwrap());
        assert_eq!(r, [0x90, 0x02]);
    }

    #[test]
    fn device_identification_per_model_and_flag() {
        for (model, code) in [
            (Model::Pm45Xp, b"081288"),
            (Model::Pm65, b"081223"),
            (Model::Pm105, b"081223"),
            (Model::Pm125, b"081251"),
        ] {
            let mut u = unit(model);
            let r = pdu(&exchange(&mut u, ms(0), &request(1, &[0x2B, 0x0E, 4, 1])).unwrap());
            assert_eq!(&r[r.len() - 6..], code);
        }
        let mut u = unit(Model::Pm85);
        u.config_mut().device_id = DeviceIdSupport::IllegalFunction;
        let r = pdu(&exchange(&mut u, ms(0), &request(1, &[0x2B, 0x0E, 4, 1])).unwrap());
        assert_eq!(r, [0xAB, 0x01]);
        u.config_mut().device_id = DeviceIdSupport::Silent;
        assert!(exchange(&mut u, ms(10), &request(1, &[0x2B, 0x0E, 4, 1])).is_none());
        // ...but it still learned its address from that valid request.
        assert_eq!(u.address(), Some(1));
    }

    #[test]
    fn the_address_is_learned_again_after_power_up() {
        let mut u = unit(Model::Pm65);
        assert!(talk(&mut u, ms(0), ":01042098000142").is_some());
        u.power_off(ms(10));
        u.power_on(ms(20));
        // Boot time keeps it deaf at first.
        u.config_mut().boot_time = Duration::from_secs(1);
        u.power_off(ms(30));
        u.power_on(ms(40));
        let r = exchange(
            &mut u,
            ms(500),
            &request(9, &[0x04, 0x20, 0x98, 0x00, 0x01]),
        );
        assert!(r.is_none());
        let r = exchange(
            &mut u,
            ms(1040),
            &request(9, &[0x04, 0x20, 0x98, 0x00, 0x01]),
        );
        assert!(r.unwrap().starts_with(b":09"));
    }

    #[test]
    fn sync_units_answer_the_old_addresses() {
        let mut u = Powermax::new(PowermaxConfig::for_model(Model::Sync65));
        for f in [":01062093000145", ":010620941040F5", ":01062096230020"] {
            talk(&mut u, ms(0), f).unwrap();
        }
        assert!(u.in_remote_mode());
        assert_eq!(read(&mut u, ms(1), 0x3011, 1), vec![65 * 64]);
        assert_eq!(read(&mut u, ms(1), 0x2098, 1), vec![0]);
    }
}
