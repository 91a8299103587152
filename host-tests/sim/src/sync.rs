//! Powermax45/65/85/105 SYNC: the 0x3xxx register map, cartridges, quick restart, and the
//! model tables, written from the *Powermax SYNC Serial Communication Programmer Reference
//! Guide* (seed 000). The unit itself is [`Powermax`].
//!
//! | address | content |
//! |---|---|
//! | 0x3000 | high byte torch id (Table 3), low byte power supply type id (Table 4) |
//! | 0x3001 | permitted modes: high byte highest, low byte lowest |
//! | 0x3002 / 0x3003 | permitted current min / max, A x 64 |
//! | 0x3004 / 0x3005 | permitted pressure min / max, psi x 128 |
//! | 0x3010-0x3012 | mode, current (A x 64), pressure (psi x 128) in use |
//! | 0x3018 / 0x3019 | actual current (A x 64), actual pressure (psi x 128) |
//! | 0x301A | active fault code (decimal code, 0-50-0 = 500) |
//! | 0x3028-0x302F | power supply starts, pilot s, transfers, transfer s: 32 bit, low word first |
//! | 0x3030-0x3037 | cartridge UID, 16 ASCII characters |
//! | 0x3038-0x303A, 0x303B | cartridge part number (6 ASCII), revision |
//! | 0x303C | cartridge nominal current, A x 64 (the guide's unit "Amperes" as for 0x3002) |
//! | 0x3040-0x3043 | cartridge starts, pilot s, transfers, transfer time in 2 s counts |
//! | 0x3044-0x3047 | cartridge fault log, newest first |
//! | 0x3048-0x304D | cartridge name, 12 ASCII characters (Table 7) |
//! | 0x3080-0x3082 | write: mode, current, pressure (remote mode) |
//! | 0x308E / 0x308F | write 0x0404 / 0x0618: quick restart (stops 0-50-0) |
//! | coils 0x3100 / 0x3101 | Start input / Motion output |
//! | coil 0x3180 | write: gas test on / off |
//!
//! Current ranges of the power supplies (maximum from the model name; the minimum is not in the
//! guide, values from Hypertherm's published specifications): SYNC45 10-45 A, SYNC65 20-65 A,
//! SYNC85 25-85 A, SYNC105 30-105 A. The permitted range with a cartridge is the power supply's
//! range capped at the cartridge's nominal current: a 45 A cartridge on a SYNC105 permits
//! 30-45 A, as in the guide's example reply.

use plasma_protocol::modbus_ascii::ExceptionCode;

use super::clock::Accumulator;
use super::powermax::{Cell, Powermax};
use super::{Model, SimulatedUnit};
use plasma_protocol::time::Instant;

/// Low byte of 0x3000 (Table 4) for the CSA variant of each model.
pub fn type_id(model: Model) -> u8 {
    match model {
        Model::Sync45 => 0x11,
        Model::Sync65 => 0x00,
        Model::Sync85 => 0x02,
        _ => 0x08,
    }
}

/// Output current range, amps.
pub fn current_range(model: Model) -> (u16, u16) {
    match model {
        Model::Sync45 => (10, 45),
        Model::Sync65 => (20, 65),
        Model::Sync85 => (25, 85),
        _ => (30, 105),
    }
}

/// Read Device Identification product code (Table 2).
pub fn product_code(model: Model) -> &'static str {
    match model {
        Model::Sync45 => "081374",
        _ => "081335",
    }
}

/// Cartridge types (Table 5) with their names (Table 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum CartridgeKind {
    Cut105,
    Cut85,
    Cut65,
    Cut45,
    FineCut45,
    MaxControlGouge105,
    MaxControlGouge65_85,
    MaxControlGouge45,
    MaxRemovalGouge105,
    MaxRemovalGouge45_65_85,
}

