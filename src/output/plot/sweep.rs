//! `--plot` of a sweep: each link's RTT p50 and p99 and its loss against
//! the offered rate, with its knee marked, and a legend of the knees. The
//! steps come from the run's summary, so the picture shows exactly the
//! figures the text and JSON reports give.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::draw::{axis_font, chart, log_axis};
use super::frame::{self, Area, DrawResult, Entry, Legend, PlotError};
use crate::engine::sweep::step::{StepFigures, StepRtt};
use crate::engine::sweep::verdict::SweepSummary;

const RTT_H: u32 = 340;
const LOSS_H: u32 = 230;
const NUMBER_W: i32 = 130;

/// Each link's sweep, in drawing order.
type Sweeps<'a> = [Entry<'a, SweepSummary>];

/// A sweep's complete steps, by offered rate.
fn points(sweep: &SweepSummary) -> Vec<&StepFigures> {
    let mut steps: Vec<&StepFigures> = sweep
        .steps
        .iter()
        .filter(|s| s.phase.sweeps() && s.complete)
        .collect();
    steps.sort_by(|a, b| a.offered_hz.total_cmp(&b.offered_hz));
    steps
}

/// A legend row per link: its knee (rate and bytes per second), the first
/// step's p99 it was judged against, and its queueing grade (A+ to F, as
/// the bufferbloat tests grade added latency).
pub(super) fn svg(title: &str, entries: &Sweeps<'_>) -> Result<String, PlotError> {
    let rows = frame::rows(entries, |s| {
        vec![
            s.knee.map(|k| format!("{:.1}", k.rate_hz)),
            s.knee.map(|k| format!("{:.0}", k.bytes_per_s)),
            s.reference_p99_us.map(|p| format!("{:.3}", p / 1e3)),
            s.queueing.map(|q| {
                let bloat = if q.bufferbloat { ", bufferbloat" } else { "" };
                format!("{}{bloat}", q.grade.as_str())
            }),
        ]
    });
    let legend = Legend {
        heads: ("link", &["knee /s", "knee B/s", "first p99 ms", "queueing"]),
        number_w: NUMBER_W,
        rows,
        empty: "no sweep",
    };
    frame::page(title, &legend, &[RTT_H, LOSS_H], |areas| {
        let rates: Vec<f64> = entries
            .iter()
            .flat_map(|e| points(e.track).into_iter().map(|s| s.offered_hz))
            .collect();
        let lo = rates.iter().copied().reduce(f64::min).unwrap_or(1.0);
        let hi = rates.iter().copied().reduce(f64::max).unwrap_or(100.0);
        // A little room either side, so no marker sits on the frame.
        let (from, to) = (lo / 1.15, (hi * 1.15).max(lo * 2.0));
        rtt_chart(entries, &areas[0], (from, to))?;
        loss_chart(entries, &areas[1], (from, to))
    })
}

/// p99 as a solid line and p50 dashed, on log axes; the knee as a
/// vertical rule with its rate.
fn rtt_chart(entries: &Sweeps<'_>, area: &Area<'_>, (from, to): (f64, f64)) -> DrawResult {
    let rtts: Vec<f64> = entries
        .iter()
        .flat_map(|e| points(e.track))
        .filter_map(|s| s.rtt)
        .flat_map(|r| [r.p50_us / 1e3, r.p99_us / 1e3])
        .collect();
    let low = rtts.iter().copied().reduce(f64::min).unwrap_or(1.0) / 1.2;
    let high = rtts.iter().copied().reduce(f64::max).unwrap_or(100.0) * 1.2;
    let high = high.max(low * 4.0);
    let caption = "RTT against offered rate (solid: p99, dashed: p50)";
    let (x, y) = (log_axis(from, to), log_axis(low, high));
    let mut chart = chart(area, caption, (None, "RTT (ms, log scale)"), x, y)?;
    for e in entries {
        let rtt = |f: fn(&StepRtt) -> f64| -> Vec<(f64, f64)> {
            let steps = points(e.track).into_iter();
            steps
                .filter_map(|s| Some((s.offered_hz, f(&s.rtt?) / 1e3)))
                .collect()
        };
        let (p99, p50) = (rtt(|r| r.p99_us), rtt(|r| r.p50_us));
        let (solid, thin) = (e.look.color.stroke_width(2), e.look.color.stroke_width(1));
        chart.draw_series(LineSeries::new(p99.iter().copied(), solid))?;
        chart.draw_series(DashedLineSeries::new(p50.iter().copied(), 6, 4, thin))?;
        for &p in p99.iter().chain(&p50) {
            chart.plotting_area().draw(&e.look.marker(p, 4))?;
        }
        if let Some(k) = &e.track.knee {
            let rule = [(k.rate_hz, low), (k.rate_hz, high)];
            chart.draw_series(DashedLineSeries::new(rule, 3, 3, thin))?;
            chart.plotting_area().draw(&Text::new(
                format!("knee {:.0}/s", k.rate_hz),
                (k.rate_hz, high / 1.1),
                axis_font()
                    .color(&e.look.color)
                    .pos(Pos::new(HPos::Right, VPos::Top)),
            ))?;
        }
    }
    Ok(())
}

/// Each step's loss, on the same rate axis.
fn loss_chart(entries: &Sweeps<'_>, area: &Area<'_>, (from, to): (f64, f64)) -> DrawResult {
    let top = entries
        .iter()
        .flat_map(|e| points(e.track))
        .map(|s| s.loss_ratio * 100.0)
        .fold(5.0f64, f64::max);
    let descs = (Some("offered rate (requests/s, log scale)"), "loss (%)");
    let (x, y) = (log_axis(from, to), 0f64..top * 1.1);
    let mut chart = chart(area, "loss against offered rate", descs, x, y)?;
    for e in entries {
        let line: Vec<(f64, f64)> = points(e.track)
            .iter()
            .map(|s| (s.offered_hz, s.loss_ratio * 100.0))
            .collect();
        let solid = e.look.color.stroke_width(2);
        chart.draw_series(LineSeries::new(line.iter().copied(), solid))?;
        for &p in &line {
            chart.plotting_area().draw(&e.look.marker(p, 4))?;
        }
    }
    Ok(())
}
