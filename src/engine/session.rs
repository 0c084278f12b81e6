//! One measurement run: sends on schedule, feeds replies to the matcher,
//! reports events, and ends on count, deadline, Ctrl-C or a link failure.
//!
//! The only place that reads a clock. Everything it decides, it decides
//! through the pure matcher with explicit timestamps.

use std::collections::HashMap;
use std::io;
use std::sync::Arc;
use std::time::Duration;

use hdrhistogram::Histogram;
use tokio::sync::Notify;
use tokio::time::{sleep_until, Instant};

use super::matcher::{MatchEvent, Matcher, MAX_RESPONDERS};
use super::radio::{radio_hints, RadioReport, Radios};
use super::roster::Roster;
use super::schedule::Schedule;
use super::stats::RttStats;
use super::summary::{responder_summaries, silent_system_hints, ScheduleSummary, Summary};
use super::Nanos;
use crate::frame::signing::{self, Gate, Signer, SigningConfig};
use crate::frame::{self, Header, Msg, SysComp, Version};
use crate::output::{Event, Reporter, StartInfo};
use crate::probe::{Classified, EchoProbe};
use crate::transport::{Inbound, LinkError, PathId, RxClock, Transport};

/// What the session needs to know, already validated.
#[derive(Debug, Clone)]
pub struct SessionConfig {
    pub link_name: String,
    pub ours: SysComp,
    pub interval: Duration,
    pub count: Option<u64>,
    pub deadline: Option<Duration>,
    pub timeout: Duration,
    pub version: Version,
    /// Send our own HEARTBEAT at 1 Hz (MAVSDK and routers need it).
    pub heartbeat: bool,
    /// Request slots in the matcher's ring.
    pub capacity: usize,
    pub first_seq: u32,
    /// Wait for sends precisely (sub-millisecond) rather than on tokio's
    /// 1 ms timer. Off for the simulated link, whose paused virtual clock
    /// only moves while the runtime is idle.
    pub precise_pacing: bool,
    /// MAVLink 2 signing (`--signing-key`): sign what we send, check what
    /// we receive.
    pub signing: Option<SigningConfig>,
}

/// How the run ended. The caller judges it and reports the summary.
pub struct Outcome {
    pub summary: Summary,
    /// Each responder's RTT histogram (µs), for exports.
    pub histograms: Vec<(SysComp, Histogram<u64>)>,
    /// The report's output went away (closed pipe): stop quietly.
    pub output_closed: bool,
}

pub(super) const HEARTBEAT_PERIOD: Duration = Duration::from_secs(1);
/// MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID: we are a ground station.
pub(super) const OUR_HEARTBEAT: Msg = Msg::Heartbeat {
    mav_type: frame::mav_type::GCS,
    autopilot: frame::AUTOPILOT_INVALID,
};

/// Sends our HEARTBEAT when it is due and schedules the next one; `None`
/// (`--no-heartbeat`) never sends.
pub(super) async fn heartbeat_if_due<T: Transport>(
    link: &mut T,
    sender: &mut Sender,
    next: &mut Option<Nanos>,
    now: Nanos,
) -> Result<(), LinkError> {
    if let Some(due) = next.filter(|&due| due <= now) {
        link.send(sender.frame(&OUR_HEARTBEAT)).await?;
        *next = Some(due + HEARTBEAT_PERIOD.as_nanos() as Nanos);
    }
    Ok(())
}

pub(super) struct Clock {
    pub(super) epoch: Instant,
}

impl Clock {
    pub(super) fn ns(&self, t: Instant) -> Nanos {
        t.saturating_duration_since(self.epoch).as_nanos() as Nanos
    }
    pub(super) fn now(&self) -> Nanos {
        self.ns(Instant::now())
    }
    pub(super) fn at(&self, ns: Nanos) -> Instant {
        self.epoch + Duration::from_nanos(ns)
    }

    /// Sleeps until session time `wake`, or forever when there is none.
    pub(super) async fn sleep_until(&self, wake: Option<Nanos>) {
        match wake {
            Some(ns) => sleep_until(self.at(ns)).await,
            None => std::future::pending().await,
        }
    }
}

pub(super) struct Sender {
    pub(super) buf: Vec<u8>,
    pub(super) packet_seq: u8,
    pub(super) ours: SysComp,
    pub(super) version: Version,
    /// Signs each frame when signing is on (MAVLink 2 only).
    pub(super) signer: Option<Signer>,
}

