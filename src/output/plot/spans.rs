//! Bins of a width that doubles, neighbours merging, whenever a value falls
//! past the last: their number stays bounded, and a long run is drawn at a
//! coarser resolution, its figures summed, never dropped. The time spans of
//! every plot, and the flight's distance bins.

use crate::engine::probe::passive::flight::FlightWindow;
use crate::engine::Nanos;
use crate::output::windows::Window;

/// `bins` summed into one.
pub(super) fn merged(bins: &[Sums]) -> Sums {
    bins.iter().fold(Sums::default(), |a, &b| a.merge(b))
}

/// At most `max` bins, the first `width` wide, drawn in `unit`s (a time
/// in ns drawn in seconds: 1e9). A time stays exact as an `f64` for 104
/// days of ns.
#[derive(Debug, Clone)]
pub(super) struct Bins {
    pub(super) width: f64,
    unit: f64,
    max: usize,
    pub(super) bins: Vec<Sums>,
}

impl Bins {
    pub(super) fn new(width: f64, unit: f64, max: usize) -> Self {
        Bins {
            width,
            unit,
            max,
            bins: Vec::new(),
        }
    }

    /// The bin `x` falls in, the bins widened until it is one of them.
    pub(super) fn at(&mut self, x: f64) -> &mut Sums {
        let index = |width: f64| (x / width).max(0.0) as usize;
        while index(self.width) >= self.max {
            self.bins = self.bins.chunks(2).map(merged).collect();
            self.width *= 2.0;
        }
        let i = index(self.width);
        if self.bins.len() <= i {
            self.bins.resize(i + 1, Sums::default());
        }
        &mut self.bins[i]
    }

    /// Each bin's middle, in the drawn unit, and what it holds.
    pub(super) fn each(&self) -> impl Iterator<Item = (f64, &Sums)> {
        let each = self.bins.iter().enumerate();
        each.map(|(i, s)| ((i as f64 + 0.5) * self.width / self.unit, s))
    }

    /// Points of `f` over the bins that have one, at their middle.
    pub(super) fn points(&self, f: impl Fn(&Sums) -> Option<f64>) -> Vec<(f64, f64)> {
        self.each().filter_map(|(x, s)| Some((x, f(s)?))).collect()
    }

    /// The end of the last bin, in the drawn unit.
    pub(super) fn end(&self) -> f64 {
        self.bins.len() as f64 * self.width / self.unit
    }
}

/// What a span or bin holds, summed: a sequence's windows (a passive
/// source's, or a log's link) and the radio's figures in them, or a
/// responder's replies and losses.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Sums {
    /// Frames, duplicates included.
    pub(super) received: u64,
    pub(super) duplicate: u64,
    /// Signed: a late frame moves a loss from an earlier window to this
    /// one's reordered (see [`Window::lost`]).
    pub(super) lost: i64,
    /// Time the windows in it covered (the last one is partial).
    pub(super) covered_ns: Nanos,
    /// The radio's RSSI and remote RSSI, each summed over its reports, and
    /// how many.
    pub(super) rssi: (f64, u64),
    pub(super) remrssi: (f64, u64),
    /// A responder's RTT in ns summed over its replies (exact as an `f64`
    /// for 104 days of it), and how many.
    pub(super) rtt_ns: (f64, u64),
    /// The highest age above the baseline put in, ms: a passive source's
    /// oldest frame of each telling, or a log window's p99. Merged bins
    /// keep the higher, so a queue's peak survives any merging.
    pub(super) age_ms: Option<f64>,
    /// A source heard on several links, this link's part (the pair
    /// report's): its lag behind the first copy in ns summed over its
    /// frames, and how many; its frames, and those it delivered first.
    pub(super) lag_ns: (f64, u64),
    pub(super) paired: u64,
    pub(super) first: u64,
}

impl Sums {
    /// Both together: what two neighbouring bins hold once merged.
    fn merge(mut self, o: Sums) -> Sums {
        self.received += o.received;
        self.duplicate += o.duplicate;
        self.lost += o.lost;
        self.covered_ns += o.covered_ns;
        self.rssi = (self.rssi.0 + o.rssi.0, self.rssi.1 + o.rssi.1);
        self.remrssi = (self.remrssi.0 + o.remrssi.0, self.remrssi.1 + o.remrssi.1);
        self.rtt_ns = (self.rtt_ns.0 + o.rtt_ns.0, self.rtt_ns.1 + o.rtt_ns.1);
        self.lag_ns = (self.lag_ns.0 + o.lag_ns.0, self.lag_ns.1 + o.lag_ns.1);
        self.paired += o.paired;
        self.first += o.first;
        if let Some(age) = o.age_ms {
            self.age(age);
        }
        self
    }

    /// An age above the baseline, ms: the bin keeps the highest.
    pub(super) fn age(&mut self, ms: f64) {
        self.age_ms = Some(self.age_ms.map_or(ms, |held| held.max(ms)));
    }

    /// A passive source's window.
    pub(super) fn window(&mut self, w: &Window) {
        self.received += w.received;
        self.duplicate += w.duplicate;
        self.lost += w.lost;
        self.covered_ns += w.end.saturating_sub(w.start);
    }

    /// A log's window.
    pub(super) fn flight(&mut self, w: &FlightWindow) {
        self.received += w.received;
        self.duplicate += w.duplicate;
        self.lost += w.lost;
        if let Some(r) = &w.radio {
            // A window's mean stands for its reports.
            for (sum, v) in [(&mut self.rssi, r.rssi), (&mut self.remrssi, r.remrssi)] {
                if let Some(v) = v {
                    sum.0 += v * r.reports as f64;
                    sum.1 += r.reports;
                }
            }
        }
        if let Some(a) = &w.age {
            self.age(a.p99_ms);
        }
    }

    pub(super) fn frames_per_s(&self) -> Option<f64> {
        (self.covered_ns > 0).then(|| self.received as f64 * 1e9 / self.covered_ns as f64)
    }

    /// `100 * lost / (lost + distinct)`; `None` with nothing to compare.
    pub(super) fn loss_pct(&self) -> Option<f64> {
        let lost = self.lost.max(0) as f64;
        let whole = lost + self.received.saturating_sub(self.duplicate) as f64;
        (whole > 0.0).then(|| 100.0 * lost / whole)
    }

    pub(super) fn mean((sum, n): (f64, u64)) -> Option<f64> {
        (n > 0).then(|| sum / n as f64)
    }

    /// The mean lag behind the first copy, ms; `None` without copies.
    pub(super) fn mean_lag_ms(&self) -> Option<f64> {
        Sums::mean(self.lag_ns).map(|ns| ns / 1e6)
    }

    /// The mean RTT of its replies, ms; `None` without replies.
    pub(super) fn mean_rtt_ms(&self) -> Option<f64> {
        Sums::mean(self.rtt_ns).map(|ns| ns / 1e6)
    }
}
