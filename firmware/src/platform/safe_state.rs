//! The panic and reset policy, as data and pure functions.
//!
//! The board image applies it: on panic or hard fault it drives [`SAFE_OUTPUTS`] (every output
//! off, so START is off), leaves [`PANIC_MARKER`] in RAM that survives the reset, logs, and
//! resets. At the next boot [`BootReport::read`] turns the reset flags and the marker into a
//! cause the supervisor can report on the CNC port.
//!
//! ```
//! use plasma_firmware::platform::safe_state::{BootReport, ResetCause, PANIC_MARKER};
//!
//! // RCC_CSR after an independent-watchdog reset: IWDGRSTF and PINRSTF (an internal reset also
//! // pulls the NRST pin, so PINRSTF comes along with every cause).
//! let report = BootReport::read((1 << 29) | (1 << 26), 0);
//! assert_eq!(report.cause, ResetCause::IndependentWatchdog);
//! assert!(report.is_fault());
//!
//! // A software reset that the panic handler asked for.
//! let report = BootReport::read(1 << 28, PANIC_MARKER);
//! assert_eq!(report.cause, ResetCause::Panic);
//! assert_eq!(report.cause.as_str(), "panic");
//! ```

use core::sync::atomic::{AtomicBool, Ordering};

/// The outputs are the I/O's; where each one is: [`crate::platform::pins`].
pub use crate::io::Output;

const fn bit(output: Output) -> u8 {
    1 << output as u8
}

/// A set of outputs that are on (asserted); every other output is off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OutputSet(u8);

impl OutputSet {
    /// All outputs off.
    pub const NONE: OutputSet = OutputSet(0);

    /// This set with `output` on.
    #[must_use]
    pub const fn with(self, output: Output) -> Self {
        OutputSet(self.0 | bit(output))
    }

    /// This set with `output` off.
    #[must_use]
    pub const fn without(self, output: Output) -> Self {
        OutputSet(self.0 & !bit(output))
    }

    /// Whether `output` is on.
    pub const fn is_on(self, output: Output) -> bool {
        self.0 & bit(output) != 0
    }

    /// The level each output should have, in [`Output::ALL`] order.
    pub fn levels(self) -> impl Iterator<Item = (Output, bool)> {
        Output::ALL.into_iter().map(move |o| (o, self.is_on(o)))
    }
}

/// The outputs in safe state: everything off. START off stops the arc; READY off tells the CNC
/// the bridge is not usable; FAULT is off too because a dead or resetting board cannot promise
/// to keep it on, so the CNC must treat "READY off" as the failure signal.
pub const SAFE_OUTPUTS: OutputSet = OutputSet::NONE;

/// Value the panic handler leaves in a RAM word that the reset does not clear (`.uninit`),
/// so the next boot can tell a panic from an ordinary software reset. ASCII "PANC".
pub const PANIC_MARKER: u32 = 0x5041_4E43;

/// The reset flags of the STM32L4's RCC_CSR register (RM0351, RCC_CSR bits 24..31).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ResetFlags(u8);

impl ResetFlags {
    /// FWRSTF, bit 24: firewall reset.
    pub const FIREWALL: ResetFlags = ResetFlags(1 << 0);
    /// OBLRSTF, bit 25: option byte loader reset.
    pub const OPTION_BYTE_LOAD: ResetFlags = ResetFlags(1 << 1);
    /// PINRSTF, bit 26: NRST pin (also set by every internal reset, which drives NRST).
    pub const PIN: ResetFlags = ResetFlags(1 << 2);
    /// BORRSTF, bit 27: brown-out reset, which includes power-on.
    pub const BROWN_OUT: ResetFlags = ResetFlags(1 << 3);
    /// SFTRSTF, bit 28: software reset (SYSRESETREQ).
    pub const SOFTWARE: ResetFlags = ResetFlags(1 << 4);
    /// IWDGRSTF, bit 29: independent watchdog.
    pub const INDEPENDENT_WATCHDOG: ResetFlags = ResetFlags(1 << 5);
    /// WWDGRSTF, bit 30: window watchdog.
    pub const WINDOW_WATCHDOG: ResetFlags = ResetFlags(1 << 6);
    /// LPWRRSTF, bit 31: illegal Stop/Standby/Shutdown entry (option bytes nRST_STOP etc.).
    pub const LOW_POWER: ResetFlags = ResetFlags(1 << 7);

    /// The flags in an RCC_CSR value; the other bits (clock controls, RMVF) are ignored.
    pub const fn from_csr(csr: u32) -> Self {
        ResetFlags((csr >> 24) as u8)
    }