impl Sender {
    pub(super) fn new(cfg: &SessionConfig) -> Self {
        Sender {
            buf: Vec::with_capacity(frame::scanner::MAX_FRAME_LEN),
            packet_seq: 0,
            ours: cfg.ours,
            version: cfg.version,
            signer: cfg.signing.as_ref().map(SigningConfig::signer),
        }
    }

    /// Serialises `msg` into the reused buffer (no allocation per request).
    pub(super) fn frame(&mut self, msg: &Msg) -> &[u8] {
        self.buf.clear();
        let header = Header {
            sysid: self.ours.sysid,
            compid: self.ours.compid,
            seq: self.packet_seq,
        };
        self.packet_seq = self.packet_seq.wrapping_add(1);
        frame::encode(&mut self.buf, self.version, header, msg);
        if let Some(signer) = self.signer.as_mut() {
            signer.sign(&mut self.buf, 0, signing::timestamp_now());
        }
        &self.buf
    }
}

/// How close to a planned send the session stops trusting tokio's 1 ms
/// timer and waits precisely instead.
const FINE_WINDOW_NS: Nanos = 1_500_000;
/// On links whose replies are stamped when read, the precise wait sleeps
/// in slices of at most this, so a reply waits little to be read...
const SLICE: Duration = Duration::from_micros(200);
/// ...and it spins for the last stretch, which nanosleep (with 1 µs timer
/// slack) overshoots by a few µs.
const SPIN_NS: Nanos = 20_000;
/// Most requests sent back to back before the session reads the link.
const MAX_BURST: usize = 256;
/// Output is buffered; while busy, it reaches the reader this often.
const FLUSH_EVERY_NS: Nanos = 50_000_000;

/// Everything a received frame can change.
struct Intake<'a, P> {
    ours: SysComp,
    matcher: &'a mut Matcher,
    roster: &'a mut Roster,
    radios: &'a mut Radios,
    probe: &'a mut P,
    events: &'a mut Vec<MatchEvent>,
    foreign_replies: &'a mut u64,
    gate: &'a mut Option<Gate>,
    /// The link path each responder answers from (links with several
    /// peers) and when it last did: its ids are believed from that path
    /// only, until it has been silent for a whole timeout (a responder that
    /// restarts or reconnects comes back on a new path).
    paths: &'a mut HashMap<SysComp, (PathId, Nanos)>,
    wrong_path_replies: &'a mut u64,
    timeout: Nanos,
}

impl<P: EchoProbe> Intake<'_, P> {
    fn take(
        &mut self,
        clock: &Clock,
        inbound: &mut Vec<Inbound>,
        report: &mut dyn Reporter,
    ) -> io::Result<()> {
        let mut output = Ok(());
        for Inbound {
            frame,
            at,
            signature,
            path,
        } in inbound.drain(..)
        {
            if !admitted(self.gate, &frame, signature.as_ref()) {
                continue;
            }
            let at = clock.ns(at);
            if let Msg::Heartbeat {
                mav_type,
                autopilot,
            } = frame.msg
            {
                if self.roster.heard(frame.source, mav_type, autopilot, at) {
                    let identity = self.roster.get(frame.source).expect("just added");
                    output = output.and(report.event(&Event::Heard {
                        id: frame.source,
                        identity,
                    }));
                }
                continue;
            }
            // Radios inject this from their own ids on any link.
            if let Msg::RadioStatus {
                rssi,
                remrssi,
                txbuf,
                noise,
                remnoise,
                rxerrors,
                fixed,
            } = frame.msg
            {
                let status = RadioReport {
                    rssi,
                    remrssi,
                    txbuf,
                    noise,
                    remnoise,
                    rxerrors,
                    fixed,
                };
                let first = self.radios.record(frame.source, status, at);
                output = output.and(report.event(&Event::Radio {
                    id: frame.source,
                    at,
                    report: status,
                    first,
                }));
                continue;
            }
            match self.probe.classify(&frame, self.ours) {
                Classified::Reply(lookup) => {
                    // A reply naming a responder that answered from another
                    // peer of this link (a spoofed id, or one system heard
                    // through two routers) is counted, never measured.
                    let timeout = self.timeout;
                    if self
                        .paths
                        .get(&frame.source)
                        .is_some_and(|&(p, last)| p != path && at < last.saturating_add(timeout))
                    {
                        *self.wrong_path_replies += 1;
                        continue;
                    }
                    let before = self.events.len();
                    let events = &mut *self.events;
                    self.matcher
                        .on_reply(frame.source, lookup, at, &mut |e| events.push(e));
                    // Only an accepted in-time reply feeds the probe.
                    for e in &self.events[before..] {
                        if let MatchEvent::Reply {
                            responder,
                            sent_at,
                            at,
                            ..
                        } = *e
                        {
                            if responder == frame.source {
                                self.probe.on_reply(&frame, sent_at, at);
                                // Bound by accepted replies only, so stale
                                // forgeries cannot claim an id.
                                if self.paths.len() < MAX_RESPONDERS
                                    || self.paths.contains_key(&responder)
                                {
                                    self.paths.insert(responder, (path, at));
                                }
                            }
                        }
                    }
                }
                Classified::ForeignReply => *self.foreign_replies += 1,
                Classified::NotAReply => {}
            }
        }
        output.and(flush(self.events, report, self.radios))
    }
}

