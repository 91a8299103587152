//! The board image for the emulated board: QEMU's `b-l475e-iot01a` (STM32L475VG, the same
//! family, flash and RAM as the Nucleo's STM32L476RG). `cargo emu-fw` builds it; `cargo emu`
//! (`pbtool emu`) runs it with a simulated power supply; the end-to-end tests in
//! host-tests/tests/emu_*.rs drive it.
//!
//! The tasks are the Nucleo image's, unchanged (the `plasma-tasks` crate, over the
//! [`board::Emulated`] implementation of its `Board` trait), over the same bridge library and
//! the same pin table. Only this board layer differs, because QEMU models too little for
//! embassy-stm32 (no PWR, FLASH, DMA, timers or watchdog; see docs/board.md):
//!
//! - [`rcc`]: clocks by register (80 MHz, as on the Nucleo);
//! - [`time_driver`]: embassy-time on SysTick;
//! - [`gpio`]: the pins of the one pin table, EXTI inputs and outputs by register;
//! - USART1 (power supply, hardware DE) and USART2 (CNC): the shared register-level driver
//!   (`plasma_tasks::uart`), as on the Nucleo;
//! - [`flash`]: the settings store and the history on RAM models of the flash;
//! - the tasks in the executors and at the priorities of the Nucleo's, one layout
//!   (`plasma_tasks::layout`), so the tests here prove the Nucleo's arrangement;
//! - [`watchdog`]: a software reset where the Nucleo has the IWDG, after the same stall judge;
//! - [`executor`]: the thread executor with sleep accounting, and [`probe`]: the latency
//!   and idle measurements;
//! - [`fault`]: panic and HardFault leave every output off and reset;
//! - [`reset_flags`]: the reset flags the boot report reads, which QEMU's RCC does not keep;
//! - logs: defmt over semihosting (`defmt-semihosting`), for QEMU's
//!   `-semihosting-config enable=on,target=native`.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "plasma-bridge-emu is firmware for QEMU's b-l475e-iot01a: build it with `cargo emu-fw`."
    );
}

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
mod executor;
#[cfg(target_os = "none")]
mod fault;
#[cfg(target_os = "none")]
mod flash;
#[cfg(target_os = "none")]
mod gpio;
#[cfg(target_os = "none")]
mod probe;
#[cfg(target_os = "none")]
mod rcc;
#[cfg(target_os = "none")]
mod reset_flags;
#[cfg(all(target_os = "none", feature = "test-hooks"))]
mod test_hooks;
#[cfg(target_os = "none")]
mod time_driver;
#[cfg(target_os = "none")]
mod watchdog;

#[cfg(target_os = "none")]
mod image {
    use cortex_m::peripheral::NVIC;
    use defmt::{info, warn};
    use defmt_semihosting as _;
    use embassy_executor::Spawner;
    use plasma_firmware::bridge::Bridge;
    use plasma_firmware::io::InputConfig;
    use plasma_firmware::platform::safe_state::BootReport;
    use plasma_tasks::boot::{boot_text, user_button_held};
    use plasma_tasks::clock::now;
    use plasma_tasks::clock_tree::UsartClock;
    use plasma_tasks::history;
    use plasma_tasks::layout::{Tasks, set_serial_priorities};
    use plasma_tasks::reset;
    use plasma_tasks::safe_state::drive_safe_state;
    use plasma_tasks::settings as shared_settings;
    use static_cell::StaticCell;
    use stm32_metapac::{Interrupt, USART1, USART2, interrupt};

    use crate::board::{Emulated, start_tasks};
    use crate::flash::{
        HISTORY_SIZE, HistoryFlash, SETTINGS_SIZE, SettingsFlash, history_flash, settings_flash,
    };
    use crate::gpio::{InputPins, Led, OutputPins};
    use crate::{executor, probe, rcc, reset_flags, time_driver, watchdog};
    use plasma_tasks::uart::{Uart, UartState, on_interrupt};

    static PS_STATE: UartState = UartState::new();
    static CNC_STATE: UartState = UartState::new();

    #[interrupt]
    fn USART1() {
        if on_interrupt(USART1, &PS_STATE) {
            time_driver::keep_receiving();
        }
    }

