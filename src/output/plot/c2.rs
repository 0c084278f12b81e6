//! `--plot` of a run with a C2 link report (`--report c2`): one page to
//! attach to a safety case. The title (link and duration), the rule the
//! link was measured by and the headline figures (availability,
//! continuity, latency, loss each way) as lines of text; the outages per
//! duration band and the availability per distance band (against the
//! floor it is held to) as bars side by side; when over the run the link
//! was down, a strip across the page; the longest outages and the
//! failsafe replays as tables. Every figure is the report's own, as
//! the text and JSON give it.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::draw::{axis_font, caption_font, Y_LABELS_W};
use super::frame::{text_width, title_font, Area, DrawResult, PlotError, FONT, MARGIN};
use super::style::Look;
use crate::engine::c2::{C2Report, DistanceBand, FailsafeReplay, Outage};
use crate::output::text::two_significant;

/// The narrowest page; a wide table widens it.
const WIDTH: u32 = 1000;
const TITLE_H: u32 = 44;
const TITLE_SIZE: f64 = 24.0;
/// A line of the headline figures, and a table's row.
const LINE_H: u32 = 24;
const BARS_H: u32 = 320;
const TIMELINE_H: u32 = 200;
/// Room between a table's columns.
const GAP: u32 = 22;
/// The longest outages listed.
const OUTAGE_ROWS: usize = 10;
/// The trips of a replay named in its row.
const TRIPS_NAMED: usize = 3;

fn text_font() -> FontDesc<'static> {
    (FONT, 16).into_font()
}

/// A table: its caption, its columns' heads, a row of cells each, and
/// what stands in place of the rows when there are none.
struct Table {
    caption: &'static str,
    heads: &'static [&'static str],
    rows: Vec<Vec<String>>,
    empty: &'static str,
}

impl Table {
    /// Each column as wide as its widest cell, and a gap.
    fn widths(&self) -> Vec<u32> {
        (0..self.heads.len())
            .map(|j| {
                let cells = self.rows.iter().map(|r| r[j].as_str());
                let widest = cells
                    .chain([self.heads[j]])
                    .map(|c| text_width(c, text_font()));
                widest.max().unwrap_or(0) + GAP
            })
            .collect()
    }

    fn width(&self) -> u32 {
        self.widths().iter().sum::<u32>() + 2 * MARGIN
    }

    /// Its caption, heads and rows (or the `empty` line), and a margin.
    fn height(&self) -> u32 {
        LINE_H * (2 + self.rows.len().max(1) as u32) + 12
    }

    fn draw(&self, area: &Area<'_>) -> DrawResult {
        let style = |font: FontDesc<'static>| {
            font.into_text_style(area)
                .pos(Pos::new(HPos::Left, VPos::Center))
        };
        let y = |r: usize| LINE_H as i32 * r as i32 + LINE_H as i32 / 2 + 4;
        let x0 = MARGIN as i32;
        area.draw(&Text::new(
            self.caption,
            (x0, y(0)),
            style((FONT, 19).into_font()),
        ))?;
        let widths = self.widths();
        let xs: Vec<i32> = widths
            .iter()
            .scan(x0, |x, w| {
                let at = *x;
                *x += *w as i32;
                Some(at)
            })
            .collect();
        let bold = style(text_font().style(FontStyle::Bold));
        for (head, &x) in self.heads.iter().zip(&xs) {
            area.draw(&Text::new(*head, (x, y(1)), bold.clone()))?;
        }
        let rule = y(1) + LINE_H as i32 / 2;
        let end = x0 + widths.iter().sum::<u32>() as i32 - GAP as i32;
        area.draw(&PathElement::new(
            [(x0, rule), (end, rule)],
            BLACK.stroke_width(1),
        ))?;
        if self.rows.is_empty() {
            area.draw(&Text::new(self.empty, (x0, y(2)), style(text_font())))?;
        }
        for (r, row) in self.rows.iter().enumerate() {
            for (cell, &x) in row.iter().zip(&xs) {
                area.draw(&Text::new(cell.as_str(), (x, y(r + 2)), style(text_font())))?;
            }
        }
        Ok(())
    }
}

