//! `--plot` of a passive run: each source's frames a second, the age of
//! its oldest frame (where its frames carry a clock stamp) and its
//! sequence loss per time span, over time, and a legend of its figures
//! from the run's summary.
//!
//! Memory is constant, as for the RTT plot: each source keeps [`SPANS`]
//! time spans, the first a second wide (the table is told once a second);
//! when a window falls past the last span, every span doubles in width and
//! neighbours merge, so a long run is drawn at a coarser resolution, its
//! frames and losses summed, never dropped, its oldest frame's age kept.

use super::age;
use super::data::SPANS;
use super::draw::{chart, line, lines, Marks, Points};
use super::frame::{self, Area, DrawResult, Entry, Legend, PlotError};
use super::spans::{Bins, Sums};
use crate::engine::pair::LinkPair;
use crate::engine::summary::passive::{SeqCounts, SourceSummary};
use crate::engine::Nanos;
use crate::output::windows::Window;

/// Width of a span at the start: the table's telling.
const FIRST_SPAN_NS: Nanos = 1_000_000_000;
const RATE_H: u32 = 300;
const LOSS_H: u32 = 280;
const AGE_H: u32 = 260;
const LAG_H: u32 = 260;
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
    /// Its headline clock's p99 age above the baseline, ms, from the same
    /// summary; `None` without stamped frames.
    pub(super) age_p99_ms: Option<f64>,
    /// Heard on several links: its part in the pair report as last told.
    pair: Option<PairTold>,
}

/// A link's part in a source's pair report, as told at `at`: counts so
/// far, whose differences between tellings fill the spans.
#[derive(Debug, Clone, Copy, Default)]
struct PairTold {
    at: Nanos,
    frames: u64,
    first: u64,
    lag: (f64, u64),
    first_pct: Option<f64>,
    lag_p50_ms: Option<f64>,
}

impl SourceTrack {
    pub(super) fn new(radio: bool) -> Self {
        SourceTrack {
            spans: Bins::new(FIRST_SPAN_NS as f64, 1e9, SPANS),
            radio,
            summary: None,
            age_p99_ms: None,
            pair: None,
        }
    }

    /// Its part in the pair report told at `at`: what came since the last
    /// telling goes in the span where that one was.
    pub(super) fn paired(&mut self, at: Nanos, link: &LinkPair) {
        let was = self.pair.unwrap_or_default();
        let span = self.spans.at(was.at as f64);
        span.paired += link.frames.saturating_sub(was.frames);
        span.first += link.first.saturating_sub(was.first);
        span.lag_ns.0 += (link.lag_sum.0 - was.lag.0).max(0.0);
        span.lag_ns.1 += link.lag_sum.1.saturating_sub(was.lag.1);
        self.pair = Some(PairTold {
            at,
            frames: link.frames,
            first: link.first,
            lag: link.lag_sum,
            first_pct: link.first_pct,
            lag_p50_ms: link.lag_p50_ms,
        });
    }

    /// Adds a window, in the span where it starts.
    pub(super) fn window(&mut self, w: &Window) {
        // A run that ended on a telling has nothing after it.
        if w.start == w.end && w.is_empty() {
            return;
        }
        self.spans.at(w.start as f64).window(w);
    }

    /// The oldest frame's age (ms) between the two tellings `w` spans.
    pub(super) fn age(&mut self, w: &Window, ms: f64) {
        self.spans.at(w.start as f64).age(ms);
    }

    fn age_points(&self) -> Points {
        age::floored(self.spans.points(|s| s.age_ms))
    }
}

