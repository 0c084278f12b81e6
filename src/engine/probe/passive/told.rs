//! What a passive run tells beside its summary: its plan at the start,
//! and every source's figures so far, once a second.

use crate::engine::age::{AgeCounts, AgeNow};
use crate::engine::summary::passive::TableSummary;
use crate::engine::Nanos;
use crate::frame::SysComp;

/// What a passive run listens to (`--passive`, or a telemetry log read).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PassivePlan {
    /// Our HEARTBEAT goes out, so the vehicle streams to us.
    pub(crate) heartbeat: bool,
    /// A telemetry log read, not a live link.
    pub(crate) log: bool,
}

impl crate::engine::kind::KindValue for PassivePlan {}

/// Every source's packet-sequence figures so far (cumulative), told once
/// a second of session time: passive runs, and echo runs for the
/// direction split.
#[derive(Debug)]
pub struct SourcesNow {
    pub(crate) at: Nanos,
    pub(crate) table: TableSummary,
    /// Each source's newest age above its baseline, where its frames
    /// carry a clock stamp...
    pub(crate) ages: Vec<(SysComp, AgeNow)>,
    /// ...and all its frames' ages so far, counted.
    pub(crate) age_counts: Vec<(SysComp, AgeCounts)>,
    /// Each source's oldest frame since the previous telling: its age
    /// above the baseline (ms), by the baseline known when it arrived.
    pub(crate) age_max: Vec<(SysComp, f64)>,
}

impl crate::engine::kind::KindValue for SourcesNow {}
