//! `sim:` — an in-process link with simulated responders and faults.
//!
//! Requests pass through the real encoder and scanner, are answered by the
//! same responder logic as `mavping respond`, and come back after a seeded
//! random delay, maybe dropped, duplicated or held back (reordered). With
//! `clock=virtual` the run uses tokio's paused clock: output is identical on
//! every run and a long simulation takes no wall time.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fmt;
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use tokio::time::{sleep_until, Instant};

use super::{push_datagram, Inbound, LinkError, PathId, RxClock, Transport};
use crate::frame::{self, Header, Msg, ScanStats, SysComp, Version};
use crate::responder::ResponderCore;

#[derive(Debug, Clone, PartialEq)]
pub struct SimParams {
    pub responders: u16,
    /// sysid of the first responder; the others follow (1, 2, 3, ...).
    pub first_sysid: u8,
    pub compid: u8,
    /// One-way delay.
    pub delay: Duration,
    /// Extra one-way delay, uniform in [0, jitter], drawn per direction.
    pub jitter: Duration,
    /// Share of exchanges lost, 0..=1.
    pub loss: f64,
    /// Share of replies delivered twice.
    pub dup: f64,
    /// Share of replies held back by `hold` (arrive after later replies).
    pub reorder: f64,
    pub hold: Duration,
    pub seed: u64,
    /// Paused tokio clock: deterministic output, no waiting.
    pub virtual_clock: bool,
    /// False: responders send HEARTBEAT but ignore PING (like ArduPilot).
    pub answer_ping: bool,
    pub heartbeat: bool,
    /// Responders' clocks read `offset + (1 + drift·1e-6)·t`, t = ns since
    /// the link opened: the truth a TIMESYNC measurement is held against.
    pub clock_offset_ns: i64,
    pub drift_ppm: f64,
    /// A serial radio link at this baud: every frame takes its bytes x 10
    /// bits of wire time, requests and replies share it (half duplex, as
    /// SiK), and a bounded buffer drops what does not fit.
    pub baud: Option<u32>,
    /// Emit RADIO_STATUS as 51/68 once a second, following the link.
    pub radio: bool,
    /// A link outage: from `start` after the link opened, for `length`,
    /// every request and reply is lost.
    pub outage: Option<(Duration, Duration)>,
    /// Share of replies hit by a delay spike of `spike_delay` extra.
    pub spike: f64,
    pub spike_delay: Duration,
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            responders: 1,
            first_sysid: 1,
            compid: 1,
            delay: Duration::from_millis(10),
            jitter: Duration::from_millis(2),
            loss: 0.0,
            dup: 0.0,
            reorder: 0.0,
            hold: Duration::from_millis(50),
            seed: 1,
            virtual_clock: false,
            answer_ping: true,
            heartbeat: true,
            clock_offset_ns: 0,
            drift_ppm: 0.0,
            baud: None,
            radio: false,
            outage: None,
            spike: 0.0,
            spike_delay: Duration::from_millis(500),
        }
    }
}

/// The keys `sim:` accepts, for error messages and the README.
pub const SIM_KEYS: &str = "responders=N (1-1000), sysid=N, compid=N, delay=DURATION, \
jitter=DURATION, loss=PCT, dup=PCT, reorder=PCT, hold=DURATION, seed=N, clock=real|virtual, \
ping=on|off, heartbeat=on|off, offset=[-]DURATION, drift=PPM, baud=N, radio=on|off, \
outage=START+LENGTH, spike=PCT, spike_delay=DURATION";

fn percent(key: &str, value: &str) -> Result<f64, String> {
    let number = value.strip_suffix('%').unwrap_or(value);
    match number.parse::<f64>() {
        Ok(p) if (0.0..=100.0).contains(&p) => Ok(p / 100.0),
        _ => Err(format!(
            "{key}={value}: expected a percentage from 0 to 100"
        )),
    }
}

