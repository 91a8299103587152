//! Just enough of QEMU's machine protocol (QMP) to start a board that QEMU created paused
//! (`-S`): the harness sets the input pins first, so the firmware's very first look at them
//! sees the levels the test chose (a TORCH_ON held at power-up, for one).

use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixStream;
use std::time::Duration;

use serde_json::Value;

use super::error::{Error, Result};

/// A QMP session in command mode.
pub struct Qmp {
    reader: BufReader<UnixStream>,
    writer: UnixStream,
}

impl Qmp {
    /// Reads QEMU's greeting and enters command mode.
    pub fn handshake(stream: UnixStream) -> Result<Qmp> {
        stream
            .set_read_timeout(Some(Duration::from_secs(20)))
            .map_err(|e| Error::io("QMP socket", e))?;
        let writer = stream.try_clone().map_err(|e| Error::io("QMP socket", e))?;
        let mut qmp = Qmp {
            reader: BufReader::new(stream),
            writer,
        };
        let greeting = qmp.read_message()?;
        if greeting.get("QMP").is_none() {
            return Err(Error::Protocol(format!(
                "QMP greeting expected, got {greeting}"
            )));
        }
        qmp.execute("qmp_capabilities")?;
        Ok(qmp)
    }

    /// Runs a command without arguments; returns its `return` value.
    pub fn execute(&mut self, command: &str) -> Result<Value> {
        let request = serde_json::json!({ "execute": command });
        self.writer
            .write_all(format!("{request}\n").as_bytes())
            .map_err(|e| Error::Exited(format!("QMP {command}: {e}")))?;
        loop {
            let message = self.read_message()?;
            if let Some(value) = message.get("return") {
                return Ok(value.clone());
            }
            if let Some(error) = message.get("error") {
                return Err(Error::Protocol(format!("QMP {command}: {error}")));
            }
            // Anything else is an asynchronous event (RESUME, STOP...): not ours to answer.
        }
    }

    /// Starts (or resumes) the guest CPU.
    pub fn cont(&mut self) -> Result<()> {
        self.execute("cont").map(drop)
    }

    fn read_message(&mut self) -> Result<Value> {
        let mut line = String::new();
        let n = self
            .reader
            .read_line(&mut line)
            .map_err(|e| Error::io("reading QMP", e))?;
        if n == 0 {
            return Err(Error::Exited("the QMP socket closed".to_string()));
        }
        serde_json::from_str(&line).map_err(|e| Error::Protocol(format!("QMP sent {line:?}: {e}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_handshake_and_cont_skip_events() {
        let (ours, theirs) = UnixStream::pair().unwrap();
        let fake = std::thread::spawn(move || {
            let mut writer = theirs.try_clone().unwrap();
            let mut lines = BufReader::new(theirs).lines();
            writer
                .write_all(b"{\"QMP\": {\"version\": {}, \"capabilities\": []}}\n")
                .unwrap();
            assert!(lines.next().unwrap().unwrap().contains("qmp_capabilities"));
            writer.write_all(b"{\"return\": {}}\n").unwrap();
            assert!(lines.next().unwrap().unwrap().contains("\"cont\""));
            writer
                .write_all(b"{\"timestamp\": {}, \"event\": \"RESUME\"}\n{\"return\": {}}\n")
                .unwrap();
            assert!(lines.next().unwrap().unwrap().contains("\"stop\""));
            writer
                .write_all(b"{\"error\": {\"class\": \"GenericError\", \"desc\": \"no\"}}\n")
                .unwrap();
        });
        let mut qmp = Qmp::handshake(ours).unwrap();
        qmp.cont().unwrap();
        assert!(matches!(qmp.execute("stop"), Err(Error::Protocol(_))));
        fake.join().unwrap();
    }
}
