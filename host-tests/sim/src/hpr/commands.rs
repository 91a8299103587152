//! The serial commands: frames in, the command table (section IV) applied to the unit, replies
//! out after the unit's response time.

use plasma_protocol::time::{Duration, Instant};
use rand::RngExt;

use super::{Hpr, Phase, max_amps};
use crate::hpr_wire::{self, Incoming};

impl Hpr {
    pub(super) fn flag(ok: bool) -> String {
        if ok { "1".into() } else { "0".into() }
    }

    pub(super) fn settings_allowed(&self) -> bool {
        self.remote || !self.config.require_remote_mode
    }

    pub(super) fn change_gases(&mut self, gases: (u16, u16), now: Instant) {
        if gases != self.gases {
            self.gases = gases;
            self.enter(Phase::Purge, now);
        }
    }

    /// Acts on one command; `None` means no reply.
    pub(super) fn command(&mut self, now: Instant, id: u16, data: &str) -> Option<(u16, String)> {
        let hpr = !self.is_maxpro();
        let auto = self.auto_gas();
        let fields: Vec<&str> = data.split_whitespace().collect();
        let numbers: Option<Vec<u16>> = fields.iter().map(|f| f.parse().ok()).collect();
        let unknown = Some((501, String::new()));
        let reply = |s: String| Some((id, s));
        match id {
            0 => reply(self.identity()),
            1 => reply(self.config.version.clone()),
            2 => reply(format!("{:04}", self.state_code())),
            3 => reply(format!("{:04}", self.error)),
            4 => {
                self.remote = true;
                reply("1".into())
            }
            28 if hpr => reply(format!("{:04}", self.actual_amps())),
            58 if auto => {
                if let (true, Some([amps])) = (self.settings_allowed(), numbers.as_deref()) {
                    self.amps = (*amps).clamp(5, max_amps(self.config.model));
                }
                reply(format!("{:04}", self.amps))
            }
            64..=67 if hpr => {
                let ok = !self.cutting() && !self.error_blocks_start();
                if ok {
                    let phase = match id {
                        64 => Phase::TestPreflow,
                        66 => Phase::TestCutflow,
                        _ => Phase::Ready,
                    };
                    let stopping = id == 65 || id == 67;
                    let running = matches!(self.phase, Phase::TestPreflow | Phase::TestCutflow);
                    if !stopping || running {
                        self.enter(phase, now);
                    }
                }
                reply(Self::flag(ok))
            }
            68 => {
                let ok = if hpr {
                    self.error > 79 && self.phase == Phase::Shutdown
                } else {
                    !self.cutting()
                };
                if ok {
                    self.error = 0;
                    self.test_gas = false;
                    self.enter(Phase::PowerUp, now);
                }
                reply(Self::flag(ok))
            }
            70 if hpr => {
                if let (true, Some([pct])) = (self.settings_allowed(), numbers.as_deref()) {
                    self.corner_pct = (*pct).clamp(50, 100);
                }
                reply(format!("{:04}", self.corner_pct))
            }
            72 if hpr => reply("1200".into()),
            // 078 SET_ALL_GAS_FLOWS (line 165): 1 = accepted, 0 = not accepted.
            78 if auto => reply(Self::flag(
                self.settings_allowed() && self.set_all_gas_flows(numbers.as_deref()),
            )),
            79 if hpr => {
                let [pc, pp, sc, sp, _, _] = self.flows.map(|f| self.measured_psi(f));
                let measured = |v: u16| if auto { v } else { 0 };
                reply(format!(
                    "PC{pc:04} PP{pp:04} SC{sc:04} SP{sp:04} CS{:04} ST{:04} ER{:04} CG{:04} CG{:04} MV{:04} MV{:04}",
                    self.amps,
                    self.state_code(),
                    self.error,
                    measured(100),
                    measured(100),
                    measured(self.flows[4]),
                    measured(self.flows[5]),
                ))
            }
            79 => reply(format!(
                "st{:04} er{:04} pg{:04} ps{:04} sg{:04} ss{:04} cs{:04} dm{:04} lm0000",
                self.state_code(),
                self.error,
                self.gases.0,
                self.flows[0],
                self.gases.1,
                self.flows[2],
                self.amps,
                // Display mode 3 "Test Mode" while the test gas flows, else 1 "Error/Status".
                if self.test_gas { 3 } else { 1 },
            )),
            85 if hpr => {
                if fields.first().and_then(|f| f.parse::<u8>().ok()) == Some(self.config.id) {
                    self.awake = true;
                    self.broadcast = false;
                    return reply(data.into());
                }
                None
            }
            // "Disconnect their transmitters" (line 173): a reply not yet sent is not sent.
            86 if hpr => {
                self.awake = false;
                self.broadcast = false;
                self.outbox.clear();
                None
            }
            87 if hpr => {
                self.broadcast = true;
                None
            }
            94 if hpr => {
                let [pc, pp, sc, sp, n2, g2] = self.flows.map(|f| self.measured_psi(f));
                let m = |v: u16| if auto { v } else { 0 };
                reply(format!(
                    "PC{pc:04} PP{pp:04} SC{sc:04} SP{sp:04} CG{:04} CG{:04} MV{:04} MV{:04}",
                    m(100),
                    m(100),
                    m(n2),
                    m(g2)
                ))
            }
            95 if auto => {
                let ok =
                    self.settings_allowed() && self.set_all_parameters(now, numbers.as_deref());
                if hpr {
                    reply(Self::flag(ok))
                } else {
                    reply(if ok { "1".into() } else { "2".into() })
                }
            }
            96 if auto => {
                let ok = match numbers.as_deref() {
                    Some(&[p, s]) if self.settings_allowed() && !self.cutting() => {
                        valid_gas(p) && valid_gas(s) && {
                            self.change_gases((p, s), now);
                            true
                        }
                    }
                    _ => false,
                };
                reply(Self::flag(ok))
            }
            97 if hpr => reply(format!("{:04}", self.corner_pct)),
            98 => reply(format!("{:04} {:04}", self.gases.0, self.gases.1)),
            99 if hpr && auto => {
                let f = self.flows;
                reply(format!(
                    "{:04} {:04} {:04} {:04} {:04} {:04}",
                    f[0], f[1], f[2], f[3], f[4], f[5]
                ))
            }
            // 122 READ_GAS_SWITCH, "Manual Gas System" only (line 252): the knobs' positions.
            122 if hpr && !auto => reply(format!("{:04} {:04}", self.gases.0, self.gases.1)),
            125 if hpr => {
                let c = self.counters;
                let fields = [
                    c.arc_on.secs(),
                    c.system_on.secs() / 60,
                    c.starts.into(),
                    c.start_errors.into(),
                    c.rampdown_errors.into(),
                    0,
                    0,
                ];
                reply(
                    fields
                        .iter()
                        .map(|v| format!("{:07} ", v % 10_000_000))
                        .collect(),
                )
            }
            131 if hpr => {
                if self.error < 43 {
                    self.error = 0;
                }
                reply("1".into())
            }
            134 if hpr => reply(
                self.error_log
                    .iter()
                    .map(|e| format!("{e:03}"))
                    .collect::<Vec<_>>()
                    .join(" "),
            ),
            // The manual answers both `>1360CA<` and `>1361CB<` with `>1361CB<`: an accept
            // flag, not an echo of the setting.
            136 if self.is_xd() => match data {
                "0" | "1" => {
                    self.response_delay = data == "1";
                    reply("1".into())
                }
                _ => reply("0".into()),
            },
            137 if !hpr => {
                let ok = match numbers.as_deref() {
                    Some(&[amps, p, s])
                        if self.settings_allowed()
                            && matches!(self.phase, Phase::Purge | Phase::Ready)
                            && (5..=200).contains(&amps)
                            && valid_gas(p)
                            && valid_gas(s) =>
                    {
                        self.amps = amps;
                        self.change_gases((p, s), now);
                        true
                    }
                    _ => false,
                };
                reply(if ok { "1".into() } else { "2".into() })
            }
            138 if !hpr => reply(Self::flag(
                self.phase == Phase::Ready && !self.error_blocks_start() && !self.test_gas,
            )),
            145 if !hpr => reply(format!("{:04}", self.config.torch_id)),
            // 143 SET TEST MODE: 1 Test Gas only in state 3, 0 stops it (line 283). The reply
            // echoes the mode taken, as the manual's sample (`>1431C9<` to `>1431C9<`).
            // 141 GET MFG DATA1: the measured pressures while gas flows (the 143 test gas or a
            // cut), 0 otherwise (HPR manual line 281); the other readings are not modelled.
            141 if !hpr => {
                let flowing = self.test_gas || self.cutting();
                let psi = |set: u16| if flowing { self.measured_psi(set) } else { 0 };
                reply(format!(
                    "plap{:04} shap{:04} icrp0000 colt0000 chpt0000 chac0000",
                    psi(self.flows[0]),
                    psi(self.flows[2]),
                ))
            }
            143 if !hpr => match data {
                "1" if self.phase == Phase::Ready && !self.error_blocks_start() => {
                    self.test_gas = true;
                    reply("1".into())
                }
                "0" => {
                    self.test_gas = false;
                    reply("0".into())
                }
                _ => reply("0".into()),
            },
            _ => unknown,
        }
    }

