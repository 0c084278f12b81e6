//! Answering a request under the link emulation of `--delay`, `--jitter`,
//! `--drop` and `--dup`: the reply queued at once, held back for later
//! (bounded), dropped or doubled; the transfers' frames
//! ([`serving`](super::serving)) go through the same emulation.

use std::cmp::Reverse;
use std::time::Duration;

use rand::Rng;
use tokio::time::Instant;

use super::respond_loop::Responder;
use crate::engine::link_io::admitted;
use crate::frame::{Msg, Version};
use crate::transport::{Inbound, PathId, To};

/// Replies held back by `--delay` at once; past it they are dropped (and
/// counted), so memory stays bounded whatever the request rate.
const MAX_HELD: usize = 1 << 16;

#[derive(PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct Held {
    pub(super) due: Instant,
    pub(super) order: u64,
    pub(super) path: PathId,
    pub(super) bytes: Vec<u8>,
    /// A reply to a probe (not a transfer's frame): counted as sent.
    pub(super) reply: bool,
}

/// What the link emulation did with a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Fate {
    Sent,
    Dropped,
    Doubled,
}

impl Responder {
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
    /// or drops it; a transfer request is taken by the transfer server,
    /// whose frames go at their pace ([`Responder::serve_due`]).
    pub(super) fn handle(&mut self, inbound: &Inbound) {
        // Our clock for TIMESYNC: ns since we started (like an autopilot's
        // boot time), read when the request arrived.
        let clock_ns = self.clock.ns(inbound.at) as i64 + 1;
        if !admitted(&mut self.gate, &inbound.frame, inbound.signature.as_ref()) {
            return;
        }
        // Answer in the version we were asked in: a MAVLink 1 stack may not
        // parse MAVLink 2.
        let version = inbound.frame.version;
        let Some(reply) = self.core.answer(&inbound.frame, clock_ns) else {
            let idle = !self.transfers.pending();
            let to = (inbound.path, version);
            if self.transfers.request(&inbound.frame, to, clock_ns as u64) && idle {
                // After a pause the pace starts again now, not in a rush
                // to catch up.
                self.transfer_next = self.transfer_next.max(inbound.at);
            }
            return;
        };
        let fate = self.emit(&reply, version, inbound.path, inbound.at, true);
        self.counts.dropped += u64::from(fate == Fate::Dropped);
        self.counts.duplicated += u64::from(fate == Fate::Doubled);
    }

    /// Writes `msg` for `path` under `--delay`, `--jitter`, `--drop` and
    /// `--dup`: queued at once, held until `at` plus the delay, dropped or
    /// doubled. A `reply` counts in the replies sent once written.
    pub(super) fn emit(
        &mut self,
        msg: &Msg,
        version: Version,
        path: PathId,
        at: Instant,
        reply: bool,
    ) -> Fate {
        if self.chance(self.settings.drop) {
            return Fate::Dropped;
        }
        let fate = if self.chance(self.settings.dup) {
            Fate::Doubled
        } else {
            Fate::Sent
        };
        self.sender.frame_as(version, msg);
        for _ in 0..=u8::from(fate == Fate::Doubled) {
            let hold = self.hold_time();
            if hold.is_zero() {
                self.outbox.push(self.sender.last(), To::Path(path));
                self.replies_queued += u64::from(reply);
            } else if self.held.len() >= MAX_HELD {
                self.counts.overflow += 1;
            } else {
                self.order += 1;
                self.held.push(Reverse(Held {
                    due: at + hold,
                    order: self.order,
                    path,
                    bytes: self.sender.last().to_vec(),
                    reply,
                }));
            }
        }
        fate
    }

    /// Queues the held replies that are due.
    pub(super) fn release_due(&mut self, now: Instant) {
        while self.held.peek().is_some_and(|h| h.0.due <= now) {
            let Reverse(h) = self.held.pop().expect("peeked");
            self.outbox.push(&h.bytes, To::Path(h.path));
            self.replies_queued += u64::from(h.reply);
        }
    }
}
