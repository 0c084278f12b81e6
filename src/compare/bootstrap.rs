//! The median RTT shift between two runs with a bootstrap interval, from
//! what a summary keeps of its RTTs: a histogram of a few buckets.
//!
//! Each run's RTTs are modelled as its buckets' counts, each RTT drawn
//! uniformly within its bucket (not at the bucket's midpoint, which would
//! put every resample's median on one of a few values). A resample of a
//! run is `n` draws from that model and its median their middle order
//! statistic. Drawing the `n` values is not needed: the `k`-th smallest of
//! `n` draws from a distribution `F` is `F⁻¹(U₍ₖ₎)`, with `U₍ₖ₎` the `k`-th
//! smallest of `n` uniforms, which is Beta(k, n - k + 1) (David and
//! Nagaraja, "Order Statistics", 3rd ed., 2003, §2.1). So each resample
//! costs a Beta draw (two Gamma draws, Marsaglia and Tsang's method,
//! ACM TOMS 26 (2000) 363-372) whatever the run's length, and gives
//! exactly the median a brute-force resample would.
//!
//! The random numbers are SplitMix64's (Steele, Lea and Flood, OOPSLA
//! 2014), seeded with a constant: the same files always give the same
//! interval, whatever the `rand` crate's version. The draws go through
//! `ln`, `cos` and `powf`, which each platform's math library may round
//! differently in the last bit: another platform's interval can differ in
//! its last binary digits.

/// Resamples of each run.
pub(crate) const RESAMPLES: usize = 2000;
/// The bootstrap's seed.
pub(crate) const SEED: u64 = 1;

/// SplitMix64: small, fast and fully specified.
#[derive(Debug, Clone)]
pub(crate) struct SplitMix64(u64);

impl SplitMix64 {
    pub(crate) fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform on (0, 1), never 0 or 1 (logarithms of it stay finite).
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal, by Box and Muller's transform.
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    /// Gamma(shape, 1) for `shape >= 1`, by Marsaglia and Tsang.
    fn gamma(&mut self, shape: f64) -> f64 {
        let base = shape - 1.0 / 3.0;
        let scale = 1.0 / (9.0 * base).sqrt();
        loop {
            let normal = self.normal();
            let cube = (1.0 + scale * normal).powi(3);
            if cube <= 0.0 {
                continue;
            }
            let accept = self.uniform().ln();
            if accept < 0.5 * normal * normal + base - base * cube + base * cube.ln() {
                return base * cube;
            }
        }
    }

    /// Beta(a, b) for `a, b >= 1`.
    fn beta(&mut self, a: f64, b: f64) -> f64 {
        let x = self.gamma(a);
        let y = self.gamma(b);
        x / (x + y)
    }
}

/// One bucket of a run's RTT histogram, µs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bucket {
    pub(crate) low: f64,
    pub(crate) high: f64,
    pub(crate) count: u64,
}

/// A run's RTTs as the histogram models them: uniform within each bucket.
#[derive(Debug, Clone)]
pub(crate) struct Model {
    buckets: Vec<Bucket>,
    n: u64,
}

impl Model {
    /// `None` without a sample (no bucket counts anything).
    pub(crate) fn new(buckets: &[Bucket]) -> Option<Self> {
        let buckets: Vec<Bucket> = buckets
            .iter()
            .copied()
            .filter(|b| b.count > 0 && b.high >= b.low && b.low.is_finite() && b.high.is_finite())
            .collect();
        let n = buckets.iter().fold(0u64, |n, b| n.saturating_add(b.count));
        (n > 0).then_some(Model { buckets, n })
    }

    /// The value below which a share `u` of the model lies.
    fn quantile(&self, u: f64) -> f64 {
        let target = u.clamp(0.0, 1.0) * self.n as f64;
        let mut below = 0.0;
        for b in &self.buckets {
            let count = b.count as f64;
            if target <= below + count {
                return b.low + (target - below) / count * (b.high - b.low);
            }
            below += count;
        }
        self.buckets.last().map_or(0.0, |b| b.high)
    }

