//! `mavping respond`: a well-behaved MAVLink system on any link, answering
//! PING, TIMESYNC and COMMAND_LONG through [`core::ResponderCore`], with
//! optional link emulation (delay, jitter, drop, duplicate) for tests,
//! and telemetry streamed as a vehicle does (`--stream`), numbered with
//! the same packet sequence as every other frame it sends.
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
use crate::telemetry::{Schedule, StreamKind, StreamSpec};
use crate::transport::{Inbound, LinkError, Outbox, PathId, To, Transport};

/// Replies held back by `--delay` at once; past it they are dropped (and
/// counted), so memory stays bounded whatever the request rate.
const MAX_HELD: usize = 1 << 16;
/// Most frames one stream sends back to back before the loop reads the
/// link again.
const MAX_BURST: usize = 64;
/// Seeds the streams' phases and `--stream-drop` beside `--seed`, so
/// streaming leaves the replies' draws as they were.
const STREAM_SEED: u64 = 0x7e1e_3e7e_5eed_0002;

/// How the responder behaves, already validated.
#[derive(Debug, Clone)]
pub(crate) struct ResponderSettings {
    pub(crate) id: SysComp,
    /// Every reply is held this long, plus up to `jitter`.
    pub(crate) delay: Duration,
    pub(crate) jitter: Duration,
    /// Shares of replies dropped and duplicated, 0..=1.
    pub(crate) drop: f64,
    pub(crate) dup: f64,
    pub(crate) seed: u64,
    pub(crate) answer_ping: bool,
    /// With a key: replies signed, requests checked (all must be signed).
    pub(crate) signing: Option<SigningConfig>,
    /// Telemetry sent to every peer unasked; a HEARTBEAT stream sets the
    /// rate of our HEARTBEAT (1 Hz without).
    pub(crate) streams: Vec<StreamSpec>,
    /// Share of streamed frames numbered, then not sent: the gap a lost
    /// frame leaves in our sequence numbers.
    pub(crate) stream_drop: f64,
}

/// What one `--stream` sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub(crate) struct StreamCount {
    pub(crate) message: &'static str,
    /// Frames written to the link.
    pub(crate) sent: u64,
    /// Frames numbered but dropped by `--stream-drop`.
    pub(crate) dropped: u64,
}