/// Whether the signing gate (if any) lets `frame` through; what it refuses
/// reaches nothing else, and is counted.
pub(super) fn admitted(
    gate: &mut Option<Gate>,
    frame: &frame::Frame,
    signature: Option<&signing::SignedBytes>,
) -> bool {
    let Some(gate) = gate else {
        return true;
    };
    let radio = matches!(frame.msg, Msg::RadioStatus { .. });
    let verdict = gate.judge(frame.source, signature, radio);
    if !verdict.accepted() {
        tracing::debug!(from = %frame.source, msgid = frame.msgid, ?verdict, "frame refused");
    }
    verdict.accepted()
}

/// Why replies may be missing when the signing gate refused frames.
fn signing_hints(c: &signing::SigningCounts) -> Vec<String> {
    let mut hints = Vec::new();
    if c.rejected_bad_signature > 0 {
        hints.push(format!(
            "{} frames were signed with another key: are both ends using the same signing key?",
            c.rejected_bad_signature
        ));
    }
    if c.rejected_unsigned > 0 && c.signed == 0 {
        hints.push(format!(
            "{} unsigned frames were refused (--require-signed) and none came signed: \
             is signing set up on the other end?",
            c.rejected_unsigned
        ));
    }
    hints
}

/// Polls a future once: its result if it is ready now. Used on cancel-safe
/// futures only (link receive, the stop signal), between precise sleeps.
fn ready_now<F: std::future::Future>(f: F) -> Option<F::Output> {
    let mut f = std::pin::pin!(f);
    let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
    match f.as_mut().poll(&mut cx) {
        std::task::Poll::Ready(v) => Some(v),
        std::task::Poll::Pending => None,
    }
}

/// Lets the OS wake us within a few µs of a requested time instead of the
/// default 50 µs slack (Linux); harmless where it is not supported.
fn tighten_timer_slack() {
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_timerslack(1_000);
}

