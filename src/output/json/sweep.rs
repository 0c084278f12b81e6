//! Lines of a sweep (`--sweep`) or a `--load` run: a `step` line per
//! step, and the summary's `sweep` (the start line's is the engine's
//! `SweepConfig` as it serialises).

use serde::Serialize;

use super::lines::Lines;
use super::units::seconds;
use crate::engine::capacity::WireBudget;
use crate::engine::load::LoadSummary;
use crate::engine::sweep::step::StepFigures;
use crate::engine::sweep::verdict::{Knee, LoadEffect, Queueing, SweepEnd, SweepSummary};

/// `step`: a step ended, stamped when its sending did.
#[derive(Serialize)]
pub(super) struct Step<'a> {
    #[serde(flatten)]
    figures: &'a StepFigures,
    r#type: &'static str,
    t_s: f64,
    time: String,
}

impl Lines {
    /// The `step` line.
    pub(super) fn step<'a>(&self, s: &'a StepFigures) -> Step<'a> {
        let end = ((s.start_s + s.duration_s) * 1e9) as u64;
        Step {
            figures: s,
            r#type: "step",
            t_s: seconds(end),
            time: self.wall.rfc3339(end),
        }
    }
}

/// The summary's `sweep`: every step, the knee beside what the baud rate
/// alone allows (the echo summary's wire budget, hence a struct here
/// rather than `SweepSummary` flattened), queueing, and the load.
#[derive(Serialize)]
pub(super) struct Summary<'a> {
    kind: &'a str,
    steps: &'a [StepFigures],
    reference_p99_us: Option<f64>,
    knee: Option<Knee>,
    baud_capacity_hz: Option<f64>,
    queueing: Option<Queueing>,
    load: &'a [LoadSummary],
    load_effect: Option<LoadEffect>,
    ending: SweepEnd,
}

impl<'a> Summary<'a> {
    pub(super) fn of(s: &'a SweepSummary, wire: Option<&WireBudget>) -> Self {
        Summary {
            kind: s.kind,
            steps: &s.steps,
            reference_p99_us: s.reference_p99_us,
            knee: s.knee,
            baud_capacity_hz: wire.map(|w| w.max_rate_hz),
            queueing: s.queueing,
            load: &s.load,
            load_effect: s.load_effect,
            ending: s.ending,
        }
    }
}
