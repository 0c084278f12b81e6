//! Clock offset and drift of one TIMESYNC responder, in constant memory.
//!
//! Each exchange gives an NTP-style sample: the responder read its clock
//! (`tc1`) somewhere between our send and our receive, so
//! `offset = tc1 - (t_send + t_recv) / 2` is right within ± RTT/2. Queueing
//! makes the two legs unequal, so the samples with the lowest RTT are the
//! trustworthy ones: the estimate is taken from the [`BEST`] lowest-RTT
//! samples. Drift is the slope of a least-squares line through the
//! offsets against our time, kept as running co-moments; samples whose RTT
//! is over twice the lowest seen so far are left out of the fit, since a
//! queue on one leg biases them by up to half their extra RTT.
//!
//! Pure: times are passed in (ns on our clock), no clock is read here.

use serde::Serialize;

use super::Nanos;

/// Lowest-RTT samples kept for the offset estimate.
pub const BEST: usize = 8;
/// Samples up to twice the lowest RTT plus this much enter the drift fit:
/// on loopback, RTTs of a few hundred µs vary by more than 2x without any
/// meaningful queue.
const FIT_SLACK_NS: Nanos = 1_000_000;

#[derive(Debug, Clone, Copy, PartialEq)]
struct Sample {
    rtt: Nanos,
    /// Our time at the middle of the exchange, ns.
    mid: Nanos,
    /// Offset measured by this exchange, ns.
    offset: i128,
}

/// The figures a report shows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClockSummary {
    /// Their clock minus ours, in ns, referred to the start of the run
    /// (our time 0) using the fitted drift.
    pub offset_ns: i128,
    /// The estimate's bound: half the lowest RTT seen.
    pub uncertainty_ns: u64,
    /// Standard deviation of the samples about the drift line, ns.
    pub spread_ns: f64,
    /// Their clock's rate relative to ours, parts per million (positive:
    /// theirs runs fast), and its standard error. None until three samples
    /// at different times: two points always fit a line exactly.
    pub drift_ppm: Option<f64>,
    pub drift_stderr_ppm: Option<f64>,
    pub samples: u64,
}

#[derive(Debug, Clone, Default)]
pub struct ClockOffset {
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
}

impl ClockOffset {
    /// Records one exchange: sent at `sent_at`, answered with their clock
    /// `theirs`, received at `at`. `base` is what our clock read at time 0
    /// (the value our request timestamps count from).
    pub fn record(&mut self, sent_at: Nanos, at: Nanos, theirs: i64, base: i128) {
        let rtt = at.saturating_sub(sent_at);
        let mid = sent_at + rtt / 2;
        let offset = i128::from(theirs) - base - i128::from(sent_at) - i128::from(rtt) / 2;
        let origin = *self.origin.get_or_insert(offset);
        self.seen += 1;
        let min_rtt = self.min_rtt.map_or(rtt, |m| m.min(rtt));
        self.min_rtt = Some(min_rtt);
        self.keep_best(Sample { rtt, mid, offset });
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

    pub fn samples(&self) -> u64 {
        self.seen
    }

    /// Slope of offset against our time, ns of offset per ns of our time.
    fn slope(&self) -> f64 {
        if self.n < 2 || self.c_xx <= 0.0 {
            0.0
        } else {
            self.c_xy / self.c_xx / 1e9
        }
    }

    pub fn summary(&self) -> Option<ClockSummary> {
        let min_rtt = self.best.iter().map(|s| s.rtt).min()?;
        let slope = self.slope();
        // Each of the best samples, moved back to time 0 along the drift
        // line, then averaged.
        let sum: f64 = self
            .best
            .iter()
            .map(|s| (s.offset - self.origin.unwrap_or(0)) as f64 - slope * s.mid as f64)
            .sum();
        let offset_ns = self.origin.unwrap_or(0) + (sum / self.best.len() as f64).round() as i128;
        let fitted = self.n >= 3 && self.c_xx > 0.0;
        let residual_var = if fitted {
            (self.c_yy - slope * 1e9 * self.c_xy).max(0.0) / (self.n - 2) as f64
        } else {
            0.0
        };
        let spread_ns = residual_var.sqrt();
        // Standard error of the slope, in ns per s, then ppm.
        let drift_stderr_ppm = fitted.then(|| (residual_var / self.c_xx).sqrt() / 1e3);
        Some(ClockSummary {
            offset_ns,
            uncertainty_ns: min_rtt / 2,
            spread_ns,
            drift_ppm: fitted.then_some(slope * 1e6),
            drift_stderr_ppm,
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
        c.record(t, arrival + down, theirs, 0);
    }

    #[test]
    fn symmetric_exchanges_give_the_exact_offset() {
        let mut c = ClockOffset::default();
        for i in 0..10 {
            exchange(&mut c, i * 1_000_000, 500, 500, -7_000_000, 0.0);
        }
        let s = c.summary().unwrap();
        assert_eq!(s.offset_ns, -7_000_000);
        assert_eq!(s.uncertainty_ns, 500);
        assert_eq!(s.drift_ppm, Some(0.0));
        assert_eq!(s.spread_ns, 0.0);
        assert_eq!(s.samples, 10);
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
        assert_eq!(s.uncertainty_ns, 100);
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
    }

    #[test]
    fn clocks_counting_from_1970_keep_ns_precision() {
        let mut c = ClockOffset::default();
        let base: i128 = 1_700_000_000_000_000_000;
        for i in 0..100u64 {
            let t = i * 20_000_000;
            // Their clock counts from their boot, 42 s before our time 0.
            c.record(t, t + 1_000, (42_000_000_000 + t + 500) as i64, base);
        }
        let s = c.summary().unwrap();
        assert_eq!(s.offset_ns, 42_000_000_000 - base);
        assert_eq!(s.drift_ppm, Some(0.0));
    }

    #[test]
    fn memory_stays_bounded() {
        let mut c = ClockOffset::default();
        for i in 0..10_000u64 {
            exchange(&mut c, i * 1_000, 10 + i % 97, 10, 0, 0.0);
        }
        assert_eq!(c.best.len(), BEST);
        assert!(c.best.iter().all(|s| s.rtt == 20));
        assert!(ClockOffset::default().summary().is_none());
        // Two samples fit any line: no drift claimed.
        let mut two = ClockOffset::default();
        exchange(&mut two, 0, 10, 10, 0, 0.0);
        exchange(&mut two, 1_000, 10, 30, 0, 0.0);
        assert_eq!(two.summary().unwrap().drift_ppm, None);
    }
}
