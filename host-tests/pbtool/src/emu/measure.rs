//! The emulated board's measurements (`emu-probe:` log lines of its board layer, see
//! firmware/boards/emu/src/probe.rs), and `pbtool emu --measure`: QEMU with
//! instruction counting (`-icount shift=0`: one guest nanosecond per instruction), TORCH_ON
//! toggled with the link up and the unit ready, the figures summarised.

use std::time::Duration;

use plasma_firmware::io::{Input, Output};

use host_tests::emu::{Board, BoardOptions, Error, Result};
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
        "{} TORCH_ON cycles measured; waiting for {} idle window(s) of 10 s guest time",
        options.toggles, options.idle_windows
    ));
    let mut mark = board.log().len();
    // The first window ending after the toggles holds some of them: not idle, skipped.
    for window in 0..=options.idle_windows {
        let line = board.log().wait_for(mark, Duration::from_secs(60), |l| {
            matches!(parse_probe(&l.text), Some(Probe::Idle { .. }))
        })?;
        mark = board
            .log()
            .lines()
            .iter()
            .position(|l| l == &line)
            .map_or(board.log().len(), |i| i + 1);
        if window > 0
            && let Some(Probe::Idle {
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
        assert_eq!(parse_probe("link up: Powermax65"), None);
        assert_eq!(
            parse_probe("emu-probe: TORCH_ON edge to START maybe: 1 ns busy"),
            None
        );
        assert_eq!(parse_probe("emu-probe: idle 1 ns asleep"), None);
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
            idle: vec![(9_900_000_000, 10_000_000_000, 1000, 2000)],
        }
        .report();
        assert!(report.contains("3 samples, instructions min 800 / median 900 / max 1000"));
        assert!(report.contains("START off: no samples"));
        assert!(
            report.contains("99.00 % asleep, 100000000 instructions executed, 100.0 wake-ups/s")
        );
    }
}
