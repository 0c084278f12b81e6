//! Clock offset and drift of one TIMESYNC responder, in constant memory.
//!
//! Every exchange bounds the offset by causality alone: the responder read
//! its clock (`tc1`) at some moment between our send and our receive, so
//! at that moment `tc1 - t_recv <= offset <= tc1 - t_send` (on our clock).
//! The bounds of all exchanges, referred to the start of the run, are
//! intersected: the true offset lies inside unless a clock stepped or the
//! responder stamps outside its receive-reply window (then they do not
//! intersect, and the summary says so). Referring an exchange at time `t`
//! back to the start widens it by what the clocks' rates can change the
//! offset in `t`: by an assumed 200 ppm while drift is not measured, or
//! by the measured drift's limit once it is.
//!
//! The estimate inside the bounds is NTP-style, `tc1 - (t_send + t_recv)
//! / 2`, from the [`BEST`] lowest-RTT exchanges (queueing makes the two
//! legs unequal, so they are the trustworthy ones), moved to the start of
//! the run along the measured drift. Drift is the slope of a
//! least-squares line through the lowest-RTT exchange of each stretch of
//! the run ([`Minima`]), reported only once they span [`MIN_DRIFT_SPAN_S`]:
//! over a shorter run the RTT's noise is larger than any real drift. The
//! offsets of neighbouring exchanges err together (a core busy for a
//! while delays one leg of every exchange in that while), so an ordinary
//! least-squares error, which assumes independent errors, was 2-4 times
//! too small on one shared clock. Minima per stretch are much less
//! correlated; what correlation is left between neighbours widens the
//! error (by blocking), and so does the most the minima's own queueing
//! could tilt the line (their RTTs above the fastest); where neighbours
//! move almost together, no drift is reported at all.
//!
//! Pure: times are passed in (ns on our clock), no clock is read here.

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::Nanos;

/// Lowest-RTT samples kept for the offset estimate.
pub(crate) const BEST: usize = 8;
/// Samples up to twice the lowest RTT plus this much enter the drift fit:
/// on loopback, RTTs of a few hundred µs vary by more than 2x without any
/// meaningful queue.
const FIT_SLACK_NS: Nanos = 1_000_000;
/// Drift is reported once the fitted exchanges span this long.
pub(crate) const MIN_DRIFT_SPAN_S: f64 = 10.0;
/// Points the drift fit needs, and the most it keeps: when full, pairs
/// of neighbours merge and each point stands for twice the exchanges.
const MIN_DRIFT_POINTS: usize = 10;
const MAX_DRIFT_POINTS: usize = 64;
/// Neighbouring residuals this correlated or more: the offsets wander
/// more than they drift, and the slope means nothing.
const MAX_NEIGHBOUR_CORRELATION: f64 = 0.9;
/// Limits on how fast the offset may change (ppm), each with its own
/// running bounds: the smallest one that holds is used. Two crystals of
/// ±100 ppm differ by at most 200 ppm, the limit assumed until drift is
/// measured.
const DRIFT_LIMITS_PPM: [i128; 6] = [50, 200, 1_000, 10_000, 100_000, 1_000_000];
const ASSUMED_DRIFT_LIMIT: usize = 1;

#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    rtt: Nanos,
    /// Our time at the middle of the exchange, ns.
    mid: Nanos,
    /// Offset measured by this exchange, ns.
    offset: i128,
}

/// The lowest-RTT exchange of each stretch of `size` exchanges, oldest
/// first: the points the drift is fitted to.
#[derive(Debug, Clone)]
struct Minima {
    points: Vec<Sample>,
    size: u64,
    current: Option<Sample>,
    in_current: u64,
}

impl Default for Minima {
    fn default() -> Self {
        Minima {
            points: Vec::with_capacity(MAX_DRIFT_POINTS),
            size: 1,
            current: None,
            in_current: 0,
        }
    }
}

fn lower_rtt(a: Sample, b: Sample) -> Sample {
    if b.rtt < a.rtt {
        b
    } else {
        a
    }
}

impl Minima {
    fn push(&mut self, sample: Sample) {
        let best = self.current.map_or(sample, |c| lower_rtt(c, sample));
        self.in_current += 1;
        if self.in_current < self.size {
            self.current = Some(best);
            return;
        }
        self.points.push(best);
        self.current = None;
        self.in_current = 0;
        if self.points.len() == MAX_DRIFT_POINTS {
            self.points = self
                .points
                .chunks(2)
                .map(|pair| pair.iter().copied().reduce(lower_rtt).unwrap())
                .collect();
            self.size *= 2;
        }
    }