/// Runs the measurement until it ends and returns what it measured.
pub async fn run<T: Transport, P: EchoProbe>(
    cfg: &SessionConfig,
    link: &mut T,
    mut probe: P,
    report: &mut dyn Reporter,
    stop: Arc<Notify>,
) -> Outcome {
    tighten_timer_slack();
    let clock = Clock {
        epoch: Instant::now(),
    };
    let timeout_ns = cfg.timeout.as_nanos() as Nanos;
    let mut matcher = Matcher::new(timeout_ns, cfg.capacity, cfg.first_seq);
    let mut roster = Roster::default();
    let mut radios = Radios::default();
    let mut sender = Sender::new(cfg);
    let mut gate = cfg.signing.map(Gate::new);
    let mut schedule: Option<Schedule> = None;
    let mut next_heartbeat: Option<Nanos> = cfg.heartbeat.then_some(0);
    let deadline_ns = cfg.deadline.map(|d| d.as_nanos() as Nanos);
    let mut events: Vec<MatchEvent> = Vec::new();
    let mut inbound: Vec<Inbound> = Vec::new();
    let mut foreign_replies = 0u64;
    let mut paths: HashMap<SysComp, (PathId, Nanos)> = HashMap::new();
    let mut wrong_path_replies = 0u64;
    let mut interrupted = false;
    let mut link_error: Option<LinkError> = None;
    let mut pacing = Pacing::default();
    let mut output: io::Result<()> = report.start(&StartInfo {
        link: cfg.link_name.clone(),
        probe: probe.name(),
        ours: cfg.ours,
        interval: cfg.interval,
        timeout: cfg.timeout,
        count: cfg.count,
    });
    let mut told_waiting = false;
    let mut last_flush: Nanos = 0;

    'run: while output.is_ok() {
        let now = clock.now();
        if deadline_ns.is_some_and(|d| now >= d) {
            break;
        }
        // Our HEARTBEAT goes first, so a stack that discovers systems by
        // their messages (MAVSDK) knows us before our first PING.
        if let Err(e) = heartbeat_if_due(link, &mut sender, &mut next_heartbeat, now).await {
            link_error = Some(e);
            break;
        }
        if schedule.is_none() {
            if link.has_peers() {
                schedule = Some(Schedule::new(
                    now,
                    cfg.interval.as_nanos() as Nanos,
                    cfg.count,
                ));
            } else if !told_waiting {
                told_waiting = true;
                output = report.event(&Event::WaitingForPeer);
            }
        }
        if let Some(s) = schedule.as_mut() {
            // At most a burst per turn: a machine too slow for the rate
            // falls behind (and the lateness figures say so) but still
            // reads replies and honours the deadline between bursts.
            for _ in 0..MAX_BURST {
                let Some((_, planned)) = s.take_due(clock.now()) else {
                    break;
                };
                let token = probe.token(clock.now());
                let seq = cfg.first_seq.wrapping_add(matcher.issued() as u32);
                let request = probe.request(seq, token);
                match link.send(sender.frame(&request)).await {
                    Ok(sent) => {
                        let sent = clock.ns(sent);
                        pacing.sent(planned, sent);
                        matcher.on_send(token, sent, &mut |e| events.push(e));
                    }
                    Err(e) => {
                        link_error = Some(e);
                        break 'run;
                    }
                }
            }
        }
        matcher.expire(clock.now(), &mut |e| events.push(e));
        output = flush(&mut events, report, &mut radios);
        if output.is_err() {
            break;
        }
        let sending_done = schedule.as_ref().is_some_and(|s| s.finished());
        if sending_done && (matcher.next_deadline().is_none() || matcher.all_answered()) {
            break;
        }

        let mut intake = Intake {
            ours: cfg.ours,
            matcher: &mut matcher,
            roster: &mut roster,
            radios: &mut radios,
            probe: &mut probe,
            events: &mut events,
            foreign_replies: &mut foreign_replies,
            gate: &mut gate,
            paths: &mut paths,
            wrong_path_replies: &mut wrong_path_replies,
            timeout: timeout_ns,
        };
        let next_send = schedule.as_ref().and_then(|s| s.next_due());
        let now = clock.now();
        // A send is due within the timer's resolution: wait for it
        // precisely, still reading the link between short sleeps.
        let fine = next_send
            .filter(|&due| cfg.precise_pacing && due.saturating_sub(now) <= FINE_WINDOW_NS);
        // Kernel-stamped replies keep their arrival time however late they
        // are read: sleep in one go and save the wake-ups.
        let slice = if link.rx_clock() == RxClock::Kernel {
            Duration::from_nanos(FINE_WINDOW_NS)
        } else {
            SLICE
        };
        if let Some(due) = fine {
            loop {
                let now = clock.now();
                if now >= due {
                    break;
                }
                if ready_now(stop.notified()).is_some() {
                    interrupted = true;
                    break 'run;
                }
                match ready_now(link.recv(&mut inbound)) {
                    Some(Err(e)) => {
                        link_error = Some(e);
                        break 'run;
                    }
                    Some(Ok(())) => {
                        output = intake.take(&clock, &mut inbound, report);
                        if output.is_err() {
                            break 'run;
                        }
                        continue;
                    }
                    None => {}
                }
                if now.saturating_sub(last_flush) > FLUSH_EVERY_NS {
                    last_flush = now;
                    output = report.flush();
                    if output.is_err() {
                        break 'run;
                    }
                }
                let left = due - now;
                if left > SPIN_NS {
                    std::thread::sleep(slice.min(Duration::from_nanos(left - SPIN_NS)));
                } else {
                    std::hint::spin_loop();
                }
            }
            continue;
        }

        let wake = [
            next_send.map(|due| {
                if cfg.precise_pacing {
                    due.saturating_sub(FINE_WINDOW_NS)
                } else {
                    due
                }
            }),
            intake.matcher.next_deadline(),
            next_heartbeat,
            deadline_ns,
        ]
        .into_iter()
        .flatten()
        .min();
        // About to block: let buffered output reach the reader.
        last_flush = now;
        output = report.flush();
        if output.is_err() {
            break;
        }
        let sleep = clock.sleep_until(wake);
        tokio::select! {
            biased;
            _ = stop.notified() => {
                interrupted = true;
                break;
            }
            received = link.recv(&mut inbound) => {
                if let Err(e) = received {
                    link_error = Some(e);
                    break;
                }
                output = intake.take(&clock, &mut inbound, report);
            }
            _ = sleep => {}
        }
    }

    // Decide what is due before counting what is still in flight.
    matcher.expire(clock.now(), &mut |e| events.push(e));
    if output.is_ok() {
        output = flush(&mut events, report, &mut radios);
    }
    let in_flight = matcher.finish();
    let mut responders = responder_summaries(&matcher, &roster);
    for r in &mut responders {
        r.clock = probe.clock(r.id);
    }
    let loss_by_txbuf = radios.loss_by_txbuf();
    let radios = radios.summaries();
    let radio_ids: Vec<SysComp> = radios.iter().map(|r| r.id).collect();
    let mut hints = silent_system_hints(&roster, &responders, cfg.ours, probe.name(), &radio_ids);
    hints.extend(radio_hints(&radios, loss_by_txbuf));
    if let Some(gate) = &gate {
        hints.extend(signing_hints(&gate.counts()));
    }
    let summary = Summary {
        link: cfg.link_name.clone(),
        probe: probe.name(),
        ours: cfg.ours,
        duration_s: clock.now() as f64 / 1e9,
        requests: matcher.issued(),
        in_flight,
        responders,
        foreign_replies,
        wrong_path_replies,
        untracked_replies: matcher.untracked(),
        frames: link.scan_stats(),
        hints,
        interrupted,
        link_error: link_error.map(|e| e.to_string()),
        downtime_s: link.downtime().as_secs_f64(),
        schedule: pacing.summary(cfg.interval),
        rx_clock: link.rx_clock().describe(),
        radios,
        wire: None,
        signing: gate.as_ref().map(Gate::summary),
    };
    let histograms = matcher
        .responders()
        .iter()
        .map(|r| (r.id, r.rtt.histogram().clone()))
        .collect();
    Outcome {
        summary,
        histograms,
        output_closed: output.is_err(),
    }
}

