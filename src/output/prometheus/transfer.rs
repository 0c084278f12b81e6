//! A download run's figures as metrics: how many downloads ended which
//! way (counters in a run, gauges of one `/probe`), and the latest
//! download's time, size, rates and what its first pass missed (gauges).
//! The TIMESYNC round trip beside the downloads is the responder's
//! usual `mavping_rtt_seconds`.

use std::collections::BTreeMap;

use super::exposition::{Exposition, Family, Figure, SeriesFigure};
use super::Metrics;
use crate::engine::probe::transfer::{AttemptFigures, Ending};

/// What a link's downloads have told so far.
#[derive(Debug, Default, Clone)]
pub(crate) struct TransferSeries {
    /// Downloads by how they ended.
    pub(super) ended: BTreeMap<&'static str, u64>,
    pub(super) missing_first_pass: u64,
    pub(super) re_requests: u64,
    pub(super) last: Option<AttemptFigures>,
}

impl TransferSeries {
    pub(super) fn add(&mut self, a: &AttemptFigures) {
        *self.ended.entry(ending_key(a.ending)).or_default() += 1;
        self.missing_first_pass += a.missing_first_pass.unwrap_or(0);
        self.re_requests += a.counts.re_requests;
        self.last = Some(a.clone());
    }
}

fn ending_key(e: Ending) -> &'static str {
    match e {
        Ending::Complete => "complete",
        Ending::NoAnswer => "no_answer",
        Ending::Stalled => "stalled",
        Ending::Refused => "refused",
        Ending::Cut => "cut",
    }
}

const DOWNLOADS: Family = Family::counter(
    "mavping_transfer_downloads_total",
    "Downloads (parameter lists, missions, files) by how they ended: complete, no_answer, stalled, refused, cut.",
);
const PROBE_DOWNLOADS: Family = Family::gauge(
    "mavping_probe_transfer_downloads",
    "This probe's downloads by how they ended: complete, no_answer, stalled, refused, cut.",
);
const TOTALS: [SeriesFigure<TransferSeries>; 2] = [
    Figure::counter(
        "mavping_transfer_missing_first_pass_total",
        "Units (parameters, items, bytes) the downloads' first passes left out.",
        |t| Some(t.missing_first_pass as f64),
    ),
    Figure::counter(
        "mavping_transfer_re_requests_total",
        "Requests sent again, or sent for what a first pass missed.",
        |t| Some(t.re_requests as f64),
    ),
];

const LAST: [SeriesFigure<AttemptFigures>; 6] = [
    Figure::gauge(
        "mavping_transfer_last_complete",
        "1 when the latest download completed.",
        |a| Some(f64::from(u8::from(a.ending == Ending::Complete))),
    ),
    Figure::gauge(
        "mavping_transfer_last_seconds",
        "The latest download's time to complete, or how long it ran when it did not.",
        |a| Some(a.progress.time_to_100_ms.unwrap_or(a.duration_ms) / 1e3),
    ),
    Figure::gauge(
        "mavping_transfer_last_received",
        "Units (parameters, items, bytes) the latest download received.",
        |a| Some(a.progress.received as f64),
    ),
    Figure::gauge(
        "mavping_transfer_last_size",
        "Units the target said the latest download has.",
        |a| a.progress.total.map(|t| t as f64),
    ),
    Figure::gauge(
        "mavping_transfer_last_missing_first_pass",
        "Units the latest download's first pass left out.",
        |a| a.missing_first_pass.map(|m| m as f64),
    ),
    Figure::gauge(
        "mavping_transfer_last_wire_bytes_per_second",
        "Bytes on the wire a second the target sent for the latest download.",
        |a| a.progress.wire_bytes_per_s,
    ),
];

/// Every link's downloads; `probe`: one `/probe`'s, its counts as gauges.
pub(super) fn write_transfers(out: &mut Exposition, links: &[&Metrics], probe: bool) {
    let series = || {
        links
            .iter()
            .filter_map(|m| Some((m.probe_labels(), m.transfer.as_ref()?)))
    };
    let ended = series().flat_map(|(labels, t)| {
        t.ended
            .iter()
            .map(move |(e, n)| (format!("{labels},ending=\"{e}\""), *n))
    });
    out.family(if probe { &PROBE_DOWNLOADS } else { &DOWNLOADS }, ended);
    if !probe {
        out.figures(&TOTALS, series);
    }
    let last = || series().filter_map(|(l, t)| Some((l, t.last.as_ref()?)));
    out.figures(&LAST, last);
}
