//! The CNC UART: USART2, the ST-LINK's virtual COM port, 115200 8N1. Lines in and out are
//! logged (debug), so a defmt log shows the commands next to what they caused.

use defmt::debug;
use embassy_stm32::usart::{self, BufferedUart};
use embedded_io_async::{ErrorType, Read, ReadReady, Write};

/// Transmit buffer size: output is written in pieces of at most this (see
/// `plasma_firmware::supervisor`).
pub const TX_BUFFER: usize = 256;
/// Receive buffer size: a few command lines.
pub const RX_BUFFER: usize = 256;

/// 115200 8N1.
pub fn uart_config() -> usart::Config {
    let mut config = usart::Config::default();
    config.baudrate = 115_200;
    config.rx_pull = embassy_stm32::gpio::Pull::Up;
    config
}

/// USART2 with logging.
pub struct CncUart(pub BufferedUart<'static>);

impl ErrorType for CncUart {
    type Error = usart::Error;
}

impl Read for CncUart {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        let n = self.0.read(buf).await?;
        debug!("CNC > {=[u8]:a}", buf.get(..n).unwrap_or(&[]));
        Ok(n)
    }
}

impl ReadReady for CncUart {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        self.0.read_ready()
    }
}

impl Write for CncUart {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        let n = self.0.write(buf).await?;
        debug!("CNC < {=[u8]:a}", buf.get(..n).unwrap_or(&[]));
        Ok(n)
    }

    async fn flush(&mut self) -> Result<(), Self::Error> {
        self.0.flush().await
    }
}
