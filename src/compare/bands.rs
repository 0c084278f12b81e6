//! Loss by distance for two telemetry logs: their flight windows sorted
//! into the same distance bands, each band's frames summed.

use std::collections::BTreeMap;

use serde::Serialize;

use super::input::Window;
use super::report::LossComparison;

/// Most bands a width is chosen for.
const MAX_BANDS: f64 = 8.0;

/// Both logs' windows by distance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Bands {
    /// `None` when neither log had a window with a position.
    pub(crate) width_m: Option<f64>,
    pub(crate) a_windows: usize,
    pub(crate) b_windows: usize,
    /// Windows with no position in them: in no band.
    pub(crate) a_no_position: usize,
    pub(crate) b_no_position: usize,
    pub(crate) bands: Vec<Band>,
}

/// One band `[from_m, to_m)`: the windows whose last position was in it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub(crate) struct Band {
    pub(crate) from_m: f64,
    pub(crate) to_m: f64,
    pub(crate) a_windows: usize,
    pub(crate) b_windows: usize,
    pub(crate) loss: LossComparison,
}

/// The smallest of 10, 20, 50, 100, 200, 500 m ... that puts the farthest
/// window in the first `MAX_BANDS` bands: a handful of bands, on round
/// distances, the same for both logs.
pub(crate) fn auto_width(farthest_m: f64) -> f64 {
    let mut width = 10.0;
    let mut steps = [2.0, 2.5, 2.0].into_iter().cycle();
    while farthest_m / width >= MAX_BANDS && width.is_finite() {
        width *= steps.next().unwrap_or(2.0);
    }
    width
}

/// A band's distinct frames received and lost, summed over its windows.
#[derive(Debug, Clone, Copy, Default)]
struct Sum {
    windows: usize,
    received: u64,
    lost: i64,
}

impl Sum {
    /// Late frames can make a window's lost count negative; a band's is
    /// at least 0.
    fn lost_of(&self) -> (u64, u64) {
        let lost = self.lost.max(0).unsigned_abs();
        (lost, self.received.saturating_add(lost))
    }
}

/// Each band's sums for A and B, by the band's index: only bands a
/// window reached, however far (a map, not a vector as long as the
/// farthest band).
fn sums(a: &[Window], b: &[Window], width: f64) -> BTreeMap<u64, [Sum; 2]> {
    let mut sums: BTreeMap<u64, [Sum; 2]> = BTreeMap::new();
    for (side, windows) in [a, b].into_iter().enumerate() {
        for w in windows {
            if let Some(d) = w.distance_m {
                // A float to integer cast saturates: no distance overflows.
                let band = (d / width).floor().max(0.0) as u64;
                let sum = &mut sums.entry(band).or_default()[side];
                sum.windows += 1;
                sum.received = sum.received.saturating_add(w.received);
                sum.lost = sum.lost.saturating_add(w.lost);
            }
        }
    }
    sums
}

/// Both logs' windows in bands of `width_m` (or one chosen from the
/// farthest window), each band's loss compared; bands neither log
/// reached are left out.
pub(crate) fn compare_bands(a: &[Window], b: &[Window], width_m: Option<f64>) -> Bands {
    let no_position = |ws: &[Window]| ws.iter().filter(|w| w.distance_m.is_none()).count();
    let farthest = a
        .iter()
        .chain(b)
        .filter_map(|w| w.distance_m)
        .fold(None, |far: Option<f64>, d| {
            Some(far.map_or(d, |f| f.max(d)))
        });
    let mut out = Bands {
        width_m: None,
        a_windows: a.len(),
        b_windows: b.len(),
        a_no_position: no_position(a),
        b_no_position: no_position(b),
        bands: Vec::new(),
    };
    let Some(farthest) = farthest else {
        return out;
    };
    let width = width_m.unwrap_or_else(|| auto_width(farthest));
    for (i, [sa, sb]) in sums(a, b, width) {
        let (la, na) = sa.lost_of();
        let (lb, nb) = sb.lost_of();
        out.bands.push(Band {
            from_m: i as f64 * width,
            to_m: (i + 1) as f64 * width,
            a_windows: sa.windows,
            b_windows: sb.windows,
            loss: LossComparison::new(la, na, lb, nb),
        });
    }
    out.width_m = Some(width);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::report::Finding;

    fn w(received: u64, lost: i64, d: Option<f64>) -> Window {
        Window {
            received,
            lost,
            distance_m: d,
        }
    }

    #[test]
    fn widths_are_round_and_give_at_most_eight_bands() {
        assert_eq!(auto_width(0.0), 10.0);
        assert_eq!(auto_width(79.0), 10.0);
        assert_eq!(auto_width(80.0), 20.0);
        assert_eq!(auto_width(245.5), 50.0);
        assert_eq!(auto_width(399.0), 50.0);
        assert_eq!(auto_width(400.0), 100.0);
        assert_eq!(auto_width(3_000.0), 500.0);
        assert_eq!(auto_width(12_000.0), 2_000.0);
    }

    #[test]
    fn windows_fall_in_their_band_and_each_band_is_compared() {
        let a = [
            w(1000, 10, Some(5.0)),
            w(1000, 30, Some(120.0)),
            w(500, -2, Some(130.0)),
            w(100, 0, None),
        ];
        let b = [w(1000, 20, Some(9.9)), w(900, 100, Some(140.0))];
        let bands = compare_bands(&a, &b, Some(100.0));
        assert_eq!(bands.width_m, Some(100.0));
        assert_eq!((bands.a_no_position, bands.b_no_position), (1, 0));
        assert_eq!(bands.bands.len(), 2);
        let near = &bands.bands[0];
        assert_eq!(
            (near.from_m, near.to_m, near.a_windows, near.b_windows),
            (0.0, 100.0, 1, 1)
        );
        assert_eq!((near.loss.a.lost, near.loss.a.of), (10, 1010));
        let far = &bands.bands[1];
        // 30 - 2 lost of 1500 + 28 in A; 100 of 1000 in B.
        assert_eq!((far.loss.a.lost, far.loss.a.of), (28, 1528));
        assert_eq!((far.loss.b.lost, far.loss.b.of), (100, 1000));
        assert_eq!(far.loss.finding, Finding::BHigher);
    }

    #[test]
    fn bands_neither_log_reached_are_left_out_and_no_position_gives_none() {
        let bands = compare_bands(
            &[w(10, 0, Some(5.0))],
            &[w(10, 0, Some(305.0))],
            Some(100.0),
        );
        let froms: Vec<f64> = bands.bands.iter().map(|b| b.from_m).collect();
        assert_eq!(froms, [0.0, 300.0]);
        assert_eq!(bands.bands[0].loss.finding, Finding::NoData);
        // However far a window claims to be, one band holds it.
        let far = compare_bands(
            &[w(10, 0, Some(1e300))],
            &[w(u64::MAX, i64::MAX, Some(1e300))],
            None,
        );
        assert_eq!(far.bands.len(), 1);
        let none = compare_bands(&[w(10, 0, None)], &[], None);
        assert_eq!(none.width_m, None);
        assert!(none.bands.is_empty());
    }
}
