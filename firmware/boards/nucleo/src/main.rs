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
//! - the I/O task on an interrupt executor above all serial work ([`io_executor`]): input
//!   edges (EXTI, lines armed for good: `plasma_tasks::edges`) to outputs, on the pins of the one pin table ([`pins`]);
//! - the bridge task in thread mode: the power-supply link on USART1 with hardware
//!   driver-enable ([`ps_uart`]), the CNC session on USART2 ([`cnc_uart`]);
//! - the settings task that stores `CONFIG SAVE` in flash ([`flash`]);
//! - [`watchdog`]: the IWDG, started before anything that could hang, then fed only while
//!   every task reports progress; the heartbeat LED;
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
mod io_executor;
#[cfg(target_os = "none")]
mod pins;
#[cfg(target_os = "none")]
mod ps_uart;
#[cfg(target_os = "none")]
mod watchdog;

#[cfg(target_os = "none")]
mod image {
    use defmt::{info, warn};
    use defmt_rtt as _;
    use embassy_executor::Spawner;
    use embassy_stm32::interrupt::{self, InterruptExt};
    use embassy_stm32::usart::{self, BufferedUart};
    use embassy_stm32::{bind_interrupts, peripherals};
    use plasma_firmware::bridge::Bridge;
    use plasma_firmware::inputs::InputConfig;
    use plasma_firmware::link::transaction::TX_CAPACITY;
    use plasma_firmware::pins::{CNC_UART, PS_UART, Port};
    use plasma_protocol::time::Duration;
    use plasma_tasks::boot::boot_text;
    use plasma_tasks::clock::now;
    use plasma_tasks::io::BoardIo;
    use plasma_tasks::progress::register;
    use plasma_tasks::reset;
    use plasma_tasks::safe_state::drive_safe_state;
    use plasma_tasks::settings as shared_settings;
    use static_cell::StaticCell;

    use crate::board::{Nucleo, bridge_task, heartbeat_task, io_task, settings_task};
    use crate::cnc_uart::CncUart;
    use crate::io_executor::{SERIAL_PRIORITY, start_io_executor};
    use crate::pins::{InputPins, OutputPins};
    use crate::ps_uart::{PsUart, uart_config};
    use crate::{cnc_uart, flash, watchdog};

    bind_interrupts!(struct Irqs {
        FLASH => embassy_stm32::flash::InterruptHandler;
        USART1 => usart::BufferedInterruptHandler<peripherals::USART1>;
        USART2 => usart::BufferedInterruptHandler<peripherals::USART2>;
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
    static BRIDGE: StaticCell<Bridge> = StaticCell::new();

    // The UARTs' pins are typed (each USART accepts only its own), so main takes them by
    // name; this ties the names to the pin table, which places everything else.
    const _: () = assert!(
        PS_UART.tx.is(Port::A, 9)
            && PS_UART.rx.is(Port::A, 10)
            && matches!(PS_UART.de, Some(de) if de.is(Port::A, 12))
            && CNC_UART.tx.is(Port::A, 2)
            && CNC_UART.rx.is(Port::A, 3)
            && CNC_UART.de.is_none(),
        "the UART pins in main.rs differ from plasma_firmware::pins"
    );

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
        // Before clocks, flash and UARTs, any of which could hang: a stalled boot resets.
        watchdog::start();

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
        for irq in [interrupt::USART1, interrupt::USART2, interrupt::FLASH] {
            irq.set_priority(SERIAL_PRIORITY);
        }

        let mut store = flash::open(flash::SettingsFlash::new(embassy_stm32::flash::Flash::new(
            p.FLASH, Irqs,
        )));
        let loaded = shared_settings::load::<Nucleo>(store.as_mut()).await;
        let settings = loaded.settings;
        // Polarity and debounce of the inputs are not (yet) part of the stored settings.
        let input_config = InputConfig::default();

        let inputs = InputPins::new(&input_config);
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
        spawner.spawn(settings_task(store, register("settings", Duration::from_secs(1))).unwrap());

        let led = crate::pins::led();
        spawner.spawn(heartbeat_task(led, register("heartbeat", Duration::from_secs(1))).unwrap());
        spawner.spawn(watchdog::watchdog().unwrap());
    }
}
