//! Simulated Hypertherm power supplies behind one byte-level interface, and the serial line
//! between them and a master in virtual time ([`line`](mod@line)).
//!
//! This crate depends on the wire formats (`plasma-protocol`) only, never on the bridge: the
//! firmware's own tests, the scenario harness and `pbtool` all use these same units.
//!
//! Every simulator is a sans-IO state machine in virtual time: the harness hands it received
//! characters and the current [`Instant`], asks for characters to send, and wakes it at
//! [`SimulatedUnit::next_wakeup`]. Nothing sleeps.
//!
//! - [`powermax::Powermax`] models both Powermax families: SYNC (45/65/85/105, registers
//!   0x3xxx, see [`sync`]) and legacy units (45 XP, 65, 85, 105, 125, registers 0x2xxx, see
//!   [`legacy`]).
//! - [`hpr::Hpr`] models HPR130/260/400 (and XD) with manual or automatic gas consoles, and the
//!   MaxPro200.
//! - [`multidrop::MultiDrop`] puts several units on one line: each answers as its manual says
//!   (HPR ids with SLEEP/WAKE, Powermax node addresses), and two answering at once collide.
//!
//! The register maps, scaling and rules are written here from the manuals, independently of
//! the bridge's own `plasma_protocol::powermax` tables, so that a mistake in one shows up as a
//! disagreement in the scenario tests.
//!
//! ```
//! use plasma_sim::{Model, SimOptions};
//! use plasma_protocol::time::Instant;
//!
//! let mut unit = Model::from_name("sync65").unwrap().build(&SimOptions::default());
//! for &b in b":010430000001CA\r\n" {
//!     unit.receive(Instant::ZERO, b);
//! }
//! let due = unit.next_wakeup().unwrap();
//! let reply = unit.poll_transmit(due).unwrap();
//! assert!(reply.starts_with(b":010402"));
//! ```

use std::any::Any;

use plasma_protocol::serial::PortConfig;
use plasma_protocol::time::{Duration, Instant};

pub mod clock;
pub mod hpr;
mod hpr_wire;
pub mod legacy;
pub mod line;
pub mod modbus_wire;
pub mod multidrop;
pub mod powermax;
pub mod sync;

pub use modbus_wire::Reply;

/// A simulated power supply as the scenario harness drives it.
pub trait SimulatedUnit {
    /// Which unit this is.
    fn model(&self) -> Model;
    /// The unit's serial settings.
    fn port(&self) -> PortConfig;
    /// A character arrived at `now`.
    fn receive(&mut self, now: Instant, byte: u8);
    /// A character arrived at `now` with a parity or framing error (the UART flagged it).
    fn receive_error(&mut self, now: Instant);
    /// Characters the unit starts sending at `now`, if a reply is due.
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>>;
    /// When the unit next needs [`advance`](Self::advance) or
    /// [`poll_transmit`](Self::poll_transmit).
    fn next_wakeup(&self) -> Option<Instant>;
    /// Runs timers (arc sequence, counters, restarts) up to `now`.
    fn advance(&mut self, now: Instant);
    /// Drives the discrete Start input.
    fn set_start(&mut self, now: Instant, on: bool);
    /// The Motion (arc transferred) output.
    fn motion(&self) -> bool;
    /// Switches the unit off: it forgets remote mode, volatile settings and a learned address.
    fn power_off(&mut self, now: Instant);
    /// Switches the unit on.
    fn power_on(&mut self, now: Instant);
    /// True while switched on.
    fn is_powered(&self) -> bool;
    /// Raises a fault / error code (the unit's own numbering: Powermax decimal code such as
    /// 500 for 0-50-0, HPR error id such as 44).
    fn inject_fault(&mut self, now: Instant, code: u16);
    /// Removes the active fault.
    fn clear_fault(&mut self, now: Instant);
    /// The active fault code (0 = none).
    fn active_fault(&self) -> u16;
    /// True while the unit is under remote (serial) control.
    fn in_remote_mode(&self) -> bool;
    /// Electrical noise the unit has made since the last call (start, length), for the line
    /// model: an HPR's HF ignition during pilot arc.
    fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)>;
    /// For downcasting to the concrete simulator and its model-specific controls.
    fn as_any(&self) -> &dyn Any;
    /// For downcasting to the concrete simulator and its model-specific controls.
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

/// Power supply families, by protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Family {
    /// Powermax SYNC: Modbus ASCII, registers 0x3xxx (and the old 0x2xxx).
    Sync,
    /// Powermax65/85/105/125 and 45 XP: Modbus ASCII, registers 0x2xxx.
    Legacy,
    /// HPR and MaxPro200: `>ID data CK<`.
    Hpr,
}

