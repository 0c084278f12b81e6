//! Availability by the report's rule: the link is up while a frame from
//! the vehicle came within `up_within`. A silence (the gap between two of
//! the vehicle's frames, or between the start and the first) longer than
//! that is an outage of the silence less `up_within`, from the last frame
//! plus `up_within`; one still going at the end is open. The start counts
//! as a frame: the rule's grace before the vehicle is first heard.
//!
//! Constant memory: sums per duration band and per distance band, and
//! the [`KEPT`] longest outages.

use super::report::{self, Band, DistanceBand, Outage, Outages};
use super::timeline::Timeline;
use crate::engine::Nanos;

/// Outages listed in the report, the longest.
pub(crate) const KEPT: usize = 5;
/// Distance bands kept; a vehicle further than this many bands goes in
/// the last.
const MAX_BANDS: usize = 200;

const SECOND: Nanos = 1_000_000_000;

/// The duration bands, their upper bounds (exclusive) in s.
const BANDS: [(&str, Nanos); 5] = [
    ("<1s", SECOND),
    ("1-3s", 3 * SECOND),
    ("3-10s", 10 * SECOND),
    ("10-30s", 30 * SECOND),
    (">30s", Nanos::MAX),
];

fn secs(ns: Nanos) -> f64 {
    ns as f64 / 1e9
}

/// Time seen and time down in one distance band.
#[derive(Debug, Clone, Copy, Default)]
struct InBand {
    observed: Nanos,
    down: Nanos,
    outages: u64,
}

/// The link's availability so far.
#[derive(Debug, Clone)]
pub(crate) struct Availability {
    up_within: Nanos,
    band_m: f64,
    /// The vehicle's last frame, or the start.
    last: Nanos,
    frames: u64,
    down: Nanos,
    bands: [(u64, Nanos); 5],
    longest: Vec<Outage>,
    by_distance: Vec<InBand>,
    timeline: Timeline,
}

impl Availability {
    pub(crate) fn new(up_within: Nanos, band_m: f64) -> Self {
        Availability {
            up_within,
            band_m,
            last: 0,
            frames: 0,
            down: 0,
            bands: [(0, 0); 5],
            longest: Vec::new(),
            by_distance: Vec::new(),
            timeline: Timeline::default(),
        }
    }

    /// Whether the link is up at `at` by the rule (`at` not before the
    /// last frame).
    pub(crate) fn up_at(&self, at: Nanos) -> bool {
        at.saturating_sub(self.last) <= self.up_within
    }

    pub(crate) fn frames(&self) -> u64 {
        self.frames
    }

    /// A frame from the vehicle at `at`; `distance` is where the vehicle
    /// was last known to be before it (metres).
    pub(crate) fn frame(&mut self, at: Nanos, distance: Option<f64>) {
        self.frames += 1;
        // A log's stamps can step back: no time passed.
        if at <= self.last {
            return;
        }
        self.gap(at, distance, false);
        self.last = at;
    }

    /// The time from the last frame to `until`, in the band of `distance`,
    /// and the outage in it.
    fn gap(&mut self, until: Nanos, distance: Option<f64>, open: bool) {
        let silence = until - self.last;
        let down = silence.saturating_sub(self.up_within);
        let band = distance.map(|d| self.band(d));
        if let Some(b) = band {
            self.by_distance[b].observed += silence;
            self.by_distance[b].down += down;
        }
        if down == 0 {
            return;
        }
        self.down += down;
        self.timeline.down(self.last + self.up_within, until);
        let i = BANDS
            .iter()
            .position(|(_, upper)| down < *upper)
            .expect("the last is MAX");
        self.bands[i].0 += 1;
        self.bands[i].1 += down;
        if let Some(b) = band {
            self.by_distance[b].outages += 1;
        }
        self.keep(Outage {
            start_s: secs(self.last + self.up_within),
            duration_s: secs(down),
            silence_s: secs(silence),
            distance_m: distance,
            open,
            at_utc: None,
        });
    }

    fn band(&mut self, distance: f64) -> usize {
        let b = ((distance.max(0.0) / self.band_m) as usize).min(MAX_BANDS - 1);
        if self.by_distance.len() <= b {
            self.by_distance.resize(b + 1, InBand::default());
        }
        b
    }

    fn keep(&mut self, o: Outage) {
        let at = self
            .longest
            .iter()
            .position(|k| k.duration_s < o.duration_s)
            .unwrap_or(self.longest.len());
        if at < KEPT {
            self.longest.insert(at, o);
            self.longest.truncate(KEPT);
        }
    }

