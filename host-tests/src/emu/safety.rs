//! The START safety rules (docs/architecture.md, "Safety rules"), checked on what the harness observed of the
//! emulated board: the TORCH_ON levels it drove and the START edges QEMU streamed, in the order
//! QEMU saw them (both travel on the one qtest socket, see
//! [`Qtest::command_marked`](super::qtest::Qtest::command_marked)).
//!
//! Order is exact; time is the host's clock when the harness read each edge, so the gap rule
//! is checked with [`GAP_TOLERANCE`] off the manuals' 50 ms (the reader thread may be
//! scheduled late for the falling edge on a loaded host, which shortens the gap seen; a rule
//! not kept at all shows gaps of a few ms). The exact check uses the firmware's own log of
//! its output changes (tests/emu_io.rs). Rules:
//! - START is off when the board starts, and when it resets itself (the fault path and the
//!   watchdog make the outputs safe first);
//! - START never rises while TORCH_ON is inactive;
//! - a TORCH_ON active at power-up, or held through a reset, never raises START until it has
//!   been seen inactive;
//! - START rises at least 50 ms after its previous fall.

use std::time::{Duration, Instant};

/// The manuals' least delay between Start signals.
pub const START_GAP: Duration = Duration::from_millis(50);
/// How much shorter than [`START_GAP`] an observed gap may be (reading jitter on the host).
pub const GAP_TOLERANCE: Duration = Duration::from_millis(25);

/// One observation, in QEMU's order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Observed {
    /// The harness drove TORCH_ON.
    TorchOn {
        /// When (host clock).
        at: Instant,
        /// Active or not.
        active: bool,
    },
    /// START changed.
    Start {
        /// When the harness read the edge (host clock).
        at: Instant,
        /// The new state.
        on: bool,
    },
    /// The firmware reset the MCU; the board booted again.
    Reset {
        /// When the harness saw the reset (host clock).
        at: Instant,
        /// START's state when the MCU reset (the reset itself releases the pin, and the
        /// pull-down holds it off).
        start_on: bool,
    },
}

impl Observed {
    /// When the harness made or saw it (host clock).
    pub fn at(self) -> Instant {
        match self {
            Observed::TorchOn { at, .. }
            | Observed::Start { at, .. }
            | Observed::Reset { at, .. } => at,
        }
    }
}

