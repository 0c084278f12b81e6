//! Draws the plot from the collected samples: RTT over time, a row of lost
//! requests per responder under it, the RTT distribution, and a legend
//! table (responder, sent, loss %, p50, p99) in a band of its own below the
//! charts, so nothing is ever drawn under it. Each responder keeps one
//! colour and one marker shape ([`Look`]) everywhere.

use plotters::chart::MeshStyle;
use plotters::coord::combinators::WithKeyPoints;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::data::{bin, bin_low_ms, Track, BINS_PER_DECADE};
use super::frame::{self, Area, DrawResult, Entry, Legend, PlotError, FONT, MARGIN};
use super::spans::Sums;
use super::style::Look;
use crate::engine::Nanos;

const TIME_H: u32 = 300;
/// Height of one responder's row of lost requests.
const LANE_H: u32 = 24;
/// The lost-requests chart besides its rows: the time axis and its labels.
const LANES_AXIS_H: u32 = 66;
const DIST_H: u32 = 270;
/// Room for the y axis labels, the same for every chart so their time and
/// RTT axes line up.
pub(super) const Y_LABELS_W: u32 = 70;
/// Width of a number column in the legend.
const NUMBER_W: i32 = 110;
/// Markers along a line of RTT over time.
const MARKS_PER_LINE: usize = 12;

