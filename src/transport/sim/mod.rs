//! `sim:` — an in-process link with simulated responders and faults.
//!
//! Requests pass through the real encoder and scanner, are answered by the
//! same responder logic as `mavping respond`, and come back after a seeded
//! random delay, maybe dropped, duplicated or held back (reordered). With
//! `clock=virtual` the run uses tokio's paused clock: output is identical on
//! every run and a long simulation takes no wall time.
//!
//! Responders number every frame they send (HEARTBEAT, `stream=` telemetry,
//! replies) with one packet sequence, in the order they send them, as an
//! autopilot does: a reply is numbered when the responder has the request,
//! one leg after mavping sent it. The per-direction faults (`loss_down=`,
//! `dup_down=`, `reorder_down=`, `loss_up=`, `dup_up=`) act on numbered
//! frames (a request heard twice is answered twice), and
//! [`DownTruth`] and [`UpTruth`] count what they did, for a passive loss
//! count held against them.

use std::cmp::{Ordering, Reverse};
use std::collections::{BinaryHeap, HashMap};
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use tokio::time::{sleep_until, Instant};

use super::link::{push_datagram, Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
use crate::answering::ResponderCore;
use crate::frame::{self, Header, Msg, RadioStatus, ScanStats, SysComp, Version};
use crate::telemetry::{Schedule, StreamKind};
use radio::RadioPair;

mod exchange;
mod params;
pub(crate) mod radio;
pub use params::{SimParams, DEFAULT_BUFFER_BYTES, SIM_KEYS};

struct SimResponder {
    core: ResponderCore,
    packet_seq: u8,
    /// Its HEARTBEAT's timetable (`heartbeat=on`), and its telemetry's.
    heartbeat: Option<Schedule>,
    streams: Vec<(StreamKind, Schedule)>,
    truth: SimTruth,
    /// A reply of its has been put on its way (delivered or spiked): the
    /// pinger's window for it opens at the first such exchange.
    replied: bool,
    /// Frames it numbered so far: the index of the next one (its packet
    /// sequence is this index plus one, modulo 256).
    numbered: u64,
    /// The highest index that has arrived at mavping.
    latest_arrived: Option<u64>,
    /// Frames with more than one copy on its way: copies still to arrive.
    copies_due: HashMap<u64, u8>,
}

/// What the simulated link did to one responder's exchanges: the ground
/// truth tests hold mavping's counts against.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct SimTruth {
    /// Requests the responder answered (before faults).
    pub answered: u64,
    /// Exchanges the link dropped...
    pub dropped: u64,
    /// ...of which before the first exchange whose reply was put on its
    /// way, in time or spiked (outside the pinger's window: not charged).
    pub dropped_before_first: u64,
    /// Replies delivered (first copies), not spiked.
    pub delivered: u64,
    /// Extra replies put on their way: copies (`dup=`, `dup_down=`), and
    /// the second answer to a request heard twice (`dup_up=`).
    pub duplicated: u64,
    /// ...of which handed to the pinger before it stopped reading.
    pub duplicates_arrived: u64,
    /// Exchanges the radio's full buffer dropped (`baud=`), also counted
    /// in `dropped`.
    pub(crate) overflowed: u64,
    /// Exchanges lost to the outage (`outage=`), also counted in `dropped`.
    pub(crate) outage: u64,
    /// Replies delayed by a spike (`spike=`); not in `delivered`: with a
    /// `spike_delay` past the timeout they arrive late.
    pub(crate) spiked: u64,
    /// ...of which handed to the pinger before it stopped reading (the
    /// late replies it can have seen).
    pub(crate) spiked_arrived: u64,
    /// Every frame the responder sent, by its sequence numbers.
    pub(crate) down: DownTruth,
    /// Every frame mavping sent towards it.
    pub(crate) up: UpTruth,
}

/// What became of the frames a responder sent (HEARTBEAT, telemetry,
/// replies), each numbered: what a passive count of its packet sequence
/// numbers is held against. `sent = dropped + delivered + in flight`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct DownTruth {
    /// Frames it numbered and sent.
    pub(crate) sent: u64,
    /// ...lost on the way to mavping: `loss_down=`, a full radio buffer
    /// (`baud=`), the outage (telemetry; `outage=`).
    pub(crate) dropped: u64,
    /// Extra copies put on their way (`dup=` on replies, `dup_down=`).
    pub(crate) duplicated: u64,
    /// ...of which arrived.
    pub(crate) duplicates_arrived: u64,
    /// Frames that arrived (first copies), reordered ones included.
    pub(crate) delivered: u64,
    /// ...of which after a frame it sent later had arrived (`hold=` by
    /// `reorder=` or `reorder_down=`, or a jitter wider than the gap).
    pub(crate) reordered: u64,
}