    pub(super) fn set_all_parameters(&mut self, now: Instant, numbers: Option<&[u16]>) -> bool {
        if self.cutting() {
            return false;
        }
        let max = max_amps(self.config.model);
        match numbers {
            Some(&[amps, corner, p, s, pc, pp, sc, sp, n2, g2]) if !self.is_maxpro() => {
                let ok = (5..=max).contains(&amps)
                    && (50..=100).contains(&corner)
                    && valid_gas(p)
                    && valid_gas(s)
                    && [pc, pp, sc, sp].iter().all(|&v| v <= 99)
                    && n2 <= 100
                    && g2 <= 100;
                if ok {
                    self.amps = amps;
                    self.corner_pct = corner;
                    self.flows = [pc, pp, sc, sp, n2, g2];
                    self.change_gases((p, s), now);
                }
                ok
            }
            Some(&[amps, p, s, pp, sp]) if self.is_maxpro() => {
                let ok = matches!(self.phase, Phase::Purge | Phase::Ready)
                    && amps <= 200
                    && valid_gas(p)
                    && valid_gas(s)
                    && pp <= 99
                    && sp <= 99;
                if ok {
                    self.amps = amps;
                    self.flows[0] = pp;
                    self.flows[2] = sp;
                    self.change_gases((p, s), now);
                }
                ok
            }
            _ => false,
        }
    }

