//! The MAVLink PING protocol: request with targets 0/0, reply echoes
//! `time_usec` and `seq` with the targets set to the pinger's ids.

use super::{Classified, EchoProbe, ProbeName};
use crate::engine::matcher::Lookup;
use crate::frame::{Frame, Msg, SysComp};

pub struct PingProbe {
    /// Wall-clock µs at session start: time_usec is sent as wall time so a
    /// peer's logs make sense, but advanced by the monotonic session clock
    /// so a clock step cannot make two requests share a token.
    wall_start_us: u64,
    /// Put in every token's low four bits: the link's number among
    /// several, so that two links' requests sent in the same µs differ
    /// (as TIMESYNC's carry it, after MAVProxy's `ping`).
    out_link: Option<u8>,
}

impl PingProbe {
    pub fn new(wall_start_us: u64) -> Self {
        PingProbe {
            wall_start_us,
            out_link: None,
        }
    }

    /// Tokens carrying `link` (below 16) in their low four bits; the
    /// `time_usec` sent is then 16 µs coarser.
    pub(crate) fn with_out_link(mut self, link: u8) -> Self {
        self.out_link = (link < 16).then_some(link);
        self
    }
}

impl EchoProbe for PingProbe {
    fn name(&self) -> ProbeName {
        ProbeName::Ping
    }

    fn token(&mut self, now_ns: u64) -> u64 {
        let us = self.wall_start_us + now_ns / 1_000;
        match self.out_link {
            Some(link) => (us & !0xF) | u64::from(link),
            None => us,
        }
    }

    fn request(&self, seq: u32, token: u64) -> Msg {
        Msg::Ping {
            time_usec: token,
            seq,
            target_system: 0,
            target_component: 0,
        }
    }

    fn classify(&self, frame: &Frame, ours: SysComp) -> Classified {
        match frame.msg {
            Msg::Ping {
                target_system: 0,
                target_component: 0,
                ..
            } => Classified::NotAReply, // someone else's request
            Msg::Ping {
                time_usec,
                seq,
                target_system,
                target_component,
            } => {
                if SysComp::new(target_system, target_component) == ours {
                    Classified::Reply(Lookup::Seq {
                        seq,
                        token: time_usec,
                    })
                } else {
                    Classified::ForeignReply
                }
            }
            _ => Classified::NotAReply,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Version;

    fn frame(msg: Msg) -> Frame {
        Frame {
            version: Version::V2,
            source: SysComp::new(1, 1),
            packet_seq: 0,
            msgid: 4,
            signed: false,
            len: 0,
            crc: 0,
            msg,
            stamps: crate::frame::Stamps::default(),
        }
    }

    fn ping(target_system: u8, target_component: u8) -> Msg {
        Msg::Ping {
            time_usec: 5,
            seq: 9,
            target_system,
            target_component,
        }
    }

    #[test]
    fn only_replies_to_our_ids_are_ours() {
        let probe = PingProbe::new(0);
        let us = SysComp::new(255, 190);
        assert_eq!(
            probe.classify(&frame(ping(255, 190)), us),
            Classified::Reply(Lookup::Seq { seq: 9, token: 5 })
        );
        assert_eq!(
            probe.classify(&frame(ping(0, 0)), us),
            Classified::NotAReply
        );
        assert_eq!(
            probe.classify(&frame(ping(255, 1)), us),
            Classified::ForeignReply
        );
        assert_eq!(
            probe.classify(
                &frame(Msg::Heartbeat {
                    mav_type: 2,
                    autopilot: 12
                }),
                us
            ),
            Classified::NotAReply
        );
    }

    #[test]
    fn requests_are_broadcast_with_targets_zero() {
        let mut probe = PingProbe::new(1_000_000);
        let token = probe.token(2_500);
        assert_eq!(token, 1_000_002);
        assert_eq!(
            probe.request(7, token),
            Msg::Ping {
                time_usec: 1_000_002,
                seq: 7,
                target_system: 0,
                target_component: 0
            }
        );
    }
}
