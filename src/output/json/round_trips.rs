//! A telemetry log's round trips as JSON: the `round_trips` field of
//! `passive_summary`, with the stamps' resolution beside the figures.

use serde::Serialize;

use crate::engine::probe::passive::round_trips::RoundTripSummary;
use crate::transport::tlog::LogFacts;

#[derive(Serialize)]
pub(super) struct RoundTrips<'a> {
    /// What the RTTs were computed from: the log's stamps, in steps of
    /// this (1000: QGroundControl's whole milliseconds).
    resolution_us: u64,
    #[serde(flatten)]
    figures: &'a RoundTripSummary,
}

impl<'a> RoundTrips<'a> {
    pub(super) fn of(rt: &'a RoundTripSummary, log: Option<&LogFacts>) -> Self {
        RoundTrips {
            resolution_us: if log.is_some_and(|l| l.stamps.whole_ms) {
                1000
            } else {
                1
            },
            figures: rt,
        }
    }
}
