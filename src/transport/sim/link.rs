//! The link itself ([`SimLink`]): its state, how it is built from the
//! parameters, and the [`Transport`] calls through which mavping sends
//! requests and receives what arrives. The model it runs is in the
//! sibling files.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use tokio::time::{sleep_until, Instant};

use super::deliveries::{Delivery, Payload};
use super::outgoing::{Outgoing, Sends};
use super::params::SimParams;
use super::paths::SimPath;
use super::radio::RadioPair;
use super::responder::SimResponder;
use super::truth::{PathCounts, PathsTruth, QueueTruth, SimTruth};
use super::wire::Wire;
use crate::answering::transfers::TransferServer;
use crate::answering::ResponderCore;
use crate::frame::{ScanStats, SysComp};
use crate::telemetry::{Schedule, StreamKind};
use crate::transport::link::{
    push_datagram, Inbound, LinkError, LinkKind, PathId, RxClock, Transport,
};

/// Seeds the responders' own draws (telemetry phases, the per-direction
/// faults) beside `seed=`, so adding them leaves the other faults of a
/// seed where they were.
const VEHICLE_SEED: u64 = 0x7e1e_3e7e_5eed_0001;

pub struct SimLink {
    /// Boxed: the parameters are read, not moved, and the link is one
    /// variant of `transport::Link` beside much smaller ones.
    pub(super) params: Box<SimParams>,
    pub(super) responders: Vec<SimResponder>,
    pub(super) rng: SmallRng,
    pub(super) queue: BinaryHeap<Reverse<Delivery>>,
    pub(super) order: u64,
    pub(super) stats: ScanStats,
    pub(super) started: Instant,
    pub(super) scratch: Vec<Inbound>,
    /// Frames carry their bytes (`--tlog`).
    pub(super) keep_raw: bool,
    pub(super) wire: Wire,
    pub(super) next_radio: Instant,
    pub(super) radio_seq: u8,
    /// `air=`: a radio pair with its own air and buffers, instead of one
    /// shared wire.
    pub(super) pair: Option<Box<RadioPair>>,
    /// What the responders send next, in the order they send it.
    pub(super) outgoing: BinaryHeap<Reverse<Outgoing>>,
    pub(super) outgoing_order: u64,
    /// Draws for telemetry and the per-direction faults.
    pub(super) vehicle_rng: SmallRng,
    /// The most each queue (`queue_up=`, `queue_down=`) delayed a frame.
    pub(super) queue_truth: QueueTruth,
    /// The paths the responders' frames take (`paths=`; none without).
    pub(super) paths: Vec<SimPath>,
}

impl SimLink {
    pub fn new(params: SimParams) -> Self {
        let now = Instant::now();
        let mut vehicle_rng = SmallRng::seed_from_u64(params.seed ^ VEHICLE_SEED);
        let heartbeat_rate = params.heartbeat_rate();
        let responders: Vec<SimResponder> = (0..params.responders)
            .map(|i| {
                let mut core = ResponderCore::new(params.responder_id(i));
                core.answer_ping = params.answer_ping;
                SimResponder {
                    core,
                    packet_seq: 0,
                    // The first at once, as a real system's at boot.
                    heartbeat: heartbeat_rate.map(|rate| Schedule::new(rate, 0.0)),
                    streams: params
                        .streams
                        .iter()
                        .filter(|s| s.kind != StreamKind::Heartbeat)
                        .map(|s| (s.kind, Schedule::new(s.rate, vehicle_rng.gen())))
                        .collect(),
                    truth: SimTruth::default(),
                    replied: false,
                    numbered: 0,
                    latest_arrived: None,
                    copies_due: HashMap::new(),
                    paths: vec![PathCounts::default(); params.paths.len()],
                    transfers: TransferServer::new(params.responder_id(i), params.serve),
                    serving: false,
                }
            })
            .collect();
        let pair = params
            .air
            .zip(params.baud)
            .map(|(air, baud)| Box::new(RadioPair::new(baud, &air, params.buffer)));
        let mut link = SimLink {
            paths: SimPath::all(&params),
            rng: SmallRng::seed_from_u64(params.seed),
            params: Box::new(params),
            responders,
            queue: BinaryHeap::new(),
            order: 0,
            stats: ScanStats::default(),
            started: now,
            scratch: Vec::new(),
            keep_raw: false,
            wire: Wire::default(),
            next_radio: now,
            radio_seq: 0,
            pair,
            outgoing: BinaryHeap::new(),
            outgoing_order: 0,
            vehicle_rng,
            queue_truth: QueueTruth::default(),
        };
        for i in 0..link.responders.len() {
            if let Some(first) = link.responders[i].heartbeat.map(|s| s.due_ns()) {
                link.schedule(first, i, Sends::Heartbeat);
            }
            for k in 0..link.responders[i].streams.len() {
                let first = link.responders[i].streams[k].1.due_ns();
                link.schedule(first, i, Sends::Stream(k));
            }
        }
        link
    }

