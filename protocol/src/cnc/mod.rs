//! What the CNC sends to the bridge, and the lines the bridge answers with.
//!
//! The CNC talks to the bridge over a serial port in one of two ways:
//!
//! - **Text commands** ([`command`]): one command per line, such as `SET AMPS 45.5`, assembled
//!   from bytes by a [`LineAssembler`] and parsed by [`Command::parse`]. The bridge answers
//!   each line with `OK ...` or `ERR <CODE> <text>` ([`reply`]).
//! - **Phoenix serial messages** ([`phoenix`]): a Hypertherm Phoenix CNC's part program sends
//!   the same command text framed by STX/ETX, SOH/EOT, CR LF and an XOR check byte, and waits
//!   for ACK or NAK. The [`Deframer`](phoenix::Deframer) returns the payload, which is then
//!   parsed like a text line.
//!
//! A framed message starts with SOH or STX; a text line never does (it holds only printable
//! characters), so one port can carry both: route a SOH/STX byte that arrives between two
//! inputs to the deframer and all other bytes to the line assembler
//! ([`phoenix::is_frame_start`]).
//!
//! Nothing here allocates or panics on any input.
//!
//! ```
//! use plasma_protocol::cnc::{Command, LineAssembler, Mode};
//! use plasma_protocol::cnc::phoenix::{ACK, Deframer, Format, NAK, frame};
//! use plasma_protocol::cnc::reply::write_parse_error;
//!
//! // A text line, cut in two chunks anywhere.
//! let mut lines = LineAssembler::new();
//! assert_eq!(lines.feed(b"set mode cu").1, None);
//! let (_, line) = lines.feed(b"t\r\n");
//! assert_eq!(Command::parse(line.unwrap().unwrap()), Ok(Command::SetMode(Mode::Cut)));
//!
//! // A Phoenix message with format 48 (STX .. ETX + check byte).
//! let format = Format::from_value(48)?;
//! let mut wire = [0u8; 32];
//! let n = frame(format, b"SET AMPS 500", &mut wire)?;
//! let mut rx: Deframer = Deframer::new(format);
//! let (_, outcome) = rx.feed(&wire[..n]);
//! let answer = match outcome {
//!     Some(Ok(payload)) => {
//!         let text = core::str::from_utf8(payload).unwrap_or("");
//!         match Command::parse(text) {
//!             Ok(_) => ACK,
//!             Err(error) => {
//!                 // The frame arrived intact: ACK it, and report the refusal as a line.
//!                 let mut reply = heapless::String::<64>::new();
//!                 write_parse_error(&mut reply, &error).unwrap();
//!                 assert_eq!(reply, "ERR RANGE amps out of range 5..400\r\n");
//!                 ACK
//!             }
//!         }
//!     }
//!     Some(Err(_)) => NAK, // damaged frame: the CNC sends it again
//!     None => return Ok(()),
//! };
//! assert_eq!(answer, ACK);
//! # Ok::<(), plasma_protocol::Error>(())
//! ```

pub mod clock;
pub mod command;
mod error;
pub mod line;
pub mod phoenix;
pub mod reply;
pub mod unit;

pub use crate::units::{Amps, Pressure, Psi};
pub use command::{
    AMPS_ARGUMENT, AMPS_MAX, AMPS_MIN, AMPS_RANGE_TEXT, AllGasFlows, AllParameters, Command,
    ConfigCommand, ConfigKey, ConsumablesCommand, Gas, GasFlow, HISTORY_DEFAULT, HISTORY_MAX,
    HPR_GAS_FLOW_WORDS, HistoryCommand, MAXPRO_GAS_FLOW_WORDS, Mode, PSI_MAX, PSI_MIN,
    PSI_RANGE_TEXT,
};
pub use error::{ErrorCode, ParseError};
pub use line::{LineAssembler, LineError, MAX_LINE_LEN};
pub use unit::{MAX_UNIT, UNIT_ARGUMENT, split_unit};
