//! Modbus ASCII frames: `:` + hex(address, PDU, LRC) + CR LF.

use super::Decoder;
use super::hex;
use super::lrc::lrc;
use super::pdu::{MAX_PDU_LEN, Request, Response};
use crate::{Error, Result};

/// Longest frame in characters: `:` + 2 address + 2 function + 2x252 data + 2 LRC + CR LF.
pub const MAX_FRAME_CHARS: usize = 513;

/// Longest frame in binary bytes: address + function + 252 data + LRC.
pub const MAX_FRAME_BYTES: usize = MAX_PDU_LEN + 2;

/// Shortest frame in binary bytes: address + function + LRC.
pub(crate) const MIN_FRAME_BYTES: usize = 3;

/// A received frame: node address and binary PDU, LRC verified and removed.
///
/// The PDU always holds at least the function code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame<'a> {
    /// Node address: of the addressed unit in a request, of the answering unit in a reply.
    /// Address 0 is a broadcast, which units never answer.
    pub address: u8,
    /// Function code and data, binary.
    pub pdu: &'a [u8],
}

impl<'a> Frame<'a> {
    /// Builds a frame from its binary bytes (address, PDU, LRC), checking the LRC.
    pub(crate) fn from_binary(bytes: &'a [u8]) -> Result<Frame<'a>> {
        if bytes.len() < MIN_FRAME_BYTES {
            return Err(Error::Truncated);
        }
        let Some((&found, body)) = bytes.split_last() else {
            return Err(Error::Truncated);
        };
        let expected = lrc(body);
        if expected != found {
            return Err(Error::BadChecksum { expected, found });
        }
        let Some((&address, pdu)) = body.split_first() else {
            return Err(Error::Truncated);
        };
        Ok(Frame { address, pdu })
    }

    /// Parses the PDU as a request (for a simulated unit).
    pub fn request(&self) -> Result<Request<'a>> {
        Request::parse(self.pdu)
    }

    /// Parses the PDU as a reply, without matching it to a request (see
    /// [`validate_reply`](super::validate_reply) for that).
    pub fn response(&self) -> Result<Response<'a>> {
        Response::parse(self.pdu)
    }

    /// Encodes this frame into `out`; see [`encode`].
    pub fn encode(&self, out: &mut [u8]) -> Result<usize> {
        encode(self.address, self.pdu, out)
    }
}

/// Number of characters [`encode`] writes for a PDU of `pdu_len` bytes.
pub const fn encoded_len(pdu_len: usize) -> usize {
    // `:` + 2 digits per byte of (address, PDU, LRC) + CR LF; saturating, never panics.
    pdu_len
        .saturating_add(2)
        .saturating_mul(2)
        .saturating_add(3)
}

// The two limits agree.
const _: () = assert!(encoded_len(MAX_PDU_LEN) == MAX_FRAME_CHARS);

/// Encodes `:` + upper-case hex of (`address`, `pdu`, LRC) + CR LF into `out`; returns the
/// number of characters written.
///
/// [`Error::Truncated`] for an empty PDU, [`Error::Overlong`] for one longer than
/// [`MAX_PDU_LEN`], [`Error::BufferTooSmall`] when `out` is shorter than
/// [`encoded_len`]`(pdu.len())`. Nothing is written on error.
pub fn encode(address: u8, pdu: &[u8], out: &mut [u8]) -> Result<usize> {
    if pdu.is_empty() {
        return Err(Error::Truncated);
    }
    if pdu.len() > MAX_PDU_LEN {
        return Err(Error::Overlong);
    }
    let len = encoded_len(pdu.len());
    let Some(out) = out.get_mut(..len) else {
        return Err(Error::BufferTooSmall);
    };
    let (start, rest) = out.split_at_mut(1);
    start.copy_from_slice(b":");
    let (digits, end) = rest.split_at_mut(len - 3);
    end.copy_from_slice(b"\r\n");
    let sum = pdu.iter().fold(address, |s, &b| s.wrapping_add(b));
    let bytes = core::iter::once(address)
        .chain(pdu.iter().copied())
        .chain([sum.wrapping_neg()]);
    for (pair, byte) in digits.chunks_exact_mut(2).zip(bytes) {
        pair.copy_from_slice(&hex::encode_byte(byte));
    }
    Ok(len)
}

/// Encodes `request` for the unit at `address`; see [`encode`].
pub fn encode_request(address: u8, request: &Request<'_>, out: &mut [u8]) -> Result<usize> {
    let mut pdu = [0u8; MAX_PDU_LEN];
    let n = request.emit(&mut pdu)?;
    encode(address, pdu.get(..n).ok_or(Error::BufferTooSmall)?, out)
}

/// Encodes `response` as sent by the unit at `address`; see [`encode`].
pub fn encode_response(address: u8, response: &Response<'_>, out: &mut [u8]) -> Result<usize> {
    let mut pdu = [0u8; MAX_PDU_LEN];
    let n = response.emit(&mut pdu)?;
    encode(address, pdu.get(..n).ok_or(Error::BufferTooSmall)?, out)
}

/// Decodes one complete frame held in `input`, copying its binary PDU into `buf`.
///
/// For tests and tools that hold a whole frame; a byte stream goes through a
/// [`Decoder`](super::Decoder). `input` must start with `:`; the CR LF terminator may be
/// missing. The result is what a [`Decoder`](super::Decoder) reports first for the same
/// characters, plus [`Error::Malformed`] when `input` does not start with `:` or goes on
/// after the frame's LF, and [`Error::BufferTooSmall`] when `buf` cannot hold the PDU
/// ([`MAX_PDU_LEN`] bytes always can).
pub fn decode<'b>(input: &[u8], buf: &'b mut [u8]) -> Result<Frame<'b>> {
    if input.first() != Some(&b':') {
        return Err(Error::Malformed);
    }
    let mut decoder = Decoder::new();
    let frame = match decoder.feed(input) {
        (used, Some(Ok(frame))) if used == input.len() => frame,
        (_, Some(Ok(_))) => return Err(Error::Malformed),
        (_, Some(Err(e))) => return Err(e),
        // No LF yet: end the frame here.
        (_, None) => decoder.push(b'\n').unwrap_or(Err(Error::Truncated))?,
    };
    let pdu = buf
        .get_mut(..frame.pdu.len())
        .ok_or(Error::BufferTooSmall)?;
    pdu.copy_from_slice(frame.pdu);
    Ok(Frame {
        address: frame.address,
        pdu,
    })
}
