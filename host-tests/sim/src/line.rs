//! A serial line between the bridge (the master end) and a power supply (the unit end), in
//! virtual time, with baud-accurate character timing and seeded fault injection.
//!
//! # Timing
//! A transmission of n bytes that starts at `start` (the later of `now` and the moment the
//! sender's previous transmission ends) delivers byte k at `start + (k+1) * char_time` of the
//! sender's [`PortConfig`], rounded up to the next microsecond. The sender is busy until its last
//! stop bit has left; a second transmission from the same end queues behind the first.
//!
//! # Mismatched port settings
//! When the two ends' settings differ (baud, parity or stop bits) the receiver is simulated bit
//! by bit, like a UART: the sender's characters become a level-versus-time waveform (start bit,
//! 8 data bits LSB first, optional parity bit, stop bits, idle high in between); the receiver
//! waits for a falling edge, samples the middle of each of *its* bit periods, checks its parity
//! bit and its first stop bit, and looks for the next falling edge after the stop-bit sample.
//! This is deterministic and mirrors real hardware, for example:
//! - sent 8E1, read 8O1: every byte arrives intact but flagged [`RxError::Parity`];
//! - sent 8E1, read 8N1: the parity bit is read as the stop bit, so every byte whose even-parity
//!   bit is 0 is flagged [`RxError::Framing`]; the data bits are right;
//! - sent 8N1, read 8E1: back-to-back characters make the receiver read the next start bit as
//!   its stop bit (framing error) and lose sync, so bytes are garbled or lost;
//! - a different baud rate garbles nearly everything.
//!
//! # Faults
//! All randomness comes from one seeded PRNG, so a test run is reproducible.
//! - [`Line::set_corrupt_probability`]: each byte has one random data bit flipped (a receiver
//!   that uses parity then flags [`RxError::Parity`], as a UART would);
//! - [`Line::set_drop_probability`]: each byte is lost;
//! - [`Line::add_noise_burst`]: during the window (e.g. an HPR's 1 s of HF ignition) every byte
//!   on the wire is either lost or replaced by a random value, and spurious random bytes appear
//!   at both receivers;
//! - [`Line::set_unit_powered`]: a unit that is off neither hears nor sends anything.
//!
//! # Wiring
//! In [`Wiring::FourWire`] the two directions are independent pairs. In [`Wiring::TwoWire`]
//! both ends share one pair and a transceiver's receiver is off while it drives the line, so an
//! end hears nothing that arrives while it is itself transmitting. With `master_echo` the
//! master's receiver stays enabled: it hears its own bytes (garbled if the unit drove the line
//! at the same time).
//!
//! ```
//! use plasma_sim::line::{End, Line, Wiring};
//! use plasma_protocol::serial::PortConfig;
//! use plasma_protocol::time::Instant;
//!
//! let mut line = Line::new(PortConfig::MODBUS_DEFAULT, PortConfig::MODBUS_DEFAULT, Wiring::FourWire, 1);
//! line.transmit(End::Master, Instant::ZERO, b":01");
//! let got = line.receive(End::Unit, Instant::from_millis(2));
//! assert_eq!(got.len(), 3);
//! assert_eq!(got[0].at, Instant::from_micros(573)); // 11 bits at 19200 baud
//! ```

use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_protocol::time::{Duration, Instant};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// One end of the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum End {
    /// The bridge (Modbus master / HPR host).
    Master,
    /// The power supply.
    Unit,
}

impl End {
    /// The other end.
    pub fn other(self) -> End {
        match self {
            End::Master => End::Unit,
            End::Unit => End::Master,
        }
    }

    fn index(self) -> usize {
        match self {
            End::Master => 0,
            End::Unit => 1,
        }
    }
}

/// How the two ends are wired.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wiring {
    /// RS-485 2-wire, half duplex: one shared pair.
    TwoWire {
        /// The master's receiver stays enabled while it transmits, so it hears its own bytes.
        master_echo: bool,
    },
    /// RS-422 / RS-485 4-wire, full duplex: one pair per direction.
    FourWire,
}

