//! Metrics in the Prometheus text format: per-responder counters and RTT
//! histogram, RADIO_STATUS gauges, LINK_NODE_STATUS counters, and what `mavping serve` adds (a
//! continuous link's state, one `/probe`'s result, the exporter's health).
//! The one renderer of every exposition mavping serves.
//!
//! A [`Metrics`] follows one link's session as an engine [`Observer`].
//! `--prometheus` serves the run's links at `/metrics` while it goes on
//! ([`PrometheusExporter`]); memory is fixed per responder, radio and
//! source (the matcher, the radio table and the source table bound how
//! many there are), whatever the run length. A passive run's per-source
//! figures and an echo run's loss by direction come from the table of
//! sources the engine tells once a second ([`sources`]).
//!
//! This file declares and re-exports; the link's `Metrics` takes its
//! session's events in `metrics.rs`; a responder's series are in
//! `series.rs`, a radio's in `radio_series.rs`, a download run's in
//! `transfer.rs`, the C2 link report's in `c2.rs`, the exposition text in
//! `render.rs`.

mod c2;
mod exporter;
mod exposition;
mod link_node;
mod metrics;
mod pair;
mod passive;
mod radio_series;
mod render;
mod series;
mod sources;
#[cfg(test)]
mod test_support;
mod transfer;

pub(crate) use exporter::borrow_all;
pub use exporter::{PrometheusExporter, SharedMetrics};
pub(crate) use metrics::Metrics;
pub(crate) use pair::render_pair;
pub(crate) use render::{render_probe, render_serve, Health, ProbeResult};
pub(crate) use series::Outcome;