    /// Ground truth per responder, in responder order.
    pub fn truth(&self) -> Vec<(SysComp, SimTruth)> {
        self.responders
            .iter()
            .map(|r| {
                let mut truth = r.truth;
                truth.served = r.transfers.counts;
                (r.core.id, truth)
            })
            .collect()
    }

    /// What each path did with each responder's frames, in responder
    /// order; none without `paths=`.
    pub(crate) fn path_truth(&self) -> Vec<(SysComp, PathsTruth)> {
        if self.paths.is_empty() {
            return Vec::new();
        }
        self.responders
            .iter()
            .map(|r| (r.core.id, r.path_truth()))
            .collect()
    }

    /// The most each queue delayed a frame, the truth of `-v`.
    pub fn queue_truth(&self) -> QueueTruth {
        self.queue_truth
    }

    /// When the link must next act on its own: a frame arriving, a
    /// responder sending, RADIO_STATUS.
    fn next_event(&self) -> Option<Instant> {
        let delivery = self.queue.peek().map(|d| d.0.at);
        let outgoing = self.outgoing.peek().map(|o| o.0.at);
        let radio = self.params.radio.then_some(self.next_radio);
        delivery.into_iter().chain(outgoing).chain(radio).min()
    }
}

impl Transport for SimLink {
    async fn send(&mut self, bytes: &[u8]) -> Result<Instant, LinkError> {
        let now = Instant::now();
        // What the responders sent until now is numbered before what they
        // answer to this.
        self.send_due_frames(now);
        let mut requests = std::mem::take(&mut self.scratch);
        requests.clear();
        // Requests go through the real scanner, as on a wire.
        let mut ignored = ScanStats::default();
        push_datagram(bytes, now, 0, false, &mut ignored, &mut requests);
        // The request's own wire time; a full buffer loses it for everyone.
        let Some(sent_done) = self.uplink(now, bytes.len()) else {
            for request in &requests {
                for i in 0..self.responders.len() {
                    let r = &mut self.responders[i];
                    r.truth.up.sent += 1;
                    r.truth.up.dropped += 1;
                    if r.core.answer(&request.frame, 0).is_some() {
                        r.truth.answered += 1;
                        r.truth.dropped(r.replied);
                        r.truth.overflowed += 1;
                        r.truth.up.requests_dropped += 1;
                    }
                }
            }
            self.scratch = requests;
            return Ok(now);
        };
        for request in &requests {
            for i in 0..self.responders.len() {
                self.exchange(i, &request.frame, now, sent_done);
            }
        }
        self.scratch = requests;
        Ok(now)
    }

    /// Every responder hears everything, whatever the path (`paths=`
    /// shapes only what comes back).
    async fn send_to(&mut self, _path: PathId, frame: &[u8]) -> Result<Instant, LinkError> {
        self.send(frame).await
    }

    async fn recv(&mut self, out: &mut Vec<Inbound>) -> Result<(), LinkError> {
        loop {
            let Some(wake) = self.next_event() else {
                return std::future::pending().await;
            };
            // The only await: everything after it runs to completion, so a
            // cancelled recv loses nothing.
            sleep_until(wake).await;
            let now = Instant::now();
            self.send_due_frames(now);
            self.queue_radio_status(now);
            let before = out.len();
            while self.queue.peek().is_some_and(|d| d.0.at <= now) {
                let Reverse(d) = self.queue.pop().expect("peeked");
                match d.payload {
                    Payload::Plain => {}
                    Payload::Spiked(i) => self.responders[i].truth.spiked_arrived += 1,
                    Payload::Duplicate(i) => self.responders[i].truth.duplicates_arrived += 1,
                }
                if let Some(tag) = d.frame {
                    self.responders[tag.responder].arrived(tag.index, d.path);
                }
                // Stamped with the simulated arrival time: the RTT is
                // exactly the simulated delay, free of scheduler noise.
                push_datagram(&d.bytes, d.at, d.path, self.keep_raw, &mut self.stats, out);
            }
            if out.len() > before {
                return Ok(());
            }
        }
    }

