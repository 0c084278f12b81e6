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
//! This file declares and re-exports, and hands each `Reporter` call to
//! the link's `Metrics` (`metrics.rs`); a responder's series are in
//! `series.rs`, a radio's in `radio_series.rs`, the exposition text in
//! `render.rs`.

mod exporter;
mod exposition;
mod link_node;
mod metrics;
mod passive;
mod radio_series;
mod render;
mod series;
mod sources;
#[cfg(test)]
mod test_support;

use std::io;

use super::Reporter;
use crate::engine::clock_offset::ClockSummary;
use crate::engine::link_node::LinkNodeReport;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{RadioHeard, StartInfo};
use crate::engine::probe::command::CommandEvent;
use crate::engine::summary::passive::{PassiveSummary, TableSummary};
use crate::engine::summary::{CommandSummary, EchoSummary};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;
pub(crate) use exporter::borrow_all;
pub use exporter::{PrometheusExporter, SharedMetrics};
pub(crate) use metrics::Metrics;
pub(crate) use render::{render_probe, render_serve, Health, ProbeResult};
pub(crate) use series::Outcome;

impl Reporter for Metrics {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.on_start(info);
        Ok(())
    }

    fn matched(&mut self, e: &MatchEvent) -> io::Result<()> {
        self.on_event(e);
        Ok(())
    }

    fn command(&mut self, e: &CommandEvent) -> io::Result<()> {
        self.on_command(e);
        Ok(())
    }

    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        self.on_radio(radio.id, radio.report, radio.judgement.kind);
        Ok(())
    }

    fn link_node(
        &mut self,
        id: SysComp,
        at: Nanos,
        report: &LinkNodeReport,
        _: bool,
    ) -> io::Result<()> {
        self.link_nodes.record(id, *report, at);
        Ok(())
    }

    fn clock(&mut self, id: SysComp, at: Nanos, clock: &ClockSummary) -> io::Result<()> {
        self.on_clock(id, at, clock);
        Ok(())
    }

    fn link_failed(&mut self, _: Nanos, _: &str) -> io::Result<()> {
        self.set_up(false);
        Ok(())
    }

    fn sources(&mut self, _: Nanos, table: &TableSummary) -> io::Result<()> {
        self.on_sources(table, false);
        Ok(())
    }

    fn progress(&mut self, _: Nanos, requests: u64) -> io::Result<()> {
        self.requests.session = requests;
        Ok(())
    }

    fn echo_summary(&mut self, summary: &EchoSummary, _: &Verdict) -> io::Result<()> {
        self.requests.session = summary.requests;
        self.on_summary(summary);
        Ok(())
    }

    fn passive_summary(&mut self, summary: &PassiveSummary, _: &Verdict) -> io::Result<()> {
        self.on_sources(&summary.table, true);
        Ok(())
    }

    fn command_summary(&mut self, summary: &CommandSummary, _: &Verdict) -> io::Result<()> {
        self.requests.session = summary.commands();
        Ok(())
    }
}
