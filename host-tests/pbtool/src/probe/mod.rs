//! `pbtool probe`: finds the unit on a port and reads everything it will tell. It only reads:
//! it sends read requests and nothing that changes the unit.
//!
//! Detection asks as the bridge's link does, in every framing (8E1, 8O1, 8N1, then two stop
//! bits): Modbus Read Device Identification tells a SYNC from a legacy Powermax, a legacy unit
//! that does not know it answers a plain register read, and at 8N1 the HPR `HELLO`. Then
//! every readable register and coil the catalogue documents for the family is read, one
//! catalogue entry per request (a unit that refuses one still answers the rest); an HPR gets
//! every query command of the manual's table ([`reads`]). Each reply is explained by the
//! same decoder as `pbtool decode` ([`report`] prints it all as text or JSON).

pub mod reads;
pub mod report;

use std::time::{Duration, Instant};

use plasma_protocol::modbus_ascii::{self, DeviceIdentification, Response};
use plasma_protocol::powermax::device_id::{AddressingSystem, model_from_device_id};
use plasma_protocol::serial::{Parity, PortConfig, StopBits};
use plasma_sim::Family;

use crate::decode::{FrameReport, Kind, decode_frames};
use crate::framer::Framer;
use crate::serial::{Port, SerialError, describe};
use reads::Read;

/// How long a unit has to answer one request: the manuals' time-outs are 100 ms and less;
/// a USB adapter adds some.
const REPLY_TIMEOUT: Duration = Duration::from_millis(500);
/// The Powermax's default node address.
pub const DEFAULT_NODE: u8 = 1;

/// The framings detection tries, in order (the bridge's link tries the same).
pub const FRAMINGS: [PortConfig; 6] = {
    const fn at(parity: Parity, stop_bits: StopBits) -> PortConfig {
        PortConfig::new(19_200, parity, stop_bits)
    }
    [
        at(Parity::Even, StopBits::One),
        at(Parity::Odd, StopBits::One),
        at(Parity::None, StopBits::One),
        at(Parity::Even, StopBits::Two),
        at(Parity::Odd, StopBits::Two),
        at(Parity::None, StopBits::Two),
    ]
};

/// The unit found.
#[derive(Debug, Clone)]
pub struct Found {
    /// Its protocol family.
    pub family: Family,
    /// The framing it answered at.
    pub framing: PortConfig,
    /// What identified it (the reply to the identifying request, decoded).
    pub identity: FrameReport,
}

/// One read and what came back.
#[derive(Debug, Clone)]
pub struct Reading {
    /// What was asked for.
    pub what: String,
    /// The request frame.
    pub request: String,
    /// The reply, decoded; `None` when none came in time.
    pub reply: Option<FrameReport>,
}

/// What a probe learnt.
#[derive(Debug, Clone)]
pub struct Probe {
    /// The port.
    pub port: String,
    /// The unit, if one answered.
    pub found: Option<Found>,
    /// Every read, in order.
    pub readings: Vec<Reading>,
}

/// A master on the port: one request, one reply, nothing else.
struct Master {
    port: Port,
}

impl Master {
    /// Sends `request`; the first whole frame of the same protocol that comes back within
    /// [`REPLY_TIMEOUT`], decoded in the light of the request.
    fn ask(&mut self, request: &str) -> Result<Option<FrameReport>, SerialError> {
        let mut stale = Vec::new();
        self.port.read(Duration::from_millis(1), &mut stale)?;
        self.port.write_all(request.as_bytes())?;
        let start = request.as_bytes().first().copied();
        let deadline = Instant::now() + REPLY_TIMEOUT;
        let mut framer = Framer::default();
        let mut rx = Vec::new();
        let began = plasma_protocol::time::Instant::ZERO;
        while let Some(left) = deadline.checked_duration_since(Instant::now()) {
            rx.clear();
            self.port.read(left, &mut rx)?;
            for &item in &rx {
                for piece in framer.push_one(began, item) {
                    if piece.complete && piece.text.as_bytes().first().copied() == start {
                        let reports = decode_frames(&[request, piece.text.as_str()]);
                        return Ok(reports.into_iter().nth(1));
                    }
                }
            }
        }
        Ok(None)
    }
}

