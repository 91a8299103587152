//! Passing an HPR line to another unit: SLEEP (086) puts every unit to sleep, WAKE (085)
//! with an id wakes that one, which echoes the WAKE (HPR manual, 002_72b43a5685974c77.txt,
//! lines 107-109 and 172-173). Only a unit with id 0 powers up awake (lines 107-108), and a
//! unit woken by an earlier master may still be: so at start the line is taken to be in an
//! unknown state and a SLEEP goes before the first WAKE.
//!
//! [`Awake`] is what the arbiter knows of the line; [`Switch`] is one hand-over in progress.
//! The rule that keeps two transmitters off the line: a WAKE goes out only when no unit can
//! be awake (after a SLEEP, with no WAKE since) or the unit it wakes is the one awake.
//!
//! The WAKE follows the SLEEP as soon as the SLEEP has left the wire: the manual asks for no
//! pause, a unit handles the frames in the order they arrive, and the WAKE's own eight
//! characters (4 ms at 19200 baud) give every unit the time to handle the SLEEP before the
//! WAKE is complete. (A link's own SLEEP, in its detection, waits `SLEEP_QUIET` as a
//! request without reply; on a shared line that wait would be paid at every hand-over.)

use heapless::Vec;
use plasma_protocol::hpr::Request;
use plasma_protocol::time::{Duration, Instant};

/// Longest SLEEP or WAKE frame (`>0851CE<`).
pub(super) const CONTROL_CAPACITY: usize = 8;

/// What the arbiter knows about which unit has its transmitter enabled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Awake {
    /// Any unit may be (power-up, a WAKE whose echo never came).
    Unknown,
    /// None: a SLEEP went out and no WAKE since.
    Nobody,
    /// At most this id.
    Unit(u8),
}

/// What a switch puts on the line next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum SwitchOut {
    /// Nothing yet: the SLEEP is still on the wire, or the WAKE echo is awaited.
    Wait,
    /// SLEEP to every unit.
    Sleep,
    /// WAKE this id.
    Wake(u8),
    /// The line is the unit's: its attempt goes out.
    Held,
    /// The WAKE was not answered by its time-out: the unit is not listening.
    Failed,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    Sleep,
    /// SLEEP handed out: it is on the wire until then.
    Sleeping {
        until: Instant,
    },
    Wake,
    /// WAKE handed out: its echo is awaited until `deadline`.
    Echo {
        deadline: Instant,
        echoes: u8,
        heard_other: bool,
    },
    Held,
}

/// One hand-over of the line to the unit `target` (SLEEP first when some unit may be awake).
/// `target` None: SLEEP only, the unit's own WAKE follows (its detection sends one).
#[derive(Debug, Clone)]
pub(super) struct Switch {
    target: Option<u8>,
    step: Step,
    /// The WAKE's reply time-out (the target unit's).
    timeout: Duration,
    /// The line echoes our own frames: the WAKE's first copy is ours.
    line_echoes: bool,
    /// The frame being received while the echo is awaited.
    rx: Vec<u8, CONTROL_CAPACITY>,
    at: Instant,
}

impl Switch {
    /// What must go out, with the line in state `awake`, before unit `id` sends a request
    /// (`own_wake`: before it sends its own WAKE, as its detection does). None when nothing.
    pub(super) fn plan(
        awake: Awake,
        id: u8,
        own_wake: bool,
        timeout: Duration,
        line_echoes: bool,
        now: Instant,
    ) -> Option<Switch> {
        let (target, step) = match (awake, own_wake) {
            (Awake::Unit(a), _) if a == id => return None,
            (Awake::Nobody, true) => return None,
            (_, true) => (None, Step::Sleep),
            (Awake::Nobody, false) => (Some(id), Step::Wake),
            (_, false) => (Some(id), Step::Sleep),
        };
        Some(Switch {
            target,
            step,
            timeout,
            line_echoes,
            rx: Vec::new(),
            at: now,
        })
    }

    /// What goes on the line now.
    pub(super) fn poll(&mut self, now: Instant) -> SwitchOut {
        self.at = now;
        match self.step {
            Step::Sleep => {
                self.step = Step::Sleeping { until: now };
                SwitchOut::Sleep
            }
            Step::Sleeping { until } if now < until => SwitchOut::Wait,
            Step::Sleeping { .. } | Step::Wake => match self.target {
                Some(id) => {
                    self.step = Step::Echo {
                        deadline: now + self.timeout,
                        echoes: 0,
                        heard_other: false,
                    };
                    SwitchOut::Wake(id)
                }
                None => {
                    self.step = Step::Held;
                    SwitchOut::Held
                }
            },
            Step::Echo {
                echoes,
                heard_other,
                deadline,
            } => {
                let needed = if self.line_echoes { 2 } else { 1 };
                if echoes >= needed || (heard_other && !self.in_frame()) {
                    // A damaged echo still shows a unit that listens: its reply tells.
                    self.step = Step::Held;
                    SwitchOut::Held
                } else if now >= deadline {
                    if heard_other {
                        self.step = Step::Held;
                        SwitchOut::Held
                    } else {
                        SwitchOut::Failed
                    }
                } else {
                    SwitchOut::Wait
                }
            }
            Step::Held => SwitchOut::Held,
        }
    }

