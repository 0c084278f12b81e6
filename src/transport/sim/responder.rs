//! The responder model ([`SimResponder`]): one simulated system's
//! answering core, its packet sequence, its HEARTBEAT and telemetry
//! timetables, and the bookkeeping of which of its frames arrived (and
//! by which paths).

use std::collections::HashMap;

use super::truth::{PathCounts, PathTruth, PathsTruth, SimTruth};
use crate::answering::ResponderCore;
use crate::frame::Header;
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
}

/// A frame with more than one copy on its way.
pub(super) struct Due {
    /// Copies still to arrive.
    left: u8,
    /// One has arrived: the others are duplicates.
    arrived: bool,
    /// The paths that carry a copy, and those a copy arrived by, a bit
    /// each.
    carried: u8,
    arrived_on: u8,
}

impl Due {
    pub(super) fn new(copies: u8, carried: u8) -> Self {
        Due {
            left: copies,
            arrived: false,
            carried,
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
        let (copy, first_on_path, only) = match self.copies_due.get_mut(&index) {
            Some(due) => {
                let seen = (due.arrived, due.arrived_on & bit != 0, due.carried == bit);
                due.arrived = true;
                due.arrived_on |= bit;
                due.left -= 1;
                if due.left == 0 {
                    self.copies_due.remove(&index);
                }
                (seen.0, !seen.1, seen.2)
            }
            None => (false, true, true),
        };
        if let Some(counts) = self.paths.get_mut(path as usize) {
            if first_on_path {
                counts.delivered += 1;
                counts.only += u64::from(only);
            } else {
                counts.duplicates += 1;
            }
        }
        let down = &mut self.truth.down;
        if copy {
            down.duplicates_arrived += 1;
            return;
        }
        down.delivered += 1;
        down.reordered += u64::from(self.latest_arrived.is_some_and(|l| index < l));
        self.latest_arrived = Some(self.latest_arrived.map_or(index, |l| l.max(index)));
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
        PathsTruth {
            paths: self
                .paths
                .iter()
                .map(|c| PathTruth {
                    sent: down.sent,
                    dropped: down.dropped + c.missed,
                    delivered: c.delivered,
                    only: c.only,
                    duplicates: c.duplicates,
                })
                .collect(),
            lost_on_every_path: down.dropped,
        }
    }
}
