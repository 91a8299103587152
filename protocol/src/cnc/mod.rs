//! What the CNC sends to the bridge.
//!
//! - [`phoenix`]: Phoenix serial messaging: format values, framing, the XOR check byte,
//!   ACK/NAK and the two-character codes for non-printing bytes.

pub mod phoenix;
