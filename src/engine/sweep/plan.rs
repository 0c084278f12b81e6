//! Which rate each step of a sweep offers. Pure: it is told the steps
//! measured so far and answers with the next, or none.
//!
//! A sweep ramps up the 1-2-5 series from the first rate to the highest
//! (`--sweep-max`), and stops ramping when a step loses more than the
//! limit. Then it refines: it bisects (geometrically) between the highest
//! rate that passed the knee test and the lowest above it that failed,
//! until they are within [`RESOLUTION`] of each other. Ramping first finds
//! the region in a handful of steps; bisecting pins the knee there without
//! flooding the link at every rate in between.

use super::step::{Phase, PlannedStep, StepFigures};
use super::{PlanKind, SweepConfig};

/// The refine stops when the bracket around the knee is this narrow (a
/// ratio of 1.1): the knee is then within 10 % below the true capacity.
pub(crate) const RESOLUTION: f64 = 0.1;
/// At most this many refining steps (a bracket of 2.5 takes four).
const MAX_REFINES: usize = 6;
/// A 1-2-5 value this close above the first rate is skipped: it would
/// measure almost the same rate again.
const MIN_RAMP_RATIO: f64 = 1.2;

/// The rates of the ramp: `first`, the 1-2-5 values above it, and `max`.
pub(crate) fn ramp(first: f64, max: f64) -> Vec<f64> {
    let mut rates = vec![first];
    let mut decade = 10f64.powf(first.log10().floor() - 1.0);
    'series: loop {
        for m in [1.0, 2.0, 5.0] {
            let v = m * decade;
            if v >= max {
                break 'series;
            }
            if v >= first * MIN_RAMP_RATIO {
                rates.push(v);
            }
        }
        decade *= 10.0;
    }
    if max > first {
        rates.push(max);
    }
    rates
}

/// Decides the steps of one run.
#[derive(Debug, Clone)]
pub(crate) struct Planner {
    config: SweepConfig,
    ramp: Vec<f64>,
}

impl Planner {
    pub(crate) fn new(config: &SweepConfig) -> Self {
        let ramp = match config.plan {
            PlanKind::Sweep {
                first_hz, max_hz, ..
            } => ramp(first_hz, max_hz),
            PlanKind::Load { .. } => Vec::new(),
        };
        Planner {
            config: config.clone(),
            ramp,
        }
    }

    #[allow(
        clippy::unnecessary_wraps,
        reason = "the value of `next`'s match arms, which may also be None"
    )]
    fn step(&self, phase: Phase, rate_hz: f64, load: bool) -> Option<PlannedStep> {
        Some(PlannedStep::new(phase, rate_hz, load, self.config.step))
    }

    /// The next step after `done` (every step closed so far, in order), or
    /// `None` when the run has measured what it set out to.
    pub(crate) fn next(&self, done: &[StepFigures]) -> Option<PlannedStep> {
        let loaded = !self.config.load.is_empty();
        // Every step so far ran to its end: an interrupted one ends the run.
        if done.iter().any(|s| !s.complete) {
            return None;
        }
        match self.config.plan {
            PlanKind::Load { rate_hz } => match done.len() {
                0 => self.step(Phase::Baseline, rate_hz, false),
                1 => self.step(Phase::Loaded, rate_hz, true),
                _ => None,
            },
            PlanKind::Sweep {
                first_hz,
                loss_limit,
                ..
            } => {
                if loaded && done.is_empty() {
                    return self.step(Phase::Baseline, first_hz, false);
                }
                let sweep: Vec<&StepFigures> = done.iter().filter(|s| s.phase.sweeps()).collect();
                if let Some(again) = self.retry(&sweep) {
                    return Some(again);
                }
                let ramped = sweep
                    .iter()
                    .filter(|s| s.phase == Phase::Ramp && !s.retry)
                    .count();
                let refined = sweep.iter().any(|s| s.phase == Phase::Refine);
                // Nothing answered: more of the same floods a silent link.
                let over_limit = sweep
                    .iter()
                    .any(|s| s.loss_ratio > loss_limit || s.received == 0);
                if !over_limit && ramped < self.ramp.len() && !refined {
                    return self.step(Phase::Ramp, self.ramp[ramped], loaded);
                }
                self.refine(&sweep, loaded)
            }
        }
    }

    /// The last step again when it failed on latency alone and was not
    /// itself a retry: a failure counts once it is seen twice.
    fn retry(&self, sweep: &[&StepFigures]) -> Option<PlannedStep> {
        let last = sweep.last()?;
        if last.retry || !last.failed_on_latency_alone() {
            return None;
        }
        self.step(last.phase, last.offered_hz, last.load)
            .map(PlannedStep::retried)
    }

    /// The geometric middle of the bracket around the knee, while it is
    /// wider than [`RESOLUTION`].
    fn refine(&self, sweep: &[&StepFigures], loaded: bool) -> Option<PlannedStep> {
        let refines = sweep
            .iter()
            .filter(|s| s.phase == Phase::Refine && !s.retry)
            .count();
        if refines >= MAX_REFINES {
            return None;
        }
        let passed = |s: &&&StepFigures| s.passed == Some(true);
        let low = sweep
            .iter()
            .filter(passed)
            .map(|s| s.offered_hz)
            .reduce(f64::max)?;
        let high = sweep
            .iter()
            .filter(|s| s.passed == Some(false) && s.offered_hz > low)
            .map(|s| s.offered_hz)
            .reduce(f64::min)?;
        if high / low <= 1.0 + RESOLUTION {
            return None;
        }
        self.step(Phase::Refine, three_digits((low * high).sqrt()), loaded)
    }
}

