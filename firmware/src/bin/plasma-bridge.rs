//! The board image for the Nucleo-L476RG (pin map and wiring: docs/board.md).
//!
//! Built for the MCU with `cargo fw`, flashed with `cargo flash`. On the host this file only
//! prints how to build it, so that `cargo build` / `cargo test` of the workspace work.
//!
//! What it does today: outputs to safe state before anything else, reset cause, clocks
//! (HSI16 -> PLL -> 80 MHz), the settings record from flash, the LD2 heartbeat, and the
//! independent watchdog fed only while every monitored task makes progress. A panic or hard
//! fault drives the outputs to safe state, logs over defmt/RTT and resets.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plasma-bridge is firmware for the STM32L476RG: build it with `cargo fw`.");
}

#[cfg(target_os = "none")]
mod image {
    use core::cell::RefCell;
    use core::mem::MaybeUninit;
    use core::sync::atomic::{AtomicU32, Ordering};

    use cortex_m_rt::{ExceptionFrame, exception};
    use defmt::{error, info, warn};
    use defmt_rtt as _;
    use embassy_executor::Spawner;
    use embassy_stm32::gpio::{Level, Output, Speed};
    use embassy_stm32::pac;
    use embassy_stm32::pac::gpio::{Gpio, vals::Moder};
    use embassy_stm32::wdg::IndependentWatchdog;
    use embassy_stm32::{Peri, bind_interrupts, flash, peripherals};
    use embassy_sync::blocking_mutex::Mutex;
    use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
    use embassy_time::Timer;
    use plasma_firmware::safe_state::{BootReport, Output as Signal, PANIC_MARKER, SAFE_OUTPUTS};
    use plasma_firmware::storage::SettingsStore;
    use plasma_firmware::time::{Duration, Instant};
    use plasma_firmware::watchdog::{ProgressMonitor, TaskId};

    bind_interrupts!(struct Irqs {
        FLASH => flash::InterruptHandler;
    });

    /// Where each output is (docs/board.md). All are active high at the MCU pin, with an
    /// external pull-down so they are off while the pin is still high-impedance after reset.
    const fn output_pin(signal: Signal) -> (Gpio, usize) {
        match signal {
            Signal::Start => (pac::GPIOB, 0),
            Signal::PsHold => (pac::GPIOC, 1),
            Signal::PsPierceComplete => (pac::GPIOC, 0),
            Signal::PsCornerCurrent => (pac::GPIOB, 8),
            Signal::CncArcOk => (pac::GPIOB, 9),
            Signal::CncReady => (pac::GPIOB, 6),
            Signal::CncFault => (pac::GPIOC, 7),
        }
    }

    /// Drives every output to its safe level with plain register writes: usable before the
    /// HAL exists, and from the panic and fault handlers while tasks own the pins.
    fn drive_safe_state() {
        pac::RCC.ahb2enr().modify(|w| {
            w.set_gpioben(true);
            w.set_gpiocen(true);
        });
        for (signal, on) in SAFE_OUTPUTS.levels() {
            let (port, pin) = output_pin(signal);
            // Level first, then output mode: the pin never drives the wrong level.
            port.bsrr().write(|w| {
                if on {
                    w.set_bs(pin, true)
                } else {
                    w.set_br(pin, true)
                }
            });
            port.moder().modify(|w| w.set_moder(pin, Moder::OUTPUT));
        }
    }

    /// A word the reset does not clear (cortex-m-rt's `.uninit`), for the panic marker.
    #[unsafe(link_section = ".uninit.PANIC_MARKER")]
    static mut PANIC_MARKER_WORD: MaybeUninit<u32> = MaybeUninit::uninit();

    fn marker_word() -> *mut u32 {
        (&raw mut PANIC_MARKER_WORD).cast()
    }

    /// Reads and clears the panic marker. The word may hold power-up garbage: BootReport
    /// only believes it together with the software-reset flag.
    fn take_panic_marker() -> u32 {
        // SAFETY: a word-aligned static only this module touches, in a single-threaded
        // context (before the executor starts); volatile because the compiler cannot know
        // the previous run wrote it.
        unsafe {
            let value = marker_word().read_volatile();
            marker_word().write_volatile(0);
            value
        }
    }

