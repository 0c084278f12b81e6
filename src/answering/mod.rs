//! How a well-behaved MAVLink system answers probes: the pure part, shared
//! by the simulated link and by `mavping respond`.
//!
//! One reply per request, never more: a responder must not amplify. The
//! transfers (the parameter list, the mission, a file) are the exception
//! a ground station asks for: [`transfers`] queues what they draw, one
//! bounded list or burst at a time, for the caller to send at its pace.
//! Each protocol is in its own file: [`params`], [`mission`], [`ftp`].

pub(crate) mod ftp;
pub(crate) mod mission;
pub(crate) mod params;
pub(crate) mod transfers;

use crate::frame::{Frame, Msg, SysComp};

/// MAV_RESULT_ACCEPTED
const RESULT_ACCEPTED: u8 = 0;

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub(crate) struct ResponderCounts {
    pub(crate) ping_requests: u64,
    pub(crate) timesync_requests: u64,
    pub(crate) commands: u64,
    /// COMMAND_LONGs with `confirmation > 0`: re-sent because our ACK was
    /// lost or late. Each is acknowledged again.
    pub(crate) retransmissions: u64,
}

impl ResponderCounts {
    pub(crate) fn requests(&self) -> u64 {
        self.ping_requests + self.timesync_requests + self.commands
    }
}

#[derive(Debug, Clone)]
pub(crate) struct ResponderCore {
    pub(crate) id: SysComp,
    /// False to behave like ArduPilot: TIMESYNC only.
    pub(crate) answer_ping: bool,
    pub(crate) answer_timesync: bool,
    pub(crate) answer_commands: bool,
    pub(crate) counts: ResponderCounts,
}

impl ResponderCore {
    pub(crate) fn new(id: SysComp) -> Self {
        ResponderCore {
            id,
            answer_ping: true,
            answer_timesync: true,
            answer_commands: true,
            counts: ResponderCounts::default(),
        }
    }

    /// The reply to `frame`, if it is a request this responder answers.
    /// `clock_ns` is the responder's own clock, for TIMESYNC.
    pub(crate) fn answer(&mut self, frame: &Frame, clock_ns: i64) -> Option<Msg> {
        if frame.source == self.id {
            return None; // our own frame echoed back by a broadcast link
        }
        let to = frame.source;
        match frame.msg {
            Msg::Ping {
                time_usec,
                seq,
                target_system: 0,
                target_component: 0,
            } if self.answer_ping => {
                self.counts.ping_requests += 1;
                Some(Msg::Ping {
                    time_usec,
                    seq,
                    target_system: to.sysid,
                    target_component: to.compid,
                })
            }
            Msg::Timesync {
                tc1: 0,
                ts1,
                target_system,
                target_component,
            } if self.answer_timesync && self.addressed(target_system, target_component) => {
                self.counts.timesync_requests += 1;
                Some(Msg::Timesync {
                    // tc1 = 0 would make the answer a request.
                    tc1: if clock_ns == 0 { 1 } else { clock_ns },
                    ts1,
                    target_system: to.sysid,
                    target_component: to.compid,
                })
            }
            Msg::CommandLong {
                command,
                confirmation,
                target_system,
                target_component,
                ..
            } if self.answer_commands
                && target_system == self.id.sysid
                && (target_component == 0 || target_component == self.id.compid) =>
            {
                self.counts.commands += 1;
                self.counts.retransmissions += u64::from(confirmation > 0);
                Some(Msg::CommandAck {
                    command,
                    result: RESULT_ACCEPTED,
                    target_system: to.sysid,
                    target_component: to.compid,
                })
            }
            _ => None,
        }
    }

    /// Broadcast (0) or our own ids.
    fn addressed(&self, system: u8, component: u8) -> bool {
        (system == 0 || system == self.id.sysid) && (component == 0 || component == self.id.compid)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::test_frame as from;

    const GCS: SysComp = SysComp::new(255, 190);

    #[test]
    fn answers_ping_requests_only() {
        let mut r = ResponderCore::new(SysComp::new(1, 1));
        let request = Msg::Ping {
            time_usec: 77,
            seq: 3,
            target_system: 0,
            target_component: 0,
        };
        assert_eq!(
            r.answer(&from(GCS, request), 0),
            Some(Msg::Ping {
                time_usec: 77,
                seq: 3,
                target_system: 255,
                target_component: 190
            })
        );
        // A reply (targets set) is not a request: answering it would loop.
        let reply = Msg::Ping {
            time_usec: 77,
            seq: 3,
            target_system: 1,
            target_component: 1,
        };
        assert_eq!(r.answer(&from(GCS, reply), 0), None);
        r.answer_ping = false;
        assert_eq!(r.answer(&from(GCS, request), 0), None);
        assert_eq!(r.counts.ping_requests, 1);
    }

    #[test]
    fn answers_timesync_and_commands() {
        let mut r = ResponderCore::new(SysComp::new(1, 1));
        let ts = Msg::Timesync {
            tc1: 0,
            ts1: 5,
            target_system: 0,
            target_component: 0,
        };
        assert_eq!(
            r.answer(&from(GCS, ts), 99),
            Some(Msg::Timesync {
                tc1: 99,
                ts1: 5,
                target_system: 255,
                target_component: 190
            })
        );
        let cmd = |target_system| Msg::CommandLong {
            command: 512,
            confirmation: u8::from(target_system == 1),
            target_system,
            target_component: 1,
            params: [0.0; 7],
        };
        assert!(matches!(
            r.answer(&from(GCS, cmd(1)), 0),
            Some(Msg::CommandAck { command: 512, .. })
        ));
        assert_eq!(r.answer(&from(GCS, cmd(2)), 0), None);
        assert_eq!((r.counts.commands, r.counts.retransmissions), (1, 1));
        assert_eq!(r.counts.requests(), 2);
    }
}