/// The longest outages, longest first.
fn outages_table(r: &C2Report) -> Table {
    let row = |o: &Outage| {
        vec![
            format!("{:.1}", o.start_s),
            format!("{:.1}", o.duration_s),
            format!("{:.1}", o.silence_s),
            o.distance_m
                .map_or_else(|| "-".into(), |m| format!("{m:.0}")),
            o.at_utc.clone().unwrap_or_else(|| "-".into()),
            if o.open { "open at end" } else { "" }.to_string(),
        ]
    };
    Table {
        caption: "the longest outages",
        heads: &[
            "start (s)",
            "duration (s)",
            "silence (s)",
            "distance (m)",
            "at (UTC)",
            "",
        ],
        rows: r
            .outages
            .longest
            .iter()
            .take(OUTAGE_ROWS)
            .map(row)
            .collect(),
        empty: "no outage",
    }
}

/// `121.5, 420.5 (long), 599.5 (open)` and how many more.
fn first_trips(f: &FailsafeReplay) -> String {
    let named = f.trip_list.iter().take(TRIPS_NAMED).map(|t| {
        let mark = match (t.open, t.long) {
            (true, _) => " (open)",
            (false, true) => " (long)",
            _ => "",
        };
        format!("{:.1}{mark}", t.at_s)
    });
    let mut text = named.collect::<Vec<_>>().join(", ");
    let more = f
        .trips
        .saturating_sub(TRIPS_NAMED.min(f.trip_list.len()) as u64);
    if more > 0 {
        text += &format!(" +{more}");
    }
    if text.is_empty() {
        "-".into()
    } else {
        text
    }
}

/// A row per failsafe model replayed.
fn failsafes_table(r: &C2Report) -> Table {
    let row = |f: &FailsafeReplay| {
        let long = f
            .long_timeout_s
            .map_or_else(String::new, |_| format!(" ({} long)", f.long_trips));
        let closest = match (f.closest_margin_s, f.closest_wait_s) {
            (Some(m), Some(w)) => format!("{m:.1} s ({w:.1} s wait)"),
            _ => "-".into(),
        };
        vec![
            f.model.clone(),
            f.setting.clone(),
            format!("{} {}@{}Hz", f.direction, f.message, f.rate_hz),
            format!("{}{}", f.basis, if f.inferred { ", inferred" } else { "" }),
            format!("{}/{}", f.delivered, f.messages),
            format!("{}{long}", f.trips),
            first_trips(f),
            closest,
            f.expected_if_independent
                .map_or_else(|| "-".into(), two_significant),
        ]
    };
    Table {
        caption: "failsafes replayed on the run's deliveries",
        heads: &[
            "model",
            "setting",
            "watches",
            "basis",
            "delivered",
            "trips",
            "first trips (s)",
            "closest margin",
            "if independent",
        ],
        rows: r.failsafes.iter().map(row).collect(),
        empty: "no failsafe model replayed",
    }
}

/// The rule and the headline figures, a line each.
fn headlines(r: &C2Report) -> Vec<String> {
    let pct = |p: Option<f64>| p.map_or_else(|| "-".into(), |p| format!("{p:.2}%"));
    let mut lines = vec![format!(
        "rule: up while a frame from the vehicle came within {:.1} s; continuity: round trips \
         within {:.1} s",
        r.rule.up_within_s, r.rule.continuity_within_s
    )];
    let continuity = r.continuity.map_or_else(
        || "continuity -".into(),
        |c| {
            format!(
                "continuity {:.2}% ({}/{} round trips, from {})",
                c.pct, c.within, c.transactions, c.from
            )
        },
    );
    lines.push(format!(
        "availability {} (down {:.1} s of {:.1} s); {continuity}",
        pct(r.availability_pct),
        r.down_s,
        r.duration_s
    ));
    let l = &r.latency;
    let mut latency = l.round_trip.map_or_else(
        || "latency round trip -".into(),
        |p| {
            format!(
                "latency round trip p50/p99/p99.9 {:.1}/{:.1}/{:.1} ms (max {:.1} ms)",
                p.p50_ms, p.p99_ms, p.p999_ms, p.max_ms
            )
        },
    );
    for (name, w) in [("uplink", l.uplink), ("downlink", l.downlink)] {
        if let Some(w) = w {
            latency += &format!("; {name} p50/p99 +{:.1}/+{:.1} ms", w.p50_ms, w.p99_ms);
        }
    }
    lines.push(latency);
    lines.push(format!(
        "loss downlink {}, uplink {}, round trip {}; outages {}, {:.1} s in all",
        pct(r.loss.downlink_pct),
        pct(r.loss.uplink_pct),
        pct(r.loss.round_trip_pct),
        r.outages.count,
        r.outages.total_s
    ));
    if let Some(m) = r.availability_under_floor_from_m {
        lines.push(format!(
            "availability under {:.2}% from {m:.0} m",
            r.rule.availability_floor_pct
        ));
    }
    lines
}

