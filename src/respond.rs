//! `mavping respond`: a well-behaved MAVLink system on any link, answering
//! PING, TIMESYNC and COMMAND_LONG through [`ResponderCore`], with optional
//! link emulation (delay, jitter, drop, duplicate) for tests.
//!
//! Every answer goes back only on the path its request came from
//! (`send_to`): one reply per request, never amplified to other peers.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::sync::Arc;
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use tokio::sync::Notify;
use tokio::time::{sleep_until, Instant};

use crate::config::RespondConfig;
use crate::frame::signing::{self, Gate, Signer, SigningCounts};
use crate::frame::{self, Header, Msg, SysComp, Version};
use crate::responder::{ResponderCore, ResponderCounts};
use crate::transport::{Inbound, LinkError, PathId, Transport};

/// Replies held back by `--delay` at once; past it they are dropped (and
/// counted), so memory stays bounded whatever the request rate.
const MAX_HELD: usize = 1 << 16;
const HEARTBEAT_PERIOD: Duration = Duration::from_secs(1);
/// A companion-computer-like system, not a vehicle: it answers probes but
/// flies nothing.
const OUR_HEARTBEAT: Msg = Msg::Heartbeat {
    mav_type: frame::mav_type::ONBOARD_CONTROLLER,
    autopilot: frame::AUTOPILOT_INVALID,
};

/// Ground truth printed on exit, to hold a pinger's figures against.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct RespondCounts {
    pub requests: ResponderCounts,
    pub replies_sent: u64,
    pub dropped: u64,
    pub duplicated: u64,
    /// Replies dropped because too many were held by `--delay`.
    pub overflow: u64,
    /// With a signing key: frames accepted and refused by signature.
    pub signing: Option<SigningCounts>,
}

impl std::fmt::Display for RespondCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let r = &self.requests;
        write!(
            f,
            "{} requests ({} ping, {} timesync, {} command, {} command retransmissions), \
             {} replies sent, {} dropped, {} duplicated",
            r.requests(),
            r.ping_requests,
            r.timesync_requests,
            r.commands,
            r.retransmissions,
            self.replies_sent,
            self.dropped,
            self.duplicated
        )?;
        if self.overflow > 0 {
            write!(f, ", {} dropped (too many held)", self.overflow)?;
        }
        if let Some(signing) = &self.signing {
            write!(f, "; signing: {signing}")?;
        }
        Ok(())
    }
}

#[derive(PartialEq, Eq, PartialOrd, Ord)]
struct Held {
    due: Instant,
    order: u64,
    path: PathId,
    bytes: Vec<u8>,
}

struct Responder {
    core: ResponderCore,
    cfg: RespondConfig,
    rng: SmallRng,
    buf: Vec<u8>,
    packet_seq: u8,
    held: BinaryHeap<Reverse<Held>>,
    order: u64,
    counts: RespondCounts,
    epoch: Instant,
    /// Paths (peers) greeted so far: links number new peers upwards and
    /// never reuse a number, so the highest one seen is enough.
    greeted: Option<PathId>,
    /// With a signing key: signs what we send...
    signer: Option<Signer>,
    /// ...and refuses requests not signed with it (or replayed).
    gate: Option<Gate>,
}

impl Responder {
    /// A new peer gets our HEARTBEAT at once rather than within a second:
    /// a GCS or router discovers systems by their HEARTBEAT.
    async fn greet<T: Transport>(&mut self, link: &mut T, path: PathId) -> Result<(), LinkError> {
        if path == PathId::MAX || self.greeted.is_some_and(|g| path <= g) {
            return Ok(());
        }
        self.greeted = Some(path);
        self.encode(Version::V2, &OUR_HEARTBEAT);
        link.send_to(path, &self.buf).await.map(|_| ())
    }

    fn encode(&mut self, version: Version, msg: &Msg) {
        self.buf.clear();
        let header = Header {
            sysid: self.core.id.sysid,
            compid: self.core.id.compid,
            seq: self.packet_seq,
        };
        self.packet_seq = self.packet_seq.wrapping_add(1);
        match self.signer.as_mut() {
            // Signed frames are MAVLink 2 only; only MAVLink 2 requests
            // can pass the gate anyway.
            Some(signer) => {
                frame::encode(&mut self.buf, Version::V2, header, msg);
                signer.sign(&mut self.buf, 0, signing::timestamp_now());
            }
            None => frame::encode(&mut self.buf, version, header, msg),
        }
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.gen::<f64>() < p
    }

    fn hold_time(&mut self) -> Duration {
        let jitter = self.cfg.jitter.as_nanos() as u64;
        let extra = if jitter == 0 {
            0
        } else {
            self.rng.gen_range(0..=jitter)
        };
        self.cfg.delay + Duration::from_nanos(extra)
    }

