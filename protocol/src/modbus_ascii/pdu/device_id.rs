//! Read Device Identification replies (function 0x2B, MEI type 0x0E).
//!
//! Reply data: `0E code conformity more_follows next_object_id count {id len value[len]}*`.

use super::request::MEI_READ_DEVICE_ID;
use super::wire::Writer;
use super::{DeviceIdCode, DeviceIdentification, FunctionCode, MAX_PDU_LEN};
use crate::{Error, Result};

/// `more_follows` byte values.
const MORE_FOLLOWS: u8 = 0xFF;
const NO_MORE: u8 = 0x00;

/// Bytes before the object list in a whole PDU: function, MEI, code, conformity, more,
/// next, count.
const HEADER_LEN: usize = 7;

impl<'a> DeviceIdentification<'a> {
    /// Parses the reply data after the function code (starting with the MEI type 0x0E).
    ///
    /// The object list must hold exactly `object_count` objects whose lengths add up to the
    /// rest of the PDU; `more_follows` must be 0x00 or 0xFF.
    pub(crate) fn parse(data: &'a [u8]) -> Result<Self> {
        if data.first().is_some_and(|&mei| mei != MEI_READ_DEVICE_ID) {
            return Err(Error::Unsupported);
        }
        let [
            _,
            code,
            conformity,
            more,
            next_object_id,
            object_count,
            ref objects @ ..,
        ] = *data
        else {
            return Err(Error::Truncated);
        };
        let code = DeviceIdCode::from_u8(code).ok_or(Error::Malformed)?;
        let more_follows = match more {
            MORE_FOLLOWS => true,
            NO_MORE => false,
            _ => return Err(Error::Malformed),
        };
        check_objects(objects, object_count)?;
        Ok(DeviceIdentification {
            code,
            conformity,
            more_follows,
            next_object_id,
            object_count,
            objects,
        })
    }

    /// The objects in order, as `(id, value)`.
    ///
    /// For a parsed reply every object is complete. For a value built by hand with an
    /// inconsistent list, iteration stops at the first object that does not fit.
    pub fn objects(&self) -> DeviceObjects<'a> {
        DeviceObjects {
            rest: self.objects,
            remaining: self.object_count,
        }
    }

    /// The value of object `id`, if the reply holds it.
    ///
    /// Objects 0x00, 0x01 and 0x02 are vendor name, product code and revision; Powermax
    /// units report their family in the product code (e.g. `081335` for Powermax65/85/105
    /// SYNC).
    pub fn object(&self, id: u8) -> Option<&'a [u8]> {
        self.objects()
            .find(|&(object_id, _)| object_id == id)
            .map(|(_, value)| value)
    }

    /// Writes the whole reply PDU (function 0x2B included) into `out`; returns its length.
    ///
    /// Refuses ([`Error::Malformed`]) an object list that does not hold exactly
    /// `object_count` complete objects.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize> {
        check_objects(self.objects, self.object_count).map_err(|_| Error::Malformed)?;
        if HEADER_LEN + self.objects.len() > MAX_PDU_LEN {
            return Err(Error::Overlong);
        }
        let mut w = Writer::new(out);
        self.emit_header(&mut w)?;
        w.bytes(self.objects)?;
        Ok(w.len())
    }

    /// Writes a whole reply PDU (function 0x2B included) carrying `objects` into `out`; returns
    /// its length. For simulators: the object list is built here from `(id, value)` pairs.
    ///
    /// [`Error::Malformed`] when a value is longer than 255 bytes or there are more than 255
    /// objects, [`Error::Overlong`] when the PDU would exceed [`MAX_PDU_LEN`].
    pub fn emit_objects(
        code: DeviceIdCode,
        conformity: u8,
        more_follows: bool,
        next_object_id: u8,
        objects: &[(u8, &[u8])],
        out: &mut [u8],
    ) -> Result<usize> {
        let object_count = u8::try_from(objects.len()).map_err(|_| Error::Malformed)?;
        let mut total = HEADER_LEN;
        for (_, value) in objects {
            if value.len() > usize::from(u8::MAX) {
                return Err(Error::Malformed);
            }
            total += 2 + value.len();
            if total > MAX_PDU_LEN {
                return Err(Error::Overlong);
            }
        }
        let header = DeviceIdentification {
            code,
            conformity,
            more_follows,
            next_object_id,
            object_count,
            objects: &[],
        };
        let mut w = Writer::new(out);
        header.emit_header(&mut w)?;
        for &(id, value) in objects {
            w.u8(id)?;
            w.u8(value.len() as u8)?;
            w.bytes(value)?;
        }
        Ok(w.len())
    }

    fn emit_header(&self, w: &mut Writer<'_>) -> Result<()> {
        w.u8(FunctionCode::EncapsulatedInterface.to_u8())?;
        w.u8(MEI_READ_DEVICE_ID)?;
        w.u8(self.code.to_u8())?;
        w.u8(self.conformity)?;
        w.u8(if self.more_follows {
            MORE_FOLLOWS
        } else {
            NO_MORE
        })?;
        w.u8(self.next_object_id)?;
        w.u8(self.object_count)
    }
}

