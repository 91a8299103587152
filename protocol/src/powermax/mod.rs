//! Powermax and Powermax SYNC: register and coil map, value scaling and the manuals' tables.
//!
//! Two register families exist:
//! - [`sync`]: Powermax45/65/85/105 SYNC, consecutive 0x3xxx registers read in blocks, with
//!   cartridge data, gas test and quick restart;
//! - [`legacy`]: Powermax65/85/105/125 and 45 XP, scattered 0x2xxx registers (SYNC units answer
//!   them too, but the SYNC guide asks for 0x3xxx).
//!
//! [`device_id`] tells which family a unit speaks. Values are exact fixed point ([`Amps`] =
//! A x 64, [`Psi`] = psi x 128, [`Pressure::Auto`] = 0), fault codes are decimal `X-YY-Z`
//! ([`FaultCode`]). Requests are [`Request`](crate::modbus_ascii::Request) values for the
//! Modbus layer to frame; decoders take the [`Registers`](crate::modbus_ascii::Registers) of a
//! reply. Block reads that cross undocumented addresses come with a fallback plan
//! ([`BlockRead`]).
//!
//! ```
//! use plasma_protocol::modbus_ascii::{Registers, Request};
//! use plasma_protocol::powermax::{sync, Amps, FaultCode, OperatingMode, Pressure};
//!
//! // Remote control: cut at 63 A, automatic pressure (the guide's
//! // `:0110308000030600010FC0000066`).
//! let words = sync::enter_remote(OperatingMode::Cut, "63".parse()?, Pressure::Auto)?;
//! assert_eq!(words, [0x0001, 0x0FC0, 0x0000]);
//! let request = sync::write_remote(&words);
//! assert!(matches!(request, Request::WriteMultipleRegisters { start: 0x3080, .. }));
//!
//! // Poll 0x3010-0x301A in one read and decode the reply.
//! assert_eq!(sync::read_status_block(), Request::ReadInputRegisters { start: 0x3010, quantity: 11 });
//! let reply = [0x0001, 0x0FC0, 0x0000, 0, 0, 0, 0, 0, 0x0FB0, 0x23DD, 0x01F4];
//! let status = sync::StatusBlock::decode(Registers::Words(&reply))?;
//! assert_eq!(status.settings.current, Amps::from_whole(63).unwrap());
//! assert_eq!(status.actual.current.to_string(), "62.75");
//! assert_eq!(status.actual.pressure.to_string(), "71.7265625");
//! assert_eq!(status.fault, FaultCode(500));
//! assert_eq!(status.fault.to_string(), "0-50-0");
//! assert!(status.fault.info().unwrap().action_required());
//! # Ok::<(), plasma_protocol::Error>(())
//! ```

mod cartridge;
pub mod device_id;
mod fault;
mod fault_table;
mod ident;
pub mod legacy;
mod mode;
mod plan;
pub mod registers;
pub mod sync;
pub mod timing;

pub use crate::units::{Amps, Pressure, Psi};
pub use cartridge::{
    CARTRIDGE_NAMES, CARTRIDGE_TYPES, CartridgeCounters, CartridgeName, CartridgeNameInfo,
    CartridgeProcess, CartridgeType, CartridgeUid, PartNumber,
};
pub use device_id::{AddressingSystem, PowerSupplyModel};
pub use fault::{FaultCode, FaultInfo, StepsRequired, SyncModels};
pub use ident::{LeadLength, SYNC_MODELS, SyncModel, TORCH_TYPES, TorchKind, TorchType};
pub use mode::OperatingMode;
pub use plan::{BlockRead, RegisterSpan, Signals};
