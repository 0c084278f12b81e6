//! JSON objects of a sweep (`--sweep`) or a `--load` run: what the start
//! object adds, a `step` object per step, and the summary's `sweep`.

use serde_json::{json, Value};

use super::JsonReporter;
use crate::engine::capacity::WireBudget;
use crate::engine::sweep::step::StepFigures;
use crate::engine::sweep::verdict::SweepSummary;
use crate::engine::sweep::{PlanKind, SweepConfig};

/// The start object's `sweep`: what will be sent.
pub(super) fn plan(c: &SweepConfig) -> Value {
    let load: Vec<Value> = c
        .load
        .iter()
        .map(|l| json!({"message": l.kind.name(), "rate": l.rate}))
        .collect();
    let mut m = match c.plan {
        PlanKind::Sweep {
            first_hz,
            max_hz,
            max_from,
            loss_limit,
        } => json!({
            "kind": "sweep",
            "first_hz": first_hz,
            "max_hz": max_hz,
            "max_from": max_from,
            "loss_limit": loss_limit,
        }),
        PlanKind::Load { rate_hz } => json!({"kind": "load", "rate_hz": rate_hz}),
    };
    m["step_s"] = json!(c.step.as_secs_f64());
    m["load"] = json!(load);
    m["load_bytes_per_s"] = json!(c.load_bytes_per_s);
    m
}

fn step_fields(s: &StepFigures) -> Value {
    json!({
        "index": s.index,
        "phase": s.phase,
        "load": s.load,
        "offered_hz": s.offered_hz,
        "achieved_hz": s.achieved_hz,
        "start_s": s.start_s,
        "duration_s": s.duration_s,
        "requests": s.requests,
        "received": s.received,
        "lost": s.lost,
        "late": s.late,
        "loss_ratio": s.loss_ratio,
        "rtt_us": s.rtt.map(|r| json!({"p50": r.p50_us, "p99": r.p99_us, "max": r.max_us})),
        "tx_bytes_per_s": s.tx_bytes_per_s,
        "rx_bytes_per_s": s.rx_bytes_per_s,
        "radio": s.radio,
        "complete": s.complete,
        "passed": s.passed,
    })
}

impl<W: std::io::Write> JsonReporter<W> {
    /// The `step` object, stamped when the step's sending ended.
    pub(super) fn step_object(&self, s: &StepFigures) -> Value {
        let end = ((s.start_s + s.duration_s) * 1e9) as u64;
        let mut v = step_fields(s);
        v["type"] = json!("step");
        v["t_s"] = json!(end as f64 / 1e9);
        v["time"] = json!(self.wall.rfc3339(end));
        v
    }
}

/// The summary's `sweep`: every step, the knee beside what the baud rate
/// alone allows, queueing, and the load.
pub(super) fn summary(s: &SweepSummary, wire: Option<&WireBudget>) -> Value {
    json!({
        "kind": s.kind,
        "steps": s.steps.iter().map(step_fields).collect::<Vec<_>>(),
        "reference_p99_us": s.reference_p99_us,
        "knee": s.knee,
        "baud_capacity_hz": wire.map(|w| w.max_rate_hz),
        "queueing": s.queueing,
        "load": s.load,
        "load_effect": s.load_effect,
        "ending": s.ending,
    })
}
