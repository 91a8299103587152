//! The board image for the Nucleo-L476RG (pin map, wiring and the task design: docs/board.md).
//!
//! Built for the MCU with `cargo fw`, flashed with `cargo flash`. On the host this file only
//! prints how to build it, so that `cargo build` / `cargo test` of the workspace work.
//!
//! The image only builds peripherals and spawns tasks. The tasks are shared with the emulated
//! board (the `plasma-tasks` crate, over the [`board::Nucleo`] implementation of its `Board`
//! trait); what they do is the library's. This crate is the board layer:
//!
//! - boot: outputs to safe state before anything else, reset cause, clocks (80 MHz),
//!   settings from flash ([`flash`]), the reset cause and the settings outcome handed to the
//!   bridge for the CNC port (`!BOOT`, `ID`);
//! - the tasks in the executors and at the priorities of the one layout both boards use
//!   (`plasma_tasks::layout`): the I/O task on an interrupt executor above all serial work,
//!   input edges (EXTI, lines armed for good: `plasma_tasks::edges`) to outputs, on the pins of
//!   the one pin table ([`pins`]); the bridge task in thread mode: the power-supply link on
//!   USART1 with hardware driver-enable, the CNC session on USART2 ([`cnc_uart`]), both through
//!   the shared register-level driver (`plasma_tasks::uart`); the settings task that stores
//!   `CONFIG SAVE` in flash and the history task that keeps the event history there
//!   ([`flash`]); the heartbeat LED; the stall judge on its own
//!   executor above every task;
//! - [`watchdog`]: the IWDG, started before anything that could hang, then fed by the stall
//!   judge only while every task reports progress;
//! - [`fault`]: panic, HardFault and NMI leave every output off and reset.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plasma-bridge is firmware for the STM32L476RG: build it with `cargo fw`.");
}

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
mod cnc_uart;
#[cfg(target_os = "none")]
mod fault;
#[cfg(target_os = "none")]
mod flash;
#[cfg(target_os = "none")]
mod pins;
#[cfg(target_os = "none")]
mod watchdog;

#[cfg(target_os = "none")]
mod image {
    use defmt::{info, warn};
    use defmt_rtt as _;
    use embassy_executor::Spawner;
    use embassy_stm32::interrupt;
    use embassy_stm32::interrupt::InterruptExt;
    use embassy_stm32::{bind_interrupts, pac};
    use plasma_firmware::bridge::Bridge;
    use plasma_firmware::io::InputConfig;
    use plasma_tasks::boot::{boot_text, user_button_held};
    use plasma_tasks::clock::now;
    use plasma_tasks::clock_tree::UsartClock;
    use plasma_tasks::reset;
    use plasma_tasks::safe_state::drive_safe_state;
    use plasma_tasks::settings as shared_settings;
    use static_cell::StaticCell;

    use plasma_tasks::layout::{Tasks, set_serial_priorities};

    use crate::board::{Nucleo, start_tasks};
    use crate::cnc_uart::CncUart;
    use crate::pins::{InputPins, OutputPins};
    use plasma_tasks::uart::{Uart, UartState, on_interrupt, route_pins};

    use crate::{flash, watchdog};

