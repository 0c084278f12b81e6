//! The age axis both passive pages share: a live run's oldest frame per
//! span, a log's window p99 (see docs/age.md).
//!
//! A log axis: a queue's age runs from a few ms (a link's jitter, whole-ms
//! stamps) to seconds (a modem's buffer), and a linear axis scaled to a
//! 3 s peak would flatten everything under 30 ms onto its floor, where a
//! healthy link and a 20 ms one look the same. On a log axis each decade
//! gets the same room, so both the quiet link and the queue's rise and
//! drain read on one chart.

use plotters::coord::combinators::WithKeyPoints;
use plotters::prelude::*;

use super::draw::{log_ticks, Points};

/// Ages below it are drawn at it: the stamps are often whole ms, and a
/// log axis has no 0 (the quickest frame's age is exactly 0).
pub(super) const FLOOR_MS: f64 = 1.0;
/// The axis reaches this at least, so a healthy link's ages sit low on
/// the chart instead of filling it: 100 ms, where the live view marks an
/// age and the queue hint starts to look.
const LEAST_TOP_MS: f64 = 100.0;
/// Past this many decades, 1 and 3 in each: 1, 2, 5 in each of four or
/// more would crowd the labels of a chart this high, and a tick a decade
/// would leave a 5 s peak with no label above 1000.
const DECADES_OF_FINE_TICKS: f64 = 3.0;

/// `points` with every age below [`FLOOR_MS`] raised to it.
pub(super) fn floored(points: Points) -> Points {
    points
        .into_iter()
        .map(|(x, y)| (x, y.max(FLOOR_MS)))
        .collect()
}

/// The y axis for `lines` (ages in ms, floored): from [`FLOOR_MS`] to a
/// little above the highest, [`LEAST_TOP_MS`] at least.
pub(super) fn axis(lines: &[Points]) -> WithKeyPoints<LogCoord<f64>> {
    let top = lines
        .iter()
        .flatten()
        .map(|p| p.1)
        .fold(LEAST_TOP_MS, f64::max)
        * 1.3;
    (FLOOR_MS..top)
        .log_scale()
        .with_key_points(ticks(FLOOR_MS, top))
}

/// Round ticks from `from` to `to`: two a decade over a wide range.
fn ticks(from: f64, to: f64) -> Vec<f64> {
    if (to / from).log10() < DECADES_OF_FINE_TICKS {
        return log_ticks(from, to);
    }
    let decades = from.log10().floor() as i32..=to.log10().floor() as i32;
    let each = decades.flat_map(|e| [1.0, 3.0].map(|m| m * 10f64.powi(e)));
    each.filter(|v| (from..=to).contains(v)).collect()
}

/// Whether any of `lines` has a point: a chart of none is left out.
pub(super) fn any(lines: &[Points]) -> bool {
    lines.iter().any(|l| !l.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quiet_link_gets_fine_ticks_and_a_queue_two_a_decade() {
        // 4 ms of jitter: the axis still reaches past 100 ms.
        assert_eq!(
            ticks(FLOOR_MS, 130.0),
            [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
        );
        // A 10 s queue.
        let ten_s = [1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0, 10_000.0];
        assert_eq!(ticks(FLOOR_MS, 13_000.0), ten_s);
    }

    #[test]
    fn ages_below_the_floor_are_drawn_on_it() {
        let points = floored(vec![(0.5, 0.0), (1.5, 0.4), (2.5, 850.0)]);
        assert_eq!(points, [(0.5, 1.0), (1.5, 1.0), (2.5, 850.0)]);
        assert!(any(&[vec![], points]));
        assert!(!any(&[vec![], vec![]]));
    }
}
