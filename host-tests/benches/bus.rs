//! Prints the link's measured figures (virtual time, deterministic): bus efficiency under
//! continuous polling and with the default schedule, fault-detection latency with the default
//! schedule (idle, and with a CNC keeping a command in flight, with the commands' own
//! latency), and the cost of a full status cycle against LinuxCNC's pmx485. See
//! `host_tests::harness::measure`.

fn main() {
    // `cargo bench` passes `--bench`; nothing to parse, the run is deterministic.
    print!("{}", host_tests::harness::measure::report());
}
