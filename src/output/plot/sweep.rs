//! `--plot` of a sweep: each link's RTT p50 and p99 and its loss against
//! the offered rate, with its knee marked, and a legend of the knees. The
//! steps come from the run's summary, so the picture shows exactly the
//! figures the text and JSON reports give.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::draw::{
    caption_font, fit, legend_font, log_ticks, mesh, text_width, title_font, DrawResult, FONT,
    MARGIN, TITLE_SIZE, WIDTH, Y_LABELS_W,
};
use super::style::Look;
use crate::engine::sweep::step::StepFigures;
use crate::engine::sweep::verdict::SweepSummary;

const TITLE_H: u32 = 44;
const RTT_H: u32 = 340;
const LOSS_H: u32 = 230;
const ROW_H: u32 = 26;
const NUMBER_W: i32 = 130;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// One link's sweep, in drawing order.
pub(super) struct SweepEntry<'a> {
    pub label: String,
    pub look: Look,
    pub sweep: &'a SweepSummary,
}

impl SweepEntry<'_> {
    /// The sweep's complete steps, by offered rate.
    fn points(&self) -> Vec<&StepFigures> {
        let mut steps: Vec<&StepFigures> = self
            .sweep
            .steps
            .iter()
            .filter(|s| s.phase.sweeps() && s.complete)
            .collect();
        steps.sort_by(|a, b| a.offered_hz.total_cmp(&b.offered_hz));
        steps
    }
}