    /// Safe state, marker, log, reset.
    fn fail(reason: impl FnOnce()) -> ! {
        cortex_m::interrupt::disable();
        drive_safe_state();
        // SAFETY: as in take_panic_marker; interrupts are off.
        unsafe { marker_word().write_volatile(PANIC_MARKER) };
        reason();
        // Give a probe ~50 ms to drain the RTT buffer; the outputs are already safe.
        cortex_m::asm::delay(4_000_000);
        cortex_m::peripheral::SCB::sys_reset()
    }

    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        fail(|| error!("panic: {}", defmt::Display2Format(info)))
    }

    #[exception]
    unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
        let pc = frame.pc();
        fail(|| error!("hard fault at pc {=u32:#010x}", pc))
    }

    /// Double ECC errors seen in the settings region (a program cut by a power loss can leave
    /// one), for the log.
    static SETTINGS_ECC_ERRORS: AtomicU32 = AtomicU32::new(0);

    /// The L4 raises an NMI when a flash read hits a double ECC error. In the settings region
    /// that is the trace of a torn write: clear it and return; the load completes with bad
    /// data, which the store's CRCs reject. Anywhere else the program itself is damaged.
    ///
    /// An NMI can interrupt a critical section, so this handler touches only an atomic and
    /// the FLASH registers; the failure path ignores that rule because it resets.
    #[exception]
    unsafe fn NonMaskableInt() {
        let eccr = pac::FLASH.eccr().read();
        if eccr.eccd() {
            let bank_base = if eccr.bk_ecc() {
                FLASH_BANK2
            } else {
                FLASH_BASE
            };
            let address = bank_base + eccr.addr_ecc();
            // ECCD is write-1-to-clear.
            pac::FLASH.eccr().modify(|w| w.set_eccd(true));
            let settings = settings_region();
            if (settings.start + FLASH_BASE..settings.end + FLASH_BASE).contains(&address) {
                SETTINGS_ECC_ERRORS.fetch_add(1, Ordering::Relaxed);
                return;
            }
            fail(|| error!("double ECC error in flash at {=u32:#010x}", address))
        }
        fail(|| error!("NMI"))
    }

    /// HSI16 / 2 = 8 MHz PLL input (4..16 MHz allowed), x 20 = 160 MHz VCO (64..344 MHz),
    /// / 2 = 80 MHz SYSCLK, the L476's maximum; embassy sets 4 flash wait states for it.
    fn clock_config() -> embassy_stm32::Config {
        use embassy_stm32::rcc::{Pll, PllMul, PllPreDiv, PllRDiv, PllSource, Sysclk};
        let mut config = embassy_stm32::Config::default();
        config.rcc.hsi = true;
        config.rcc.msi = None;
        config.rcc.pll = Some(Pll {
            source: PllSource::HSI,
            prediv: PllPreDiv::DIV2,
            mul: PllMul::MUL20,
            divp: None,
            divq: None,
            divr: Some(PllRDiv::DIV2),
        });
        config.rcc.sys = Sysclk::PLL1_R;
        config
    }

    const FLASH_BASE: u32 = 0x0800_0000;
    const FLASH_BANK2: u32 = 0x0808_0000;

    /// The settings region from memory.x, as offsets from the start of flash.
    fn settings_region() -> core::ops::Range<u32> {
        unsafe extern "C" {
            static __settings_start: u8;
            static __settings_end: u8;
        }
        // Only the addresses of these linker symbols are used, never their contents.
        let start = (&raw const __settings_start) as u32;
        let end = (&raw const __settings_end) as u32;
        start - FLASH_BASE..end - FLASH_BASE
    }

    fn now() -> Instant {
        Instant::from_micros(embassy_time::Instant::now().as_micros())
    }

    static MONITOR: Mutex<CriticalSectionRawMutex, RefCell<ProgressMonitor<4>>> =
        Mutex::new(RefCell::new(ProgressMonitor::new()));

    fn register(name: &'static str, deadline: Duration) -> TaskId {
        MONITOR.lock(|m| m.borrow_mut().register(name, deadline, now()).unwrap())
    }

    fn report(task: TaskId) {
        MONITOR.lock(|m| m.borrow_mut().report(task, now()));
    }

    /// How long the IWDG runs without a feed before it resets the MCU.
    const IWDG_TIMEOUT_US: u32 = 1_000_000;
    const FEED_PERIOD_MS: u64 = 100;

    #[embassy_executor::task]
    async fn watchdog(iwdg: Peri<'static, peripherals::IWDG>) {
        // Halting the core in a debugger must not reset it.
        pac::DBGMCU.apb1fzr1().modify(|w| w.set_iwdg(true));
        let mut dog = IndependentWatchdog::new(iwdg, IWDG_TIMEOUT_US);
        dog.unleash();
        loop {
            let feed = MONITOR.lock(|m| m.borrow_mut().should_feed(now()));
            if feed {
                dog.pet();
            } else {
                // Stop feeding for good; the outputs go safe now rather than when the IWDG
                // fires up to a second later.
                drive_safe_state();
                if let Some(stall) = MONITOR.lock(|m| m.borrow().stalled()) {
                    error!(
                        "task '{}' silent for {} ms (limit {} ms): watchdog reset follows",
                        stall.name,
                        stall.silent_for.as_millis(),
                        stall.deadline.as_millis()
                    );
                }
                loop {
                    Timer::after_secs(1).await;
                }
            }
            Timer::after_millis(FEED_PERIOD_MS).await;
        }
    }

    #[embassy_executor::task]
    async fn heartbeat(mut led: Output<'static>, progress: TaskId) {
        loop {
            led.toggle();
            report(progress);
            Timer::after_millis(500).await;
        }
    }

    #[embassy_executor::main]
    async fn main(spawner: Spawner) {
        // Before clocks, before anything that could fail: START and every other output off.
        drive_safe_state();
        let csr = pac::RCC.csr().read().0;
        let boot = BootReport::read(csr, take_panic_marker());
        pac::RCC.csr().modify(|w| w.set_rmvf(true));

        let p = embassy_stm32::init(clock_config());
        // The HAL takes the pins over at the level they already have.
        let _outputs = [
            Output::new(p.PB0, Level::Low, Speed::Low),
            Output::new(p.PC1, Level::Low, Speed::Low),
            Output::new(p.PC0, Level::Low, Speed::Low),
            Output::new(p.PB8, Level::Low, Speed::Low),
            Output::new(p.PB9, Level::Low, Speed::Low),
            Output::new(p.PB6, Level::Low, Speed::Low),
            Output::new(p.PC7, Level::Low, Speed::Low),
        ];

        info!(
            "plasma-bridge {} on STM32L476RG at 80 MHz; reset: {} (RCC_CSR flags {=u8:#04x})",
            env!("CARGO_PKG_VERSION"),
            boot.cause.as_str(),
            boot.flags.bits()
        );
        if boot.is_fault() {
            warn!("the previous run ended in a fault: {}", boot.cause.as_str());
        }

        let flash = flash::Flash::new(p.FLASH, Irqs);
        match SettingsStore::new(flash, settings_region()) {
            Ok(mut store) => match store.load().await {
                Ok(Some(record)) => info!(
                    "settings: version {}, save #{}, {} bytes",
                    record.version,
                    record.sequence,
                    record.payload.len()
                ),
                Ok(None) => info!("settings: none stored"),
                Err(e) => warn!("settings: {}", e.as_str()),
            },
            Err(e) => error!("settings region: {}", e.as_str()),
        }
        let ecc_errors = SETTINGS_ECC_ERRORS.load(Ordering::Relaxed);
        if ecc_errors > 0 {
            warn!(
                "settings: {} double ECC error(s) read (torn writes), skipped",
                ecc_errors
            );
        }

        let led = Output::new(p.PA5, Level::Low, Speed::Low);
        spawner.spawn(heartbeat(led, register("heartbeat", Duration::from_secs(1))).unwrap());
        spawner.spawn(watchdog(p.IWDG).unwrap());
    }
}
