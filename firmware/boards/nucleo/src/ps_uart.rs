//! The power-supply UART: USART1 with hardware driver-enable for the RS-485/422 transceiver.

use embassy_stm32::usart::{self, BufferedUart};
use embedded_io_async::{ErrorType, Read, ReadReady, Write};
use plasma_firmware::runner::{ConfigurablePort, UnsupportedConfig};
use plasma_protocol::serial::{self, PortConfig};

/// DE raised this long before the start bit and held this long after the stop bit, in 1/16
/// bit (8 = half a bit, 26 us at 19200: far more than a transceiver's enable time).
/// embassy-stm32 0.6.0 writes DEDT from the assertion field, so both must be equal
/// (shared/EMULATION.md).
const DE_TIME: u8 = 8;

/// The HAL's settings for `config` (8 data bits always; the parity bit comes on top).
pub fn uart_config(config: PortConfig) -> usart::Config {
    let mut uart = usart::Config::default();
    uart.baudrate = config.baud;
    uart.data_bits = usart::DataBits::DataBits8;
    uart.parity = match config.parity {
        serial::Parity::None => usart::Parity::ParityNone,
        serial::Parity::Even => usart::Parity::ParityEven,
        serial::Parity::Odd => usart::Parity::ParityOdd,
    };
    uart.stop_bits = match config.stop_bits {
        serial::StopBits::One => usart::StopBits::STOP1,
        serial::StopBits::Two => usart::StopBits::STOP2,
    };
    uart.de_assertion_time = DE_TIME;
    uart.de_deassertion_time = DE_TIME;
    // An idle receive line must read as mark when the transceiver's receiver is off (2-wire,
    // while DE is high).
    uart.rx_pull = embassy_stm32::gpio::Pull::Up;
    uart
}

/// USART1 as the runner's port. Its transmit buffer holds the longest frame the link builds,
/// so a frame is always written into an empty buffer in one piece (embassy-stm32 0.6's
/// BufferedUart refuses a write larger than its buffer).
pub struct PsUart(pub BufferedUart<'static>);

impl ErrorType for PsUart {
    type Error = usart::Error;
}

impl Read for PsUart {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        self.0.read(buf).await
    }
}

impl ReadReady for PsUart {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        self.0.read_ready()
    }
}

impl Write for PsUart {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.0.write(buf).await
    }

    async fn flush(&mut self) -> Result<(), Self::Error> {
        self.0.flush().await
    }
}

impl ConfigurablePort for PsUart {
    fn set_port_config(&mut self, config: PortConfig) -> Result<(), UnsupportedConfig> {
        self.0
            .set_config(&uart_config(config))
            .map_err(|_| UnsupportedConfig)
    }
}
