//! The emulated board's measurements (`emu-probe:` log lines of its board layer, see
//! firmware/boards/emu/src/probe.rs), and `pbtool emu --measure`: QEMU with
//! instruction counting (`-icount shift=0`: one guest nanosecond per instruction), TORCH_ON
//! toggled with the link up and the unit ready, pmx485's Modbus requests on the CNC port, the
//! figures summarised.

use std::time::Duration;

use plasma_firmware::io::{Input, Output};

use host_tests::emu::log::LogLine;
use host_tests::emu::{Board, BoardOptions, Error, Result};
use plasma_protocol::modbus_ascii::{self, Request};
use plasma_protocol::powermax::legacy;
use plasma_sim::Model;

/// One `emu-probe:` line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Probe {
    /// A START change that followed a TORCH_ON edge.
    TorchToStart {
        /// The new START level.
        on: bool,
        /// Guest nanoseconds the core was busy (not asleep) from the edge's interrupt to the
        /// GPIO write: under `-icount shift=0`, instructions.
        busy_ns: u64,
        /// Guest nanoseconds from the edge to the write, asleep or not.
        elapsed_ns: u64,
    },
    /// CNC lines answered in one idle window: from the read of a line's LF to the write of
    /// its reply's.
    CncReplies(CncFigures),
    /// One idle window.
    Idle {
        /// Guest nanoseconds asleep (WFI).
        asleep_ns: u64,
        /// The window's length.
        elapsed_ns: u64,
        /// Wake-ups from sleep in the window.
        wake_ups: u32,
        /// Executor polls in the window.
        polls: u32,
    },
}

/// Parses an `emu-probe:` line; `None` for any other line.
pub fn parse_probe(text: &str) -> Option<Probe> {
    let rest = text.strip_prefix("emu-probe: ")?;
    let numbers = |s: &str| -> Vec<u64> {
        s.split(|c: char| !c.is_ascii_digit())
            .filter(|w| !w.is_empty())
            .filter_map(|w| w.parse().ok())
            .collect()
    };
    if let Some(rest) = rest.strip_prefix("TORCH_ON edge to START ") {
        let (level, figures) = rest.split_once(':')?;
        let on = match level {
            "on" => true,
            "off" => false,
            _ => return None,
        };
        let &[busy_ns, elapsed_ns] = numbers(figures).as_slice() else {
            return None;
        };
        return Some(Probe::TorchToStart {
            on,
            busy_ns,
            elapsed_ns,
        });
    }
    if let Some(rest) = rest.strip_prefix("CNC line to reply: ") {
        let &[
            lines,
            busy_min,
            busy_max,
            busy_sum,
            elapsed_min,
            elapsed_max,
            elapsed_sum,
        ] = numbers(rest).as_slice()
        else {
            return None;
        };
        return Some(Probe::CncReplies(CncFigures {
            lines,
            busy: Spread {
                min: busy_min,
                max: busy_max,
                sum: busy_sum,
            },
            elapsed: Spread {
                min: elapsed_min,
                max: elapsed_max,
                sum: elapsed_sum,
            },
        }));
    }
    if let Some(rest) = rest.strip_prefix("idle ") {
        let &[asleep_ns, elapsed_ns, wake_ups, polls] = numbers(rest).as_slice() else {
            return None;
        };
        return Some(Probe::Idle {
            asleep_ns,
            elapsed_ns,
            wake_ups: u32::try_from(wake_ups).ok()?,
            polls: u32::try_from(polls).ok()?,
        });
    }
    None
}

/// Minimum, maximum and sum of one figure over several samples, in guest ns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Spread {
    /// The smallest.
    pub min: u64,
    /// The largest.
    pub max: u64,
    /// All of them added.
    pub sum: u64,
}

/// CNC lines answered (the board sums them per idle window).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CncFigures {
    /// How many.
    pub lines: u64,
    /// Guest ns the core was busy in each: instructions.
    pub busy: Spread,
    /// Guest ns each took, asleep or not.
    pub elapsed: Spread,
}

impl CncFigures {
    /// The figures of `self` and `other` together.
    pub fn merge(self, other: CncFigures) -> CncFigures {
        let spread = |a: Spread, b: Spread| Spread {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
            sum: a.sum + b.sum,
        };
        CncFigures {
            lines: self.lines + other.lines,
            busy: spread(self.busy, other.busy),
            elapsed: spread(self.elapsed, other.elapsed),
        }
    }
}

