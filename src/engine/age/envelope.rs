//! The lower envelope of one stream of (receive time, raw delay) points
//! from one sender clock, in constant memory.
//!
//! A point's raw delay `d = receive − stamp` is the clocks' offset, plus
//! their drift times the time, plus the frame's delay. The lowest line
//! under every point is the delay's floor: its slope the drift, and each
//! point's height above it the delay above the baseline (as OWAMP and
//! Moon, Skelly and Towsley's linear program fit it). Of all lines under
//! the points the one highest at their mean time is chosen: it is the
//! lower convex hull's edge over the mean time, and it maximises the sum
//! of the points' heights' complement, so a queue that builds and drains
//! within the run does not tilt it.
//!
//! Memory: the points are kept as the lowest one per time bucket; when
//! more than [`MAX_BUCKETS`] are held the buckets double in width and
//! neighbours merge. A point dropped from a bucket can sit below the
//! line fitted without it by at most the drift times the bucket's width
//! (200 ppm × 60 s = 12 ms after 2 hours with 128 buckets of 56 s): the
//! ages of such points are clamped to 0.

use super::super::Nanos;

/// Buckets kept; their width doubles whenever more would be needed.
pub(crate) const MAX_BUCKETS: usize = 128;
/// The first buckets' width: four a second, so a short run keeps every
/// batch's lowest point.
const FIRST_WIDTH_NS: i64 = 250_000_000;
/// Drift is fitted once the points span this long; before, the line is
/// flat through the lowest point: over a few seconds a ms-resolution
/// stamp's rounding tilts a fitted line more than any real clock drifts.
pub(crate) const MIN_DRIFT_SPAN_NS: i64 = 10_000_000_000;
/// The most two clocks' rates differ (ppm): two crystals of ±100 ppm and
/// then some. A steeper floor is a queue that built through the whole
/// run, not drift, and must show as age.
pub(crate) const MAX_DRIFT_PPM: f64 = 500.0;

/// A point relative to the envelope's first one: ns of our time, ns of
/// raw delay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Point {
    pub(crate) t: i64,
    pub(crate) d: i64,
}

/// The floor `d = a + b t` (ns, ns per ns) in the envelope's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Line {
    pub(crate) a: f64,
    pub(crate) b: f64,
}

impl Line {
    pub(crate) fn at(&self, t: i64) -> f64 {
        self.a + self.b * t as f64
    }
}

#[derive(Debug, Clone)]
pub(crate) struct Envelope {
    /// Our time and raw delay of the first point: the others are kept
    /// relative to it, so i64 ns and f64 hold them exactly.
    origin: (Nanos, i128),
    width: i64,
    /// (bucket index, lowest point in it), oldest first.
    buckets: Vec<(i64, Point)>,
    /// Points seen and the sum of their times (for the mean time).
    n: u64,
    sum_t: f64,
    line: Line,
    /// The buckets changed since `line` was fitted.
    stale: bool,
}

impl Envelope {
    /// An envelope starting at the point (`at`, `d`).
    pub(crate) fn new(at: Nanos, d: i128) -> Self {
        Envelope {
            origin: (at, d),
            width: FIRST_WIDTH_NS,
            buckets: Vec::with_capacity(MAX_BUCKETS + 1),
            n: 0,
            sum_t: 0.0,
            line: Line { a: 0.0, b: 0.0 },
            stale: true,
        }
    }

    /// The point (`at`, `d`) in the envelope's frame; receive times never
    /// go back, and raw delays this far apart were refused before.
    pub(crate) fn relative(&self, at: Nanos, d: i128) -> Point {
        let t = at.saturating_sub(self.origin.0);
        Point {
            t: i64::try_from(t).unwrap_or(i64::MAX),
            d: i64::try_from(d - self.origin.1).unwrap_or(if d < self.origin.1 {
                i64::MIN / 2
            } else {
                i64::MAX / 2
            }),
        }
    }

    pub(crate) fn push(&mut self, p: Point) {
        self.n += 1;
        self.sum_t += p.t as f64;
        let index = p.t / self.width;
        match self.buckets.last_mut() {
            Some((last, low)) if *last == index => {
                if p.d < low.d {
                    *low = p;
                    self.stale = true;
                }
            }
            _ => {
                self.buckets.push((index, p));
                self.stale = true;
                if self.buckets.len() > MAX_BUCKETS {
                    self.coarsen();
                }
            }
        }
    }