/// How well requests kept to their schedule: achieved rate and how late
/// each went out against its planned time. Late sends mean the machine,
/// not the link, was the bottleneck.
#[derive(Default)]
struct Pacing {
    first: Option<Nanos>,
    last: Nanos,
    count: u64,
    lateness: RttStats,
}

impl Pacing {
    fn sent(&mut self, planned: Nanos, actual: Nanos) {
        self.first.get_or_insert(actual);
        self.last = actual;
        self.count += 1;
        self.lateness.record(actual.saturating_sub(planned));
    }

    fn summary(&self, interval: Duration) -> Option<ScheduleSummary> {
        let first = self.first?;
        let late = self.lateness.summary()?;
        let span = self.last.saturating_sub(first) as f64 / 1e9;
        Some(ScheduleSummary {
            requested_rate_hz: 1.0 / interval.as_secs_f64(),
            achieved_rate_hz: if self.count > 1 && span > 0.0 {
                (self.count - 1) as f64 / span
            } else {
                0.0
            },
            lateness_p50_us: late.p50_us,
            lateness_p99_us: late.p99_us,
            lateness_max_us: late.max_us,
        })
    }
}

fn flush(
    events: &mut Vec<MatchEvent>,
    report: &mut dyn Reporter,
    radios: &mut Radios,
) -> io::Result<()> {
    let mut result = Ok(());
    for e in events.drain(..) {
        // Outcomes against the radio's buffer, for the "overloaded" hint.
        match e {
            MatchEvent::Reply { sent_at, .. } => radios.outcome(false, sent_at),
            MatchEvent::Lost { sent_at, .. } => radios.outcome(true, sent_at),
            _ => {}
        }
        if result.is_ok() {
            result = report.event(&Event::Match(e));
        }
    }
    result
}