    /// Slope (ns of offset per ns of our time) and its standard error, ppm,
    /// with the span in s; `None` while the points cannot say.
    fn drift(&self, origin: i128) -> Option<Drift> {
        let n = self.points.len();
        if n < MIN_DRIFT_POINTS {
            return None;
        }
        let xy: Vec<(f64, f64)> = self
            .points
            .iter()
            .map(|p| (p.mid as f64 / 1e9, (p.offset - origin) as f64))
            .collect();
        let nf = n as f64;
        let mean_x = xy.iter().map(|p| p.0).sum::<f64>() / nf;
        let mean_y = xy.iter().map(|p| p.1).sum::<f64>() / nf;
        let s_xx: f64 = xy.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
        if s_xx <= 0.0 {
            return None;
        }
        let s_xy: f64 = xy.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
        let slope = s_xy / s_xx;
        let residuals: Vec<f64> = xy
            .iter()
            .map(|p| p.1 - mean_y - slope * (p.0 - mean_x))
            .collect();
        let ss: f64 = residuals.iter().map(|r| r * r).sum();
        let inflation = correlation_inflation(&residuals)?;
        // Queueing and scheduling only add delay, to either leg: a point
        // whose RTT is `e` above the fastest one's has its offset moved
        // by at most e/2 more than that one's. Those moves may trend over
        // the run (a core busy for its second half), which no spread
        // shows, so the error includes the most they can tilt the line,
        // read as a uniform error (/ √3).
        let floor = self.points.iter().map(|p| p.rtt).min().unwrap_or(0);
        let tilt: f64 = xy
            .iter()
            .zip(&self.points)
            .map(|(p, s)| (p.0 - mean_x).abs() * (s.rtt - floor) as f64 / 2.0)
            .sum::<f64>()
            / s_xx;
        let statistical = (ss / (nf - 2.0) / s_xx).sqrt() * inflation;
        // ns per s is ppm after / 1e3.
        let stderr = statistical.hypot(tilt / 3f64.sqrt());
        Some(Drift {
            slope: slope / 1e9,
            stderr_ppm: stderr / 1e3,
            span_s: xy[n - 1].0 - xy[0].0,
        })
    }
}

/// How much neighbouring residuals' correlation widens a slope's error,
/// by blocking (Flyvbjerg and Petersen): the means of blocks of 2, 4, 8
/// neighbours vary as independent errors' would only if there is no
/// correlation; the worst ratio is the widening. `None` when neighbours
/// move almost together (lag-1 correlation [`MAX_NEIGHBOUR_CORRELATION`]
/// or more): the offsets wander more than they drift.
fn correlation_inflation(residuals: &[f64]) -> Option<f64> {
    let n = residuals.len();
    let ss: f64 = residuals.iter().map(|r| r * r).sum();
    if ss <= 0.0 {
        return Some(1.0);
    }
    let lag1 = residuals.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / ss;
    if lag1 >= MAX_NEIGHBOUR_CORRELATION {
        return None;
    }
    let var = ss / n as f64;
    let mut worst: f64 = 1.0;
    let mut block = 2;
    // At least four blocks, or their spread says nothing.
    while n / block >= 4 {
        let means: Vec<f64> = residuals
            .chunks_exact(block)
            .map(|c| c.iter().sum::<f64>() / block as f64)
            .collect();
        let var_means = means.iter().map(|m| m * m).sum::<f64>() / means.len() as f64;
        worst = worst.max(block as f64 * var_means / var);
        block *= 2;
    }
    Some(worst.sqrt())
}

#[derive(Debug, Clone, Copy)]
struct Drift {
    slope: f64,
    stderr_ppm: f64,
    span_s: f64,
}

