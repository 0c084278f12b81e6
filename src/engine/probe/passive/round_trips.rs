//! Round trips recovered from a telemetry log: each request a system
//! logged (TIMESYNC, PING, COMMAND_LONG) matched to the reply logged after
//! it, the RTT being the difference of their stamps. Pure and
//! synchronous: frames and their times in, figures per requester,
//! responder and kind out.
//!
//! How a reply names its request (the MAVLink services' rules, and what
//! pymavlink, MAVProxy, PX4 and ArduPilot send):
//! - TIMESYNC: a request has `tc1 == 0` and `ts1` the requester's clock;
//!   the reply mirrors `ts1` with `tc1 != 0`. Its targets name the
//!   requester where set; ArduPilot and pymavlink's dialect leave them 0,
//!   and then `ts1` alone finds the request.
//! - PING: a request has targets 0/0 (broadcast); the reply targets the
//!   requester's ids with the same `seq` and `time_usec`.
//! - COMMAND_LONG → COMMAND_ACK: the same command, the ACK's source the
//!   command's target (0 = any) and the ACK's target its sender (0 = any,
//!   for stacks that leave it). A repeat with `confirmation > 0` before
//!   any ACK is a retransmission: the RTT is measured from the last
//!   attempt before the ACK, and the match says it followed one.
//!
//! Memory is bounded: at most [`MAX_QUEUES`] (requester, kind) tables of
//! at most [`MAX_IN_FLIGHT`] requests (the oldest evicted and counted), a
//! ring of [`MAX_EXPIRED`] timed-out requests each (to tell a late reply
//! from one with no request), and [`MAX_PAIRS`] pairs of figures.

use std::collections::VecDeque;

use serde::Serialize;

use crate::engine::stats::{RttStats, RttSummary};
use crate::engine::Nanos;
use crate::frame::{Frame, Msg, SysComp};

/// Requests in flight kept per requester and kind.
pub(crate) const MAX_IN_FLIGHT: usize = 256;
/// Timed-out requests kept per requester and kind, for late replies.
pub(crate) const MAX_EXPIRED: usize = 64;
/// (requester, kind) tables kept.
pub(crate) const MAX_QUEUES: usize = 32;
/// (requester, responder, kind) figures kept.
pub(crate) const MAX_PAIRS: usize = 64;
/// Responders remembered per request (a broadcast PING answered by each
/// component of a vehicle).
const MAX_ANSWERS: usize = 8;
/// MAV_RESULT_IN_PROGRESS: more ACKs of the same command follow.
const IN_PROGRESS: u8 = 5;

/// Which exchange.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Kind {
    Timesync,
    Ping,
    Command,
}

impl Kind {
    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Kind::Timesync => "timesync",
            Kind::Ping => "ping",
            Kind::Command => "command",
        }
    }
}

/// What a reply must echo to answer a request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Key {
    Ts1(i64),
    Ping { seq: u32, time_usec: u64 },
    Command(u16),
}

/// One frame's part in an exchange.
enum Role {
    Request {
        key: Key,
        /// Who may answer: 0 in either field is any.
        target: SysComp,
        /// A COMMAND_LONG's `confirmation > 0`.
        retransmission: bool,
    },
    Reply {
        key: Key,
        /// The requester the reply names: 0 in either field is any.
        requester: SysComp,
        /// A COMMAND_ACK saying more ACKs follow.
        in_progress: bool,
    },
}