/// Minimum, median and maximum of `values` (`None` when empty).
pub fn min_median_max(values: &[u64]) -> Option<(u64, u64, u64)> {
    let mut sorted = values.to_vec();
    sorted.sort_unstable();
    let median = match sorted.len() {
        0 => return None,
        n if n % 2 == 1 => sorted[n / 2],
        n => (sorted[n / 2 - 1] + sorted[n / 2]) / 2,
    };
    Some((sorted[0], median, sorted[sorted.len() - 1]))
}

/// What `pbtool emu --measure` asks for.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasureOptions {
    /// The simulated unit.
    pub model: Model,
    /// TORCH_ON cycles (each gives a START-on and a START-off figure).
    pub toggles: usize,
    /// pmx485 cycles on the CNC port (each: its six reads, see [`PMX485_CYCLE`]), after its
    /// three connect writes.
    pub modbus_cycles: usize,
    /// Idle windows (10 s of guest time each) to report after the toggles (the window in which
    /// the toggles end is skipped).
    pub idle_windows: usize,
}

/// The figures.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Measurements {
    /// Instructions from a TORCH_ON edge to START on (busy guest ns under icount).
    pub to_start_on: Vec<u64>,
    /// Instructions from a TORCH_ON release to START off.
    pub to_start_off: Vec<u64>,
    /// pmx485's Modbus requests on the CNC port, answered.
    pub modbus: Option<CncFigures>,
    /// Idle windows: (asleep ns, elapsed ns, wake-ups, polls).
    pub idle: Vec<(u64, u64, u32, u32)>,
}

impl Measurements {
    /// The report `pbtool emu --measure` prints.
    pub fn report(&self) -> String {
        let mut text = String::new();
        for (what, values) in [
            ("TORCH_ON edge -> START on", &self.to_start_on),
            ("TORCH_ON release -> START off", &self.to_start_off),
        ] {
            match min_median_max(values) {
                Some((min, median, max)) => text.push_str(&format!(
                    "{what:<29}: {} samples, instructions min {min} / median {median} / max \
                     {max}\n",
                    values.len()
                )),
                None => text.push_str(&format!("{what:<29}: no samples\n")),
            }
        }
        match self.modbus {
            Some(cnc) if cnc.lines > 0 => {
                let us = |ns: u64| ns as f64 / 1e3;
                text.push_str(&format!(
                    "CNC Modbus request -> reply  : {} samples, guest time min {:.1} / mean {:.1} \
                     / max {:.1} us, instructions mean {} / max {}\n",
                    cnc.lines,
                    us(cnc.elapsed.min),
                    us(cnc.elapsed.sum / cnc.lines),
                    us(cnc.elapsed.max),
                    cnc.busy.sum / cnc.lines,
                    cnc.busy.max
                ));
            }
            _ => text.push_str("CNC Modbus request -> reply  : no samples\n"),
        }
        for &(asleep, elapsed, wake_ups, polls) in &self.idle {
            let seconds = elapsed as f64 / 1e9;
            text.push_str(&format!(
                "idle window of {seconds:.1} s guest time: {:.2} % asleep, {} instructions \
                 executed, {:.1} wake-ups/s, {:.1} executor polls/s\n",
                100.0 * asleep as f64 / elapsed.max(1) as f64,
                elapsed.saturating_sub(asleep),
                f64::from(wake_ups) / seconds.max(1e-9),
                f64::from(polls) / seconds.max(1e-9),
            ));
        }
        text
    }
}

/// How long the link may take to come up (a slow, loaded machine).
const LINK_TIMEOUT: Duration = Duration::from_secs(30);
/// Generous bound for one START change or one probe line.
const STEP_TIMEOUT: Duration = Duration::from_secs(5);
/// Between START off and the next TORCH_ON: more than the 50 ms gap, so START follows the
/// edge itself (a START delayed by the gap is the timer's, not the edge's, and not measured).
const PAUSE: Duration = Duration::from_millis(150);