    /// Whether every flag of `other` is set here.
    pub const fn contains(self, other: ResetFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// The raw flags, bit 0 = FWRSTF .. bit 7 = LPWRRSTF.
    pub const fn bits(self) -> u8 {
        self.0
    }
}

/// Why the MCU last reset, the most specific cause first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetCause {
    /// The firmware panicked (or hard-faulted) and reset itself.
    Panic,
    /// The independent watchdog was not fed: a task stalled.
    IndependentWatchdog,
    /// The window watchdog fired.
    WindowWatchdog,
    /// A low-power mode was entered while the option bytes forbid it.
    LowPower,
    /// The firewall caught an illegal access.
    Firewall,
    /// The firmware asked for a reset (for example after a settings change).
    Software,
    /// Option bytes were reloaded.
    OptionByteLoad,
    /// Power-on or supply brown-out.
    PowerOn,
    /// The reset button or the debugger pulled NRST.
    Pin,
    /// No flag was set (the flags were cleared and nothing reset since, or a debugger
    /// restarted the core without a system reset).
    Unknown,
}

impl ResetCause {
    /// A short text for the log and the CNC port.
    pub const fn as_str(self) -> &'static str {
        match self {
            ResetCause::Panic => "panic",
            ResetCause::IndependentWatchdog => "watchdog",
            ResetCause::WindowWatchdog => "window watchdog",
            ResetCause::LowPower => "low-power reset",
            ResetCause::Firewall => "firewall",
            ResetCause::Software => "software reset",
            ResetCause::OptionByteLoad => "option byte load",
            ResetCause::PowerOn => "power-on",
            ResetCause::Pin => "reset pin",
            ResetCause::Unknown => "unknown",
        }
    }

    /// Whether the reset means the firmware misbehaved, so the supervisor raises a fault the
    /// operator has to see, rather than starting up silently.
    pub const fn is_fault(self) -> bool {
        matches!(
            self,
            ResetCause::Panic
                | ResetCause::IndependentWatchdog
                | ResetCause::WindowWatchdog
                | ResetCause::LowPower
                | ResetCause::Firewall
        )
    }
}

/// Decodes the cause of the last reset from RCC_CSR.
///
/// Several flags are usually set at once: every internal reset also drives the NRST pin
/// (PINRSTF), and power-on sets BORRSTF and PINRSTF. So the flags are ranked from the most
/// specific to the least: watchdogs, low-power, firewall, software, option bytes, brown-out,
/// and the pin last.
pub const fn reset_cause(csr: u32) -> ResetCause {
    let flags = ResetFlags::from_csr(csr);
    if flags.contains(ResetFlags::INDEPENDENT_WATCHDOG) {
        ResetCause::IndependentWatchdog
    } else if flags.contains(ResetFlags::WINDOW_WATCHDOG) {
        ResetCause::WindowWatchdog
    } else if flags.contains(ResetFlags::LOW_POWER) {
        ResetCause::LowPower
    } else if flags.contains(ResetFlags::FIREWALL) {
        ResetCause::Firewall
    } else if flags.contains(ResetFlags::SOFTWARE) {
        ResetCause::Software
    } else if flags.contains(ResetFlags::OPTION_BYTE_LOAD) {
        ResetCause::OptionByteLoad
    } else if flags.contains(ResetFlags::BROWN_OUT) {
        ResetCause::PowerOn
    } else if flags.contains(ResetFlags::PIN) {
        ResetCause::Pin
    } else {
        ResetCause::Unknown
    }
}

/// What the board knows at boot about the previous run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BootReport {
    /// The decoded cause.
    pub cause: ResetCause,
    /// The raw reset flags, for the log.
    pub flags: ResetFlags,
}

impl BootReport {
    /// From RCC_CSR (read before the flags are cleared) and the word the panic handler
    /// writes. The marker counts only together with SFTRSTF: after a power cut the RAM word
    /// holds whatever the SRAM powered up with, and after a watchdog reset the watchdog is
    /// the better explanation.
    pub const fn read(csr: u32, marker: u32) -> Self {
        let flags = ResetFlags::from_csr(csr);
        let mut cause = reset_cause(csr);
        if marker == PANIC_MARKER && matches!(cause, ResetCause::Software) {
            cause = ResetCause::Panic;
        }
        BootReport { cause, flags }
    }

    /// Whether the previous run ended in a fault (see [`ResetCause::is_fault`]).
    pub const fn is_fault(&self) -> bool {
        self.cause.is_fault()
    }
}

/// The fail-safe latch: once a task stalled and the outputs went to [`SAFE_OUTPUTS`], nothing
/// may drive them again until the reset that follows.
///
/// Without it the I/O task, which runs on while another task hangs, would rewrite the pins at
/// its next wake-up (START following TORCH_ON again) until the watchdog resets the MCU up to a
/// second later. The board trips it together with its safe-state write and passes every
/// output write through [`FailSafe::drive_unless_tripped`], both under one critical section,
/// so no write can slip between the two.
#[derive(Debug)]
pub struct FailSafe(AtomicBool);