/// What became of the frames mavping sent, as one responder hears them.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct UpTruth {
    /// Frames mavping sent (requests, its HEARTBEAT, `--load`).
    pub(crate) sent: u64,
    /// ...lost on the way to this responder: `loss_up=`, a full buffer
    /// (`baud=`).
    pub(crate) dropped: u64,
    /// ...of which requests it would have answered (also counted in
    /// `answered` and `dropped`: the exchange is lost).
    pub(crate) requests_dropped: u64,
    /// Frames it heard twice (`dup_up=`)...
    pub(crate) duplicated: u64,
    /// ...of which requests it answered twice: two replies, each numbered
    /// in its sequence; the second to arrive is a duplicate reply
    /// (`duplicated`), and the exchange is lost only if both are.
    pub(crate) requests_duplicated: u64,
}

impl SimTruth {
    fn dropped(&mut self, replied: bool) {
        self.dropped += 1;
        self.dropped_before_first += u64::from(!replied);
    }
}

impl SimResponder {
    /// The header of the next frame it sends, and the frame's index.
    fn header(&mut self) -> (Header, u64) {
        self.packet_seq = self.packet_seq.wrapping_add(1);
        let index = self.numbered;
        self.numbered += 1;
        self.truth.down.sent += 1;
        let header = Header {
            sysid: self.core.id.sysid,
            compid: self.core.id.compid,
            seq: self.packet_seq,
        };
        (header, index)
    }

    /// A frame of its reached mavping: a first copy, maybe reordered, or
    /// an extra one.
    fn arrived(&mut self, index: u64) {
        let copy = match self.copies_due.get_mut(&index) {
            Some(left) => {
                *left -= 1;
                let copy = *left == 0;
                if copy {
                    self.copies_due.remove(&index);
                }
                copy
            }
            None => false,
        };
        let down = &mut self.truth.down;
        if copy {
            down.duplicates_arrived += 1;
            return;
        }
        down.delivered += 1;
        down.reordered += u64::from(self.latest_arrived.is_some_and(|l| index < l));
        self.latest_arrived = Some(self.latest_arrived.map_or(index, |l| l.max(index)));
    }
}

/// Which responder's frame a delivery is, and which of its frames.
#[derive(PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
struct Tag {
    responder: usize,
    index: u64,
}

/// A delivery waiting in the simulated link, ordered by time then by the
/// order it was queued (so equal times stay deterministic).
#[derive(PartialEq, Eq, PartialOrd, Ord)]
struct Delivery {
    at: Instant,
    order: u64,
    bytes: Vec<u8>,
    /// What it is, for the ground truth of what arrived.
    payload: Payload,
    /// A responder's frame (not RADIO_STATUS): for [`DownTruth`].
    frame: Option<Tag>,
}

/// A frame a responder sends at `at`, numbered then.
struct Outgoing {
    at: Instant,
    order: u64,
    responder: usize,
    what: Sends,
}

enum Sends {
    Heartbeat,
    /// Telemetry: the responder's stream of this index.
    Stream(usize),
    /// A reply, its fate drawn when its request was sent.
    Reply(Box<Reply>),
}

struct Reply {
    msg: Msg,
    version: Version,
    /// When its copies arrive, or `None`: lost on the way.
    copies: Option<Copies>,
}

/// A frame's arrivals: its first copy and maybe an extra one.
type Copies = ([(Instant, Payload); 2], usize);

