//! Confidence intervals for a loss rate and for the difference of two:
//! Wilson's score interval for each run, combined by Newcombe's hybrid
//! score method.
//!
//! - E. B. Wilson, "Probable inference, the law of succession, and
//!   statistical inference", JASA 22 (1927) 209-212.
//! - R. G. Newcombe, "Interval estimation for the difference between
//!   independent proportions: comparison of eleven methods", Statistics
//!   in Medicine 17 (1998) 873-890: method 10. Unlike Wald's interval it
//!   stays within [-1, 1], keeps its coverage near 95 % for the small
//!   loss rates links have, and does not collapse to a point when a run
//!   lost nothing.

/// The normal quantile of a two-sided 95 % interval.
pub(crate) const Z_95: f64 = 1.959_963_984_540_054;

/// Wilson's score interval for `x` events in `n` trials, as a share
/// (0 to 1); `None` with no trials.
pub(crate) fn wilson(x: u64, n: u64) -> Option<(f64, f64)> {
    if n == 0 {
        return None;
    }
    let (x, n) = (x.min(n) as f64, n as f64);
    let p = x / n;
    let z2 = Z_95 * Z_95;
    let denominator = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denominator;
    let half = Z_95 / denominator * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    // Rounding can leave a hair outside [0, 1] at x = 0 or x = n.
    Some(((centre - half).max(0.0), (centre + half).min(1.0)))
}

/// The difference `b - a` of two shares with its 95 % interval, as
/// shares (-1 to 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Difference {
    pub(crate) estimate: f64,
    pub(crate) low: f64,
    pub(crate) high: f64,
}

/// Newcombe's hybrid score interval for `xb/nb - xa/na`; `None` when
/// either run had no trials.
pub(crate) fn newcombe(xa: u64, na: u64, xb: u64, nb: u64) -> Option<Difference> {
    let (la, ua) = wilson(xa, na)?;
    let (lb, ub) = wilson(xb, nb)?;
    let pa = xa.min(na) as f64 / na as f64;
    let pb = xb.min(nb) as f64 / nb as f64;
    let d = pb - pa;
    Some(Difference {
        estimate: d,
        low: d - ((pb - lb).powi(2) + (ua - pa).powi(2)).sqrt(),
        high: d + ((ub - pb).powi(2) + (pa - la).powi(2)).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: f64, want: f64, tol: f64) {
        assert!((got - want).abs() <= tol, "{got} is not {want} ± {tol}");
    }

    /// Newcombe (1998), Table II, method 10, its eight examples (a) to
    /// (h) to the four places it prints: the paper's examples are
    /// p1 - p2, ours b - a, so p1 is b.
    #[test]
    fn newcombe_reproduces_the_published_examples() {
        for (xb, nb, xa, na, low, high) in [
            (56, 70, 48, 80, 0.0524, 0.3339),
            (9, 10, 3, 10, 0.1705, 0.8090),
            (6, 7, 2, 7, 0.0582, 0.8062),
            (5, 56, 0, 29, -0.0381, 0.1926),
            (0, 10, 0, 20, -0.1611, 0.2775),
            (0, 10, 0, 10, -0.2775, 0.2775),
            (10, 10, 0, 20, 0.6791, 1.0000),
            (10, 10, 0, 10, 0.6075, 1.0000),
        ] {
            let d = newcombe(xa, na, xb, nb).unwrap();
            close(d.low, low, 0.000_05);
            close(d.high, high, 0.000_05);
        }
    }

    /// 50 of 1000 lost against 80 of 1000: +3.0 points. The Wilson
    /// intervals, by hand (z = 1.959964, z² = 3.841459):
    /// 50/1000: centre (0.05 + 0.001921) / 1.003841 = 0.051722, half
    /// 1.952467 × √(0.0000475 + 0.00000096) = 0.013592 → [0.038130,
    /// 0.065314]; 80/1000: centre 0.081607, half 0.016859 → [0.064748,
    /// 0.098466]. Then low = 0.03 - √(0.015252² + 0.015314²) = 0.008387,
    /// high = 0.03 + √(0.018466² + 0.011870²) = 0.051952.
    #[test]
    fn three_points_more_loss_in_a_thousand_each() {
        let (l, u) = wilson(50, 1000).unwrap();
        close(l, 0.038_130, 0.000_001);
        close(u, 0.065_314, 0.000_001);
        let d = newcombe(50, 1000, 80, 1000).unwrap();
        close(d.estimate, 0.03, 1e-12);
        close(d.low, 0.008_387, 0.000_001);
        close(d.high, 0.051_952, 0.000_001);
    }

    #[test]
    fn nothing_lost_still_has_an_interval_and_no_trials_none() {
        let (l, u) = wilson(0, 100).unwrap();
        close(l, 0.0, 1e-12);
        close(u, 0.036_993, 0.000_001);
        let d = newcombe(0, 100, 0, 100).unwrap();
        assert_eq!(d.estimate, 0.0);
        assert!(d.low < 0.0 && d.high > 0.0, "{d:?}");
        assert_eq!(wilson(0, 0), None);
        assert_eq!(newcombe(1, 10, 0, 0), None);
    }

    #[test]
    fn the_interval_is_antisymmetric_in_the_runs() {
        let ab = newcombe(9, 500, 51, 500).unwrap();
        let ba = newcombe(51, 500, 9, 500).unwrap();
        close(ab.low, -ba.high, 1e-12);
        close(ab.high, -ba.low, 1e-12);
    }
}