impl FailSafe {
    /// Not tripped.
    pub const fn new() -> Self {
        FailSafe(AtomicBool::new(false))
    }

    /// From now on every output write is refused.
    pub fn trip(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether [`FailSafe::trip`] was called.
    pub fn is_tripped(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    /// Runs `drive` (an output write) unless tripped; says whether it ran.
    pub fn drive_unless_tripped(&self, drive: impl FnOnce()) -> bool {
        if self.is_tripped() {
            return false;
        }
        drive();
        true
    }
}

impl Default for FailSafe {
    fn default() -> Self {
        Self::new()
    }
}

/// Entry into the fault path (panic, HardFault, NMI): the first entry logs and resets; an
/// entry while that runs (a fault inside the log write, an NMI during it) must not log again,
/// because defmt's RTT logger panics on re-entry: it only makes the outputs safe and resets.
#[derive(Debug)]
pub struct FaultEntry(AtomicBool);

impl FaultEntry {
    /// No fault yet.
    pub const fn new() -> Self {
        FaultEntry(AtomicBool::new(false))
    }

    /// `true` for the first entry only.
    pub fn first(&self) -> bool {
        !self.0.swap(true, Ordering::SeqCst)
    }
}

impl Default for FaultEntry {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LPWRRSTF: u32 = 1 << 31;
    const WWDGRSTF: u32 = 1 << 30;
    const IWDGRSTF: u32 = 1 << 29;
    const SFTRSTF: u32 = 1 << 28;
    const BORRSTF: u32 = 1 << 27;
    const PINRSTF: u32 = 1 << 26;
    const OBLRSTF: u32 = 1 << 25;
    const FWRSTF: u32 = 1 << 24;
    const RMVF: u32 = 1 << 23;

    #[test]
    fn each_flag_alone_decodes_to_its_cause() {
        let cases = [
            (LPWRRSTF, ResetCause::LowPower),
            (WWDGRSTF, ResetCause::WindowWatchdog),
            (IWDGRSTF, ResetCause::IndependentWatchdog),
            (SFTRSTF, ResetCause::Software),
            (BORRSTF, ResetCause::PowerOn),
            (PINRSTF, ResetCause::Pin),
            (OBLRSTF, ResetCause::OptionByteLoad),
            (FWRSTF, ResetCause::Firewall),
            (0, ResetCause::Unknown),
        ];
        for (csr, cause) in cases {
            assert_eq!(reset_cause(csr), cause, "csr {csr:#010x}");
        }
    }

    #[test]
    fn real_flag_combinations() {
        // Power-on reset value of RCC_CSR: BORRSTF | PINRSTF, MSISRANGE = 6 (4 MHz, bits 11:8).
        assert_eq!(reset_cause(0x0C00_0600), ResetCause::PowerOn);
        // Internal resets pulse NRST, so PINRSTF accompanies them.
        assert_eq!(
            reset_cause(IWDGRSTF | PINRSTF),
            ResetCause::IndependentWatchdog
        );
        assert_eq!(reset_cause(SFTRSTF | PINRSTF), ResetCause::Software);
        // Flags accumulate until RMVF clears them: a watchdog reset after a power-on.
        assert_eq!(
            reset_cause(IWDGRSTF | BORRSTF | PINRSTF),
            ResetCause::IndependentWatchdog
        );
    }

    #[test]
    fn bits_outside_the_flags_are_ignored() {
        // LSION, LSIRDY, MSISRANGE, RMVF and the reserved bits.
        let noise = 0x00FF_FFFF | RMVF;
        assert_eq!(reset_cause(noise), ResetCause::Unknown);
        assert_eq!(reset_cause(noise | PINRSTF), ResetCause::Pin);
        assert_eq!(ResetFlags::from_csr(noise).bits(), 0);
    }

    #[test]
    fn every_flag_combination_decodes_to_a_flag_that_is_set() {
        for flags in 0u32..=0xFF {
            let csr = flags << 24;
            let cause = reset_cause(csr);
            let implied = match cause {
                ResetCause::LowPower => LPWRRSTF,
                ResetCause::WindowWatchdog => WWDGRSTF,
                ResetCause::IndependentWatchdog => IWDGRSTF,
                ResetCause::Software => SFTRSTF,
                ResetCause::PowerOn => BORRSTF,
                ResetCause::Pin => PINRSTF,
                ResetCause::OptionByteLoad => OBLRSTF,
                ResetCause::Firewall => FWRSTF,
                ResetCause::Unknown => 0,
                ResetCause::Panic => unreachable!("only BootReport reports panics"),
            };
            assert_eq!(csr & implied, implied, "{csr:#010x} -> {cause:?}");
            assert_eq!(cause == ResetCause::Unknown, flags == 0);
            // The watchdog always wins: it is the one that says a task stalled.
            if csr & IWDGRSTF != 0 {
                assert_eq!(cause, ResetCause::IndependentWatchdog);
            }
        }
    }

    #[test]
    fn panic_marker_counts_only_with_a_software_reset() {
        assert_eq!(
            BootReport::read(SFTRSTF | PINRSTF, PANIC_MARKER).cause,
            ResetCause::Panic
        );
        assert_eq!(BootReport::read(SFTRSTF, 0).cause, ResetCause::Software);
        // Stale marker after a power cycle: SRAM content is undefined, the flags decide.
        assert_eq!(
            BootReport::read(BORRSTF | PINRSTF, PANIC_MARKER).cause,
            ResetCause::PowerOn
        );
        // Panic handler hung and the watchdog finished the job.
        assert_eq!(
            BootReport::read(IWDGRSTF | SFTRSTF, PANIC_MARKER).cause,
            ResetCause::IndependentWatchdog
        );
    }

    #[test]
    fn faults_are_the_unplanned_resets() {
        assert!(BootReport::read(SFTRSTF, PANIC_MARKER).is_fault());
        assert!(BootReport::read(IWDGRSTF, 0).is_fault());
        assert!(!BootReport::read(BORRSTF | PINRSTF, 0).is_fault());
        assert!(!BootReport::read(PINRSTF, 0).is_fault());
        assert!(!BootReport::read(SFTRSTF, 0).is_fault());
    }

    #[test]
    fn safe_state_has_every_output_off() {
        for (output, on) in SAFE_OUTPUTS.levels() {
            assert!(!on, "{} on in safe state", output.as_str());
        }
        assert_eq!(SAFE_OUTPUTS.levels().count(), Output::ALL.len());
        assert_eq!(Output::ALL[0], Output::Start);
    }

    #[test]
    fn output_set_tracks_each_output_separately() {
        let set = OutputSet::NONE.with(Output::Start).with(Output::Ready);
        assert!(set.is_on(Output::Start) && set.is_on(Output::Ready));
        assert!(!set.is_on(Output::Fault));
        let set = set.without(Output::Start);
        assert!(!set.is_on(Output::Start) && set.is_on(Output::Ready));
        let names: Vec<&str> = Output::ALL.iter().map(|o| o.as_str()).collect();
        let mut unique = names.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), names.len());
    }