/// Boots a board under instruction counting and measures; `progress` hears what happens.
pub fn measure(options: &MeasureOptions, mut progress: impl FnMut(&str)) -> Result<Measurements> {
    let mut board = Board::boot(BoardOptions {
        icount: true,
        ..BoardOptions::new(options.model)
    })?;
    progress("booted under -icount shift=0,sleep=on; waiting for the link and a ready unit");
    board.wait_status(LINK_TIMEOUT, |s| {
        s.contains("link=UP") && s.contains("ready=ON")
    })?;
    let mut result = Measurements::default();
    for _ in 0..options.toggles {
        for on in [true, false] {
            let mark = board.log().len();
            board.set_input(Input::TorchOn, on)?;
            board.wait_output(Output::Start, on, STEP_TIMEOUT)?;
            let line = board.log().wait_for(mark, STEP_TIMEOUT, |l| {
                matches!(parse_probe(&l.text), Some(Probe::TorchToStart { on: o, .. }) if o == on)
            })?;
            if let Some(Probe::TorchToStart { busy_ns, .. }) = parse_probe(&line.text) {
                if on {
                    result.to_start_on.push(busy_ns);
                } else {
                    result.to_start_off.push(busy_ns);
                }
            }
            std::thread::sleep(PAUSE);
        }
    }
    progress(&format!(
        "{} TORCH_ON cycles measured; the Modbus requests and {} idle window(s) of 10 s guest \
         time follow",
        options.toggles, options.idle_windows
    ));
    // The window in which the toggles end holds some of them: not idle, skipped.
    let (mut mark, _) = next_window(&board, board.log().len())?;
    if options.modbus_cycles > 0 {
        let sent = send_pmx485_requests(&mut board, options.modbus_cycles)?;
        // The board sums the figures per window: the windows they fall in (not idle either).
        let mut figures: Option<CncFigures> = None;
        // Sent within a second or two: two windows at most (three, to be generous).
        for _ in 0..3 {
            if figures.map_or(0, |f| f.lines) >= sent {
                break;
            }
            let (end, _) = next_window(&board, mark)?;
            for line in board.log().since(mark).iter().take(end - mark) {
                if let Some(Probe::CncReplies(window)) = parse_probe(&line.text) {
                    figures = Some(figures.map_or(window, |f| f.merge(window)));
                }
            }
            mark = end;
        }
        let reported = figures.map_or(0, |f| f.lines);
        if reported != sent {
            return Err(Error::Protocol(format!(
                "the board reported {reported} answered CNC lines for the {sent} requests sent"
            )));
        }
        result.modbus = figures;
    }
    for _ in 0..options.idle_windows {
        let (end, line) = next_window(&board, mark)?;
        mark = end;
        if let Some(Probe::Idle {
            asleep_ns,
            elapsed_ns,
            wake_ups,
            polls,
        }) = parse_probe(&line.text)
        {
            result.idle.push((asleep_ns, elapsed_ns, wake_ups, polls));
        }
    }
    if result.to_start_on.is_empty() && options.toggles > 0 {
        return Err(Error::Protocol("no TORCH_ON figure was logged".to_string()));
    }
    Ok(result)
}

/// pmx485's connect writes (mode 1, 45 A, pressure automatic), as QtPlasmaC sends them.
pub const PMX485_CONNECT: [(u16, u16); 3] = [
    (legacy::MODE_FORCE, 1),
    (legacy::CURRENT_FORCE, 45 * 64),
    (legacy::PRESSURE_FORCE, 0),
];

/// The registers pmx485 reads every cycle (function 04, one each): the settings back, the
/// fault, the arc time.
pub const PMX485_CYCLE: [u16; 6] = [
    legacy::MODE_FORCE,
    legacy::CURRENT_FORCE,
    legacy::PRESSURE_FORCE,
    legacy::FAULT_CODE,
    legacy::ARC_TIME_LOW,
    legacy::ARC_TIME_HIGH,
];

/// pmx485's node (hard-coded in it; the bridge's default `cnc_address`).
const PMX485_NODE: u8 = 1;

/// `request` as a frame for the CNC port, without its CR LF (the console adds it).
fn modbus_line(request: &Request<'_>) -> Result<String> {
    let mut out = [0u8; modbus_ascii::MAX_FRAME_CHARS];
    let n = modbus_ascii::encode_request(PMX485_NODE, request, &mut out)
        .map_err(|e| Error::Protocol(format!("encoding {request:?}: {e:?}")))?;
    Ok(String::from_utf8_lossy(&out[..n]).trim_end().to_string())
}

/// Sends pmx485's writes, then `cycles` of its reads, one at a time as pmx485 does; how many
/// it sent (every one answered with a Modbus reply).
fn send_pmx485_requests(board: &mut Board, cycles: usize) -> Result<u64> {
    let mut lines = Vec::new();
    for (address, value) in PMX485_CONNECT {
        lines.push(modbus_line(&Request::WriteSingleRegister {
            address,
            value,
        })?);
    }
    for _ in 0..cycles {
        for start in PMX485_CYCLE {
            lines.push(modbus_line(&Request::ReadInputRegisters {
                start,
                quantity: 1,
            })?);
        }
    }
    for line in &lines {
        let reply = board.command(line, STEP_TIMEOUT)?;
        if !reply.starts_with(':') {
            return Err(Error::Protocol(format!(
                "{line} was answered with {reply:?}"
            )));
        }
    }
    Ok(lines.len() as u64)
}

