//! RTT statistics for one responder, in constant memory.

use hdrhistogram::{Counter, Histogram};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::Nanos;

/// RTTs above this are recorded as this (one hour): keeps the histogram's
/// memory bounded whatever a broken clock or a stuck link reports.
const HIST_MAX_US: u64 = 3_600_000_000;

/// Running RTT figures: exact min/max/mean/stddev from running sums,
/// percentiles from an HDR histogram at µs resolution (3 significant digits),
/// jitter as the mean absolute difference of consecutive RTTs (RFC 3550).
#[derive(Clone)]
pub struct RttStats {
    hist: Counts,
    count: u64,
    min: Nanos,
    max: Nanos,
    mean: f64,
    m2: f64,
    last: Option<Nanos>,
    jitter_sum: f64,
    jitter_count: u64,
}

/// The histogram's counts: 4 bytes a bucket, half what 8 take, so a
/// thousand responders fit in a few tens of MiB. A bucket cannot overflow
/// before the run has recorded `u32::MAX` samples in all; then the counts
/// widen to 8 bytes, so every count stays exact.
#[derive(Clone)]
enum Counts {
    Narrow(Histogram<u32>),
    Wide(Histogram<u64>),
}

/// The same buckets with 8-byte counts.
fn widened<T: Counter>(narrow: &Histogram<T>) -> Histogram<u64> {
    let mut wide = Histogram::new_from(narrow);
    for v in narrow.iter_recorded() {
        // Cannot fail: the value is within the auto-resizing histogram's range.
        let _ = wide.record_n(v.value_iterated_to(), v.count_at_value().as_u64());
    }
    wide
}

/// Each recorded value's bucket and count, for any counter size.
fn recorded<T: Counter>(h: &Histogram<T>) -> impl Iterator<Item = (u64, u64)> + '_ {
    h.iter_recorded()
        .map(|v| (v.value_iterated_to(), v.count_at_value().as_u64()))
}

impl Default for RttStats {
    fn default() -> Self {
        Self::new()
    }
}

/// One row of the RTT distribution: `count` samples in `[low_us, high_us)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Bucket {
    pub(crate) low_us: f64,
    pub(crate) high_us: f64,
    pub(crate) count: u64,
}

/// The figures a report shows, in µs. Serialised without the unit, as
/// the JSON lines name it once where they hold the figures (`rtt_us`);
/// the command summary names it in each ([`with_units`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct RttSummary {
    #[serde(rename = "min")]
    pub(crate) min_us: f64,
    #[serde(rename = "mean")]
    pub(crate) mean_us: f64,
    #[serde(rename = "max")]
    pub(crate) max_us: f64,
    #[serde(rename = "stddev")]
    pub(crate) stddev_us: f64,
    #[serde(rename = "p50")]
    pub(crate) p50_us: f64,
    #[serde(rename = "p90")]
    pub(crate) p90_us: f64,
    #[serde(rename = "p99")]
    pub(crate) p99_us: f64,
    #[serde(rename = "p99_9")]
    pub(crate) p999_us: f64,
    #[serde(rename = "jitter")]
    pub(crate) jitter_us: f64,
}

/// The figures each named with its unit (`min_us`…), as the command
/// summary's `time_to_ack` gives them.
#[allow(clippy::ref_option)] // serde's `serialize_with` lends the field as it is
pub(crate) fn with_units<S: Serializer>(r: &Option<RttSummary>, s: S) -> Result<S::Ok, S::Error> {
    let Some(r) = r else {
        return s.serialize_none();
    };
    let mut map = s.serialize_map(Some(9))?;
    map.serialize_entry("min_us", &r.min_us)?;
    map.serialize_entry("mean_us", &r.mean_us)?;
    map.serialize_entry("max_us", &r.max_us)?;
    map.serialize_entry("stddev_us", &r.stddev_us)?;
    map.serialize_entry("p50_us", &r.p50_us)?;
    map.serialize_entry("p90_us", &r.p90_us)?;
    map.serialize_entry("p99_us", &r.p99_us)?;
    map.serialize_entry("p999_us", &r.p999_us)?;
    map.serialize_entry("jitter_us", &r.jitter_us)?;
    map.end()
}