    /// 078's set points: six on an HPR (flows 0-99 psi, mix 0-100), the plasma and shield
    /// set points (0-99) on a MaxPro200; no state is named for it.
    pub(super) fn set_all_gas_flows(&mut self, numbers: Option<&[u16]>) -> bool {
        match numbers {
            Some(&[pc, pp, sc, sp, n2, g2]) if !self.is_maxpro() => {
                let ok = [pc, pp, sc, sp].iter().all(|&v| v <= 99) && n2 <= 100 && g2 <= 100;
                if ok {
                    self.flows = [pc, pp, sc, sp, n2, g2];
                }
                ok
            }
            Some(&[plasma, shield]) if self.is_maxpro() => {
                let ok = plasma <= 99 && shield <= 99;
                if ok {
                    self.flows[0] = plasma;
                    self.flows[2] = shield;
                }
                ok
            }
            _ => false,
        }
    }

    pub(super) fn response_time(&mut self) -> Duration {
        // 1-7 ms (XD about half), plus 1.0-1.8 ms with 136 enabled.
        let (lo, hi) = if self.is_xd() {
            (500, 3_500)
        } else {
            (1_000, 7_000)
        };
        let mut us = self.rng.random_range(lo..=hi);
        if self.response_delay {
            us += self.rng.random_range(1_000..=1_800);
        }
        Duration::from_micros(us)
    }

    pub(super) fn on_frame(&mut self, now: Instant, frame: Incoming) {
        let (id, data) = match frame {
            Incoming::BadChecksum => {
                if self.awake && !self.broadcast {
                    self.send(now, 500, String::new());
                }
                return;
            }
            Incoming::Command { id: None, .. } => {
                if self.awake && !self.broadcast {
                    self.send(now, 501, String::new());
                }
                return;
            }
            Incoming::Command { id: Some(id), data } => (id, data),
        };
        self.received.push(id);
        // Asleep: only WAKE (and SLEEP) matter.
        if !self.awake && !self.broadcast && !matches!(id, 85 | 86) {
            return;
        }
        let reply = self.command(now, id, &data);
        if let (Some((rid, text)), true) = (reply, self.awake && !self.broadcast) {
            self.send(now, rid, text);
        }
    }

    pub(super) fn send(&mut self, now: Instant, id: u16, data: String) {
        let due = now + self.response_time();
        self.outbox.push_back((due, hpr_wire::encode(id, &data)));
    }
}

/// A gas type code a CNC may select (table VI; 9, 10 and 12 are internal marking modes).
fn valid_gas(code: u16) -> bool {
    matches!(code, 1..=8 | 11)
}
