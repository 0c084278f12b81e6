//! When the link was down over the run: the down time in at most
//! [`BINS`] equal bins of the run, in constant memory. The bins start a
//! second wide and double (neighbours merged) whenever the run outgrows
//! them, so an hour and a week both fit.

use super::report;
use crate::engine::Nanos;

/// Bins kept at most.
pub(crate) const BINS: usize = 120;

const SECOND: Nanos = 1_000_000_000;

#[derive(Debug, Clone)]
pub(crate) struct Timeline {
    /// Each bin's width: bin i is [i × width, (i + 1) × width).
    width: Nanos,
    down: Vec<Nanos>,
}

impl Default for Timeline {
    fn default() -> Self {
        Timeline {
            width: SECOND,
            down: Vec::new(),
        }
    }
}

impl Timeline {
    /// Widens the bins until `to` falls within them.
    fn reach(&mut self, to: Nanos) {
        while to > self.width.saturating_mul(BINS as Nanos) {
            self.width = self.width.saturating_mul(2);
            self.down = self.down.chunks(2).map(|pair| pair.iter().sum()).collect();
        }
    }

    /// The link was down from `from` to `to`.
    pub(crate) fn down(&mut self, from: Nanos, to: Nanos) {
        self.reach(to);
        let mut t = from;
        while t < to {
            let bin = (t / self.width) as usize;
            let bin_end = (bin as Nanos + 1) * self.width;
            let until = to.min(bin_end);
            if self.down.len() <= bin {
                self.down.resize(bin + 1, 0);
            }
            self.down[bin] += until - t;
            t = until;
        }
    }

    /// The bins to `end`, each with its down time.
    pub(crate) fn finish(mut self, end: Nanos) -> report::Timeline {
        self.reach(end);
        let bins = end.div_ceil(self.width) as usize;
        self.down.resize(bins.max(self.down.len()), 0);
        report::Timeline {
            bin_s: self.width as f64 / 1e9,
            down_s: self.down.iter().map(|&d| d as f64 / 1e9).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Nanos = 1_000_000;

    #[test]
    fn an_outage_across_bins_is_split_between_them() {
        let mut t = Timeline::default();
        t.down(1_500 * MS, 3_250 * MS);
        let r = t.finish(5 * SECOND);
        assert_eq!(r.bin_s, 1.0);
        assert_eq!(r.down_s, [0.0, 0.5, 1.0, 0.25, 0.0]);
    }

    /// A run past 120 bins doubles them, keeping every down second.
    #[test]
    fn a_long_run_widens_the_bins_and_keeps_the_down_time() {
        let mut t = Timeline::default();
        t.down(10 * SECOND, 12 * SECOND);
        t.down(3_000 * SECOND, 3_600 * SECOND);
        let r = t.finish(3_600 * SECOND);
        assert_eq!(r.bin_s, 32.0);
        assert!(r.down_s.len() <= BINS, "{}", r.down_s.len());
        assert_eq!(r.down_s.iter().sum::<f64>(), 602.0);
        assert_eq!(r.down_s[0], 2.0);
    }
}