    /// Doubles the buckets' width until they fit, keeping each merged
    /// pair's lower point.
    fn coarsen(&mut self) {
        while self.buckets.len() > MAX_BUCKETS {
            self.width *= 2;
            let mut merged: Vec<(i64, Point)> = Vec::with_capacity(MAX_BUCKETS + 1);
            for &(index, p) in &self.buckets {
                let index = index / 2;
                match merged.last_mut() {
                    Some((last, low)) if *last == index => {
                        if p.d < low.d {
                            *low = p;
                        }
                    }
                    _ => merged.push((index, p)),
                }
            }
            self.buckets = merged;
        }
    }

    pub(crate) fn stored_points(&self) -> usize {
        self.buckets.len()
    }

    /// The kept points (each bucket's lowest), oldest first.
    pub(crate) fn points(&self) -> Vec<Point> {
        self.buckets.iter().map(|&(_, p)| p).collect()
    }

    /// Time from the first kept point to the last, ns.
    pub(crate) fn span(&self) -> i64 {
        match (self.buckets.first(), self.buckets.last()) {
            (Some((_, first)), Some((_, last))) => last.t - first.t,
            _ => 0,
        }
    }

    /// The floor fitted to the points so far.
    pub(crate) fn line(&mut self) -> Line {
        if self.stale {
            self.line = self.fit();
            self.stale = false;
        }
        self.line
    }

    /// The floor, fitted afresh (for `&self` readers).
    pub(crate) fn current_line(&self) -> Line {
        if self.stale {
            self.fit()
        } else {
            self.line
        }
    }

    /// Our time at the first point, and the floor's raw delay (receive −
    /// stamp, ns) then.
    pub(crate) fn floor_at_start(&self) -> (Nanos, i128) {
        let (at, d) = self.origin;
        (at, d + self.current_line().a.round() as i128)
    }

    /// Drift of their clock against ours, ppm (positive: theirs is slow,
    /// the raw delay grows).
    pub(crate) fn drift_ppm(&self) -> f64 {
        self.current_line().b * 1e6
    }

    fn fit(&self) -> Line {
        let points = self.points();
        let span = self.span();
        let hull = lower_hull(&points);
        if points.is_empty() {
            return Line { a: 0.0, b: 0.0 };
        }
        if span < MIN_DRIFT_SPAN_NS || hull.len() < 2 {
            let low = points.iter().map(|p| p.d).min().unwrap_or(0);
            return Line {
                a: low as f64,
                b: 0.0,
            };
        }
        let mean_t = self.sum_t / self.n.max(1) as f64;
        // The hull's edge over the mean time (the first or last beyond it).
        let edge = hull
            .windows(2)
            .position(|e| (e[1].t as f64) >= mean_t)
            .unwrap_or(hull.len() - 2);
        let (from, to) = (hull[edge], hull[edge + 1]);
        let slope = (to.d - from.d) as f64 / (to.t - from.t) as f64;
        let limit = MAX_DRIFT_PPM / 1e6;
        if slope.abs() <= limit {
            return Line {
                a: from.d as f64 - slope * from.t as f64,
                b: slope,
            };
        }
        // Steeper than any drift: the line of the limit's slope touching
        // the hull from below.
        let b = slope.clamp(-limit, limit);
        let a = hull
            .iter()
            .map(|p| p.d as f64 - b * p.t as f64)
            .fold(f64::INFINITY, f64::min);
        Line { a, b }
    }
}

/// The lower convex hull of points sorted by time (Andrew's monotone
/// chain), collinear points dropped.
pub(crate) fn lower_hull(points: &[Point]) -> Vec<Point> {
    let mut hull: Vec<Point> = Vec::with_capacity(points.len());
    for &p in points {
        while hull.len() >= 2 {
            let (o, a) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            let cross = i128::from(a.t - o.t) * i128::from(p.d - o.d)
                - i128::from(a.d - o.d) * i128::from(p.t - o.t);
            if cross <= 0 {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(p);
    }
    hull
}