/// The rate chart, the age chart when a source's frames carry clock
/// stamps, the loss chart and the legend. The ages go between the rate
/// and the loss, so the loss chart keeps the time axis and a page
/// without ages is drawn as it was.
pub(super) fn svg(title: &str, entries: &[Entry<'_, SourceTrack>]) -> Result<String, PlotError> {
    let ages = lines(entries, SourceTrack::age_points);
    let aged = age::any(&ages) || entries.iter().any(|e| e.track.age_p99_ms.is_some());
    let paired = entries.iter().any(|e| e.track.pair.is_some());
    let rows = frame::rows(entries, |t| {
        let s = t.summary.as_ref();
        let count = |n: fn(&SeqCounts) -> u64| s.map(|s| n(&s.counts).to_string());
        let mut cells = vec![
            count(|c| c.received),
            count(|c| c.lost),
            s.and_then(|s| s.loss_pct).map(|v| format!("{v:.2}")),
            count(|c| c.duplicate),
            count(|c| c.reordered),
            s.and_then(|s| s.frames_per_s).map(|v| format!("{v:.1}")),
        ];
        if aged {
            cells.push(t.age_p99_ms.map(|v| format!("{v:.1}")));
        }
        if paired {
            let pair = t.pair.as_ref();
            cells.push(pair.and_then(|p| p.first_pct).map(|v| format!("{v:.1}")));
            cells.push(pair.and_then(|p| p.lag_p50_ms).map(|v| format!("{v:.1}")));
        }
        cells
    });
    let mut heads = vec!["received", "lost", "loss %", "dup", "reordered", "frames/s"];
    if aged {
        heads.push("age p99 ms");
    }
    if paired {
        heads.extend(["first %", "lag p50 ms"]);
    }
    let legend = Legend {
        heads: ("source", &heads),
        number_w: NUMBER_W,
        rows,
        empty: "nothing heard",
    };
    let lags = lines(entries, |t| t.spans.points(Sums::mean_lag_ms));
    let lagged = lags.iter().any(|l| !l.is_empty());
    let mut heights = vec![RATE_H];
    heights.extend(age::any(&ages).then_some(AGE_H));
    heights.extend(lagged.then_some(LAG_H));
    heights.push(LOSS_H);
    frame::page(title, &legend, &heights, |areas| {
        let t_max = entries
            .iter()
            .map(|e| e.track.spans.end())
            .fold(1.0, f64::max);
        let (first, rest) = areas.split_first().expect("a rate chart");
        let (last, middle) = rest.split_last().expect("a loss chart");
        rate_chart(entries, first, t_max)?;
        let mut middle = middle.iter();
        if age::any(&ages) {
            age_chart(entries, &ages, middle.next().expect("an age chart"), t_max)?;
        }
        if lagged {
            lag_chart(entries, &lags, middle.next().expect("a lag chart"), t_max)?;
        }
        loss_chart(entries, last, t_max)
    })
}

/// A source heard on several links: each link's mean lag behind the
/// first copy per span, one line each (0 on the link that is first).
fn lag_chart(
    entries: &[Entry<'_, SourceTrack>],
    lags: &[Points],
    area: &Area<'_>,
    t_max: f64,
) -> DrawResult {
    let caption = "lag behind the first copy, by link (mean per span)";
    let descs = (None, "lag (ms)");
    let y = 0f64..top(lags) * 1.08;
    let mut chart = chart(area, caption, descs, 0f64..t_max, y)?;
    for (k, (e, points)) in entries.iter().zip(lags).enumerate() {
        line(&mut chart, &e.look, points, Marks::Spread(k, entries.len()))?;
    }
    Ok(())
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

/// Each source's oldest frame's age per span, one line each; a source
/// without stamped frames has none.
fn age_chart(
    entries: &[Entry<'_, SourceTrack>],
    ages: &[Points],
    area: &Area<'_>,
    t_max: f64,
) -> DrawResult {
    let caption = "age above baseline, by source (oldest frame per span)";
    let descs = (None, "age (ms, log scale)");
    let mut chart = chart(area, caption, descs, 0f64..t_max, age::axis(ages))?;
    for (k, (e, points)) in entries.iter().zip(ages).enumerate() {
        line(&mut chart, &e.look, points, Marks::Spread(k, entries.len()))?;
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
    use crate::engine::probe::passive::tracker::SourceTable;
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
        use crate::engine::probe::passive::tracker::RADIO_SOURCE;
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
            link.windows(at, &table.summary(at), &[]);
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
        plot.data.borrow_mut().on_sources(0, &summary, &[]);
        let svg = plot.svg().unwrap();
        // Without stamped frames, no age chart and no age column.
        assert!(!svg.contains("age"), "an age without ages");
        // 980 frames, 20 lost: 2.00 %; 979 in the 19.98 s after the first.
        for text in ["980", "20", "2.00", "49.0", "received", "reordered"] {
            assert!(svg.contains(&format!("\n{text}\n")), "{text} missing");
        }
        assert!(!svg.contains("\n-\n"), "a figure is missing");
    }

    /// A second's window of `source` and the oldest frame's age in it.
    fn aged(data: &mut super::super::data::PlotData, source: SysComp, n: u64, age_ms: f64) {
        let w = Window {
            source,
            ..second(n, 50, 0)
        };
        data.on_windows(0, &[w], &[(source, age_ms)]);
    }

    #[test]
    fn a_queue_draws_an_age_line_per_stamped_source_and_its_p99_in_the_legend() {
        let plot = super::super::Plot::default();
        let mut link = plot.link();
        plot.data.borrow_mut().links[0] = "sim:".into();
        link.windows = Some(crate::output::windows::Windows::default());
        let (one, two) = (SysComp::new(1, 1), SysComp::new(2, 1));
        {
            let mut data = plot.data.borrow_mut();
            // 1/1 behind a queue that grows to 1.2 s over 12 s and drains;
            // 2/1's frames carry no stamps.
            for n in 0..24u64 {
                let ms = 100.0 * (12 - (n as i64 - 12).abs()) as f64;
                aged(&mut data, one, n, ms);
                data.on_windows(
                    0,
                    &[Window {
                        source: two,
                        ..second(n, 50, 0)
                    }],
                    &[],
                );
            }
        }
        let svg = plot.svg().unwrap();
        for text in [
            "age above baseline, by source",
            "age (ms, log scale)",
            "1000",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        // Rate and loss of both, the age of 1/1 only (axes and ticks are
        // polylines too, opaque and thin).
        let drawn = svg.matches(r#"opacity="0.85""#).count();
        assert_eq!(drawn, 5, "{svg}");
        // Before the summary, the p99 is unknown, not made up; after it,
        // the summary's own, and `-` for the source without stamps.
        assert!(
            svg.contains(
                "
age p99 ms
"
            ),
            "no age column"
        );
        let ages = crate::output::runs::ages();
        let nobody = SourceTable::new(None, 32).summary(0);
        plot.data.borrow_mut().on_sources(0, &nobody, &ages);
        let svg = plot.svg().unwrap();
        assert!(
            svg.contains(
                "
1480.0
"
            ),
            "the summary's p99 missing"
        );
        assert!(
            svg.contains(
                "
-
"
            ),
            "2/1's p99 made up"
        );

        // The age chart sits between the rate and the loss charts, so the
        // loss chart keeps the time axis.
        let at = |text: &str| svg.find(text).unwrap_or_else(|| panic!("{text}"));
        assert!(at("frames a second") < at("age above baseline"));
        assert!(at("age above baseline") < at("sequence loss per span"));
        assert!(at("sequence loss per span") < at("time since start"));
    }

    /// A link's part in a source's pair report, as told: `frames` so far,
    /// each `lag_ms` behind the first copy.
    fn part(link: usize, frames: u64, lag_ms: f64) -> LinkPair {
        LinkPair {
            link,
            frames,
            damaged: 0,
            duplicates: 0,
            first: if lag_ms == 0.0 { frames } else { 0 },
            first_pct: Some(if lag_ms == 0.0 { 100.0 } else { 0.0 }),
            only: 0,
            only_undecided: 0,
            lost: 0,
            lost_pct: Some(0.0),
            lag_p50_ms: Some(lag_ms),
            lag_p99_ms: Some(lag_ms),
            lag_max_ms: Some(lag_ms),
            stale: 0,
            stale_first: 0,
            lag_sum: (frames as f64 * lag_ms * 1e6, frames),
        }
    }

    #[test]
    fn each_links_lag_is_drawn_from_what_came_between_two_tellings() {
        let mut t = SourceTrack::new(false);
        // 50 frames a second; the lag 30 ms for 3 s, then 90 ms.
        let mut frames = 0;
        let mut sum = (0.0, 0);
        for second in 1..=6u64 {
            frames += 50;
            let lag = if second <= 3 { 30.0 } else { 90.0 };
            sum = (sum.0 + 50.0 * lag * 1e6, sum.1 + 50);
            let mut told = part(1, frames, lag);
            told.lag_sum = sum;
            t.paired(second * FIRST_SPAN_NS, &told);
        }
        let lags: Vec<f64> = t
            .spans
            .points(Sums::mean_lag_ms)
            .iter()
            .map(|p| p.1)
            .collect();
        assert_eq!(lags, [30.0, 30.0, 30.0, 90.0, 90.0, 90.0]);
        assert_eq!(t.spans.bins.iter().map(|s| s.paired).sum::<u64>(), 300);
        assert_eq!(t.spans.bins.iter().map(|s| s.first).sum::<u64>(), 0);
    }

    fn second_window(n: u64) -> Window {
        second(n, 50, 0)
    }

    #[test]
    fn a_paired_source_gets_a_lag_chart_and_its_figures_in_the_legend() {
        let plot = super::super::Plot::default();
        let (_a, _b) = (plot.link(), plot.link());
        let one = SysComp::new(1, 1);
        for second in 1..=5u64 {
            let summary = crate::engine::pair::PairSummary {
                window_ms: 5000.0,
                sources: vec![crate::engine::pair::SourcePair {
                    source: one,
                    distinct_frames: second * 50,
                    lost_on_every_link: 0,
                    lost_on_every_link_pct: Some(0.0),
                    copies: second * 50,
                    dedup_window_p999_ms: Some(80.0),
                    copy_lag_max_ms: Some(80.0),
                    late_beyond_window: 0,
                    conflicts: 0,
                    links: vec![part(0, second * 50, 0.0), part(1, second * 50, 80.0)],
                }],
                single_link_sources: Vec::new(),
                uncopied_sources: Vec::new(),
                conflicting_sources: Vec::new(),
                untracked_frames: 0,
            };
            // A passive run's sources: drawn with their part in the pair.
            for link in 0..2 {
                let w = Window {
                    source: one,
                    ..second_window(second - 1)
                };
                plot.data.borrow_mut().on_windows(link, &[w], &[]);
            }
            plot.on_pair(second * FIRST_SPAN_NS, &summary);
        }
        let svg = plot.svg().unwrap();
        for text in [
            "lag behind the first copy, by link",
            "\nfirst %\n",
            "\nlag p50 ms\n",
            "\n100.0\n",
            "\n80.0\n",
        ] {
            assert!(svg.contains(text), "{text:?} missing");
        }
        let at = |text: &str| svg.find(text).unwrap_or_else(|| panic!("{text}"));
        assert!(at("frames a second") < at("lag behind the first copy"));
        assert!(at("lag behind the first copy") < at("sequence loss per span"));
    }

    #[test]
    fn merged_spans_keep_the_oldest_frame_and_no_age_stays_no_age() {
        let mut t = SourceTrack::new(false);
        // A day: an 8 s spike at noon, ages of 3 ms elsewhere, the first
        // hour without stamps.
        let day = 86_400;
        for n in 0..day {
            let w = second(n, 50, 0);
            t.window(&w);
            match n {
                0..3_600 => {}
                43_200..43_208 => t.age(&w, 8_000.0),
                _ => t.age(&w, 3.0),
            }
        }
        assert!(t.spans.bins.len() <= SPANS);
        let ages: Vec<Option<f64>> = t.spans.bins.iter().map(|s| s.age_ms).collect();
        // 128 s spans: the first 28 without stamps.
        assert_eq!(ages.iter().filter(|a| a.is_none()).count(), 28);
        assert_eq!(ages.iter().filter(|&&a| a == Some(8_000.0)).count(), 1);
        assert_eq!(ages[43_200 / 128], Some(8_000.0));
        assert_eq!(ages[43_200 / 128 + 1], Some(3.0));
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
