//! What the link's tests share: frames built independently of the code under test, and
//! [`Bench`], which drives a link by the byte against scripted replies or a simulated unit.
//!
//! Seed frames from the manuals are used only after their LRC/checksum was recomputed
//! ([`assert_lrc`] / [`hpr_checksum_ok`]).

use std::string::String;
use std::vec::Vec;

use plasma_protocol::powermax::Amps;
use plasma_protocol::time::{Duration, Instant};
use plasma_sim::clock::earliest;

use crate::link::{LinkConfig, LinkEvent, PsLink};
use crate::testing::SimPs;

pub(crate) fn ms(v: u64) -> Instant {
    Instant::from_millis(v)
}

/// Modbus ASCII frame for node 1 from a binary PDU (LRC computed here, independently).
pub(crate) fn mb(pdu: &[u8]) -> Vec<u8> {
    let mut bytes = std::vec![1u8];
    bytes.extend_from_slice(pdu);
    let sum = bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    bytes.push(sum.wrapping_neg());
    let mut out = String::from(":");
    for b in bytes {
        out.push_str(&std::format!("{b:02X}"));
    }
    out.push_str("\r\n");
    out.into_bytes()
}

/// Recompute the LRC of a seed frame (`:...LL\r\n`) and check it.
pub(crate) fn assert_lrc(frame: &[u8]) {
    let text = std::str::from_utf8(frame).unwrap();
    let hex = text.trim_start_matches(':').trim_end_matches("\r\n");
    let bytes: Vec<u8> = (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect();
    let sum = bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    assert_eq!(sum, 0, "LRC of seed {text:?} does not check");
}

/// HPR frame `>ID data CK<` (checksum computed here).
pub(crate) fn hf(id: u16, data: &str) -> Vec<u8> {
    let body = std::format!("{id:03}{data}");
    let sum = body.bytes().fold(0u8, |s, b| s.wrapping_add(b));
    std::format!(">{body}{sum:02X}<").into_bytes()
}

pub(crate) fn hpr_checksum_ok(frame: &[u8]) -> bool {
    let inner = &frame[1..frame.len() - 3];
    let sum = inner.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    let ck = std::str::from_utf8(&frame[frame.len() - 3..frame.len() - 1]).unwrap();
    u8::from_str_radix(ck, 16).unwrap() == sum
}

/// Drives a link: collects transmitted frames, moves time, and either takes scripted reply
/// bytes from the test or runs the link against a simulated unit of `plasma-sim`.
pub(crate) struct Bench {
    pub(crate) link: PsLink,
    pub(crate) now: Instant,
    pub(crate) sent: Vec<(Instant, Vec<u8>)>,
    /// The unit on the line, for [`Bench::run`].
    pub(crate) unit: Option<SimPs>,
}

impl Bench {
    pub(crate) fn new(config: LinkConfig) -> Self {
        Bench {
            link: PsLink::new(config, Instant::ZERO),
            now: Instant::ZERO,
            sent: Vec::new(),
            unit: None,
        }
    }

    /// A link with the simulated `model` (pbtool's names) on the line.
    pub(crate) fn with_unit(config: LinkConfig, model: &str) -> Self {
        Bench {
            unit: Some(SimPs::new(model)),
            ..Bench::new(config)
        }
    }

    /// Next frame the link sends, advancing time to `poll_at` as needed (up to `limit`).
    pub(crate) fn next_tx(&mut self, limit: Instant) -> Option<Vec<u8>> {
        loop {
            if let Some(frame) = self.link.poll_transmit(self.now) {
                let frame = frame.to_vec();
                self.sent.push((self.now, frame.clone()));
                return Some(frame);
            }
            let at = self.link.poll_at()?;
            // Nothing was sent: the link must not ask for this instant again (a board task
            // sleeping until `poll_at` would spin).
            assert!(at > self.now, "poll_at {at:?} not after {:?}", self.now);
            if at > limit {
                return None;
            }
            self.now = at;
        }
    }

    pub(crate) fn rx(&mut self, delay_ms: u64, bytes: &[u8]) {
        self.now = self.now + Duration::from_millis(delay_ms);
        self.link.handle_rx(self.now, bytes);
    }

    /// The simulated unit.
    pub(crate) fn ps(&mut self) -> &mut SimPs {
        self.unit.as_mut().expect("a bench with a unit")
    }

    /// Run the link against the unit until `until`, or until it sends a frame `stop` accepts
    /// (returned; it is then on its way to the unit).
    pub(crate) fn run_until_sent(
        &mut self,
        until: Instant,
        mut stop: impl FnMut(&[u8]) -> bool,
    ) -> Option<Vec<u8>> {
        let unit = self.unit.as_mut().expect("a bench with a unit");
        loop {
            let mark = unit.sent.len();
            let mut line_next = unit.exchange(&mut self.link, self.now);
            let mut link_next = self.link.poll_at();
            if link_next.is_some_and(|at| at <= self.now) {
                // What just arrived may have made a frame due now: it goes out at once.
                line_next = earliest(line_next, unit.exchange(&mut self.link, self.now));
                link_next = self.link.poll_at();
                // Nothing more to send: the link must not ask for this instant again (a
                // board task sleeping until `poll_at` would spin).
                if let Some(at) = link_next {
                    assert!(at > self.now, "poll_at {at:?} not after {:?}", self.now);
                }
            }
            self.sent.extend(unit.sent[mark..].iter().cloned());
            if let Some((_, frame)) = unit.sent[mark..].iter().find(|(_, f)| stop(f)) {
                return Some(frame.clone());
            }
            match earliest(line_next, link_next) {
                Some(at) if at <= until => self.now = self.now.max(at),
                _ => break,
            }
        }
        self.now = self.now.max(until);
        None
    }

    /// Run the link against the unit until `until`.
    pub(crate) fn run(&mut self, until: Instant) {
        self.run_until_sent(until, |_| false);
    }

    /// The write requests (functions 05, 06, 0x10) sent since `mark` (an index into `sent`).
    pub(crate) fn writes_since(&self, mark: usize) -> Vec<Vec<u8>> {
        self.sent[mark..]
            .iter()
            .map(|(_, f)| f)
            .filter(|f| f.len() > 5 && matches!(&f[3..5], b"05" | b"06" | b"10"))
            .cloned()
            .collect()
    }

    /// Everything the unit sent the link so far, as one text.
    pub(crate) fn heard(&mut self) -> Vec<u8> {
        self.ps().heard.iter().map(|&(_, b)| b).collect()
    }

    /// The unit raises fault `code` now (its own numbering); 0 clears it.
    pub(crate) fn fault(&mut self, code: u16) {
        let now = self.now;
        let unit = self.ps().unit();
        match code {
            0 => unit.clear_fault(now),
            code => unit.inject_fault(now, code),
        }
    }

    /// Pulls the unit's serial cable now (true), or plugs it back (false).
    pub(crate) fn unplug(&mut self, unplugged: bool) {
        let now = self.now;
        self.ps().unplug(now, unplugged);
    }

    pub(crate) fn events(&mut self) -> Vec<LinkEvent> {
        std::iter::from_fn(|| self.link.poll_event()).collect()
    }
}

/// A Powermax65 SYNC found and its slow data read.
pub(crate) fn sync_bench() -> Bench {
    let mut bench = Bench::with_unit(LinkConfig::default(), "sync65");
    bench.run(ms(500));
    assert!(bench.link.status().link_up);
    assert!(
        bench.link.status().limits.is_some(),
        "slow data read at start"
    );
    bench
}

pub(crate) fn amps(a: u16) -> Amps {
    Amps::from_whole(a).unwrap()
}
