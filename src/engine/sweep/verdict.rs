//! What a sweep's steps say about the link, pure arithmetic over them: the
//! knee (the measured capacity), whether the link queues before it drops
//! (bufferbloat), and how much the background load raised the RTT.

use super::step::KNEE_MAX_LOSS;
pub(crate) use crate::engine::sweep_report::{
    Grade, Knee, LoadEffect, Queueing, SweepEnd, SweepSummary,
};
use crate::engine::sweep_report::{Phase, StepFigures};

impl Grade {
    /// Upper bounds of each grade but F, in µs of added latency.
    const BOUNDS: [(f64, Grade); 5] = [
        (5_000.0, Grade::APlus),
        (30_000.0, Grade::A),
        (60_000.0, Grade::B),
        (200_000.0, Grade::C),
        (400_000.0, Grade::D),
    ];

    pub(crate) fn of(added_us: f64) -> Grade {
        Self::BOUNDS
            .iter()
            .find(|(bound, _)| added_us < *bound)
            .map_or(Grade::F, |(_, g)| *g)
    }

    pub(crate) fn as_str(self) -> &'static str {
        match self {
            Grade::APlus => "A+",
            Grade::A => "A",
            Grade::B => "B",
            Grade::C => "C",
            Grade::D => "D",
            Grade::F => "F",
        }
    }

    /// C and below: the queue adds enough to be felt (a command 200 ms
    /// late, video stutter); what a bufferbloat test calls bloat.
    pub(crate) fn is_bufferbloat(self) -> bool {
        self >= Grade::C
    }
}

/// The first sweep step's p99: the knee test's reference.
pub(crate) fn reference_p99(steps: &[StepFigures]) -> Option<f64> {
    steps
        .iter()
        .find(|s| s.phase.sweeps() && s.complete)
        .and_then(|s| s.rtt)
        .map(|r| r.p99_us)
}

pub(crate) fn knee(steps: &[StepFigures]) -> Option<Knee> {
    let best = steps
        .iter()
        .filter(|s| s.phase.sweeps() && s.passed == Some(true))
        .max_by(|a, b| a.offered_hz.total_cmp(&b.offered_hz))?;
    let failed_above_hz = steps
        .iter()
        .filter(|s| s.phase.sweeps() && s.passed == Some(false) && s.offered_hz > best.offered_hz)
        .map(|s| s.offered_hz)
        .reduce(f64::min);
    Some(Knee {
        step: best.index,
        rate_hz: best.offered_hz,
        achieved_hz: best.achieved_hz,
        bytes_per_s: best.wire_bytes_per_s(),
        tx_bytes_per_s: best.tx_bytes_per_s,
        rx_bytes_per_s: best.rx_bytes_per_s,
        p99_us: best.rtt.map_or(0.0, |r| r.p99_us),
        loss_ratio: best.loss_ratio,
        failed_above_hz,
    })
}

pub(crate) fn queueing(steps: &[StepFigures]) -> Option<Queueing> {
    let reference = reference_p99(steps)?;
    let (worst_p99_us, worst_at_hz) = steps
        .iter()
        .filter(|s| s.phase.sweeps() && s.complete && s.loss_ratio < KNEE_MAX_LOSS)
        .filter_map(|s| Some((s.rtt?.p99_us, s.offered_hz)))
        .max_by(|a, b| a.0.total_cmp(&b.0))?;
    let lost_at_hz = steps
        .iter()
        .filter(|s| s.phase.sweeps() && s.complete && s.loss_ratio >= KNEE_MAX_LOSS)
        .map(|s| s.offered_hz)
        .reduce(f64::min);
    let added_us = (worst_p99_us - reference).max(0.0);
    let grade = Grade::of(added_us);
    Some(Queueing {
        bufferbloat: grade.is_bufferbloat(),
        grade,
        reference_p99_us: reference,
        worst_p99_us,
        worst_at_hz,
        added_us,
        lost_at_hz,
    })
}