fn role(msg: &Msg) -> Option<(Kind, Role)> {
    Some(match *msg {
        Msg::Timesync {
            tc1: 0,
            ts1,
            target_system,
            target_component,
        } => (
            Kind::Timesync,
            Role::Request {
                key: Key::Ts1(ts1),
                target: SysComp::new(target_system, target_component),
                retransmission: false,
            },
        ),
        Msg::Timesync {
            ts1,
            target_system,
            target_component,
            ..
        } => (
            Kind::Timesync,
            Role::Reply {
                key: Key::Ts1(ts1),
                requester: SysComp::new(target_system, target_component),
                in_progress: false,
            },
        ),
        Msg::Ping {
            time_usec,
            seq,
            target_system: 0,
            target_component: 0,
        } => (
            Kind::Ping,
            Role::Request {
                key: Key::Ping { seq, time_usec },
                target: SysComp::new(0, 0),
                retransmission: false,
            },
        ),
        Msg::Ping {
            time_usec,
            seq,
            target_system,
            target_component,
        } => (
            Kind::Ping,
            Role::Reply {
                key: Key::Ping { seq, time_usec },
                requester: SysComp::new(target_system, target_component),
                in_progress: false,
            },
        ),
        Msg::CommandLong {
            command,
            confirmation,
            target_system,
            target_component,
            ..
        } => (
            Kind::Command,
            Role::Request {
                key: Key::Command(command),
                target: SysComp::new(target_system, target_component),
                retransmission: confirmation > 0,
            },
        ),
        Msg::CommandAck {
            command,
            result,
            target_system,
            target_component,
        } => (
            Kind::Command,
            Role::Reply {
                key: Key::Command(command),
                requester: SysComp::new(target_system, target_component),
                in_progress: result == IN_PROGRESS,
            },
        ),
        _ => return None,
    })
}

/// `pattern` names `id`: its 0 fields are any.
fn names(pattern: SysComp, id: SysComp) -> bool {
    (pattern.sysid == 0 || pattern.sysid == id.sysid)
        && (pattern.compid == 0 || pattern.compid == id.compid)
}

/// A request logged and not yet timed out.
#[derive(Debug, Clone)]
struct Request {
    key: Key,
    target: SysComp,
    /// The attempt the RTT is measured from (the last, for commands).
    at: Nanos,
    attempts: u32,
    /// Who answered it, and whether their last ACK said more follow.
    answers: Vec<(SysComp, bool)>,
}

impl Request {
    fn answered(&self) -> bool {
        !self.answers.is_empty()
    }
}

/// The requests of one requester and kind.
#[derive(Debug, Clone)]
struct Queue {
    requester: SysComp,
    kind: Kind,
    in_flight: VecDeque<Request>,
    /// Requests timed out unanswered: (key, target, at).
    expired: VecDeque<(Key, SysComp, Nanos)>,
    counts: RequestCounts,
}

/// The requests one system made of one kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub(crate) struct RequestCounts {
    /// Distinct requests.
    pub(crate) requests: u64,
    /// The same request logged again before it timed out: a duplicated
    /// frame, or a command's retransmission.
    pub(crate) repeats: u64,
    /// Pushed out of the table by newer ones while still in flight:
    /// neither matched nor unanswered.
    pub(crate) evicted: u64,
    /// Still within their timeout when the log ended, unanswered.
    pub(crate) in_flight_at_end: u64,
}

/// The figures of one requester → responder exchange.
#[derive(Clone, Default)]
struct Pair {
    rtt: RttStats,
    counts: PairCounts,
}

/// What came of the requests of one requester to one responder.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub(crate) struct PairCounts {
    /// Requests answered within the timeout: the RTT samples.
    pub(crate) matched: u64,
    /// Of those, commands answered after a retransmission (measured from
    /// the last attempt).
    pub(crate) after_retransmission: u64,
    /// Requests the responder did not answer within the timeout.
    pub(crate) unanswered: u64,
    /// Replies after the timeout to a request counted unanswered.
    pub(crate) late: u64,
    /// Replies to a request the responder had answered already.
    pub(crate) duplicate: u64,
    /// Replies that match no request in the log (made before it began,
    /// or not logged).
    pub(crate) no_request: u64,
}

/// One row of figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct PairSummary {
    pub(crate) kind: Kind,
    /// 0/0 where a reply does not name its requester.
    pub(crate) requester: SysComp,
    /// 0/0 for requests to anyone no responder was heard answering.
    pub(crate) responder: SysComp,
    #[serde(flatten)]
    pub(crate) counts: PairCounts,
    pub(crate) rtt: Option<RttSummary>,
}

/// One requester's requests of a kind.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct RequesterSummary {
    pub(crate) kind: Kind,
    pub(crate) requester: SysComp,
    #[serde(flatten)]
    pub(crate) counts: RequestCounts,
}

