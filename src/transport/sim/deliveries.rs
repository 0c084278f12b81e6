//! Frames on their way to mavping: the deliveries waiting in the link,
//! in time order, each copy of a responder's frame tagged for the ground
//! truth of what arrived (and by which path), and the cap that keeps the
//! queue bounded.

use std::cmp::Reverse;

use tokio::time::Instant;

use super::link::SimLink;
use super::params::MAX_PATHS;
use super::responder::Due;
use crate::transport::link::PathId;

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
    /// The path it comes by (`paths=`; 0 without).
    pub(super) path: PathId,
}

/// One copy of a frame on its way: when it arrives, what it is for the
/// ground truth, and by which path.
#[derive(Clone, Copy)]
pub(super) struct Arrival {
    pub(super) at: Instant,
    pub(super) payload: Payload,
    pub(super) path: PathId,
}

/// The most copies of one frame: two (`dup=` or `dup_down=`) on each path.
const MAX_COPIES: usize = 2 * MAX_PATHS;

/// A frame's copies on their way: its first and maybe an extra one, on
/// each path; none when every one was lost.
#[derive(Clone, Copy)]
pub(super) struct Copies {
    /// Past `n`, filler.
    list: [Arrival; MAX_COPIES],
    n: usize,
}

impl Copies {
    /// One copy, on path 0.
    pub(super) fn one(at: Instant, payload: Payload) -> Self {
        let arrival = Arrival {
            at,
            payload,
            path: 0,
        };
        Copies {
            list: [arrival; MAX_COPIES],
            n: 1,
        }
    }

    /// None yet, to push copies into.
    pub(super) fn emptied(&self) -> Self {
        Copies {
            list: self.list,
            n: 0,
        }
    }

    pub(super) fn push(&mut self, at: Instant, payload: Payload, path: PathId) {
        self.list[self.n] = Arrival { at, payload, path };
        self.n += 1;
    }

    pub(super) fn as_slice(&self) -> &[Arrival] {
        &self.list[..self.n]
    }

    pub(super) fn as_mut_slice(&mut self) -> &mut [Arrival] {
        &mut self.list[..self.n]
    }
}

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
        path: PathId,
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
            path,
        }));
        true
    }

    /// Queues the copies of frame `index` of responder `i`.
    pub(super) fn put_on_way(&mut self, i: usize, index: u64, bytes: Vec<u8>, copies: &Copies) {
        let tag = Some(Tag {
            responder: i,
            index,
        });
        // The paths that carry a copy, a bit each.
        let mut carried = 0u8;
        let mut queued = 0;
        for copy in copies.as_slice() {
            if self.enqueue(copy.at, bytes.clone(), copy.payload, copy.path, tag) {
                queued += 1;
                carried |= 1 << copy.path;
            }
        }
        let r = &mut self.responders[i];
        match queued {
            0 => r.truth.down.dropped += 1,
            1 => r.missed_on_paths(carried),
            more => {
                r.missed_on_paths(carried);
                r.truth.down.duplicated += more as u64 - 1;
                r.copies_due.insert(index, Due::new(more as u8));
            }
        }
    }
}
