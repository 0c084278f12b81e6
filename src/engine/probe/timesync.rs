//! The MAVLink TIMESYNC exchange: request `tc1 = 0`, `ts1 = our clock in
//! ns`; the reply carries `tc1 = their clock in ns` and the same `ts1`.
//! ArduPilot answers nothing else, so this is the probe that works on it.

use std::collections::HashMap;

use super::{Classified, EchoProbe, ProbeName};
use crate::engine::clock_offset::{ClockOffset, ClockSummary};
use crate::engine::link_io::WallAtZero;
use crate::engine::matcher::{Lookup, MAX_RESPONDERS};
use crate::engine::Nanos;
use crate::frame::{Frame, Msg, SysComp};

pub(crate) struct TimesyncProbe {
    /// What our clock reads at session time 0, in ns: wall time on real
    /// links (so offsets against a responder's wall clock mean something),
    /// advanced by the monotonic session clock so a clock step cannot
    /// repeat a token. 0 on the simulated link, whose responders count
    /// from its start.
    base_ns: i128,
    /// How far `base_ns` may be off the wall clock at time 0 (ns): the
    /// clock bounds widen by it.
    base_within_ns: i128,
    wall: bool,
    target: SysComp,
    last_token: u64,
    /// Put in every token's low four bits: the link's number among
    /// several, as MAVProxy's `ping` tells its out-link (0-15).
    out_link: Option<u8>,
    clocks: HashMap<SysComp, ClockOffset>,
}

impl TimesyncProbe {
    /// Requests to `target`; our clock is the wall clock when `wall`, else
    /// session time.
    pub(crate) fn new(target: SysComp, wall: bool) -> Self {
        TimesyncProbe {
            base_ns: 0,
            base_within_ns: 0,
            wall,
            target,
            last_token: 0,
            out_link: None,
            clocks: HashMap::new(),
        }
    }

    /// Tokens carrying `link` (below 16) in their low four bits; our
    /// clock in them is then 16 ns coarser.
    pub(crate) fn with_out_link(mut self, link: u8) -> Self {
        self.out_link = (link < 16).then_some(link);
        self
    }
}

impl TimesyncProbe {
    /// Our clock at session time 0, in ns (0 until `begin`, and on the
    /// simulated link).
    pub(crate) fn base_ns(&self) -> u64 {
        self.base_ns as u64
    }
}

impl EchoProbe for TimesyncProbe {
    fn name(&self) -> ProbeName {
        ProbeName::Timesync
    }