/// What a UART reports with a received character.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RxError {
    /// The parity bit did not match.
    Parity,
    /// The stop bit was not high.
    Framing,
}

/// A character as the receiving UART hands it over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RxByte {
    /// When the receiver finished reading it.
    pub at: Instant,
    /// The character (possibly garbled).
    pub byte: u8,
    /// Error flag the UART raised with it.
    pub error: Option<RxError>,
}

/// Counts of what the line did to the traffic, for assertions and reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LineStats {
    /// Characters handed to a receiver.
    pub delivered: u64,
    /// Characters delivered with a random bit flipped.
    pub corrupted: u64,
    /// Characters lost (random drop, noise, power, half-duplex).
    pub dropped: u64,
    /// Spurious characters produced by noise bursts.
    pub noise: u64,
}

/// Why a pending character is where it is; decides which checks apply at delivery.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Source {
    /// Sent by the other end.
    Traffic,
    /// The master hearing itself on a 2-wire line.
    Echo,
    /// Produced by a noise burst.
    Noise,
}

#[derive(Debug, Clone, Copy)]
struct Pending {
    /// Delivery time, ns.
    at_ns: u64,
    /// When the character started on the wire, ns.
    begin_ns: u64,
    /// Insertion order, to keep equal times stable.
    seq: u64,
    to: End,
    byte: u8,
    error: Option<RxError>,
    source: Source,
}

/// The serial line model. See the [module docs](self).
#[derive(Debug)]
pub struct Line {
    ports: [PortConfig; 2],
    wiring: Wiring,
    rng: Xoshiro256PlusPlus,
    corrupt_probability: f64,
    drop_probability: f64,
    /// Characters per char-time slot a noise burst injects at each receiver.
    noise_density: f64,
    busy_until_ns: [u64; 2],
    /// Intervals (ns) during which each end drove the line; pruned as time passes.
    transmitting: [Vec<(u64, u64)>; 2],
    bursts: Vec<(u64, u64)>,
    /// Unit power changes (ns, on), in time order; the unit starts powered.
    power_log: Vec<(u64, bool)>,
    pending: Vec<Pending>,
    seq: u64,
    stats: LineStats,
}

fn ns(t: Instant) -> u64 {
    t.as_micros().saturating_mul(1000)
}

/// Rounds a nanosecond time up to the microsecond the caller's clock can express.
fn instant_from_ns(t: u64) -> Instant {
    Instant::from_micros(t.div_ceil(1000))
}

fn overlaps(a: (u64, u64), b: (u64, u64)) -> bool {
    a.0 < b.1 && b.0 < a.1
}

impl Line {
    /// A line between a master set to `master` and a unit set to `unit`, with its PRNG seeded
    /// from `seed`. No faults are injected until asked for.
    pub fn new(master: PortConfig, unit: PortConfig, wiring: Wiring, seed: u64) -> Line {
        Line {
            ports: [master, unit],
            wiring,
            rng: Xoshiro256PlusPlus::seed_from_u64(seed),
            corrupt_probability: 0.0,
            drop_probability: 0.0,
            noise_density: 0.3,
            busy_until_ns: [0; 2],
            transmitting: [Vec::new(), Vec::new()],
            bursts: Vec::new(),
            power_log: Vec::new(),
            pending: Vec::new(),
            seq: 0,
            stats: LineStats::default(),
        }
    }

    /// Port settings of `end`.
    pub fn port(&self, end: End) -> PortConfig {
        self.ports[end.index()]
    }

    /// Changes the port settings of `end` (applies to characters sent from now on).
    pub fn set_port(&mut self, end: End, config: PortConfig) {
        self.ports[end.index()] = config;
    }

    /// The wiring.
    pub fn wiring(&self) -> Wiring {
        self.wiring
    }

    /// Probability that a character gets one random data bit flipped.
    pub fn set_corrupt_probability(&mut self, p: f64) {
        self.corrupt_probability = p.clamp(0.0, 1.0);
    }

    /// Probability that a character is lost.
    pub fn set_drop_probability(&mut self, p: f64) {
        self.drop_probability = p.clamp(0.0, 1.0);
    }