    /// The figures at `end`: an outage still going is open. Returns the
    /// time down, the outages, when they were, and the distance bands.
    pub(crate) fn finish(
        mut self,
        end: Nanos,
        distance: Option<f64>,
    ) -> (Nanos, Outages, report::Timeline, Vec<DistanceBand>) {
        if end > self.last {
            self.gap(end, distance, true);
        }
        let count = self.bands.iter().map(|b| b.0).sum();
        let outages = Outages {
            count,
            total_s: secs(self.down),
            bands: BANDS
                .iter()
                .zip(self.bands)
                .map(|((band, _), (count, total))| Band {
                    band,
                    count,
                    total_s: secs(total),
                })
                .collect(),
            longest: self.longest,
        };
        let band_m = self.band_m;
        let bands = self
            .by_distance
            .iter()
            .enumerate()
            .filter(|(_, b)| b.observed > 0)
            .map(|(i, b)| DistanceBand {
                from_m: i as f64 * band_m,
                to_m: (i + 1) as f64 * band_m,
                observed_s: secs(b.observed),
                down_s: secs(b.down),
                availability_pct: 100.0 * (1.0 - b.down as f64 / b.observed as f64),
                outages: b.outages,
            })
            .collect();
        (self.down, outages, self.timeline.finish(end), bands)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Nanos = SECOND;
    const MS: Nanos = 1_000_000;

    /// Frames every 100 ms but for silences of 2.5 s, 4 s, 12.2 s and 40 s
    /// against a 2 s rule: outages of 0.5, 2, 10.2 and 38 s.
    #[test]
    fn silences_past_the_rule_are_outages_of_what_exceeds_it_in_their_bands() {
        let mut a = Availability::new(2 * S, 500.0);
        let mut t = 0;
        for silence in [2_500 * MS, 4 * S, 12_200 * MS, 40 * S] {
            for _ in 0..10 {
                t += 100 * MS;
                a.frame(t, None);
            }
            t += silence;
            a.frame(t, None);
        }
        let (down, o, _, _) = a.finish(t, None);
        assert_eq!(down, 500 * MS + 2 * S + 10_200 * MS + 38 * S);
        assert_eq!(o.count, 4);
        let counts: Vec<_> = o.bands.iter().map(|b| (b.band, b.count)).collect();
        assert_eq!(
            counts,
            [
                ("<1s", 1),
                ("1-3s", 1),
                ("3-10s", 0),
                ("10-30s", 1),
                (">30s", 1)
            ]
        );
        assert_eq!(o.longest[0].duration_s, 38.0);
        assert_eq!(o.longest[0].silence_s, 40.0);
        assert_eq!(o.longest.len(), 4);
    }

    /// Exactly the rule is still up; a band edge goes to the upper band.
    #[test]
    fn a_silence_of_exactly_the_rule_is_no_outage_and_1s_is_in_1_to_3() {
        let mut a = Availability::new(2 * S, 500.0);
        a.frame(2 * S, None);
        a.frame(5 * S, None);
        let (down, o, _, _) = a.finish(5 * S, None);
        assert_eq!(down, S);
        assert_eq!(o.bands[1].count, 1);
    }

    #[test]
    fn a_vehicle_never_heard_is_down_from_the_grace_on_and_the_outage_is_open() {
        let a = Availability::new(2 * S, 500.0);
        let (down, o, _, _) = a.finish(10 * S, None);
        assert_eq!(down, 8 * S);
        assert!(o.longest[0].open);
        assert_eq!(o.longest[0].start_s, 2.0);
    }

    /// The time between frames goes to the band of the distance before.
    #[test]
    fn distance_bands_hold_the_time_seen_there_and_its_outages() {
        let mut a = Availability::new(S, 500.0);
        a.frame(S, Some(100.0));
        a.frame(2 * S, Some(100.0));
        a.frame(5 * S, Some(700.0)); // 3 s silence at 700 m: 2 s down
        a.frame(6 * S, Some(700.0));
        let (_, _, _, bands) = a.finish(6 * S, Some(700.0));
        assert_eq!(bands.len(), 2);
        assert_eq!(
            (bands[0].from_m, bands[0].observed_s, bands[0].down_s),
            (0.0, 2.0, 0.0)
        );
        assert_eq!(
            (bands[1].from_m, bands[1].observed_s, bands[1].down_s),
            (500.0, 4.0, 2.0)
        );
        assert_eq!(bands[1].availability_pct, 50.0);
        assert_eq!(bands[1].outages, 1);
    }

    #[test]
    fn stamps_that_step_back_take_no_time() {
        let mut a = Availability::new(S, 500.0);
        a.frame(5 * S, None);
        a.frame(4 * S, None);
        a.frame(5_500 * MS, None);
        assert_eq!(a.frames(), 3);
        let (down, o, _, _) = a.finish(5_500 * MS, None);
        assert_eq!((down, o.count), (4 * S, 1));
    }
}