impl CartridgeKind {
    /// Part number (Table 5).
    pub fn part_number(self) -> &'static str {
        match self {
            CartridgeKind::Cut105 => "428936",
            CartridgeKind::Cut85 => "428934",
            CartridgeKind::Cut65 => "428930",
            CartridgeKind::Cut45 => "428925",
            CartridgeKind::FineCut45 => "428926",
            CartridgeKind::MaxControlGouge105 => "428939",
            CartridgeKind::MaxControlGouge65_85 => "428933",
            CartridgeKind::MaxControlGouge45 => "428929",
            CartridgeKind::MaxRemovalGouge105 => "428938",
            CartridgeKind::MaxRemovalGouge45_65_85 => "428932",
        }
    }

    /// Name as stored in the cartridge (Table 7).
    pub fn name(self) -> &'static str {
        match self {
            CartridgeKind::Cut105
            | CartridgeKind::Cut85
            | CartridgeKind::Cut65
            | CartridgeKind::Cut45 => "C MECH",
            CartridgeKind::FineCut45 => "C MFNC",
            CartridgeKind::MaxControlGouge105
            | CartridgeKind::MaxControlGouge65_85
            | CartridgeKind::MaxControlGouge45 => "G CNTL",
            CartridgeKind::MaxRemovalGouge105 | CartridgeKind::MaxRemovalGouge45_65_85 => "G RMVL",
        }
    }

    /// Highest current the cartridge is rated for, amps.
    pub fn nominal_amps(self) -> u16 {
        match self {
            CartridgeKind::Cut105
            | CartridgeKind::MaxControlGouge105
            | CartridgeKind::MaxRemovalGouge105 => 105,
            CartridgeKind::Cut85
            | CartridgeKind::MaxControlGouge65_85
            | CartridgeKind::MaxRemovalGouge45_65_85 => 85,
            CartridgeKind::Cut65 => 65,
            CartridgeKind::Cut45 | CartridgeKind::FineCut45 | CartridgeKind::MaxControlGouge45 => {
                45
            }
        }
    }

    /// True for gouging cartridges (mode 3 only).
    pub fn is_gouge(self) -> bool {
        self.name().starts_with('G')
    }
}

/// A SYNC cartridge: identity, permitted settings, its own counters and fault log.
#[derive(Debug, Clone, PartialEq)]
pub struct Cartridge {
    /// Type.
    pub kind: CartridgeKind,
    /// 16-character UID.
    pub uid: [u8; 16],
    /// Part number revision register value.
    pub revision: u16,
    /// Nominal current, amps.
    pub nominal_amps: u16,
    /// Lowest current the cartridge permits, amps (the power supply's minimum applies too).
    pub min_amps: u16,
    /// Permitted pressure, psi (illustrative default 58-78 psi, from the guide's example).
    pub psi: (u16, u16),
    /// Automatic pressure, psi.
    pub auto_psi: u16,
    /// Pilot arc starts (16 bit).
    pub starts: u16,
    /// Pilot arc time.
    pub pilot: Accumulator,
    /// Arc transfers (16 bit).
    pub transfers: u16,
    /// Transferred arc time.
    pub transfer: Accumulator,
    /// Fault log, newest first.
    pub fault_log: [u16; 4],
}

impl Cartridge {
    /// A new cartridge of `kind` with `uid` (up to 16 ASCII characters, zero padded).
    pub fn new(kind: CartridgeKind, uid: &str) -> Cartridge {
        let mut id = [0u8; 16];
        for (d, s) in id.iter_mut().zip(uid.bytes()) {
            *d = s;
        }
        Cartridge {
            kind,
            uid: id,
            revision: 0x0001,
            nominal_amps: kind.nominal_amps(),
            min_amps: 10,
            psi: (58, 78),
            auto_psi: 72,
            starts: 0,
            pilot: Accumulator::default(),
            transfers: 0,
            transfer: Accumulator::default(),
            fault_log: [0; 4],
        }
    }

    /// The cut cartridge matching a power supply's rating, with the guide's example UID.
    pub fn default_for(model: Model) -> Cartridge {
        let kind = match model {
            Model::Sync45 => CartridgeKind::Cut45,
            Model::Sync65 => CartridgeKind::Cut65,
            Model::Sync85 => CartridgeKind::Cut85,
            _ => CartridgeKind::Cut105,
        };
        Cartridge::new(kind, "E00401D0036FB25D")
    }

    /// Permitted modes (lowest, highest) on `model`: cut cartridges also allow expanded metal
    /// (2) except on the Powermax45 SYNC; gouging cartridges only gouge (3).
    pub fn modes(&self, model: Model) -> (u16, u16) {
        match (self.kind.is_gouge(), model) {
            (true, _) => (3, 3),
            (false, Model::Sync45) => (1, 1),
            (false, _) => (1, 2),
        }
    }

    pub(crate) fn log_fault(&mut self, code: u16) {
        if code != 0 {
            self.fault_log.rotate_right(1);
            self.fault_log[0] = code;
        }
    }
}