/// Checks `observed` (from power-up: `torch_at_power_up` is TORCH_ON's state before the first
/// instruction, `start_at_power_up` START's before the first instruction and right after
/// it); returns each broken rule as a sentence, with its time from `epoch`.
pub fn check(
    epoch: Instant,
    torch_at_power_up: bool,
    start_at_power_up: bool,
    observed: &[Observed],
) -> Vec<String> {
    let ms = |at: Instant| at.saturating_duration_since(epoch).as_secs_f64() * 1000.0;
    let mut broken = Vec::new();
    if start_at_power_up {
        broken.push("START on at power-up".to_string());
    }
    let mut torch = torch_at_power_up;
    let mut stuck = torch_at_power_up;
    let mut start = start_at_power_up;
    let mut last_fall: Option<Instant> = None;
    for item in observed {
        match *item {
            Observed::TorchOn { active, .. } => {
                torch = active;
                if !active {
                    stuck = false;
                }
            }
            Observed::Start { at, on } => {
                if on && !start {
                    if !torch {
                        broken.push(format!(
                            "{:.1} ms: START rose while TORCH_ON was off",
                            ms(at)
                        ));
                    }
                    if stuck {
                        broken.push(format!(
                            "{:.1} ms: START rose from a TORCH_ON held since power-up or a reset",
                            ms(at)
                        ));
                    }
                    if let Some(fall) = last_fall {
                        let gap = at.saturating_duration_since(fall);
                        if gap + GAP_TOLERANCE < START_GAP {
                            broken.push(format!(
                                "{:.1} ms: START rose {:.1} ms after it fell (at least 50 ms)",
                                ms(at),
                                gap.as_secs_f64() * 1000.0
                            ));
                        }
                    }
                }
                if !on && start {
                    last_fall = Some(at);
                }
                start = on;
            }
            Observed::Reset { at, start_on } => {
                if start_on {
                    broken.push(format!(
                        "{:.1} ms: START on when the MCU reset (not made safe first)",
                        ms(at)
                    ));
                    last_fall = Some(at);
                }
                start = false;
                stuck = torch;
            }
        }
    }
    broken
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(epoch: Instant, ms: u64) -> Instant {
        epoch + Duration::from_millis(ms)
    }

    #[test]
    fn a_clean_run_breaks_nothing() {
        let t0 = Instant::now();
        let run = [
            Observed::TorchOn {
                at: at(t0, 100),
                active: true,
            },
            Observed::Start {
                at: at(t0, 101),
                on: true,
            },
            Observed::TorchOn {
                at: at(t0, 200),
                active: false,
            },
            Observed::Start {
                at: at(t0, 201),
                on: false,
            },
            Observed::TorchOn {
                at: at(t0, 210),
                active: true,
            },
            Observed::Start {
                at: at(t0, 252),
                on: true,
            },
        ];
        assert_eq!(check(t0, false, false, &run), Vec::<String>::new());
    }

    #[test]
    fn each_rule_is_caught() {
        let t0 = Instant::now();
        assert_eq!(check(t0, false, true, &[]), ["START on at power-up"]);
        let without_torch = [Observed::Start {
            at: at(t0, 5),
            on: true,
        }];
        assert_eq!(
            check(t0, false, false, &without_torch),
            ["5.0 ms: START rose while TORCH_ON was off"]
        );
        // Held since power-up: released and pressed again is fine, held is not.
        let stuck = [Observed::Start {
            at: at(t0, 5),
            on: true,
        }];
        assert_eq!(
            check(t0, true, false, &stuck),
            ["5.0 ms: START rose from a TORCH_ON held since power-up or a reset"]
        );
        let released = [
            Observed::TorchOn {
                at: at(t0, 10),
                active: false,
            },
            Observed::TorchOn {
                at: at(t0, 20),
                active: true,
            },
            Observed::Start {
                at: at(t0, 21),
                on: true,
            },
        ];
        assert!(check(t0, true, false, &released).is_empty());
        let quick = [
            Observed::TorchOn {
                at: at(t0, 10),
                active: true,
            },
            Observed::Start {
                at: at(t0, 10),
                on: true,
            },
            Observed::TorchOn {
                at: at(t0, 20),
                active: false,
            },
            Observed::Start {
                at: at(t0, 20),
                on: false,
            },
            Observed::TorchOn {
                at: at(t0, 30),
                active: true,
            },
            Observed::Start {
                at: at(t0, 40),
                on: true,
            },
        ];
        assert_eq!(
            check(t0, false, false, &quick),
            ["40.0 ms: START rose 20.0 ms after it fell (at least 50 ms)"]
        );
    }

    #[test]
    fn a_reset_is_a_power_up() {
        let t0 = Instant::now();
        let torch_held = |start_on| {
            [
                Observed::TorchOn {
                    at: at(t0, 10),
                    active: true,
                },
                Observed::Start {
                    at: at(t0, 11),
                    on: true,
                },
                Observed::Reset {
                    at: at(t0, 20),
                    start_on,
                },
                Observed::Start {
                    at: at(t0, 500),
                    on: true,
                },
            ]
        };
        assert_eq!(
            check(t0, false, false, &torch_held(false)),
            ["500.0 ms: START rose from a TORCH_ON held since power-up or a reset"]
        );
        assert_eq!(
            check(t0, false, false, &torch_held(true)),
            [
                "20.0 ms: START on when the MCU reset (not made safe first)",
                "500.0 ms: START rose from a TORCH_ON held since power-up or a reset"
            ]
        );
        // Released and pressed again after the reset: a new press.
        let pressed_again = [
            Observed::TorchOn {
                at: at(t0, 10),
                active: true,
            },
            Observed::Reset {
                at: at(t0, 20),
                start_on: false,
            },
            Observed::TorchOn {
                at: at(t0, 400),
                active: false,
            },
            Observed::TorchOn {
                at: at(t0, 450),
                active: true,
            },
            Observed::Start {
                at: at(t0, 451),
                on: true,
            },
        ];
        assert!(check(t0, false, false, &pressed_again).is_empty());
    }

    #[test]
    fn a_gap_read_a_little_short_is_tolerated() {
        let t0 = Instant::now();
        let run = [
            Observed::TorchOn {
                at: at(t0, 10),
                active: true,
            },
            Observed::Start {
                at: at(t0, 10),
                on: true,
            },
            Observed::TorchOn {
                at: at(t0, 20),
                active: false,
            },
            // The reader was scheduled 15 ms late for the falling edge.
            Observed::Start {
                at: at(t0, 35),
                on: false,
            },
            Observed::TorchOn {
                at: at(t0, 30),
                active: true,
            },
            Observed::Start {
                at: at(t0, 70),
                on: true,
            },
        ];
        assert!(check(t0, false, false, &run).is_empty());
    }
}