    /// The model's own median.
    pub(crate) fn median(&self) -> f64 {
        self.quantile(0.5)
    }

    /// The median of `n` draws from the model: the middle order statistic
    /// (the mean of the two middle ones for an even `n`).
    fn resampled_median(&self, rng: &mut SplitMix64) -> f64 {
        let n = self.n as f64;
        let k = self.n.div_ceil(2) as f64;
        let lower = rng.beta(k, n - k + 1.0);
        if self.n % 2 == 1 {
            return self.quantile(lower);
        }
        // The next order statistic: the least of the n - k uniforms above
        // the k-th, each uniform on (lower, 1).
        let least = 1.0 - rng.uniform().powf(1.0 / (n - k));
        let upper = lower + (1.0 - lower) * least;
        0.5 * (self.quantile(lower) + self.quantile(upper))
    }
}

/// The median shift `b - a` and its 95 % interval, µs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Shift {
    pub(crate) estimate: f64,
    pub(crate) low: f64,
    pub(crate) high: f64,
}

/// `b_p50 - a_p50` (the summaries' own medians, exact to the HDR
/// histogram's three digits) with the percentile bootstrap's 95 %
/// interval of the histograms' medians. The bucket model's median can sit
/// a little off the exact one, so the interval is placed around the exact
/// shift: moved by the model's own shift's distance from it (the
/// bootstrap gives the estimate's spread, the summaries its centre).
pub(crate) fn median_shift(a: &Model, b: &Model, a_p50: f64, b_p50: f64) -> Shift {
    let mut rng = SplitMix64::new(SEED);
    let mut draws: Vec<f64> = (0..RESAMPLES)
        .map(|_| {
            let ma = a.resampled_median(&mut rng);
            b.resampled_median(&mut rng) - ma
        })
        .collect();
    draws.sort_by(f64::total_cmp);
    let at = |q: f64| draws[((draws.len() - 1) as f64 * q).round() as usize];
    let estimate = b_p50 - a_p50;
    let offset = estimate - (b.median() - a.median());
    Shift {
        estimate,
        low: at(0.025) + offset,
        high: at(0.975) + offset,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean_var(xs: &[f64]) -> (f64, f64) {
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var)
    }

    #[test]
    fn gamma_draws_have_their_mean_and_variance() {
        let mut rng = SplitMix64::new(7);
        for shape in [1.0, 2.5, 50.0] {
            let xs: Vec<f64> = (0..40_000).map(|_| rng.gamma(shape)).collect();
            let (mean, var) = mean_var(&xs);
            // Gamma(k, 1): mean k, variance k; 40 000 draws put the mean
            // within 4 standard errors (√(k/40 000)) and the variance
            // within 5 %.
            assert!(
                (mean - shape).abs() < 4.0 * (shape / 40_000.0).sqrt(),
                "{shape}: {mean}"
            );
            assert!((var / shape - 1.0).abs() < 0.05, "{shape}: {var}");
        }
    }

    /// One bucket [0, 1): the median of n uniforms. n = 1: uniform
    /// (variance 1/12); n = 2: the mean of two (1/24); n = 3: Beta(2, 2)
    /// (1/20); n = 4: the mean of the 2nd and 3rd of four, variance
    /// (Var U₂ + Var U₃ + 2 Cov)/4 = (2·6/150 + 2·4/150)/4 = 1/30.
    #[test]
    fn the_median_of_a_few_uniform_draws_has_its_known_spread() {
        for (n, want) in [(1, 1.0 / 12.0), (2, 1.0 / 24.0), (3, 0.05), (4, 1.0 / 30.0)] {
            let model = Model::new(&[Bucket {
                low: 0.0,
                high: 1.0,
                count: n,
            }])
            .unwrap();
            let mut rng = SplitMix64::new(n);
            let xs: Vec<f64> = (0..50_000)
                .map(|_| model.resampled_median(&mut rng))
                .collect();
            let (mean, var) = mean_var(&xs);
            assert!((mean - 0.5).abs() < 0.005, "n = {n}: mean {mean}");
            assert!(
                (var / want - 1.0).abs() < 0.04,
                "n = {n}: variance {var}, want {want}"
            );
        }
    }

    /// The order-statistic draw against brute force: n draws from the
    /// buckets, sorted, the middle taken.
    #[test]
    fn resampled_medians_match_brute_force_resampling() {
        let buckets = [
            Bucket {
                low: 10.0,
                high: 20.0,
                count: 31,
            },
            Bucket {
                low: 20.0,
                high: 30.0,
                count: 50,
            },
            Bucket {
                low: 30.0,
                high: 60.0,
                count: 20,
            },
        ];
        let model = Model::new(&buckets).unwrap();
        let mut rng = SplitMix64::new(3);
        let mut fast: Vec<f64> = (0..8000)
            .map(|_| model.resampled_median(&mut rng))
            .collect();
        let mut brute: Vec<f64> = (0..8000)
            .map(|_| {
                let mut xs: Vec<f64> = (0..101)
                    .map(|_| {
                        let mut pick = rng.uniform() * 101.0;
                        let b = buckets
                            .iter()
                            .find(|b| {
                                pick -= b.count as f64;
                                pick < 0.0
                            })
                            .unwrap_or(&buckets[2]);
                        b.low + rng.uniform() * (b.high - b.low)
                    })
                    .collect();
                xs.sort_by(f64::total_cmp);
                xs[50]
            })
            .collect();
        fast.sort_by(f64::total_cmp);
        brute.sort_by(f64::total_cmp);
        for q in [0.025, 0.5, 0.975] {
            let i = (7999.0 * q) as usize;
            assert!(
                (fast[i] - brute[i]).abs() < 0.25,
                "q {q}: {} vs {}",
                fast[i],
                brute[i]
            );
        }
    }

    #[test]
    fn the_model_median_interpolates_within_its_bucket() {
        let model = Model::new(&[
            Bucket {
                low: 0.0,
                high: 10.0,
                count: 25,
            },
            Bucket {
                low: 10.0,
                high: 20.0,
                count: 0,
            },
            Bucket {
                low: 20.0,
                high: 30.0,
                count: 50,
            },
        ])
        .unwrap();
        // 37.5 of 75 below: 25 in the first bucket, 12.5 of 50 into the third.
        assert!((model.median() - 22.5).abs() < 1e-12);
        assert!(Model::new(&[]).is_none());
    }

    /// Runs 40 ms apart (20-24 ms and 60-64 ms, 500 each): the shift is
    /// the medians' difference and its interval a fraction of a bucket.
    #[test]
    fn a_40_ms_shift_is_found_with_a_narrow_interval_and_the_same_each_time() {
        let run = |base: f64| {
            let counts = [27, 41, 80, 110, 102, 78, 35, 27];
            let buckets: Vec<Bucket> = counts
                .iter()
                .enumerate()
                .map(|(i, &count)| Bucket {
                    low: base + 500.0 * i as f64,
                    high: base + 500.0 * (i + 1) as f64,
                    count,
                })
                .collect();
            Model::new(&buckets).unwrap()
        };
        let (a, b) = (run(20_000.0), run(60_000.0));
        let shift = median_shift(&a, &b, a.median(), b.median());
        assert!((shift.estimate - 40_000.0).abs() < 1e-9);
        assert!(shift.low < 40_000.0 && shift.high > 40_000.0, "{shift:?}");
        assert!(shift.high - shift.low < 500.0, "{shift:?}");
        assert_eq!(shift, median_shift(&a, &b, a.median(), b.median()));
        // The exact medians place the interval: 100 µs more, 100 µs later.
        let moved = median_shift(&a, &b, a.median(), b.median() + 100.0);
        assert!((moved.low - shift.low - 100.0).abs() < 1e-9);
    }
}