/// Every round trip recovered. Serialised as the `round_trips` of the
/// JSON `passive_summary`, in this order, after what the line adds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct RoundTripSummary {
    /// A request not answered within this is unanswered (`-W`).
    pub(crate) timeout_s: f64,
    pub(crate) pairs: Vec<PairSummary>,
    pub(crate) requesters: Vec<RequesterSummary>,
    /// Requests and replies beyond the tables' caps: counted, not matched.
    pub(crate) untracked: u64,
}

/// The matcher: see the module's rules.
#[derive(Debug, Clone)]
pub(crate) struct RoundTrips {
    timeout: Nanos,
    queues: Vec<Queue>,
    pairs: Vec<((Kind, SysComp, SysComp), Pair)>,
    untracked: u64,
}

impl std::fmt::Debug for Pair {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pair")
            .field("counts", &self.counts)
            .finish_non_exhaustive()
    }
}

impl RoundTrips {
    pub(crate) fn new(timeout: Nanos) -> Self {
        RoundTrips {
            timeout,
            queues: Vec::new(),
            pairs: Vec::new(),
            untracked: 0,
        }
    }

    /// Takes one logged frame at its time; a reply that completes a
    /// round trip within the timeout gives its requester and RTT.
    pub(crate) fn on_frame(&mut self, frame: &Frame, at: Nanos) -> Option<(SysComp, Nanos)> {
        let (kind, role) = role(&frame.msg)?;
        self.expire(at);
        match role {
            Role::Request {
                key,
                target,
                retransmission,
            } => {
                self.request(kind, frame.source, key, target, retransmission, at);
                None
            }
            Role::Reply {
                key,
                requester,
                in_progress,
            } => self.reply(kind, frame.source, key, requester, in_progress, at),
        }
    }

    fn request(
        &mut self,
        kind: Kind,
        requester: SysComp,
        key: Key,
        target: SysComp,
        retransmission: bool,
        at: Nanos,
    ) {
        let Some(q) = self.queue(requester, kind) else {
            self.untracked += 1;
            return;
        };
        let queue = &mut self.queues[q];
        let same = |r: &Request| r.key == key && r.target == target;
        let repeat = match kind {
            // A retransmission restarts the clock of the command it repeats.
            Kind::Command => queue
                .in_flight
                .iter_mut()
                .rev()
                .find(|r| same(r) && !r.answered())
                .filter(|_| retransmission),
            // The same ts1 or seq again is the same request, logged twice.
            Kind::Timesync | Kind::Ping => queue.in_flight.iter_mut().rev().find(|r| same(r)),
        };
        if let Some(r) = repeat {
            queue.counts.repeats += 1;
            if kind == Kind::Command {
                r.attempts += 1;
                r.at = at;
            }
            return;
        }
        queue.counts.requests += 1;
        if queue.in_flight.len() == MAX_IN_FLIGHT {
            let old = queue.in_flight.pop_front().expect("full");
            if !old.answered() {
                queue.counts.evicted += 1;
            }
        }
        queue.in_flight.push_back(Request {
            key,
            target,
            at,
            attempts: 1,
            answers: Vec::new(),
        });
    }