    /// Expected spurious characters per character time at each receiver during a noise burst
    /// (default 0.3).
    pub fn set_noise_density(&mut self, density: f64) {
        self.noise_density = density.clamp(0.0, 1.0);
    }

    /// Statistics so far.
    pub fn stats(&self) -> LineStats {
        self.stats
    }

    /// When the last character `end` has queued will have left the wire.
    pub fn busy_until(&self, end: End) -> Instant {
        instant_from_ns(self.busy_until_ns[end.index()])
    }

    /// True while `end` is driving the line at `now`.
    pub fn is_transmitting(&self, end: End, now: Instant) -> bool {
        let t = ns(now);
        self.transmitting[end.index()]
            .iter()
            .any(|&(a, b)| a <= t && t < b)
    }

    /// Switches the unit on or off from `now`: while off it neither receives nor sends.
    pub fn set_unit_powered(&mut self, now: Instant, on: bool) {
        self.power_log.push((ns(now), on));
    }

    fn unit_powered_at(&self, t: u64) -> bool {
        self.power_log
            .iter()
            .rev()
            .find(|&&(when, _)| when <= t)
            .is_none_or(|&(_, on)| on)
    }

    /// Adds a window of electrical noise: every character on the wire during it is lost or
    /// garbled, and spurious characters appear at both receivers.
    pub fn add_noise_burst(&mut self, start: Instant, length: Duration) {
        let begin = ns(start);
        let end = begin.saturating_add(length.as_micros().saturating_mul(1000));
        self.bursts.push((begin, end));
        for to in [End::Master, End::Unit] {
            let slot = self.ports[to.index()].char_time_ns().max(1);
            let mut t = begin;
            while t.saturating_add(slot) <= end {
                if self.rng.random_bool(self.noise_density) {
                    let byte = self.rng.random::<u8>();
                    let error = self.random_error(to);
                    self.push(Pending {
                        at_ns: t + slot,
                        begin_ns: t,
                        seq: 0,
                        to,
                        byte,
                        error,
                        source: Source::Noise,
                    });
                }
                t += slot;
            }
        }
    }

    fn random_error(&mut self, to: End) -> Option<RxError> {
        let uses_parity = self.ports[to.index()].parity != Parity::None;
        match self.rng.random_range(0..3u8) {
            0 => Some(RxError::Framing),
            1 if uses_parity => Some(RxError::Parity),
            _ => None,
        }
    }

    fn push(&mut self, mut p: Pending) {
        p.seq = self.seq;
        self.seq += 1;
        let pos = self
            .pending
            .partition_point(|q| (q.at_ns, q.seq) <= (p.at_ns, p.seq));
        self.pending.insert(pos, p);
    }

    /// Queues `bytes` from `from` at `now` and returns when the last one will have left the
    /// wire. A unit that is off sends nothing.
    pub fn transmit(&mut self, from: End, now: Instant, bytes: &[u8]) -> Instant {
        let start = ns(now).max(self.busy_until_ns[from.index()]);
        let tx = self.ports[from.index()];
        let to = from.other();
        let rx = self.ports[to.index()];
        let char_ns = tx.char_time_ns();
        let end = start + char_ns * bytes.len() as u64;
        if from == End::Unit && !self.unit_powered_at(start) {
            return instant_from_ns(start);
        }
        self.busy_until_ns[from.index()] = end;
        self.transmitting[from.index()].push((start, end));

        let received = if tx == rx {
            bytes
                .iter()
                .enumerate()
                .map(|(k, &b)| {
                    let k = k as u64;
                    (start + k * char_ns, start + (k + 1) * char_ns, b, None)
                })
                .collect()
        } else {
            uart_receive(tx, rx, bytes)
                .into_iter()
                .map(|c| {
                    (
                        start + c.begin_ps / 1000,
                        start + c.end_ps.div_ceil(1000),
                        c.byte,
                        c.error,
                    )
                })
                .collect::<Vec<_>>()
        };
        for (begin_ns, at_ns, byte, error) in received {
            if self.rng.random_bool(self.drop_probability) {
                self.stats.dropped += 1;
                continue;
            }
            let (byte, error) = if self.rng.random_bool(self.corrupt_probability) {
                self.stats.corrupted += 1;
                let flipped = byte ^ (1 << self.rng.random_range(0..8u8));
                let error = match (error, rx.parity) {
                    (Some(e), _) => Some(e),
                    (None, Parity::None) => None,
                    (None, _) => Some(RxError::Parity),
                };
                (flipped, error)
            } else {
                (byte, error)
            };
            self.push(Pending {
                at_ns,
                begin_ns,
                seq: 0,
                to,
                byte,
                error,
                source: Source::Traffic,
            });
        }
        if from == End::Master && self.wiring == (Wiring::TwoWire { master_echo: true }) {
            for (k, &byte) in bytes.iter().enumerate() {
                let k = k as u64;
                self.push(Pending {
                    at_ns: start + (k + 1) * char_ns,
                    begin_ns: start + k * char_ns,
                    seq: 0,
                    to: End::Master,
                    byte,
                    error: None,
                    source: Source::Echo,
                });
            }
        }
        instant_from_ns(end)
    }