pub(super) fn svg(title: &str, entries: &[SweepEntry<'_>]) -> Result<String, String> {
    let label_w = entries
        .iter()
        .map(|e| e.label.as_str())
        .chain(["link"])
        .map(|l| text_width(l, legend_font()))
        .max()
        .unwrap_or(0);
    let numbers_x = 70 + label_w as i32 + 20;
    let width = WIDTH.max((numbers_x + 4 * NUMBER_W + 30) as u32);
    let title_size = fit(title, TITLE_SIZE, width - 2 * MARGIN);
    let width = width.max(text_width(title, title_font(title_size)) + 2 * MARGIN);
    let rows = entries.len().max(1) as u32;
    let height = TITLE_H + RTT_H + LOSS_H + ROW_H * (rows + 1) + 20;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        draw((title, title_size), entries, &root, numbers_x).map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

fn draw(
    (title, title_size): (&str, f64),
    entries: &[SweepEntry<'_>],
    root: &Area<'_>,
    numbers_x: i32,
) -> DrawResult {
    root.fill(&WHITE)?;
    let (head, rest) = root.split_vertically(TITLE_H);
    head.draw(&Text::new(
        title,
        (MARGIN as i32, TITLE_H as i32 / 2),
        title_font(title_size)
            .into_text_style(root)
            .pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    let (rtt, rest) = rest.split_vertically(RTT_H);
    let (loss, legend) = rest.split_vertically(LOSS_H);
    let rates: Vec<f64> = entries
        .iter()
        .flat_map(|e| e.points().into_iter().map(|s| s.offered_hz))
        .collect();
    let lo = rates.iter().copied().reduce(f64::min).unwrap_or(1.0);
    let hi = rates.iter().copied().reduce(f64::max).unwrap_or(100.0);
    // A little room either side, so no marker sits on the frame.
    let (from, to) = (lo / 1.15, (hi * 1.15).max(lo * 2.0));
    rtt_chart(entries, &rtt, (from, to))?;
    loss_chart(entries, &loss, (from, to))?;
    legend_table(entries, &legend, numbers_x)?;
    root.present()?;
    Ok(())
}

/// p99 as a solid line and p50 dashed, on log axes; the knee as a
/// vertical rule with its rate.
fn rtt_chart(entries: &[SweepEntry<'_>], area: &Area<'_>, (from, to): (f64, f64)) -> DrawResult {
    let rtts: Vec<f64> = entries
        .iter()
        .flat_map(|e| e.points())
        .filter_map(|s| s.rtt)
        .flat_map(|r| [r.p50_us / 1e3, r.p99_us / 1e3])
        .collect();
    let low = rtts.iter().copied().reduce(f64::min).unwrap_or(1.0) / 1.2;
    let high = rtts.iter().copied().reduce(f64::max).unwrap_or(100.0) * 1.2;
    let high = high.max(low * 4.0);
    let mut chart = ChartBuilder::on(area)
        .caption(
            "RTT against offered rate (solid: p99, dashed: p50)",
            caption_font(),
        )
        .margin(MARGIN)
        .margin_bottom(0)
        .x_label_area_size(0)
        .y_label_area_size(Y_LABELS_W)
        .build_cartesian_2d(
            (from..to).log_scale().with_key_points(log_ticks(from, to)),
            (low..high)
                .log_scale()
                .with_key_points(log_ticks(low, high)),
        )?;
    mesh(&mut chart).y_desc("RTT (ms, log scale)").draw()?;
    for e in entries {
        let points = e.points();
        let p99: Vec<(f64, f64)> = points
            .iter()
            .filter_map(|s| Some((s.offered_hz, s.rtt?.p99_us / 1e3)))
            .collect();
        let p50: Vec<(f64, f64)> = points
            .iter()
            .filter_map(|s| Some((s.offered_hz, s.rtt?.p50_us / 1e3)))
            .collect();
        chart.draw_series(LineSeries::new(
            p99.iter().copied(),
            e.look.color.stroke_width(2),
        ))?;
        chart.draw_series(DashedLineSeries::new(
            p50.iter().copied(),
            6,
            4,
            e.look.color.stroke_width(1),
        ))?;
        for &p in p99.iter().chain(&p50) {
            chart.plotting_area().draw(&e.look.marker(p, 4))?;
        }
        if let Some(k) = &e.sweep.knee {
            let rule = [(k.rate_hz, low), (k.rate_hz, high)];
            chart.draw_series(DashedLineSeries::new(
                rule,
                3,
                3,
                e.look.color.stroke_width(1),
            ))?;
            chart.plotting_area().draw(&Text::new(
                format!("knee {:.0}/s", k.rate_hz),
                (k.rate_hz, high / 1.1),
                (FONT, 15)
                    .into_font()
                    .color(&e.look.color)
                    .pos(Pos::new(HPos::Right, VPos::Top)),
            ))?;
        }
    }
    Ok(())
}

/// Each step's loss, on the same rate axis.
fn loss_chart(entries: &[SweepEntry<'_>], area: &Area<'_>, (from, to): (f64, f64)) -> DrawResult {
    let top = entries
        .iter()
        .flat_map(|e| e.points())
        .map(|s| s.loss_ratio * 100.0)
        .fold(5.0f64, f64::max);
    let mut chart = ChartBuilder::on(area)
        .caption("loss against offered rate", caption_font())
        .margin(MARGIN)
        .x_label_area_size(44)
        .y_label_area_size(Y_LABELS_W)
        .build_cartesian_2d(
            (from..to).log_scale().with_key_points(log_ticks(from, to)),
            0f64..top * 1.1,
        )?;
    mesh(&mut chart)
        .x_desc("offered rate (requests/s, log scale)")
        .y_desc("loss (%)")
        .draw()?;
    for e in entries {
        let line: Vec<(f64, f64)> = e
            .points()
            .iter()
            .map(|s| (s.offered_hz, s.loss_ratio * 100.0))
            .collect();
        chart.draw_series(LineSeries::new(
            line.iter().copied(),
            e.look.color.stroke_width(2),
        ))?;
        for &p in &line {
            chart.plotting_area().draw(&e.look.marker(p, 4))?;
        }
    }
    Ok(())
}

/// A row per link: its knee (rate and bytes per second), the first step's
/// p99 it was judged against, and whether it queues before it drops.
fn legend_table(entries: &[SweepEntry<'_>], area: &Area<'_>, numbers_x: i32) -> DrawResult {
    let font = legend_font();
    let left = font
        .clone()
        .into_text_style(area)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let right = font
        .into_text_style(area)
        .pos(Pos::new(HPos::Right, VPos::Center));
    let bold = legend_font().style(FontStyle::Bold).into_text_style(area);
    let row_y = |r: usize| ROW_H as i32 * r as i32 + ROW_H as i32 / 2 + 4;
    let column = |j: i32| numbers_x + NUMBER_W * (j + 1);
    area.draw(&Text::new(
        "link",
        (70, row_y(0)),
        bold.clone().pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    for (j, name) in ["knee /s", "knee B/s", "first p99 ms", "bufferbloat"]
        .into_iter()
        .enumerate()
    {
        area.draw(&Text::new(
            name,
            (column(j as i32), row_y(0)),
            bold.clone().pos(Pos::new(HPos::Right, VPos::Center)),
        ))?;
    }
    let rule = row_y(0) + ROW_H as i32 / 2;
    area.draw(&PathElement::new(
        [(MARGIN as i32, rule), (column(3), rule)],
        BLACK.stroke_width(1),
    ))?;
    for (r, e) in entries.iter().enumerate() {
        let y = row_y(r + 1);
        area.draw(&PathElement::new(
            [(18, y), (58, y)],
            e.look.color.stroke_width(2),
        ))?;
        area.draw(&e.look.marker((38, y), 5))?;
        area.draw(&Text::new(e.label.as_str(), (70, y), left.clone()))?;
        let s = e.sweep;
        let cells = [
            s.knee.map(|k| format!("{:.1}", k.rate_hz)),
            s.knee.map(|k| format!("{:.0}", k.bytes_per_s)),
            s.reference_p99_us.map(|p| format!("{:.3}", p / 1e3)),
            s.queueing
                .map(|q| if q.bufferbloat { "yes" } else { "no" }.to_string()),
        ];
        for (j, cell) in cells.into_iter().enumerate() {
            let text = cell.unwrap_or_else(|| "-".into());
            area.draw(&Text::new(text, (column(j as i32), y), right.clone()))?;
        }
    }
    Ok(())
}
