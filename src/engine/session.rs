//! One measurement run: sends on schedule, feeds replies to the matcher,
//! reports events, and ends on count, deadline, Ctrl-C or a link failure.
//!
//! The only place that reads a clock. Everything it decides, it decides
//! through the pure matcher with explicit timestamps.

use std::io;
use std::sync::Arc;
use std::time::Duration;

use hdrhistogram::Histogram;
use tokio::sync::Notify;
use tokio::time::{sleep_until, Instant};

use super::matcher::{MatchEvent, Matcher};
use super::roster::Roster;
use super::schedule::Schedule;
use super::summary::{responder_summaries, silent_system_hints, Summary};
use super::Nanos;
use crate::frame::{self, Header, Msg, SysComp, Version};
use crate::output::{Event, Reporter, StartInfo};
use crate::probe::{Classified, EchoProbe};
use crate::transport::{Inbound, LinkError, Transport};

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
}

pub(super) struct Sender {
    pub(super) buf: Vec<u8>,
    pub(super) packet_seq: u8,
    pub(super) ours: SysComp,
    pub(super) version: Version,
}

impl Sender {
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
        &self.buf
    }
}

/// Runs the measurement until it ends and returns what it measured.
pub async fn run<T: Transport, P: EchoProbe>(
    cfg: &SessionConfig,
    link: &mut T,
    mut probe: P,
    report: &mut dyn Reporter,
    stop: Arc<Notify>,
) -> Outcome {
    let clock = Clock {
        epoch: Instant::now(),
    };
    let timeout_ns = cfg.timeout.as_nanos() as Nanos;
    let mut matcher = Matcher::new(timeout_ns, cfg.capacity, cfg.first_seq);
    let mut roster = Roster::default();
    let mut sender = Sender {
        buf: Vec::with_capacity(frame::scanner::MAX_FRAME_LEN),
        packet_seq: 0,
        ours: cfg.ours,
        version: cfg.version,
    };
    let mut schedule: Option<Schedule> = None;
    let mut next_heartbeat: Option<Nanos> = cfg.heartbeat.then_some(0);
    let deadline_ns = cfg.deadline.map(|d| d.as_nanos() as Nanos);
    let mut events: Vec<MatchEvent> = Vec::new();
    let mut inbound: Vec<Inbound> = Vec::new();
    let mut foreign_replies = 0u64;
    let mut interrupted = false;
    let mut link_error: Option<LinkError> = None;
    let mut output: io::Result<()> = report.start(&StartInfo {
        link: cfg.link_name.clone(),
        probe: probe.name(),
        ours: cfg.ours,
        interval: cfg.interval,
        timeout: cfg.timeout,
        count: cfg.count,
    });
    let mut told_waiting = false;

    'run: while output.is_ok() {
        let now = clock.now();
        if deadline_ns.is_some_and(|d| now >= d) {
            break;
        }
        // Our HEARTBEAT goes first, so a stack that discovers systems by
        // their messages (MAVSDK) knows us before our first PING.
        if let Some(due) = next_heartbeat.filter(|&due| due <= now) {
            if let Err(e) = link.send(sender.frame(&OUR_HEARTBEAT)).await {
                link_error = Some(e);
                break;
            }
            next_heartbeat = Some(due + HEARTBEAT_PERIOD.as_nanos() as Nanos);
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
            while s.take_due(clock.now()).is_some() {
                let token = probe.token(clock.now());
                let seq = cfg.first_seq.wrapping_add(matcher.issued() as u32);
                let request = probe.request(seq, token);
                match link.send(sender.frame(&request)).await {
                    Ok(sent) => {
                        matcher.on_send(token, clock.ns(sent), &mut |e| events.push(e));
                    }
                    Err(e) => {
                        link_error = Some(e);
                        break 'run;
                    }
                }
            }
        }
        matcher.expire(clock.now(), &mut |e| events.push(e));
        output = flush(&mut events, report);
        if output.is_err() {
            break;
        }
        let sending_done = schedule.as_ref().is_some_and(|s| s.finished());
        if sending_done && (matcher.next_deadline().is_none() || matcher.all_answered()) {
            break;
        }

        let wake = [
            schedule.as_ref().and_then(|s| s.next_due()),
            matcher.next_deadline(),
            next_heartbeat,
            deadline_ns,
        ]
        .into_iter()
        .flatten()
        .min();
        let sleep = async {
            match wake {
                Some(ns) => sleep_until(clock.at(ns)).await,
                None => std::future::pending().await,
            }
        };
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
                for Inbound { frame, at, .. } in inbound.drain(..) {
                    let at = clock.ns(at);
                    if let Msg::Heartbeat { mav_type, autopilot } = frame.msg {
                        if roster.heard(frame.source, mav_type, autopilot, at) {
                            let identity = roster.get(frame.source).expect("just added");
                            output = output.and(report.event(&Event::Heard { id: frame.source, identity }));
                        }
                        continue;
                    }
                    match probe.classify(&frame, cfg.ours) {
                        Classified::Reply(lookup) => {
                            let before = events.len();
                            matcher.on_reply(frame.source, lookup, at, &mut |e| events.push(e));
                            // Only an accepted in-time reply feeds the probe.
                            for e in &events[before..] {
                                if let MatchEvent::Reply { responder, sent_at, at, .. } = *e {
                                    if responder == frame.source {
                                        probe.on_reply(&frame, sent_at, at);
                                    }
                                }
                            }
                        }
                        Classified::ForeignReply => foreign_replies += 1,
                        Classified::NotAReply => {}
                    }
                }
                output = output.and(flush(&mut events, report));
            }
            _ = sleep => {}
        }
    }

    // Decide what is due before counting what is still in flight.
    matcher.expire(clock.now(), &mut |e| events.push(e));
    if output.is_ok() {
        output = flush(&mut events, report);
    }
    let in_flight = matcher.finish();
    let mut responders = responder_summaries(&matcher, &roster);
    for r in &mut responders {
        r.clock = probe.clock(r.id);
    }
    let hints = silent_system_hints(&roster, &responders, cfg.ours, probe.name());
    let summary = Summary {
        link: cfg.link_name.clone(),
        probe: probe.name(),
        ours: cfg.ours,
        duration_s: clock.now() as f64 / 1e9,
        requests: matcher.issued(),
        in_flight,
        responders,
        foreign_replies,
        untracked_replies: matcher.untracked(),
        frames: link.scan_stats(),
        hints,
        interrupted,
        link_error: link_error.map(|e| e.to_string()),
        downtime_s: link.downtime().as_secs_f64(),
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

fn flush(events: &mut Vec<MatchEvent>, report: &mut dyn Reporter) -> io::Result<()> {
    let mut result = Ok(());
    for e in events.drain(..) {
        if result.is_ok() {
            result = report.event(&Event::Match(e));
        }
    }
    result
}
