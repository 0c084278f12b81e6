//! `--probe auto`: PING for everyone, and TIMESYNC for each responder that
//! shows it will not answer PING — it announces itself as ArduPilot in its
//! HEARTBEAT, or it sends HEARTBEAT but left [`SWITCH_AFTER`] PINGs
//! unanswered for a whole timeout. ArduPilot answers on the first try.
//!
//! Both requests of a slot carry one token, so one matcher counts every
//! responder, each by the one probe chosen for it: a PING reply counts for
//! a responder on PING, a TIMESYNC reply for one on TIMESYNC, and the other
//! kind is ignored (PX4 answers both; counted once). A responder switched
//! to TIMESYNC never answered a PING, so the matcher never opened its
//! window on one: the PINGs before its first TIMESYNC reply are not charged
//! to it (they show as its `not_charged`), exactly as for a responder that
//! joins late. From its first TIMESYNC reply on, every request counts.

use std::collections::HashMap;

use super::ping::PingProbe;
use super::timesync::TimesyncProbe;
use super::{Classified, EchoProbe, ProbeName};
use crate::engine::clock_offset::ClockSummary;
use crate::engine::link_io::WallAtZero;
use crate::engine::matcher::{Lookup, MAX_RESPONDERS};
use crate::engine::roster::AUTOPILOT_ARDUPILOT;
use crate::engine::Nanos;
use crate::frame::{mav_type, Frame, Msg, SysComp};

/// PINGs a responder heard by its HEARTBEAT may leave unanswered (the
/// first of them for a whole timeout) before it is asked by TIMESYNC:
/// enough that one lost PING or reply does not switch a PX4, few enough
/// that a run of `-c 10` still measures an ArduPilot that hides its kind.
pub(crate) const SWITCH_AFTER: u64 = 3;

/// What a responder heard by its HEARTBEAT is asked with.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Choice {
    /// Not decided yet: PINGs sent since it was heard, and when the first
    /// of them went.
    Waiting {
        pings: u64,
        first_ping: Option<Nanos>,
    },
    /// It answered a PING: PING for the rest of the run.
    Ping,
    /// TIMESYNC for the rest of the run.
    Timesync,
}

pub(crate) struct AutoProbe {
    ping: PingProbe,
    timesync: TimesyncProbe,
    timeout: Nanos,
    /// Tokens are µs since the epoch (PING's `time_usec`), strictly rising
    /// so TIMESYNC replies can be looked up by them; `ping_base_us` is the
    /// token at session time 0.
    ping_base_us: u64,
    last_token: u64,
    /// TIMESYNC's clock at session time 0, in ns (its `ts1` base).
    timesync_base_ns: u64,
    /// Bounded by [`MAX_RESPONDERS`], like the matcher.
    choices: HashMap<SysComp, Choice>,
    /// Whether any responder is on TIMESYNC (then every slot sends one).
    any_timesync: bool,
}

impl AutoProbe {
    /// `wall_start_us` as for [`PingProbe`]; `wall` as for [`TimesyncProbe`];
    /// `timeout` is the session's.
    pub(crate) fn new(wall_start_us: u64, wall: bool, timeout: Nanos) -> Self {
        AutoProbe {
            ping: PingProbe::new(wall_start_us),
            timesync: TimesyncProbe::new(SysComp::new(0, 0), wall),
            timeout,
            ping_base_us: wall_start_us,
            last_token: 0,
            timesync_base_ns: 0,
            choices: HashMap::new(),
            any_timesync: false,
        }
    }

    fn choose(&mut self, id: SysComp, choice: Choice) {
        self.any_timesync |= choice == Choice::Timesync;
        self.choices.insert(id, choice);
    }

    fn choice(&self, id: SysComp) -> Option<Choice> {
        self.choices.get(&id).copied()
    }

