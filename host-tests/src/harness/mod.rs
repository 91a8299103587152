//! The scenario harness: the bridge's power-supply side, a serial [`Line`](plasma_sim::line::Line)
//! and a [`SimulatedUnit`](plasma_sim::SimulatedUnit) in one deterministic discrete-event
//! [`World`], in virtual time (no sleeps, no wall clock).
//!
//! Each step takes the earliest instant at which anything needs attention (the endpoint's
//! `poll_at`, the next character on the line, the simulator's wake-up, the interlocks'
//! timers) and processes it in causal order:
//!
//! 1. the unit hears its characters, runs its timers and may start a reply; its HF-ignition
//!    noise goes onto the line;
//! 2. the unit's Motion output goes to the interlocks' MOTION input;
//! 3. the bridge endpoint hears its characters, its events are drained, and it transmits (the
//!    port settings it asks for are applied to the line's master end first);
//! 4. the endpoint's [`SupplyState`](plasma_firmware::io::SupplyState) goes to the
//!    [`Interlocks`](plasma_firmware::io::Interlocks), whose START drives the unit's Start
//!    input;
//! 5. the independent [`SafetyMonitor`](plasma_firmware::io::SafetyMonitor), fed the input
//!    edges as the harness drives them (never the interlocks' view), checks them against
//!    START and the blackout. A broken rule panics at once (with the last frames on the wire), so
//!    every scenario enforces the safety rules.
//!
//! With several units on a multi-drop line ([`World::with_bridge_on_line`],
//! [`World::on_one_line`]) steps 2, 4 and 5 run once per unit, each with its own interlocks and
//! monitor: unit k's MOTION, supply state and TORCH_ON reach only unit k's set, whose START
//! drives only unit k.
//!
//! The endpoint is anything implementing [`WorldEndpoint`] (the firmware's
//! [`PsEndpoint`](plasma_firmware::platform::PsEndpoint) for its port, plus what the world
//! observes): a bare
//! [`PsLink`](plasma_firmware::link::PsLink), the `Bridge` façade, or a [`BridgeEndpoint`]
//! (the bridge with its CNC port, settings store and the simulator's TORCH_ON), whose world
//! is driven from the CNC side (`World::cnc_line`, `World::power_cycle_bridge`).
//!
//! ```
//! use host_tests::harness::{World, WorldOptions};
//! use plasma_sim::Model;
//! use plasma_firmware::link::{Family, LinkEvent};
//! use plasma_protocol::time::Duration;
//!
//! let mut world = World::new(Model::Sync65, WorldOptions::default());
//! world.wait_link_up(Duration::from_secs(1)).unwrap();
//! assert!(matches!(
//!     world.events()[0].1,
//!     LinkEvent::LinkUp { family: Family::PowermaxSync, .. }
//! ));
//! // Auto-detection begins with Read Device Identification.
//! assert_eq!(world.trace().frames()[0].bytes, b":012B0E0401C1\r\n");
//! ```

mod bridge;
mod endpoint;
pub mod measure;
mod options;
mod pins;
mod shared;
mod trace;
mod world;

pub use bridge::{BridgeEndpoint, CNC_REPLY_TIMEOUT, CncItem, CncRecord, is_reply_line};
pub use endpoint::WorldEndpoint;
pub use options::{RxErrors, WorldOptions};
pub use shared::{SharedLineError, named_units_on_line};
pub use trace::{Direction, TraceFrame, WireTrace};
pub use world::{Timeout, World, WorldStats};
