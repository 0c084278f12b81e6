//! `--plot` of a telemetry log: a one-page flight report. The link's loss
//! per time span, the vehicle's frame age p99 per time span (where its
//! frames carry clock stamps), the radio's RSSI and remote RSSI over time,
//! and the loss against the distance from the origin (the range test a
//! radio user does by hand), with the flight's figures below.
//!
//! Memory is constant: [`SPANS`] time spans that double in width and merge
//! when a window falls past the last (as the passive page's), and
//! [`DISTANCE_BINS`] distance bins that do the same when a window is
//! farther than the last bin; frames and losses are summed, never dropped,
//! and a merged span keeps its windows' highest age p99.

use plotters::prelude::*;

use super::age;
use super::data::SPANS;
use super::draw::{caption_font, chart, line, Marks};
use super::frame::{self, Area, DrawResult, Legend, LegendRow, PlotError};
use super::spans::{merged, Bins, Sums};
use super::style::Look;
use crate::engine::age::SourceAge;
use crate::engine::probe::passive::flight::{FlightSummary, FlightWindow, DEFAULT_WINDOW_NS};

/// Distance bins at most.
pub(super) const DISTANCE_BINS: usize = 40;
/// Width of a distance bin at the start, metres.
const FIRST_BIN_M: f64 = 25.0;
const LOSS_H: u32 = 250;
const RSSI_H: u32 = 250;
const AGE_H: u32 = 250;
const RANGE_H: u32 = 300;
const NUMBER_W: i32 = 110;

/// The flight of one log, window by window.
#[derive(Debug, Clone)]
pub(super) struct FlightTrack {
    time: Bins,
    distance: Bins,
    summary: Option<FlightSummary>,
    /// The vehicle's headline p99 age over the whole log, ms, from the
    /// run's summary.
    age_p99_ms: Option<f64>,
}

impl Default for FlightTrack {
    fn default() -> Self {
        FlightTrack {
            time: Bins::new(DEFAULT_WINDOW_NS as f64 / 1e9, 1.0, SPANS),
            distance: Bins::new(FIRST_BIN_M, 1.0, DISTANCE_BINS),
            summary: None,
            age_p99_ms: None,
        }
    }
}

impl FlightTrack {
    pub(super) fn window(&mut self, w: &FlightWindow) {
        self.time.at(w.start as f64 / 1e9).flight(w);
        if let Some(r) = &w.range {
            self.distance.at(r.distance_m).flight(w);
        }
    }

    /// The summary's figures, and its last window; of `ages`, the
    /// vehicle's (whose positions are read: the windows' ages are its
    /// frames').
    pub(super) fn on_summary(&mut self, f: &FlightSummary, ages: &[SourceAge]) {
        if let Some(last) = &f.last {
            self.window(last);
        }
        let age = match &f.origin {
            Some(o) => ages.iter().find(|a| a.source == o.vehicle),
            // Without a position every source's frames went into the
            // windows' ages: one source's figure stands for them only
            // when it is the one stamped.
            None => match ages {
                [one] => Some(one),
                _ => None,
            },
        };
        self.age_p99_ms = age.map(|a| a.headline.p99_ms);
        self.summary = Some(f.clone());
    }

    fn age_points(&self) -> Vec<(f64, f64)> {
        age::floored(self.time.points(|s| s.age_ms))
    }

    pub(super) fn is_empty(&self) -> bool {
        // Every window widens or fills a time span.
        self.time.bins.is_empty()
    }
}