    /// A HEARTBEAT from `id`: a new responder waits for its PINGs, unless
    /// it says it is ArduPilot.
    fn heard_heartbeat(&mut self, id: SysComp, autopilot: u8) {
        if self.choices.contains_key(&id) || self.choices.len() >= MAX_RESPONDERS {
            return;
        }
        let choice = if autopilot == AUTOPILOT_ARDUPILOT {
            Choice::Timesync
        } else {
            Choice::Waiting {
                pings: 0,
                first_ping: None,
            }
        };
        self.choose(id, choice);
    }

    /// A PING goes at `now`: it counts for every responder still waiting,
    /// and those that have left enough unanswered switch first.
    fn ping_sent(&mut self, now: Nanos) {
        let timeout = self.timeout;
        let mut switched = false;
        for choice in self.choices.values_mut() {
            if let Choice::Waiting { pings, first_ping } = choice {
                let waited = first_ping.is_some_and(|f| now >= f.saturating_add(timeout));
                if *pings >= SWITCH_AFTER && waited {
                    *choice = Choice::Timesync;
                    switched = true;
                } else {
                    *pings += 1;
                    first_ping.get_or_insert(now);
                }
            }
        }
        self.any_timesync |= switched;
    }

    /// The TIMESYNC `ts1` that carries `token`.
    fn ts1_of(&self, token: u64) -> i64 {
        let since_zero_ns = token
            .saturating_sub(self.ping_base_us)
            .saturating_mul(1_000);
        self.timesync_base_ns.saturating_add(since_zero_ns) as i64
    }

    /// The token a TIMESYNC reply's `ts1` echoes, or 0 (never a token) when
    /// it is not one of ours.
    fn token_of(&self, ts1: i64) -> u64 {
        let since_zero_ns = (ts1 as u64).wrapping_sub(self.timesync_base_ns);
        if ts1 < 0 || (ts1 as u64) < self.timesync_base_ns || !since_zero_ns.is_multiple_of(1_000) {
            return 0;
        }
        self.ping_base_us.saturating_add(since_zero_ns / 1_000)
    }
}

impl EchoProbe for AutoProbe {
    fn begin(&mut self, wall_at_zero: WallAtZero) {
        self.timesync.begin(wall_at_zero);
        self.timesync_base_ns = self.timesync.base_ns();
    }

    fn name(&self) -> ProbeName {
        ProbeName::Auto
    }

    fn token(&mut self, now_ns: u64) -> u64 {
        let token = self.ping.token(now_ns).max(self.last_token + 1);
        self.last_token = token;
        self.ping_sent(now_ns);
        token
    }

    fn request(&self, seq: u32, token: u64) -> Msg {
        self.ping.request(seq, token)
    }

    fn second_request(&self, _seq: u32, token: u64) -> Option<Msg> {
        self.any_timesync.then(|| Msg::Timesync {
            tc1: 0,
            ts1: self.ts1_of(token),
            target_system: 0,
            target_component: 0,
        })
    }

    fn heard(&mut self, frame: &Frame, ours: SysComp) {
        match frame.msg {
            // A ground station or router (QGroundControl, MAVProxy) answers
            // neither probe: asking it by TIMESYNC too would only double
            // what goes on the link.
            Msg::Heartbeat { mav_type, .. } if mav_type == mav_type::GCS => {}
            Msg::Heartbeat { autopilot, .. } if frame.source != ours => {
                self.heard_heartbeat(frame.source, autopilot);
            }
            // A PING answered (in time or not) keeps its responder on PING,
            // or takes it back to PING while no TIMESYNC of ours was
            // answered (a HEARTBEAT that says ArduPilot, from a system that
            // answers PING).
            Msg::Ping { .. } => {
                let answered = matches!(self.ping.classify(frame, ours), Classified::Reply(_));
                let undecided = self.choice(frame.source) != Some(Choice::Timesync)
                    || self.timesync.clock(frame.source).is_none();
                if answered
                    && undecided
                    && (self.choices.len() < MAX_RESPONDERS
                        || self.choices.contains_key(&frame.source))
                {
                    self.choose(frame.source, Choice::Ping);
                }
            }
            _ => {}
        }
    }