    /// Time of the next character delivery to either end, if any is pending.
    pub fn next_delivery(&self) -> Option<Instant> {
        self.pending.first().map(|p| instant_from_ns(p.at_ns))
    }

    /// Time of the next character delivery to `to`, if any is pending.
    pub fn next_delivery_to(&self, to: End) -> Option<Instant> {
        self.pending
            .iter()
            .find(|p| p.to == to)
            .map(|p| instant_from_ns(p.at_ns))
    }

    /// Hands over, in order, every character that has reached `to` by `now`.
    pub fn receive(&mut self, to: End, now: Instant) -> Vec<RxByte> {
        let now_ns = ns(now);
        let mut due = Vec::new();
        let mut keep = Vec::with_capacity(self.pending.len());
        for p in std::mem::take(&mut self.pending) {
            if p.to == to && instant_from_ns(p.at_ns) <= now {
                due.push(p);
            } else {
                keep.push(p);
            }
        }
        self.pending = keep;
        let mut out = Vec::new();
        for p in due {
            if let Some(b) = self.deliver(p) {
                out.push(b);
            }
        }
        self.prune(now_ns);
        out
    }

    /// Applies the delivery-time checks (power, half duplex, noise) to one character.
    fn deliver(&mut self, p: Pending) -> Option<RxByte> {
        let span = (p.begin_ns, p.at_ns);
        let unit_involved = p.to == End::Unit || p.source == Source::Traffic;
        if unit_involved && (!self.unit_powered_at(p.begin_ns) || !self.unit_powered_at(p.at_ns)) {
            self.stats.dropped += 1;
            return None;
        }
        let mut byte = p.byte;
        let mut error = p.error;
        if let Wiring::TwoWire { master_echo } = self.wiring {
            let receiver_driving = self.transmitting[p.to.index()]
                .iter()
                .any(|&iv| overlaps(iv, span));
            let other_driving = self.transmitting[p.to.other().index()]
                .iter()
                .any(|&iv| overlaps(iv, span));
            match p.source {
                Source::Echo if other_driving => {
                    byte = self.rng.random();
                    error = Some(RxError::Framing);
                }
                Source::Echo => {}
                _ if receiver_driving && p.to == End::Master && master_echo => {
                    byte = self.rng.random();
                    error = Some(RxError::Framing);
                }
                _ if receiver_driving => {
                    self.stats.dropped += 1;
                    return None;
                }
                _ => {}
            }
        }
        if p.source != Source::Noise && self.bursts.iter().any(|&b| overlaps(b, span)) {
            if self.rng.random_bool(0.5) {
                self.stats.dropped += 1;
                return None;
            }
            byte = self.rng.random();
            error = self.random_error(p.to);
        }
        if p.source == Source::Noise {
            self.stats.noise += 1;
        }
        self.stats.delivered += 1;
        Some(RxByte {
            at: instant_from_ns(p.at_ns),
            byte,
            error,
        })
    }

