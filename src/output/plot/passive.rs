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
use super::draw::{chart, line, Marks};
use super::frame::{self, Area, DrawResult, Entry, Legend, PlotError};
use crate::engine::summary::passive::SourceSummary;
use crate::engine::Nanos;
use crate::output::windows::Window;

/// Width of a span at the start: the table's telling.
const FIRST_SPAN_NS: Nanos = 1_000_000_000;
const RATE_H: u32 = 300;
const LOSS_H: u32 = 280;
const NUMBER_W: i32 = 100;

/// One time span of a source: its windows summed.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Span {
    received: u64,
    /// Distinct frames (received less duplicates).
    distinct: u64,
    /// Signed: a late frame moves a loss from an earlier span to this one's
    /// reordered (see [`Window::lost`]).
    lost: i64,
    /// Time the windows in it covered (the last one is partial).
    covered_ns: Nanos,
}

impl Span {
    fn merge(self, other: Span) -> Span {
        Span {
            received: self.received + other.received,
            distinct: self.distinct + other.distinct,
            lost: self.lost + other.lost,
            covered_ns: self.covered_ns + other.covered_ns,
        }
    }

    fn frames_per_s(&self) -> Option<f64> {
        (self.covered_ns > 0).then(|| self.received as f64 * 1e9 / self.covered_ns as f64)
    }

    /// `100 * lost / (lost + distinct)`; `None` with nothing to compare.
    fn loss_pct(&self) -> Option<f64> {
        let lost = self.lost.max(0) as f64;
        let whole = lost + self.distinct as f64;
        (whole > 0.0).then(|| 100.0 * lost / whole)
    }
}

/// A source's figures from the run's summary, shown in the legend.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Figures {
    received: u64,
    lost: u64,
    loss_pct: Option<f64>,
    duplicate: u64,
    reordered: u64,
    frames_per_s: Option<f64>,
}

/// One source of a passive run, span by span.
#[derive(Debug, Clone)]
pub(super) struct SourceTrack {
    span_ns: Nanos,
    spans: Vec<Span>,
    radio: bool,
    /// Known once the link's summary came.
    figures: Option<Figures>,
}

impl SourceTrack {
    pub(super) fn new(radio: bool) -> Self {
        SourceTrack {
            span_ns: FIRST_SPAN_NS,
            spans: Vec::new(),
            radio,
            figures: None,
        }
    }

    /// Adds a window, in the span where it starts.
    pub(super) fn window(&mut self, w: &Window) {
        // A run that ended on a telling has nothing after it.
        if w.start == w.end && w.is_empty() {
            return;
        }
        while w.start / self.span_ns >= SPANS as u64 {
            self.spans = self
                .spans
                .chunks(2)
                .map(|c| c.iter().fold(Span::default(), |a, &b| a.merge(b)))
                .collect();
            self.span_ns *= 2;
        }
        let i = (w.start / self.span_ns) as usize;
        if self.spans.len() <= i {
            self.spans.resize(i + 1, Span::default());
        }
        let s = &mut self.spans[i];
        s.received += w.received;
        s.distinct += w.received.saturating_sub(w.duplicate);
        s.lost += w.lost;
        s.covered_ns += w.end.saturating_sub(w.start);
    }

    pub(super) fn on_summary(&mut self, s: &SourceSummary) {
        self.figures = Some(Figures {
            received: s.counts.received,
            lost: s.counts.lost,
            loss_pct: s.loss_pct,
            duplicate: s.counts.duplicate,
            reordered: s.counts.reordered,
            frames_per_s: s.frames_per_s,
        });
    }

    pub(super) fn is_radio(&self) -> bool {
        self.radio
    }

    /// Points of `f` over the spans that have one, at their middle.
    fn points(&self, f: impl Fn(&Span) -> Option<f64>) -> Vec<(f64, f64)> {
        let at = |i: usize| (i as f64 + 0.5) * self.span_ns as f64 / 1e9;
        let each = self.spans.iter().enumerate();
        each.filter_map(|(i, s)| Some((at(i), f(s)?))).collect()
    }

    /// The end of the last span, in seconds.
    fn end_s(&self) -> f64 {
        self.spans.len() as f64 * self.span_ns as f64 / 1e9
    }
}

pub(super) fn svg(title: &str, entries: &[Entry<'_, SourceTrack>]) -> Result<String, PlotError> {
    let rows = frame::rows(entries, |t| {
        let f = t.figures;
        let one = |v: Option<f64>, decimals: usize| v.map(|v| format!("{v:.decimals$}"));
        vec![
            f.map(|f| f.received.to_string()),
            f.map(|f| f.lost.to_string()),
            f.and_then(|f| one(f.loss_pct, 2)),
            f.map(|f| f.duplicate.to_string()),
            f.map(|f| f.reordered.to_string()),
            f.and_then(|f| one(f.frames_per_s, 1)),
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
        let t_max = entries.iter().map(|e| e.track.end_s()).fold(1.0, f64::max);
        rate_chart(entries, &areas[0], t_max)?;
        loss_chart(entries, &areas[1], t_max)
    })
}

/// Each source's frames a second per span, one line each.
fn rate_chart(entries: &[Entry<'_, SourceTrack>], area: &Area<'_>, t_max: f64) -> DrawResult {
    let top = entries
        .iter()
        .flat_map(|e| e.track.spans.iter().filter_map(Span::frames_per_s))
        .fold(1.0f64, f64::max);
    let (x, y) = (0f64..t_max, 0f64..top * 1.08);
    let descs = (None, "frames/s");
    let mut chart = chart(area, "frames a second, by source", descs, x, y)?;
    for (k, e) in entries.iter().enumerate() {
        let points = e.track.points(Span::frames_per_s);
        line(
            &mut chart,
            &e.look,
            &points,
            Marks::Spread(k, entries.len()),
        )?;
    }
    Ok(())
}

/// Each source's sequence loss per span, a line each with its marker where
/// a span lost frames; it carries the time axis.
fn loss_chart(entries: &[Entry<'_, SourceTrack>], area: &Area<'_>, t_max: f64) -> DrawResult {
    let top = entries
        .iter()
        .flat_map(|e| e.track.spans.iter().filter_map(Span::loss_pct))
        .fold(1.0f64, f64::max);
    let caption = "sequence loss per span (marker: a span that lost frames)";
    let descs = (Some("time since start (s)"), "lost (%)");
    let mut chart = chart(area, caption, descs, 0f64..t_max, 0f64..top * 1.1)?;
    for e in entries {
        line(
            &mut chart,
            &e.look,
            &e.track.points(Span::loss_pct),
            Marks::Lost,
        )?;
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
        assert!(t.spans.len() <= SPANS, "{}", t.spans.len());
        assert_eq!(t.spans.iter().map(|s| s.received).sum::<u64>(), 50 * day);
        assert_eq!(t.spans.iter().map(|s| s.lost).sum::<i64>(), 8_640);
        let covered: Nanos = t.spans.iter().map(|s| s.covered_ns).sum();
        assert_eq!(covered, day * FIRST_SPAN_NS);
        // 128 s a span now: each still at 50 a second; the fourth, seconds
        // 384 to 511, lost 13 (390, 400, ... 510).
        assert_eq!(t.span_ns, 128 * FIRST_SPAN_NS);
        let fourth = &t.spans[3];
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
        assert_eq!(t.spans[1].loss_pct(), Some(0.0));
        // Merged, the two add up.
        for n in 2..SPANS as u64 * 2 {
            t.window(&second(n, 50, 0));
        }
        assert_eq!(t.spans[0].lost, 0);
        assert_eq!(t.spans[0].received, 100);
    }
}