    bind_interrupts!(struct Irqs {
        FLASH => embassy_stm32::flash::InterruptHandler;
    });

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
        // The CNC port's USART on HSI16: 80 MHz cannot make 1200 baud (BRR tops out at
        // 0xFFFF, 80 MHz / 1200 = 66 667), 16 MHz makes 1200 to 115200 (BRR 13 333 to 138).
        config.rcc.mux.usart2sel = embassy_stm32::pac::rcc::vals::Usartsel::HSI;
        // No RTC: embassy's default clocks an RTC the bridge never reads from the LSI (the
        // IWDG keeps the LSI running by itself once started). DBG_SLEEP stays on (embassy's
        // default): probe-rs reads the RTT buffer while the core sleeps in WFE, and it only
        // costs power; the bridge never enters Stop or Standby (docs/board.md).
        config.rcc.ls = embassy_stm32::rcc::LsConfig::off();
        config
    }

    /// The CNC USART's kernel clock [`clock_config`] means to set: HSI16 (RCC_CCIPR
    /// USART2SEL; the PS USART stays on PCLK2 = SYSCLK). The UARTs program BRR from the clock
    /// the RCC actually runs (`plasma_tasks::clock_tree`); this only checks at build time that
    /// the intended one runs every baud rate `CONFIG cnc_baud` accepts.
    const INTENDED_CNC_USART_CLOCK_HZ: u32 = 16_000_000;
    const _: () = assert!(plasma_tasks::uart::runs_every_baud(
        INTENDED_CNC_USART_CLOCK_HZ,
        &plasma_firmware::settings::CNC_BAUDS
    ));

    static PS_STATE: UartState = UartState::new();
    static CNC_STATE: UartState = UartState::new();

    // The UARTs by register (`plasma_tasks::uart`: flagged bytes reach the link, flush waits
    // for the last stop bit); their vectors are these, not embassy-stm32's.
    #[interrupt]
    unsafe fn USART1() {
        on_interrupt(pac::USART1, &PS_STATE);
    }

    #[interrupt]
    unsafe fn USART2() {
        on_interrupt(pac::USART2, &CNC_STATE);
    }

    static BRIDGE: StaticCell<Bridge> = StaticCell::new();

    /// A UART with fixed, valid settings; `None` only for a clock the RCC runs that cannot
    /// make the baud rate, a build mistake: panic = safe state.
    fn uart(built: Option<Uart>) -> Uart {
        match built {
            Some(uart) => uart,
            None => defmt::panic!("UART set-up: baud rate out of range"),
        }
    }

    #[embassy_executor::main]
    async fn main(spawner: Spawner) {
        // Before clocks, before anything that could fail: START and every other output off.
        drive_safe_state();
        let boot = reset::boot_report();
        // Before clocks, flash and UARTs, any of which could hang: a stalled boot resets.
        let iwdg = watchdog::start();

        let p = embassy_stm32::init(clock_config());
        // The HAL takes the pins over at the level they already have.
        let outputs = OutputPins::new();

        info!(
            "plasma-bridge {=str} on STM32L476RG at 80 MHz; reset: {=str} (RCC_CSR flags {=u8:#04x})",
            env!("CARGO_PKG_VERSION"),
            boot.cause.as_str(),
            boot.flags.bits()
        );
        if boot.is_fault() {
            warn!(
                "the previous run ended in a fault: {=str}",
                boot.cause.as_str()
            );
        }

        // Serial and flash interrupts below the I/O executor (docs/board.md, START latency).
        set_serial_priorities();

        let (mut store, history) = flash::open(embassy_stm32::flash::Flash::new(p.FLASH, Irqs));
        let loaded = shared_settings::load::<Nucleo>(store.as_mut()).await;
        let consumables = shared_settings::load_consumables::<Nucleo>(store.as_mut()).await;
        let settings = shared_settings::at_boot(loaded.settings, user_button_held());
        // The pulls belong to the board's input circuit (the pin table's polarity), not to
        // the level the CNC's wiring settings call active (docs/board.md, the CNC's wiring).
        let input_config = InputConfig::default();

        let inputs = InputPins::new(&input_config);
        let io_config = settings.io;

        pac::RCC.apb2enr().modify(|w| w.set_usart1en(true));
        pac::RCC.apb1enr1().modify(|w| w.set_usart2en(true));
        route_pins();
        let ps_uart = uart(Uart::new(
            pac::USART1,
            &PS_STATE,
            UsartClock::Usart1,
            settings.link.modbus_port(),
            true,
        ));
        let cnc_uart = uart(Uart::new(
            pac::USART2,
            &CNC_STATE,
            UsartClock::Usart2,
            // The saved CNC framing (115200 8N1 unless saved otherwise); CONFIG
            // cnc_baud/cnc_parity/cnc_stop_bits switch it while the board runs.
            settings.cnc_port_config(),
            false,
        ));
        for irq in [interrupt::USART1, interrupt::USART2] {
            // SAFETY: the handlers above touch only their own UartState.
            unsafe { irq.enable() };
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
                cnc: CncUart(cnc_uart),
                store,
                history,
                led: crate::pins::led(),
                watchdog: iwdg,
            },
        );
    }
}