    /// Forgets transmissions that can no longer overlap a pending character.
    fn prune(&mut self, now_ns: u64) {
        let horizon = self
            .pending
            .iter()
            .map(|p| p.begin_ns)
            .min()
            .unwrap_or(now_ns)
            .min(now_ns);
        for list in &mut self.transmitting {
            list.retain(|&(_, end)| end > horizon);
        }
    }
}

/// A character as a mismatched receiver reads it, times relative to the transmission start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct UartChar {
    begin_ps: u64,
    end_ps: u64,
    byte: u8,
    error: Option<RxError>,
}

fn parity_bit(byte: u8, parity: Parity) -> Option<bool> {
    let odd_ones = byte.count_ones() % 2 == 1;
    match parity {
        Parity::None => None,
        Parity::Even => Some(odd_ones),
        Parity::Odd => Some(!odd_ones),
    }
}

/// The bits `config` puts on the wire for `bytes`, back to back (true = high / mark).
fn waveform(config: PortConfig, bytes: &[u8]) -> Vec<bool> {
    let mut bits = Vec::with_capacity(bytes.len() * 12);
    for &b in bytes {
        bits.push(false);
        bits.extend((0..8).map(|i| b & (1 << i) != 0));
        if let Some(p) = parity_bit(b, config.parity) {
            bits.push(p);
        }
        bits.push(true);
        if config.stop_bits == StopBits::Two {
            bits.push(true);
        }
    }
    bits
}