    #[test]
    fn a_tripped_fail_safe_refuses_every_later_write() {
        use crate::io::{DiscreteIo, Input, IoConfig, Outputs, PinLevels, SupplyState};
        use plasma_protocol::time::Instant;

        // The I/O task's loop in miniature: the logic decides, the gate writes the "pins".
        let latch = FailSafe::new();
        let mut pins = Outputs::default();
        let idle = PinLevels::ALL_HIGH;
        let torch = PinLevels::ALL_HIGH.with(Input::TorchOn, false);
        let mut io = DiscreteIo::new(IoConfig::default(), Instant::ZERO, idle);
        io.on_supply(Instant::ZERO, SupplyState::HEALTHY);
        let step = |io: &mut DiscreteIo, at_ms: u64, levels: PinLevels, pins: &mut Outputs| {
            let now = Instant::from_millis(at_ms);
            io.on_pins(now, levels);
            io.poll(now);
            let wanted = io.outputs();
            latch.drive_unless_tripped(|| *pins = wanted)
        };
        assert!(step(&mut io, 100, torch, &mut pins));
        assert!(step(&mut io, 200, torch, &mut pins));
        assert!(pins.start, "START follows TORCH_ON before the trip");

        // A task stalled: the watchdog side trips the latch and writes the safe state.
        latch.trip();
        pins = Outputs::default();
        // The I/O logic runs on and still wants START with TORCH_ON; the pins stay safe.
        let mut wanted_start = false;
        for at_ms in (300..2000).step_by(50) {
            let levels = if at_ms % 200 == 0 { idle } else { torch };
            assert!(!step(&mut io, at_ms, levels, &mut pins));
            assert_eq!(pins, Outputs::default(), "at {at_ms} ms");
            wanted_start |= io.outputs().start;
        }
        assert!(
            wanted_start,
            "the logic wanted START again: the latch refused it"
        );
    }

    #[test]
    fn only_the_first_fault_entry_may_log() {
        let entry = FaultEntry::new();
        assert!(entry.first());
        assert!(!entry.first());
        assert!(!entry.first());
    }
}