    fn classify(&self, frame: &Frame, ours: SysComp) -> Classified {
        let timesync = self.choice(frame.source) == Some(Choice::Timesync);
        match frame.msg {
            Msg::Ping { .. } if timesync => Classified::NotAReply,
            Msg::Ping { .. } => self.ping.classify(frame, ours),
            Msg::Timesync { .. } if !timesync => Classified::NotAReply,
            Msg::Timesync { ts1, .. } => match self.timesync.classify(frame, ours) {
                Classified::Reply(_) => Classified::Reply(Lookup::Token(self.token_of(ts1))),
                other => other,
            },
            _ => Classified::NotAReply,
        }
    }

    fn on_reply(&mut self, frame: &Frame, sent_at: Nanos, at: Nanos) {
        if matches!(frame.msg, Msg::Timesync { .. }) {
            self.timesync.on_reply(frame, sent_at, at);
        }
    }

    fn measures_clocks(&self) -> bool {
        self.any_timesync
    }

    fn clock(&self, responder: SysComp) -> Option<ClockSummary> {
        self.timesync.clock(responder)
    }

    fn clock_base_ns(&self) -> i128 {
        self.timesync.clock_base_ns()
    }

    fn used_by(&self, responder: SysComp) -> Option<ProbeName> {
        Some(match self.choice(responder) {
            Some(Choice::Timesync) => ProbeName::Timesync,
            _ => ProbeName::Ping,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::test_frame as frame;

    const US: SysComp = SysComp::new(250, 190);
    const PX4: SysComp = SysComp::new(1, 1);
    const ARDU: SysComp = SysComp::new(2, 1);
    const SECOND: Nanos = 1_000_000_000;

    fn heartbeat(source: SysComp, autopilot: u8) -> Frame {
        frame(
            source,
            Msg::Heartbeat {
                mav_type: 2,
                autopilot,
            },
        )
    }

    fn ping_reply(source: SysComp, seq: u32, token: u64) -> Frame {
        frame(
            source,
            Msg::Ping {
                time_usec: token,
                seq,
                target_system: US.sysid,
                target_component: US.compid,
            },
        )
    }

    fn timesync_reply(source: SysComp, ts1: i64) -> Frame {
        frame(
            source,
            Msg::Timesync {
                tc1: 77,
                ts1,
                target_system: 0,
                target_component: 0,
            },
        )
    }

    fn probe() -> AutoProbe {
        let mut p = AutoProbe::new(5_000_000, false, 2 * SECOND);
        p.begin(WallAtZero::exactly(std::time::UNIX_EPOCH));
        p
    }

    #[test]
    fn an_ardupilot_heartbeat_switches_at_once_and_its_pings_are_ignored() {
        let mut p = probe();
        assert_eq!(p.second_request(0, p.last_token), None);
        p.heard(&heartbeat(ARDU, AUTOPILOT_ARDUPILOT), US);
        let token = p.token(10_000);
        assert_eq!(token, 5_000_010);
        assert_eq!(
            p.second_request(0, token),
            Some(Msg::Timesync {
                tc1: 0,
                ts1: 10_000,
                target_system: 0,
                target_component: 0
            })
        );
        assert_eq!(
            p.classify(&timesync_reply(ARDU, 10_000), US),
            Classified::Reply(Lookup::Token(token))
        );
        // Not a ts1 of ours: a token never issued (stale).
        assert_eq!(
            p.classify(&timesync_reply(ARDU, 10_001), US),
            Classified::Reply(Lookup::Token(0))
        );
        assert_eq!(
            p.classify(&ping_reply(ARDU, 0, token), US),
            Classified::NotAReply
        );
        assert_eq!(p.used_by(ARDU), Some(ProbeName::Timesync));
        assert!(p.measures_clocks());
    }

    #[test]
    fn a_silent_responder_switches_after_three_pings_and_a_timeout() {
        let mut p = probe();
        p.heard(&heartbeat(PX4, 12), US);
        for i in 0..3 {
            p.token(i * SECOND / 2);
            assert_eq!(p.used_by(PX4), Some(ProbeName::Ping), "ping {i}");
        }
        // Three sent, but the first has not had its whole timeout yet.
        p.token(SECOND + SECOND / 2);
        assert_eq!(p.used_by(PX4), Some(ProbeName::Ping));
        let token = p.token(2 * SECOND);
        assert_eq!(p.used_by(PX4), Some(ProbeName::Timesync));
        assert!(p.second_request(0, token).is_some());
    }

    #[test]
    fn a_responder_that_answers_ping_stays_on_ping_and_its_timesync_is_ignored() {
        let mut p = probe();
        p.heard(&heartbeat(PX4, 12), US);
        p.heard(&heartbeat(ARDU, AUTOPILOT_ARDUPILOT), US);
        let token = p.token(0);
        let reply = ping_reply(PX4, 0, token);
        p.heard(&reply, US);
        assert_eq!(
            p.classify(&reply, US),
            Classified::Reply(Lookup::Seq { seq: 0, token })
        );
        for i in 1..10 {
            p.token(i * SECOND);
        }
        assert_eq!(p.used_by(PX4), Some(ProbeName::Ping));
        assert_eq!(p.used_by(ARDU), Some(ProbeName::Timesync));
        assert_eq!(
            p.classify(&timesync_reply(PX4, 0), US),
            Classified::NotAReply
        );
        // A PING reply addressed elsewhere keeps nobody on PING.
        let mut q = probe();
        q.heard(&heartbeat(PX4, 12), US);
        q.heard(&ping_reply(PX4, 0, 1), SysComp::new(9, 9));
        for i in 0..5 {
            q.token(i * SECOND);
        }
        assert_eq!(q.used_by(PX4), Some(ProbeName::Timesync));
    }

    #[test]
    fn our_own_heartbeat_is_no_responder() {
        let mut p = probe();
        p.heard(&heartbeat(US, AUTOPILOT_ARDUPILOT), US);
        assert!(p.choices.is_empty());
        assert!(!p.measures_clocks());
    }

    #[test]
    fn a_ground_station_heard_draws_no_timesync() {
        let mut p = AutoProbe::new(1_000_000, false, SECOND);
        let gcs = frame(
            SysComp::new(255, 190),
            Msg::Heartbeat {
                mav_type: mav_type::GCS,
                autopilot: crate::frame::AUTOPILOT_INVALID,
            },
        );
        p.heard(&gcs, US);
        for k in 0..10 {
            let token = p.token(k * SECOND);
            assert_eq!(p.second_request(k as u32, token), None, "request {k}");
        }
        assert_eq!(p.used_by(SysComp::new(255, 190)), Some(ProbeName::Ping));
    }

    #[test]
    fn a_heartbeat_that_says_ardupilot_from_a_system_answering_ping_goes_back_to_ping() {
        let mut p = AutoProbe::new(1_000_000, false, SECOND);
        p.heard(&heartbeat(ARDU, AUTOPILOT_ARDUPILOT), US);
        let token = p.token(0);
        let reply = frame(
            ARDU,
            Msg::Ping {
                time_usec: token,
                seq: 0,
                target_system: US.sysid,
                target_component: US.compid,
            },
        );
        assert_eq!(p.used_by(ARDU), Some(ProbeName::Timesync));
        p.heard(&reply, US);
        assert_eq!(p.used_by(ARDU), Some(ProbeName::Ping));
        assert!(matches!(p.classify(&reply, US), Classified::Reply(_)));
    }
}