    fn reply(
        &mut self,
        kind: Kind,
        responder: SysComp,
        key: Key,
        requester: SysComp,
        in_progress: bool,
        at: Nanos,
    ) -> Option<(SysComp, Nanos)> {
        let timeout = self.timeout;
        // The request: in flight, else timed out (a late reply).
        let mut found = None;
        for (q, queue) in self.queues.iter_mut().enumerate() {
            if queue.kind != kind
                || queue.requester == responder
                || !names(requester, queue.requester)
            {
                continue;
            }
            let hit = queue
                .in_flight
                .iter_mut()
                .rev()
                .find(|r| r.key == key && names(r.target, responder));
            if let Some(r) = hit {
                found = Some((
                    q,
                    Some((
                        at.saturating_sub(r.at),
                        r.attempts,
                        answer(r, responder, in_progress),
                    )),
                ));
                break;
            }
            if queue
                .expired
                .iter()
                .any(|&(k, target, _)| k == key && names(target, responder))
            {
                found = Some((q, None));
                break;
            }
        }
        let Some((q, how)) = found else {
            // No request: the reply's own target is all we know of who
            // asked.
            if let Some(p) = self.pair(kind, requester, responder) {
                p.counts.no_request += 1;
            }
            return None;
        };
        let requester = self.queues[q].requester;
        let p = self.pair(kind, requester, responder)?;
        match how {
            None => p.counts.late += 1,
            Some((_, _, Answer::Again)) => p.counts.duplicate += 1,
            Some((_, _, Answer::Progress)) => {}
            Some((rtt, attempts, Answer::First)) => {
                if rtt > timeout {
                    // Still in the table (it expires lazily): late all the same.
                    p.counts.late += 1;
                    p.counts.unanswered += 1;
                    return None;
                }
                p.counts.matched += 1;
                if attempts > 1 {
                    p.counts.after_retransmission += 1;
                }
                p.rtt.record(rtt);
                return Some((requester, rtt));
            }
        }
        None
    }

    /// Requests whose timeout has passed by `now` leave the table; the
    /// responders that did not answer them count them unanswered.
    fn expire(&mut self, now: Nanos) {
        for q in 0..self.queues.len() {
            loop {
                let queue = &mut self.queues[q];
                let Some(front) = queue.in_flight.front() else {
                    break;
                };
                if now.saturating_sub(front.at) <= self.timeout {
                    break;
                }
                let r = queue.in_flight.pop_front().expect("a front");
                if !r.answered() {
                    if queue.expired.len() == MAX_EXPIRED {
                        queue.expired.pop_front();
                    }
                    queue.expired.push_back((r.key, r.target, r.at));
                }
                let (requester, kind) = (queue.requester, queue.kind);
                self.unanswered(kind, requester, &r);
            }
        }
    }

    /// Counts `r` unanswered by each responder it could reach (those heard
    /// answering this requester, or its target where none was) that did
    /// not answer it. A command wants one ACK, whoever of its targets
    /// sends it; a broadcast PING or TIMESYNC one reply from each.
    fn unanswered(&mut self, kind: Kind, requester: SysComp, r: &Request) {
        if kind == Kind::Command && r.answered() {
            return;
        }
        let reachable: Vec<SysComp> = self
            .pairs
            .iter()
            .filter(|((k, from, to), p)| {
                *k == kind
                    && *from == requester
                    && names(r.target, *to)
                    && (p.counts.matched > 0 || p.counts.late > 0)
            })
            .map(|((_, _, to), _)| *to)
            .collect();
        let answered = |to: &SysComp| r.answers.iter().any(|(a, _)| a == to);
        if reachable.is_empty() {
            if !r.answered() {
                if let Some(p) = self.pair(kind, requester, r.target) {
                    p.counts.unanswered += 1;
                }
            }
            return;
        }
        for to in reachable.iter().filter(|to| !answered(to)) {
            if let Some(p) = self.pair(kind, requester, *to) {
                p.counts.unanswered += 1;
            }
        }
    }

    /// The index of the (requester, kind) table, made if there is room.
    fn queue(&mut self, requester: SysComp, kind: Kind) -> Option<usize> {
        if let Some(i) = self
            .queues
            .iter()
            .position(|q| q.requester == requester && q.kind == kind)
        {
            return Some(i);
        }
        if self.queues.len() == MAX_QUEUES {
            return None;
        }
        self.queues.push(Queue {
            requester,
            kind,
            in_flight: VecDeque::new(),
            expired: VecDeque::new(),
            counts: RequestCounts::default(),
        });
        Some(self.queues.len() - 1)
    }

    /// The figures of a pair, made if there is room (else counted
    /// untracked).
    fn pair(&mut self, kind: Kind, from: SysComp, to: SysComp) -> Option<&mut Pair> {
        let key = (kind, from, to);
        let i = match self.pairs.iter().position(|(k, _)| *k == key) {
            Some(i) => i,
            None if self.pairs.len() < MAX_PAIRS => {
                self.pairs.push((key, Pair::default()));
                self.pairs.len() - 1
            }
            None => {
                self.untracked += 1;
                return None;
            }
        };
        Some(&mut self.pairs[i].1)
    }