/// The page: `link`'s report.
pub(super) fn svg(link: &str, r: &C2Report) -> Result<String, PlotError> {
    let title = format!("mavping C2 link report: {link}, {:.1} s", r.duration_s);
    let lines = headlines(r);
    let tables = [outages_table(r), failsafes_table(r)];
    let widest_line = lines.iter().map(|l| text_width(l, text_font())).max();
    let width = tables
        .iter()
        .map(Table::width)
        .chain([WIDTH, widest_line.unwrap_or(0) + 2 * MARGIN])
        .max()
        .unwrap_or(WIDTH);
    let title_size = fitting(&title, width);
    let width = width.max(text_width(&title, title_font(title_size)) + 2 * MARGIN);
    let lines_h = LINE_H * lines.len() as u32 + 12;
    let tables_h: u32 = tables.iter().map(Table::height).sum();
    let height = TITLE_H + lines_h + BARS_H + TIMELINE_H + tables_h + 12;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        let drawn = (|| -> DrawResult {
            root.fill(&WHITE)?;
            let (head, rest) = root.split_vertically(TITLE_H);
            let left = Pos::new(HPos::Left, VPos::Center);
            let title_style = title_font(title_size).into_text_style(&root).pos(left);
            head.draw(&Text::new(
                title.as_str(),
                (MARGIN as i32, TITLE_H as i32 / 2),
                title_style,
            ))?;
            let (text, rest) = rest.split_vertically(lines_h);
            let style = text_font().into_text_style(&root).pos(left);
            for (k, line) in lines.iter().enumerate() {
                let y = LINE_H as i32 * k as i32 + LINE_H as i32 / 2 + 4;
                text.draw(&Text::new(line.as_str(), (MARGIN as i32, y), style.clone()))?;
            }
            let (bars, rest) = rest.split_vertically(BARS_H);
            let (left, right) = bars.split_horizontally(width / 2);
            outage_bars(r, &left)?;
            distance_bars(r, &right)?;
            let (strip, mut rest) = rest.split_vertically(TIMELINE_H);
            timeline(r, &strip)?;
            for table in &tables {
                let (area, below) = rest.split_vertically(table.height());
                table.draw(&area)?;
                rest = below;
            }
            root.present()?;
            Ok(())
        })();
        drawn.map_err(|e| PlotError(e.to_string()))?;
    }
    Ok(svg)
}

/// The title's font size: smaller for a long title, down to three fifths,
/// before the page gets wider (as the other pages' titles).
fn fitting(title: &str, width: u32) -> f64 {
    let wide = f64::from(text_width(title, title_font(TITLE_SIZE)).max(1));
    let fits = TITLE_SIZE * f64::from(width - 2 * MARGIN) / wide;
    fits.clamp(TITLE_SIZE * 0.6, TITLE_SIZE)
}

/// A bar chart on `area`: a bar a name, from `base` to its value, each
/// labelled above; `y` the value axis's range and name.
struct Bars<'a> {
    caption: &'a str,
    x_desc: &'a str,
    y_desc: &'a str,
    y: std::ops::Range<f64>,
    /// The values are counts: the axis labels whole numbers only.
    counts: bool,
    /// Name, value, the label above the bar, whether it is marked.
    bars: Vec<(String, f64, String, bool)>,
}

