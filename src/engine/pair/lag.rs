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
}

impl Lag {
    pub(super) fn new(window: Nanos) -> Self {
        let high = (window / 1_000).max(2);
        Lag {
            hist: Histogram::new_with_bounds(1, high, 3).expect("valid histogram bounds"),
            max_ns: 0,
        }
    }

    pub(super) fn record(&mut self, ns: Nanos) {
        self.hist.saturating_record((ns + 500) / 1_000);
        self.max_ns = self.max_ns.max(ns);
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