    #[interrupt]
    fn USART2() {
        if on_interrupt(USART2, &CNC_STATE) {
            time_driver::keep_receiving();
        }
    }

    static BRIDGE: StaticCell<Bridge> = StaticCell::new();

    /// A UART with fixed, valid settings; `None` only for a baud rate BRR cannot make, a
    /// build mistake: panic = safe state.
    fn uart(built: Option<Uart>) -> Uart {
        match built {
            Some(uart) => uart,
            None => defmt::panic!("UART set-up: baud rate out of range"),
        }
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        // Before clocks, before anything that could fail: START and every other output off.
        drive_safe_state();
        // QEMU's RCC_CSR says power-on after every reset: the board's own record instead.
        let boot = reset::boot_report_from(reset_flags::take());
        rcc::init();
        let mut core = cortex_m::Peripherals::take()
            .unwrap_or_else(|| defmt::panic!("core peripherals taken"));
        time_driver::init(core.SYST, &mut core.SCB);

        info!(
            "plasma-bridge {=str} on the emulated STM32L475VG at 80 MHz; reset: {=str}",
            env!("CARGO_PKG_VERSION"),
            boot.cause.as_str()
        );
        if boot.is_fault() {
            warn!(
                "the previous run ended in a fault: {=str}",
                boot.cause.as_str()
            );
        }

        // The kept flash models here, on main's small frame: the first boot erases them
        // (16 KB at most on the stack, while nothing else is on it).
        let flashes = (settings_flash(), history_flash());

        // Serial interrupts below the I/O executor, as on the Nucleo.
        set_serial_priorities();
        executor::run(
            |spawner| spawner.spawn(boot_task(spawner, boot, flashes).unwrap()),
            probe::report,
        )
    }

    #[embassy_executor::task]
    async fn boot_task(spawner: Spawner, boot: BootReport, flashes: (SettingsFlash, HistoryFlash)) {
        let (settings_flash, history_flash) = flashes;
        let mut store = shared_settings::open::<Emulated>(settings_flash, 0..SETTINGS_SIZE as u32);
        let history = history::open::<Emulated>(history_flash, 0..HISTORY_SIZE as u32);
        let loaded = shared_settings::load::<Emulated>(store.as_mut()).await;
        let consumables = shared_settings::load_consumables::<Emulated>(store.as_mut()).await;
        let settings = shared_settings::at_boot(loaded.settings, user_button_held());
        // Pulls per the board's circuit (the pin table), whatever the wiring settings say.
        let input_config = InputConfig::default();

        let inputs = InputPins::new(&input_config);
        let outputs = OutputPins::new();
        let io_config = settings.io;

        // The pin table's UART pins, as wired on the Nucleo; QEMU routes the USARTs to its
        // sockets whatever the pins say.
        plasma_tasks::uart::route_pins();
        let ps_uart = uart(Uart::new(
            USART1,
            &PS_STATE,
            UsartClock::Usart1,
            settings.link.modbus_port(),
            true,
        ));
        let cnc_uart = uart(Uart::new(
            USART2,
            &CNC_STATE,
            UsartClock::Usart2,
            // The saved CNC framing (115200 8N1 unless saved otherwise); CONFIG
            // cnc_baud/cnc_parity/cnc_stop_bits switch it while the board runs.
            settings.cnc_port_config(),
            false,
        ));
        // SAFETY: the handlers touch only their own UartState.
        unsafe {
            NVIC::unmask(Interrupt::USART1);
            NVIC::unmask(Interrupt::USART2);
        }

        let bridge = BRIDGE.init_with(|| Bridge::new(settings, now()));
        bridge.set_boot_report(now(), boot_text(&boot, loaded.outcome));
        if let Some(set) = consumables {
            bridge.restore_consumables(set);
        }
        bridge.record_reset(now(), boot.cause);
        start_tasks(
            spawner,
            Tasks {
                inputs,
                outputs,
                io_config,
                bridge,
                ps: ps_uart,
                cnc: probe::ProbedCnc(cnc_uart),
                store,
                history,
                led: Led::new(),
                watchdog: watchdog::SoftWatchdog,
            },
        );
        #[cfg(feature = "test-hooks")]
        spawner.spawn(crate::test_hooks::fail_on_request().unwrap());
    }
}
