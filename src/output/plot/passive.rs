//! `--plot` of a passive run: each source's frames a second and its
//! sequence loss per time span, over time, and a legend of its figures
//! from the run's summary.
//!
//! Memory is constant, as for the RTT plot: each source keeps [`SPANS`]
//! time spans, the first a second wide (the table is told once a second);
//! when a window falls past the last span, every span doubles in width and
//! neighbours merge, so a long run is drawn at a coarser resolution, its
//! frames and losses summed, never dropped.

use super::data::SPANS;
use super::draw::{chart, line, lines, Marks, Points};
use super::frame::{self, Area, DrawResult, Entry, Legend, PlotError};
use super::spans::{Bins, Sums};
use crate::engine::summary::passive::{SeqCounts, SourceSummary};
use crate::engine::Nanos;
use crate::output::windows::Window;

/// Width of a span at the start: the table's telling.
const FIRST_SPAN_NS: Nanos = 1_000_000_000;
const RATE_H: u32 = 300;
const LOSS_H: u32 = 280;
const NUMBER_W: i32 = 100;

/// One source of a passive run, span by span.
#[derive(Debug, Clone)]
pub(super) struct SourceTrack {
    spans: Bins,
    /// The SiK radio's own RADIO_STATUS source.
    pub(super) radio: bool,
    /// The run's own figures for it, for the legend: known once the
    /// link's summary came.
    pub(super) summary: Option<SourceSummary>,
}

impl SourceTrack {
    pub(super) fn new(radio: bool) -> Self {
        SourceTrack {
            spans: Bins::new(FIRST_SPAN_NS as f64, 1e9, SPANS),
            radio,
            summary: None,
        }
    }

    /// Adds a window, in the span where it starts.
    pub(super) fn window(&mut self, w: &Window) {
        // A run that ended on a telling has nothing after it.
        if w.start == w.end && w.is_empty() {
            return;
        }
        self.spans.at(w.start as f64).window(w);
    }
}