/// A rate rounded to three significant digits: 154, not 154.2135623.
fn three_digits(v: f64) -> f64 {
    let scale = 10f64.powi(2 - v.log10().floor() as i32);
    (v * scale).round() / scale
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;
    use crate::engine::load::LoadSpec;
    use crate::engine::sweep::MaxFrom;

    fn sweep(first: f64, max: f64, load: &[&str]) -> SweepConfig {
        SweepConfig {
            plan: PlanKind::Sweep {
                first_hz: first,
                max_hz: max,
                max_from: MaxFrom::Given,
                loss_limit: 0.2,
            },
            step: Duration::from_secs(2),
            load: load
                .iter()
                .map(|l| l.parse::<LoadSpec>().unwrap())
                .collect(),
            load_bytes_per_s: 0.0,
        }
    }

    /// Runs the planner against a link that carries `capacity` PINGs/s:
    /// steps above it fail the knee test, and lose more the further above.
    fn run(config: &SweepConfig, capacity: f64) -> Vec<StepFigures> {
        let planner = Planner::new(config);
        let mut done = Vec::new();
        while let Some(p) = planner.next(&done) {
            assert!(done.len() < 40, "the plan never ends");
            let over = (p.rate_hz - capacity).max(0.0) / p.rate_hz;
            let mut s = StepFigures::test(p.phase, p.rate_hz, over);
            (s.load, s.retry) = (p.load, p.retry);
            if p.phase.sweeps() {
                s.passed = Some(p.rate_hz <= capacity);
            }
            done.push(s);
        }
        done
    }

    #[test]
    fn the_ramp_climbs_the_1_2_5_series_to_the_maximum() {
        assert_eq!(
            ramp(2.0, 244.0),
            vec![2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 244.0]
        );
        assert_eq!(ramp(1.0, 50.0), vec![1.0, 2.0, 5.0, 10.0, 20.0, 50.0]);
        // 4.5 then 5 would measure the same rate twice.
        assert_eq!(ramp(4.5, 20.0), vec![4.5, 10.0, 20.0]);
        assert_eq!(ramp(10.0, 10.0), vec![10.0]);
    }

    #[test]
    fn the_refine_pins_the_knee_within_the_resolution() {
        for capacity in [3.3, 37.0, 122.5, 153.8, 307.7, 999.0] {
            let steps = run(&sweep(2.0, 2000.0, &[]), capacity);
            let knee = steps
                .iter()
                .filter(|s| s.passed == Some(true))
                .map(|s| s.offered_hz)
                .reduce(f64::max)
                .unwrap();
            assert!(
                knee <= capacity && knee >= capacity / (1.0 + RESOLUTION),
                "capacity {capacity}: knee {knee} after {} steps",
                steps.len()
            );
            // The ramp stopped past the loss limit; a handful of refines.
            assert!(steps.len() <= 16, "{capacity}: {} steps", steps.len());
            assert!(steps.iter().filter(|s| s.loss_ratio > 0.2).count() <= 1);
        }
    }

    #[test]
    fn a_link_that_carries_the_maximum_needs_no_refine() {
        let steps = run(&sweep(2.0, 100.0, &[]), 500.0);
        assert!(steps.iter().all(|s| s.phase == Phase::Ramp));
        assert_eq!(steps.last().unwrap().offered_hz, 100.0);
    }

    #[test]
    fn load_adds_an_unloaded_baseline_first() {
        let steps = run(&sweep(5.0, 100.0, &["ATTITUDE@50"]), 60.0);
        assert_eq!(steps[0].phase, Phase::Baseline);
        assert!(!steps[0].load);
        assert_eq!(steps[0].offered_hz, 5.0);
        assert!(steps[1..].iter().all(|s| s.load && s.phase.sweeps()));
        let only_load = SweepConfig {
            plan: PlanKind::Load { rate_hz: 10.0 },
            ..sweep(1.0, 1.0, &["ATTITUDE@50"])
        };
        let steps = run(&only_load, 100.0);
        let phases: Vec<Phase> = steps.iter().map(|s| s.phase).collect();
        assert_eq!(phases, [Phase::Baseline, Phase::Loaded]);
        assert_eq!((steps[0].load, steps[1].load), (false, true));
    }

    #[test]
    fn a_link_that_never_answers_gets_one_step() {
        let config = sweep(2.0, 100.0, &[]);
        let planner = Planner::new(&config);
        let mut s = StepFigures::test(Phase::Ramp, 2.0, 0.0);
        (s.received, s.lost, s.passed) = (0, 0, Some(false));
        assert_eq!(planner.next(&[s]), None);
    }

    #[test]
    fn an_interrupted_step_ends_the_plan() {
        let config = sweep(2.0, 100.0, &[]);
        let planner = Planner::new(&config);
        let mut s = StepFigures::test(Phase::Ramp, 2.0, 0.0);
        s.complete = false;
        assert_eq!(planner.next(&[s]), None);
    }

    #[test]
    fn a_step_that_failed_on_latency_alone_is_run_once_more() {
        let config = sweep(2.0, 100.0, &[]);
        let planner = Planner::new(&config);
        let mut first = StepFigures::test(Phase::Ramp, 2.0, 0.0);
        first.passed = Some(true);
        // 5/s lost nothing but its p99 failed: 5/s again, marked a retry.
        let mut hiccup = StepFigures::test(Phase::Ramp, 5.0, 0.0);
        hiccup.passed = Some(false);
        let again = planner.next(&[first.clone(), hiccup.clone()]).unwrap();
        assert_eq!(
            (again.phase, again.rate_hz, again.retry),
            (Phase::Ramp, 5.0, true)
        );
        // It passed the second time: the ramp goes on where it was.
        let mut passed = StepFigures::test(Phase::Ramp, 5.0, 0.0);
        (passed.passed, passed.retry) = (Some(true), true);
        let next = planner
            .next(&[first.clone(), hiccup.clone(), passed])
            .unwrap();
        assert_eq!((next.rate_hz, next.retry), (10.0, false));
        // Failed twice: no third try; the refine takes it from there.
        let mut twice = StepFigures::test(Phase::Ramp, 5.0, 0.0);
        (twice.passed, twice.retry) = (Some(false), true);
        let next = planner.next(&[first.clone(), hiccup, twice]).unwrap();
        assert!(!next.retry, "{next:?}");
        // A step that lost is never retried: loss is not a hiccup.
        let mut lossy = StepFigures::test(Phase::Ramp, 5.0, 0.3);
        lossy.passed = Some(false);
        assert!(!planner.next(&[first, lossy]).unwrap().retry);
    }

    #[test]
    fn refined_rates_have_three_digits() {
        assert_eq!(three_digits(154.2135), 154.0);
        assert_eq!(three_digits(12.345), 12.3);
        assert_eq!(three_digits(0.98765), 0.988);
        assert_eq!(three_digits(1414.2), 1410.0);
    }

    #[test]
    fn counts_follow_the_step_duration() {
        let p = PlannedStep::new(Phase::Ramp, 2.5, false, Duration::from_secs(2));
        assert_eq!((p.count, p.interval_ns()), (5, 400_000_000));
        // At least one request however short the step.
        let p = PlannedStep::new(Phase::Ramp, 0.1, false, Duration::from_secs(1));
        assert_eq!(p.count, 1);
    }
}
