//! `sim:` — an in-process link with simulated responders and faults.
//!
//! Requests pass through the real encoder and scanner, are answered by the
//! same responder logic as `mavping respond`, and come back after a seeded
//! random delay, maybe dropped, duplicated or held back (reordered). With
//! `clock=virtual` the run uses tokio's paused clock: output is identical on
//! every run and a long simulation takes no wall time.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use tokio::time::{sleep_until, Instant};

use super::{push_datagram, Inbound, LinkError, LinkKind, PathId, RxClock, Transport};
use crate::answering::ResponderCore;
use crate::frame::{self, Header, Msg, RadioStatus, ScanStats, SysComp, Version};
use radio::RadioPair;

mod params;
pub mod radio;
pub use params::{SimParams, DEFAULT_BUFFER_BYTES, SIM_KEYS};

struct SimResponder {
    core: ResponderCore,
    packet_seq: u8,
    next_heartbeat: Instant,
    truth: SimTruth,
    /// A reply of its has been put on its way (delivered or spiked): the
    /// pinger's window for it opens at the first such exchange.
    replied: bool,
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
    /// Extra copies put on their way.
    pub duplicated: u64,
    /// ...of which handed to the pinger before it stopped reading.
    pub duplicates_arrived: u64,
    /// Exchanges the radio's full buffer dropped (`baud=`), also counted
    /// in `dropped`.
    pub overflowed: u64,
    /// Exchanges lost to the outage (`outage=`), also counted in `dropped`.
    pub outage: u64,
    /// Replies delayed by a spike (`spike=`); not in `delivered`: with a
    /// `spike_delay` past the timeout they arrive late.
    pub spiked: u64,
    /// ...of which handed to the pinger before it stopped reading (the
    /// late replies it can have seen).
    pub spiked_arrived: u64,
}

impl SimTruth {
    fn dropped(&mut self, replied: bool) {
        self.dropped += 1;
        self.dropped_before_first += u64::from(!replied);
    }
}

impl SimResponder {
    fn header(&mut self) -> Header {
        self.packet_seq = self.packet_seq.wrapping_add(1);
        Header {
            sysid: self.core.id.sysid,
            compid: self.core.id.compid,
            seq: self.packet_seq,
        }
    }
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
}

/// What a delivery carries, for the ground truth.
#[derive(PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
enum Payload {
    /// HEARTBEAT, RADIO_STATUS, a reply's first copy on time.
    Plain,
    /// A reply's first copy, spiked (responder index).
    Spiked(usize),
    /// A reply's extra copy (responder index).
    Duplicate(usize),
}

/// Queued deliveries are capped so an absurd rate x delay cannot grow
/// memory without bound; past it, replies are dropped like a full queue.
const MAX_QUEUED: usize = 1 << 20;

pub const RADIO_ID: SysComp = SysComp::new(51, 68);

/// The shared wire of a `baud=` link: when it is next free.
#[derive(Default)]
struct Wire {
    free_at: Option<Instant>,
}

pub struct SimLink {
    params: SimParams,
    responders: Vec<SimResponder>,
    rng: SmallRng,
    queue: BinaryHeap<Reverse<Delivery>>,
    order: u64,
    stats: ScanStats,
    started: Instant,
    scratch: Vec<Inbound>,
    wire: Wire,
    next_radio: Instant,
    radio_seq: u8,
    /// `air=`: a radio pair with its own air and buffers, instead of one
    /// shared wire.
    pair: Option<Box<RadioPair>>,
}

impl SimLink {
    pub fn new(params: SimParams) -> Self {
        let now = Instant::now();
        let responders = (0..params.responders)
            .map(|i| {
                let mut core = ResponderCore::new(params.responder_id(i));
                core.answer_ping = params.answer_ping;
                SimResponder {
                    core,
                    packet_seq: 0,
                    next_heartbeat: now,
                    truth: SimTruth::default(),
                    replied: false,
                }
            })
            .collect();
        let pair = params
            .air
            .zip(params.baud)
            .map(|(air, baud)| Box::new(RadioPair::new(baud, &air, params.buffer)));
        SimLink {
            rng: SmallRng::seed_from_u64(params.seed),
            params,
            responders,
            queue: BinaryHeap::new(),
            order: 0,
            stats: ScanStats::default(),
            started: now,
            scratch: Vec::new(),
            wire: Wire::default(),
            next_radio: now,
            radio_seq: 0,
            pair,
        }
    }

    /// Ground truth per responder, in responder order.
    pub fn truth(&self) -> Vec<(SysComp, SimTruth)> {
        self.responders
            .iter()
            .map(|r| (r.core.id, r.truth))
            .collect()
    }