/// `Ok` when `objects` is exactly `count` complete `{id len value}` entries.
fn check_objects(objects: &[u8], count: u8) -> Result<()> {
    let mut rest = objects;
    for _ in 0..count {
        let [_, len, ref tail @ ..] = *rest else {
            return Err(Error::Truncated);
        };
        rest = tail.get(usize::from(len)..).ok_or(Error::Truncated)?;
    }
    if rest.is_empty() {
        Ok(())
    } else {
        Err(Error::Malformed)
    }
}

/// Iterator over the `(id, value)` objects of a [`DeviceIdentification`].
#[derive(Debug, Clone)]
pub struct DeviceObjects<'a> {
    rest: &'a [u8],
    remaining: u8,
}

impl<'a> Iterator for DeviceObjects<'a> {
    type Item = (u8, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        self.remaining = self.remaining.checked_sub(1)?;
        let [id, len, ref tail @ ..] = *self.rest else {
            self.remaining = 0;
            return None;
        };
        let Some((value, rest)) = tail.split_at_checked(usize::from(len)) else {
            self.remaining = 0;
            return None;
        };
        self.rest = rest;
        Some((id, value))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modbus_ascii::Response;

    /// The SYNC guide's reply PDU (after the address), checked in the seed tests.
    const SYNC_REPLY: [u8; 15] = [
        0x2B, 0x0E, 0x04, 0x81, 0x00, 0x01, 0x01, 0x01, 0x06, b'0', b'8', b'1', b'3', b'3', b'5',
    ];

    #[test]
    fn parses_objects() {
        let Ok(Response::ReadDeviceIdentification(id)) = Response::parse(&SYNC_REPLY) else {
            panic!("not a device id reply");
        };
        let mut objects = id.objects();
        assert_eq!(objects.next(), Some((0x01, &b"081335"[..])));
        assert_eq!(objects.next(), None);
        assert_eq!(id.object(0x01), Some(&b"081335"[..]));
        assert_eq!(id.object(0x00), None);
    }

    #[test]
    fn emit_objects_builds_the_same_pdu() {
        let mut out = [0u8; 64];
        let n = DeviceIdentification::emit_objects(
            DeviceIdCode::Specific,
            0x81,
            false,
            0x01,
            &[(0x01, b"081335")],
            &mut out,
        )
        .unwrap();
        assert_eq!(&out[..n], &SYNC_REPLY);
    }

    #[test]
    fn several_objects() {
        let objects: [(u8, &[u8]); 3] = [(0x00, b"Hypertherm"), (0x01, b"081223"), (0x02, b"")];
        let mut out = [0u8; 64];
        let n = DeviceIdentification::emit_objects(
            DeviceIdCode::Basic,
            0x01,
            true,
            0x03,
            &objects,
            &mut out,
        )
        .unwrap();
        let Ok(Response::ReadDeviceIdentification(id)) = Response::parse(&out[..n]) else {
            panic!("not a device id reply");
        };
        assert!(id.more_follows);
        assert_eq!(id.next_object_id, 0x03);
        assert_eq!(id.object_count, 3);
        assert!(id.objects().eq(objects.iter().copied()));
        let mut again = [0u8; 64];
        assert_eq!(
            Response::ReadDeviceIdentification(id).emit(&mut again),
            Ok(n)
        );
        assert_eq!(&again[..n], &out[..n]);
    }

    #[test]
    fn rejects_inconsistent_lists() {
        let mut pdu = SYNC_REPLY;
        // Object length 7 but only 6 bytes follow.
        pdu[8] = 0x07;
        assert_eq!(Response::parse(&pdu), Err(Error::Truncated));
        // Object length 5 leaves a stray byte.
        pdu[8] = 0x05;
        assert_eq!(Response::parse(&pdu), Err(Error::Malformed));
        // Two objects announced, one present.
        let mut pdu = SYNC_REPLY;
        pdu[6] = 0x02;
        assert_eq!(Response::parse(&pdu), Err(Error::Truncated));
        // Zero objects announced, one present.
        pdu[6] = 0x00;
        assert_eq!(Response::parse(&pdu), Err(Error::Malformed));
        // more_follows neither 00 nor FF.
        let mut pdu = SYNC_REPLY;
        pdu[4] = 0x01;
        assert_eq!(Response::parse(&pdu), Err(Error::Malformed));
        // Unknown access code.
        let mut pdu = SYNC_REPLY;
        pdu[2] = 0x05;
        assert_eq!(Response::parse(&pdu), Err(Error::Malformed));
        // Other MEI type.
        let mut pdu = SYNC_REPLY;
        pdu[1] = 0x0D;
        assert_eq!(Response::parse(&pdu), Err(Error::Unsupported));
        assert_eq!(Response::parse(&SYNC_REPLY[..6]), Err(Error::Truncated));
        assert_eq!(Response::parse(&SYNC_REPLY[..1]), Err(Error::Truncated));
    }

    #[test]
    fn emit_limits() {
        let mut out = [0u8; 300];
        let long = [0u8; 256];
        assert_eq!(
            DeviceIdentification::emit_objects(
                DeviceIdCode::Basic,
                1,
                false,
                0,
                &[(0, &long)],
                &mut out
            ),
            Err(Error::Malformed)
        );
        // 7 header bytes + 2 + 245 = 254 > 253.
        assert_eq!(
            DeviceIdentification::emit_objects(
                DeviceIdCode::Basic,
                1,
                false,
                0,
                &[(0, &long[..245])],
                &mut out
            ),
            Err(Error::Overlong)
        );
        assert_eq!(
            DeviceIdentification::emit_objects(
                DeviceIdCode::Basic,
                1,
                false,
                0,
                &[(0, &long[..244])],
                &mut out
            ),
            Ok(253)
        );
        assert_eq!(
            DeviceIdentification::emit_objects(
                DeviceIdCode::Basic,
                1,
                false,
                0,
                &[(0, b"abc")],
                &mut out[..11]
            ),
            Err(Error::BufferTooSmall)
        );
        // A hand-built value whose list disagrees with its count.
        let bad = DeviceIdentification {
            code: DeviceIdCode::Basic,
            conformity: 1,
            more_follows: false,
            next_object_id: 0,
            object_count: 2,
            objects: &[0x00, 0x01, b'x'],
        };
        assert_eq!(bad.emit(&mut out), Err(Error::Malformed));
        assert_eq!(bad.objects().count(), 1);
    }
}