fn duration(key: &str, value: &str) -> Result<Duration, String> {
    let d = humantime::parse_duration(value)
        .map_err(|e| format!("{key}={value}: {e} (e.g. 20ms, 1.5s)"))?;
    if d > Duration::from_secs(3600) {
        return Err(format!("{key}={value}: at most 1h"));
    }
    Ok(d)
}

fn switch(key: &str, value: &str) -> Result<bool, String> {
    match value {
        "on" | "1" | "true" | "yes" => Ok(true),
        "off" | "0" | "false" | "no" => Ok(false),
        _ => Err(format!("{key}={value}: expected on or off")),
    }
}

fn number<T: std::str::FromStr>(key: &str, value: &str, range: &str) -> Result<T, String> {
    value
        .parse()
        .map_err(|_| format!("{key}={value}: expected {range}"))
}

impl SimParams {
    /// Parses the part after `sim:`: empty, or `?key=value&key=value`.
    pub fn parse(query: &str) -> Result<Self, String> {
        let mut p = SimParams::default();
        let query = query.strip_prefix('?').unwrap_or(query);
        for pair in query.split('&').filter(|s| !s.is_empty()) {
            let (key, value) = pair
                .split_once('=')
                .ok_or_else(|| format!("'{pair}' is not key=value; keys: {SIM_KEYS}"))?;
            match key {
                "responders" => {
                    p.responders = number(key, value, "1 to 1000")?;
                    if !(1..=1000).contains(&p.responders) {
                        return Err(format!("{key}={value}: expected 1 to 1000"));
                    }
                }
                "sysid" => {
                    p.first_sysid = number(key, value, "1 to 255")?;
                    if p.first_sysid == 0 {
                        return Err(format!("{key}={value}: expected 1 to 255"));
                    }
                }
                "compid" => {
                    p.compid = number(key, value, "1 to 255")?;
                    if p.compid == 0 {
                        return Err(format!("{key}={value}: expected 1 to 255"));
                    }
                }
                "delay" => p.delay = duration(key, value)?,
                "jitter" => p.jitter = duration(key, value)?,
                "hold" => p.hold = duration(key, value)?,
                "loss" => p.loss = percent(key, value)?,
                "dup" => p.dup = percent(key, value)?,
                "reorder" => p.reorder = percent(key, value)?,
                "seed" => p.seed = number(key, value, "a whole number")?,
                "clock" => {
                    p.virtual_clock = match value {
                        "virtual" => true,
                        "real" => false,
                        _ => return Err(format!("{key}={value}: expected real or virtual")),
                    }
                }
                "ping" => p.answer_ping = switch(key, value)?,
                "heartbeat" => p.heartbeat = switch(key, value)?,
                "offset" => {
                    let (negative, magnitude) = match value.strip_prefix('-') {
                        Some(rest) => (true, rest),
                        None => (false, value.strip_prefix('+').unwrap_or(value)),
                    };
                    let ns = humantime::parse_duration(magnitude)
                        .ok()
                        .and_then(|d| i64::try_from(d.as_nanos()).ok())
                        .filter(|ns| *ns <= 10 * 365 * 86_400 * 1_000_000_000)
                        .ok_or_else(|| {
                            format!("{key}={value}: expected a duration up to 10 years, e.g. 1.5s or -250ms")
                        })?;
                    p.clock_offset_ns = if negative { -ns } else { ns };
                }
                "drift" => {
                    p.drift_ppm = number(key, value, "parts per million, -1000000 to 1000000")?;
                    if !p.drift_ppm.is_finite() || p.drift_ppm.abs() > 1e6 {
                        return Err(format!("{key}={value}: expected -1000000 to 1000000 ppm"));
                    }
                }
                "baud" => {
                    let baud: u32 = number(key, value, "a baud rate from 300 to 10000000")?;
                    if !(300..=10_000_000).contains(&baud) {
                        return Err(format!(
                            "{key}={value}: expected a baud rate from 300 to 10000000"
                        ));
                    }
                    p.baud = Some(baud);
                }
                "radio" => p.radio = switch(key, value)?,
                "outage" => {
                    let (start, length) = value.split_once('+').ok_or_else(|| {
                        format!("{key}={value}: expected START+LENGTH, e.g. outage=30s+5s")
                    })?;
                    p.outage = Some((duration(key, start)?, duration(key, length)?));
                }
                "spike" => p.spike = percent(key, value)?,
                "spike_delay" => p.spike_delay = duration(key, value)?,
                _ => return Err(format!("unknown key '{key}'; keys: {SIM_KEYS}")),
            }
        }
        // Responders are numbered by sysid; the last one must still fit.
        if usize::from(p.first_sysid) + usize::from(p.responders) - 1 > 255 * 255 {
            return Err("too many responders for the sysid range".into());
        }
        Ok(p)
    }

