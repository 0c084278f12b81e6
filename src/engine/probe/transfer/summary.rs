//! The end of a transfer run: how many downloads completed and how long
//! they took, the last one's figures, the round trip measured beside
//! them, and why any failed.

use serde::Serialize;

use super::attempt::{AttemptFigures, Ending};
use super::spec::TransferSpec;
use crate::engine::answers::AnswerSummary;
use crate::engine::hint::Hint;
use crate::engine::link_node::LinkNodeSummary;
use crate::engine::matcher::Counts as EchoCounts;
use crate::engine::stats::{RttStats, RttSummary};
use crate::engine::Nanos;
use crate::frame::signing::SigningSummary;
use crate::frame::{ScanStats, SysComp};

/// The downloads' times to complete, in ms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct CompletionTimes {
    pub(crate) min_ms: f64,
    pub(crate) p50_ms: f64,
    pub(crate) p90_ms: f64,
    pub(crate) max_ms: f64,
    pub(crate) mean_ms: f64,
}

impl CompletionTimes {
    fn of(stats: &RttStats) -> Option<Self> {
        let s = stats.summary()?;
        Some(CompletionTimes {
            min_ms: s.min_us / 1e3,
            p50_ms: s.p50_us / 1e3,
            p90_ms: s.p90_us / 1e3,
            max_ms: s.max_us / 1e3,
            mean_ms: s.mean_us / 1e3,
        })
    }
}

/// Round trips to the target (PING, or TIMESYNC where PING goes
/// unanswered) while the downloads ran: the latency under the heaviest
/// downlink a ground station makes.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct LatencyBeside {
    pub(crate) responder: SysComp,
    #[serde(flatten)]
    pub(crate) counts: EchoCounts,
    #[serde(serialize_with = "crate::engine::stats::with_units")]
    pub(crate) rtt: Option<RttSummary>,
}

/// Every download of a run, added up as they end (constant memory).
#[derive(Clone, Default)]
pub(crate) struct Tally {
    pub(crate) attempts: u32,
    pub(crate) complete: u32,
    pub(crate) times: RttStats,
    pub(crate) requests: u64,
    /// Units the targets said there were, over every download.
    pub(crate) units: u64,
    pub(crate) re_requests_answered: u64,
    /// The first download whose list stopped by itself.
    pub(crate) first_stopped: Option<AttemptFigures>,
    pub(crate) missing_first_pass: u64,
    pub(crate) re_requests: u64,
    pub(crate) given_up: u64,
    /// The first download that did not complete, and the last download.
    pub(crate) first_failed: Option<AttemptFigures>,
    pub(crate) last: Option<AttemptFigures>,
}

impl Tally {
    pub(crate) fn add(&mut self, a: &AttemptFigures) {
        self.attempts += 1;
        if a.ending == Ending::Complete {
            self.complete += 1;
            if let Some(ms) = a.progress.time_to_100_ms {
                self.times.record((ms * 1e6) as Nanos);
            }
        } else if self.first_failed.is_none() {
            self.first_failed = Some(a.clone());
        }
        self.missing_first_pass += a.missing_first_pass.unwrap_or(0);
        self.requests += a.counts.requests;
        self.units += a.progress.total.unwrap_or(0);
        self.re_requests_answered += a.counts.re_requests_answered;
        if a.stopped_after.is_some() && self.first_stopped.is_none() {
            self.first_stopped = Some(a.clone());
        }
        self.re_requests += a.counts.re_requests;
        self.given_up += a.counts.given_up;
        self.last = Some(a.clone());
    }

    pub(crate) fn times(&self) -> Option<CompletionTimes> {
        CompletionTimes::of(&self.times)
    }
}

/// The end of a `--probe params`, `mission` or `ftp` run: its JSON
/// `transfer_summary` line's figures (the line adds the link).
#[derive(Debug, Clone, Serialize)]
pub(crate) struct TransferSummary {
    #[serde(skip)]
    pub(crate) link: String,
    pub(crate) ours: SysComp,
    pub(crate) plan: TransferSpec,
    pub(crate) duration_s: f64,
    /// Downloads begun, and of them completed.
    pub(crate) attempts: u32,
    pub(crate) complete: u32,
    pub(crate) time_to_complete: Option<CompletionTimes>,
    /// Over every download: what the first pass left out, the requests
    /// sent again or for what was missing, the pieces given up.
    pub(crate) missing_first_pass: u64,
    /// Requests put on the wire, re-sends included.
    pub(crate) requests: u64,
    pub(crate) re_requests: u64,
    pub(crate) given_up: u64,
    pub(crate) last: Option<AttemptFigures>,
    /// The first download that did not complete, when it is not the last.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) first_failed: Option<AttemptFigures>,
    pub(crate) latency: Option<LatencyBeside>,
    pub(crate) hints: Vec<Hint>,
    pub(crate) frames: ScanStats,
    pub(crate) interrupted: bool,
    pub(crate) link_error: Option<String>,
    pub(crate) signing: SigningSummary,
    #[serde(skip_serializing_if = "AnswerSummary::is_none")]
    pub(crate) answered: AnswerSummary,
    pub(crate) link_node: Vec<LinkNodeSummary>,
}

impl TransferSummary {
    /// Downloads that did not complete.
    pub(crate) fn failed(&self) -> u32 {
        self.attempts - self.complete
    }
}

impl crate::engine::summary::KindSummary for TransferSummary {
    fn link(&self) -> &str {
        &self.link
    }
    fn link_error(&self) -> Option<&str> {
        self.link_error.as_deref()
    }
    fn requests(&self) -> (u64, u64) {
        (self.requests, 0)
    }
    fn serialized(&self) -> Option<(&'static str, &dyn erased_serde::Serialize)> {
        Some(("transfer_summary", self))
    }
}
