//! The CNC UART: USART2, the ST-LINK's virtual COM port, at the CNC framing of the settings
//! (115200 8N1 by default), through the shared driver (`plasma_tasks::uart`). Lines in and out are logged (debug), so a defmt log shows
//! the commands next to what they caused.

use defmt::debug;
use embedded_io_async::{ErrorType, Read, ReadReady, Write};
use plasma_firmware::platform::runner::{ConfigurablePort, UnsupportedConfig};
use plasma_protocol::serial::PortConfig;
use plasma_tasks::uart::{Uart, UartError};

/// USART2 with logging.
pub struct CncUart(pub Uart);

impl ErrorType for CncUart {
    type Error = UartError;
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

impl ConfigurablePort for CncUart {
    fn set_port_config(&mut self, config: PortConfig) -> Result<(), UnsupportedConfig> {
        self.0.set_port_config(config)
    }
}