impl RttStats {
    pub fn new() -> Self {
        // Grows with the largest RTT seen (capped at HIST_MAX_US), so a
        // responder on loopback costs 8 KiB, not the 1-hour worst case.
        let hist = Histogram::new(3).expect("3 significant digits is a valid histogram");
        RttStats {
            hist: Counts::Narrow(hist),
            count: 0,
            min: Nanos::MAX,
            max: 0,
            mean: 0.0,
            m2: 0.0,
            last: None,
            jitter_sum: 0.0,
            jitter_count: 0,
        }
    }

    pub fn record(&mut self, rtt: Nanos) {
        let us = (rtt / 1_000).clamp(1, HIST_MAX_US);
        if self.count == u64::from(u32::MAX) {
            if let Counts::Narrow(narrow) = &self.hist {
                self.hist = Counts::Wide(widened(narrow));
            }
        }
        // Cannot fail: the value is within the auto-resizing histogram's range.
        let _ = match &mut self.hist {
            Counts::Narrow(h) => h.record(us),
            Counts::Wide(h) => h.record(us),
        };
        self.count += 1;
        self.min = self.min.min(rtt);
        self.max = self.max.max(rtt);
        let x = rtt as f64;
        let delta = x - self.mean;
        self.mean += delta / self.count as f64;
        self.m2 += delta * (x - self.mean);
        if let Some(last) = self.last {
            self.jitter_sum += last.abs_diff(rtt) as f64;
            self.jitter_count += 1;
        }
        self.last = Some(rtt);
    }

    pub fn count(&self) -> u64 {
        self.count
    }

    pub(crate) fn last(&self) -> Option<Nanos> {
        self.last
    }

    /// The histogram (µs), with 8-byte counts: a copy, for exports.
    pub(crate) fn histogram(&self) -> Histogram<u64> {
        match &self.hist {
            Counts::Narrow(h) => widened(h),
            Counts::Wide(h) => h.clone(),
        }
    }