    /// When [`Switch::poll`] has something to do.
    pub(super) fn poll_at(&self) -> Instant {
        match self.step {
            Step::Sleeping { until } => until,
            Step::Echo { deadline, .. } => deadline,
            Step::Sleep | Step::Wake | Step::Held => self.at,
        }
    }

    /// The frame handed out last left the wire at `at`: the WAKE follows the SLEEP from
    /// there, the echo's time-out runs from there (never earlier). True when it was the WAKE.
    pub(super) fn transmitted(&mut self, at: Instant) -> bool {
        match &mut self.step {
            Step::Sleeping { until } => {
                *until = (*until).max(at);
                false
            }
            Step::Echo { deadline, .. } => {
                *deadline = (*deadline).max(at + self.timeout);
                true
            }
            _ => false,
        }
    }

    /// Bytes heard. A copy of the SLEEP (which no unit answers) is the line echoing our own
    /// requests (2-wire, receiver on): the WAKE's first copy is then ours, the unit's echo is
    /// the second. While the echo is awaited, a frame equal to the WAKE counts as an echo, any
    /// other frame as a damaged one. Returns the characters heard outside a frame (stray).
    pub(super) fn hear(&mut self, bytes: &[u8]) -> usize {
        let mut stray = 0;
        for &byte in bytes {
            if byte == b'>' {
                if !self.rx.is_empty() {
                    self.heard_other();
                }
                self.rx.clear();
            } else if self.rx.is_empty() {
                stray += 1;
                continue;
            }
            if self.rx.push(byte).is_err() {
                self.heard_other();
                self.rx.clear();
                continue;
            }
            if byte == b'<' {
                self.heard_frame();
                self.rx.clear();
            }
        }
        stray
    }

    /// A whole frame is in `rx`.
    fn heard_frame(&mut self) {
        let mut control = [0u8; CONTROL_CAPACITY];
        let sleep_len = emit_control(None, &mut control);
        if Some(self.rx.as_slice()) == control.get(..sleep_len) {
            self.line_echoes = true;
            return;
        }
        let wake_len = emit_control(self.target, &mut control);
        let is_wake = self.target.is_some() && Some(self.rx.as_slice()) == control.get(..wake_len);
        if let Step::Echo {
            echoes,
            heard_other,
            ..
        } = &mut self.step
        {
            if is_wake {
                *echoes = echoes.saturating_add(1);
            } else {
                *heard_other = true;
            }
        }
    }

    fn heard_other(&mut self) {
        if let Step::Echo { heard_other, .. } = &mut self.step {
            *heard_other = true;
        }
    }

    /// True once the line has been heard echoing our own frames.
    pub(super) fn line_echoes(&self) -> bool {
        self.line_echoes
    }

    /// A character received in error while the echo is awaited: a damaged echo.
    pub(super) fn hear_error(&mut self) {
        if let Step::Echo { heard_other, .. } = &mut self.step {
            *heard_other = true;
        }
    }

    fn in_frame(&self) -> bool {
        !self.rx.is_empty()
    }
}