    /// The ids of responder `i`: sysids count up from `first_sysid`, and
    /// past 255 the component id counts up too, so 1,000 stay distinct.
    pub fn responder_id(&self, i: u16) -> SysComp {
        let slot = usize::from(self.first_sysid) - 1 + usize::from(i);
        SysComp::new(
            (slot % 255 + 1) as u8,
            (usize::from(self.compid) - 1 + slot / 255) as u8 % 255 + 1,
        )
    }
}

impl fmt::Display for SimParams {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "sim:?responders={}&delay={}&jitter={}&loss={}%&dup={}%&reorder={}%&seed={}",
            self.responders,
            humantime::format_duration(self.delay),
            humantime::format_duration(self.jitter),
            self.loss * 100.0,
            self.dup * 100.0,
            self.reorder * 100.0,
            self.seed
        )?;
        if self.clock_offset_ns != 0 {
            // Seconds as a number: humantime's "3s 250ms" has a space.
            write!(f, "&offset={}s", self.clock_offset_ns as f64 / 1e9)?;
        }
        if self.drift_ppm != 0.0 {
            write!(f, "&drift={}", self.drift_ppm)?;
        }
        if let Some(baud) = self.baud {
            write!(f, "&baud={baud}")?;
        }
        if self.radio {
            write!(f, "&radio=on")?;
        }
        if let Some((start, length)) = self.outage {
            write!(
                f,
                "&outage={}+{}",
                humantime::format_duration(start),
                humantime::format_duration(length)
            )?;
        }
        if self.spike > 0.0 {
            write!(
                f,
                "&spike={}%&spike_delay={}",
                self.spike * 100.0,
                humantime::format_duration(self.spike_delay)
            )?;
        }
        Ok(())
    }
}

struct SimResponder {
    core: ResponderCore,
    packet_seq: u8,
    next_heartbeat: Instant,
    truth: SimTruth,
}

/// What the simulated link did to one responder's exchanges: the ground
/// truth tests hold mavping's counts against.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct SimTruth {
    /// Requests the responder answered (before faults).
    pub answered: u64,
    /// Exchanges the link dropped...
    pub dropped: u64,
    /// ...of which before the first delivered reply (outside the window).
    pub dropped_before_first: u64,
    /// Replies delivered (first copies).
    pub delivered: u64,
    /// Extra copies delivered.
    pub duplicated: u64,
    /// Exchanges the radio's full buffer dropped (`baud=`), also counted
    /// in `dropped`.
    pub overflowed: u64,
    /// Exchanges lost to the outage (`outage=`), also counted in `dropped`.
    pub outage: u64,
    /// Replies delayed by a spike (`spike=`); not in `delivered`: with a
    /// `spike_delay` past the timeout they arrive late.
    pub spiked: u64,
    /// ...of which before the first delivered reply.
    pub spiked_before_first: u64,
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
}

/// Queued deliveries are capped so an absurd rate x delay cannot grow
/// memory without bound; past it, replies are dropped like a full queue.
const MAX_QUEUED: usize = 1 << 20;

