//! Counters that tell an installer how healthy the power-supply line is.

use plasma_protocol::modbus_ascii::ExceptionCode;

use crate::link::transaction::TransactionError;

/// Link counters. Every failed attempt is counted by its class; a transaction that needs
/// retries counts each failed attempt and each retry. Counters saturate instead of wrapping.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Diagnostics {
    /// Transactions that ended with a valid reply.
    pub transactions_ok: u32,
    /// Transactions that failed after all their attempts (or with a final answer).
    pub transactions_failed: u32,
    /// Retries sent.
    pub retries: u32,
    /// Attempts that got no reply in time.
    pub timeouts: u32,
    /// Replies with a bad LRC / checksum.
    pub bad_checksums: u32,
    /// Modbus exception replies, by code: index 0 = code 01 ... index 10 = code 0B; codes
    /// above 0x0B are counted in `exceptions_other`.
    pub exceptions: [u32; 11],
    /// Modbus exception replies with a code outside 01-0B.
    pub exceptions_other: u32,
    /// Replies that did not answer their request.
    pub mismatches: u32,
    /// Replies that could not be parsed.
    pub malformed: u32,
    /// HPR error replies 500 (the unit saw a bad checksum).
    pub hpr_bad_checksum_500: u32,
    /// HPR error replies 501 (unknown command).
    pub hpr_unknown_command_501: u32,
    /// Times the link went down.
    pub link_downs: u32,
    /// Events dropped because the event queue was full.
    pub events_dropped: u32,
    /// Frames (or damaged frames) received while no reply was awaited (late replies, noise).
    pub unsolicited_frames: u32,
    /// Characters the UART flagged with a parity or framing error
    /// ([`PsLink::handle_rx_error`](crate::link::PsLink::handle_rx_error)).
    pub rx_errors: u32,
    /// Frames equal to the request just sent, taken for its echo (2-wire line with the
    /// receiver left on) and ignored.
    pub echoes: u32,
}

fn bump(counter: &mut u32) {
    *counter = counter.saturating_add(1);
}

impl Diagnostics {
    /// Count one failed attempt by its class.
    pub(crate) fn record_error(&mut self, error: TransactionError) {
        match error {
            TransactionError::Timeout => bump(&mut self.timeouts),
            TransactionError::BadChecksum => bump(&mut self.bad_checksums),
            TransactionError::Exception(code) => {
                let byte = code.to_u8();
                match self.exceptions.get_mut(usize::from(byte).wrapping_sub(1)) {
                    Some(counter) => bump(counter),
                    None => bump(&mut self.exceptions_other),
                }
            }
            TransactionError::Mismatch => bump(&mut self.mismatches),
            TransactionError::HprBadChecksum500 => bump(&mut self.hpr_bad_checksum_500),
            TransactionError::HprUnknownCommand501 => bump(&mut self.hpr_unknown_command_501),
            TransactionError::Malformed => bump(&mut self.malformed),
        }
    }

    /// Exception replies seen with this code.
    pub fn exceptions_with(&self, code: ExceptionCode) -> u32 {
        let byte = code.to_u8();
        match self.exceptions.get(usize::from(byte).wrapping_sub(1)) {
            Some(count) => *count,
            None => self.exceptions_other,
        }
    }

    /// Count a retry.
    pub(crate) fn record_retry(&mut self) {
        bump(&mut self.retries);
    }

    /// Count a transaction that succeeded.
    pub(crate) fn record_ok(&mut self) {
        bump(&mut self.transactions_ok);
    }

    /// Count a transaction that failed for good.
    pub(crate) fn record_failed(&mut self) {
        bump(&mut self.transactions_failed);
    }

    /// Count a link-down.
    pub(crate) fn record_link_down(&mut self) {
        bump(&mut self.link_downs);
    }

    /// Count a dropped event.
    pub(crate) fn record_event_dropped(&mut self) {
        bump(&mut self.events_dropped);
    }

    /// Count a frame that arrived while no reply was awaited.
    pub(crate) fn record_unsolicited(&mut self) {
        bump(&mut self.unsolicited_frames);
    }

    /// Count an echo of our own request.
    pub(crate) fn record_echo(&mut self) {
        bump(&mut self.echoes);
    }

    /// Count a character the UART flagged.
    pub(crate) fn record_rx_error(&mut self) {
        bump(&mut self.rx_errors);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_class_has_its_own_counter() {
        let mut d = Diagnostics::default();
        d.record_error(TransactionError::Timeout);
        d.record_error(TransactionError::BadChecksum);
        d.record_error(TransactionError::Exception(
            ExceptionCode::IllegalDataAddress,
        ));
        d.record_error(TransactionError::Exception(
            ExceptionCode::IllegalDataAddress,
        ));
        d.record_error(TransactionError::Exception(
            ExceptionCode::GatewayTargetFailed,
        ));
        d.record_error(TransactionError::Exception(ExceptionCode::Other(0x00)));
        d.record_error(TransactionError::Exception(ExceptionCode::Other(0x40)));
        d.record_error(TransactionError::Mismatch);
        d.record_error(TransactionError::HprBadChecksum500);
        d.record_error(TransactionError::HprUnknownCommand501);
        d.record_error(TransactionError::Malformed);
        assert_eq!(d.timeouts, 1);
        assert_eq!(d.bad_checksums, 1);
        assert_eq!(d.exceptions_with(ExceptionCode::IllegalDataAddress), 2);
        assert_eq!(d.exceptions_with(ExceptionCode::GatewayTargetFailed), 1);
        assert_eq!(d.exceptions_other, 2);
        assert_eq!(d.mismatches, 1);
        assert_eq!(d.hpr_bad_checksum_500, 1);
        assert_eq!(d.hpr_unknown_command_501, 1);
        assert_eq!(d.malformed, 1);
    }

    #[test]
    fn counters_saturate() {
        let mut d = Diagnostics {
            retries: u32::MAX,
            ..Default::default()
        };
        d.record_retry();
        assert_eq!(d.retries, u32::MAX);
    }
}
