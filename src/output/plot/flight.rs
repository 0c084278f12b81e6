//! `--plot` of a telemetry log: a one-page flight report. The link's loss
//! per time span, the radio's RSSI and remote RSSI over time, and the loss
//! against the distance from the origin (the range test a radio user does
//! by hand), with the flight's figures below.
//!
//! Memory is constant: [`SPANS`] time spans that double in width and merge
//! when a window falls past the last (as the passive page's), and
//! [`DISTANCE_BINS`] distance bins that do the same when a window is
//! farther than the last bin; frames and losses are summed, never dropped.

use plotters::prelude::*;

use super::data::SPANS;
use super::draw::{caption_font, chart, line, Marks};
use super::frame::{self, Area, DrawResult, Legend, LegendRow, PlotError};
use super::spans::{merged, Bins, Sums};
use super::style::Look;
use crate::engine::probe::passive::flight::{FlightSummary, FlightWindow, DEFAULT_WINDOW_NS};

/// Distance bins at most.
pub(super) const DISTANCE_BINS: usize = 40;
/// Width of a distance bin at the start, metres.
const FIRST_BIN_M: f64 = 25.0;
const LOSS_H: u32 = 250;
const RSSI_H: u32 = 250;
const RANGE_H: u32 = 300;
const NUMBER_W: i32 = 110;

/// The flight of one log, window by window.
#[derive(Debug, Clone)]
pub(super) struct FlightTrack {
    time: Bins,
    distance: Bins,
    summary: Option<FlightSummary>,
}

impl Default for FlightTrack {
    fn default() -> Self {
        FlightTrack {
            time: Bins::new(DEFAULT_WINDOW_NS as f64 / 1e9, 1.0, SPANS),
            distance: Bins::new(FIRST_BIN_M, 1.0, DISTANCE_BINS),
            summary: None,
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

    /// The summary's figures, and its last window.
    pub(super) fn on_summary(&mut self, f: &FlightSummary) {
        if let Some(last) = &f.last {
            self.window(last);
        }
        self.summary = Some(f.clone());
    }

    pub(super) fn is_empty(&self) -> bool {
        // Every window widens or fills a time span.
        self.time.bins.is_empty()
    }
}

/// Three rows in the legend, a line each: its figure over the whole log,
/// and the lowest and highest of its spans.
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
    let rows = vec![
        row(0, "loss (%)", &Sums::loss_pct),
        row(1, "rssi", &|s| Sums::mean(s.rssi)),
        row(2, "remote rssi", &|s| Sums::mean(s.remrssi)),
    ];
    let legend = Legend {
        heads: ("", &["whole log", "lowest", "highest"]),
        number_w: NUMBER_W,
        rows,
        empty: "no window",
    };
    frame::page(title, &legend, &[LOSS_H, RSSI_H, RANGE_H], |areas| {
        let t_max = track.time.end().max(1.0);
        loss_over_time(track, &areas[0], t_max)?;
        rssi_over_time(track, &areas[1], t_max)?;
        loss_against_distance(track, &areas[2])
    })
}

fn loss_over_time(track: &FlightTrack, area: &Area<'_>, t_max: f64) -> DrawResult {
    let points = track.time.points(Sums::loss_pct);
    let top = points.iter().map(|p| p.1).fold(1.0f64, f64::max);
    let caption = "sequence loss over time (marker: a span that lost frames)";
    let (x, y) = (0f64..t_max, 0f64..top * 1.1);
    let mut chart = chart(area, caption, (None, "lost (%)"), x, y)?;
    line(&mut chart, &Look::nth(0), &points, Marks::Lost)
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
    use crate::engine::probe::passive::flight::{RadioWindow, Range};

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
    }
}