    fn scan_stats(&self) -> ScanStats {
        self.stats
    }

    fn kind(&self) -> LinkKind {
        LinkKind::Simulated
    }

    fn keep_raw(&mut self) {
        self.keep_raw = true;
    }

    fn rx_clock(&self) -> RxClock {
        RxClock::Simulated
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;
    use std::time::Duration;

    use super::*;
    use crate::frame::{self, ids, Header, Msg, Version};

    const ATTITUDE: u32 = 30;
    const GLOBAL_POSITION_INT: u32 = 33;

    fn sim(query: &str) -> SimLink {
        SimLink::new(SimParams::parse(query).unwrap())
    }

    /// A PING request from mavping (250/190).
    fn ping(seq: u32) -> Vec<u8> {
        let mut bytes = Vec::new();
        let header = Header {
            sysid: 250,
            compid: 190,
            seq: seq as u8,
        };
        let msg = Msg::Ping {
            time_usec: u64::from(seq) + 1,
            seq,
            target_system: 0,
            target_component: 0,
        };
        frame::encode(&mut bytes, Version::V2, header, &msg);
        bytes
    }

    /// Reads the link for `run` of its (paused) clock, sending `pings`
    /// PINGs `every` apart from the start; what arrived, in order.
    async fn drive(link: &mut SimLink, run: Duration, every: Duration, pings: u32) -> Vec<Inbound> {
        let end = Instant::now() + run;
        let mut next = Instant::now();
        let (mut sent, mut out) = (0, Vec::new());
        loop {
            let wake = if sent < pings { next.min(end) } else { end };
            tokio::select! {
                r = link.recv(&mut out) => r.unwrap(),
                () = sleep_until(wake) => {
                    if Instant::now() >= end {
                        return out;
                    }
                    link.send(&ping(sent)).await.unwrap();
                    sent += 1;
                    next += every;
                }
            }
        }
    }

    /// What a passive count of `source`'s packet sequence numbers finds:
    /// each frame's index unwrapped from its 8-bit sequence, nearest the
    /// latest one.
    #[derive(Debug, Default, PartialEq)]
    struct Passive {
        delivered: u64,
        reordered: u64,
        duplicates: u64,
        /// Indices up to the latest never seen: lost, or still on the way.
        missing: u64,
    }

    fn passive(frames: &[Inbound], source: SysComp) -> Passive {
        let mut latest: Option<u64> = None;
        let mut seen = HashSet::new();
        let mut p = Passive::default();
        for f in frames.iter().filter(|f| f.frame.source == source) {
            let seq = u64::from(f.frame.packet_seq);
            // Frame i carries sequence i + 1 (modulo 256).
            let index = match latest {
                None => (seq + 255) % 256,
                Some(l) => {
                    let back = (l + 1 + 256 - seq) % 256;
                    if back < 128 {
                        l - back
                    } else {
                        l + 256 - back
                    }
                }
            };
            if !seen.insert(index) {
                p.duplicates += 1;
                continue;
            }
            p.delivered += 1;
            p.reordered += u64::from(latest.is_some_and(|l| index < l));
            latest = Some(latest.map_or(index, |l| l.max(index)));
        }
        p.missing = latest.map_or(0, |l| l + 1) - p.delivered;
        p
    }

    fn of(frames: &[Inbound], source: SysComp, msgid: u32) -> usize {
        frames
            .iter()
            .filter(|f| f.frame.source == source && f.frame.msgid == msgid)
            .count()
    }

    #[tokio::test(start_paused = true)]
    async fn telemetry_heartbeats_and_replies_share_one_sequence_in_the_order_sent() {
        let mut link = sim("?stream=ATTITUDE@50,GLOBAL_POSITION_INT@5,HEARTBEAT@4&jitter=0");
        let frames = drive(
            &mut link,
            Duration::from_secs(10),
            Duration::from_millis(200),
            50,
        )
        .await;
        let id = SysComp::new(1, 1);
        let ours: Vec<&Inbound> = frames.iter().filter(|f| f.frame.source == id).collect();
        // One counter, one more each frame, wrapping past 255: nothing
        // lost, doubled or out of order on a clean link.
        assert!(ours.len() > 512, "{}", ours.len());
        for pair in ours.windows(2) {
            let (a, b) = (pair[0].frame.packet_seq, pair[1].frame.packet_seq);
            assert_eq!(b, a.wrapping_add(1), "{a} then {b}");
        }
        // 10 s at 50 and 5 Hz from a random phase, 10 ms on the way; 4
        // HEARTBEATs a second from the start (the one at 10 s is on its
        // way), every PING answered.
        assert!((499..=500).contains(&of(&frames, id, ATTITUDE)));
        assert!((49..=50).contains(&of(&frames, id, GLOBAL_POSITION_INT)));
        assert_eq!(of(&frames, id, ids::HEARTBEAT), 40);
        assert_eq!(of(&frames, id, ids::PING), 50);
        let down = link.truth()[0].1.down;
        let arrived = ours.len() as u64;
        assert_eq!(
            (
                down.delivered,
                down.dropped,
                down.reordered,
                down.duplicated
            ),
            (arrived, 0, 0, 0)
        );
        assert!(down.sent - arrived <= 3, "{down:?}");
        let seen = passive(&frames, id);
        assert_eq!(
            (seen.delivered, seen.missing, seen.reordered),
            (arrived, 0, 0)
        );
    }

    #[tokio::test(start_paused = true)]
    async fn per_direction_faults_are_the_ground_truth_of_a_passive_count() {
        let mut link = sim(
            "?responders=2&stream=ATTITUDE@50&loss_down=10%&dup_down=5%&reorder_down=5%\
             &loss_up=20%&seed=3",
        );
        // 500 PINGs in 50 s, then 10 s for the last replies.
        let frames = drive(
            &mut link,
            Duration::from_secs(60),
            Duration::from_millis(100),
            500,
        )
        .await;
        for (id, t) in link.truth() {
            let seen = passive(&frames, id);
            let down = t.down;
            assert_eq!(
                (seen.delivered, seen.reordered, seen.duplicates),
                (down.delivered, down.reordered, down.duplicates_arrived),
                "{id}: {down:?}"
            );
            // What is still on its way was sent in the last few frames.
            let in_flight = down.sent - down.dropped - down.delivered;
            assert!(in_flight <= 5, "{id}: {down:?}");
            assert!(
                seen.missing.abs_diff(down.dropped) <= in_flight,
                "{seen:?} {down:?}"
            );
            let share = down.dropped as f64 / down.sent as f64;
            assert!((0.08..0.12).contains(&share), "{id}: {down:?}");
            assert!(
                down.reordered > 20 && down.duplicates_arrived > 50,
                "{down:?}"
            );
            // Every PING reached the link; a fifth lost on the way up, for
            // each responder its own fifth.
            assert_eq!((t.up.sent, t.answered), (500, 500));
            assert_eq!(t.up.dropped, t.up.requests_dropped);
            assert!(
                (70..130).contains(&t.up.requests_dropped),
                "{id}: {:?}",
                t.up
            );
            // The exchange's truth holds too: every reply not dropped
            // arrived, its extra copies too.
            let replies: Vec<u32> = frames
                .iter()
                .filter(|f| f.frame.source == id)
                .filter_map(|f| match f.frame.msg {
                    Msg::Ping { seq, .. } => Some(seq),
                    _ => None,
                })
                .collect();
            let unique: HashSet<u32> = replies.iter().copied().collect();
            assert_eq!(unique.len() as u64, t.delivered, "{id}: {t:?}");
            assert_eq!(t.answered - t.dropped, t.delivered);
            assert_eq!(
                (replies.len() - unique.len()) as u64,
                t.duplicates_arrived,
                "{t:?}"
            );
            assert!(t.dropped > t.up.requests_dropped, "{t:?}");
        }
        let [(_, a), (_, b)] = link.truth()[..] else {
            panic!("two responders")
        };
        assert_ne!(a.up.requests_dropped, b.up.requests_dropped);
    }

    #[tokio::test(start_paused = true)]
    async fn a_request_heard_twice_is_answered_twice_each_reply_numbered() {
        let mut link = sim("?stream=ATTITUDE@50&dup_up=20%&loss_down=10%&seed=5");
        let frames = drive(
            &mut link,
            Duration::from_secs(25),
            Duration::from_millis(100),
            200,
        )
        .await;
        let (id, t) = link.truth()[0];
        // About a fifth of the PINGs reached it twice; each copy was
        // answered.
        assert_eq!(t.up.sent, 200);
        assert_eq!((t.up.dropped, t.up.requests_dropped), (0, 0));
        assert_eq!(t.up.requests_duplicated, t.up.duplicated);
        assert!((25..60).contains(&t.up.duplicated), "{:?}", t.up);
        let replies: Vec<u32> = frames
            .iter()
            .filter(|f| f.frame.source == id)
            .filter_map(|f| match f.frame.msg {
                Msg::Ping { seq, .. } => Some(seq),
                _ => None,
            })
            .collect();
        let unique: HashSet<u32> = replies.iter().copied().collect();
        // An exchange is lost only when every reply of it is: the truth
        // counts what the pinger sees, replies and duplicate replies.
        assert_eq!(t.answered, 200);
        assert_eq!(unique.len() as u64, t.delivered, "{t:?}");
        assert_eq!(t.answered - t.dropped, t.delivered);
        assert!(t.dropped > 5 && t.dropped < t.down.dropped, "{t:?}");
        assert_eq!(
            (replies.len() - unique.len()) as u64,
            t.duplicates_arrived,
            "{t:?}"
        );
        assert!(t.duplicates_arrived > 15, "{t:?}");
        // On the way down the second reply is a frame of its own: in the
        // sequence, no duplicate, and its losses are the downlink's.
        let down = t.down;
        let seen = passive(&frames, id);
        assert_eq!((seen.duplicates, down.duplicated), (0, 0));
        assert_eq!(seen.delivered, down.delivered);
        let in_flight = down.sent - down.dropped - down.delivered;
        assert!(in_flight <= 5, "{down:?}");
        assert!(
            seen.missing.abs_diff(down.dropped) <= in_flight,
            "{seen:?} {down:?}"
        );
        // Without dup_up= the same seed answers each request once.
        let mut once = sim("?stream=ATTITUDE@50&loss_down=10%&seed=5");
        let frames = drive(
            &mut once,
            Duration::from_secs(25),
            Duration::from_millis(100),
            200,
        )
        .await;
        let (_, t) = once.truth()[0];
        assert_eq!((t.up.duplicated, t.duplicates_arrived), (0, 0));
        assert_eq!(of(&frames, id, ids::PING) as u64, t.delivered);
    }

    #[tokio::test(start_paused = true)]
    async fn loss_loses_exchanges_without_a_gap_and_loss_down_leaves_one() {
        let every = Duration::from_millis(100);
        let mut link = sim("?loss=30%&heartbeat=off&seed=4");
        let frames = drive(&mut link, Duration::from_secs(12), every, 100).await;
        let (id, t) = link.truth()[0];
        let seen = passive(&frames, id);
        assert!(t.dropped > 15, "{t:?}");
        assert_eq!(t.down.sent, t.answered - t.dropped);
        assert_eq!((seen.delivered, seen.missing), (t.down.sent, 0));

        let mut link = sim("?loss_down=30%&heartbeat=off&seed=4");
        let frames = drive(&mut link, Duration::from_secs(12), every, 100).await;
        let (id, t) = link.truth()[0];
        let seen = passive(&frames, id);
        assert!(t.down.dropped > 15, "{t:?}");
        assert_eq!((t.down.sent, t.dropped), (100, t.down.dropped));
        // The last frames' loss shows only once a later frame arrives.
        let tail = t.down.sent - (seen.delivered + seen.missing);
        assert_eq!(seen.missing + tail, t.down.dropped);
        assert_eq!(seen.delivered, t.down.delivered);
    }

    /// A frame's copies: when each arrived, and by which path.
    type Arrivals = Vec<(Instant, usize)>;

    /// Each path's frames: (raw bytes, arrival) by path index.
    fn by_path(frames: &[Inbound], source: SysComp, paths: usize) -> Vec<Vec<(Vec<u8>, Instant)>> {
        let mut out = vec![Vec::new(); paths];
        for f in frames.iter().filter(|f| f.frame.source == source) {
            let raw = f.raw.as_deref().expect("kept").to_vec();
            out[f.path as usize].push((raw, f.at));
        }
        out
    }

    /// What a count of the sequence of `frames` (raw bytes) finds lost:
    /// the numbers between the lowest and the highest never seen, each
    /// unwrapped nearest the previous frame's.
    fn passive_of(frames: &[(Vec<u8>, Instant)]) -> u64 {
        let mut sorted: Vec<&(Vec<u8>, Instant)> = frames.iter().collect();
        sorted.sort_by_key(|(_, at)| *at);
        let mut seen = HashSet::new();
        let mut latest: Option<i64> = None;
        for (raw, _) in sorted {
            // MAVLink 2: the sequence is the header's fifth byte.
            let seq = i64::from(raw[4]);
            let index = match latest {
                None => seq,
                Some(l) => l + i64::from((seq - l).rem_euclid(256) as u8 as i8),
            };
            seen.insert(index);
            latest = Some(latest.map_or(index, |l| l.max(index)));
        }
        let (Some(low), Some(high)) = (seen.iter().min(), seen.iter().max()) else {
            return 0;
        };
        (high - low + 1) as u64 - seen.len() as u64
    }

    #[tokio::test(start_paused = true)]
    async fn each_path_delivers_the_same_bytes_as_its_truth_counts_them() {
        let delays = [20, 100, 0].map(Duration::from_millis);
        let mut link = sim(
            "?stream=ATTITUDE@50,GLOBAL_POSITION_INT@5&loss_down=3%&reorder_down=2%&paths=3\
             &path_loss=10%,2%,30%&path_delay=20ms,100ms,0s&path_outage=none,none,3s+1s&seed=5",
        );
        link.keep_raw();
        let frames = drive(
            &mut link,
            Duration::from_secs(10),
            Duration::from_millis(100),
            50,
        )
        .await;
        let id = SysComp::new(1, 1);
        let paths = by_path(&frames, id, 3);
        // A frame's copies leave the link together and each path adds its
        // delay: the same frame is the same bytes at the same time less it.
        // Which paths delivered each frame, and when, by that key.
        let mut delivered_by: HashMap<(Vec<u8>, Instant), Arrivals> = HashMap::new();
        for (k, path) in paths.iter().enumerate() {
            for (raw, at) in path {
                delivered_by
                    .entry((raw.clone(), *at - delays[k]))
                    .or_default()
                    .push((*at, k));
            }
        }
        let (_, t) = link.truth()[0];
        let [(truth_id, truth)] = &link.path_truth()[..] else {
            panic!("one responder");
        };
        assert_eq!(*truth_id, id);
        assert_eq!(delivered_by.len() as u64, t.down.delivered);
        for (k, path) in paths.iter().enumerate() {
            let p = &truth.paths[k];
            let only = delivered_by
                .values()
                .filter(|by| by.iter().all(|&(_, j)| j == k))
                .count();
            let first = delivered_by
                .values()
                .filter(|by| by.iter().min().is_some_and(|&(_, j)| j == k))
                .count();
            assert_eq!(
                (path.len() as u64, first as u64, only as u64, 0),
                (p.delivered, p.first, p.only, p.duplicates),
                "path {k}: {p:?}"
            );
            assert_eq!(p.sent, t.down.sent);
            let in_flight = p.sent - p.dropped - p.delivered;
            assert!(in_flight <= 12, "path {k}: {p:?}");
            let lost = p.dropped as f64 / p.sent as f64;
            // 3 % before the split, then the path's own loss; the third
            // path's outage is a tenth of the run.
            let expected = [0.127, 0.049, 0.389][k];
            assert!((lost - expected).abs() < 0.05, "path {k}: {p:?}");
            // What its own sequence finds lost: the frames before its
            // first and after its newest are not between.
            let seen = passive_of(path);
            assert_eq!(seen, p.missing, "path {k}: {p:?}");
            assert!(p.drawn + p.outage <= p.dropped, "path {k}: {p:?}");
            assert_eq!(p.outage == 0, k != 2, "path {k}: {p:?}");
            let share = p.drawn as f64 / (p.sent - p.outage) as f64;
            let drawn = [0.1, 0.02, 0.3][k] * 0.97;
            assert!((share - drawn).abs() < 0.04, "path {k}: {p:?}");
        }
        // The third path's outage: a second of a 66-frame-a-second
        // vehicle, less the 3 % lost before the split.
        assert!((55..=70).contains(&truth.paths[2].outage), "{truth:?}");
        let merged: Vec<(Vec<u8>, Instant)> = delivered_by.keys().cloned().collect();
        assert_eq!(passive_of(&merged), truth.missing_on_every_path);
        // Lost on every path: in none of the paths' frames, and what a
        // passive count of the merged stream finds missing.
        assert_eq!(truth.lost_on_every_path, t.down.dropped);
        assert!(truth
            .paths
            .iter()
            .all(|p| p.only > 0 && p.dropped > truth.lost_on_every_path));
        let seen = passive(&frames, id);
        assert_eq!(
            (seen.delivered, seen.duplicates, seen.reordered),
            (
                t.down.delivered,
                t.down.duplicates_arrived,
                t.down.reordered
            )
        );
        assert_eq!(
            seen.duplicates,
            truth.paths.iter().map(|p| p.delivered).sum::<u64>() - t.down.delivered
        );
        // The third path's outage: nothing by it from 3 s to 4 s (10 ms
        // and the jitter on the way), the others go on.
        let start = link.started;
        let quiet = |k: usize| {
            !paths[k].iter().any(|(_, at)| {
                let t = *at - start;
                t > Duration::from_millis(3_020) && t < Duration::from_secs(4)
            })
        };
        assert!(quiet(2) && !quiet(0) && !quiet(1));
        // Replies go by every path: the first to arrive is the reply, the
        // others duplicates, as the pinger counts them.
        assert_eq!(
            of(&frames, id, ids::PING) as u64,
            t.delivered + t.duplicates_arrived
        );
        assert!(t.duplicates_arrived > 50 && t.delivered > 45, "{t:?}");
    }

    #[tokio::test(start_paused = true)]
    async fn a_paths_plan_is_its_own_and_one_path_is_the_link_as_it_was() {
        // Each run starts later on the paused clock: times from its start.
        async fn arrivals(query: &str) -> Vec<(PathId, Vec<u8>, Duration)> {
            let mut link = sim(query);
            link.keep_raw();
            let frames = drive(
                &mut link,
                Duration::from_secs(6),
                Duration::from_millis(100),
                40,
            )
            .await;
            frames
                .into_iter()
                .map(|f| (f.path, f.raw.unwrap().to_vec(), f.at - link.started))
                .collect()
        }
        let on = |frames: &[(PathId, Vec<u8>, Duration)], k| {
            let on_k: Vec<_> = frames.iter().filter(|f| f.0 == k).cloned().collect();
            on_k
        };
        let base = "?stream=ATTITUDE@50&dup_down=5%&loss_down=5%&seed=8";
        let two = arrivals(&format!("{base}&paths=2&path_loss=10%,2%")).await;
        let three = arrivals(&format!(
            "{base}&paths=3&path_loss=10%,40%,5%&path_delay=0s,1s,30ms&path_outage=none,2s+1s,none"
        ))
        .await;
        assert!(on(&two, 0).len() > 200 && on(&two, 1).len() > on(&two, 0).len());
        // Adding a path, or changing another's faults, leaves path 0's
        // copies where they were.
        assert_eq!(on(&two, 0), on(&three, 0));
        assert_ne!(on(&two, 1), on(&three, 1));
        // One faultless path is the link without paths.
        let as_it_was = arrivals(base).await;
        assert_eq!(arrivals(&format!("{base}&paths=1")).await, as_it_was);
        // The link's own extra copies go by each path: duplicates on it.
        let mut link = sim(&format!("{base}&paths=2&path_loss=10%,2%"));
        let frames = drive(
            &mut link,
            Duration::from_secs(6),
            Duration::from_millis(100),
            40,
        )
        .await;
        let truth = &link.path_truth()[0].1;
        for (k, p) in truth.paths.iter().enumerate() {
            let by_k = frames.iter().filter(|f| f.path == k as PathId).count() as u64;
            assert_eq!(p.delivered + p.duplicates, by_k, "path {k}: {p:?}");
            assert!(p.duplicates > 0, "path {k}: {p:?}");
        }
        let seen = passive(&frames, SysComp::new(1, 1));
        let down = link.truth()[0].1.down;
        assert_eq!(
            (seen.delivered, seen.duplicates),
            (down.delivered, down.duplicates_arrived)
        );
    }
}