/// Waits for the next idle report after log line `mark`; the index after it, and the line.
fn next_window(board: &Board, mark: usize) -> Result<(usize, LogLine)> {
    let line = board.log().wait_for(mark, Duration::from_secs(60), |l| {
        matches!(parse_probe(&l.text), Some(Probe::Idle { .. }))
    })?;
    let end = board
        .log()
        .lines()
        .iter()
        .skip(mark)
        .position(|l| l == &line)
        .map_or(board.log().len(), |i| mark + i + 1);
    Ok((end, line))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_lines_are_parsed() {
        assert_eq!(
            parse_probe("emu-probe: TORCH_ON edge to START on: 812 ns busy, 1040 ns elapsed"),
            Some(Probe::TorchToStart {
                on: true,
                busy_ns: 812,
                elapsed_ns: 1040
            })
        );
        assert_eq!(
            parse_probe("emu-probe: TORCH_ON edge to START off: 5 ns busy, 9 ns elapsed"),
            Some(Probe::TorchToStart {
                on: false,
                busy_ns: 5,
                elapsed_ns: 9
            })
        );
        assert_eq!(
            parse_probe(
                "emu-probe: idle 9990000000 ns asleep of 10000000000 ns, 1200 wake-ups, 1500 polls"
            ),
            Some(Probe::Idle {
                asleep_ns: 9_990_000_000,
                elapsed_ns: 10_000_000_000,
                wake_ups: 1200,
                polls: 1500
            })
        );
        assert_eq!(
            parse_probe(
                "emu-probe: CNC line to reply: 3 lines, busy min 5000 max 6000 sum 16500 ns, \
                 elapsed min 5200 max 6300 sum 17100 ns"
            ),
            Some(Probe::CncReplies(CncFigures {
                lines: 3,
                busy: Spread {
                    min: 5000,
                    max: 6000,
                    sum: 16_500
                },
                elapsed: Spread {
                    min: 5200,
                    max: 6300,
                    sum: 17_100
                },
            }))
        );
        assert_eq!(parse_probe("link up: Powermax65"), None);
        assert_eq!(
            parse_probe("emu-probe: TORCH_ON edge to START maybe: 1 ns busy"),
            None
        );
        assert_eq!(parse_probe("emu-probe: idle 1 ns asleep"), None);
    }

    #[test]
    fn pmx485s_requests_are_the_frames_it_sends() {
        // From LinuxCNC's pmx485: node 1, function 06 / 04, CR LF added by the console.
        let write = Request::WriteSingleRegister {
            address: legacy::CURRENT_FORCE,
            value: 45 * 64,
        };
        assert_eq!(modbus_line(&write).unwrap(), ":010620940B40FA");
        let read = Request::ReadInputRegisters {
            start: legacy::CURRENT_MIN,
            quantity: 1,
        };
        assert_eq!(modbus_line(&read).unwrap(), ":01042099000141");
    }

    #[test]
    fn figures_are_summarised() {
        assert_eq!(min_median_max(&[]), None);
        assert_eq!(min_median_max(&[5]), Some((5, 5, 5)));
        assert_eq!(min_median_max(&[9, 1, 5]), Some((1, 5, 9)));
        assert_eq!(min_median_max(&[4, 1, 2, 3]), Some((1, 2, 4)));
        let report = Measurements {
            to_start_on: vec![800, 900, 1000],
            to_start_off: vec![],
            modbus: Some(
                CncFigures {
                    lines: 1,
                    busy: Spread {
                        min: 20_000,
                        max: 20_000,
                        sum: 20_000,
                    },
                    elapsed: Spread {
                        min: 30_000,
                        max: 30_000,
                        sum: 30_000,
                    },
                }
                .merge(CncFigures {
                    lines: 1,
                    busy: Spread {
                        min: 25_000,
                        max: 25_000,
                        sum: 25_000,
                    },
                    elapsed: Spread {
                        min: 40_500,
                        max: 40_500,
                        sum: 40_500,
                    },
                }),
            ),
            idle: vec![(9_900_000_000, 10_000_000_000, 1000, 2000)],
        }
        .report();
        assert!(report.contains("3 samples, instructions min 800 / median 900 / max 1000"));
        assert!(report.contains("START off: no samples"));
        assert!(
            report.contains(
                "2 samples, guest time min 30.0 / mean 35.2 / max 40.5 us, instructions mean \
                 22500 / max 25000"
            ),
            "{report}"
        );
        assert!(
            report.contains("99.00 % asleep, 100000000 instructions executed, 100.0 wake-ups/s")
        );
    }
}
