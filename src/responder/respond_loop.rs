//! The responder's loop ([`run`]): its state, the greeting of new peers,
//! one write per batch of answers, and the wake-ups for held replies,
//! HEARTBEATs and streams, until stopped or the link fails.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::Duration;

use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use tokio::sync::Notify;
use tokio::time::{sleep_until, Instant};

use super::counts::{RespondCounts, StreamCount};
use super::replies::Held;
use super::settings::ResponderSettings;
use super::streams::{Stream, STREAM_SEED};
use crate::answering::transfers::TransferServer;
use crate::answering::ResponderCore;
use crate::engine::link_io::{Clock, Heartbeat, Sender};
use crate::frame::signing::{Gate, SigningConfig};
use crate::frame::Version;
use crate::telemetry::{Schedule, StreamKind};
use crate::transport::several;
use crate::transport::{Inbound, LinkError, Outbox, PathId, To, Transport};

pub(super) struct Responder {
    pub(super) core: ResponderCore,
    pub(super) settings: ResponderSettings,
    pub(super) rng: SmallRng,
    pub(super) sender: Sender,
    pub(super) heartbeat: Heartbeat,
    pub(super) clock: Clock,
    pub(super) held: BinaryHeap<Reverse<Held>>,
    pub(super) order: u64,
    pub(super) counts: RespondCounts,
    /// Paths (peers) greeted so far, on each link: links number new
    /// peers upwards and never reuse a number, so the highest one seen is
    /// enough.
    pub(super) greeted: Vec<Option<PathId>>,
    /// With a signing key: refuses requests not signed with it (or
    /// replayed).
    pub(super) gate: Gate,
    /// What answers one batch of requests: written together once the batch
    /// is handled (one system call on UDP), and how many of them are
    /// replies (the rest are greetings).
    pub(super) outbox: Outbox,
    pub(super) replies_queued: u64,
    /// `--stream`, and the draws for their phases and `--stream-drop`.
    pub(super) streams: Vec<Stream>,
    pub(super) stream_rng: SmallRng,
    /// False when a HEARTBEAT stream sends our HEARTBEAT instead.
    pub(super) periodic_heartbeat: bool,
    /// The parameters, mission and file served; each reply goes back by
    /// the path (and in the version) its request came.
    pub(super) transfers: TransferServer<(PathId, Version)>,
    /// When the next transfer frame may go (`--transfer-rate`).
    pub(super) transfer_next: Instant,
}

impl Responder {
    /// A new peer gets our HEARTBEAT at once rather than within a second:
    /// a GCS or router discovers systems by their HEARTBEAT.
    fn greet(&mut self, path: PathId) {
        if path == PathId::MAX {
            return;
        }
        let link = several::link_of(path);
        if self.greeted.len() <= link {
            self.greeted.resize(link + 1, None);
        }
        if self.greeted[link].is_some_and(|g| path <= g) {
            return;
        }
        self.greeted[link] = Some(path);
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
        let transfer = self.transfers.pending().then_some(self.transfer_next);
        streams
            .chain(held)
            .chain(transfer)
            .fold(heartbeat, Instant::min)
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
        greeted: Vec::new(),
        gate: Gate::new(settings.signing),
        outbox: Outbox::default(),
        replies_queued: 0,
        streams,
        stream_rng,
        periodic_heartbeat,
        transfers: TransferServer::new(settings.id, settings.serve),
        transfer_next: Instant::now(),
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
        r.serve_due(Instant::now());
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
                // A single reply (a re-request's) goes with the batch.
                r.serve_due(Instant::now());
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
    r.counts.served = r.transfers.counts;
    (r.counts, error)
}
