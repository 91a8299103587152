//! The board image for the Nucleo-L476RG (pin map, wiring and the task design: docs/board.md).
//!
//! Built for the MCU with `cargo fw`, flashed with `cargo flash`. On the host this file only
//! prints how to build it, so that `cargo build` / `cargo test` of the workspace work.
//!
//! The image only builds peripherals and spawns tasks. The tasks are shared with the emulated
//! board (`../tasks`, included as [`tasks`]); what they do is the library's. This file and
//! its modules are the board layer ([`board`] lists what the tasks take from it):
//!
//! - boot: outputs to safe state before anything else, reset cause, clocks (80 MHz),
//!   settings from flash ([`flash`]), the reset cause and the settings outcome handed to the
//!   bridge for the CNC port (`!BOOT`, `ID`);
//! - the I/O task on an interrupt executor above all serial work ([`io_executor`]): input
//!   edges (EXTI, [`pins`]) to outputs;
//! - the bridge task in thread mode: the power-supply link on USART1 with hardware
//!   driver-enable ([`ps_uart`]), the CNC session on USART2 ([`cnc_uart`]);
//! - the settings task that stores `CONFIG SAVE` in flash ([`flash`]);
//! - [`watchdog`]: the IWDG fed only while every task reports progress; the heartbeat LED;
//! - [`fault`]: panic, HardFault and NMI leave every output off and reset.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("plasma-bridge is firmware for the STM32L476RG: build it with `cargo fw`.");
}

#[cfg(target_os = "none")]
mod cnc_uart;
#[cfg(target_os = "none")]
mod fault;
#[cfg(target_os = "none")]
mod flash;
#[cfg(target_os = "none")]
mod io_executor;
#[cfg(target_os = "none")]
mod pins;
#[cfg(target_os = "none")]
mod ps_uart;
#[cfg(target_os = "none")]
#[path = "../tasks/mod.rs"]
mod tasks;
#[cfg(target_os = "none")]
mod watchdog;

/// What the shared tasks take from this board (see `../tasks/mod.rs`).
#[cfg(target_os = "none")]
mod board {
    pub use crate::cnc_uart::{CncUart, TX_BUFFER as CNC_TX_BUFFER};
    pub use crate::flash::{SettingsFlash, flash_errors_seen};
    pub use crate::pins::{InputPins, OutputPins};
    pub use crate::ps_uart::PsUart;
    pub use embassy_stm32::pac;

    /// The heartbeat LED (LD2, PA5).
    pub type Led = embassy_stm32::gpio::Output<'static>;
}

#[cfg(target_os = "none")]
mod image {
    use core::fmt::Write;

    use defmt::{info, warn};
    use defmt_rtt as _;
    use embassy_executor::Spawner;
    use embassy_stm32::exti::{self, ExtiInput};
    use embassy_stm32::gpio::{Level, Output, Speed};
    use embassy_stm32::interrupt::{self, InterruptExt};
    use embassy_stm32::usart::{self, BufferedUart};
    use embassy_stm32::{bind_interrupts, peripherals};
    use heapless::String;
    use plasma_firmware::bridge::Bridge;
    use plasma_firmware::inputs::InputConfig;
    use plasma_firmware::io::Input;
    use plasma_firmware::link::transaction::TX_CAPACITY;
    use plasma_firmware::safe_state::BootReport;
    use plasma_firmware::storage::LoadOutcome;
    use plasma_protocol::time::Duration;
    use static_cell::StaticCell;

    use crate::cnc_uart::CncUart;
    use crate::io_executor::{SERIAL_PRIORITY, start_io_executor};
    use crate::pins::{InputPins, OutputPins, pull};
    use crate::ps_uart::{PsUart, uart_config};
    use crate::tasks::bridge::bridge as bridge_task;
    use crate::tasks::clock::now;
    use crate::tasks::io::{BoardIo, io_task};
    use crate::tasks::pin_map::drive_safe_state;
    use crate::tasks::progress::{heartbeat, register};
    use crate::tasks::reset;
    use crate::tasks::settings::{self as settings_task, outcome_word};
    use crate::{cnc_uart, flash, watchdog};

    bind_interrupts!(struct Irqs {
        FLASH => embassy_stm32::flash::InterruptHandler;
        USART1 => usart::BufferedInterruptHandler<peripherals::USART1>;
        USART2 => usart::BufferedInterruptHandler<peripherals::USART2>;
        EXTI0 => exti::InterruptHandler<interrupt::typelevel::EXTI0>;
        EXTI1 => exti::InterruptHandler<interrupt::typelevel::EXTI1>;
        EXTI4 => exti::InterruptHandler<interrupt::typelevel::EXTI4>;
        EXTI9_5 => exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
        EXTI15_10 => exti::InterruptHandler<interrupt::typelevel::EXTI15_10>;
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
        config
    }

    /// PS UART buffers: transmit holds the longest frame (see `PsUart`).
    static PS_TX: StaticCell<[u8; TX_CAPACITY]> = StaticCell::new();
    static PS_RX: StaticCell<[u8; 256]> = StaticCell::new();
    static CNC_TX: StaticCell<[u8; cnc_uart::TX_BUFFER]> = StaticCell::new();
    static CNC_RX: StaticCell<[u8; cnc_uart::RX_BUFFER]> = StaticCell::new();
    static BOOT_TEXT: StaticCell<String<64>> = StaticCell::new();
    static BRIDGE: StaticCell<Bridge> = StaticCell::new();

    /// `<reset cause>,settings:<outcome>` for the CNC port (`ID ... reset=...`,
    /// `!BOOT reason=...`).
    fn boot_text(boot: &BootReport, outcome: LoadOutcome) -> &'static str {
        let text = BOOT_TEXT.init(String::new());
        // 64 bytes hold the longest cause and outcome; a cut text is still a report.
        let _ = write!(
            text,
            "{},settings:{}",
            boot.cause.as_str(),
            outcome_word(outcome)
        );
        text.as_str()
    }

