//! Frames on their way to mavping: the deliveries waiting in the link,
//! in time order, each copy of a responder's frame tagged for the ground
//! truth of what arrived, and the cap that keeps the queue bounded.

use std::cmp::Reverse;

use tokio::time::Instant;

use super::link::SimLink;

/// Which responder's frame a delivery is, and which of its frames.
#[derive(PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
pub(super) struct Tag {
    pub(super) responder: usize,
    pub(super) index: u64,
}

/// A delivery waiting in the simulated link, ordered by time then by the
/// order it was queued (so equal times stay deterministic).
#[derive(PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct Delivery {
    pub(super) at: Instant,
    pub(super) order: u64,
    pub(super) bytes: Vec<u8>,
    /// What it is, for the ground truth of what arrived.
    pub(super) payload: Payload,
    /// A responder's frame (not RADIO_STATUS): for [`DownTruth`](super::truth::DownTruth).
    pub(super) frame: Option<Tag>,
}

/// A frame's arrivals: its first copy and maybe an extra one.
pub(super) type Copies = ([(Instant, Payload); 2], usize);

/// What a delivery carries, for the ground truth.
#[derive(PartialEq, Eq, PartialOrd, Ord, Clone, Copy)]
pub(super) enum Payload {
    /// HEARTBEAT, telemetry, RADIO_STATUS, a reply's first copy on time.
    Plain,
    /// A reply's first copy, spiked (responder index).
    Spiked(usize),
    /// A reply's extra copy (responder index).
    Duplicate(usize),
}

/// Queued deliveries are capped so an absurd rate x delay cannot grow
/// memory without bound; past it, replies are dropped like a full queue.
const MAX_QUEUED: usize = 1 << 20;

impl SimLink {
    /// Queues a delivery; false when the queue is full and it is dropped.
    pub(super) fn enqueue(
        &mut self,
        at: Instant,
        bytes: Vec<u8>,
        payload: Payload,
        frame: Option<Tag>,
    ) -> bool {
        if self.queue.len() >= MAX_QUEUED {
            return false;
        }
        self.order += 1;
        self.queue.push(Reverse(Delivery {
            at,
            order: self.order,
            bytes,
            payload,
            frame,
        }));
        true
    }

    /// Queues the copies of frame `index` of responder `i`.
    pub(super) fn put_on_way(&mut self, i: usize, index: u64, bytes: Vec<u8>, (copies, n): Copies) {
        let tag = Some(Tag {
            responder: i,
            index,
        });
        let queued = copies[..n]
            .iter()
            .filter(|(at, payload)| self.enqueue(*at, bytes.clone(), *payload, tag))
            .count();
        let down = &mut self.responders[i].truth.down;
        match queued {
            0 => down.dropped += 1,
            1 => {}
            more => {
                down.duplicated += more as u64 - 1;
                self.responders[i].copies_due.insert(index, more as u8);
            }
        }
    }
}