/// The SLEEP frame, or WAKE `id`, into `out`; its length (0 if it does not fit).
pub(super) fn emit_control(sleep_or_wake: Option<u8>, out: &mut [u8; CONTROL_CAPACITY]) -> usize {
    let request = match sleep_or_wake {
        None => Request::Sleep,
        Some(system_id) => Request::Wake { system_id },
    };
    request.emit(out).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    const T100: Duration = Duration::from_millis(100);
    const WAKE_1: &[u8] = b">0851CE<";

    fn ms(v: u64) -> Instant {
        Instant::from_millis(v)
    }

    fn to_unit_1(awake: Awake, line_echoes: bool) -> Switch {
        Switch::plan(awake, 1, false, T100, line_echoes, ms(0)).expect("a switch")
    }

    #[test]
    fn the_frames_a_switch_needs_follow_from_what_may_be_awake() {
        let plan = |awake, own_wake| Switch::plan(awake, 1, own_wake, T100, false, ms(0));
        assert!(plan(Awake::Unit(1), false).is_none(), "already awake");
        assert!(plan(Awake::Unit(1), true).is_none());
        assert!(plan(Awake::Nobody, true).is_none(), "its own WAKE may go");
        let mut sleep_only = plan(Awake::Unit(0), true).unwrap();
        assert_eq!(sleep_only.poll(ms(0)), SwitchOut::Sleep);
        sleep_only.transmitted(ms(4));
        assert_eq!(sleep_only.poll(ms(4)), SwitchOut::Held);
        assert_eq!(
            plan(Awake::Nobody, false).unwrap().poll(ms(0)),
            SwitchOut::Wake(1)
        );
        for awake in [Awake::Unknown, Awake::Unit(0)] {
            assert_eq!(plan(awake, false).unwrap().poll(ms(0)), SwitchOut::Sleep);
        }
    }

    #[test]
    fn the_wake_follows_the_sleep_once_it_has_left_the_wire() {
        let mut switch = to_unit_1(Awake::Unknown, false);
        assert_eq!(switch.poll(ms(0)), SwitchOut::Sleep);
        assert!(!switch.transmitted(ms(4)));
        assert_eq!(switch.poll_at(), ms(4));
        assert_eq!(switch.poll(ms(3)), SwitchOut::Wait);
        assert_eq!(switch.poll(ms(4)), SwitchOut::Wake(1));
        assert!(switch.transmitted(ms(8)), "the WAKE");
        assert_eq!(switch.poll_at(), ms(108), "its time-out runs from its end");
        assert_eq!(switch.hear(WAKE_1), 0);
        assert_eq!(switch.poll(ms(13)), SwitchOut::Held);
    }

    #[test]
    fn an_unanswered_wake_fails_at_its_time_out() {
        let mut switch = to_unit_1(Awake::Nobody, false);
        assert_eq!(switch.poll(ms(0)), SwitchOut::Wake(1));
        switch.transmitted(ms(4));
        assert_eq!(switch.poll(ms(103)), SwitchOut::Wait);
        assert_eq!(switch.poll(ms(104)), SwitchOut::Failed);
    }

    #[test]
    fn on_a_line_that_echoes_the_units_echo_is_the_second_copy() {
        let mut switch = to_unit_1(Awake::Nobody, true);
        assert_eq!(switch.poll(ms(0)), SwitchOut::Wake(1));
        switch.transmitted(ms(4));
        switch.hear(WAKE_1);
        assert_eq!(switch.poll(ms(4)), SwitchOut::Wait, "our own WAKE");
        switch.hear(&WAKE_1[..3]);
        switch.hear(&WAKE_1[3..]);
        assert_eq!(switch.poll(ms(10)), SwitchOut::Held);
    }

    #[test]
    fn a_copy_of_the_sleep_shows_a_line_that_echoes() {
        // Nobody answers SLEEP: a copy is our own, so the WAKE's first copy will be too.
        let mut switch = to_unit_1(Awake::Unknown, false);
        assert_eq!(switch.poll(ms(0)), SwitchOut::Sleep);
        switch.transmitted(ms(4));
        assert_eq!(switch.poll(ms(4)), SwitchOut::Wake(1));
        // A board hands the received characters over after its writes: both copies late.
        switch.hear(b">0869E<>0851CE<");
        assert!(switch.line_echoes());
        assert_eq!(switch.poll(ms(9)), SwitchOut::Wait);
        switch.hear(WAKE_1);
        assert_eq!(switch.poll(ms(13)), SwitchOut::Held);
    }

    #[test]
    fn a_damaged_echo_still_hands_the_line_over_once_complete() {
        let mut switch = to_unit_1(Awake::Nobody, false);
        assert_eq!(switch.poll(ms(0)), SwitchOut::Wake(1));
        switch.transmitted(ms(4));
        // Noise before the frame is stray; a wrong checksum is a damaged echo.
        assert_eq!(switch.hear(b"\x00\x00>0851"), 2);
        assert_eq!(switch.poll(ms(6)), SwitchOut::Wait);
        switch.hear(b"CF<");
        assert_eq!(switch.poll(ms(8)), SwitchOut::Held);
        // A character received in error, and nothing after it: at the time-out.
        let mut switch = to_unit_1(Awake::Nobody, false);
        switch.poll(ms(0));
        switch.transmitted(ms(4));
        switch.hear(b">08");
        switch.hear_error();
        assert_eq!(switch.poll(ms(50)), SwitchOut::Wait);
        assert_eq!(switch.poll(ms(104)), SwitchOut::Held);
    }

    #[test]
    fn the_control_frames_are_the_manuals() {
        // HPR manual lines 172-173: >0850CD< and >0869E<.
        let mut out = [0; CONTROL_CAPACITY];
        let len = emit_control(Some(0), &mut out);
        assert_eq!(&out[..len], b">0850CD<");
        let len = emit_control(None, &mut out);
        assert_eq!(&out[..len], b">0869E<");
    }
}
