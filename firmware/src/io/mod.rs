//! The torch-safe discrete I/O between the CNC and the power supply, all of it:
//!
//! - the CNC's wiring, as settings: [`InputConfig`] (each input's active level and debounce)
//!   and [`OutputConfig`] (the outputs a table may invert), parts of [`IoConfig`];
//! - the input filter: from [`PinLevels`] to logical inputs (polarity, debounce), on the one
//!   debouncer that ARC_OK's MOTION filter uses too;
//! - [`Interlocks`]: the rules from the logical inputs and the supply's state to the outputs;
//! - [`DiscreteIo`]: filter and interlocks, as the board's I/O task runs them;
//! - [`EdgeLatch`]: input edges from the interrupt to that task, without a gap;
//! - [`SafetyMonitor`]: an independent check of the safety rules, for tests.
//!
//! [`Interlocks`] is a sans-IO state machine: the board (or a simulator) feeds it input
//! edges ([`Interlocks::on_input`]), the link's view of the supply ([`Interlocks::on_supply`])
//! and the passing of time ([`Interlocks::poll`]), and drives the pins from
//! [`Interlocks::outputs`]. Every output change is logged with a [`Reason`].
//!
//! # Behaviour
//!
//! - **START** is off at reset and follows TORCH_ON only while every interlock allows it.
//!   It drops in the same call that reports TORCH_ON released or an interlock lost.
//! - **Power-up**: a TORCH_ON already active in the initial inputs is ignored until it has
//!   been seen inactive (on the supply that would be fault 0-51-0 / error 050).
//! - **Gap between starts**: START's rising edge comes at least
//!   [`IoConfig::start_gap`] (never less than [`MIN_START_GAP`]) after its previous falling edge; reset
//!   counts as a falling edge. A TORCH_ON that arrives inside the gap is *delayed*, not
//!   refused: START follows when the gap ends if TORCH_ON is still active and every interlock
//!   still allows it ([`IoEvent::StartDelayed`]). This is a relay-timing rule, so the torch
//!   fires at most one gap later than asked for while the CNC still asks for it.
//! - **Interlocks** ([`Interlock`]): link down, quick-restart blackout, fault that requires
//!   action (the first and last can be switched off in [`IoConfig`]), transfer time-out.
//!   A TORCH_ON refused by one, or a START dropped by one, *latches*: START stays off until
//!   TORCH_ON is released and asserted again. Clearing a fault, ending a blackout or
//!   bringing the link back never fires the torch on its own.
//! - **Blackout**: the latest blackout end the link ever reported is kept; a later report
//!   cannot shorten it.
//! - **ARC_OK** follows MOTION once MOTION has held a level for [`IoConfig::arc_ok_debounce`]
//!   (both edges), and by default only while START is on; it drops with START at once.
//! - **Transfer time-out**: if MOTION (debounced) has not come [`IoConfig::transfer_timeout`]
//!   after START's rising edge, [`IoEvent::TransferTimeout`] is raised once and, by default,
//!   START drops and latches off.
//! - **READY** = link up, no fault requiring action, no blackout, the link reports the unit
//!   ready, and the HPR NOT_READY input inactive. NOT_READY does not refuse START (the
//!   supply itself ignores a start it is not ready for); it only clears READY.
//!   **FAULT** = the link is down, the supply reports a fault, or the HPR / MaxPro200
//!   SYSTEM_ERROR signal is active.
//!   With [`IoConfig::link_required`] cleared, the link state is left out of START, READY and
//!   FAULT (a discrete-only installation).
//! - **HOLD, PIERCE_COMPLETE, CORNER_CURRENT** pass from the CNC to the supply at once and
//!   are never gated: HOLD only keeps the HPR in preflow (delays ignition), PIERCE_COMPLETE
//!   only switches shield preflow gas to cutflow gas, CORNER_CURRENT only lowers the current
//!   to the set corner percentage. None of them can start an arc.
//! - **RAMPDOWN_ERROR** raises [`IoEvent::RampdownError`] on its rising edge (consumable wear,
//!   not a fault).
//! - **SYSTEM_ERROR** raises [`IoEvent::SystemError`] on its rising edge and holds FAULT on
//!   while active. It does not refuse START: the manual says only that an error occurred
//!   and that its code is read over the serial link, which decides the fault interlock.
//!
//! [`SafetyMonitor`] checks the TORCH_ON edges the board receives and the START pin against
//! the safety rules, independently of [`Interlocks`] (it never reads their view of the
//! inputs), for scenario and property tests.
//!
//! # Example
//!
//! ```
//! use plasma_firmware::io::{Input, Inputs, Interlocks, IoConfig, Output, Reason, SupplyState};
//! use plasma_protocol::time::Instant;
//!
//! let t = Instant::from_millis;
//! let mut io = Interlocks::new(IoConfig::default(), t(0), Inputs::NONE);
//! io.on_supply(t(100), SupplyState::HEALTHY);
//! io.on_input(t(200), Input::TorchOn, true);
//! assert!(io.outputs().start);
//!
//! // The log: FAULT on at reset (no link yet), then cleared, READY, START.
//! let mut last = None;
//! while let Some(transition) = io.poll_transition() {
//!     last = Some(transition);
//! }
//! let last = last.unwrap();
//! assert_eq!((last.output, last.reason), (Output::Start, Reason::TorchOn));
//! assert_eq!(last.to_string(), "200.000 ms START on: torch-on from CNC");
//!
//! io.on_input(t(300), Input::TorchOn, false);
//! assert!(!io.outputs().start);
//! ```

mod config;
mod debounce;
mod discrete;
mod edges;
mod input_config;
mod input_filter;
mod interlocks;
mod monitor;
mod output_levels;
mod reason;
mod signals;
mod units;

pub use config::{IoConfig, MIN_START_GAP};
pub use discrete::DiscreteIo;
pub use edges::EdgeLatch;
pub use input_config::{InputConfig, InputSetting, MAX_DEBOUNCE, Polarity, Pull};
pub use input_filter::PinLevels;
pub use interlocks::Interlocks;
pub use monitor::{SafetyMonitor, Violation, ViolationKind};
pub use output_levels::{NotInvertible, OutputConfig};
pub use reason::{Interlock, IoEvent, Reason, Transition};
pub use signals::{Input, Inputs, Output, Outputs, SupplyState};
pub use units::UnitsIo;