/// The figures a report shows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClockSummary {
    /// Their clock minus ours at the start of the run (our time 0), ns;
    /// inside the bounds when they intersect.
    #[serde(serialize_with = "ns")]
    pub(crate) offset_ns: i128,
    /// Half the width of the bounds, or half the lowest RTT without them.
    pub(crate) uncertainty_ns: u64,
    /// The causal bounds of the offset at the start of the run; `None`
    /// when the exchanges' bounds do not intersect.
    #[serde(flatten, serialize_with = "bounds")]
    pub(crate) bounds_ns: Option<(i128, i128)>,
    /// The limit on the clocks' relative rate the bounds assume, ppm.
    pub(crate) bounds_drift_limit_ppm: u32,
    /// Standard deviation of the samples about the drift line, ns.
    pub(crate) spread_ns: f64,
    /// Their clock's rate relative to ours, parts per million (positive:
    /// theirs runs fast), and its standard error; `None` until the
    /// exchanges span [`MIN_DRIFT_SPAN_S`].
    pub(crate) drift_ppm: Option<f64>,
    pub(crate) drift_stderr_ppm: Option<f64>,
    pub(crate) samples: u64,
}

/// i64 holds ±292 years of ns: enough for any two clocks, and what a
/// JSON reader takes whole.
fn clamped(v: i128) -> i64 {
    i64::try_from(v).unwrap_or(if v < 0 { i64::MIN } else { i64::MAX })
}

fn ns<S: Serializer>(v: &i128, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_i64(clamped(*v))
}

/// The bounds as two figures, `lower_ns` and `upper_ns`, each null
/// without them.
#[allow(clippy::ref_option)] // serde's `serialize_with` lends the field as it is
fn bounds<S: Serializer>(b: &Option<(i128, i128)>, s: S) -> Result<S::Ok, S::Error> {
    let mut map = s.serialize_map(Some(2))?;
    map.serialize_entry("lower_ns", &b.map(|(lower, _)| clamped(lower)))?;
    map.serialize_entry("upper_ns", &b.map(|(_, upper)| clamped(upper)))?;
    map.end()
}

/// The running intersection of every exchange's bounds, referred to time
/// 0 under one drift limit.
#[derive(Debug, Clone, Copy)]
struct Bounds {
    lower: i128,
    upper: i128,
}

impl Default for Bounds {
    fn default() -> Self {
        Bounds {
            lower: i128::MIN,
            upper: i128::MAX,
        }
    }
}

#[derive(Debug, Clone, Default)]
pub(crate) struct ClockOffset {
    best: Vec<Sample>,
    /// First sample's offset: the regression runs on offsets relative to it,
    /// so f64 keeps ns precision even for clocks counting from 1970.
    origin: Option<i128>,
    min_rtt: Option<Nanos>,
    /// Samples seen, and samples in the fit.
    seen: u64,
    n: u64,
    mean_x: f64,
    mean_y: f64,
    c_xx: f64,
    c_xy: f64,
    c_yy: f64,
    minima: Minima,
    bounds: [Bounds; DRIFT_LIMITS_PPM.len()],
}

/// `t * ppm / 1e6` rounded up: how far the offset may move in `t` ns.
fn drift_allowance(t: Nanos, ppm: i128) -> i128 {
    (i128::from(t) * ppm + 999_999) / 1_000_000
}

impl ClockOffset {
    /// Records one exchange: the request left at `sent_at` (our session
    /// time, ns; no later than the moment it was written), was answered
    /// with their clock `theirs`, and the reply arrived at `at`. `base` is
    /// what our clock read at time 0 (the value our timestamps count from),
    /// known to within `base_within` ns either way.
    pub(crate) fn record(
        &mut self,
        sent_at: Nanos,
        at: Nanos,
        theirs: i64,
        base: i128,
        base_within: i128,
    ) {
        let at = at.max(sent_at);
        let rtt = at - sent_at;
        let mid = sent_at + rtt / 2;
        let theirs = i128::from(theirs);
        let offset = theirs - base - i128::from(sent_at) - i128::from(rtt) / 2;
        let origin = *self.origin.get_or_insert(offset);
        self.seen += 1;
        // Causality: they read their clock between our send and receive.
        let (lower, upper) = (
            theirs - base - i128::from(at) - base_within,
            theirs - base - i128::from(sent_at) + base_within,
        );
        for (b, &ppm) in self.bounds.iter_mut().zip(&DRIFT_LIMITS_PPM) {
            let slack = drift_allowance(at, ppm);
            b.lower = b.lower.max(lower - slack);
            b.upper = b.upper.min(upper + slack);
        }
        let min_rtt = self.min_rtt.map_or(rtt, |m| m.min(rtt));
        self.min_rtt = Some(min_rtt);
        let sample = Sample { rtt, mid, offset };
        self.keep_best(sample);
        self.minima.push(sample);
        if rtt > min_rtt.saturating_mul(2) + FIT_SLACK_NS {
            return;
        }

        // Running co-moments (Welford), x in seconds, y in ns.
        let x = mid as f64 / 1e9;
        let y = (offset - origin) as f64;
        self.n += 1;
        let n = self.n as f64;
        let dx = x - self.mean_x;
        let dy = y - self.mean_y;
        self.mean_x += dx / n;
        self.mean_y += dy / n;
        self.c_xx += dx * (x - self.mean_x);
        self.c_xy += dx * (y - self.mean_y);
        self.c_yy += dy * (y - self.mean_y);
    }