    /// Answers one inbound frame: sends now, holds for later, or drops.
    async fn handle<T: Transport>(
        &mut self,
        link: &mut T,
        inbound: &Inbound,
    ) -> Result<(), LinkError> {
        // Our clock for TIMESYNC: ns since we started (like an autopilot's
        // boot time), read when the request arrived.
        let clock_ns = (inbound.at - self.epoch).as_nanos() as i64 + 1;
        if let Some(gate) = self.gate.as_mut() {
            let frame = &inbound.frame;
            let radio = matches!(frame.msg, Msg::RadioStatus { .. });
            let verdict = gate.judge(frame.source, inbound.signature.as_ref(), radio);
            if !verdict.accepted() {
                tracing::debug!(from = %frame.source, msgid = frame.msgid, ?verdict, "frame refused");
                return Ok(());
            }
        }
        let Some(reply) = self.core.answer(&inbound.frame, clock_ns) else {
            return Ok(());
        };
        if self.chance(self.cfg.drop) {
            self.counts.dropped += 1;
            return Ok(());
        }
        let copies = if self.chance(self.cfg.dup) {
            self.counts.duplicated += 1;
            2
        } else {
            1
        };
        // Answer in the version we were asked in: a MAVLink 1 stack may not
        // parse MAVLink 2.
        self.encode(inbound.frame.version, &reply);
        for _ in 0..copies {
            let hold = self.hold_time();
            if hold.is_zero() {
                link.send_to(inbound.path, &self.buf).await?;
                self.counts.replies_sent += 1;
            } else if self.held.len() >= MAX_HELD {
                self.counts.overflow += 1;
            } else {
                self.order += 1;
                self.held.push(Reverse(Held {
                    due: inbound.at + hold,
                    order: self.order,
                    path: inbound.path,
                    bytes: self.buf.clone(),
                }));
            }
        }
        Ok(())
    }

    async fn send_due<T: Transport>(
        &mut self,
        link: &mut T,
        now: Instant,
    ) -> Result<(), LinkError> {
        while self.held.peek().is_some_and(|h| h.0.due <= now) {
            let Reverse(h) = self.held.pop().expect("peeked");
            link.send_to(h.path, &h.bytes).await?;
            self.counts.replies_sent += 1;
        }
        Ok(())
    }
}

/// Answers until `stop` (Ctrl-C, SIGTERM) or a link failure; returns the
/// counts either way.
pub async fn run<T: Transport>(
    cfg: &RespondConfig,
    link: &mut T,
    stop: Arc<Notify>,
) -> (RespondCounts, Option<LinkError>) {
    let mut core = ResponderCore::new(cfg.id);
    core.answer_ping = cfg.answer_ping;
    let epoch = Instant::now();
    let mut r = Responder {
        core,
        cfg: cfg.clone(),
        rng: SmallRng::seed_from_u64(cfg.seed),
        buf: Vec::with_capacity(frame::scanner::MAX_FRAME_LEN),
        packet_seq: 0,
        held: BinaryHeap::new(),
        order: 0,
        counts: RespondCounts::default(),
        epoch,
        greeted: None,
        signer: cfg.signing.as_ref().map(|s| s.signer()),
        gate: cfg.signing.map(Gate::new),
    };
    let mut next_heartbeat = epoch;
    let mut inbound: Vec<Inbound> = Vec::new();
    let error = loop {
        let now = Instant::now();
        if next_heartbeat <= now {
            r.encode(Version::V2, &OUR_HEARTBEAT);
            if let Err(e) = link.send(&r.buf).await {
                break Some(e);
            }
            next_heartbeat += HEARTBEAT_PERIOD;
        }
        if let Err(e) = r.send_due(link, now).await {
            break Some(e);
        }
        let wake = r
            .held
            .peek()
            .map_or(next_heartbeat, |h| h.0.due.min(next_heartbeat));
        tokio::select! {
            biased;
            _ = stop.notified() => break None,
            received = link.recv(&mut inbound) => {
                if let Err(e) = received {
                    break Some(e);
                }
                // Taken out and put back so the buffer is reused, not
                // reallocated per datagram.
                let batch = std::mem::take(&mut inbound);
                let mut failed = None;
                for i in &batch {
                    if let Err(e) = r.greet(link, i.path).await {
                        failed = Some(e);
                        break;
                    }
                    if let Err(e) = r.handle(link, i).await {
                        failed = Some(e);
                        break;
                    }
                }
                inbound = batch;
                inbound.clear();
                if failed.is_some() {
                    break failed;
                }
            }
            _ = sleep_until(wake) => {}
        }
    };
    r.counts.requests = r.core.counts;
    r.counts.signing = r.gate.as_ref().map(Gate::counts);
    (r.counts, error)
}

/// Who we are, for the first line.
pub fn describe(cfg: &RespondConfig, link_name: &str) -> String {
    let SysComp { sysid, compid } = cfg.id;
    let what = if cfg.answer_ping {
        "PING, TIMESYNC and COMMAND_LONG"
    } else {
        "TIMESYNC and COMMAND_LONG (not PING)"
    };
    let signed = if cfg.signing.is_some() {
        " (signed requests only)"
    } else {
        ""
    };
    format!("mavping respond: {sysid}/{compid} on {link_name}, answering {what}{signed}")
}
