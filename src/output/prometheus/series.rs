//! A responder's series: its counts, its RTT histogram, and the figures
//! the summary adds at the end (percentiles, clock offset, loss by
//! direction).

use super::sources::SourceSeries;
use crate::engine::summary::Direction;
use crate::engine::Nanos;

/// Upper bounds of the RTT histogram, in seconds: from loopback (sub-ms)
/// to a congested 57600-baud radio (seconds).
pub(crate) const BUCKETS_S: [f64; 14] = [
    0.000_5, 0.001, 0.002_5, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
];

#[derive(Debug, Default, Clone)]
pub(super) struct Series {
    /// Requests whose fate is decided (received + lost): what
    /// `mavping_sent_total` exports, not the matcher's `sent`.
    pub(super) decided: u64,
    pub(super) received: u64,
    pub(super) lost: u64,
    pub(super) late: u64,
    pub(super) duplicate: u64,
    /// Non-cumulative counts per bucket; the last one is +Inf.
    pub(super) buckets: [u64; BUCKETS_S.len() + 1],
    pub(super) rtt_sum_s: f64,
    pub(super) last_rtt_s: Option<f64>,
    /// From the summary at the end (the HDR histogram's figures).
    pub(super) p50_s: Option<f64>,
    pub(super) p99_s: Option<f64>,
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
    fn observe(&mut self, rtt: Nanos) {
        let s = rtt as f64 / 1e9;
        let i = BUCKETS_S
            .iter()
            .position(|&b| s <= b)
            .unwrap_or(BUCKETS_S.len());
        self.buckets[i] += 1;
        self.rtt_sum_s += s;
        self.last_rtt_s = Some(s);
    }

    pub(super) fn decided(&mut self, received: Option<Nanos>) {
        self.decided += 1;
        match received {
            Some(rtt) => {
                self.answering = true;
                self.received += 1;
                self.observe(rtt);
            }
            None => self.lost += 1,
        }
    }

    pub(super) fn loss_ratio(&self) -> Option<f64> {
        (self.decided > 0).then(|| self.lost as f64 / self.decided as f64)
    }

    /// Its loss by direction, from its requests and its own frames'
    /// sequence (`downlink`), as the summary splits it.
    pub(super) fn direction(&self, downlink: Option<&SourceSeries>) -> Option<Direction> {
        match self.split {
            Split::AtEnd(at_end) => at_end,
            Split::Live => {
                Direction::of_sequence(self.loss_ratio()?, self.decided, &downlink?.seq())
            }
        }
    }
}