    fn keep_best(&mut self, sample: Sample) {
        let rtt = sample.rtt;
        if self.best.len() < BEST {
            self.best.push(sample);
        } else if let Some(worst) = self.best.iter_mut().max_by_key(|s| s.rtt) {
            if rtt < worst.rtt {
                *worst = sample;
            }
        }
    }

    /// Slope of offset against our time, ns of offset per ns of our time.
    fn slope(&self) -> f64 {
        if self.n < 2 || self.c_xx <= 0.0 {
            0.0
        } else {
            self.c_xy / self.c_xx / 1e9
        }
    }

    pub(crate) fn summary(&self) -> Option<ClockSummary> {
        let min_rtt = self.best.iter().map(|s| s.rtt).min()?;
        let origin = self.origin.unwrap_or(0);
        let fitted = self.n >= 3 && self.c_xx > 0.0;
        let slope = self.slope();
        let residual_var = if fitted {
            (self.c_yy - slope * 1e9 * self.c_xy).max(0.0) / (self.n - 2) as f64
        } else {
            0.0
        };
        let drift = self
            .minima
            .drift(origin)
            .filter(|d| d.span_s >= MIN_DRIFT_SPAN_S);
        let measured = drift.is_some();
        let slope = drift.map_or(0.0, |d| d.slope);
        let stderr_ppm = drift.map_or(0.0, |d| d.stderr_ppm);
        let drift_ppm = drift.map(|d| d.slope * 1e6);
        // The bounds under the smallest drift limit that holds: assumed
        // until drift is measured, then the measurement's own.
        let needed = match drift_ppm {
            Some(d) => d.abs() + 3.0 * stderr_ppm,
            None => DRIFT_LIMITS_PPM[ASSUMED_DRIFT_LIMIT] as f64,
        };
        let limit = DRIFT_LIMITS_PPM
            .iter()
            .position(|&ppm| ppm as f64 >= needed)
            .unwrap_or(DRIFT_LIMITS_PPM.len() - 1)
            .max(if measured { 0 } else { ASSUMED_DRIFT_LIMIT });
        let b = self.bounds[limit];
        let bounds_ns = (b.lower <= b.upper).then_some((b.lower, b.upper));
        // Each of the best samples, moved back to time 0 along the drift
        // (none while it is not measured), then averaged.
        let used_slope = if measured { slope } else { 0.0 };
        let sum: f64 = self
            .best
            .iter()
            .map(|s| (s.offset - origin) as f64 - used_slope * s.mid as f64)
            .sum();
        let estimate = origin + (sum / self.best.len() as f64).round() as i128;
        let (offset_ns, uncertainty_ns) = match bounds_ns {
            Some((lower, upper)) => (
                estimate.clamp(lower, upper),
                u64::try_from((upper - lower + 1) / 2).unwrap_or(u64::MAX),
            ),
            None => (estimate, min_rtt / 2),
        };
        Some(ClockSummary {
            offset_ns,
            uncertainty_ns,
            bounds_ns,
            bounds_drift_limit_ppm: DRIFT_LIMITS_PPM[limit] as u32,
            spread_ns: residual_var.sqrt(),
            drift_ppm,
            drift_stderr_ppm: measured.then_some(stderr_ppm),
            samples: self.seen,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A responder whose clock is `offset + (1 + ppm) * t`, reading it when
    /// the request arrives after `up` ns and answering after `down` ns.
    fn exchange(c: &mut ClockOffset, t: Nanos, up: Nanos, down: Nanos, offset: i64, ppm: f64) {
        let arrival = t + up;
        let theirs = offset + arrival as i64 + (arrival as f64 * ppm * 1e-6).round() as i64;
        c.record(t, arrival + down, theirs, 0, 0);
    }

    fn inside(s: &ClockSummary, truth: i128) -> bool {
        s.bounds_ns
            .is_some_and(|(lo, hi)| lo <= truth && truth <= hi)
    }

    #[test]
    fn symmetric_exchanges_give_the_exact_offset() {
        let mut c = ClockOffset::default();
        for i in 0..10 {
            exchange(&mut c, i * 1_000_000, 500, 500, -7_000_000, 0.0);
        }
        let s = c.summary().unwrap();
        assert_eq!(s.offset_ns, -7_000_000);
        assert!(inside(&s, -7_000_000), "{s:?}");
        // The first exchange binds, widened by the 1 ns that 200 ppm can
        // drift in its 1 µs (rounded up).
        assert_eq!(s.bounds_ns, Some((-7_000_501, -6_999_499)));
        assert_eq!(s.uncertainty_ns, 501);
        assert_eq!(s.drift_ppm, None, "10 ms of exchanges tell no drift");
        assert_eq!(s.samples, 10);
    }

    #[test]
    fn asymmetric_legs_keep_the_truth_inside_the_bounds() {
        // The responder stamps late in each exchange (it reads its clock
        // after a wake-up): the NTP midpoint is biased, the bounds are not.
        let mut c = ClockOffset::default();
        for i in 0..50u64 {
            let up = 40_000 + (i * 7_919) % 30_000;
            exchange(&mut c, i * 20_000_000, up, 5_000, 0, 0.0);
        }
        let s = c.summary().unwrap();
        assert!(inside(&s, 0), "{s:?}");
        let (lo, hi) = s.bounds_ns.unwrap();
        assert!(lo <= s.offset_ns && s.offset_ns <= hi, "{s:?}");
    }

    #[test]
    fn queued_samples_are_left_out_of_the_offset() {
        let mut c = ClockOffset::default();
        // Ten clean exchanges, then twenty whose reply sat 5 ms in a queue:
        // each of those alone would be 2.5 ms off.
        for i in 0..30 {
            let down = if i < 10 { 100 } else { 5_000_000 };
            exchange(&mut c, i * 10_000_000, 100, down, 3_000_000_000, 0.0);
        }
        let s = c.summary().unwrap();
        assert_eq!(s.offset_ns, 3_000_000_000);
        assert!(inside(&s, 3_000_000_000), "{s:?}");
    }

    #[test]
    fn drift_is_fitted_and_the_offset_referred_to_time_zero() {
        let mut c = ClockOffset::default();
        // 40 ppm fast over 100 s, offset 1.5 s at our time 0.
        for i in 0..1_000u64 {
            exchange(
                &mut c,
                1_000 + i * 100_000_000,
                2_000,
                2_000,
                1_500_000_000,
                40.0,
            );
        }
        let s = c.summary().unwrap();
        assert!((s.drift_ppm.unwrap() - 40.0).abs() < 1e-3, "{s:?}");
        assert!(s.drift_stderr_ppm.unwrap() < 1e-3, "{s:?}");
        assert!((s.offset_ns - 1_500_000_000).abs() <= 2, "{s:?}");
        assert!(s.spread_ns < 1.0, "{s:?}");
        assert!(inside(&s, 1_500_000_000), "{s:?}");
        assert_eq!(s.bounds_drift_limit_ppm, 50);
    }

    #[test]
    fn a_stepped_clock_makes_the_bounds_disjoint() {
        let mut c = ClockOffset::default();
        for i in 0..20u64 {
            let offset = if i < 10 { 0 } else { 5_000_000 };
            exchange(&mut c, i * 10_000_000, 1_000, 1_000, offset, 0.0);
        }
        let s = c.summary().unwrap();
        assert_eq!(s.bounds_ns, None, "{s:?}");
    }

    #[test]
    fn clocks_counting_from_1970_keep_ns_precision() {
        let mut c = ClockOffset::default();
        let base: i128 = 1_700_000_000_000_000_000;
        for i in 0..100u64 {
            let t = i * 20_000_000;
            // Their clock counts from their boot, 42 s before our time 0.
            c.record(t, t + 1_000, (42_000_000_000 + t + 500) as i64, base, 0);
        }
        let s = c.summary().unwrap();
        assert_eq!(s.offset_ns, 42_000_000_000 - base);
        assert!(inside(&s, 42_000_000_000 - base), "{s:?}");
        assert_eq!(s.drift_ppm, None);
    }

    #[test]
    fn a_base_read_late_is_still_inside_bounds_widened_by_its_error() {
        // Our wall clock at time 0 was read 5 µs late (a preempted
        // thread): every exchange then seems 5 µs earlier to them.
        let late = 5_000;
        let record = |within: i128| {
            let mut c = ClockOffset::default();
            for i in 0..50u64 {
                let t = i * 20_000_000;
                c.record(t, t + 2_000, (t + 1_000) as i64, late, within);
            }
            c.summary().unwrap()
        };
        assert!(!inside(&record(0), 0), "{:?}", record(0));
        let widened = record(late);
        assert!(inside(&widened, 0), "{widened:?}");
    }

    /// 12 s at 50 Hz on one shared clock (true drift 0) with a busy
    /// neighbour: it holds a core in spells of about 3 s, and during
    /// a spell every request waits up to 400 µs more before the responder
    /// reads its clock, so neighbouring offsets err together. Returns the
    /// summary and the z of a plain least-squares slope through every
    /// exchange, for comparison.
    fn busy_shared_clock(seed: u64) -> (ClockSummary, f64) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::SmallRng::seed_from_u64(seed);
        let mut c = ClockOffset::default();
        let mut busy = false;
        let mut offsets = Vec::new();
        for i in 0..600u64 {
            if rng.gen_bool(0.007) {
                busy = !busy;
            }
            let wait = if busy { rng.gen_range(0..400_000) } else { 0 };
            let up = 40_000 + wait + rng.gen_range(0..10_000);
            let down = 40_000 + rng.gen_range(0..10_000);
            let t = i * 20_000_000;
            exchange(&mut c, t, up, down, 0, 0.0);
            let mid = (t + u64::midpoint(up, down)) as f64 / 1e9;
            offsets.push((mid, (up as f64 - down as f64) / 2.0));
        }
        let ols_z = plain_slope_z(&offsets);
        (c.summary().unwrap(), ols_z)
    }

    /// A least-squares slope over its textbook standard error.
    fn plain_slope_z(points: &[(f64, f64)]) -> f64 {
        let count = points.len() as f64;
        let mean_x = points.iter().map(|p| p.0).sum::<f64>() / count;
        let mean_y = points.iter().map(|p| p.1).sum::<f64>() / count;
        let s_xx: f64 = points.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
        let s_xy: f64 = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
        let slope = s_xy / s_xx;
        let residual: f64 = points
            .iter()
            .map(|p| (p.1 - mean_y - slope * (p.0 - mean_x)).powi(2))
            .sum();
        slope / (residual / (count - 2.0) / s_xx).sqrt()
    }

    #[test]
    fn drift_error_bars_hold_a_true_drift_of_zero_beside_a_busy_core() {
        // Two standard errors should miss about 1 run in 20. A plain
        // least-squares error misses far more often on these runs; the
        // fit through minima, widened by its neighbours' correlation,
        // must stay near the nominal rate (or report no drift).
        let runs = 200;
        let (mut missed, mut ols_missed, mut reported, mut widest) = (0, 0, 0, 0.0_f64);
        for seed in 0..runs {
            let (s, ols_z) = busy_shared_clock(seed);
            if ols_z.abs() > 2.0 {
                ols_missed += 1;
            }
            if let (Some(d), Some(e)) = (s.drift_ppm, s.drift_stderr_ppm) {
                reported += 1;
                widest = widest.max(e);
                if d.abs() > 2.0 * e {
                    missed += 1;
                }
            }
        }
        assert!(
            ols_missed > runs / 5,
            "the plain fit missed {ols_missed} of {runs}"
        );
        assert!(
            reported > runs * 9 / 10,
            "drift reported in {reported} of {runs}"
        );
        assert!(missed * 10 <= reported, "missed {missed} of {reported}");
        // And the bars still say something: 12 s of loopback exchanges
        // tell drift to a few ppm.
        assert!(widest < 3.0, "widest error {widest} ppm");
    }

    #[test]
    fn memory_stays_bounded() {
        let mut c = ClockOffset::default();
        for i in 0..10_000u64 {
            exchange(&mut c, i * 1_000, 10 + i % 97, 10, 0, 0.0);
        }
        assert_eq!(c.best.len(), BEST);
        assert!(c.best.iter().all(|s| s.rtt == 20));
        assert!(c.minima.points.len() < MAX_DRIFT_POINTS);
        assert!(ClockOffset::default().summary().is_none());
    }
}
