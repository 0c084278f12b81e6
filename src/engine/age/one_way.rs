//! The age above baseline of one sender clock's stamps ([`OneWay`]):
//! the envelope, the clock's resets and bad stamps, and the distribution.
//!
//! Each point is recorded in the distribution once [`LOOKAHEAD`] later
//! points have refined the envelope (the rest when the summary is read,
//! with the final envelope): an online approximation of the final
//! answer. Its error is measured and reported: at one recorded point per
//! bucket the envelope used is compared with the final one
//! (`baseline_error_ms`); it comes from drift fitted before the run was
//! long, and is a few ms at most once the envelope spans a minute.

use std::collections::VecDeque;

use hdrhistogram::Histogram;

use super::super::Nanos;
use super::envelope::{Envelope, Line, Point, MAX_BUCKETS, MIN_DRIFT_SPAN_NS};

/// Points held back so the envelope they are measured against has seen
/// what followed them: 5 s of a 50 Hz stream.
pub(crate) const LOOKAHEAD: usize = 256;
/// Ages above this are recorded as this (µs, one hour), bounding the
/// histogram's memory.
const HIST_MAX_US: u64 = 3_600_000_000;
/// A stamp this far behind the clock's newest is not a frame overtaken
/// by another, but a clock that restarted (a reboot) or a bad stamp.
const BACKWARD_NS: i128 = 1_000_000_000;
/// Age outside [-AHEAD, BEYOND] of the current baseline: the stamp is
/// from another clock epoch (a step, a reboot, a bad clock). Queues of
/// 10 s happen on LTE links; ten minutes do not.
const AHEAD_NS: f64 = 10e9;
const BEYOND_NS: f64 = 600e9;
/// Stamps that agree with each other but not the baseline, needed before
/// the baseline restarts on them: fewer are bad stamps, refused.
const CONFIRM: usize = 3;

/// Stamps that do not fit the current baseline, held until they confirm
/// a new one or are refused.
#[derive(Debug, Clone, Default)]
struct Candidate {
    points: Vec<(Nanos, i128, i128)>,
    /// Fitting points seen since the first of them.
    against: usize,
}

/// One sender clock's ages: see the module's documentation.
#[derive(Debug, Clone)]
pub(crate) struct OneWay {
    envelope: Option<Envelope>,
    ring: VecDeque<Point>,
    hist: Histogram<u32>,
    max_ns: f64,
    last_stamp: Option<i128>,
    candidate: Candidate,
    /// Envelopes started after the first (reboots, steps).
    restarts: u32,
    rejected: u64,
    samples: u64,
    probes: Probes,
    /// The largest error of earlier envelopes' recorded ages, ns.
    closed_error_ns: f64,
    now: Option<(Nanos, f64)>,
}

/// One recorded point per time slot with the floor used for it, to
/// compare with the final floor: slots double in width as buckets do.
#[derive(Debug, Clone, Default)]
struct Probes {
    width: i64,
    slots: Vec<(i64, i64, f64)>,
}

impl Probes {
    fn note(&mut self, t: i64, used: f64) {
        if self.width == 0 {
            self.width = 250_000_000;
        }
        let slot = t / self.width;
        if self.slots.last().is_some_and(|s| s.0 == slot) {
            return;
        }
        self.slots.push((slot, t, used));
        while self.slots.len() > MAX_BUCKETS {
            self.width *= 2;
            self.slots.dedup_by_key(|s| {
                s.0 /= 2;
                s.0
            });
        }
    }

    fn error_ns(&self, line: Line) -> f64 {
        self.slots
            .iter()
            .map(|&(_, t, used)| (line.at(t) - used).abs())
            .fold(0.0, f64::max)
    }
}

impl Default for OneWay {
    fn default() -> Self {
        OneWay {
            envelope: None,
            ring: VecDeque::with_capacity(LOOKAHEAD),
            hist: Histogram::new(3).expect("3 significant digits is a valid histogram"),
            max_ns: 0.0,
            last_stamp: None,
            candidate: Candidate::default(),
            restarts: 0,
            rejected: 0,
            samples: 0,
            probes: Probes::default(),
            closed_error_ns: 0.0,
            now: None,
        }
    }
}

/// The figures of one clock's ages above its baseline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OneWayFigures {
    pub(crate) samples: u64,
    pub(crate) p50_ns: f64,
    pub(crate) p90_ns: f64,
    pub(crate) p99_ns: f64,
    pub(crate) max_ns: f64,
    /// `None` until the envelope spans long enough to fit drift.
    pub(crate) drift_ppm: Option<f64>,
    pub(crate) restarts: u32,
    pub(crate) rejected: u64,
    pub(crate) baseline_error_ns: f64,
    pub(crate) stored_points: usize,
}

