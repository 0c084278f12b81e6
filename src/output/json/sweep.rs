//! Lines of a sweep (`--sweep`) or a `--load` run: what the start line
//! adds, a `step` line per step, and the summary's `sweep`.

use serde::Serialize;

use super::lines::Lines;
use super::units::seconds;
use crate::engine::capacity::WireBudget;
use crate::engine::load::LoadSummary;
use crate::engine::sweep::step::{Phase, StepFigures, StepRadio};
use crate::engine::sweep::verdict::{Knee, LoadEffect, Queueing, SweepEnd, SweepSummary};
use crate::engine::sweep::{MaxFrom, PlanKind, SweepConfig};

/// The start line's `sweep`: what will be sent.
#[derive(Serialize)]
pub(super) struct Plan {
    #[serde(flatten)]
    steps: Steps,
    step_s: f64,
    load: Vec<Stream>,
    load_bytes_per_s: f64,
}

/// How the steps' rates are chosen.
#[derive(Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum Steps {
    Sweep {
        first_hz: f64,
        max_hz: f64,
        max_from: MaxFrom,
        loss_limit: f64,
    },
    Load {
        rate_hz: f64,
    },
}

/// One `--load` stream as given.
#[derive(Serialize)]
struct Stream {
    message: &'static str,
    rate: f64,
}

impl Plan {
    pub(super) fn of(c: &SweepConfig) -> Self {
        Plan {
            steps: match c.plan {
                PlanKind::Sweep {
                    first_hz,
                    max_hz,
                    max_from,
                    loss_limit,
                } => Steps::Sweep {
                    first_hz,
                    max_hz,
                    max_from,
                    loss_limit,
                },
                PlanKind::Load { rate_hz } => Steps::Load { rate_hz },
            },
            step_s: c.step.as_secs_f64(),
            load: c
                .load
                .iter()
                .map(|l| Stream {
                    message: l.kind.name(),
                    rate: l.rate,
                })
                .collect(),
            load_bytes_per_s: c.load_bytes_per_s,
        }
    }
}

/// One step's figures, in the `step` line and the summary's steps.
#[derive(Serialize)]
struct Figures {
    index: u32,
    phase: Phase,
    load: bool,
    offered_hz: f64,
    achieved_hz: f64,
    start_s: f64,
    duration_s: f64,
    requests: u64,
    received: u64,
    lost: u64,
    late: u64,
    loss_ratio: f64,
    rtt_us: Option<Rtt>,
    tx_bytes_per_s: f64,
    rx_bytes_per_s: f64,
    radio: Option<StepRadio>,
    complete: bool,
    passed: Option<bool>,
    retry: bool,
}

/// A step's RTT over every responder's in-time replies, in µs.
#[derive(Serialize)]
struct Rtt {
    p50: f64,
    p99: f64,
    max: f64,
}

impl Figures {
    fn of(s: &StepFigures) -> Self {
        Figures {
            index: s.index,
            phase: s.phase,
            load: s.load,
            offered_hz: s.offered_hz,
            achieved_hz: s.achieved_hz,
            start_s: s.start_s,
            duration_s: s.duration_s,
            requests: s.requests,
            received: s.received,
            lost: s.lost,
            late: s.late,
            loss_ratio: s.loss_ratio,
            rtt_us: s.rtt.map(|r| Rtt {
                p50: r.p50_us,
                p99: r.p99_us,
                max: r.max_us,
            }),
            tx_bytes_per_s: s.tx_bytes_per_s,
            rx_bytes_per_s: s.rx_bytes_per_s,
            radio: s.radio,
            complete: s.complete,
            passed: s.passed,
            retry: s.retry,
        }
    }
}

/// `step`: a step ended, stamped when its sending did.
#[derive(Serialize)]
pub(super) struct Step {
    #[serde(flatten)]
    figures: Figures,
    r#type: &'static str,
    t_s: f64,
    time: String,
}

impl Lines {
    /// The `step` line.
    pub(super) fn step(&self, s: &StepFigures) -> Step {
        let end = ((s.start_s + s.duration_s) * 1e9) as u64;
        Step {
            figures: Figures::of(s),
            r#type: "step",
            t_s: seconds(end),
            time: self.wall.rfc3339(end),
        }
    }
}

/// The summary's `sweep`: every step, the knee beside what the baud rate
/// alone allows, queueing, and the load.
#[derive(Serialize)]
pub(super) struct Summary<'a> {
    kind: &'a str,
    steps: Vec<Figures>,
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
            steps: s.steps.iter().map(Figures::of).collect(),
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