/// The simulated models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[allow(missing_docs)]
pub enum Model {
    Sync45,
    Sync65,
    Sync85,
    Sync105,
    Pm45Xp,
    Pm65,
    Pm85,
    Pm105,
    Pm125,
    Hpr130,
    Hpr260,
    Hpr400,
    Hpr130Xd,
    Hpr260Xd,
    Hpr400Xd,
    MaxPro200,
}

impl Model {
    /// Every model.
    pub const ALL: [Model; 16] = [
        Model::Sync45,
        Model::Sync65,
        Model::Sync85,
        Model::Sync105,
        Model::Pm45Xp,
        Model::Pm65,
        Model::Pm85,
        Model::Pm105,
        Model::Pm125,
        Model::Hpr130,
        Model::Hpr260,
        Model::Hpr400,
        Model::Hpr130Xd,
        Model::Hpr260Xd,
        Model::Hpr400Xd,
        Model::MaxPro200,
    ];

    /// The CLI name (`sync65`, `pm45xp`, `hpr260xd`, `maxpro200`...).
    pub fn name(self) -> &'static str {
        match self {
            Model::Sync45 => "sync45",
            Model::Sync65 => "sync65",
            Model::Sync85 => "sync85",
            Model::Sync105 => "sync105",
            Model::Pm45Xp => "pm45xp",
            Model::Pm65 => "pm65",
            Model::Pm85 => "pm85",
            Model::Pm105 => "pm105",
            Model::Pm125 => "pm125",
            Model::Hpr130 => "hpr130",
            Model::Hpr260 => "hpr260",
            Model::Hpr400 => "hpr400",
            Model::Hpr130Xd => "hpr130xd",
            Model::Hpr260Xd => "hpr260xd",
            Model::Hpr400Xd => "hpr400xd",
            Model::MaxPro200 => "maxpro200",
        }
    }

    /// Parses a CLI name (case-insensitive).
    pub fn from_name(name: &str) -> Option<Model> {
        let name = name.to_ascii_lowercase();
        Model::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Protocol family.
    pub fn family(self) -> Family {
        match self {
            Model::Sync45 | Model::Sync65 | Model::Sync85 | Model::Sync105 => Family::Sync,
            Model::Pm45Xp | Model::Pm65 | Model::Pm85 | Model::Pm105 | Model::Pm125 => {
                Family::Legacy
            }
            _ => Family::Hpr,
        }
    }

    /// Builds the simulator with `options`.
    pub fn build(self, options: &SimOptions) -> Box<dyn SimulatedUnit> {
        match self.family() {
            Family::Sync | Family::Legacy => {
                let mut config = powermax::PowermaxConfig::for_model(self);
                config.address = options.modbus_address;
                config.seed = options.seed;
                Box::new(powermax::Powermax::new(config))
            }
            Family::Hpr => {
                let mut config = hpr::HprConfig::for_model(self);
                config.id = options.hpr_id;
                config.console = options.gas_console;
                config.seed = options.seed;
                Box::new(hpr::Hpr::new(config))
            }
        }
    }
}

impl core::fmt::Display for Model {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Options common to [`Model::build`]; model-specific settings are on each simulator's config.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimOptions {
    /// PRNG seed (response-time jitter).
    pub seed: u64,
    /// Powermax node address setting; 0 = learn from the first valid request.
    pub modbus_address: u8,
    /// HPR dip-switch id, 0-3.
    pub hpr_id: u8,
    /// HPR gas console (ignored by other models; MaxPro200 has its own).
    pub gas_console: hpr::GasConsole,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            seed: 1,
            modbus_address: 0,
            hpr_id: 0,
            gas_console: hpr::GasConsole::Auto,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::line::{End, Line, RxByte, Wiring};
    use clock::earliest;
    use plasma_protocol::serial::Parity;