fn ascii_word(text: &[u8], index: usize) -> u16 {
    let byte = |i: usize| u16::from(text.get(i).copied().unwrap_or(0));
    byte(index * 2) << 8 | byte(index * 2 + 1)
}

/// Reads one 0x3xxx register.
pub(crate) fn register(unit: &Powermax, address: u16) -> Cell {
    let limits = unit.limits();
    let settings = unit.settings();
    let counters = unit.counters();
    let cartridge = unit.cartridge();
    let low = |v: u64| (v & 0xFFFF) as u16;
    let high = |v: u64| ((v >> 16) & 0xFFFF) as u16;
    let cart = |f: &dyn Fn(&Cartridge) -> u16| cartridge.map_or(0, f);
    let value = match address {
        0x3000 => u16::from(unit.config().torch_id) << 8 | u16::from(unit.config().type_id),
        0x3001 => limits.modes.1 << 8 | limits.modes.0,
        0x3002 => limits.current.0,
        0x3003 => limits.current.1,
        0x3004 => limits.pressure.0,
        0x3005 => limits.pressure.1,
        0x3006..=0x300F => return Cell::Gap,
        0x3010 => settings.mode,
        0x3011 => settings.current,
        0x3012 => unit.effective_pressure(),
        0x3013..=0x3017 => return Cell::Gap,
        0x3018 => unit.actual_current(),
        0x3019 => unit.actual_pressure(),
        0x301A => unit.active_fault(),
        0x301B..=0x3027 => return Cell::Gap,
        0x3028 => low(counters.starts.into()),
        0x3029 => high(counters.starts.into()),
        0x302A => low(counters.pilot.secs()),
        0x302B => high(counters.pilot.secs()),
        0x302C => low(counters.transfers.into()),
        0x302D => high(counters.transfers.into()),
        0x302E => low(counters.transfer.secs()),
        0x302F => high(counters.transfer.secs()),
        0x3030..=0x3037 => cart(&|c| ascii_word(&c.uid, usize::from(address - 0x3030))),
        0x3038..=0x303A => cart(&|c| {
            ascii_word(
                c.kind.part_number().as_bytes(),
                usize::from(address - 0x3038),
            )
        }),
        0x303B => cart(&|c| c.revision),
        0x303C => cart(&|c| c.nominal_amps * 64),
        0x303D..=0x303F => return Cell::Gap,
        0x3040 => cart(&|c| c.starts),
        0x3041 => cart(&|c| c.pilot.secs().min(0xFFFF) as u16),
        0x3042 => cart(&|c| c.transfers),
        0x3043 => cart(&|c| (c.transfer.secs() / 2).min(0xFFFF) as u16),
        0x3044..=0x3047 => cart(&|c| c.fault_log[usize::from(address - 0x3044)]),
        0x3048..=0x304D => {
            cart(&|c| ascii_word(c.kind.name().as_bytes(), usize::from(address - 0x3048)))
        }
        _ => return Cell::Unknown,
    };
    Cell::Value(value)
}

/// Reads one 0x3xxx coil.
pub(crate) fn coil(unit: &Powermax, address: u16) -> Cell {
    match address {
        0x3100 => Cell::Value(unit.start_input().into()),
        0x3101 => Cell::Value(unit.motion().into()),
        _ => Cell::Unknown,
    }
}