/// An axis label without trailing zeros: `10`, `2.5`, `0.125`.
fn tick(v: &f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Ticks for a log axis from `from` to `to`: 1, 2, 5 (or 1, 2, 3, 5)
/// times the powers of ten inside it; a range too narrow for four of those
/// gets evenly spaced ticks, as a linear axis would.
pub(super) fn log_ticks(from: f64, to: f64) -> Vec<f64> {
    let within = |steps: &[f64]| -> Vec<f64> {
        let first = from.log10().floor() as i32;
        let last = to.log10().ceil() as i32;
        (first..=last)
            .flat_map(|e| steps.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|v| (from..=to).contains(v))
            .collect()
    };
    for steps in [&[1.0, 2.0, 5.0][..], &[1.0, 2.0, 3.0, 5.0]] {
        let ticks = within(steps);
        if ticks.len() >= 4 {
            return ticks;
        }
    }
    // About six ticks (five to eight), a step of 1, 2 or 5 times a power
    // of ten.
    let rough = (to - from) / 6.0;
    let power = 10f64.powf(rough.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|&s| s >= rough * 0.75)
        .unwrap_or(10.0 * power);
    let first = (from / step).ceil() as i64;
    let last = (to / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A log axis from `from` to `to` with round ticks.
pub(super) fn log_axis(from: f64, to: f64) -> WithKeyPoints<LogCoord<f64>> {
    (from..to).log_scale().with_key_points(log_ticks(from, to))
}

pub(super) fn svg(title: &str, entries: &[Entry<'_, Track>]) -> Result<String, PlotError> {
    let rows = frame::rows(entries, |t| {
        let r = t.summary.as_ref();
        let rtt = r.and_then(|r| r.rtt);
        vec![
            r.map(|r| r.counts.sent.to_string()),
            r.map(|r| format!("{:.2}", 100.0 * r.loss_ratio)),
            rtt.map(|s| format!("{:.3}", s.p50_us / 1e3)),
            rtt.map(|s| format!("{:.3}", s.p99_us / 1e3)),
        ]
    });
    let legend = Legend {
        heads: ("responder", &["sent", "loss %", "p50 ms", "p99 ms"]),
        number_w: NUMBER_W,
        rows,
        empty: "no responder answered",
    };
    let lanes = LANE_H * entries.len().max(1) as u32 + LANES_AXIS_H;
    frame::page(title, &legend, &[TIME_H, lanes, DIST_H], |areas| {
        let t_max = entries
            .iter()
            .map(|e| e.track.spans.end())
            .reduce(f64::max)
            .unwrap_or(1.0);
        over_time(entries, &areas[0], t_max)?;
        losses(entries, &areas[1], t_max)?;
        distribution_chart(entries, &areas[2])
    })
}

pub(super) fn axis_font() -> TextStyle<'static> {
    (FONT, 15).into()
}

pub(super) fn caption_font() -> TextStyle<'static> {
    (FONT, 19).into()
}

/// Each responder's mean RTT per span, one line each.
fn over_time(entries: &[Entry<'_, Track>], area: &Area<'_>, t_max: f64) -> DrawResult {
    let lines = lines(entries, |t| t.spans.points(Sums::mean_rtt_ms));
    let rtt_max = lines.iter().flatten().map(|p| p.1).reduce(f64::max);
    let rtt_max = rtt_max.unwrap_or(1.0);
    let (x, y) = (0f64..t_max, 0f64..rtt_max * 1.08);
    let mut chart = chart(area, "RTT over time", (None, "RTT (ms)"), x, y)?;
    for (k, (e, points)) in entries.iter().zip(&lines).enumerate() {
        let marks = Marks::Spread(k, entries.len());
        line(&mut chart, &e.look, points, marks)?;
    }
    Ok(())
}

/// A chart on `area` with `caption`, its grid and axes drawn, the axes
/// named `x_desc` and `y_desc`. Without an `x_desc` it has no x labels
/// and sits on the chart below it, whose time axis it shares.
pub(super) fn chart<'a, X, Y>(
    area: &Area<'a>,
    caption: &str,
    (x_desc, y_desc): (Option<&str>, &str),
    x: X,
    y: Y,
) -> Result<Chart<'a, X::CoordDescType, Y::CoordDescType>, Box<dyn std::error::Error>>
where
    X: AsRangedCoord<CoordDescType: Axis>,
    Y: AsRangedCoord<CoordDescType: Axis>,
{
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(caption, caption_font())
        .margin(MARGIN)
        .y_label_area_size(Y_LABELS_W);
    match x_desc {
        Some(_) => builder.x_label_area_size(44),
        None => builder.margin_bottom(0).x_label_area_size(0),
    };
    let mut chart = builder.build_cartesian_2d(x, y)?;
    let mut mesh = mesh(&mut chart);
    if let Some(x_desc) = x_desc {
        mesh.x_desc(x_desc);
    }
    mesh.y_desc(y_desc).draw()?;
    Ok(chart)
}

/// A line's points, (x, y).
pub(super) type Points = Vec<(f64, f64)>;

pub(super) type Chart<'a, X, Y> = ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>;

/// An axis of every chart: of `f64`s, with labels.
pub(super) trait Axis: Ranged<ValueType = f64> + ValueFormatter<f64> {}

impl<T: Ranged<ValueType = f64> + ValueFormatter<f64>> Axis for T {}

/// Each entry's line, by `points`.
pub(super) fn lines<T>(entries: &[Entry<'_, T>], points: impl Fn(&T) -> Points) -> Vec<Points> {
    entries.iter().map(|e| points(e.track)).collect()
}

/// Where a line's markers go.
pub(super) enum Marks {
    /// A few along it, staggered as the `k`-th of `n` lines', so that the
    /// lines tell apart without their colour.
    Spread(usize, usize),
    /// Where its value is above 0: a span that lost.
    Lost,
}

/// `points` as a line in `look`'s colour, with its markers at `marks`.
pub(super) fn line<X: Axis, Y: Axis>(
    chart: &mut Chart<'_, X, Y>,
    look: &Look,
    points: &[(f64, f64)],
    marks: Marks,
) -> DrawResult {
    let style = look.color.mix(0.85).stroke_width(2);
    chart.draw_series(LineSeries::new(points.iter().copied(), style))?;
    let marked: Vec<(f64, f64)> = match marks {
        Marks::Spread(k, n) => {
            let every = (points.len() / MARKS_PER_LINE).max(1);
            let spread = points.iter().skip(k * every / n).step_by(every);
            spread.copied().collect()
        }
        Marks::Lost => points.iter().filter(|p| p.1 > 0.0).copied().collect(),
    };
    for p in marked {
        chart.plotting_area().draw(&look.marker(p, 5))?;
    }
    Ok(())
}

/// The grid and axes every chart shares: its fonts, round tick labels, few
/// and faint minor lines.
fn mesh<'a, 'b, X: Axis, Y: Axis>(
    chart: &'b mut Chart<'a, X, Y>,
) -> MeshStyle<'a, 'b, X, Y, SVGBackend<'a>> {
    let mut mesh = chart.configure_mesh();
    mesh.label_style(axis_font())
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .axis_desc_style(axis_font())
        .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
        .max_light_lines(1);
    mesh
}

/// A row per responder, in legend order, with its marker where a span lost
/// a request; it carries the time axis of the chart above.
fn losses(entries: &[Entry<'_, Track>], area: &Area<'_>, t_max: f64) -> DrawResult {
    let n = entries.len().max(1);
    let mut chart = ChartBuilder::on(area)
        .margin(MARGIN)
        .margin_top(4)
        .x_label_area_size(44)
        .y_label_area_size(Y_LABELS_W)
        .build_cartesian_2d(0f64..t_max, -0.6f64..n as f64 - 0.4)?;
    mesh(&mut chart)
        .disable_y_mesh()
        .y_labels(0)
        .x_desc("time since start (s)")
        .draw()?;
    let lane = |k: usize| (n - 1 - k) as f64;
    for (k, e) in entries.iter().enumerate() {
        let guide = [(0.0, lane(k)), (t_max, lane(k))];
        chart.draw_series(LineSeries::new(guide, RGBColor(0xDD, 0xDD, 0xDD)))?;
        for (x, _) in e.track.spans.each().filter(|(_, s)| s.lost > 0) {
            let mark = e.look.marker((x, lane(k)), 5);
            chart.plotting_area().draw(&mark)?;
        }
    }
    // The rows' name, where the other charts have their y axis title.
    let (xs, ys) = chart.plotting_area().get_pixel_range();
    let (ox, oy) = area.get_base_pixel();
    let at = (xs.start - ox - 12, ys.start.midpoint(ys.end) - oy);
    let font = axis_font().pos(Pos::new(HPos::Right, VPos::Center));
    area.draw(&Text::new("lost", at, font))?;
    Ok(())
}

/// Each responder's share of replies per RTT bin, as a step outline so
/// several stay readable overlaid.
fn distribution_chart(entries: &[Entry<'_, Track>], area: &Area<'_>) -> DrawResult {
    let used: Vec<usize> = entries
        .iter()
        .flat_map(|e| e.track.bins.iter().enumerate().filter(|(_, &c)| c > 0))
        .map(|(i, _)| i)
        .collect();
    // Without replies, 1 to 100 ms: an empty chart with sensible ticks.
    let lo = used.iter().min().copied().unwrap_or(2 * BINS_PER_DECADE);
    let hi = used.iter().max().map_or(4 * BINS_PER_DECADE, |i| i + 1);
    let share = |t: &Track, i: usize| {
        let total: u64 = t.bins.iter().sum();
        100.0 * t.bins[i] as f64 / total.max(1) as f64
    };
    let top_share = entries
        .iter()
        .flat_map(|e| (lo..hi).map(move |i| share(e.track, i)))
        .fold(1.0f64, f64::max);
    // A bin of room either side, so no outline sits on the frame.
    let (from, to) = (bin_low_ms(lo.saturating_sub(1)), bin_low_ms(hi + 1));
    let x = log_axis(from, to);
    let descs = (Some("RTT (ms, log scale: each bin 4% wide)"), "replies (%)");
    let caption = "RTT distribution (marker: median)";
    let mut chart = chart(area, caption, descs, x, 0f64..top_share * 1.1)?;
    for e in entries {
        let t = e.track;
        let mut steps = vec![(bin_low_ms(lo), 0.0)];
        for i in lo..hi {
            steps.push((bin_low_ms(i), share(t, i)));
            steps.push((bin_low_ms(i + 1), share(t, i)));
        }
        steps.push((bin_low_ms(hi), 0.0));
        chart.draw_series(LineSeries::new(steps, e.look.color.stroke_width(2)))?;
        if let Some(rtt) = t.summary.as_ref().and_then(|r| r.rtt) {
            let p50 = rtt.p50_us / 1e3;
            let i = bin((p50 * 1e6) as Nanos).clamp(lo, hi - 1);
            chart
                .plotting_area()
                .draw(&e.look.marker((p50, share(t, i)), 6))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_round_and_within_the_range() {
        assert_eq!(
            log_ticks(0.9, 120.0),
            [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
        );
        assert_eq!(log_ticks(19.2, 160.0), [20.0, 30.0, 50.0, 100.0]);
        assert_eq!(log_ticks(19.2, 31.6), [20.0, 22.0, 24.0, 26.0, 28.0, 30.0]);
    }

    #[test]
    fn tick_labels_have_no_trailing_zeros() {
        assert_eq!(tick(&10.0), "10");
        assert_eq!(tick(&2.5), "2.5");
        assert_eq!(tick(&0.125), "0.125");
    }
}