    /// The figures at the end of the log, `end` its last time: requests
    /// whose timeout passed by then are unanswered, the others in flight.
    pub(crate) fn summary(&mut self, end: Nanos) -> RoundTripSummary {
        self.expire(end);
        let mut requesters: Vec<RequesterSummary> = self
            .queues
            .iter()
            .map(|q| RequesterSummary {
                kind: q.kind,
                requester: q.requester,
                counts: RequestCounts {
                    in_flight_at_end: q.in_flight.iter().filter(|r| !r.answered()).count() as u64,
                    ..q.counts
                },
            })
            .collect();
        requesters.sort_by_key(|r| (r.kind, r.requester));
        let mut pairs: Vec<PairSummary> = self
            .pairs
            .iter()
            .map(|((kind, requester, responder), p)| PairSummary {
                kind: *kind,
                requester: *requester,
                responder: *responder,
                counts: p.counts,
                rtt: p.rtt.summary(),
            })
            .collect();
        pairs.sort_by_key(|p| (p.kind, p.requester, p.responder));
        RoundTripSummary {
            timeout_s: self.timeout as f64 / 1e9,
            requesters,
            pairs,
            untracked: self.untracked,
        }
    }
}

/// What a reply was to its request.
enum Answer {
    /// The responder's first answer: a round trip.
    First,
    /// An ACK after one that said more follow.
    Progress,
    Again,
}