/// True for a reply that answers the request it followed (an exception reply included).
fn answers(report: &FrameReport) -> bool {
    report.kind == Some(Kind::Reply) && report.answers_request == Some(true)
}

/// True for a Modbus exception reply.
fn is_exception(report: &FrameReport) -> bool {
    report.function.as_ref().is_some_and(|f| f.code & 0x80 != 0)
}

/// Finds the unit on `port` (trying for up to `patience`; a Powermax at Modbus node `node`)
/// and reads it, telling `progress` each framing it tries.
pub fn probe(
    port: Port,
    patience: Duration,
    node: u8,
    progress: &mut dyn FnMut(&str),
) -> Result<Probe, SerialError> {
    let name = port.name().to_string();
    let mut master = Master { port };
    let began = Instant::now();
    let mut found = None;
    let mut round = 0;
    while found.is_none() && began.elapsed() < patience {
        round += 1;
        found = detect(&mut master, node, &mut |step| {
            progress(&format!("round {round}: {step}"));
        })?;
    }
    if let Some(found) = &found {
        progress(&format!(
            "a unit answered at {}; reading it",
            describe(found.framing)
        ));
    }
    let mut readings = Vec::new();
    if let Some(found) = &found {
        master.port.set_config(found.framing)?;
        for read in reads::for_family(found.family, node) {
            let Read { what, request } = read;
            let reply = master.ask(&request)?;
            readings.push(Reading {
                what,
                request,
                reply,
            });
        }
    }
    Ok(Probe {
        port: name,
        found,
        readings,
    })
}

/// One round over every framing.
fn detect(
    master: &mut Master,
    node: u8,
    progress: &mut dyn FnMut(&str),
) -> Result<Option<Found>, SerialError> {
    for framing in FRAMINGS {
        progress(&format!("Modbus at {}, node {node}", describe(framing)));
        master.port.set_config(framing)?;
        if let Some(found) = detect_modbus(master, framing, node)? {
            return Ok(Some(found));
        }
    }
    progress(&format!("HPR HELLO at {}", describe(PortConfig::HPR)));
    master.port.set_config(PortConfig::HPR)?;
    let hello = reads::hpr_request(plasma_protocol::hpr::command::id::HELLO);
    Ok(master
        .ask(&hello)?
        .filter(|r| answers(r) && r.valid)
        .map(|identity| Found {
            family: Family::Hpr,
            framing: PortConfig::HPR,
            identity,
        }))
}

fn detect_modbus(
    master: &mut Master,
    framing: PortConfig,
    node: u8,
) -> Result<Option<Found>, SerialError> {
    let device_id = reads::device_id_request(node);
    if let Some(reply) = master.ask(&device_id)?.filter(answers)
        && !is_exception(&reply)
    {
        let family = match addressing(&reply) {
            Some(AddressingSystem::Legacy) => Family::Legacy,
            _ => Family::Sync,
        };
        return Ok(Some(Found {
            family,
            framing,
            identity: reply,
        }));
    }
    // A legacy unit may not know Read Device Identification: a plain register read.
    let legacy = reads::legacy_presence_request(node);
    Ok(master
        .ask(&legacy)?
        .filter(|r| answers(r) && !is_exception(r))
        .map(|identity| Found {
            family: Family::Legacy,
            framing,
            identity,
        }))
}

/// The addressing system the device-identification reply names.
fn addressing(report: &FrameReport) -> Option<AddressingSystem> {
    let mut buf = [0u8; modbus_ascii::MAX_FRAME_BYTES];
    let frame = modbus_ascii::decode(format!("{}\r\n", report.frame).as_bytes(), &mut buf).ok()?;
    let Ok(Response::ReadDeviceIdentification(reply)) = frame.response() else {
        return None;
    };
    let reply: DeviceIdentification<'_> = reply;
    Some(model_from_device_id(&reply).ok()??.addressing())
}
