//! Timing rules the SYNC guide gives ("Programming recommendations" and the quick-restart
//! section). Plain milliseconds: the protocol crate has no clock; the link applies them.

/// Shortest response time-out to program ("60 ms - 100 ms").
pub const RESPONSE_TIMEOUT_MIN_MS: u32 = 60;
/// Longest response time-out to program.
pub const RESPONSE_TIMEOUT_MAX_MS: u32 = 100;
/// Check for faults at least this often ("every 1 second").
pub const FAULT_CHECK_INTERVAL_MS: u32 = 1_000;
/// Delay between Start signals, for the relay circuits to finish switching.
pub const START_SIGNAL_GAP_MS: u32 = 50;
/// Send no request for this long after a quick restart (0x308E/0x308F).
pub const QUICK_RESTART_SILENCE_MS: u32 = 2_000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values() {
        assert_eq!(
            (RESPONSE_TIMEOUT_MIN_MS, RESPONSE_TIMEOUT_MAX_MS),
            (60, 100)
        );
        assert_eq!(FAULT_CHECK_INTERVAL_MS, 1000);
        assert_eq!(START_SIGNAL_GAP_MS, 50);
        assert_eq!(QUICK_RESTART_SILENCE_MS, 2000);
    }
}
