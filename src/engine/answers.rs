//! The vehicle's clock questions, answered as a ground station does: a
//! TIMESYNC request (ArduPilot's GCS failsafe work relies on the ground
//! answering them) and a PING request addressed to us or to all (PX4
//! streams them to the ground), from our own ids, one reply per request,
//! on the path the request came by and in its MAVLink version. Counted
//! for the summary; `--no-answer` turns it off.

use crate::answering::{ResponderCore, ResponderCounts};
use crate::frame::{Frame, Msg, SysComp, Version};
use crate::transport::{LinkError, PathId, Transport};

use super::link_io::Sender;
use super::Nanos;

/// Replies waiting for the next turn of the session: a burst of requests
/// beyond this many between two turns is not answered (and counted), so
/// a flood of requests cannot grow memory.
const MOST_PENDING: usize = 64;

/// The requests answered so far and the replies still to send.
pub(crate) struct Answers {
    /// `None`: answering is off.
    core: Option<ResponderCore>,
    pending: Vec<(Msg, Version, PathId)>,
    /// Requests taken but not answered: more than [`MOST_PENDING`] at
    /// once.
    unanswered: u64,
}

impl Answers {
    pub(crate) fn new(ours: SysComp, on: bool) -> Self {
        let core = on.then(|| {
            let mut core = ResponderCore::new(ours);
            // A ground station acknowledges no commands: it is not their
            // target, and an ACK from it would read as the vehicle's.
            core.answer_commands = false;
            core
        });
        Answers {
            core,
            pending: Vec::new(),
            unanswered: 0,
        }
    }

    /// Takes a received frame at session time `at`; a request gets its
    /// reply queued. TIMESYNC's `tc1` is our session clock (ns since the
    /// run started, as an autopilot's is since it booted), never 0, which
    /// would make the reply a request.
    pub(crate) fn take(&mut self, frame: &Frame, path: PathId, at: Nanos) {
        let Some(core) = self.core.as_mut() else {
            return;
        };
        let clock_ns = i64::try_from(at).unwrap_or(i64::MAX).max(1);
        let Some(reply) = core.answer(frame, clock_ns) else {
            return;
        };
        if self.pending.len() >= MOST_PENDING {
            self.unanswered += 1;
            return;
        }
        self.pending.push((reply, frame.version, path));
    }

    /// Sends the replies queued since the last turn.
    pub(crate) async fn send<T: Transport>(
        &mut self,
        link: &mut T,
        sender: &mut Sender,
    ) -> Result<(), LinkError> {
        for (reply, version, path) in self.pending.drain(..) {
            link.send_to(path, sender.frame_as(version, &reply)).await?;
        }
        Ok(())
    }

    /// What was answered, for the summary: requests by kind, and those
    /// left unanswered in a flood.
    pub(crate) fn summary(&self) -> AnswerSummary {
        AnswerSummary {
            counts: self.core.as_ref().map(|c| c.counts).unwrap_or_default(),
            unanswered: self.unanswered,
        }
    }
}

/// The vehicle's requests mavping took (`answered` in the summaries),
/// by kind, and of them those left unanswered in a flood: written only
/// when there were some.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub(crate) struct AnswerSummary {
    #[serde(flatten)]
    pub(crate) counts: ResponderCounts,
    pub(crate) unanswered: u64,
}

impl AnswerSummary {
    /// No request was heard (answered or not).
    pub(crate) fn is_none(&self) -> bool {
        self.counts.requests() + self.unanswered == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::test_frame;

    const VEHICLE: SysComp = SysComp::new(1, 1);
    const OURS: SysComp = SysComp::new(255, 190);

    fn timesync_request() -> Msg {
        Msg::Timesync {
            tc1: 0,
            ts1: 42,
            target_system: 0,
            target_component: 0,
        }
    }

    #[test]
    fn answers_timesync_and_ping_requests_once_each_and_no_commands() {
        let mut a = Answers::new(OURS, true);
        let ping = Msg::Ping {
            time_usec: 7,
            seq: 3,
            target_system: 0,
            target_component: 0,
        };
        let command = Msg::CommandLong {
            command: 400,
            confirmation: 0,
            target_system: 255,
            target_component: 190,
            params: [0.0; 7],
        };
        for msg in [timesync_request(), ping, command] {
            a.take(&test_frame(VEHICLE, msg), PathId::default(), 5_000);
        }
        let replies: Vec<Msg> = a.pending.iter().map(|p| p.0).collect();
        assert_eq!(
            replies,
            [
                Msg::Timesync {
                    tc1: 5_000,
                    ts1: 42,
                    target_system: 1,
                    target_component: 1
                },
                Msg::Ping {
                    time_usec: 7,
                    seq: 3,
                    target_system: 1,
                    target_component: 1
                }
            ]
        );
        let s = a.summary();
        assert_eq!((s.counts.timesync_requests, s.counts.ping_requests), (1, 1));
        assert_eq!(s.counts.commands, 0);
        assert!(!s.is_none());
    }

    #[test]
    fn replies_and_our_own_echo_are_not_requests_and_off_answers_nothing() {
        let mut a = Answers::new(OURS, true);
        let reply = Msg::Timesync {
            tc1: 9,
            ts1: 42,
            target_system: 255,
            target_component: 190,
        };
        a.take(&test_frame(VEHICLE, reply), PathId::default(), 1);
        a.take(&test_frame(OURS, timesync_request()), PathId::default(), 1);
        assert!(a.pending.is_empty() && a.summary().is_none());
        let mut off = Answers::new(OURS, false);
        off.take(
            &test_frame(VEHICLE, timesync_request()),
            PathId::default(),
            1,
        );
        assert!(off.pending.is_empty() && off.summary().is_none());
    }

    #[test]
    fn a_flood_between_two_turns_is_answered_up_to_a_bound_and_counted() {
        let mut a = Answers::new(OURS, true);
        for _ in 0..MOST_PENDING + 10 {
            a.take(
                &test_frame(VEHICLE, timesync_request()),
                PathId::default(),
                1,
            );
        }
        assert_eq!(a.pending.len(), MOST_PENDING);
        assert_eq!(a.summary().unanswered, 10);
        // At session time 0 the clock still reads 1: tc1 = 0 is a request.
        let mut a = Answers::new(OURS, true);
        a.take(
            &test_frame(VEHICLE, timesync_request()),
            PathId::default(),
            0,
        );
        assert!(matches!(a.pending[0].0, Msg::Timesync { tc1: 1, .. }));
    }
}
