//! Answering a request under the link emulation of `--delay`, `--jitter`,
//! `--drop` and `--dup`: the reply queued at once, held back for later
//! (bounded), dropped or doubled.

use std::cmp::Reverse;
use std::time::Duration;

use rand::Rng;
use tokio::time::Instant;

use super::respond_loop::Responder;
use crate::engine::link_io::admitted;
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
    /// or drops it.
    pub(super) fn handle(&mut self, inbound: &Inbound) {
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
    pub(super) fn release_due(&mut self, now: Instant) {
        while self.held.peek().is_some_and(|h| h.0.due <= now) {
            let Reverse(h) = self.held.pop().expect("peeked");
            self.outbox.push(&h.bytes, To::Path(h.path));
            self.replies_queued += 1;
        }
    }
}