/// The simulated radio's transmit buffer (`baud=`): bytes waiting for the
/// wire beyond this are dropped, as a radio drops what its buffer cannot
/// hold.
pub const RADIO_BUFFER_BYTES: u64 = 1024;
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
                }
            })
            .collect();
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

    /// True while the `outage=` window is on.
    fn in_outage(&self, now: Instant) -> bool {
        self.params.outage.is_some_and(|(start, length)| {
            let t = now.saturating_duration_since(self.started);
            t >= start && t < start + length
        })
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.gen::<f64>() < p
    }

    fn enqueue(&mut self, at: Instant, bytes: Vec<u8>) {
        if self.queue.len() < MAX_QUEUED {
            self.order += 1;
            self.queue.push(Reverse(Delivery {
                at,
                order: self.order,
                bytes,
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
                self.enqueue(at, bytes);
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
        if self.backlog_bytes(now) + bytes as u64 > RADIO_BUFFER_BYTES {
            return None;
        }
        let start = self.wire.free_at.map_or(now, |t| t.max(now));
        let done = start + self.wire_time(bytes);
        self.wire.free_at = Some(done);
        Some(done)
    }

    /// RADIO_STATUS once a second: RSSI falls with the simulated loss,
    /// txbuf is the buffer's free share, rxerrors the drops so far.
    fn queue_radio_status(&mut self, now: Instant) {
        while self.params.radio && self.next_radio <= now {
            let sent = self.next_radio;
            self.next_radio += Duration::from_secs(1);
            let rssi = (200.0 - 300.0 * self.params.loss).clamp(0.0, 254.0) as u8;
            let free = RADIO_BUFFER_BYTES.saturating_sub(self.backlog_bytes(sent));
            let txbuf = (free * 100 / RADIO_BUFFER_BYTES) as u8;
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
                &Msg::RadioStatus {
                    rssi,
                    remrssi: rssi,
                    txbuf,
                    noise: 40,
                    remnoise: 40,
                    // Since-boot counters wrap at 65 535, as a radio's do.
                    rxerrors: dropped as u16,
                    fixed: 0,
                },
            );
            // The radio is the near end: no link delay.
            self.enqueue(sent, bytes);
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
        let Some(sent_done) = self.serialise(now, bytes.len()) else {
            for request in &requests {
                for i in 0..self.responders.len() {
                    if self.responders[i].core.answer(&request.frame, 0).is_some() {
                        let truth = &mut self.responders[i].truth;
                        truth.answered += 1;
                        truth.dropped += 1;
                        truth.overflowed += 1;
                        truth.dropped_before_first += u64::from(truth.delivered == 0);
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
                    let truth = &mut self.responders[i].truth;
                    truth.dropped += 1;
                    truth.outage += 1;
                    truth.dropped_before_first += u64::from(truth.delivered == 0);
                    continue;
                }
                // Loss is drawn once per exchange: request or reply leg.
                if self.chance(self.params.loss) {
                    let truth = &mut self.responders[i].truth;
                    truth.dropped += 1;
                    truth.dropped_before_first += u64::from(truth.delivered == 0);
                    continue;
                }
                let up = self.one_way();
                // A real responder reads its clock when the request arrives,
                // one leg after we sent it: that is what makes the NTP
                // offset estimate unbiased.
                if let Msg::Timesync { tc1, .. } = &mut reply {
                    *tc1 = self.clock_ns(now + up);
                }
                let header = self.responders[i].header();
                let mut out = Vec::new();
                frame::encode(&mut out, request.frame.version, header, &reply);
                // Simplification: the reply is queued for the wire when the
                // request is, so the wire's order is the requests' order.
                let Some(reply_done) = self.serialise(sent_done, out.len()) else {
                    let truth = &mut self.responders[i].truth;
                    truth.dropped += 1;
                    truth.overflowed += 1;
                    truth.dropped_before_first += u64::from(truth.delivered == 0);
                    continue;
                };
                let mut at = reply_done + up + self.one_way();
                // Drawn only when asked for, so seeds keep their faults.
                if self.chance(self.params.spike) {
                    let truth = &mut self.responders[i].truth;
                    truth.spiked += 1;
                    truth.spiked_before_first += u64::from(truth.delivered == 0);
                    at += self.params.spike_delay;
                } else {
                    self.responders[i].truth.delivered += 1;
                }
                if self.chance(self.params.reorder) {
                    at += self.params.hold;
                }
                if self.chance(self.params.dup) {
                    self.responders[i].truth.duplicated += 1;
                    let again = at + self.one_way();
                    self.enqueue(again, out.clone());
                }
                self.enqueue(at, out);
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

    fn rx_clock(&self) -> RxClock {
        RxClock::Simulated
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_key() {
        let p = SimParams::parse(
            "?responders=3&sysid=10&compid=2&delay=20ms&jitter=5ms&loss=2%&dup=1&reorder=0.5%\
             &hold=30ms&seed=7&clock=virtual&ping=off&heartbeat=on",
        )
        .unwrap();
        assert_eq!(p.responders, 3);
        assert_eq!(p.responder_id(2), SysComp::new(12, 2));
        assert_eq!(p.delay, Duration::from_millis(20));
        assert_eq!(p.jitter, Duration::from_millis(5));
        assert!((p.loss - 0.02).abs() < 1e-12);
        assert!((p.dup - 0.01).abs() < 1e-12);
        assert!((p.reorder - 0.005).abs() < 1e-12);
        assert_eq!(p.seed, 7);
        assert!(p.virtual_clock);
        assert!(!p.answer_ping);
        assert_eq!(SimParams::parse("").unwrap(), SimParams::default());
        let p = SimParams::parse("?offset=-1.5s&drift=-20.5").unwrap();
        assert_eq!(p.clock_offset_ns, -1_500_000_000);
        assert_eq!(p.drift_ppm, -20.5);
        assert_eq!(
            SimParams::parse("?offset=+250ms").unwrap().clock_offset_ns,
            250_000_000
        );
        let p = SimParams::parse("?outage=30s+5s&spike=1%&spike_delay=2s").unwrap();
        assert_eq!(
            p.outage,
            Some((Duration::from_secs(30), Duration::from_secs(5)))
        );
        assert!((p.spike - 0.01).abs() < 1e-12);
        assert_eq!(p.spike_delay, Duration::from_secs(2));
        assert_eq!(
            SimParams::parse(&p.to_string()[4..]).unwrap().outage,
            p.outage
        );
    }

    #[test]
    fn rejects_bad_values_with_the_reason() {
        for (q, needle) in [
            ("?loss=120%", "percentage"),
            ("?outage=5s", "START+LENGTH"),
            ("?outage=5s+2h", "at most 1h"),
            ("?spike=-1", "percentage"),
            ("?responders=0", "1 to 1000"),
            ("?delay=soon", "delay=soon"),
            ("?delay=2h", "at most 1h"),
            ("?warp=9", "unknown key 'warp'"),
            ("?loss", "not key=value"),
            ("?clock=fast", "real or virtual"),
            ("?offset=soon", "offset=soon"),
            ("?offset=20y", "up to 10 years"),
            ("?drift=2e6", "ppm"),
            ("?drift=fast", "parts per million"),
        ] {
            let err = SimParams::parse(q).unwrap_err();
            assert!(err.contains(needle), "{q}: {err}");
        }
    }

    #[test]
    fn a_thousand_responders_have_distinct_ids() {
        let p = SimParams::parse("?responders=1000").unwrap();
        let ids: std::collections::HashSet<_> = (0..1000).map(|i| p.responder_id(i)).collect();
        assert_eq!(ids.len(), 1000);
        assert!(ids.iter().all(|id| id.sysid != 0 && id.compid != 0));
    }

    #[test]
    fn baud_and_radio_parse_and_bad_values_are_refused() {
        let p = SimParams::parse("?baud=57600&radio=on").unwrap();
        assert_eq!((p.baud, p.radio), (Some(57_600), true));
        assert!(p.to_string().ends_with("&baud=57600&radio=on"));
        for bad in ["?baud=0", "?baud=fast", "?radio=maybe"] {
            assert!(SimParams::parse(bad).is_err(), "{bad}");
        }
    }
}