impl PartialEq for Outgoing {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Outgoing {}

impl PartialOrd for Outgoing {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Outgoing {
    fn cmp(&self, other: &Self) -> Ordering {
        (self.at, self.order).cmp(&(other.at, other.order))
    }
}

/// What a delivery carries, for the ground truth.
#[derive(PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
enum Payload {
    /// HEARTBEAT, telemetry, RADIO_STATUS, a reply's first copy on time.
    Plain,
    /// A reply's first copy, spiked (responder index).
    Spiked(usize),
    /// A reply's extra copy (responder index).
    Duplicate(usize),
}

/// Queued deliveries are capped so an absurd rate x delay cannot grow
/// memory without bound; past it, replies are dropped like a full queue.
const MAX_QUEUED: usize = 1 << 20;

/// The simulated responders' HEARTBEAT: a PX4 quadrotor, or with
/// `ping=off` an ArduPilot one (which answers TIMESYNC, never PING).
const fn heartbeat(answers_ping: bool) -> Msg {
    Msg::Heartbeat {
        mav_type: 2, // quadrotor
        autopilot: if answers_ping {
            12 // PX4
        } else {
            crate::frame::AUTOPILOT_ARDUPILOT
        },
    }
}

/// Seeds the responders' own draws (telemetry phases, the per-direction
/// faults) beside `seed=`, so adding them leaves the other faults of a
/// seed where they were.
const VEHICLE_SEED: u64 = 0x7e1e_3e7e_5eed_0001;

pub(crate) const RADIO_ID: SysComp = SysComp::new(51, 68);

/// `delay=` plus a draw of `jitter=`.
fn one_way(params: &SimParams, rng: &mut SmallRng) -> Duration {
    let jitter = params.jitter.as_nanos() as u64;
    let extra = if jitter == 0 {
        0
    } else {
        rng.gen_range(0..=jitter)
    };
    params.delay + Duration::from_nanos(extra)
}

/// The shared wire of a `baud=` link: when it is next free.
#[derive(Default)]
struct Wire {
    free_at: Option<Instant>,
}

pub struct SimLink {
    /// Boxed: the parameters are read, not moved, and the link is one
    /// variant of `transport::Link` beside much smaller ones.
    params: Box<SimParams>,
    responders: Vec<SimResponder>,
    rng: SmallRng,
    queue: BinaryHeap<Reverse<Delivery>>,
    order: u64,
    stats: ScanStats,
    started: Instant,
    scratch: Vec<Inbound>,
    /// Frames carry their bytes (`--tlog`).
    keep_raw: bool,
    wire: Wire,
    next_radio: Instant,
    radio_seq: u8,
    /// `air=`: a radio pair with its own air and buffers, instead of one
    /// shared wire.
    pair: Option<Box<RadioPair>>,
    /// What the responders send next, in the order they send it.
    outgoing: BinaryHeap<Reverse<Outgoing>>,
    outgoing_order: u64,
    /// Draws for telemetry and the per-direction faults.
    vehicle_rng: SmallRng,
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
                }
            })
            .collect();
        let pair = params
            .air
            .zip(params.baud)
            .map(|(air, baud)| Box::new(RadioPair::new(baud, &air, params.buffer)));
        let mut link = SimLink {
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
            .map(|r| (r.core.id, r.truth))
            .collect()
    }

    fn one_way(&mut self) -> Duration {
        one_way(&self.params, &mut self.rng)
    }

    /// A one-way delay drawn for the responders' own frames.
    fn vehicle_one_way(&mut self) -> Duration {
        one_way(&self.params, &mut self.vehicle_rng)
    }

    /// A responder's clock at `t`.
    fn clock_ns(&self, t: Instant) -> i64 {
        let t = (t - self.started).as_nanos() as i64;
        let drift = (t as f64 * self.params.drift_ppm * 1e-6).round() as i64;
        self.params
            .clock_offset_ns
            .saturating_add(t)
            .saturating_add(drift)
    }

    /// True while an `outage=` window is on (`outage_every=` repeats it).
    fn in_outage(&self, now: Instant) -> bool {
        self.params.outage.is_some_and(|(start, length)| {
            let Some(t) = now
                .saturating_duration_since(self.started)
                .checked_sub(start)
            else {
                return false;
            };
            let into = match self.params.outage_every {
                Some(every) => Duration::from_nanos((t.as_nanos() % every.as_nanos()) as u64),
                None => t,
            };
            into < length
        })
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.gen::<f64>() < p
    }

    /// A per-direction fault's draw, from the responders' own draws.
    fn vehicle_chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.vehicle_rng.gen::<f64>() < p
    }

    /// Queues a delivery; false when the queue is full and it is dropped.
    fn enqueue(
        &mut self,
        at: Instant,
        bytes: Vec<u8>,
        payload: Payload,
        frame: Option<Tag>,
    ) -> bool {
        if self.queue.len() >= MAX_QUEUED {
            return false;
        }
        self.order += 1;
        self.queue.push(Reverse(Delivery {
            at,
            order: self.order,
            bytes,
            payload,
            frame,
        }));
        true
    }

    /// Responder `i` sends `what` at `ns` after the link opened.
    fn schedule(&mut self, ns: u64, i: usize, what: Sends) {
        self.outgoing_order += 1;
        self.outgoing.push(Reverse(Outgoing {
            at: self.instant(ns),
            order: self.outgoing_order,
            responder: i,
            what,
        }));
    }

    /// Numbers and sends, in order, every frame the responders send until
    /// `now`.
    fn send_due_frames(&mut self, now: Instant) {
        while self.outgoing.peek().is_some_and(|o| o.0.at <= now) {
            let Reverse(o) = self.outgoing.pop().expect("peeked");
            let i = o.responder;
            match o.what {
                Sends::Heartbeat => {
                    self.send_heartbeat(i, o.at);
                    let schedule = self.responders[i].heartbeat.as_mut().expect("on");
                    schedule.advance();
                    let next = schedule.due_ns();
                    self.schedule(next, i, Sends::Heartbeat);
                }
                Sends::Stream(k) => {
                    self.send_telemetry(i, k, o.at);
                    let schedule = &mut self.responders[i].streams[k].1;
                    schedule.advance();
                    let next = schedule.due_ns();
                    self.schedule(next, i, Sends::Stream(k));
                }
                Sends::Reply(reply) => {
                    let (header, index) = self.responders[i].header();
                    match reply.copies {
                        Some(copies) => {
                            let mut bytes = Vec::new();
                            frame::encode(&mut bytes, reply.version, header, &reply.msg);
                            self.put_on_way(i, index, bytes, copies);
                        }
                        None => self.responders[i].truth.down.dropped += 1,
                    }
                }
            }
        }
    }

    /// A HEARTBEAT sent at `sent`: one leg later at mavping (no jitter, no
    /// wire time), but for the per-direction faults.
    fn send_heartbeat(&mut self, i: usize, sent: Instant) {
        let (header, index) = self.responders[i].header();
        let mut bytes = Vec::new();
        frame::encode(
            &mut bytes,
            Version::V2,
            header,
            &heartbeat(self.params.answer_ping),
        );
        let at = sent + self.params.delay;
        self.send_down(i, index, bytes, at);
    }

    /// A telemetry frame sent at `sent`: through the outage, the wire or
    /// the radios, and the per-direction faults.
    fn send_telemetry(&mut self, i: usize, k: usize, sent: Instant) {
        let kind = self.responders[i].streams[k].0;
        let (header, index) = self.responders[i].header();
        let time_boot_ms = (self.ns(sent) / 1_000_000) as u32;
        let mut bytes = Vec::new();
        frame::encode(
            &mut bytes,
            Version::V2,
            header,
            &kind.msg(time_boot_ms, &heartbeat(self.params.answer_ping)),
        );
        if self.in_outage(sent) {
            self.responders[i].truth.down.dropped += 1;
            return;
        }
        let Some(done) = self.downlink(sent, Duration::ZERO, bytes.len()) else {
            self.responders[i].truth.down.dropped += 1;
            return;
        };
        let at = done + self.vehicle_one_way();
        self.send_down(i, index, bytes, at);
    }

    /// The per-direction faults on a frame of responder `i` due at `at`.
    fn send_down(&mut self, i: usize, index: u64, bytes: Vec<u8>, mut at: Instant) {
        if self.vehicle_chance(self.params.loss_down) {
            self.responders[i].truth.down.dropped += 1;
            return;
        }
        if self.vehicle_chance(self.params.reorder_down) {
            at += self.params.hold;
        }
        let mut copies = [(at, Payload::Plain); 2];
        let mut n = 1;
        if self.vehicle_chance(self.params.dup_down) {
            copies[1].0 = at + self.vehicle_one_way();
            n = 2;
        }
        self.put_on_way(i, index, bytes, (copies, n));
    }

    /// Queues the copies of frame `index` of responder `i`.
    fn put_on_way(&mut self, i: usize, index: u64, bytes: Vec<u8>, (copies, n): Copies) {
        let tag = Some(Tag {
            responder: i,
            index,
        });
        let queued = copies[..n]
            .iter()
            .filter(|(at, payload)| self.enqueue(*at, bytes.clone(), *payload, tag))
            .count();
        let down = &mut self.responders[i].truth.down;
        match queued {
            0 => down.dropped += 1,
            1 => {}
            more => {
                down.duplicated += more as u64 - 1;
                self.responders[i].copies_due.insert(index, more as u8);
            }
        }
    }

    /// When the link must next act on its own: a frame arriving, a
    /// responder sending, RADIO_STATUS.
    fn next_event(&self) -> Option<Instant> {
        let delivery = self.queue.peek().map(|d| d.0.at);
        let outgoing = self.outgoing.peek().map(|o| o.0.at);
        let radio = self.params.radio.then_some(self.next_radio);
        delivery.into_iter().chain(outgoing).chain(radio).min()
    }

    /// Wire time of `bytes` at the link's baud.
    fn wire_time(&self, bytes: usize) -> Duration {
        let baud = u64::from(self.params.baud.unwrap_or(u32::MAX));
        Duration::from_nanos(bytes as u64 * 10 * 1_000_000_000 / baud)
    }

    /// Bytes waiting for the wire at `now`.
    fn backlog_bytes(&self, now: Instant) -> u64 {
        let Some(baud) = self.params.baud else {
            return 0;
        };
        let wait = self
            .wire
            .free_at
            .map_or(Duration::ZERO, |t| t.saturating_duration_since(now));
        (wait.as_nanos() * u128::from(baud) / 10 / 1_000_000_000) as u64
    }

    /// Puts `bytes` on the shared wire: when their last bit is sent, or
    /// None when the buffer is full and they are dropped.
    fn serialise(&mut self, now: Instant, bytes: usize) -> Option<Instant> {
        if self.params.baud.is_none() {
            return Some(now);
        }
        if self.backlog_bytes(now) + bytes as u64 > self.params.buffer {
            return None;
        }
        let start = self.wire.free_at.map_or(now, |t| t.max(now));
        let done = start + self.wire_time(bytes);
        self.wire.free_at = Some(done);
        Some(done)
    }

    /// Nanoseconds since the link opened: the radio pair's time.
    fn ns(&self, t: Instant) -> u64 {
        t.saturating_duration_since(self.started).as_nanos() as u64
    }

    fn instant(&self, ns: u64) -> Instant {
        self.started + Duration::from_nanos(ns)
    }

    /// A frame we send at `now`: when the responders have it, or `None`
    /// when a full buffer drops it.
    fn uplink(&mut self, now: Instant, bytes: usize) -> Option<Instant> {
        let at = self.ns(now);
        match self.pair.as_mut() {
            Some(pair) => {
                let done = pair.uplink(at, bytes as u64).ok()?;
                Some(self.instant(done))
            }
            None => self.serialise(now, bytes),
        }
    }

    /// A reply to a request the responder has from `request_done` on,
    /// answered `up` later: when it reaches us but for the return leg's
    /// delay, or `None` when a full buffer drops it.
    fn downlink(&mut self, request_done: Instant, up: Duration, bytes: usize) -> Option<Instant> {
        let at = self.ns(request_done + up);
        match self.pair.as_mut() {
            Some(pair) => {
                let done = pair.downlink(at, bytes as u64).ok()?;
                Some(self.instant(done))
            }
            // One shared wire: the reply is queued for it when the request
            // is, so the wire's order is the requests' order.
            None => self.serialise(request_done, bytes).map(|done| done + up),
        }
    }

    /// RADIO_STATUS once a second: RSSI falls with the simulated loss,
    /// txbuf is the buffer's free share, rxerrors the drops so far.
    fn queue_radio_status(&mut self, now: Instant) {
        while self.params.radio && self.next_radio <= now {
            let sent = self.next_radio;
            self.next_radio += Duration::from_secs(1);
            let rssi = (200.0 - 300.0 * self.params.loss).clamp(0.0, 254.0) as u8;
            let at = self.ns(sent);
            let txbuf = match self.pair.as_mut() {
                Some(pair) => pair.ground_free_percent(at),
                None => {
                    let buffer = self.params.buffer;
                    let free = buffer.saturating_sub(self.backlog_bytes(sent));
                    (free * 100 / buffer) as u8
                }
            };
            let dropped = self.responders.iter().map(|r| r.truth.dropped).sum::<u64>();
            self.radio_seq = self.radio_seq.wrapping_add(1);
            let header = Header {
                sysid: RADIO_ID.sysid,
                compid: RADIO_ID.compid,
                seq: self.radio_seq,
            };
            let mut bytes = Vec::new();
            frame::encode(
                &mut bytes,
                Version::V2,
                header,
                &Msg::RadioStatus(RadioStatus {
                    rssi,
                    remrssi: rssi,
                    txbuf,
                    noise: 40,
                    remnoise: 40,
                    // Since-boot counters wrap at 65 535, as a radio's do.
                    rxerrors: dropped as u16,
                    fixed: 0,
                }),
            );
            // The radio is the near end: no link delay.
            self.enqueue(sent, bytes, Payload::Plain, None);
        }
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

    /// The simulated link has one path: every responder hears everything.
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
                    self.responders[tag.responder].arrived(tag.index);
                }
                // Stamped with the simulated arrival time: the RTT is
                // exactly the simulated delay, free of scheduler noise.
                push_datagram(&d.bytes, d.at, 0, self.keep_raw, &mut self.stats, out);
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

    use super::*;
    use crate::frame::ids;

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
}
