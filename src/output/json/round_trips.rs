//! A telemetry log's round trips as JSON: the `round_trips` field of
//! `passive_summary`, with the stamps' resolution beside the figures.

use serde::Serialize;

use super::echo::Rtt;
use crate::engine::probe::passive::round_trips::{
    Kind, PairCounts, RequesterSummary, RoundTripSummary,
};
use crate::frame::SysComp;
use crate::transport::tlog::LogFacts;

/// One requester → responder exchange.
#[derive(Serialize)]
pub(super) struct Pair {
    kind: Kind,
    requester: SysComp,
    responder: SysComp,
    #[serde(flatten)]
    counts: PairCounts,
    rtt: Option<Rtt>,
}

#[derive(Serialize)]
pub(super) struct RoundTrips<'a> {
    /// What the RTTs were computed from: the log's stamps, in steps of
    /// this (1000: QGroundControl's whole milliseconds).
    resolution_us: u64,
    timeout_s: f64,
    pairs: Vec<Pair>,
    requesters: &'a [RequesterSummary],
    untracked: u64,
}

impl<'a> RoundTrips<'a> {
    pub(super) fn of(rt: &'a RoundTripSummary, log: Option<&LogFacts>) -> Self {
        RoundTrips {
            resolution_us: if log.is_some_and(|l| l.stamps.whole_ms) {
                1000
            } else {
                1
            },
            timeout_s: rt.timeout_s,
            pairs: rt
                .pairs
                .iter()
                .map(|p| Pair {
                    kind: p.kind,
                    requester: p.requester,
                    responder: p.responder,
                    counts: p.counts,
                    rtt: p.rtt.as_ref().map(Rtt::of),
                })
                .collect(),
            requesters: &rt.requesters,
            untracked: rt.untracked,
        }
    }
}