impl Bars<'_> {
    /// Draws it, and a line across at `floor` (its label beside it).
    fn draw(&self, area: &Area<'_>, floor: Option<(f64, String)>) -> DrawResult {
        let n = self.bars.len().max(1);
        let mut chart = ChartBuilder::on(area)
            .caption(self.caption, caption_font())
            .margin(MARGIN)
            .x_label_area_size(44)
            .y_label_area_size(Y_LABELS_W)
            .build_cartesian_2d(0f64..n as f64, self.y.clone())?;
        let number = |v: &f64| {
            if self.counts && v.fract() != 0.0 {
                String::new()
            } else {
                format!("{v}")
            }
        };
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .label_style(axis_font())
            .axis_desc_style(axis_font())
            .y_label_formatter(&number)
            .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
            .max_light_lines(1)
            .x_desc(self.x_desc)
            .y_desc(self.y_desc)
            .draw()?;
        // Each bar's name under it, where the axis's labels go.
        let (ox, oy) = area.get_base_pixel();
        let under = axis_font().pos(Pos::new(HPos::Center, VPos::Top));
        for (i, (name, ..)) in self.bars.iter().enumerate() {
            let (x, y) = chart.backend_coord(&(i as f64 + 0.5, self.y.start));
            area.draw(&Text::new(
                name.as_str(),
                (x - ox, y - oy + 6),
                under.clone(),
            ))?;
        }
        let (plain, marked) = (Look::nth(0).color, Look::nth(1).color);
        let base = self.y.start;
        for (i, (_, value, label, mark)) in self.bars.iter().enumerate() {
            let colour = if *mark { marked } else { plain };
            let x = i as f64;
            let bar = Rectangle::new([(x + 0.15, base), (x + 0.85, *value)], colour.filled());
            chart.plotting_area().draw(&bar)?;
            let above = axis_font().pos(Pos::new(HPos::Center, VPos::Bottom));
            let text = Text::new(label.as_str(), (x + 0.5, *value), above);
            chart.plotting_area().draw(&text)?;
        }
        if let Some((at, label)) = floor {
            let dashed = BLACK.stroke_width(1);
            chart.draw_series(DashedLineSeries::new(
                [(0.0, at), (n as f64, at)],
                6,
                4,
                dashed,
            ))?;
            let right = axis_font().pos(Pos::new(HPos::Right, VPos::Bottom));
            chart
                .plotting_area()
                .draw(&Text::new(label, (n as f64, at), right))?;
        }
        Ok(())
    }
}

/// The outages per duration band: how many, and their time in all.
fn outage_bars(r: &C2Report, area: &Area<'_>) -> DrawResult {
    let bands = &r.outages.bands;
    let most = bands.iter().map(|b| b.count).max().unwrap_or(0).max(1);
    let bars = bands
        .iter()
        .map(|b| {
            let label = format!("{} ({:.1} s)", b.count, b.total_s);
            (b.band.to_string(), b.count as f64, label, false)
        })
        .collect();
    Bars {
        caption: "outages by duration",
        x_desc: "outage duration",
        y_desc: "outages",
        y: 0.0..(most as f64 * 1.25).ceil(),
        counts: true,
        bars,
    }
    .draw(area, None)
}

/// The availability in each distance band, marked where it is under the
/// floor, the floor a dashed line across.
fn distance_bars(r: &C2Report, area: &Area<'_>) -> DrawResult {
    if r.distance.is_empty() {
        return no_positions(area);
    }
    let floor = r.rule.availability_floor_pct;
    let lowest = r
        .distance
        .iter()
        .map(|d| d.availability_pct)
        .fold(floor, f64::min);
    // From a round 5 % under the lowest, so a drop shows.
    let base = ((lowest - 1.0) / 5.0).floor() * 5.0;
    let bar = |d: &DistanceBand| {
        let name = format!("{:.0}-{:.0}", d.from_m, d.to_m);
        let label = format!("{:.1}%", d.availability_pct);
        (name, d.availability_pct, label, d.availability_pct < floor)
    };
    Bars {
        caption: "availability by distance",
        x_desc: "distance from the start (m)",
        y_desc: "availability (%)",
        y: base.max(0.0)..100.0 + (100.0 - base) * 0.12,
        counts: false,
        bars: r.distance.iter().map(bar).collect(),
    }
    .draw(area, Some((floor, format!("floor {floor:.2}%"))))
}

