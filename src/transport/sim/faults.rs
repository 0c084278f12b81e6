//! The fault model: the delay and jitter of a leg, the outage window,
//! and the draws of the per-direction faults (`loss_down=`,
//! `reorder_down=`, `dup_down=`), from the link's and the responders'
//! own random streams.

use std::time::Duration;

use rand::rngs::SmallRng;
use rand::Rng;
use tokio::time::Instant;

use super::deliveries::{Copies, Payload};
use super::link::SimLink;
use super::params::{Queue, SimParams};

/// `delay=` plus a draw of `jitter=`.
fn one_way(params: &SimParams, rng: &mut SmallRng) -> Duration {
    let jitter = params.jitter.as_nanos() as u64;
    let extra = if jitter == 0 {
        0
    } else {
        rng.gen_range(0..=jitter)
    };
    params.delay + Duration::from_nanos(extra)
}

impl SimLink {
    pub(super) fn one_way(&mut self) -> Duration {
        one_way(&self.params, &mut self.rng)
    }

    /// A one-way delay drawn for the responders' own frames.
    pub(super) fn vehicle_one_way(&mut self) -> Duration {
        one_way(&self.params, &mut self.vehicle_rng)
    }

    /// The delay the uplink's queue (`queue_up=`) adds to a frame
    /// entering it at `t`.
    pub(super) fn queued_up(&mut self, t: Instant) -> Duration {
        let delay = self.queued(self.params.queue_up, t);
        self.queue_truth.up = self.queue_truth.up.max(delay);
        delay
    }

    /// The delay the downlink's queue (`queue_down=`) adds to a frame
    /// entering it at `t`; the largest so far is the truth `-v` shows.
    pub(super) fn queued_down(&mut self, t: Instant) -> Duration {
        let delay = self.queued(self.params.queue_down, t);
        self.queue_truth.down = self.queue_truth.down.max(delay);
        delay
    }

    fn queued(&self, queue: Option<Queue>, t: Instant) -> Duration {
        queue.map_or(Duration::ZERO, |q| {
            q.delay_at(t.saturating_duration_since(self.started))
        })
    }

    /// True while an `outage=` window is on (`outage_every=` repeats it).
    pub(super) fn in_outage(&self, now: Instant) -> bool {
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

    pub(super) fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.rng.gen::<f64>() < p
    }

    /// A per-direction fault's draw, from the responders' own draws.
    pub(super) fn vehicle_chance(&mut self, p: f64) -> bool {
        p > 0.0 && self.vehicle_rng.gen::<f64>() < p
    }

    /// The per-direction faults on a frame of responder `i` sent at
    /// `sent` and due at `at`, then its paths'.
    pub(super) fn send_down(
        &mut self,
        i: usize,
        index: u64,
        bytes: Vec<u8>,
        sent: Instant,
        mut at: Instant,
    ) {
        if self.vehicle_chance(self.params.loss_down) {
            self.responders[i].truth.down.dropped += 1;
            return;
        }
        if self.vehicle_chance(self.params.reorder_down) {
            at += self.params.hold;
        }
        let mut copies = Copies::one(at, Payload::Plain);
        if self.vehicle_chance(self.params.dup_down) {
            let again = at + self.vehicle_one_way();
            copies.push(again, Payload::Plain, 0);
        }
        let copies = self.on_paths(i, sent, &copies);
        self.put_on_way(i, index, bytes, &copies);
    }
}