impl OneWay {
    /// One stamp: read at `stamp_ns` on the sender's clock (unwrapped),
    /// received at `at` on ours.
    pub(crate) fn record(&mut self, at: Nanos, stamp_ns: i128) {
        self.samples += 1;
        let d = i128::from(at) - stamp_ns;
        let fits = match (&mut self.envelope, self.last_stamp) {
            (Some(env), Some(last)) => {
                let p = env.relative(at, d);
                let age = p.d as f64 - env.line().at(p.t);
                stamp_ns >= last - BACKWARD_NS && (-AHEAD_NS..=BEYOND_NS).contains(&age)
            }
            _ => {
                self.envelope = Some(Envelope::new(at, d));
                true
            }
        };
        if fits {
            self.candidate.against += usize::from(!self.candidate.points.is_empty());
            if self.candidate.against >= CONFIRM {
                self.rejected += self.candidate.points.len() as u64;
                self.candidate = Candidate::default();
            }
            self.accept(at, d, stamp_ns);
        } else {
            self.doubt(at, d, stamp_ns);
        }
    }

    fn accept(&mut self, at: Nanos, d: i128, stamp_ns: i128) {
        let Some(env) = self.envelope.as_mut() else {
            return;
        };
        let p = env.relative(at, d);
        env.push(p);
        self.last_stamp = Some(self.last_stamp.map_or(stamp_ns, |l| l.max(stamp_ns)));
        let line = env.line();
        self.now = Some((at, (p.d as f64 - line.at(p.t)).max(0.0)));
        if self.ring.len() == LOOKAHEAD {
            if let Some(old) = self.ring.pop_front() {
                self.probes.note(old.t, line.at(old.t));
                record(&mut self.hist, &mut self.max_ns, old, line);
            }
        }
        self.ring.push_back(p);
    }

    /// A stamp that does not fit the baseline: held with those like it;
    /// enough alike restart the baseline on them.
    fn doubt(&mut self, at: Nanos, d: i128, stamp_ns: i128) {
        let alike = self.candidate.points.last().is_some_and(|&(_, cd, cs)| {
            stamp_ns >= cs - BACKWARD_NS && ((d - cd) as f64).abs() <= AHEAD_NS
        });
        if !alike {
            self.rejected += self.candidate.points.len() as u64;
            self.candidate = Candidate::default();
        }
        self.candidate.points.push((at, d, stamp_ns));
        if self.candidate.points.len() >= CONFIRM {
            let points = std::mem::take(&mut self.candidate).points;
            self.restart();
            for (at, d, stamp_ns) in points {
                if self.envelope.is_none() {
                    self.envelope = Some(Envelope::new(at, d));
                }
                self.accept(at, d, stamp_ns);
            }
        }
    }

    /// Closes the current envelope (its held points recorded against its
    /// final floor) and starts afresh.
    fn restart(&mut self) {
        if let Some(mut env) = self.envelope.take() {
            let line = env.line();
            self.closed_error_ns = self.closed_error_ns.max(self.probes.error_ns(line));
            for p in self.ring.drain(..) {
                record(&mut self.hist, &mut self.max_ns, p, line);
            }
            self.restarts += 1;
        }
        self.probes = Probes::default();
        self.last_stamp = None;
    }

    /// Stamps taken, fitting or not.
    pub(crate) fn samples(&self) -> u64 {
        self.samples
    }

    /// The newest point's age above the floor known when it arrived, ns,
    /// and when it arrived.
    pub(crate) fn now(&self) -> Option<(Nanos, f64)> {
        self.now
    }

    /// The current baseline's first point's time, and the floor's raw
    /// delay (receive − stamp, ns) then.
    pub(crate) fn floor_at_start(&self) -> Option<(Nanos, i128)> {
        self.envelope.as_ref().map(Envelope::floor_at_start)
    }

    /// The figures, the held points measured against the final floor.
    pub(crate) fn figures(&self) -> Option<OneWayFigures> {
        let env = self.envelope.as_ref()?;
        let line = env.current_line();
        let mut hist = self.hist.clone();
        let mut max_ns = self.max_ns;
        for &p in &self.ring {
            record(&mut hist, &mut max_ns, p, line);
        }
        let q = |q: f64| (hist.value_at_quantile(q) as f64 * 1e3).min(max_ns);
        let span = self.ring.back().map_or(0, |p| p.t);
        Some(OneWayFigures {
            samples: self.samples,
            p50_ns: q(0.5),
            p90_ns: q(0.9),
            p99_ns: q(0.99),
            max_ns,
            drift_ppm: (span >= MIN_DRIFT_SPAN_NS).then(|| env.drift_ppm()),
            restarts: self.restarts,
            rejected: self.rejected + self.candidate.points.len() as u64,
            baseline_error_ns: self.closed_error_ns.max(self.probes.error_ns(line)),
            stored_points: env.stored_points(),
        })
    }
}

fn record(hist: &mut Histogram<u32>, max_ns: &mut f64, p: Point, line: Line) {
    let age = (p.d as f64 - line.at(p.t)).max(0.0);
    *max_ns = max_ns.max(age);
    let us = ((age / 1e3).round() as u64).min(HIST_MAX_US);
    // Cannot fail: the value is within the auto-resizing histogram's range.
    let _ = hist.record(us);
}
