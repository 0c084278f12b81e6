//! `mavping respond`: a well-behaved MAVLink system on any link, answering
//! PING, TIMESYNC and COMMAND_LONG through [`core::ResponderCore`], with
//! optional link emulation (delay, jitter, drop, duplicate) for tests.
//!
//! Every answer goes back only on the path its request came from
//! (`send_to`): one reply per request, never amplified to other peers.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use tokio::sync::Notify;
use tokio::time::{sleep_until, Instant};

use crate::answering::{ResponderCore, ResponderCounts};
use crate::engine::link_io::{admitted, Clock, Heartbeat, Sender};
use crate::frame::signing::{Gate, SigningConfig, SigningCounts};
use crate::frame::{SysComp, Version};
use crate::transport::{Inbound, LinkError, Outbox, PathId, To, Transport};

/// Replies held back by `--delay` at once; past it they are dropped (and
/// counted), so memory stays bounded whatever the request rate.
const MAX_HELD: usize = 1 << 16;

/// How the responder behaves, already validated.
#[derive(Debug, Clone)]
pub struct ResponderSettings {
    pub id: SysComp,
    /// Every reply is held this long, plus up to `jitter`.
    pub delay: Duration,
    pub jitter: Duration,
    /// Shares of replies dropped and duplicated, 0..=1.
    pub drop: f64,
    pub dup: f64,
    pub seed: u64,
    pub answer_ping: bool,
    /// With a key: replies signed, requests checked (all must be signed).
    pub signing: Option<SigningConfig>,
}

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
    settings: ResponderSettings,
    rng: SmallRng,
    sender: Sender,
    heartbeat: Heartbeat,
    clock: Clock,
    held: BinaryHeap<Reverse<Held>>,
    order: u64,
    counts: RespondCounts,
    /// Paths (peers) greeted so far: links number new peers upwards and
    /// never reuse a number, so the highest one seen is enough.
    greeted: Option<PathId>,
    /// With a signing key: refuses requests not signed with it (or
    /// replayed).
    gate: Gate,
    /// What answers one batch of requests: written together once the batch
    /// is handled (one system call on UDP), and how many of them are
    /// replies (the rest are greetings).
    outbox: Outbox,
    replies_queued: u64,
}

impl Responder {
    /// A new peer gets our HEARTBEAT at once rather than within a second:
    /// a GCS or router discovers systems by their HEARTBEAT.
    fn greet(&mut self, path: PathId) {
        if path == PathId::MAX || self.greeted.is_some_and(|g| path <= g) {
            return;
        }
        self.greeted = Some(path);
        let bytes = self.sender.frame_as(Version::V2, self.heartbeat.msg());
        self.outbox.push(bytes, To::Path(path));
    }

    /// Writes what the last batch queued; its replies count as sent once
    /// the link took them.
    async fn flush<T: Transport>(&mut self, link: &mut T) -> Result<(), LinkError> {
        if self.outbox.is_empty() {
            return Ok(());
        }
        link.send_all(&self.outbox).await?;
        self.outbox.clear();
        self.counts.replies_sent += std::mem::take(&mut self.replies_queued);
        Ok(())
    }

    fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.gen::<f64>() < p
    }

    fn hold_time(&mut self) -> Duration {
        let jitter = self.settings.jitter.as_nanos() as u64;
        let extra = if jitter == 0 {
            0
        } else {
            self.rng.gen_range(0..=jitter)
        };
        self.settings.delay + Duration::from_nanos(extra)
    }

    /// Answers one inbound frame: queues the answer, holds it for later,
    /// or drops it.
    fn handle(&mut self, inbound: &Inbound) {
        // Our clock for TIMESYNC: ns since we started (like an autopilot's
        // boot time), read when the request arrived.
        let clock_ns = self.clock.ns(inbound.at) as i64 + 1;
        if !admitted(&mut self.gate, &inbound.frame, inbound.signature.as_ref()) {
            return;
        }
        let Some(reply) = self.core.answer(&inbound.frame, clock_ns) else {
            return;
        };
        if self.chance(self.settings.drop) {
            self.counts.dropped += 1;
            return;
        }
        let copies = if self.chance(self.settings.dup) {
            self.counts.duplicated += 1;
            2
        } else {
            1
        };
        // Answer in the version we were asked in: a MAVLink 1 stack may not
        // parse MAVLink 2.
        self.sender.frame_as(inbound.frame.version, &reply);
        for _ in 0..copies {
            let hold = self.hold_time();
            if hold.is_zero() {
                self.outbox.push(self.sender.last(), To::Path(inbound.path));
                self.replies_queued += 1;
            } else if self.held.len() >= MAX_HELD {
                self.counts.overflow += 1;
            } else {
                self.order += 1;
                self.held.push(Reverse(Held {
                    due: inbound.at + hold,
                    order: self.order,
                    path: inbound.path,
                    bytes: self.sender.last().to_vec(),
                }));
            }
        }
    }

    /// Queues the held replies that are due.
    fn release_due(&mut self, now: Instant) {
        while self.held.peek().is_some_and(|h| h.0.due <= now) {
            let Reverse(h) = self.held.pop().expect("peeked");
            self.outbox.push(&h.bytes, To::Path(h.path));
            self.replies_queued += 1;
        }
    }

    /// When the loop must wake at the latest: the next held reply or
    /// HEARTBEAT.
    fn wake(&self) -> Instant {
        let heartbeat = self.heartbeat.next().map_or_else(
            || Instant::now() + Duration::from_secs(1),
            |ns| self.clock.at(ns),
        );
        self.held
            .peek()
            .map_or(heartbeat, |h| h.0.due.min(heartbeat))
    }
}

/// Answers until `stop` (Ctrl-C, SIGTERM) or a link failure; returns the
/// counts either way.
pub async fn run<T: Transport>(
    settings: &ResponderSettings,
    link: &mut T,
    stop: &Notify,
) -> (RespondCounts, Option<LinkError>) {
    let mut core = ResponderCore::new(settings.id);
    core.answer_ping = settings.answer_ping;
    let mut r = Responder {
        core,
        settings: settings.clone(),
        rng: SmallRng::seed_from_u64(settings.seed),
        sender: Sender::new(
            settings.id,
            Version::V2,
            settings.signing.as_ref().map(SigningConfig::signer),
        ),
        heartbeat: Heartbeat::onboard_controller(),
        clock: Clock::start(),
        held: BinaryHeap::new(),
        order: 0,
        counts: RespondCounts::default(),
        greeted: None,
        gate: Gate::new(settings.signing),
        outbox: Outbox::default(),
        replies_queued: 0,
    };
    let mut inbound: Vec<Inbound> = Vec::new();
    let error = loop {
        let now = r.clock.now();
        if let Err(e) = r.heartbeat.send_if_due(link, &mut r.sender, now).await {
            break Some(e);
        }
        r.release_due(Instant::now());
        if let Err(e) = r.flush(link).await {
            break Some(e);
        }
        tokio::select! {
            biased;
            _ = stop.notified() => break None,
            received = link.recv(&mut inbound) => {
                if let Err(e) = received {
                    break Some(e);
                }
                for i in inbound.drain(..) {
                    r.greet(i.path);
                    r.handle(&i);
                }
                // Answered together: one write for the whole batch.
                if let Err(e) = r.flush(link).await {
                    break Some(e);
                }
            }
            _ = sleep_until(r.wake()) => {}
        }
    };
    r.counts.requests = r.core.counts;
    r.counts.signing = settings.signing.map(|_| r.gate.counts());
    (r.counts, error)
}

/// Who we are, for the first line.
pub fn describe(settings: &ResponderSettings, link_name: &str) -> String {
    let SysComp { sysid, compid } = settings.id;
    let what = if settings.answer_ping {
        "PING, TIMESYNC and COMMAND_LONG"
    } else {
        "TIMESYNC and COMMAND_LONG (not PING)"
    };
    let signed = if settings.signing.is_some() {
        " (signed requests only)"
    } else {
        ""
    };
    format!("mavping respond: {sysid}/{compid} on {link_name}, answering {what}{signed}")
}
