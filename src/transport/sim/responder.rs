//! The responder model ([`SimResponder`]): one simulated system's
//! answering core, its packet sequence, its HEARTBEAT and telemetry
//! timetables, and the bookkeeping of which of its frames arrived (and
//! by which paths).

use std::collections::HashMap;

use super::truth::{between, PathCounts, PathTruth, PathsTruth, SimTruth};
use crate::answering::transfers::TransferServer;
use crate::answering::ResponderCore;
use crate::frame::{Header, Version};
use crate::telemetry::{Schedule, StreamKind};
use crate::transport::link::PathId;

pub(super) struct SimResponder {
    pub(super) core: ResponderCore,
    pub(super) packet_seq: u8,
    /// Its HEARTBEAT's timetable (`heartbeat=on`), and its telemetry's.
    pub(super) heartbeat: Option<Schedule>,
    pub(super) streams: Vec<(StreamKind, Schedule)>,
    pub(super) truth: SimTruth,
    /// A reply of its has been put on its way (delivered or spiked): the
    /// pinger's window for it opens at the first such exchange.
    pub(super) replied: bool,
    /// Frames it numbered so far: the index of the next one (its packet
    /// sequence is this index plus one, modulo 256).
    pub(super) numbered: u64,
    /// The highest index that has arrived at mavping.
    pub(super) latest_arrived: Option<u64>,
    /// Frames with more than one copy on its way, until the last arrives.
    pub(super) copies_due: HashMap<u64, Due>,
    /// What each path did with its frames (`paths=`; none without).
    pub(super) paths: Vec<PathCounts>,
    /// The parameters, mission and file it serves, each reply in the
    /// version its request came in; and whether its next transfer frame
    /// is scheduled.
    pub(super) transfers: TransferServer<Version>,
    pub(super) serving: bool,
}

/// A frame with more than one copy on its way.
pub(super) struct Due {
    /// Copies still to arrive.
    left: u8,
    /// The paths a copy arrived by, a bit each: none yet, or the others
    /// are duplicates.
    arrived_on: u8,
}

impl Due {
    pub(super) fn new(copies: u8) -> Self {
        Due {
            left: copies,
            arrived_on: 0,
        }
    }
}

impl SimResponder {
    /// The header of the next frame it sends, and the frame's index.
    pub(super) fn header(&mut self) -> (Header, u64) {
        self.packet_seq = self.packet_seq.wrapping_add(1);
        let index = self.numbered;
        self.numbered += 1;
        self.truth.down.sent += 1;
        let header = Header {
            sysid: self.core.id.sysid,
            compid: self.core.id.compid,
            seq: self.packet_seq,
        };
        (header, index)
    }

    /// A frame of its reached mavping by `path`: a first copy, maybe
    /// reordered, or an extra one.
    pub(super) fn arrived(&mut self, index: u64, path: PathId) {
        let bit = 1u8 << path;
        // A frame with one copy: the first, and its path's alone.
        let before = match self.copies_due.get_mut(&index) {
            Some(due) => {
                let before = due.arrived_on;
                due.arrived_on |= bit;
                due.left -= 1;
                if due.left == 0 {
                    self.copies_due.remove(&index);
                }
                before
            }
            None => 0,
        };
        self.arrived_by(index, path, before);
        let down = &mut self.truth.down;
        if before != 0 {
            down.duplicates_arrived += 1;
            return;
        }
        down.delivered += 1;
        down.reordered += u64::from(self.latest_arrived.is_some_and(|l| index < l));
        self.latest_arrived = Some(self.latest_arrived.map_or(index, |l| l.max(index)));
    }

    /// A copy of frame `index` came by `path`, and before it copies by
    /// the paths in `before` (a bit each): its counts (`paths=`). "Only"
    /// is as things arrived: a second path's copy takes the frame from
    /// the first's.
    fn arrived_by(&mut self, index: u64, path: PathId, before: u8) {
        if self.paths.is_empty() {
            return;
        }
        let k = path as usize;
        if before & (1 << path) != 0 {
            self.paths[k].duplicates += 1;
            return;
        }
        let counts = &mut self.paths[k];
        counts.delivered += 1;
        counts.spans(index);
        if before == 0 {
            counts.first += 1;
            counts.only += 1;
        } else if before.is_power_of_two() {
            self.paths[before.trailing_zeros() as usize].only -= 1;
        }
    }

    /// A frame put on its way by the paths in `carried` (a bit each): the
    /// others missed it.
    pub(super) fn missed_on_paths(&mut self, carried: u8) {
        for (k, counts) in self.paths.iter_mut().enumerate() {
            counts.missed += u64::from(carried & (1 << k) == 0);
        }
    }

    /// What each path did with its frames (`paths=`).
    pub(super) fn path_truth(&self) -> PathsTruth {
        let down = self.truth.down;
        let span = self
            .paths
            .iter()
            .filter_map(|c| c.span)
            .reduce(|(low, high), (l, h)| (low.min(l), high.max(h)));
        PathsTruth {
            paths: self
                .paths
                .iter()
                .map(|c| PathTruth {
                    sent: down.sent,
                    dropped: down.dropped + c.missed,
                    drawn: c.drawn,
                    outage: c.outage,
                    missing: between(c.span, c.delivered),
                    delivered: c.delivered,
                    first: c.first,
                    only: c.only,
                    duplicates: c.duplicates,
                })
                .collect(),
            lost_on_every_path: down.dropped,
            missing_on_every_path: between(span, down.delivered),
        }
    }
}
