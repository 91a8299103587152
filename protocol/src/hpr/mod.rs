//! The `>ID data CK<` serial protocol of HyPerformance (HPR130/260/400, XD) and MaxPro200
//! plasma systems (RS-422, 19200 8N1).
//!
//! Layers, bottom up:
//! - [`frame`]: `>` + 3-digit id + ASCII data + 2 hex checksum digits + `<`; the checksum
//!   and a streaming [`Decoder`] that survives HF-ignition noise.
//! - [`command`]: every id of the manual's command table with its [`Class`]; [`is_allowed`]
//!   is the bridge's allow-list (factory-only and dangerous commands are never on it).
//! - [`Request`] / [`Reply`]: typed data of the commands a CNC uses, with parse/emit pairs
//!   both ways (the bridge emits requests and parses replies; the simulator the reverse).
//! - [`error_codes`], [`state`], [`gas`]: the manual's tables IV, V and VI.
//!
//! Rules from the manual the link layer must keep (not enforced here): wait for each reply
//! before the next command (older boards lock up otherwise), send nothing after `<`, retry
//! so that a 1 s HF-ignition blackout is survived, and on a multi-drop line send SLEEP (086)
//! then WAKE (085 + id 0-3) before talking to another system.
//!
//! ```
//! use plasma_protocol::hpr::{Frame, Reply, Request, StateCode};
//!
//! let mut buf = [0u8; plasma_protocol::hpr::MAX_FRAME_LEN];
//! let n = Request::SetNominalAmps { amps: 130 }.emit(&mut buf)?;
//! assert_eq!(&buf[..n], b">05813031<");
//!
//! let frame = Frame::parse(b">002000355<")?;
//! let reply = Reply::parse_for(&Request::GetState, &frame)?;
//! assert_eq!(reply, Reply::State(StateCode(3)));
//! assert_eq!(StateCode(3).hpr_name().unwrap(), "IDLE2");
//! # Ok::<(), plasma_protocol::Error>(())
//! ```

pub mod command;
mod diagnostics;
pub mod error_codes;
mod field;
pub mod frame;
pub mod gas;
mod identity;
mod reply;
mod request;
#[cfg(test)]
mod seed_frames;
pub mod state;
mod values;

#[cfg(feature = "descriptions")]
pub use command::command_name;
pub use command::{
    Class, CommandInfo, Systems, accepts, classify, command_info, is_allowed, systems_of,
};
#[cfg(feature = "diagnostics")]
pub use diagnostics::{
    AUTO_CONSOLE_INPUTS, ControlData, ControlData3, CoolantCounts, GasConsoleInputs,
    MANUAL_CONSOLE_INPUTS, MaxProControlData, MfgData2,
};
pub use diagnostics::{DiagnosticRead, DiagnosticReply, MfgData1};
pub use error_codes::ErrorCode;
pub use frame::{Decoder, Frame, MAX_DATA_LEN, MAX_FRAME_LEN, checksum};
pub use gas::GasCode;
pub use identity::{GasConsole, HprRating, SystemId};
pub use reply::{
    ACK_COMMANDS, Acceptance, IoStatus, MAX_COUNTER, MaxProPsInfo, PsInfo, Reply, TimerCounter,
    Version,
};
pub use request::{
    CORNER_PERCENT, MAX_HPR_AMPS, MAX_MAXPRO_AMPS, MAX_SYSTEM_ID, MIN_AMPS, Request,
};
pub use state::StateCode;
pub use values::{
    GasFlows, GasPair, GasPressures, HprParameters, LeakCheckMode, MAX_FLOW_PSI, MAX_MIX_PSI,
    MaxProParameters, MaxProPressures, TORCH_IDS, TestMode, TorchId,
};
