//! The ground truth ([`SimTruth`], [`DownTruth`], [`UpTruth`]): what the
//! simulated link did to each responder's exchanges and frames, kept
//! apart from the simulation so tests can hold mavping's counts against
//! it.

use crate::answering::transfers::ServedCounts;

/// What the simulated link did to one responder's exchanges: the ground
/// truth tests hold mavping's counts against.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct SimTruth {
    /// Requests the responder answered (before faults).
    pub answered: u64,
    /// Exchanges the link dropped...
    pub dropped: u64,
    /// ...of which before the first exchange whose reply was put on its
    /// way, in time or spiked (outside the pinger's window: not charged).
    pub dropped_before_first: u64,
    /// Replies delivered (first copies), not spiked.
    pub delivered: u64,
    /// Extra replies put on their way: copies (`dup=`, `dup_down=`), and
    /// the second answer to a request heard twice (`dup_up=`).
    pub duplicated: u64,
    /// ...of which handed to the pinger before it stopped reading.
    pub duplicates_arrived: u64,
    /// Exchanges the radio's full buffer dropped (`baud=`), also counted
    /// in `dropped`.
    pub(crate) overflowed: u64,
    /// Exchanges lost to the outage (`outage=`), also counted in `dropped`.
    pub(crate) outage: u64,
    /// Replies delayed by a spike (`spike=`); not in `delivered`: with a
    /// `spike_delay` past the timeout they arrive late.
    pub(crate) spiked: u64,
    /// ...of which handed to the pinger before it stopped reading (the
    /// late replies it can have seen).
    pub(crate) spiked_arrived: u64,
    /// Every frame the responder sent, by its sequence numbers.
    pub(crate) down: DownTruth,
    /// Every frame mavping sent towards it.
    pub(crate) up: UpTruth,
    /// The transfers it served: requests heard, frames put on their way
    /// and frames lost (`loss=`, a full buffer, the outage, `loss_down=`),
    /// by kind. Its frames are also in `down`.
    pub(crate) served: ServedCounts,
}

/// What became of the frames a responder sent (HEARTBEAT, telemetry,
/// replies), each numbered: what a passive count of its packet sequence
/// numbers is held against. `sent = dropped + delivered + in flight`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct DownTruth {
    /// Frames it numbered and sent.
    pub(crate) sent: u64,
    /// ...lost on the way to mavping: `loss_down=`, a full radio buffer
    /// (`baud=`), the outage (telemetry; `outage=`).
    pub(crate) dropped: u64,
    /// Extra copies put on their way (`dup=` on replies, `dup_down=`, a
    /// copy on each path past the first with `paths=`).
    pub(crate) duplicated: u64,
    /// ...of which arrived.
    pub(crate) duplicates_arrived: u64,
    /// Frames that arrived (first copies), reordered ones included.
    pub(crate) delivered: u64,
    /// ...of which after a frame it sent later had arrived (`hold=` by
    /// `reorder=` or `reorder_down=`, or a jitter wider than the gap).
    pub(crate) reordered: u64,
}

/// What became of the frames mavping sent, as one responder hears them.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(crate) struct UpTruth {
    /// Frames mavping sent (requests, its HEARTBEAT, `--load`).
    pub(crate) sent: u64,
    /// ...lost on the way to this responder: `loss_up=`, a full buffer
    /// (`baud=`).
    pub(crate) dropped: u64,
    /// ...of which requests it would have answered (also counted in
    /// `answered` and `dropped`: the exchange is lost).
    pub(crate) requests_dropped: u64,
    /// Frames it heard twice (`dup_up=`)...
    pub(crate) duplicated: u64,
    /// ...of which requests it answered twice: two replies, each numbered
    /// in its sequence; the second to arrive is a duplicate reply
    /// (`duplicated`), and the exchange is lost only if both are.
    pub(crate) requests_duplicated: u64,
}

/// What one path (`paths=`) did with one responder's frames: what a
/// pair report of the paths is held against. `sent = dropped + delivered
/// + on its way`.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub(crate) struct PathTruth {
    /// Frames the responder numbered and sent (the same on every path).
    pub(crate) sent: u64,
    /// ...that this path did not carry to mavping: lost before the frames
    /// split onto the paths (`loss_down=`, `outage=`, a full buffer) or on
    /// it...
    pub(crate) dropped: u64,
    /// ...by its own draw (`path_loss=`)...
    pub(crate) drawn: u64,
    /// ...or while its outage was on (`path_outage=`; drawn or not).
    pub(crate) outage: u64,
    /// Frames between the first and the newest it delivered that did not
    /// arrive by it: dropped, or on their way on it when the run ended.
    /// What a count of its sequence alone finds lost.
    pub(crate) missing: u64,
    /// Frames that arrived by it (their first copy on it)...
    pub(crate) delivered: u64,
    /// ...of which before any other path's copy...
    pub(crate) first: u64,
    /// ...and of which no other path delivered a copy: only this one.
    pub(crate) only: u64,
    /// Extra copies that arrived by it (`dup=`, `dup_down=`).
    pub(crate) duplicates: u64,
}

/// What the paths did with one responder's frames.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub(crate) struct PathsTruth {
    /// By path index.
    pub(crate) paths: Vec<PathTruth>,
    /// Frames no path carried: the loss left once the paths' copies are
    /// merged (`down_dropped`: with paths a frame is lost when no path
    /// carries it).
    pub(crate) lost_on_every_path: u64,
    /// Frames between the first and the newest any path delivered that
    /// arrived by none: lost on every path, or on their way on one (a
    /// slower path's copy of a frame the faster lost) when the run ended.
    /// What a count of the merged sequence finds lost.
    pub(crate) missing_on_every_path: u64,
}

/// A path's own counts, [`PathTruth`] once the responder's are added.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct PathCounts {
    /// Frames put on their way by other paths, not by this one.
    pub(super) missed: u64,
    pub(super) drawn: u64,
    pub(super) outage: u64,
    pub(super) delivered: u64,
    pub(super) first: u64,
    pub(super) only: u64,
    pub(super) duplicates: u64,
    /// The lowest and the highest index of a frame that arrived by it.
    pub(super) span: Option<(u64, u64)>,
}

impl PathCounts {
    /// Frame `index` arrived by it.
    pub(super) fn spans(&mut self, index: u64) {
        self.span = Some(self.span.map_or((index, index), |(low, high)| {
            (low.min(index), high.max(index))
        }));
    }
}

/// The frames between two indices, both in, less those that arrived: the
/// numbers a count of the sequence finds lost.
pub(super) fn between(span: Option<(u64, u64)>, arrived: u64) -> u64 {
    span.map_or(0, |(low, high)| high - low + 1 - arrived)
}

/// The most the link's queues (`queue_up=`, `queue_down=`) delayed a
/// frame: the growth an age or a direction split must find.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct QueueTruth {
    pub up: std::time::Duration,
    pub down: std::time::Duration,
}

impl SimTruth {
    pub(super) fn dropped(&mut self, replied: bool) {
        self.dropped += 1;
        self.dropped_before_first += u64::from(!replied);
    }
}