/// Function 0x10 to 0x3080-0x308F: settings / remote mode, or the quick restart.
pub(crate) fn write_multiple(
    unit: &mut Powermax,
    now: Instant,
    start: u16,
    values: &[u16],
) -> Result<(), ExceptionCode> {
    let end = u32::from(start) + values.len() as u32;
    match start {
        0x3080..=0x3082 if end <= 0x3083 => {
            let writes: Vec<(usize, u16)> = values
                .iter()
                .enumerate()
                .map(|(i, &v)| (usize::from(start - 0x3080) + i, v))
                .collect();
            unit.write_force(&writes, true)
        }
        0x308E if values == [0x0404, 0x0618] => {
            unit.quick_restart(now);
            Ok(())
        }
        0x308E | 0x308F if end <= 0x3090 => Err(ExceptionCode::IllegalDataValue),
        _ => Err(ExceptionCode::IllegalDataAddress),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SimulatedUnit;
    use crate::powermax::testing::*;
    use crate::powermax::{ArcState, Counters, OutOfRange, PowermaxConfig, UndocumentedAddresses};
    use plasma_protocol::time::Duration;

    fn unit(model: Model) -> Powermax {
        Powermax::new(PowermaxConfig::for_model(model))
    }

    fn ms(t: u64) -> Instant {
        Instant::from_millis(t)
    }

    /// Sends a manual frame (text without CR LF) and returns the reply text without CR LF.
    fn talk(unit: &mut Powermax, now: Instant, frame: &str) -> Option<String> {
        let mut bytes = frame.as_bytes().to_vec();
        bytes.extend_from_slice(b"\r\n");
        exchange(unit, now, &bytes).map(|r| {
            assert!(r.ends_with(b"\r\n"));
            String::from_utf8(r[..r.len() - 2].to_vec()).unwrap()
        })
    }

    #[test]
    fn identification_register_matches_the_guide() {
        let mut config = PowermaxConfig::for_model(Model::Sync105);
        config.torch_id = 0x05;
        let mut u = Powermax::new(config);
        assert_eq!(
            talk(&mut u, ms(0), ":010430000001CA").unwrap(),
            ":0104020508EC"
        );
    }

    #[test]
    fn device_identification_matches_table_2() {
        let mut u = unit(Model::Sync65);
        assert_eq!(
            talk(&mut u, ms(0), ":012B0E0401C1").unwrap(),
            ":012B0E0481000101010630383133333504"
        );
        let mut u = unit(Model::Sync45);
        let reply = pdu(&exchange(&mut u, ms(0), &request(1, &[0x2B, 0x0E, 4, 1])).unwrap());
        assert_eq!(&reply[reply.len() - 6..], b"081374");
    }

    #[test]
    fn permitted_settings_for_a_45_a_cartridge_on_a_sync105() {
        let mut u = unit(Model::Sync105);
        u.install_cartridge(ms(0), Cartridge::new(CartridgeKind::Cut45, "X"));
        assert_eq!(
            talk(&mut u, ms(0), ":010430010005C5").unwrap(),
            ":01040A020107800B401D002700D8"
        );
    }

    #[test]
    fn remote_mode_is_entered_with_all_three_settings_and_left_with_zeros() {
        let mut u = unit(Model::Sync65);
        assert!(!u.in_remote_mode());
        assert_eq!(
            talk(&mut u, ms(0), ":0110308000030600010FC0000066").unwrap(),
            ":0110308000033C"
        );
        assert!(u.in_remote_mode());
        // 63 A, cut, automatic pressure (72 psi = 0x2400 for the default cartridge).
        assert_eq!(
            read(&mut u, ms(10), 0x3010, 3),
            vec![0x0001, 0x0FC0, 0x2400]
        );
        // Exit. The guide's frame ":01103080000306000000000000036" has one '0' too many;
        // the LRC 36 is right for the 28-character frame.
        assert_eq!(
            talk(&mut u, ms(20), ":0110308000030600000000000036").unwrap(),
            ":0110308000033C"
        );
        assert!(!u.in_remote_mode());
        assert_eq!(u.active_fault(), 0);
    }

    #[test]
    fn a_partial_settings_write_raises_0_11_n_and_does_not_enter_remote_mode() {
        // Only the current (function 06): mode is missing first -> 0-11-0.
        let mut u = unit(Model::Sync85);
        let r = exchange(&mut u, ms(0), &request(1, &[0x06, 0x30, 0x81, 0x10, 0x40])).unwrap();
        assert_eq!(pdu(&r), [0x06, 0x30, 0x81, 0x10, 0x40]);
        assert!(!u.in_remote_mode());
        assert_eq!(read(&mut u, ms(10), 0x301A, 1), vec![110]);
        // Mode and current without pressure -> 0-11-2.
        let mut u = unit(Model::Sync85);
        exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x3080, &[1, 0x1040])),
        )
        .unwrap();
        assert!(!u.in_remote_mode());
        assert_eq!(u.active_fault(), 112);
        // A complete write afterwards clears it.
        exchange(
            &mut u,
            ms(5),
            &request(1, &write_multiple_pdu(0x3080, &[1, 0x1040, 0])),
        )
        .unwrap();
        assert!(u.in_remote_mode());
        assert_eq!(u.active_fault(), 0);
        // In the cartridge's fault log, newest first.
        assert_eq!(read(&mut u, ms(10), 0x3044, 4), vec![112, 0, 0, 0]);
    }

    #[test]
    fn out_of_range_settings_raise_a_fault_or_an_exception() {
        let mut u = unit(Model::Sync65);
        exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x3080, &[1, 65 * 64, 0])),
        )
        .unwrap();
        // 80 A is above the 65 A cartridge: acknowledged, not applied, 0-11-1.
        let r = exchange(&mut u, ms(5), &request(1, &[0x06, 0x30, 0x81, 0x14, 0x00])).unwrap();
        assert_eq!(pdu(&r)[0], 0x06);
        assert_eq!(u.active_fault(), 111);
        assert_eq!(u.settings().current, 65 * 64);
        // Pressure 100 psi: 0-11-2. Mode 2 (expanded metal) is fine on a SYNC65.
        exchange(&mut u, ms(6), &request(1, &[0x06, 0x30, 0x82, 0x32, 0x00])).unwrap();
        assert_eq!(u.active_fault(), 112);
        exchange(&mut u, ms(7), &request(1, &[0x06, 0x30, 0x80, 0x00, 0x02])).unwrap();
        assert_eq!(u.active_fault(), 0);
        assert_eq!(u.settings().mode, 2);

        let mut config = PowermaxConfig::for_model(Model::Sync65);
        config.out_of_range = OutOfRange::Exception;
        let mut u = Powermax::new(config);
        let r = exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x3080, &[1, 90 * 64, 0])),
        )
        .unwrap();
        assert_eq!(pdu(&r), [0x90, 0x03]);
        assert!(!u.in_remote_mode());
    }

    #[test]
    fn expanded_metal_is_not_permitted_on_the_sync45() {
        let mut u = unit(Model::Sync45);
        assert_eq!(read(&mut u, ms(0), 0x3001, 1), vec![0x0101]);
        exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x3080, &[2, 40 * 64, 0])),
        )
        .unwrap();
        assert_eq!(u.active_fault(), 110);
    }

    #[test]
    fn a_unit_set_to_address_0_learns_the_first_valid_request() {
        let mut u = unit(Model::Sync65);
        // A frame with a bad LRC does not count.
        assert_eq!(talk(&mut u, ms(0), ":070430000001C5"), None);
        assert_eq!(u.address(), None);
        let r = exchange(&mut u, ms(1), &request(7, &[0x04, 0x30, 0x00, 0x00, 0x01])).unwrap();
        assert!(r.starts_with(b":07"));
        assert_eq!(u.address(), Some(7));
        assert_eq!(talk(&mut u, ms(2), ":010430000001CA"), None);
        // Power cycle: learns again.
        u.power_off(ms(10));
        u.power_on(ms(20));
        assert!(talk(&mut u, ms(30), ":010430000001CA").is_some());
        assert_eq!(u.address(), Some(1));
    }

    #[test]
    fn a_unit_with_an_address_set_ignores_other_addresses() {
        let mut config = PowermaxConfig::for_model(Model::Sync65);
        config.address = 3;
        let mut u = Powermax::new(config);
        assert_eq!(talk(&mut u, ms(0), ":010430000001CA"), None);
        assert!(exchange(&mut u, ms(1), &request(3, &[0x04, 0x30, 0x00, 0x00, 0x01])).is_some());
    }

    #[test]
    fn exceptions_for_unknown_addresses_functions_and_quantities() {
        let mut u = unit(Model::Sync65);
        let ask = |u: &mut Powermax, p: &[u8]| pdu(&exchange(u, ms(0), &request(1, p)).unwrap());
        assert_eq!(ask(&mut u, &[0x04, 0x40, 0x00, 0x00, 0x01]), [0x84, 0x02]);
        assert_eq!(ask(&mut u, &[0x04, 0x30, 0x4D, 0x00, 0x02]), [0x84, 0x02]);
        assert_eq!(ask(&mut u, &[0x02, 0x31, 0x00, 0x00, 0x01]), [0x82, 0x01]);
        assert_eq!(ask(&mut u, &[0x04, 0x30, 0x00, 0x00, 0x00]), [0x84, 0x03]);
        assert_eq!(ask(&mut u, &[0x04, 0x30, 0x00, 0x00, 0x7E]), [0x84, 0x03]);
        assert_eq!(ask(&mut u, &[0x06, 0x30, 0x00, 0x00, 0x01]), [0x86, 0x02]);
        assert_eq!(ask(&mut u, &[0x05, 0x31, 0x00, 0xFF, 0x00]), [0x85, 0x02]);
        // Settings registers are write-only.
        assert_eq!(ask(&mut u, &[0x04, 0x30, 0x80, 0x00, 0x03]), [0x84, 0x02]);
        // A quick restart with the wrong approval value.
        assert_eq!(
            ask(&mut u, &write_multiple_pdu(0x308E, &[0x0404, 0x0000])),
            [0x90, 0x03]
        );
    }

    #[test]
    fn function_03_reads_the_same_registers_as_04() {
        let mut u = unit(Model::Sync65);
        let r =
            pdu(&exchange(&mut u, ms(0), &request(1, &[0x03, 0x30, 0x00, 0x00, 0x01])).unwrap());
        assert_eq!(r, [0x03, 0x02, 0x04, 0x00]);
    }

    #[test]
    fn block_reads_over_undocumented_addresses_follow_the_flag() {
        let mut u = unit(Model::Sync65);
        let values = read(&mut u, ms(0), 0x3010, 11);
        assert_eq!(values.len(), 11);
        assert_eq!(&values[3..8], &[0; 5]);
        assert_eq!(values[10], 0); // 0x301A, no fault

        let mut config = PowermaxConfig::for_model(Model::Sync65);
        config.undocumented = UndocumentedAddresses::Refuse;
        let mut u = Powermax::new(config);
        let r =
            pdu(&exchange(&mut u, ms(0), &request(1, &[0x04, 0x30, 0x10, 0x00, 0x0B])).unwrap());
        assert_eq!(r, [0x84, 0x02]);
        // The documented sub-blocks still work.
        assert_eq!(read(&mut u, ms(1), 0x3010, 3).len(), 3);
        assert_eq!(read(&mut u, ms(2), 0x3018, 3).len(), 3);
    }

    #[test]
    fn quick_restart_clears_0_50_0_then_the_unit_is_deaf_for_2_s() {
        let mut u = unit(Model::Sync65);
        u.remove_cartridge(ms(0));
        assert_eq!(
            talk(&mut u, ms(1), ":0104301A0001B0").unwrap(),
            ":01040201F404"
        );
        u.install_cartridge(
            ms(100),
            Cartridge::new(CartridgeKind::Cut65, "NEWCARTRIDGE0001"),
        );
        assert_eq!(u.active_fault(), 500);
        let t = ms(200);
        assert_eq!(
            talk(&mut u, t, ":0110308E0002040404061805").unwrap(),
            ":0110308E00022F"
        );
        assert_eq!(u.active_fault(), 0);
        assert_eq!(
            talk(&mut u, t + Duration::from_millis(1999), ":0104301A0001B0"),
            None
        );
        assert_eq!(
            talk(&mut u, t + Duration::from_millis(2000), ":0104301A0001B0").unwrap(),
            ":0104020000F9"
        );
        // The new cartridge's UID.
        let uid = read(&mut u, t + Duration::from_millis(2100), 0x3030, 8);
        assert_eq!(uid[0], u16::from_be_bytes(*b"NE"));
    }

    #[test]
    fn quick_restart_does_not_clear_other_faults() {
        let mut u = unit(Model::Sync65);
        u.inject_fault(ms(0), 320);
        talk(&mut u, ms(1), ":0110308E0002040404061805").unwrap();
        assert_eq!(u.active_fault(), 320);
    }

    #[test]
    fn counters_advance_with_the_arc() {
        let mut u = unit(Model::Sync65);
        u.config_mut().timings.transfer_delay = Some(Duration::from_millis(500));
        u.set_start(ms(1000), true);
        assert_eq!(u.arc_state(), ArcState::Pilot);
        assert_eq!(u.next_wakeup(), Some(ms(1500)));
        u.advance(ms(1499));
        assert!(!u.motion());
        u.advance(ms(1500));
        assert!(u.motion());
        assert_eq!(
            talk(&mut u, ms(1600), ":010131000002CB").unwrap(),
            ":01010103FA"
        );
        u.set_start(ms(5500), false);
        assert!(!u.motion());
        assert_eq!(u.arc_state(), ArcState::Postflow);
        // Power supply counters: 1 start, 0 s pilot (0.5 s), 1 transfer, 4 s transferred.
        assert_eq!(
            read(&mut u, ms(5600), 0x3028, 8),
            vec![1, 0, 0, 0, 1, 0, 4, 0]
        );
        // Cartridge counters (transfer time in 2 s counts).
        assert_eq!(read(&mut u, ms(5600), 0x3040, 4), vec![1, 0, 1, 2]);
        // Postflow ends.
        u.advance(ms(15_500));
        assert_eq!(u.arc_state(), ArcState::Idle);
        assert_eq!(read(&mut u, ms(15_600), 0x3019, 1), vec![0]);
    }

    #[test]
    fn thirty_two_bit_counters_come_low_word_first() {
        let mut u = unit(Model::Sync65);
        u.set_counters(Counters {
            starts: 53_686,
            pilot: Accumulator::from_secs(4_331),
            transfers: 53_365,
            transfer: Accumulator::from_secs(447_918),
        });
        assert_eq!(
            talk(&mut u, ms(0), ":0104302800089B").unwrap(),
            ":010410D1B6000010EB0000D0750000D5AE00069B"
        );
    }

    #[test]
    fn cartridge_registers_match_the_guide() {
        let mut u = unit(Model::Sync105);
        {
            let c = u.cartridge_mut().unwrap();
            c.starts = 214;
            c.pilot = Accumulator::from_secs(9);
            c.transfers = 211;
            c.transfer = Accumulator::from_secs(4_894);
        }
        assert_eq!(
            talk(&mut u, ms(0), ":01043040000487").unwrap(),
            ":01040800D6000900D3098FA9"
        );
        assert_eq!(
            talk(&mut u, ms(1), ":01043038000390").unwrap(),
            ":010406343238393336B5"
        );
        assert_eq!(
            talk(&mut u, ms(2), ":01043030000893").unwrap(),
            ":0104104530303430314430303336464232354471"
        );
        // The guide's ":01040C43204D45434800000000000006F" has one '0' too many.
        assert_eq!(
            talk(&mut u, ms(3), ":0104304800067D").unwrap(),
            ":01040C43204D4543480000000000006F"
        );
        u.inject_fault(ms(4), 121);
        u.clear_fault(ms(5));
        u.inject_fault(ms(6), 121);
        // The guide's ":0104080079007900000000001" has one '0' too many; the LRC 01 is right.
        assert_eq!(
            talk(&mut u, ms(7), ":01043044000483").unwrap(),
            ":010408007900790000000001"
        );
        assert_eq!(read(&mut u, ms(8), 0x303C, 1), vec![105 * 64]);
    }

    #[test]
    fn actual_output_while_cutting_matches_the_guide() {
        let mut u = unit(Model::Sync65);
        exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x3080, &[1, 65 * 64, 0x23DD])),
        )
        .unwrap();
        assert!(u.in_remote_mode());
        u.set_start(ms(10), true);
        u.advance(ms(200));
        assert_eq!(
            talk(&mut u, ms(200), ":010430180002B1").unwrap(),
            ":010404104023DDA7"
        );
    }

    #[test]
    fn settings_readback_matches_the_guide() {
        let mut u = unit(Model::Sync105);
        exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x3080, &[1, 105 * 64, 76 * 128])),
        )
        .unwrap();
        assert_eq!(
            talk(&mut u, ms(5), ":010430100003B8").unwrap(),
            ":01040600011A40260074"
        );
    }

    #[test]
    fn gas_test_starts_and_stops() {
        let mut u = unit(Model::Sync65);
        assert_eq!(
            talk(&mut u, ms(0), ":01053180FF004A").unwrap(),
            ":01053180FF004A"
        );
        assert!(u.gas_test_active());
        assert_eq!(read(&mut u, ms(5), 0x3019, 1), vec![72 * 128]);
        // No arc during a gas test.
        u.set_start(ms(10), true);
        assert_eq!(u.arc_state(), ArcState::Idle);
        u.set_start(ms(20), false);
        assert_eq!(
            talk(&mut u, ms(30), ":01053180000049").unwrap(),
            ":01053180000049"
        );
        assert!(!u.gas_test_active());
        // The old coil address works too.
        exchange(&mut u, ms(40), &request(1, &[0x05, 0x08, 0x32, 0xFF, 0x00])).unwrap();
        assert!(u.gas_test_active());
    }

    #[test]
    fn power_cycle_loses_remote_mode_and_settings() {
        let mut u = unit(Model::Sync85);
        exchange(
            &mut u,
            ms(0),
            &request(1, &write_multiple_pdu(0x3080, &[1, 40 * 64, 0])),
        )
        .unwrap();
        assert!(u.in_remote_mode());
        u.power_off(ms(100));
        assert_eq!(talk(&mut u, ms(200), ":010430000001CA"), None);
        u.power_on(ms(300));
        assert!(!u.in_remote_mode());
        assert_eq!(u.settings().current, 85 * 64);
    }

    #[test]
    fn a_unit_whose_remote_settings_do_not_apply_reads_back_its_panel() {
        let mut u = unit(Model::Sync65);
        u.config_mut().remote_settings_apply = false;
        let panel = read(&mut u, ms(0), 0x3010, 3);
        let echo = exchange(
            &mut u,
            ms(10),
            &request(1, &write_multiple_pdu(0x3080, &[2, 40 * 64, 0])),
        )
        .unwrap();
        assert_eq!(pdu(&echo)[0], 0x10, "acknowledged");
        assert_eq!(read(&mut u, ms(20), 0x3010, 3), panel);
    }

    #[test]
    fn refused_registers_fail_every_read_that_touches_them() {
        let mut u = unit(Model::Sync65);
        u.config_mut().refused_registers = vec![0x3001];
        let ask = |u: &mut Powermax, start: u16, quantity: u16| {
            let mut p = vec![0x04];
            p.extend_from_slice(&start.to_be_bytes());
            p.extend_from_slice(&quantity.to_be_bytes());
            pdu(&exchange(u, ms(0), &request(1, &p)).unwrap())
        };
        assert_eq!(ask(&mut u, 0x3000, 6), vec![0x84, 0x02]);
        assert_eq!(ask(&mut u, 0x3001, 1), vec![0x84, 0x02]);
        assert_eq!(ask(&mut u, 0x3002, 4)[0], 0x04);
    }

    #[test]
    fn start_held_at_power_up_is_a_stuck_start_until_released() {
        let mut u = unit(Model::Sync65);
        u.power_off(ms(0));
        u.set_start(ms(10), true);
        u.power_on(ms(20));
        assert_eq!(u.active_fault(), 510);
        assert_eq!(u.arc_state(), ArcState::Idle);
        u.set_start(ms(30), false);
        assert_eq!(u.active_fault(), 0);
        u.set_start(ms(100), true);
        assert_eq!(u.arc_state(), ArcState::Pilot);
    }

    #[test]
    fn a_blocking_fault_stops_the_arc_and_prevents_a_start() {
        let mut u = unit(Model::Sync65);
        u.set_start(ms(0), true);
        u.advance(ms(200));
        assert!(u.motion());
        u.inject_fault(ms(300), 220);
        assert!(!u.motion());
        u.set_start(ms(400), false);
        u.set_start(ms(500), true);
        assert_ne!(u.arc_state(), ArcState::Pilot);
        // A warning (0-12-1) does not.
        u.set_start(ms(600), false);
        u.clear_fault(ms(600));
        u.inject_fault(ms(700), 121);
        u.advance(ms(20_000));
        u.set_start(ms(20_000), true);
        assert_eq!(u.arc_state(), ArcState::Pilot);
    }

    #[test]
    fn replies_come_after_the_configured_latency() {
        let mut u = unit(Model::Sync65);
        u.config_mut().latency = Duration::from_millis(7);
        for &b in b":010430000001CA\r\n" {
            u.receive(ms(100), b);
        }
        assert_eq!(u.next_wakeup(), Some(ms(107)));
        assert_eq!(u.poll_transmit(ms(106)), None);
        assert!(u.poll_transmit(ms(107)).is_some());
    }

    #[test]
    fn a_character_with_a_parity_error_voids_the_frame() {
        let mut u = unit(Model::Sync65);
        for (i, &b) in b":010430000001CA\r\n".iter().enumerate() {
            if i == 5 {
                u.receive_error(ms(0));
            } else {
                u.receive(ms(0), b);
            }
        }
        assert_eq!(u.next_wakeup(), None);
    }

    #[test]
    fn broadcast_writes_are_executed_without_reply() {
        let mut u = unit(Model::Sync65);
        assert!(
            exchange(
                &mut u,
                ms(0),
                &request(0, &write_multiple_pdu(0x3080, &[1, 40 * 64, 0]))
            )
            .is_none()
        );
        assert!(u.in_remote_mode());
        assert_eq!(u.address(), None);
    }
}
