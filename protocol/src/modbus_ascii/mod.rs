//! Modbus ASCII, as spoken by Powermax and Powermax SYNC power supplies.
//!
//! A frame is `:` + hex(address, function, data..., LRC) + CR LF. This module keeps the two
//! layers apart: [`pdu`] holds typed requests and replies (function code and data, binary), and
//! the framing code turns an address + PDU into ASCII characters and back.
//!
//! - [`encode`], [`encode_request`], [`encode_response`]: address + PDU to characters.
//! - [`Decoder`]: characters to [`Frame`]s, byte by byte or chunk by chunk, fixed buffer.
//! - [`Request`] / [`Response`]: `parse` and `emit` of the binary PDUs, with the Modbus limits.
//! - [`validate_reply`]: does this reply answer that request?
//! - [`lrc`]: the checksum.
//!
//! # Example
//!
//! Read the four newest faults of a SYNC unit (the example of its programmer's guide):
//!
//! ```
//! use plasma_protocol::modbus_ascii::{
//!     encode_request, validate_reply, Decoder, Request, Response, MAX_FRAME_CHARS,
//! };
//!
//! let request = Request::ReadInputRegisters { start: 0x3044, quantity: 4 };
//! let mut out = [0u8; MAX_FRAME_CHARS];
//! let n = encode_request(0x01, &request, &mut out)?;
//! assert_eq!(&out[..n], b":01043044000483\r\n");
//!
//! // The unit's reply arrives in pieces.
//! let mut decoder = Decoder::new();
//! assert_eq!(decoder.feed(b":01040800790079"), (15, None));
//! let (_, result) = decoder.feed(b"0000000001\r\n");
//! let frame = result.expect("frame ended")?;
//! let Response::ReadInputRegisters { values } = validate_reply(&request, 0x01, &frame)? else {
//!     panic!("an exception reply");
//! };
//! // 0x0079 = 121 = fault 0-12-1, twice; then no fault.
//! assert!(values.iter().eq([0x0079, 0x0079, 0x0000, 0x0000]));
//! # Ok::<(), plasma_protocol::Error>(())
//! ```
mod decoder;
mod frame;
mod hex;
mod lrc;
pub mod pdu;
mod validate;

#[cfg(test)]
mod tests;

pub use decoder::Decoder;
pub use frame::{
    Frame, MAX_FRAME_BYTES, MAX_FRAME_CHARS, decode, encode, encode_request, encode_response,
    encoded_len,
};
pub use lrc::lrc;
pub use pdu::{
    DeviceIdCode, DeviceIdentification, DeviceObjects, ExceptionCode, FunctionCode, MAX_PDU_LEN,
    Registers, Request, Response,
};
pub use validate::validate_reply;