/// Bit-level UART receiver reading a waveform sent with different settings.
fn uart_receive(tx: PortConfig, rx: PortConfig, bytes: &[u8]) -> Vec<UartChar> {
    const PS: u64 = 1_000_000_000_000;
    let bits = waveform(tx, bytes);
    let tx_bit = PS / u64::from(tx.baud.max(1));
    let rx_bit = PS / u64::from(rx.baud.max(1));
    let level = |t: u64| bits.get((t / tx_bit) as usize).copied().unwrap_or(true);
    // First falling edge (high -> low at a bit boundary) at or after `from`.
    let next_edge = |from: u64| -> Option<u64> {
        let first = from.div_ceil(tx_bit) as usize;
        (first..bits.len())
            .find(|&j| !bits[j] && (j == 0 || bits[j - 1]))
            .map(|j| j as u64 * tx_bit)
    };
    let mut out = Vec::new();
    let mut search_from = 0;
    while let Some(edge) = next_edge(search_from) {
        let sample = |i: u64| level(edge + i * rx_bit + rx_bit / 2);
        if sample(0) {
            // Glitch shorter than half a bit: not a start bit.
            search_from = edge + rx_bit / 2 + 1;
            continue;
        }
        let mut byte = 0u8;
        for i in 0..8 {
            if sample(1 + i) {
                byte |= 1 << i;
            }
        }
        let mut next = 9;
        let parity_ok = match parity_bit(byte, rx.parity) {
            None => true,
            Some(expected) => {
                let ok = sample(next) == expected;
                next += 1;
                ok
            }
        };
        let stop_ok = sample(next);
        let error = if !stop_ok {
            Some(RxError::Framing)
        } else if !parity_ok {
            Some(RxError::Parity)
        } else {
            None
        };
        out.push(UartChar {
            begin_ps: edge,
            end_ps: edge + u64::from(rx.bits_per_char()) * rx_bit,
            byte,
            error,
        });
        search_from = edge + next * rx_bit + rx_bit / 2;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const E1: PortConfig = PortConfig::MODBUS_DEFAULT;
    const N1: PortConfig = PortConfig::HPR;
    const O1: PortConfig = PortConfig::new(19_200, Parity::Odd, StopBits::One);
    const E2: PortConfig = PortConfig::new(19_200, Parity::Even, StopBits::Two);

    fn clean(config: PortConfig, wiring: Wiring) -> Line {
        Line::new(config, config, wiring, 7)
    }

    fn all(line: &mut Line, to: End) -> Vec<RxByte> {
        line.receive(to, Instant::from_micros(u64::MAX / 2000))
    }

    #[test]
    fn bytes_arrive_one_character_time_apart_at_8e1() {
        let mut line = clean(E1, Wiring::FourWire);
        let done = line.transmit(End::Master, Instant::from_millis(10), b"ABC");
        let got = all(&mut line, End::Unit);
        let times: Vec<u64> = got.iter().map(|b| b.at.as_micros()).collect();
        // 11 bits / 19200 baud = 572.916 us per character, rounded up to whole microseconds.
        assert_eq!(times, vec![10_573, 11_146, 11_719]);
        assert_eq!(done, Instant::from_micros(11_719));
        assert_eq!(got.iter().map(|b| b.byte).collect::<Vec<_>>(), b"ABC");
        assert!(got.iter().all(|b| b.error.is_none()));
    }

    #[test]
    fn bytes_arrive_one_character_time_apart_at_8n1() {
        let mut line = clean(N1, Wiring::FourWire);
        line.transmit(End::Unit, Instant::ZERO, b"><");
        let got = all(&mut line, End::Master);
        // 10 bits / 19200 baud = 520.833 us.
        assert_eq!(got[0].at, Instant::from_micros(521));
        assert_eq!(got[1].at, Instant::from_micros(1042));
    }

    #[test]
    fn a_second_transmission_queues_behind_the_first() {
        let mut line = clean(E1, Wiring::FourWire);
        let first_done = line.transmit(End::Master, Instant::ZERO, b"12");
        assert!(line.is_transmitting(End::Master, Instant::from_micros(600)));
        let second_done = line.transmit(End::Master, Instant::from_micros(100), b"3");
        assert_eq!(first_done, Instant::from_micros(1146));
        assert_eq!(second_done, Instant::from_micros(1719));
        let got = all(&mut line, End::Unit);
        assert_eq!(got[2].at, Instant::from_micros(1719));
        assert_eq!(line.busy_until(End::Master), Instant::from_micros(1719));
    }

    #[test]
    fn nothing_is_handed_over_before_its_time() {
        let mut line = clean(E1, Wiring::FourWire);
        line.transmit(End::Master, Instant::ZERO, b"xy");
        assert_eq!(line.next_delivery(), Some(Instant::from_micros(573)));
        assert!(
            line.receive(End::Unit, Instant::from_micros(572))
                .is_empty()
        );
        assert_eq!(line.receive(End::Unit, Instant::from_micros(573)).len(), 1);
        assert!(
            line.receive(End::Master, Instant::from_millis(5))
                .is_empty()
        );
        assert_eq!(line.receive(End::Unit, Instant::from_millis(5)).len(), 1);
    }

    #[test]
    fn odd_against_even_parity_flags_every_byte() {
        let mut line = Line::new(E1, O1, Wiring::FourWire, 1);
        line.transmit(End::Master, Instant::ZERO, b":0104");
        let got = all(&mut line, End::Unit);
        assert_eq!(got.iter().map(|b| b.byte).collect::<Vec<_>>(), b":0104");
        assert!(got.iter().all(|b| b.error == Some(RxError::Parity)));
        // Same frame length, so the timing is unchanged.
        assert_eq!(got[0].at, Instant::from_micros(573));
    }

    #[test]
    fn even_parity_read_without_parity_is_a_framing_error_when_the_parity_bit_is_low() {
        let mut line = Line::new(E1, N1, Wiring::FourWire, 1);
        // '0' = 0x30 has two ones (parity bit 0); '1' = 0x31 has three (parity bit 1).
        line.transmit(End::Master, Instant::ZERO, b"0101");
        let got = all(&mut line, End::Unit);
        assert_eq!(got.iter().map(|b| b.byte).collect::<Vec<_>>(), b"0101");
        let errors: Vec<_> = got.iter().map(|b| b.error).collect();
        assert_eq!(
            errors,
            vec![Some(RxError::Framing), None, Some(RxError::Framing), None]
        );
    }

    #[test]
    fn no_parity_read_with_even_parity_loses_sync_on_back_to_back_bytes() {
        let mut line = Line::new(N1, E1, Wiring::FourWire, 1);
        let sent = b">00090<";
        line.transmit(End::Master, Instant::ZERO, sent);
        let got = all(&mut line, End::Unit);
        let clean = got.len() == sent.len()
            && got
                .iter()
                .zip(sent)
                .all(|(g, &s)| g.byte == s && g.error.is_none());
        assert!(!clean, "{got:?}");
        assert!(got.iter().any(|b| b.error == Some(RxError::Framing)));
    }

    #[test]
    fn two_stop_bits_are_read_fine_by_a_one_stop_bit_receiver() {
        let mut line = Line::new(E2, E1, Wiring::FourWire, 1);
        line.transmit(End::Master, Instant::ZERO, b"AB");
        let got = all(&mut line, End::Unit);
        assert_eq!(
            got.iter().map(|b| (b.byte, b.error)).collect::<Vec<_>>(),
            vec![(b'A', None), (b'B', None)]
        );
        // The second character starts 12 bit times after the first.
        assert_eq!(
            got[1].at.as_micros(),
            (12 * 52_083 + 11 * 52_083) / 1000 + 1
        );
    }

    #[test]
    fn a_different_baud_rate_garbles_the_traffic() {
        let other = PortConfig { baud: 9600, ..E1 };
        let mut line = Line::new(E1, other, Wiring::FourWire, 1);
        line.transmit(End::Master, Instant::ZERO, b":010430000001CA\r\n");
        let got = all(&mut line, End::Unit);
        let text: Vec<u8> = got
            .iter()
            .filter(|b| b.error.is_none())
            .map(|b| b.byte)
            .collect();
        assert_ne!(text, b":010430000001CA\r\n");
    }

    #[test]
    fn corruption_flips_one_bit_and_is_seen_by_parity() {
        let mut line = clean(E1, Wiring::FourWire);
        line.set_corrupt_probability(1.0);
        line.transmit(End::Master, Instant::ZERO, &[0u8; 50]);
        let got = all(&mut line, End::Unit);
        assert_eq!(got.len(), 50);
        assert!(got.iter().all(|b| b.byte.count_ones() == 1));
        assert!(got.iter().all(|b| b.error == Some(RxError::Parity)));
        assert_eq!(line.stats().corrupted, 50);
    }

    #[test]
    fn corruption_without_parity_goes_unnoticed_by_the_uart() {
        let mut line = clean(N1, Wiring::FourWire);
        line.set_corrupt_probability(1.0);
        line.transmit(End::Unit, Instant::ZERO, b"AAAA");
        let got = all(&mut line, End::Master);
        assert!(got.iter().all(|b| b.byte != b'A' && b.error.is_none()));
    }

    #[test]
    fn corruption_and_drops_are_random_but_reproducible() {
        let run = |seed| {
            let mut line = Line::new(E1, E1, Wiring::FourWire, seed);
            line.set_corrupt_probability(0.2);
            line.set_drop_probability(0.2);
            line.transmit(End::Master, Instant::ZERO, &[b'5'; 400]);
            all(&mut line, End::Unit)
        };
        let a = run(42);
        assert_eq!(a, run(42));
        assert_ne!(a, run(43));
        let dropped = 400 - a.len();
        let corrupted = a.iter().filter(|b| b.byte != b'5').count();
        assert!((40..=120).contains(&dropped), "{dropped}");
        assert!((40..=120).contains(&corrupted), "{corrupted}");
    }

    #[test]
    fn dropping_everything_delivers_nothing() {
        let mut line = clean(E1, Wiring::FourWire);
        line.set_drop_probability(1.0);
        line.transmit(End::Master, Instant::ZERO, b"hello");
        assert!(all(&mut line, End::Unit).is_empty());
        assert_eq!(line.stats().dropped, 5);
    }

    #[test]
    fn a_noise_burst_garbles_every_byte_inside_the_window_only() {
        let mut line = clean(N1, Wiring::FourWire);
        line.set_noise_density(0.0);
        line.add_noise_burst(Instant::from_millis(100), Duration::from_secs(1));
        line.transmit(End::Master, Instant::from_millis(500), &[b'7'; 100]);
        line.transmit(End::Master, Instant::from_millis(1200), b">00090<");
        let got = all(&mut line, End::Unit);
        let (inside, after): (Vec<&RxByte>, Vec<&RxByte>) =
            got.iter().partition(|b| b.at < Instant::from_millis(1200));
        assert_eq!(after.iter().map(|b| b.byte).collect::<Vec<_>>(), b">00090<");
        // Each of the 100 characters was lost or replaced by a random value.
        let lost = 100 - inside.len();
        assert!((30..=70).contains(&lost), "{lost}");
        assert!(inside.iter().filter(|b| b.byte == b'7').count() <= 2);
    }

    #[test]
    fn a_noise_burst_produces_spurious_bytes_at_both_ends() {
        let mut line = clean(N1, Wiring::FourWire);
        line.add_noise_burst(Instant::from_millis(100), Duration::from_secs(1));
        let at_unit = all(&mut line, End::Unit);
        let at_master = all(&mut line, End::Master);
        // About 0.3 characters per 520.8 us slot over 1 s: ~576 each.
        for heard in [&at_unit, &at_master] {
            assert!((450..=700).contains(&heard.len()), "{}", heard.len());
            assert!(heard.iter().all(|b| {
                b.at > Instant::from_millis(100) && b.at <= Instant::from_millis(1100)
            }));
        }
    }

    #[test]
    fn a_powered_off_unit_neither_hears_nor_speaks() {
        let mut line = clean(E1, Wiring::FourWire);
        line.set_unit_powered(Instant::from_millis(10), false);
        line.transmit(End::Master, Instant::from_millis(20), b"abc");
        line.transmit(End::Unit, Instant::from_millis(20), b"xyz");
        assert!(all(&mut line, End::Unit).is_empty());
        assert!(all(&mut line, End::Master).is_empty());
        line.set_unit_powered(Instant::from_millis(30), true);
        line.transmit(End::Master, Instant::from_millis(40), b"abc");
        line.transmit(End::Unit, Instant::from_millis(40), b"xyz");
        assert_eq!(all(&mut line, End::Unit).len(), 3);
        assert_eq!(all(&mut line, End::Master).len(), 3);
    }

    #[test]
    fn two_wire_master_hears_nothing_while_it_transmits() {
        let mut line = clean(E1, Wiring::TwoWire { master_echo: false });
        // The unit answers early, while the master is still sending.
        line.transmit(End::Master, Instant::ZERO, &[b'a'; 10]);
        line.transmit(End::Unit, Instant::from_millis(2), b"RESP");
        let heard = all(&mut line, End::Master);
        // Characters that ended while the master drove the line (until 5.73 ms) are lost.
        assert!(heard.iter().all(|b| b.at > Instant::from_micros(5_730)));
        assert!(heard.len() < 4);
        // ...and the unit, driving the line, lost part of the master's request.
        assert!(all(&mut line, End::Unit).len() < 10);
    }

    #[test]
    fn four_wire_is_full_duplex() {
        let mut line = clean(E1, Wiring::FourWire);
        line.transmit(End::Master, Instant::ZERO, &[b'a'; 10]);
        line.transmit(End::Unit, Instant::from_millis(2), b"RESP");
        assert_eq!(all(&mut line, End::Master).len(), 4);
        assert_eq!(all(&mut line, End::Unit).len(), 10);
    }

    #[test]
    fn two_wire_echo_returns_the_masters_own_bytes() {
        let mut line = clean(E1, Wiring::TwoWire { master_echo: true });
        line.transmit(End::Master, Instant::ZERO, b":01");
        let echo = all(&mut line, End::Master);
        assert_eq!(echo.iter().map(|b| b.byte).collect::<Vec<_>>(), b":01");
        assert_eq!(echo[0].at, Instant::from_micros(573));
        assert_eq!(all(&mut line, End::Unit).len(), 3);
    }
}
