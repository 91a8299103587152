//! The manuals' sample frames that are printed with a typo, and the frame each meant.
//!
//! The decoders reject the printed forms (an odd number of hex digits, a wrong checksum), as
//! they would any damaged frame; this table lets a host tool say what the manual meant. Only
//! typos whose correction the frame itself confirms are listed (the byte count and LRC, or
//! the checksum, match the corrected frame and nothing else near it); samples that cannot be
//! corrected with confidence are not (the HPR tests list them with the reason).

/// A sample frame printed wrongly in a manual.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Erratum {
    /// The frame as printed (without the `<CR><LF>` the SYNC guide writes after it).
    pub printed: &'static str,
    /// The frame the manual meant.
    pub meant: &'static str,
    /// Which sample it is.
    pub sample: &'static str,
    /// What is wrong and what confirms the correction.
    pub why: &'static str,
}

/// SYNC guide, exit remote mode (line 1154 of the OCR'd guide).
pub const SYNC_EXIT_REMOTE_MODE: Erratum = Erratum {
    printed: ":01103080000306000000000000036",
    meant: ":0110308000030600000000000036",
    sample: "SYNC guide, exit remote mode request",
    why: "thirteen 0s where byte count 06 needs twelve; the LRC 36 matches the corrected frame",
};

/// SYNC guide, fault log reply (line 1589).
pub const SYNC_FAULT_LOG_REPLY: Erratum = Erratum {
    printed: ":0104080079007900000000001",
    meant: ":010408007900790000000001",
    sample: "SYNC guide, fault log reply",
    why: "ten 0s where byte count 08 needs nine before the LRC; the LRC 01 matches the corrected frame",
};

/// SYNC guide, cartridge name reply (line 1662).
pub const SYNC_CARTRIDGE_NAME_REPLY: Erratum = Erratum {
    printed: ":01040C43204D45434800000000000006F",
    meant: ":01040C43204D4543480000000000006F",
    sample: "SYNC guide, cartridge name reply",
    why: "thirteen 0s where six NUL bytes need twelve; the LRC 6F matches the corrected frame",
};

/// HPR manual, HELLO reply of an HPR130 with a manual gas console (line 139).
pub const HPR_HELLO_MANUAL_CONSOLE: Erratum = Erratum {
    printed: ">000HYPERPERFORMANCE130MANUALB5<",
    meant: ">000HYPERFORMANCE130MANUALB5<",
    sample: "HPR manual, HELLO reply (manual gas console)",
    why: "the name is doubled (HYPERPERFORMANCE); the checksum B5 matches HYPERFORMANCE",
};

/// HPR manual, HELLO reply of an HPR130 with an automatic gas console (line 139).
pub const HPR_HELLO_AUTO_CONSOLE: Erratum = Erratum {
    printed: ">000HYPERPERFORMANCE130AUTO30<",
    meant: ">000HYPERFORMANCE130AUTO30<",
    sample: "HPR manual, HELLO reply (automatic gas console)",
    why: "the name is doubled (HYPERPERFORMANCE); the checksum 30 matches HYPERFORMANCE",
};

/// HPR manual, HELLO reply of an HPR130 with an automatic mixing console (line 139).
pub const HPR_HELLO_AUTOMIX_CONSOLE: Erratum = Erratum {
    printed: ">000HYPERPERFORMANCE130AUTOMIX1E<",
    meant: ">000HYPERFORMANCE130AUTOMIX1E<",
    sample: "HPR manual, HELLO reply (automatic mixing gas console)",
    why: "the name is doubled (HYPERPERFORMANCE); the checksum 1E matches HYPERFORMANCE",
};

/// Every listed typo.
pub const MANUAL_TYPOS: [Erratum; 6] = [
    SYNC_EXIT_REMOTE_MODE,
    SYNC_FAULT_LOG_REPLY,
    SYNC_CARTRIDGE_NAME_REPLY,
    HPR_HELLO_MANUAL_CONSOLE,
    HPR_HELLO_AUTO_CONSOLE,
    HPR_HELLO_AUTOMIX_CONSOLE,
];

/// The erratum whose printed form is `frame` (exactly, after its line ending is removed).
pub fn erratum_for(frame: &str) -> Option<&'static Erratum> {
    MANUAL_TYPOS.iter().find(|e| e.printed == frame)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;
    use crate::hpr::{Frame, Reply};
    use crate::modbus_ascii::Decoder;

    /// The Modbus decoder's verdict on a whole frame followed by CR LF.
    fn modbus(frame: &str) -> Option<Result<(), Error>> {
        let mut wire = [0u8; 64];
        let n = frame.len();
        wire[..n].copy_from_slice(frame.as_bytes());
        wire[n..n + 2].copy_from_slice(b"\r\n");
        let mut decoder = Decoder::new();
        let (_, result) = decoder.feed(&wire[..n + 2]);
        result.map(|r| r.map(|_| ()))
    }

    #[test]
    fn printed_forms_are_rejected_and_meant_forms_decode() {
        // SYNC guide (000_dd931256418ae627.txt) lines 1154, 1589 and 1662: each printed
        // frame has one hex digit too many.
        for e in [
            SYNC_EXIT_REMOTE_MODE,
            SYNC_FAULT_LOG_REPLY,
            SYNC_CARTRIDGE_NAME_REPLY,
        ] {
            assert_eq!(
                modbus(e.printed),
                Some(Err(Error::OddLength)),
                "{}",
                e.sample
            );
            assert_eq!(modbus(e.meant), Some(Ok(())), "{}", e.sample);
            assert_eq!(e.printed.len(), e.meant.len() + 1);
        }
        // HPR manual (002_72b43a5685974c77.txt) line 139: the checksums only match the
        // name spelled once.
        for e in [
            HPR_HELLO_MANUAL_CONSOLE,
            HPR_HELLO_AUTO_CONSOLE,
            HPR_HELLO_AUTOMIX_CONSOLE,
        ] {
            assert!(
                matches!(
                    Frame::parse(e.printed.as_bytes()),
                    Err(Error::BadChecksum { .. })
                ),
                "{}",
                e.sample
            );
            let meant = Frame::parse(e.meant.as_bytes()).unwrap();
            assert!(matches!(Reply::parse(&meant), Ok(Reply::Hello(_))));
        }
        assert_eq!(
            erratum_for(">000HYPERPERFORMANCE130MANUALB5<"),
            Some(&HPR_HELLO_MANUAL_CONSOLE)
        );
        assert_eq!(erratum_for(">000HYPERFORMANCE130MANUALB5<"), None);
    }
}