pub(super) fn svg(title: &str, entries: &[Entry<'_, SourceTrack>]) -> Result<String, PlotError> {
    let rows = frame::rows(entries, |t| {
        let s = t.summary.as_ref();
        let count = |n: fn(&SeqCounts) -> u64| s.map(|s| n(&s.counts).to_string());
        vec![
            count(|c| c.received),
            count(|c| c.lost),
            s.and_then(|s| s.loss_pct).map(|v| format!("{v:.2}")),
            count(|c| c.duplicate),
            count(|c| c.reordered),
            s.and_then(|s| s.frames_per_s).map(|v| format!("{v:.1}")),
        ]
    });
    let legend = Legend {
        heads: (
            "source",
            &["received", "lost", "loss %", "dup", "reordered", "frames/s"],
        ),
        number_w: NUMBER_W,
        rows,
        empty: "nothing heard",
    };
    frame::page(title, &legend, &[RATE_H, LOSS_H], |areas| {
        let t_max = entries
            .iter()
            .map(|e| e.track.spans.end())
            .fold(1.0, f64::max);
        rate_chart(entries, &areas[0], t_max)?;
        loss_chart(entries, &areas[1], t_max)
    })
}

/// The highest of `lines`, 1 at least.
fn top(lines: &[Points]) -> f64 {
    lines.iter().flatten().map(|p| p.1).fold(1.0f64, f64::max)
}

/// Each source's frames a second per span, one line each.
fn rate_chart(entries: &[Entry<'_, SourceTrack>], area: &Area<'_>, t_max: f64) -> DrawResult {
    let lines = lines(entries, |t| t.spans.points(Sums::frames_per_s));
    let (x, y) = (0f64..t_max, 0f64..top(&lines) * 1.08);
    let descs = (None, "frames/s");
    let mut chart = chart(area, "frames a second, by source", descs, x, y)?;
    for (k, (e, points)) in entries.iter().zip(&lines).enumerate() {
        let marks = Marks::Spread(k, entries.len());
        line(&mut chart, &e.look, points, marks)?;
    }
    Ok(())
}

/// Each source's sequence loss per span, a line each with its marker where
/// a span lost frames; it carries the time axis.
fn loss_chart(entries: &[Entry<'_, SourceTrack>], area: &Area<'_>, t_max: f64) -> DrawResult {
    let lines = lines(entries, |t| t.spans.points(Sums::loss_pct));
    let caption = "sequence loss per span (marker: a span that lost frames)";
    let descs = (Some("time since start (s)"), "lost (%)");
    let mut chart = chart(area, caption, descs, 0f64..t_max, 0f64..top(&lines) * 1.1)?;
    for (e, points) in entries.iter().zip(&lines) {
        line(&mut chart, &e.look, points, Marks::Lost)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::SysComp;

    fn second(n: u64, received: u64, lost: i64) -> Window {
        Window {
            source: SysComp::new(1, 1),
            radio: false,
            start: n * FIRST_SPAN_NS,
            end: (n + 1) * FIRST_SPAN_NS,
            received,
            lost,
            duplicate: 0,
            reordered: 0,
            bytes: 0,
        }
    }

    #[test]
    fn a_long_run_merges_spans_and_keeps_every_frame() {
        let mut t = SourceTrack::new(false);
        // A day at 50 frames a second, one lost every tenth second.
        let day = 86_400;
        for n in 0..day {
            t.window(&second(n, 50, i64::from(n % 10 == 0)));
        }
        assert!(t.spans.bins.len() <= SPANS, "{}", t.spans.bins.len());
        assert_eq!(
            t.spans.bins.iter().map(|s| s.received).sum::<u64>(),
            50 * day
        );
        assert_eq!(t.spans.bins.iter().map(|s| s.lost).sum::<i64>(), 8_640);
        let covered: Nanos = t.spans.bins.iter().map(|s| s.covered_ns).sum();
        assert_eq!(covered, day * FIRST_SPAN_NS);
        // 128 s a span now: each still at 50 a second; the fourth, seconds
        // 384 to 511, lost 13 (390, 400, ... 510).
        assert_eq!(t.spans.width, (128 * FIRST_SPAN_NS) as f64);
        let fourth = &t.spans.bins[3];
        assert_eq!(fourth.frames_per_s(), Some(50.0));
        assert_eq!(fourth.loss_pct(), Some(100.0 * 13.0 / (13.0 + 6_400.0)));
    }

    #[test]
    fn the_svg_has_a_line_per_source_and_the_summary_in_its_legend() {
        use crate::engine::probe::passive::tracker::{SourceTable, RADIO_SOURCE};
        use crate::output::windows::Windows;
        let plot = super::super::Plot::default();
        let mut link = plot.link();
        plot.data.borrow_mut().links[0] = "sim:".into();
        link.windows = Some(Windows::default());
        let mut table = SourceTable::new(None, 32);
        let ms = 1_000_000;
        for second in 0..20u64 {
            for k in 0..50u64 {
                let seq = (second * 50 + k) as u8;
                if k != 7 {
                    table.on_frame(
                        SysComp::new(1, 1),
                        seq,
                        30,
                        40,
                        (second * 1_000 + k * 20) * ms,
                    );
                }
            }
            table.on_frame(
                RADIO_SOURCE,
                second as u8,
                109,
                38,
                (second * 1_000 + 500) * ms,
            );
            let at = (second + 1) * 1_000 * ms;
            link.windows(at, &table.summary(at));
        }
        let svg = plot.svg().unwrap();
        for text in [
            "mavping --passive sim:",
            "1/1",
            "51/68 (radio)",
            "frames a second",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        // Before the summary, the figures are unknown, not made up.
        assert!(svg.contains("\n-\n"), "no placeholder");
        assert!(svg.matches("<polyline").count() >= 4);

        let summary = table.summary(20_000 * ms);
        plot.data.borrow_mut().on_sources(0, &summary);
        let svg = plot.svg().unwrap();
        // 980 frames, 20 lost: 2.00 %; 979 in the 19.98 s after the first.
        for text in ["980", "20", "2.00", "49.0", "received", "reordered"] {
            assert!(svg.contains(&format!("\n{text}\n")), "{text} missing");
        }
        assert!(!svg.contains("\n-\n"), "a figure is missing");
    }

    #[test]
    fn a_late_frame_in_the_next_span_does_not_plot_below_zero() {
        let mut t = SourceTrack::new(false);
        t.window(&second(0, 49, 1));
        t.window(&second(1, 51, -1));
        assert_eq!(t.spans.bins[1].loss_pct(), Some(0.0));
        // Merged, the two add up.
        for n in 2..SPANS as u64 * 2 {
            t.window(&second(n, 50, 0));
        }
        assert_eq!(t.spans.bins[0].lost, 0);
        assert_eq!(t.spans.bins[0].received, 100);
    }
}