/// Three rows in the legend, a line each: its figure over the whole log,
/// and the lowest and highest of its spans; a fourth, and a chart under
/// the loss sharing its time axis, for the age where the log has any.
pub(super) fn svg(title: &str, track: &FlightTrack) -> Result<String, PlotError> {
    let total = merged(&track.time.bins);
    let row = |n: usize, label: &'static str, f: &dyn Fn(&Sums) -> Option<f64>| {
        let spans: Vec<f64> = track.time.bins.iter().filter_map(f).collect();
        let low = spans.iter().copied().reduce(f64::min);
        let high = spans.iter().copied().reduce(f64::max);
        let decimals = if n == 0 { 2 } else { 0 };
        let cell = |v: Option<f64>| v.map(|v| format!("{v:.decimals$}"));
        LegendRow {
            look: Look::nth(n),
            label,
            cells: vec![cell(f(&total)), cell(low), cell(high)],
        }
    };
    let mut rows = vec![
        row(0, "loss (%)", &Sums::loss_pct),
        row(1, "rssi", &|s| Sums::mean(s.rssi)),
        row(2, "remote rssi", &|s| Sums::mean(s.remrssi)),
    ];
    let ages = track.age_points();
    let mut heights = vec![LOSS_H, RSSI_H, RANGE_H];
    if !ages.is_empty() {
        let mut age = row(AGE_LOOK, "age p99 (ms)", &|s| s.age_ms);
        // Merged, a span holds its windows' highest p99, not the log's.
        age.cells[0] = track.age_p99_ms.map(|v| format!("{v:.0}"));
        rows.push(age);
        heights.insert(1, AGE_H);
    }
    let legend = Legend {
        heads: ("", &["whole log", "lowest", "highest"]),
        number_w: NUMBER_W,
        rows,
        empty: "no window",
    };
    frame::page(title, &legend, &heights, |areas| {
        let t_max = track.time.end().max(1.0);
        let (loss, rest) = areas.split_first().expect("a loss chart");
        loss_over_time(track, loss, t_max)?;
        let rest = match rest {
            [age, rest @ ..] if !ages.is_empty() => {
                age_over_time(&ages, age, t_max)?;
                rest
            }
            rest => rest,
        };
        rssi_over_time(track, &rest[0], t_max)?;
        loss_against_distance(track, &rest[1])
    })
}

/// The age line's look: the legend's fourth row.
const AGE_LOOK: usize = 3;

fn loss_over_time(track: &FlightTrack, area: &Area<'_>, t_max: f64) -> DrawResult {
    let points = track.time.points(Sums::loss_pct);
    let top = points.iter().map(|p| p.1).fold(1.0f64, f64::max);
    let caption = "sequence loss over time (marker: a span that lost frames)";
    let (x, y) = (0f64..t_max, 0f64..top * 1.1);
    let mut chart = chart(area, caption, (None, "lost (%)"), x, y)?;
    line(&mut chart, &Look::nth(0), &points, Marks::Lost)
}

/// The vehicle's frames' age p99 per span (a merged span's highest).
fn age_over_time(points: &[(f64, f64)], area: &Area<'_>, t_max: f64) -> DrawResult {
    let caption = "age above baseline over time (p99 per span)";
    let y = age::axis(&[points.to_vec()]);
    let mut chart = chart(area, caption, (None, "age (ms, log scale)"), 0f64..t_max, y)?;
    line(
        &mut chart,
        &Look::nth(AGE_LOOK),
        points,
        Marks::Spread(0, 1),
    )
}

fn rssi_over_time(track: &FlightTrack, area: &Area<'_>, t_max: f64) -> DrawResult {
    let rssi = track.time.points(|s| Sums::mean(s.rssi));
    let remrssi = track.time.points(|s| Sums::mean(s.remrssi));
    let caption = "radio RSSI over time (RADIO_STATUS)";
    let descs = (Some("time since the log began (s)"), "RSSI (0-254)");
    let mut chart = chart(area, caption, descs, 0f64..t_max, 0f64..255f64)?;
    for (n, points) in [(1, rssi), (2, remrssi)] {
        line(&mut chart, &Look::nth(n), &points, Marks::Spread(n, 3))?;
    }
    if track.summary.as_ref().is_some_and(|s| s.radio.is_none()) {
        chart.plotting_area().draw(&Text::new(
            "no RADIO_STATUS in the log",
            (t_max * 0.02, 230.0),
            caption_font(),
        ))?;
    }
    Ok(())
}