    /// The UART, or a panic: the settings are fixed ones the USARTs support at 80 MHz, so an
    /// error is a build mistake (panic = safe state). One UART at a time: a pair of results
    /// would bring the drop code of a `BufferedUart` into the image for the other one.
    fn uart<U>(built: Result<U, usart::ConfigError>) -> U {
        match built {
            Ok(uart) => uart,
            Err(e) => defmt::panic!("UART set-up: {}", e),
        }
    }

    #[embassy_executor::main]
    async fn main(spawner: Spawner) {
        // Before clocks, before anything that could fail: START and every other output off.
        drive_safe_state();
        let boot = reset::boot_report();

        let p = embassy_stm32::init(clock_config());
        // The HAL takes the pins over at the level they already have.
        let outputs = OutputPins {
            start: Output::new(p.PB0, Level::Low, Speed::Low),
            hold: Output::new(p.PC1, Level::Low, Speed::Low),
            pierce_complete: Output::new(p.PC0, Level::Low, Speed::Low),
            corner_current: Output::new(p.PB8, Level::Low, Speed::Low),
            arc_ok: Output::new(p.PB9, Level::Low, Speed::Low),
            ready: Output::new(p.PB6, Level::Low, Speed::Low),
            fault: Output::new(p.PC7, Level::Low, Speed::Low),
        };

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
        for irq in [interrupt::USART1, interrupt::USART2, interrupt::FLASH] {
            irq.set_priority(SERIAL_PRIORITY);
        }

        let mut store = flash::open(embassy_stm32::flash::Flash::new(p.FLASH, Irqs));
        let loaded = settings_task::load(store.as_mut()).await;
        let settings = loaded.settings;
        // Polarity and debounce of the inputs are not (yet) part of the stored settings.
        let input_config = InputConfig::default();

        // Inputs in Input::ALL order, each with the pull that reads inactive when open.
        let c = &input_config;
        let inputs = InputPins([
            ExtiInput::new(p.PA0, p.EXTI0, pull(c, Input::TorchOn), Irqs),
            ExtiInput::new(p.PA4, p.EXTI4, pull(c, Input::Hold), Irqs),
            ExtiInput::new(p.PA6, p.EXTI6, pull(c, Input::PierceComplete), Irqs),
            ExtiInput::new(p.PA7, p.EXTI7, pull(c, Input::CornerCurrent), Irqs),
            ExtiInput::new(p.PA1, p.EXTI1, pull(c, Input::Motion), Irqs),
            ExtiInput::new(p.PA8, p.EXTI8, pull(c, Input::NotReady), Irqs),
            ExtiInput::new(p.PB10, p.EXTI10, pull(c, Input::RampdownError), Irqs),
        ]);
        let io_progress = register("io", Duration::from_millis(200));
        start_io_executor()
            .spawn(io_task(inputs, outputs, (settings.io, input_config), io_progress).unwrap());

        let ps_uart = uart(BufferedUart::new_with_de(
            p.USART1,
            p.PA10,
            p.PA9,
            p.PA12,
            Irqs,
            PS_TX.init([0; TX_CAPACITY]),
            PS_RX.init([0; 256]),
            uart_config(settings.link.modbus_port()),
        ));
        let cnc_uart = uart(BufferedUart::new(
            p.USART2,
            p.PA3,
            p.PA2,
            CNC_TX.init([0; cnc_uart::TX_BUFFER]),
            CNC_RX.init([0; cnc_uart::RX_BUFFER]),
            Irqs,
            cnc_uart::uart_config(),
        ));

        let bridge = BRIDGE.init_with(|| Bridge::new(settings, now()));
        bridge.set_boot_report(now(), boot_text(&boot, loaded.outcome));
        spawner.spawn(
            bridge_task(
                bridge,
                PsUart(ps_uart),
                CncUart(cnc_uart),
                BoardIo {
                    inputs: input_config,
                },
                register("bridge", Duration::from_millis(500)),
            )
            .unwrap(),
        );
        spawner.spawn(
            settings_task::settings(store, register("settings", Duration::from_secs(1))).unwrap(),
        );

        let led = Output::new(p.PA5, Level::Low, Speed::Low);
        spawner.spawn(heartbeat(led, register("heartbeat", Duration::from_secs(1))).unwrap());
        spawner.spawn(watchdog::watchdog(p.IWDG).unwrap());
    }
}