/// The unloaded baseline against the first loaded step (the same rate).
pub(crate) fn load_effect(steps: &[StepFigures]) -> Option<LoadEffect> {
    let base = steps
        .iter()
        .find(|s| s.phase == Phase::Baseline && s.complete)?;
    let loaded = steps
        .iter()
        .find(|s| s.load && s.complete && s.offered_hz == base.offered_hz)?;
    let (b, l) = (base.rtt?, loaded.rtt?);
    Some(LoadEffect {
        rate_hz: base.offered_hz,
        unloaded_p50_us: b.p50_us,
        unloaded_p99_us: b.p99_us,
        loaded_p50_us: l.p50_us,
        loaded_p99_us: l.p99_us,
        p99_rise_us: l.p99_us - b.p99_us,
        p99_ratio: l.p99_us / b.p99_us,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::sweep::step::StepRtt;

    fn step(index: u32, phase: Phase, rate: f64, loss: f64, p99_ms: f64) -> StepFigures {
        let mut s = StepFigures::test(phase, rate, loss);
        s.index = index;
        s.rtt = Some(StepRtt {
            p50_us: p99_ms * 800.0,
            p99_us: p99_ms * 1000.0,
            max_us: p99_ms * 1100.0,
        });
        s
    }

    /// Judges every sweep step as the driver does.
    fn judged(mut steps: Vec<StepFigures>) -> Vec<StepFigures> {
        let reference = reference_p99(&steps).unwrap();
        for s in steps.iter_mut().filter(|s| s.phase.sweeps()) {
            s.passed = Some(s.passes(reference));
        }
        steps
    }

    #[test]
    fn the_knee_is_the_highest_rate_that_passed() {
        let steps = judged(vec![
            step(1, Phase::Ramp, 10.0, 0.0, 30.0),
            step(2, Phase::Ramp, 100.0, 0.0, 40.0),
            step(3, Phase::Ramp, 200.0, 0.3, 300.0),
            step(4, Phase::Refine, 141.0, 0.0, 45.0),
            step(5, Phase::Refine, 168.0, 0.05, 200.0),
            step(6, Phase::Refine, 154.0, 0.0, 50.0),
        ]);
        let k = knee(&steps).unwrap();
        assert_eq!((k.step, k.rate_hz, k.p99_us), (6, 154.0, 50_000.0));
        assert_eq!(k.failed_above_hz, Some(168.0));
        assert_eq!(k.bytes_per_s, 154.0 * 47.0);
        // Dropping before queueing: no step under 1 % loss reached 60 ms.
        let q = queueing(&steps).unwrap();
        assert!(!q.bufferbloat);
        assert_eq!(q.grade, Grade::A, "20 ms added");
        assert_eq!((q.worst_p99_us, q.worst_at_hz), (50_000.0, 154.0));
        assert_eq!((q.added_us, q.lost_at_hz), (20_000.0, Some(168.0)));
    }

    #[test]
    fn a_link_that_queues_without_loss_is_bufferbloat() {
        let steps = judged(vec![
            step(1, Phase::Ramp, 10.0, 0.0, 30.0),
            step(2, Phase::Ramp, 100.0, 0.0, 35.0),
            step(3, Phase::Ramp, 200.0, 0.0, 900.0),
            step(4, Phase::Ramp, 500.0, 0.4, 2000.0),
        ]);
        assert_eq!(knee(&steps).unwrap().rate_hz, 100.0);
        let q = queueing(&steps).unwrap();
        assert!(q.bufferbloat);
        assert_eq!(q.grade, Grade::F);
        assert_eq!((q.worst_at_hz, q.added_us), (200.0, 870_000.0));
    }

    #[test]
    fn the_grade_follows_the_bufferbloat_scale_and_bloat_starts_at_c() {
        let graded = [
            (0.0, "A+"),
            (4_999.0, "A+"),
            (5_000.0, "A"),
            (29_999.0, "A"),
            (30_000.0, "B"),
            (59_999.0, "B"),
            (60_000.0, "C"),
            (199_999.0, "C"),
            (200_000.0, "D"),
            (399_999.0, "D"),
            (400_000.0, "F"),
            (2e6, "F"),
        ];
        for (added, grade) in graded {
            let g = Grade::of(added);
            assert_eq!(g.as_str(), grade, "{added} µs");
            assert_eq!(serde_json::to_value(g).unwrap(), grade);
            assert_eq!(g.is_bufferbloat(), added >= 60_000.0, "{added} µs");
        }
        // A 30 ms queue on a 0.1 ms link: B, not bloat; 1 s of queue is.
        let q = |p99_ms| {
            let steps = judged(vec![
                step(1, Phase::Ramp, 10.0, 0.0, 0.1),
                step(2, Phase::Ramp, 50.0, 0.0, p99_ms),
                step(3, Phase::Ramp, 100.0, 0.3, 2000.0),
            ]);
            queueing(&steps).unwrap()
        };
        assert_eq!((q(45.0).grade, q(45.0).bufferbloat), (Grade::B, false));
        assert_eq!((q(1000.0).grade, q(1000.0).bufferbloat), (Grade::F, true));
    }

    #[test]
    fn nothing_passed_means_no_knee() {
        let steps = judged(vec![step(1, Phase::Ramp, 10.0, 0.5, 30.0)]);
        assert!(knee(&steps).is_none());
        // Every rate passed: the knee is the top, nothing failed above it.
        let steps = judged(vec![
            step(1, Phase::Ramp, 10.0, 0.0, 30.0),
            step(2, Phase::Ramp, 20.0, 0.0, 31.0),
        ]);
        assert_eq!(knee(&steps).unwrap().failed_above_hz, None);
    }

    #[test]
    fn the_load_effect_compares_one_rate_with_and_without_load() {
        let mut steps = vec![
            step(1, Phase::Baseline, 10.0, 0.0, 40.0),
            step(2, Phase::Ramp, 10.0, 0.0, 52.0),
            step(3, Phase::Ramp, 20.0, 0.0, 70.0),
        ];
        steps[1].load = true;
        steps[2].load = true;
        let e = load_effect(&steps).unwrap();
        assert_eq!((e.unloaded_p99_us, e.loaded_p99_us), (40_000.0, 52_000.0));
        assert_eq!(e.p99_rise_us, 12_000.0);
        assert!((e.p99_ratio - 1.3).abs() < 1e-12);
        // The baseline is not a sweep step: the reference is the first
        // loaded one.
        assert_eq!(reference_p99(&steps), Some(52_000.0));
        assert!(load_effect(&steps[1..]).is_none());
    }
}