    /// Each recorded bucket's highest value (µs) and count.
    fn buckets(&self) -> Box<dyn Iterator<Item = (u64, u64)> + '_> {
        match &self.hist {
            Counts::Narrow(h) => Box::new(recorded(h)),
            Counts::Wide(h) => Box::new(recorded(h)),
        }
    }

    /// Value at a quantile in µs, kept inside the exact [min, max].
    pub(crate) fn quantile_us(&self, q: f64) -> f64 {
        let v = match &self.hist {
            Counts::Narrow(h) => h.value_at_quantile(q),
            Counts::Wide(h) => h.value_at_quantile(q),
        } as f64;
        v.clamp(self.min as f64 / 1e3, self.max as f64 / 1e3)
    }

    pub(crate) fn summary(&self) -> Option<RttSummary> {
        if self.count == 0 {
            return None;
        }
        let variance = if self.count > 1 {
            self.m2 / (self.count - 1) as f64
        } else {
            0.0
        };
        Some(RttSummary {
            min_us: self.min as f64 / 1e3,
            mean_us: self.mean / 1e3,
            max_us: self.max as f64 / 1e3,
            stddev_us: variance.sqrt() / 1e3,
            p50_us: self.quantile_us(0.5),
            p90_us: self.quantile_us(0.9),
            p99_us: self.quantile_us(0.99),
            p999_us: self.quantile_us(0.999),
            jitter_us: if self.jitter_count == 0 {
                0.0
            } else {
                self.jitter_sum / self.jitter_count as f64 / 1e3
            },
        })
    }

    /// The distribution in at most `rows` buckets between min and max:
    /// log-spaced when the range spans more than a factor of 4, else linear
    /// with buckets at least 1 µs wide (the resolution reports show), so
    /// equal RTTs make one row, not eight with the same label.
    pub(crate) fn distribution(&self, rows: usize) -> Vec<Bucket> {
        if self.count == 0 || rows == 0 {
            return Vec::new();
        }
        let lo = (self.min / 1_000).max(1) as f64;
        let hi = ((self.max / 1_000).max(1) as f64).max(lo) + 1.0;
        let log = hi / lo > 4.0;
        let rows = if log {
            rows
        } else {
            rows.min((hi - lo) as usize)
        };
        let edge = |i: usize| {
            let t = i as f64 / rows as f64;
            if log {
                lo * (hi / lo).powf(t)
            } else {
                lo + (hi - lo) * t
            }
        };
        let mut buckets: Vec<Bucket> = (0..rows)
            .map(|i| Bucket {
                low_us: edge(i),
                high_us: edge(i + 1),
                count: 0,
            })
            .collect();
        for (value, count) in self.buckets() {
            let value = value as f64;
            let idx = buckets
                .iter()
                .position(|b| value < b.high_us)
                .unwrap_or(rows - 1);
            buckets[idx].count += count;
        }
        buckets
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_figures_for_known_samples() {
        let mut s = RttStats::new();
        for us in [100, 200, 300, 400] {
            s.record(us * 1_000);
        }
        let r = s.summary().unwrap();
        assert_eq!(r.min_us, 100.0);
        assert_eq!(r.max_us, 400.0);
        assert_eq!(r.mean_us, 250.0);
        assert!((r.stddev_us - 129.099).abs() < 0.001);
        assert_eq!(r.jitter_us, 100.0);
        assert_eq!(r.p50_us, 200.0);
        assert_eq!(r.p99_us, 400.0);
    }

    #[test]
    fn outliers_saturate_instead_of_panicking() {
        let mut s = RttStats::new();
        s.record(1);
        s.record(u64::MAX / 2);
        let r = s.summary().unwrap();
        // Exact figures keep the outlier; the histogram saturates at 1 h.
        assert_eq!(r.max_us, (u64::MAX / 2) as f64 / 1e3);
        assert!((r.p999_us / 3.6e9 - 1.0).abs() < 0.001, "{}", r.p999_us);
        assert_eq!(s.count(), 2);
    }

    #[test]
    fn distribution_accounts_for_every_sample() {
        let mut s = RttStats::new();
        for i in 1..=1000u64 {
            s.record(i * 37_000);
        }
        let buckets = s.distribution(8);
        assert_eq!(buckets.len(), 8);
        assert_eq!(buckets.iter().map(|b| b.count).sum::<u64>(), 1000);
    }

    #[test]
    fn equal_rtts_make_one_row() {
        let mut s = RttStats::new();
        for _ in 0..5 {
            s.record(10_000_000);
        }
        let buckets = s.distribution(8);
        assert_eq!(buckets.len(), 1, "{buckets:?}");
        assert_eq!(buckets[0].count, 5);
        // Three distinct µs: three rows at most.
        let mut s = RttStats::new();
        for ns in [101_503_000, 101_504_000, 101_505_400] {
            s.record(ns);
        }
        let buckets = s.distribution(8);
        assert_eq!(buckets.len(), 3, "{buckets:?}");
        assert_eq!(buckets.iter().map(|b| b.count).sum::<u64>(), 3);
    }

    #[test]
    fn counts_widen_before_any_could_overflow_and_stay_exact() {
        let mut s = RttStats::new();
        for us in [7, 7, 900, 35_000] {
            s.record(us * 1_000);
        }
        let narrow = s.histogram();
        // As if the run had recorded u32::MAX samples already.
        s.count = u64::from(u32::MAX);
        s.record(7_000);
        assert!(matches!(s.hist, Counts::Wide(_)));
        let wide = s.histogram();
        assert_eq!(wide.len(), narrow.len() + 1);
        assert_eq!(wide.count_at(7), 3);
        assert_eq!(wide.count_at(35_000), 1);
        assert_eq!(wide.max(), narrow.max());
        assert_eq!(s.quantile_us(0.5), 7.0);
    }

    #[test]
    fn no_samples_no_summary() {
        assert!(RttStats::new().summary().is_none());
        assert!(RttStats::new().distribution(5).is_empty());
    }
}