/// Ground truth printed on exit, to hold a pinger's figures against.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub(crate) struct RespondCounts {
    pub(crate) requests: ResponderCounts,
    pub(crate) replies_sent: u64,
    pub(crate) dropped: u64,
    pub(crate) duplicated: u64,
    /// Replies dropped because too many were held by `--delay`.
    pub(crate) overflow: u64,
    /// With a signing key: frames accepted and refused by signature.
    pub(crate) signing: Option<SigningCounts>,
    /// With `--stream`: each stream's frames, in the order given.
    pub(crate) streamed: Vec<StreamCount>,
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
        if !self.streamed.is_empty() {
            let each: Vec<String> = self
                .streamed
                .iter()
                .map(|s| format!("{} {}", s.sent, s.message))
                .collect();
            write!(
                f,
                "; {} frames streamed ({}), {} dropped by --stream-drop",
                self.streamed.iter().map(|s| s.sent).sum::<u64>(),
                each.join(", "),
                self.streamed.iter().map(|s| s.dropped).sum::<u64>()
            )?;
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

/// One `--stream`: its timetable and counts.
struct Stream {
    kind: StreamKind,
    schedule: Schedule,
    count: StreamCount,
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
    /// `--stream`, and the draws for their phases and `--stream-drop`.
    streams: Vec<Stream>,
    stream_rng: SmallRng,
    /// False when a HEARTBEAT stream sends our HEARTBEAT instead.
    periodic_heartbeat: bool,
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

    /// Sends every streamed frame due at `now` (at most a burst per
    /// stream), each numbered, some dropped by `--stream-drop` instead.
    async fn stream_due<T: Transport>(&mut self, link: &mut T, now: u64) -> Result<(), LinkError> {
        for s in &mut self.streams {
            for _ in 0..MAX_BURST {
                let due = s.schedule.due_ns();
                if due > now {
                    break;
                }
                s.schedule.advance();
                let msg = s.kind.msg((due / 1_000_000) as u32, self.heartbeat.msg());
                let frame = self.sender.frame(&msg);
                let drop = self.settings.stream_drop;
                if drop > 0.0 && self.stream_rng.gen::<f64>() < drop {
                    s.count.dropped += 1;
                    continue;
                }
                link.send(frame).await?;
                s.count.sent += 1;
            }
        }
        Ok(())
    }

    /// When the loop must wake at the latest: the next held reply,
    /// HEARTBEAT or streamed frame.
    fn wake(&self) -> Instant {
        let heartbeat = self
            .heartbeat
            .next()
            .filter(|_| self.periodic_heartbeat)
            .map_or_else(
                || Instant::now() + Duration::from_secs(1),
                |ns| self.clock.at(ns),
            );
        let streams = self
            .streams
            .iter()
            .map(|s| self.clock.at(s.schedule.due_ns()));
        let held = self.held.peek().map(|h| h.0.due);
        streams.chain(held).fold(heartbeat, Instant::min)
    }
}

/// Answers until `stop` (Ctrl-C, SIGTERM) or a link failure; returns the
/// counts either way.
pub(crate) async fn run<T: Transport>(
    settings: &ResponderSettings,
    link: &mut T,
    stop: &Notify,
) -> (RespondCounts, Option<LinkError>) {
    let mut core = ResponderCore::new(settings.id);
    core.answer_ping = settings.answer_ping;
    let mut stream_rng = SmallRng::seed_from_u64(settings.seed ^ STREAM_SEED);
    let streams: Vec<Stream> = settings
        .streams
        .iter()
        .map(|spec| {
            // Our HEARTBEAT's first goes at once, as without --stream.
            let phase = match spec.kind {
                StreamKind::Heartbeat => 0.0,
                _ => stream_rng.gen(),
            };
            Stream {
                kind: spec.kind,
                schedule: Schedule::new(spec.rate, phase),
                count: StreamCount {
                    message: spec.kind.name(),
                    sent: 0,
                    dropped: 0,
                },
            }
        })
        .collect();
    let periodic_heartbeat = streams.iter().all(|s| s.kind != StreamKind::Heartbeat);
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
        streams,
        stream_rng,
        periodic_heartbeat,
    };
    let mut inbound: Vec<Inbound> = Vec::new();
    let error = loop {
        let now = r.clock.now();
        if r.periodic_heartbeat {
            if let Err(e) = r.heartbeat.send_if_due(link, &mut r.sender, now).await {
                break Some(e);
            }
        }
        if let Err(e) = r.stream_due(link, now).await {
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
    r.counts.streamed = r.streams.iter().map(|s| s.count).collect();
    (r.counts, error)
}

/// Who we are, for the first line.
pub(crate) fn describe(settings: &ResponderSettings, link_name: &str) -> String {
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
    let streaming = if settings.streams.is_empty() {
        String::new()
    } else {
        let streams: Vec<String> = settings.streams.iter().map(ToString::to_string).collect();
        format!(", streaming {}", streams.join(", "))
    };
    format!("mavping respond: {sysid}/{compid} on {link_name}, answering {what}{signed}{streaming}")
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::frame::{self, ids, ScanStats};
    use crate::transport::{LinkKind, PathId};

    /// A link that keeps what is sent to it and hears nothing.
    #[derive(Default)]
    struct Capture {
        sent: Vec<frame::Frame>,
    }

    impl Transport for Capture {
        async fn send(&mut self, bytes: &[u8]) -> Result<Instant, LinkError> {
            let mut stats = ScanStats::default();
            frame::scan_datagram(bytes, &mut stats, &mut |raw| {
                self.sent.push(frame::decode(raw));
            });
            Ok(Instant::now())
        }

        async fn send_to(&mut self, _: PathId, bytes: &[u8]) -> Result<Instant, LinkError> {
            self.send(bytes).await
        }

        async fn recv(&mut self, _: &mut Vec<Inbound>) -> Result<(), LinkError> {
            std::future::pending().await
        }

        fn scan_stats(&self) -> ScanStats {
            ScanStats::default()
        }

        fn kind(&self) -> LinkKind {
            LinkKind::Connecting
        }

        fn keep_raw(&mut self) {}
    }

    #[tokio::test(start_paused = true)]
    async fn streams_go_at_their_rates_numbered_with_everything_else() {
        let settings = ResponderSettings {
            id: SysComp::new(1, 1),
            delay: Duration::ZERO,
            jitter: Duration::ZERO,
            drop: 0.0,
            dup: 0.0,
            seed: 1,
            answer_ping: true,
            signing: None,
            streams: crate::telemetry::parse_list("ATTITUDE@50,HEARTBEAT@2").unwrap(),
            stream_drop: 0.1,
        };
        let mut link = Capture::default();
        let stop = Notify::new();
        let ((counts, error), ()) = tokio::join!(run(&settings, &mut link, &stop), async {
            tokio::time::sleep(Duration::from_millis(9_999)).await;
            stop.notify_one();
        });
        assert!(error.is_none());
        let [attitude, heartbeat] = counts.streamed[..] else {
            panic!("two streams: {counts:?}")
        };
        // 10 s: 500 ATTITUDE from a random phase, 20 HEARTBEAT from the
        // start (and no 1 Hz one beside them), a tenth of both dropped.
        assert!(
            (499..=500).contains(&(attitude.sent + attitude.dropped)),
            "{counts:?}"
        );
        assert_eq!(heartbeat.sent + heartbeat.dropped, 20, "{counts:?}");
        let dropped = attitude.dropped + heartbeat.dropped;
        assert!((30..75).contains(&dropped), "{counts:?}");
        let of = |msgid| link.sent.iter().filter(|f| f.msgid == msgid).count() as u64;
        assert_eq!(of(30), attitude.sent);
        assert_eq!(of(ids::HEARTBEAT), heartbeat.sent);
        // One sequence from 0: every gap is a dropped frame, the rest were
        // dropped after the last frame sent.
        let mut next = 0u64;
        let mut missing = 0;
        for f in &link.sent {
            let gap = u64::from(f.packet_seq.wrapping_sub(next as u8));
            missing += gap;
            next += gap + 1;
        }
        let numbered = attitude.sent + attitude.dropped + heartbeat.sent + heartbeat.dropped;
        assert!(numbered - next < 5 && missing + (numbered - next) == dropped);
        let line = counts.to_string();
        assert!(
            line.ends_with(&format!(
                "; {} frames streamed ({} ATTITUDE, {} HEARTBEAT), {dropped} dropped by \
                 --stream-drop",
                attitude.sent + heartbeat.sent,
                attitude.sent,
                heartbeat.sent
            )),
            "{line}"
        );
    }
}
