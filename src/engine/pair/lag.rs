//! How far copies lag behind the first: quantiles from a histogram, as
//! the age split keeps its queue delays, the max exact.

use hdrhistogram::Histogram;

use crate::engine::Nanos;

/// Lags in µs at three significant digits (exact to 2 ms, then within
/// 0.1 %), up to the window: no copy is matched later than that.
#[derive(Debug, Clone)]
pub(super) struct Lag {
    hist: Histogram<u32>,
    max_ns: Nanos,
    /// Every lag recorded, summed (exact as an `f64` for 104 days of
    /// ns), and how many: what a plot's span means.
    sum_ns: f64,
    count: u64,
}

impl Lag {
    pub(super) fn new(window: Nanos) -> Self {
        let high = (window / 1_000).max(2);
        Lag {
            hist: Histogram::new_with_bounds(1, high, 3).expect("valid histogram bounds"),
            max_ns: 0,
            sum_ns: 0.0,
            count: 0,
        }
    }

    pub(super) fn record(&mut self, ns: Nanos) {
        self.hist.saturating_record((ns + 500) / 1_000);
        self.max_ns = self.max_ns.max(ns);
        self.sum_ns += ns as f64;
        self.count += 1;
    }

    /// The lags summed, ns, and how many.
    pub(super) fn sum(&self) -> (f64, u64) {
        (self.sum_ns, self.count)
    }

    /// The `q` quantile in ms, never above the max; none before a lag.
    pub(super) fn quantile_ms(&self, q: f64) -> Option<f64> {
        (!self.hist.is_empty())
            .then(|| (self.hist.value_at_quantile(q) as f64 / 1e3).min(self.max_ms()))
    }

    fn max_ms(&self) -> f64 {
        self.max_ns as f64 / 1e6
    }

    /// The longest lag in ms; none before a lag.
    pub(super) fn max(&self) -> Option<f64> {
        (!self.hist.is_empty()).then(|| self.max_ms())
    }

    /// Bytes held, for the tests of the memory bound.
    #[cfg(test)]
    pub(super) fn bytes(&self) -> usize {
        self.hist.distinct_values() * std::mem::size_of::<u32>()
    }
}