    fn one_way(&mut self) -> Duration {
        let jitter = self.params.jitter.as_nanos() as u64;
        let extra = if jitter == 0 {
            0
        } else {
            self.rng.gen_range(0..=jitter)
        };
        self.params.delay + Duration::from_nanos(extra)
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

    fn enqueue(&mut self, at: Instant, bytes: Vec<u8>, payload: Payload) {
        if self.queue.len() < MAX_QUEUED {
            self.order += 1;
            self.queue.push(Reverse(Delivery {
                at,
                order: self.order,
                bytes,
                payload,
            }));
        }
    }

    fn queue_heartbeats(&mut self, now: Instant) {
        if !self.params.heartbeat {
            return;
        }
        for i in 0..self.responders.len() {
            while self.responders[i].next_heartbeat <= now {
                let sent = self.responders[i].next_heartbeat;
                self.responders[i].next_heartbeat += Duration::from_secs(1);
                let header = self.responders[i].header();
                let mut bytes = Vec::new();
                frame::encode(
                    &mut bytes,
                    Version::V2,
                    header,
                    &Msg::Heartbeat {
                        mav_type: 2,   // quadrotor
                        autopilot: 12, // PX4
                    },
                );
                let at = sent + self.params.delay;
                self.enqueue(at, bytes, Payload::Plain);
            }
        }
    }

    fn next_heartbeat(&self) -> Option<Instant> {
        let heartbeat = self
            .params
            .heartbeat
            .then(|| self.responders.iter().map(|r| r.next_heartbeat).min())
            .flatten();
        let radio = self.params.radio.then_some(self.next_radio);
        heartbeat.into_iter().chain(radio).min()
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
            self.enqueue(sent, bytes, Payload::Plain);
        }
    }
}

impl Transport for SimLink {
    async fn send(&mut self, bytes: &[u8]) -> Result<Instant, LinkError> {
        let now = Instant::now();
        let mut requests = std::mem::take(&mut self.scratch);
        requests.clear();
        // Requests go through the real scanner, as on a wire.
        let mut ignored = ScanStats::default();
        push_datagram(bytes, now, 0, &mut ignored, &mut requests);
        // The request's own wire time; a full buffer loses it for everyone.
        let Some(sent_done) = self.uplink(now, bytes.len()) else {
            for request in &requests {
                for i in 0..self.responders.len() {
                    if self.responders[i].core.answer(&request.frame, 0).is_some() {
                        let r = &mut self.responders[i];
                        r.truth.answered += 1;
                        r.truth.dropped(r.replied);
                        r.truth.overflowed += 1;
                    }
                }
            }
            self.scratch = requests;
            return Ok(now);
        };
        for request in &requests {
            for i in 0..self.responders.len() {
                let Some(mut reply) = self.responders[i].core.answer(&request.frame, 0) else {
                    continue;
                };
                self.responders[i].truth.answered += 1;
                if self.in_outage(now) {
                    let r = &mut self.responders[i];
                    r.truth.dropped(r.replied);
                    r.truth.outage += 1;
                    continue;
                }
                // Loss is drawn once per exchange: request or reply leg.
                if self.chance(self.params.loss) {
                    let r = &mut self.responders[i];
                    r.truth.dropped(r.replied);
                    continue;
                }
                let up = self.one_way();
                // A real responder reads its clock when the request arrives,
                // one leg after we sent it: that is what makes the NTP
                // offset estimate unbiased.
                if let Msg::Timesync { tc1, .. } = &mut reply {
                    // Through a radio pair the request arrives once it is
                    // through the air.
                    let read_at = if self.pair.is_some() { sent_done } else { now };
                    *tc1 = self.clock_ns(read_at + up);
                }
                let header = self.responders[i].header();
                let mut out = Vec::new();
                frame::encode(&mut out, request.frame.version, header, &reply);
                let Some(reply_done) = self.downlink(sent_done, up, out.len()) else {
                    let r = &mut self.responders[i];
                    r.truth.dropped(r.replied);
                    r.truth.overflowed += 1;
                    continue;
                };
                self.responders[i].replied = true;
                let mut at = reply_done + self.one_way();
                // Drawn only when asked for, so seeds keep their faults.
                let payload = if self.chance(self.params.spike) {
                    self.responders[i].truth.spiked += 1;
                    at += self.params.spike_delay;
                    Payload::Spiked(i)
                } else {
                    self.responders[i].truth.delivered += 1;
                    Payload::Plain
                };
                if self.chance(self.params.reorder) {
                    at += self.params.hold;
                }
                if self.chance(self.params.dup) {
                    self.responders[i].truth.duplicated += 1;
                    let again = at + self.one_way();
                    self.enqueue(again, out.clone(), Payload::Duplicate(i));
                }
                self.enqueue(at, out, payload);
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
            let next_delivery = self.queue.peek().map(|d| d.0.at);
            let wake = match (next_delivery, self.next_heartbeat()) {
                (Some(a), Some(b)) => a.min(b),
                (Some(a), None) | (None, Some(a)) => a,
                (None, None) => return std::future::pending().await,
            };
            // The only await: everything after it runs to completion, so a
            // cancelled recv loses nothing.
            sleep_until(wake).await;
            let now = Instant::now();
            self.queue_heartbeats(now);
            self.queue_radio_status(now);
            let before = out.len();
            while self.queue.peek().is_some_and(|d| d.0.at <= now) {
                let Reverse(d) = self.queue.pop().expect("peeked");
                match d.payload {
                    Payload::Plain => {}
                    Payload::Spiked(i) => self.responders[i].truth.spiked_arrived += 1,
                    Payload::Duplicate(i) => self.responders[i].truth.duplicates_arrived += 1,
                }
                // Stamped with the simulated arrival time: the RTT is
                // exactly the simulated delay, free of scheduler noise.
                push_datagram(&d.bytes, d.at, 0, &mut self.stats, out);
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

    fn rx_clock(&self) -> RxClock {
        RxClock::Simulated
    }
}