    fn begin(&mut self, wall_at_zero: WallAtZero) {
        if self.wall {
            self.base_ns = wall_at_zero
                .wall
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos() as i128);
            self.base_within_ns = wall_at_zero.within.as_nanos() as i128;
        }
    }

    fn token(&mut self, now_ns: u64) -> u64 {
        // Strictly rising (the matcher binary-searches tokens) and never 0.
        let clock = self.base_ns as u64 + now_ns;
        let token = match self.out_link {
            None => clock.max(self.last_token + 1),
            Some(link) => {
                let token = (clock & !0xF) | u64::from(link);
                // The next with the same low bits, when the clock has not
                // moved on by 16 ns.
                let token = if token > self.last_token {
                    token
                } else {
                    (self.last_token & !0xF) + 16 + u64::from(link)
                };
                if token == 0 {
                    16
                } else {
                    token
                }
            }
        };
        self.last_token = token;
        token
    }

    fn request(&self, _seq: u32, token: u64) -> Msg {
        Msg::Timesync {
            tc1: 0,
            ts1: token as i64,
            target_system: self.target.sysid,
            target_component: self.target.compid,
        }
    }

    fn classify(&self, frame: &Frame, ours: SysComp) -> Classified {
        match frame.msg {
            Msg::Timesync { tc1: 0, .. } => Classified::NotAReply, // a request
            Msg::Timesync {
                ts1,
                target_system,
                target_component,
                ..
            } => {
                // ArduPilot and MAVLink 1 stacks leave the targets 0/0:
                // only targets that are set can make a reply someone else's.
                let other_system = target_system != 0 && target_system != ours.sysid;
                let other_component = target_component != 0 && target_component != ours.compid;
                if other_system || other_component {
                    Classified::ForeignReply
                } else {
                    Classified::Reply(Lookup::Token(ts1 as u64))
                }
            }
            _ => Classified::NotAReply,
        }
    }

    fn on_reply(&mut self, frame: &Frame, sent_at: Nanos, at: Nanos) {
        let Msg::Timesync { tc1, ts1, .. } = frame.msg else {
            return;
        };
        // ts1 is our clock when the request was made, before it was
        // written: the earliest the responder can have read its clock.
        let made = u64::try_from(i128::from(ts1) - self.base_ns).unwrap_or(sent_at);
        let sent_at = sent_at.min(made);
        // The matcher tracks at most MAX_RESPONDERS; so do we.
        if self.clocks.len() >= MAX_RESPONDERS && !self.clocks.contains_key(&frame.source) {
            return;
        }
        self.clocks.entry(frame.source).or_default().record(
            sent_at,
            at,
            tc1,
            self.base_ns,
            self.base_within_ns,
        );
    }

    fn measures_clocks(&self) -> bool {
        true
    }

    fn clock(&self, responder: SysComp) -> Option<ClockSummary> {
        self.clocks.get(&responder).and_then(ClockOffset::summary)
    }

    fn clock_base_ns(&self) -> i128 {
        self.base_ns
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Version;

    const US: SysComp = SysComp::new(255, 190);

    fn reply(tc1: i64, ts1: i64, target_system: u8, target_component: u8) -> Frame {
        Frame {
            version: Version::V2,
            source: SysComp::new(1, 1),
            packet_seq: 0,
            msgid: 111,
            signed: false,
            len: 0,
            crc: 0,
            msg: Msg::Timesync {
                tc1,
                ts1,
                target_system,
                target_component,
            },
            stamps: crate::frame::Stamps::default(),
        }
    }

    #[test]
    fn replies_match_by_ts1_and_unset_targets_are_ours() {
        let p = TimesyncProbe::new(SysComp::new(0, 0), false);
        assert_eq!(
            p.classify(&reply(9, 42, 0, 0), US),
            Classified::Reply(Lookup::Token(42))
        );
        assert_eq!(
            p.classify(&reply(9, 42, 255, 190), US),
            Classified::Reply(Lookup::Token(42))
        );
        assert_eq!(
            p.classify(&reply(9, 42, 255, 0), US),
            Classified::Reply(Lookup::Token(42))
        );
        assert_eq!(
            p.classify(&reply(9, 42, 254, 0), US),
            Classified::ForeignReply
        );
        assert_eq!(
            p.classify(&reply(9, 42, 255, 1), US),
            Classified::ForeignReply
        );
        // tc1 = 0 is someone's request, not a reply.
        assert_eq!(p.classify(&reply(0, 42, 0, 0), US), Classified::NotAReply);
    }

    #[test]
    fn an_out_link_is_in_every_tokens_low_four_bits() {
        let mut p = TimesyncProbe::new(SysComp::new(0, 0), false).with_out_link(3);
        let tokens: Vec<u64> = [0, 0, 5, 1_000, 1_001, 1_000_007]
            .iter()
            .map(|&t| p.token(t))
            .collect();
        assert_eq!(tokens, [3, 19, 35, 995, 1_011, 1_000_003]);
        let mut zero = TimesyncProbe::new(SysComp::new(0, 0), false).with_out_link(0);
        assert_eq!(zero.token(0), 16);
        assert!(TimesyncProbe::new(SysComp::new(0, 0), false)
            .with_out_link(16)
            .out_link
            .is_none());
    }

    #[test]
    fn tokens_rise_strictly_and_are_never_zero() {
        let mut p = TimesyncProbe::new(SysComp::new(1, 1), false);
        assert_eq!(p.token(0), 1);
        assert_eq!(p.token(0), 2);
        assert_eq!(p.token(1_000), 1_000);
        assert_eq!(p.token(1_000), 1_001);
        assert_eq!(
            p.request(0, 7),
            Msg::Timesync {
                tc1: 0,
                ts1: 7,
                target_system: 1,
                target_component: 1
            }
        );
        let mut wall = TimesyncProbe::new(SysComp::new(0, 0), true);
        let at_zero = WallAtZero::exactly(
            std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000),
        );
        wall.begin(at_zero);
        assert_eq!(wall.token(5), 1_700_000_000_000_000_005);
        // Session time only, on the simulated link.
        let mut sim = TimesyncProbe::new(SysComp::new(0, 0), false);
        sim.begin(at_zero);
        assert_eq!(sim.token(5), 5);
    }

    #[test]
    fn offsets_are_kept_per_responder() {
        let mut p = TimesyncProbe::new(SysComp::new(0, 0), true);
        p.begin(WallAtZero::exactly(
            std::time::UNIX_EPOCH + std::time::Duration::from_micros(1),
        ));
        // Made at 100 (ts1 1_100), answered at 300: their clock read 5_200
        // between our 1_100 and 1_300.
        p.on_reply(&reply(5_200, 1_100, 0, 0), 100, 300);
        let c = p.clock(SysComp::new(1, 1)).unwrap();
        assert_eq!(c.offset_ns, 4_000);
        // Widened by 1 ns: what 200 ppm of drift could do in 300 ns,
        // rounded up.
        assert_eq!(c.bounds_ns, Some((3_899, 4_101)));
        assert_eq!(c.uncertainty_ns, 101);
        assert!(p.clock(SysComp::new(2, 1)).is_none());
    }

    #[test]
    fn bounds_widen_by_how_far_the_wall_clock_at_zero_may_be_off() {
        let mut p = TimesyncProbe::new(SysComp::new(0, 0), true);
        p.begin(WallAtZero {
            wall: std::time::UNIX_EPOCH + std::time::Duration::from_micros(1),
            within: std::time::Duration::from_nanos(50),
        });
        p.on_reply(&reply(5_200, 1_100, 0, 0), 100, 300);
        let c = p.clock(SysComp::new(1, 1)).unwrap();
        assert_eq!(c.bounds_ns, Some((3_849, 4_151)));
    }
}