    /// What the loop below needs of the unit end of a line: one unit, or a line of them.
    pub(crate) trait UnitEnd {
        fn receive(&mut self, now: Instant, byte: u8);
        fn receive_error(&mut self, now: Instant);
        fn advance(&mut self, now: Instant);
        fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>>;
        fn next_wakeup(&self) -> Option<Instant>;
        fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)>;
    }

    /// One impl per type, each forwarding to the methods of the same names.
    macro_rules! unit_end_by_names {
        ($($unit:ty),+) => {$(
            impl UnitEnd for $unit {
                fn receive(&mut self, now: Instant, byte: u8) {
                    <$unit>::receive(self, now, byte)
                }
                fn receive_error(&mut self, now: Instant) {
                    <$unit>::receive_error(self, now)
                }
                fn advance(&mut self, now: Instant) {
                    <$unit>::advance(self, now)
                }
                fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>> {
                    <$unit>::poll_transmit(self, now)
                }
                fn next_wakeup(&self) -> Option<Instant> {
                    <$unit>::next_wakeup(self)
                }
                fn take_noise_bursts(&mut self) -> Vec<(Instant, Duration)> {
                    <$unit>::take_noise_bursts(self)
                }
            }
        )+};
    }

    unit_end_by_names!(dyn SimulatedUnit, crate::multidrop::MultiDrop);

    /// A minimal discrete-event loop (the shape of the scenario harness): the master sends
    /// `request` at `t0`; returns what the master hears until `until`.
    pub(crate) fn over_the_line(
        unit: &mut (impl UnitEnd + ?Sized),
        line: &mut Line,
        t0: Instant,
        request: &[u8],
        until: Instant,
    ) -> Vec<RxByte> {
        line.transmit(End::Master, t0, request);
        let mut heard = Vec::new();
        let mut now = t0;
        while let Some(t) = earliest(line.next_delivery(), unit.next_wakeup()) {
            if t > until {
                break;
            }
            now = now.max(t);
            for b in line.receive(End::Unit, now) {
                match b.error {
                    None => unit.receive(b.at, b.byte),
                    Some(_) => unit.receive_error(b.at),
                }
            }
            unit.advance(now);
            for (start, length) in unit.take_noise_bursts() {
                line.add_noise_burst(start, length);
            }
            if let Some(bytes) = unit.poll_transmit(now) {
                line.transmit(End::Unit, now, &bytes);
            }
            heard.extend(line.receive(End::Master, now));
        }
        heard
    }

    fn text(heard: &[RxByte]) -> Vec<u8> {
        heard.iter().map(|b| b.byte).collect()
    }

    #[test]
    fn every_model_round_trips_its_name_and_builds() {
        for m in Model::ALL {
            assert_eq!(Model::from_name(m.name()), Some(m));
            let unit = m.build(&SimOptions::default());
            assert_eq!(unit.model(), m);
            let expected = match m.family() {
                Family::Hpr => PortConfig::HPR,
                _ => PortConfig::MODBUS_DEFAULT,
            };
            assert_eq!(unit.port(), expected);
        }
        assert_eq!(Model::from_name("SYNC65"), Some(Model::Sync65));
        assert_eq!(Model::from_name("hd4070"), None);
    }

    #[test]
    fn a_sync_reply_arrives_with_baud_accurate_timing() {
        let mut unit = Model::Sync65.build(&SimOptions::default());
        let mut line = Line::new(unit.port(), unit.port(), Wiring::FourWire, 3);
        let heard = over_the_line(
            &mut *unit,
            &mut line,
            Instant::ZERO,
            b":010430000001CA\r\n",
            Instant::from_millis(100),
        );
        assert_eq!(text(&heard), b":0104020400F5\r\n");
        // Request: 17 characters of 572.9 us = 9.740 ms; 3 ms latency; reply: 15 characters.
        assert_eq!(heard[0].at, Instant::from_micros(12_740 + 573));
        assert_eq!(heard[14].at, Instant::from_micros(21_334));
    }

    #[test]
    fn a_sync_set_to_odd_parity_does_not_answer_an_even_parity_master() {
        let mut unit = Model::Sync65.build(&SimOptions::default());
        let odd = PortConfig {
            parity: Parity::Odd,
            ..PortConfig::MODBUS_DEFAULT
        };
        let mut line = Line::new(PortConfig::MODBUS_DEFAULT, odd, Wiring::FourWire, 3);
        let heard = over_the_line(
            &mut *unit,
            &mut line,
            Instant::ZERO,
            b":010430000001CA\r\n",
            Instant::from_millis(100),
        );
        assert!(heard.is_empty());
    }

    #[test]
    fn hpr_traffic_is_lost_in_the_hf_ignition_burst_and_works_after_it() {
        let mut unit = Model::Hpr260.build(&SimOptions::default());
        {
            let hpr = unit.as_any_mut().downcast_mut::<hpr::Hpr>().unwrap();
            hpr.config_mut().timings.transfer_delay = None;
            hpr.config_mut().timings.pilot_timeout = Duration::from_secs(2);
        }
        let mut line = Line::new(PortConfig::HPR, PortConfig::HPR, Wiring::FourWire, 5);
        unit.advance(Instant::from_millis(3_000));
        unit.set_start(Instant::from_millis(3_000), true);
        // Ignition at 3.5 s: the noise burst lasts 1 s.
        let during = over_the_line(
            &mut *unit,
            &mut line,
            Instant::from_millis(3_600),
            b">00292<",
            Instant::from_millis(3_700),
        );
        assert!(!text(&during).windows(4).any(|w| w == b">002"));
        let after = over_the_line(
            &mut *unit,
            &mut line,
            Instant::from_millis(4_600),
            b">00292<",
            Instant::from_millis(4_700),
        );
        // Still pilot arc (state 5) at 4.6 s.
        assert!(text(&after).ends_with(b">002000557<"), "{:?}", text(&after));
    }
}
