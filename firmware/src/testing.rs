//! Test-only: a real simulated power supply of `plasma-sim` on the far end of a baud-accurate
//! serial line, driven in virtual time against the link or the whole bridge.
//!
//! The firmware's own tests use the same units as the scenario harness and `pbtool`, so a
//! test here cannot pass against a private idea of how a unit answers. What a test needs of an
//! unusual unit (one that refuses a block read, does not apply remote settings, a cable
//! pulled) is an option of the simulator or of the line, set through [`SimPs`].

extern crate std;

use std::boxed::Box;
use std::vec::Vec;

use plasma_protocol::time::Instant;
use plasma_sim::clock::earliest;
use plasma_sim::hpr::Hpr;
use plasma_sim::line::{End, Line, Wiring};
use plasma_sim::powermax::Powermax;
use plasma_sim::{Model, SimOptions, SimulatedUnit};

use crate::platform::PsEndpoint;

/// A simulated unit at the end of a serial line, every frame the master sent it and every
/// character it heard back.
pub(crate) struct SimPs {
    unit: Box<dyn SimulatedUnit>,
    line: Line,
    /// Every frame the master sent, with the instant it began to send it.
    pub sent: Vec<(Instant, Vec<u8>)>,
    /// Every character the master was handed, with its instant.
    pub heard: Vec<(Instant, u8)>,
}

impl SimPs {
    /// The model named as on pbtool's command line (`sync65`, `pm65`, `hpr130`, `maxpro200`),
    /// with the simulator's defaults (address learned from the first request, dip switch 0).
    pub(crate) fn new(model: &str) -> Self {
        let model = Model::from_name(model).expect("a plasma-sim model name");
        Self::with_unit(model.build(&SimOptions::default()))
    }

    /// `unit` on a fresh four-wire line.
    pub(crate) fn with_unit(unit: Box<dyn SimulatedUnit>) -> Self {
        Self::on_line(unit, Wiring::FourWire)
    }

    /// `unit` on a fresh line wired as `wiring`.
    pub(crate) fn on_line(unit: Box<dyn SimulatedUnit>, wiring: Wiring) -> Self {
        let port = unit.port();
        SimPs {
            line: Line::new(port, port, wiring, 1),
            unit,
            sent: Vec::new(),
            heard: Vec::new(),
        }
    }

    /// The unit.
    pub(crate) fn unit(&mut self) -> &mut dyn SimulatedUnit {
        &mut *self.unit
    }

    /// The unit as the Powermax simulator, for its model-specific controls.
    pub(crate) fn powermax(&mut self) -> &mut Powermax {
        self.unit
            .as_any_mut()
            .downcast_mut()
            .expect("a Powermax model")
    }

    /// The unit as the HPR / MaxPro200 simulator, for its model-specific controls.
    pub(crate) fn hpr(&mut self) -> &mut Hpr {
        self.unit.as_any_mut().downcast_mut().expect("an HPR model")
    }

    /// Pulls the serial cable at `now` (true) or plugs it back (false): the unit keeps its
    /// state but neither hears nor answers while unplugged.
    pub(crate) fn unplug(&mut self, now: Instant, unplugged: bool) {
        self.line.set_unit_powered(now, !unplugged);
    }

    /// Everything due at `now` on both sides: the master's frame onto the line, the
    /// characters that arrived at each end, the unit's timers and its reply. Returns the next
    /// instant at which the line or the unit (not the master: the caller sleeps until the
    /// earlier of this and the master's `poll_at`) needs attention.
    pub(crate) fn exchange(
        &mut self,
        master: &mut dyn PsEndpoint,
        now: Instant,
    ) -> Option<Instant> {
        let port = master.ps_port_config();
        if self.line.port(End::Master) != port {
            self.line.set_port(End::Master, port);
        }
        while let Some(frame) = master.poll_ps_transmit(now) {
            let frame = frame.to_vec();
            let end = self.line.transmit(End::Master, now, &frame);
            master.ps_transmitted(end);
            self.sent.push((now, frame));
        }
        for b in self.line.receive(End::Unit, now) {
            match b.error {
                None => self.unit.receive(b.at, b.byte),
                Some(_) => self.unit.receive_error(b.at),
            }
        }
        self.unit.advance(now);
        for (start, length) in self.unit.take_noise_bursts() {
            self.line.add_noise_burst(start, length);
        }
        if let Some(bytes) = self.unit.poll_transmit(now) {
            self.line.transmit(End::Unit, now, &bytes);
        }
        let mut run = Vec::new();
        for b in self.line.receive(End::Master, now) {
            match b.error {
                None => {
                    self.heard.push((now, b.byte));
                    run.push(b.byte);
                }
                Some(_) => {
                    if !run.is_empty() {
                        master.handle_ps_rx(now, &run);
                        run.clear();
                    }
                    master.handle_ps_rx_error(now);
                }
            }
        }
        if !run.is_empty() {
            master.handle_ps_rx(now, &run);
        }
        earliest(self.line.next_delivery(), self.unit.next_wakeup())
    }
}