/// The share of each bin of the run the link was down, across the page.
fn timeline(r: &C2Report, area: &Area<'_>) -> DrawResult {
    let t = &r.timeline;
    let end = (t.bin_s * t.down_s.len() as f64)
        .max(r.duration_s)
        .max(1e-9);
    let mut chart = ChartBuilder::on(area)
        .caption("the link down over the run", caption_font())
        .margin(MARGIN)
        .x_label_area_size(40)
        .y_label_area_size(Y_LABELS_W)
        .build_cartesian_2d(0f64..end, 0f64..100f64)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .label_style(axis_font())
        .axis_desc_style(axis_font())
        .light_line_style(RGBColor(0xEE, 0xEE, 0xEE))
        .max_light_lines(1)
        .y_labels(3)
        .x_desc(format!("s since the start (bins of {} s)", t.bin_s))
        .y_desc("down (%)")
        .draw()?;
    let colour = Look::nth(1).color;
    for (i, down) in t.down_s.iter().enumerate().filter(|(_, d)| **d > 0.0) {
        let from = i as f64 * t.bin_s;
        let share = 100.0 * (down / t.bin_s).min(1.0);
        let bar = Rectangle::new([(from, 0.0), (from + t.bin_s, share)], colour.filled());
        chart.plotting_area().draw(&bar)?;
    }
    Ok(())
}

/// In place of the distance chart when no position was known.
fn no_positions(area: &DrawingArea<SVGBackend<'_>, Shift>) -> DrawResult {
    let (w, h) = area.dim_in_pixel();
    let centre = Pos::new(HPos::Center, VPos::Center);
    let style = caption_font().pos(centre);
    let at = (w as i32 / 2, h as i32 / 2);
    area.draw(&Text::new(
        "availability by distance: no position known",
        at,
        style,
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::runs::c2_report;

    /// The SVG's elements open and close in order.
    fn balanced(svg: &str) {
        let mut open: Vec<&str> = Vec::new();
        for tag in svg.split('<').skip(1) {
            let tag = &tag[..tag.find('>').expect("a tag closes")];
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(open.pop(), Some(name.trim()), "</{name}> out of order");
            } else if !tag.ends_with('/') && !tag.starts_with('?') && !tag.starts_with('!') {
                open.push(tag.split_whitespace().next().expect("a name"));
            }
        }
        assert!(open.is_empty(), "never closed: {open:?}");
    }

    #[test]
    fn the_page_has_every_part_and_its_figures() {
        let svg = svg("udp:radio", &c2_report()).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..80]);
        balanced(&svg);
        for text in [
            "mavping C2 link report: udp:radio, 600.0 s",
            "continuity: round trips within 1.0 s",
            "availability 98.42% (down 9.5 s of 600.0 s)",
            "continuity 97.50% (1170/1200 round trips, from probes)",
            "p50/p99/p99.9 45.2/180.5/950.0 ms",
            "uplink p50/p99 +3.1/+60.2 ms",
            "loss downlink 0.50%, uplink 1.20%, round trip 1.70%",
            "availability under 99.00% from 750 m",
            // The bars, their labels and the floor.
            "outages by duration",
            "1-3s",
            "2 (3.5 s)",
            "750-1000",
            "86.2%",
            "floor 99.00%",
            // When it was down: the strip, its bins.
            "the link down over the run",
            "bins of 8 s",
            // The tables.
            "the longest outages",
            "912",
            "2026-12-05T10:07:00Z",
            "open at end",
            "FS_SHORT_TIMEOUT=1.5s FS_LONG_TIMEOUT=5s",
            "up HEARTBEAT@1Hz",
            "downlink, inferred",
            "591/600",
            "3 (1 long)",
            "121.5, 420.5 (long), 599.5 (open)",
            "1.0 s (4.0 s wait)",
            "1.5e-7",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        // The band under the floor in the second colour, the others in
        // the first.
        assert!(svg.contains(r##"fill="#D55E00""##));
        assert!(svg.contains(r##"fill="#0072B2""##));
    }

    #[test]
    fn a_report_without_positions_outages_or_failsafes_still_draws() {
        let mut r = c2_report();
        r.distance.clear();
        r.availability_under_floor_from_m = None;
        r.outages.longest.clear();
        r.failsafes.clear();
        r.availability_pct = None;
        r.continuity = None;
        let svg = svg("sim:", &r).unwrap();
        balanced(&svg);
        for text in [
            "no position known",
            "no outage",
            "no failsafe model replayed",
            "availability - (down",
            "continuity -",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
    }
}
