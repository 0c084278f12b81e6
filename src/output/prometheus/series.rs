//! A responder's series: its counts, its RTT histogram, and the figures
//! the summary adds at the end (percentiles, clock offset, loss by
//! direction).

use super::sources::SourceSeries;
use crate::engine::matcher::{Counts, MatchEvent};
use crate::engine::probe::command::CommandEvent;
use crate::engine::stats::RttSummary;
use crate::engine::summary::Direction;
use crate::engine::Nanos;
use crate::frame::SysComp;

/// Upper bounds of the RTT histogram, in seconds: from loopback (sub-ms)
/// to a congested 57600-baud radio (seconds).
pub(crate) const BUCKETS_S: [f64; 14] = [
    0.000_5, 0.001, 0.002_5, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
];

/// What one event told of a responder's requests. The exporter and the
/// live view count the same events the same way, in the matcher's own
/// [`Counts`] (whose `sent` is the requests decided: received + lost).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// Answered within the timeout, in this RTT.
    Received(Nanos),
    Lost,
    /// A first reply after the timeout: the request was counted lost then.
    Late,
    Duplicate,
}

impl Outcome {
    /// An echo probe's event, and whose; a stale reply tells nothing.
    pub(crate) fn of_match(e: &MatchEvent) -> Option<(SysComp, Outcome)> {
        Some(match *e {
            MatchEvent::Reply { responder, rtt, .. } => (responder, Outcome::Received(rtt)),
            MatchEvent::Lost { responder, .. } => (responder, Outcome::Lost),
            MatchEvent::Late { responder, .. } => (responder, Outcome::Late),
            MatchEvent::Duplicate { responder, .. } => (responder, Outcome::Duplicate),
            MatchEvent::Stale { .. } => return None,
        })
    }

    /// `--probe command`: a command target is a responder whose requests
    /// are commands; acknowledged is received, failed is lost, and the
    /// time to ACK its RTT.
    pub(crate) fn of_command(e: &CommandEvent) -> Option<(SysComp, Outcome)> {
        Some(match *e {
            CommandEvent::Acked {
                target,
                time_to_ack,
                ..
            } => (target, Outcome::Received(time_to_ack)),
            CommandEvent::Failed { target, .. } => (target, Outcome::Lost),
            CommandEvent::LateAck { from, .. } => (from, Outcome::Late),
            CommandEvent::DuplicateAck { from, .. } => (from, Outcome::Duplicate),
            CommandEvent::Send { .. } | CommandEvent::Skipped { .. } => return None,
        })
    }

    pub(crate) fn count(self, counts: &mut Counts) {
        // A request received or lost is decided: `sent` counts it.
        let (count, decided) = match self {
            Outcome::Received(_) => (&mut counts.received, 1),
            Outcome::Lost => (&mut counts.lost, 1),
            Outcome::Late => (&mut counts.late, 0),
            Outcome::Duplicate => (&mut counts.duplicate, 0),
        };
        *count += 1;
        counts.sent += decided;
    }
}

#[derive(Debug, Default, Clone)]
pub(super) struct Series {
    /// Counted from the events; only `sent` (the requests decided),
    /// `received`, `lost`, `late` and `duplicate` are kept.
    pub(super) counts: Counts,
    /// Non-cumulative counts per bucket; the last one is +Inf.
    pub(super) buckets: [u64; BUCKETS_S.len() + 1],
    pub(super) rtt_sum_s: f64,
    pub(super) last_rtt_s: Option<f64>,
    /// From the summary at the end (the HDR histogram's figures).
    pub(super) rtt: Option<RttSummary>,
    pub(super) clock_offset_s: Option<f64>,
    /// `--probe auto`: whether it is measured by TIMESYNC (else PING).
    pub(super) via_timesync: Option<u8>,
    pub(super) split: Split,
    /// It answered a request of the link's current session (in time or
    /// late).
    pub(super) answering: bool,
}

/// Where a responder's loss by direction comes from.
#[derive(Debug, Default, Clone, Copy)]
pub(super) enum Split {
    /// Made at each scrape while the run goes on.
    #[default]
    Live,
    /// The summary's own, once the run has ended (`None`: it found none).
    AtEnd(Option<Direction>),
}

impl Series {
    pub(super) fn record(&mut self, outcome: Outcome) {
        outcome.count(&mut self.counts);
        self.answering |= outcome != Outcome::Lost;
        if let Outcome::Received(rtt) = outcome {
            let s = rtt as f64 / 1e9;
            // The first bucket whose bound is not below it, else +Inf.
            self.buckets[BUCKETS_S.partition_point(|&b| b < s)] += 1;
            self.rtt_sum_s += s;
            self.last_rtt_s = Some(s);
        }
    }

    pub(super) fn loss_ratio(&self) -> Option<f64> {
        (self.counts.sent > 0).then(|| self.counts.loss_ratio())
    }

    /// Its loss by direction, from its requests and its own frames'
    /// sequence (`downlink`), as the summary splits it.
    pub(super) fn direction(&self, downlink: Option<&SourceSeries>) -> Option<Direction> {
        match self.split {
            Split::AtEnd(at_end) => at_end,
            Split::Live => {
                let c = &self.counts;
                Direction::of_sequence(self.loss_ratio()?, c.sent, c.late, &downlink?.seq())
            }
        }
    }
}
