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
        self.execute_with(command, None)
    }

    /// Runs a command with `arguments` (an object), if any; returns its `return` value.
    pub fn execute_with(&mut self, command: &str, arguments: Option<Value>) -> Result<Value> {
        let request = match arguments {
            Some(arguments) => serde_json::json!({ "execute": command, "arguments": arguments }),
            None => serde_json::json!({ "execute": command }),
        };
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

    /// The VM's run state (`query-status`): `running`, `paused`, `prelaunch`, `shutdown`...
    pub fn status(&mut self) -> Result<String> {
        let status = self.execute("query-status")?;
        status
            .get("status")
            .and_then(Value::as_str)
            .map(str::to_string)
            .ok_or_else(|| Error::Protocol(format!("QMP query-status returned {status}")))
    }

    /// What QEMU does when the guest resets itself: with `hold`, it stops the VM instead
    /// (`set-action reboot=shutdown shutdown=pause`, run state `shutdown`) until
    /// [`Qmp::reset_stopped`]; without, it resets and runs on (QEMU's default).
    pub fn hold_guest_resets(&mut self, hold: bool) -> Result<()> {
        let (reboot, shutdown) = if hold {
            ("shutdown", "pause")
        } else {
            ("reset", "poweroff")
        };
        self.execute_with(
            "set-action",
            Some(serde_json::json!({ "reboot": reboot, "shutdown": shutdown })),
        )
        .map(drop)
    }

    /// Resets the stopped VM and leaves it stopped (run state `prelaunch`, as under `-S`), to
    /// be started with [`Qmp::cont`]; held guest resets are no longer held. `system_reset`
    /// only asks for the reset (a held reboot action would turn it into another stop), so
    /// this waits for the run state that follows it.
    pub fn reset_stopped(&mut self, timeout: Duration) -> Result<()> {
        self.hold_guest_resets(false)?;
        self.execute("system_reset")?;
        self.wait_status("prelaunch", timeout)
    }

    /// Waits until the run state is `status`.
    pub fn wait_status(&mut self, status: &str, timeout: Duration) -> Result<()> {
        let began = std::time::Instant::now();
        loop {
            let now = self.status()?;
            if now == status {
                return Ok(());
            }
            if began.elapsed() > timeout {
                return Err(Error::Timeout(format!(
                    "QEMU's run state still {now} after {} ms (waiting for {status})",
                    timeout.as_millis()
                )));
            }
            std::thread::sleep(Duration::from_millis(2));
        }
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