/// Notes `responder`'s reply to `r`.
fn answer(r: &mut Request, responder: SysComp, in_progress: bool) -> Answer {
    match r.answers.iter_mut().find(|(a, _)| *a == responder) {
        Some((_, more)) if *more => {
            *more = in_progress;
            Answer::Progress
        }
        Some(_) => Answer::Again,
        None => {
            if r.answers.len() < MAX_ANSWERS {
                r.answers.push((responder, in_progress));
            }
            Answer::First
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::test_frame as frame;

    const MS: Nanos = 1_000_000;
    const GCS: SysComp = SysComp::new(255, 190);
    const VEHICLE: SysComp = SysComp::new(1, 1);
    const CAMERA: SysComp = SysComp::new(1, 100);

    fn ping(seq: u32, to: SysComp) -> Msg {
        Msg::Ping {
            time_usec: 1_000 + u64::from(seq),
            seq,
            target_system: to.sysid,
            target_component: to.compid,
        }
    }

    fn timesync(tc1: i64, ts1: i64, to: SysComp) -> Msg {
        Msg::Timesync {
            tc1,
            ts1,
            target_system: to.sysid,
            target_component: to.compid,
        }
    }

    fn command(command: u16, confirmation: u8, to: SysComp) -> Msg {
        Msg::CommandLong {
            command,
            confirmation,
            target_system: to.sysid,
            target_component: to.compid,
            params: [0.0; 7],
        }
    }

    fn ack(command: u16, result: u8, to: SysComp) -> Msg {
        Msg::CommandAck {
            command,
            result,
            target_system: to.sysid,
            target_component: to.compid,
        }
    }

    const ANY: SysComp = SysComp::new(0, 0);

    fn pair(s: &RoundTripSummary, kind: Kind, from: SysComp, to: SysComp) -> &PairSummary {
        s.pairs
            .iter()
            .find(|p| p.kind == kind && p.requester == from && p.responder == to)
            .unwrap_or_else(|| panic!("no {kind:?} {from} -> {to} in {s:?}"))
    }

    #[test]
    fn pings_match_by_seq_and_targets_with_exact_rtts() {
        let mut rt = RoundTrips::new(2_000 * MS);
        // Ten requests 1 s apart; the vehicle answers all but 3 and 7
        // after 10 + k ms, answers 5 twice.
        for k in 0..10u32 {
            let t = u64::from(k) * 1_000 * MS;
            rt.on_frame(&frame(GCS, ping(k, ANY)), t);
            if k == 3 || k == 7 {
                continue;
            }
            let rtt = (10 + u64::from(k)) * MS;
            rt.on_frame(&frame(VEHICLE, ping(k, GCS)), t + rtt);
            if k == 5 {
                rt.on_frame(&frame(VEHICLE, ping(k, GCS)), t + rtt + MS);
            }
            // Someone else's reply is not ours.
            rt.on_frame(&frame(VEHICLE, ping(k, SysComp::new(9, 9))), t + rtt);
        }
        let s = rt.summary(20_000 * MS);
        let p = pair(&s, Kind::Ping, GCS, VEHICLE);
        assert_eq!(p.counts.matched, 8);
        assert_eq!(p.counts.unanswered, 2);
        assert_eq!(p.counts.duplicate, 1);
        assert_eq!(p.counts.no_request, 0);
        let rtt = p.rtt.unwrap();
        assert_eq!((rtt.min_us, rtt.max_us), (10_000.0, 19_000.0));
        assert_eq!(
            pair(&s, Kind::Ping, SysComp::new(9, 9), VEHICLE)
                .counts
                .no_request,
            8
        );
        assert_eq!(s.requesters[0].counts.requests, 10);
        assert_eq!(s.requesters[0].counts.in_flight_at_end, 0);
    }

    #[test]
    fn a_broadcast_ping_is_unanswered_by_each_responder_that_did_not() {
        let mut rt = RoundTrips::new(2_000 * MS);
        for k in 0..4u32 {
            let t = u64::from(k) * 1_000 * MS;
            rt.on_frame(&frame(GCS, ping(k, ANY)), t);
            rt.on_frame(&frame(VEHICLE, ping(k, GCS)), t + 5 * MS);
            if k != 2 {
                rt.on_frame(&frame(CAMERA, ping(k, GCS)), t + 7 * MS);
            }
        }
        let s = rt.summary(10_000 * MS);
        assert_eq!(pair(&s, Kind::Ping, GCS, VEHICLE).counts.matched, 4);
        assert_eq!(pair(&s, Kind::Ping, GCS, VEHICLE).counts.unanswered, 0);
        let camera = pair(&s, Kind::Ping, GCS, CAMERA).counts;
        assert_eq!((camera.matched, camera.unanswered), (3, 1));
    }

    #[test]
    fn timesync_replies_without_targets_match_by_ts1_late_and_orphans_told_apart() {
        let mut rt = RoundTrips::new(2_000 * MS);
        // ArduPilot leaves the reply's targets 0; ts1 finds the request.
        rt.on_frame(&frame(GCS, timesync(0, 111, ANY)), 0);
        rt.on_frame(&frame(VEHICLE, timesync(5, 111, ANY)), 40 * MS);
        // Answered after 3 s: unanswered, then late.
        rt.on_frame(&frame(GCS, timesync(0, 222, ANY)), 1_000 * MS);
        rt.on_frame(&frame(VEHICLE, timesync(5, 222, ANY)), 4_000 * MS);
        // A reply to a request before the log began.
        rt.on_frame(&frame(VEHICLE, timesync(5, 99, GCS)), 4_100 * MS);
        // The vehicle's own request, answered by the GCS (targets set).
        rt.on_frame(&frame(VEHICLE, timesync(0, 7, ANY)), 5_000 * MS);
        rt.on_frame(&frame(GCS, timesync(9, 7, VEHICLE)), 5_003 * MS);
        // A request the log ends before the timeout of.
        rt.on_frame(&frame(GCS, timesync(0, 333, ANY)), 6_000 * MS);
        let s = rt.summary(7_000 * MS);
        let p = pair(&s, Kind::Timesync, GCS, VEHICLE).counts;
        assert_eq!(
            (p.matched, p.unanswered, p.late, p.no_request),
            (1, 1, 1, 1),
            "{s:?}"
        );
        let back = pair(&s, Kind::Timesync, VEHICLE, GCS);
        assert_eq!(back.counts.matched, 1);
        assert_eq!(back.rtt.unwrap().min_us, 3_000.0);
        let gcs = s
            .requesters
            .iter()
            .find(|r| r.requester == GCS)
            .unwrap()
            .counts;
        assert_eq!((gcs.requests, gcs.in_flight_at_end), (3, 1));
    }

    #[test]
    fn a_command_is_measured_from_its_last_attempt() {
        let mut rt = RoundTrips::new(2_000 * MS);
        // MAV_CMD_COMPONENT_ARM_DISARM to 1/1, retransmitted twice,
        // acknowledged 30 ms after the third attempt.
        rt.on_frame(&frame(GCS, command(400, 0, VEHICLE)), 0);
        rt.on_frame(&frame(GCS, command(400, 1, VEHICLE)), 1_000 * MS);
        rt.on_frame(&frame(GCS, command(400, 2, VEHICLE)), 2_500 * MS);
        rt.on_frame(&frame(VEHICLE, ack(400, 0, GCS)), 2_530 * MS);
        // A command to any component, answered in progress then done.
        rt.on_frame(&frame(GCS, command(42, 0, SysComp::new(1, 0))), 5_000 * MS);
        rt.on_frame(&frame(CAMERA, ack(42, IN_PROGRESS, GCS)), 5_010 * MS);
        rt.on_frame(&frame(CAMERA, ack(42, 0, GCS)), 5_900 * MS);
        rt.on_frame(&frame(CAMERA, ack(42, 0, GCS)), 5_901 * MS);
        // Never answered.
        rt.on_frame(&frame(GCS, command(511, 0, VEHICLE)), 8_000 * MS);
        let s = rt.summary(20_000 * MS);
        let p = pair(&s, Kind::Command, GCS, VEHICLE);
        assert_eq!(
            (
                p.counts.matched,
                p.counts.after_retransmission,
                p.counts.unanswered
            ),
            (1, 1, 1)
        );
        assert_eq!(p.rtt.unwrap().max_us, 30_000.0);
        let c = pair(&s, Kind::Command, GCS, CAMERA);
        assert_eq!((c.counts.matched, c.counts.duplicate), (1, 1));
        assert_eq!(c.rtt.unwrap().max_us, 10_000.0);
        let r = s.requesters[0].counts;
        assert_eq!((r.requests, r.repeats), (3, 2));
    }

    #[test]
    fn the_table_is_bounded_and_the_evicted_are_counted() {
        let mut rt = RoundTrips::new(10_000_000 * MS);
        let n = MAX_IN_FLIGHT as u32 + 10;
        for k in 0..n {
            rt.on_frame(&frame(GCS, ping(k, ANY)), u64::from(k) * MS);
        }
        // The first ten are gone: their replies match nothing.
        for k in 0..n {
            rt.on_frame(&frame(VEHICLE, ping(k, GCS)), 1_000 * MS);
        }
        let s = rt.summary(1_000 * MS);
        let p = pair(&s, Kind::Ping, GCS, VEHICLE).counts;
        assert_eq!((p.matched, p.no_request), (MAX_IN_FLIGHT as u64, 10));
        assert_eq!(s.requesters[0].counts.evicted, 10);
        // Requesters and pairs beyond the caps are counted, not kept.
        for k in 0..(MAX_QUEUES as u8 + 5) {
            rt.on_frame(&frame(SysComp::new(100 + k, 1), ping(1, ANY)), 2_000 * MS);
        }
        assert_eq!(rt.queues.len(), MAX_QUEUES);
        assert_eq!(rt.summary(2_000 * MS).untracked, 6);
    }

    #[test]
    fn a_request_logged_twice_is_one_request() {
        let mut rt = RoundTrips::new(2_000 * MS);
        rt.on_frame(&frame(GCS, ping(1, ANY)), 0);
        rt.on_frame(&frame(GCS, ping(1, ANY)), MS);
        rt.on_frame(&frame(VEHICLE, ping(1, GCS)), 20 * MS);
        let s = rt.summary(5_000 * MS);
        assert_eq!(s.requesters[0].counts.requests, 1);
        assert_eq!(s.requesters[0].counts.repeats, 1);
        let p = pair(&s, Kind::Ping, GCS, VEHICLE);
        assert_eq!((p.counts.matched, p.counts.unanswered), (1, 0));
        assert_eq!(p.rtt.unwrap().min_us, 20_000.0);
    }
}
