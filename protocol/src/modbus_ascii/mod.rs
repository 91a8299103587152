//! Modbus ASCII, as spoken by Powermax and Powermax SYNC power supplies.
//!
//! A frame is `:` + hex(address, function, data..., LRC) + CR LF. This module keeps the two
//! layers apart: [`pdu`] holds typed requests and replies (function code and data, binary), and
//! the framing code turns an address + PDU into ASCII characters and back.
pub mod pdu;

pub use pdu::{DeviceIdCode, ExceptionCode, FunctionCode, Registers, Request, Response};