fn loss_against_distance(track: &FlightTrack, area: &Area<'_>) -> DrawResult {
    let bars = track.distance.points(Sums::loss_pct);
    let top = bars.iter().map(|p| p.1).fold(1.0f64, f64::max);
    let d_max = track.distance.end().max(FIRST_BIN_M);
    let half = track.distance.width * 0.4;
    let caption = format!(
        "sequence loss against distance from the origin ({:.0} m bins)",
        track.distance.width
    );
    let descs = (Some("distance (m, straight line)"), "lost (%)");
    let mut chart = chart(area, &caption, descs, 0f64..d_max, 0f64..top * 1.1)?;
    let look = Look::nth(0);
    chart.draw_series(bars.iter().map(|&(x, pct)| {
        Rectangle::new([(x - half, 0.0), (x + half, pct)], look.color.filled())
    }))?;
    if bars.is_empty() {
        chart.plotting_area().draw(&Text::new(
            "no position in the log",
            (d_max * 0.02, top),
            caption_font(),
        ))?;
    }
    Ok(())
}

/// The title: the link, and the flight's figures.
pub(super) fn title(link: &str, track: &FlightTrack) -> String {
    let Some(s) = &track.summary else {
        return format!("mavping {link}: the flight");
    };
    let far = s
        .farthest
        .and_then(|w| w.range)
        .map_or_else(String::new, |r| format!(", farthest {:.0} m", r.distance_m));
    format!(
        "mavping {link}: the flight, {} windows of {:.0} s, {} silence{}, {} loss burst{}{far}",
        s.windows,
        s.window_ns as f64 / 1e9,
        s.silence_count,
        if s.silence_count == 1 { "" } else { "s" },
        s.burst_count,
        if s.burst_count == 1 { "" } else { "s" },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::probe::passive::flight::{RadioWindow, Range, WindowAge};

    fn window(k: u64, received: u64, lost: i64, distance_m: f64) -> FlightWindow {
        FlightWindow {
            index: k,
            start: k * 10_000_000_000,
            end: (k + 1) * 10_000_000_000,
            received,
            duplicate: 0,
            lost,
            loss_pct: None,
            radio: Some(RadioWindow {
                reports: 10,
                rssi: Some(200.0 - k as f64),
                remrssi: Some(190.0),
                noise: None,
                remnoise: None,
                rxerrors: 0,
            }),
            range: Some(Range {
                ground_m: distance_m,
                distance_m,
                alt_m: 100.0,
            }),
            age: None,
        }
    }

    #[test]
    fn distance_bins_stay_bounded_and_keep_every_frame() {
        let mut t = FlightTrack::default();
        // 10 hours of windows, flying out 10 km and back, a loss in each
        // window beyond 8 km.
        let n = 3_600u64;
        for k in 0..n {
            let d = 10_000.0 * (1.0 - ((k as f64 / n as f64) * 2.0 - 1.0).abs());
            t.window(&window(k, 500, i64::from(d > 8_000.0), d));
        }
        assert!(t.distance.bins.len() <= DISTANCE_BINS);
        assert!(t.time.bins.len() <= SPANS);
        let sum = |b: &Bins| b.bins.iter().map(|s| s.received).sum::<u64>();
        assert_eq!(sum(&t.distance), 500 * n);
        assert_eq!(sum(&t.time), 500 * n);
        // 25 m doubled to 400 m: 10 km in 26 bins; the losses only in the
        // bins past 8 km.
        assert_eq!(t.distance.width, 400.0);
        for (x, s) in t.distance.each() {
            assert_eq!(s.lost > 0, x > 8_000.0, "{x}: {s:?}");
        }
    }

    #[test]
    fn the_report_draws_its_three_charts_and_the_figures() {
        let mut t = FlightTrack::default();
        for k in 0..30 {
            t.window(&window(
                k,
                500,
                if k == 12 { 50 } else { 0 },
                100.0 * k as f64,
            ));
        }
        let svg = svg("mavping tlog:flight.tlog", &t).unwrap();
        for text in [
            "sequence loss over time",
            "radio RSSI over time",
            "loss against distance",
            "whole log",
            // 50 lost of 15 000: 0.33 %; the worst span 50 of 550.
            "\n0.33\n",
            "\n9.09\n",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        // The loss line and the two RSSI lines.
        assert!(svg.matches("<polyline").count() >= 3);
        // A log without clock stamps: no age chart, no age row.
        assert!(!svg.contains("age"), "an age without ages");
    }

    /// A flight whose queue grows to `peak_ms` (window p99) at window 20
    /// of 40, 12 ms before and after it.
    fn queued(peak_ms: f64) -> FlightTrack {
        let mut t = FlightTrack::default();
        for k in 0..40u64 {
            let p99_ms = if k == 20 { peak_ms } else { 12.0 };
            t.window(&FlightWindow {
                age: Some(WindowAge {
                    p99_ms,
                    max_ms: p99_ms * 1.1,
                }),
                ..window(k, 500, 0, 50.0 * k as f64)
            });
        }
        t
    }

    #[test]
    fn the_vehicles_age_is_drawn_under_the_loss_with_a_row_of_its_own() {
        let mut t = queued(2_949.0);
        let ages = crate::output::runs::ages();
        let mut summary = crate::output::runs::flight().1;
        summary.last = None;
        t.on_summary(&summary, &ages);
        let svg = svg("mavping tlog:vtol.tlog", &t).unwrap();
        let at = |text: &str| svg.find(text).unwrap_or_else(|| panic!("{text} missing"));
        // Between the loss and the RSSI, sharing their time axis.
        assert!(at("sequence loss over time") < at("age above baseline over time"));
        assert!(at("age above baseline over time") < at("radio RSSI over time"));
        assert!(at("age (ms, log scale)") > 0);
        // Its row: the vehicle's p99 over the log (the summary's), the
        // quietest window's and the queue's.
        for text in ["\nage p99 (ms)\n", "\n1480\n", "\n12\n", "\n2949\n"] {
            assert!(svg.contains(text), "{text:?} missing");
        }
        // Loss, age, RSSI and remote RSSI.
        assert_eq!(svg.matches(r#"opacity="0.85""#).count(), 4, "{svg}");

        // A log without positions: the one stamped source's p99 stands for
        // the log, two sources' do not.
        summary.origin = None;
        t.on_summary(&summary, &ages);
        assert_eq!(t.age_p99_ms, Some(1480.0));
        let two = [ages.clone(), ages].concat();
        t.on_summary(&summary, &two);
        assert_eq!(t.age_p99_ms, None);
    }

    #[test]
    fn merged_time_spans_keep_the_highest_window_p99() {
        let mut t = FlightTrack::default();
        // 2 048 windows of 10 s: spans of 20 s hold two each.
        for k in 0..2_048u64 {
            let p99_ms = if k == 1_001 { 3_000.0 } else { k as f64 % 7.0 };
            let age = Some(WindowAge {
                p99_ms,
                max_ms: p99_ms,
            });
            t.window(&FlightWindow {
                age,
                ..window(k, 500, 0, 0.0)
            });
        }
        assert_eq!(t.time.width, 20.0);
        let ages: Vec<f64> = t.time.bins.iter().filter_map(|s| s.age_ms).collect();
        assert_eq!(ages.len(), 1_024);
        assert_eq!(ages[500], 3_000.0);
        // Windows 1 000 (6 ms) and 1 001 (the queue) in one span, 1 002
        // (1 ms) and 1 003 (2 ms) in the next.
        assert_eq!(ages[501], 2.0);
    }
}
