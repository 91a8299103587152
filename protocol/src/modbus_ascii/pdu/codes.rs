//! Byte values of function, access and exception codes, and the text for exception codes.

use core::fmt;

use super::{DeviceIdCode, ExceptionCode, FunctionCode};

impl FunctionCode {
    /// The function for `byte`, or `None` for one this crate does not implement (including
    /// exception codes `0x80 | function`).
    pub const fn from_u8(byte: u8) -> Option<Self> {
        Some(match byte {
            0x01 => FunctionCode::ReadCoils,
            0x03 => FunctionCode::ReadHoldingRegisters,
            0x04 => FunctionCode::ReadInputRegisters,
            0x05 => FunctionCode::WriteSingleCoil,
            0x06 => FunctionCode::WriteSingleRegister,
            0x10 => FunctionCode::WriteMultipleRegisters,
            0x2B => FunctionCode::EncapsulatedInterface,
            _ => return None,
        })
    }

    /// The byte on the wire.
    pub const fn to_u8(self) -> u8 {
        self as u8
    }
}

impl DeviceIdCode {
    /// The access code for `byte`, or `None` outside 0x01..=0x04.
    pub const fn from_u8(byte: u8) -> Option<Self> {
        Some(match byte {
            0x01 => DeviceIdCode::Basic,
            0x02 => DeviceIdCode::Regular,
            0x03 => DeviceIdCode::Extended,
            0x04 => DeviceIdCode::Specific,
            _ => return None,
        })
    }

    /// The byte on the wire.
    pub const fn to_u8(self) -> u8 {
        self as u8
    }
}

impl ExceptionCode {
    /// The exception for `byte`. Codes without a name become [`ExceptionCode::Other`], so
    /// `from_u8(b).to_u8() == b` for every byte.
    pub const fn from_u8(byte: u8) -> Self {
        match byte {
            0x01 => ExceptionCode::IllegalFunction,
            0x02 => ExceptionCode::IllegalDataAddress,
            0x03 => ExceptionCode::IllegalDataValue,
            0x04 => ExceptionCode::ServerDeviceFailure,
            0x05 => ExceptionCode::Acknowledge,
            0x06 => ExceptionCode::ServerDeviceBusy,
            0x08 => ExceptionCode::MemoryParityError,
            0x0A => ExceptionCode::GatewayPathUnavailable,
            0x0B => ExceptionCode::GatewayTargetFailed,
            other => ExceptionCode::Other(other),
        }
    }

    /// The byte on the wire.
    pub const fn to_u8(self) -> u8 {
        match self {
            ExceptionCode::IllegalFunction => 0x01,
            ExceptionCode::IllegalDataAddress => 0x02,
            ExceptionCode::IllegalDataValue => 0x03,
            ExceptionCode::ServerDeviceFailure => 0x04,
            ExceptionCode::Acknowledge => 0x05,
            ExceptionCode::ServerDeviceBusy => 0x06,
            ExceptionCode::MemoryParityError => 0x08,
            ExceptionCode::GatewayPathUnavailable => 0x0A,
            ExceptionCode::GatewayTargetFailed => 0x0B,
            ExceptionCode::Other(byte) => byte,
        }
    }

    /// Short name, as the Modbus application protocol calls the code.
    pub const fn name(self) -> &'static str {
        match self {
            ExceptionCode::IllegalFunction => "illegal function",
            ExceptionCode::IllegalDataAddress => "illegal data address",
            ExceptionCode::IllegalDataValue => "illegal data value",
            ExceptionCode::ServerDeviceFailure => "server device failure",
            ExceptionCode::Acknowledge => "acknowledge",
            ExceptionCode::ServerDeviceBusy => "server device busy",
            ExceptionCode::MemoryParityError => "memory parity error",
            ExceptionCode::GatewayPathUnavailable => "gateway path unavailable",
            ExceptionCode::GatewayTargetFailed => "gateway target device failed to respond",
            ExceptionCode::Other(_) => "unknown exception",
        }
    }

    /// One sentence saying what the unit meant.
    pub const fn description(self) -> &'static str {
        match self {
            ExceptionCode::IllegalFunction => {
                "The unit does not implement the function code of the request."
            }
            ExceptionCode::IllegalDataAddress => {
                "The unit has no register or coil at (part of) the requested address range."
            }
            ExceptionCode::IllegalDataValue => {
                "A value in the request (quantity, byte count or data) is not allowed by the unit."
            }
            ExceptionCode::ServerDeviceFailure => {
                "The unit hit an unrecoverable error while carrying out the request."
            }
            ExceptionCode::Acknowledge => {
                "The unit accepted the request but needs a long time to complete it."
            }
            ExceptionCode::ServerDeviceBusy => {
                "The unit is busy with a long-running command; retry later."
            }
            ExceptionCode::MemoryParityError => {
                "The unit found a parity error in its memory while reading a record."
            }
            ExceptionCode::GatewayPathUnavailable => {
                "A gateway could not open a path to the target unit."
            }
            ExceptionCode::GatewayTargetFailed => "A gateway got no reply from the target unit.",
            ExceptionCode::Other(_) => {
                "The unit answered with an exception code Modbus does not define."
            }
        }
    }
}

impl fmt::Display for ExceptionCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "exception {:02X} ({})", self.to_u8(), self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exception_codes_round_trip_every_byte() {
        for b in 0..=255u8 {
            assert_eq!(ExceptionCode::from_u8(b).to_u8(), b);
        }
    }

    #[test]
    fn named_exception_codes() {
        let named = [
            (0x01, ExceptionCode::IllegalFunction),
            (0x02, ExceptionCode::IllegalDataAddress),
            (0x03, ExceptionCode::IllegalDataValue),
            (0x04, ExceptionCode::ServerDeviceFailure),
            (0x05, ExceptionCode::Acknowledge),
            (0x06, ExceptionCode::ServerDeviceBusy),
            (0x08, ExceptionCode::MemoryParityError),
            (0x0A, ExceptionCode::GatewayPathUnavailable),
            (0x0B, ExceptionCode::GatewayTargetFailed),
        ];
        for (byte, code) in named {
            assert_eq!(ExceptionCode::from_u8(byte), code);
            assert_ne!(code.name(), ExceptionCode::Other(0).name());
            assert!(!code.description().is_empty());
        }
        assert_eq!(ExceptionCode::from_u8(0x07), ExceptionCode::Other(0x07));
        assert_eq!(ExceptionCode::from_u8(0x00), ExceptionCode::Other(0x00));
    }

    #[test]
    fn function_codes_round_trip() {
        for b in 0..=255u8 {
            if let Some(f) = FunctionCode::from_u8(b) {
                assert_eq!(f.to_u8(), b);
            }
        }
        assert_eq!(FunctionCode::from_u8(0x84), None);
        assert_eq!(FunctionCode::from_u8(0x02), None);
        assert_eq!(
            FunctionCode::from_u8(0x10),
            Some(FunctionCode::WriteMultipleRegisters)
        );
    }

    #[test]
    fn device_id_codes() {
        for b in 0..=255u8 {
            match DeviceIdCode::from_u8(b) {
                Some(c) => assert_eq!(c.to_u8(), b),
                None => assert!(b == 0 || b > 4),
            }
        }
    }
}
