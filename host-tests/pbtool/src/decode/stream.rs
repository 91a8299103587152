//! Frames as they pass on a line, one at a time: each is decoded in the light of the request
//! before it, as `pbtool decode` reads its arguments.

use super::{FrameReport, Kind, decode_frames};

/// Decodes a line's frames in order.
#[derive(Debug, Default)]
pub struct FrameStream {
    /// The last frame, while it is a request its reply may still follow.
    pending: Option<String>,
}

impl FrameStream {
    /// The report of `frame`, the next frame on the line.
    pub fn decode(&mut self, frame: &str) -> FrameReport {
        let mut reports = match self.pending.take() {
            Some(request) => decode_frames(&[request.as_str(), frame]),
            None => decode_frames(&[frame]),
        };
        let report = reports.pop().unwrap_or_else(|| FrameReport::new(frame));
        if report.kind == Some(Kind::Request) {
            self.pending = Some(frame.to_string());
        }
        report
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reply_is_read_against_its_request_and_a_request_alone() {
        let mut stream = FrameStream::default();
        let request = stream.decode(":01043044000483\r\n");
        assert_eq!(request.kind, Some(Kind::Request));
        let reply = stream.decode(":010408007900790000000001\r\n");
        assert_eq!(reply.kind, Some(Kind::Reply));
        assert_eq!(reply.answers_request, Some(true));
        let next = stream.decode(":01043044000483\r\n");
        assert_eq!(next.kind, Some(Kind::Request));
        let again = stream.decode(":01043044000483\r\n");
        assert_eq!(again.kind, Some(Kind::Request), "a request after a request");
    }
}
