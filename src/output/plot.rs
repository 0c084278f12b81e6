//! `--plot FILE.svg`: RTT over time per responder of every link (losses
//! marked) above the RTT distribution, drawn when the run ends.
//!
//! Memory is constant: each responder keeps [`SPANS`] time spans. When a
//! sample falls past the last span, every span doubles in width and
//! neighbours merge, so a long run is drawn at a coarser time resolution
//! (the mean RTT of each span, and whether it lost anything), never dropped.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io;
use std::rc::Rc;

use plotters::prelude::*;

use super::{Event, Observer, Reporter, StartInfo};
use crate::engine::matcher::MatchEvent;
use crate::engine::summary::LinkSummary;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;

/// Time spans kept per responder.
pub const SPANS: usize = 1024;
/// Width of a span at the start: fine enough for 1 kHz pinging.
const FIRST_SPAN_NS: Nanos = 1_000_000;
/// Distribution bins per decade (4% wide), from 10 µs to 100 s.
const BINS_PER_DECADE: usize = 60;
const LOWEST_US: f64 = 10.0;
const BINS: usize = 7 * BINS_PER_DECADE;
const SIZE: (u32, u32) = (1000, 720);

#[derive(Debug, Clone, Copy, Default)]
struct Span {
    replies: u64,
    rtt_sum: Nanos,
    lost: u64,
}

impl Span {
    fn merge(self, other: Span) -> Span {
        Span {
            replies: self.replies + other.replies,
            rtt_sum: self.rtt_sum + other.rtt_sum,
            lost: self.lost + other.lost,
        }
    }
}

#[derive(Debug, Clone)]
struct Track {
    span_ns: Nanos,
    spans: Vec<Span>,
    bins: [u64; BINS],
}

impl Track {
    fn new() -> Self {
        Track {
            span_ns: FIRST_SPAN_NS,
            spans: Vec::new(),
            bins: [0; BINS],
        }
    }

    fn span(&mut self, sent_at: Nanos) -> &mut Span {
        while sent_at / self.span_ns >= SPANS as u64 {
            self.spans = self
                .spans
                .chunks(2)
                .map(|c| c.iter().fold(Span::default(), |a, &b| a.merge(b)))
                .collect();
            self.span_ns *= 2;
        }
        let i = (sent_at / self.span_ns) as usize;
        if self.spans.len() <= i {
            self.spans.resize(i + 1, Span::default());
        }
        &mut self.spans[i]
    }

    fn reply(&mut self, sent_at: Nanos, rtt: Nanos) {
        let s = self.span(sent_at);
        s.replies += 1;
        s.rtt_sum += rtt;
        self.bins[bin(rtt)] += 1;
    }

    fn lost(&mut self, sent_at: Nanos) {
        self.span(sent_at).lost += 1;
    }
}

fn bin(rtt: Nanos) -> usize {
    let us = (rtt as f64 / 1e3).max(LOWEST_US);
    let i = ((us / LOWEST_US).log10() * BINS_PER_DECADE as f64) as usize;
    i.min(BINS - 1)
}

fn bin_low_ms(i: usize) -> f64 {
    LOWEST_US * 10f64.powf(i as f64 / BINS_PER_DECADE as f64) / 1e3
}

/// The samples a plot is drawn from: every link's responders.
#[derive(Debug, Default)]
pub struct PlotData {
    /// Each link's name, by its place on the command line.
    links: Vec<String>,
    tracks: BTreeMap<(usize, SysComp), Track>,
}

impl PlotData {
    pub fn on_event(&mut self, link: usize, e: &MatchEvent) {
        match *e {
            MatchEvent::Reply {
                responder,
                sent_at,
                rtt,
                ..
            } => self
                .tracks
                .entry((link, responder))
                .or_insert_with(Track::new)
                .reply(sent_at, rtt),
            MatchEvent::Lost {
                responder, sent_at, ..
            } => self
                .tracks
                .entry((link, responder))
                .or_insert_with(Track::new)
                .lost(sent_at),
            _ => {}
        }
    }

    /// The plot's title: the link, or how many.
    fn title(&self) -> String {
        match self.links.as_slice() {
            [one] => format!("mavping {one}"),
            several => format!("mavping, {} links", several.len()),
        }
    }

    /// A responder's legend entry; with several links, its link too.
    fn label(&self, link: usize, id: SysComp) -> String {
        let id = format!("{}/{}", id.sysid, id.compid);
        match self.links.len() {
            1 => id,
            _ => format!("{} {id}", self.links.get(link).map_or("?", String::as_str)),
        }
    }

    /// Draws the SVG document.
    pub fn svg(&self) -> Result<String, String> {
        let mut svg = String::new();
        draw(self, SVGBackend::with_string(&mut svg, SIZE)).map_err(|e| e.to_string())?;
        Ok(svg)
    }
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn draw(data: &PlotData, backend: SVGBackend<'_>) -> DrawResult {
    let root = backend.into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(&data.title(), ("sans-serif", 18).into_font())?;
    let (top, bottom) = root.split_vertically(SIZE.1 * 3 / 5);

    let mut t_max = 1e-3f64;
    let mut rtt_max = 1e-3f64;
    for t in data.tracks.values() {
        t_max = t_max.max(t.spans.len() as f64 * t.span_ns as f64 / 1e9);
        for s in t.spans.iter().filter(|s| s.replies > 0) {
            rtt_max = rtt_max.max(s.rtt_sum as f64 / s.replies as f64 / 1e6);
        }
    }
    let mut chart = ChartBuilder::on(&top)
        .caption(
            "RTT over time (x: lost, drawn at the top)",
            ("sans-serif", 15),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..t_max, 0f64..rtt_max * 1.1)?;
    chart
        .configure_mesh()
        .x_desc("time since start (s)")
        .y_desc("RTT (ms)")
        .draw()?;
    for (n, (&(link, id), t)) in data.tracks.iter().enumerate() {
        let color = Palette99::pick(n).to_rgba();
        let at = |i: usize| (i as f64 + 0.5) * t.span_ns as f64 / 1e9;
        let line: Vec<(f64, f64)> = t
            .spans
            .iter()
            .enumerate()
            .filter(|(_, s)| s.replies > 0)
            .map(|(i, s)| (at(i), s.rtt_sum as f64 / s.replies as f64 / 1e6))
            .collect();
        chart
            .draw_series(LineSeries::new(line, color.stroke_width(1)))?
            .label(data.label(link, id))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], color.stroke_width(2)));
        chart.draw_series(
            t.spans
                .iter()
                .enumerate()
                .filter(|(_, s)| s.lost > 0)
                .map(|(i, _)| Cross::new((at(i), rtt_max * 1.05), 4, RED.stroke_width(2))),
        )?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;

    let used: Vec<usize> = data
        .tracks
        .values()
        .flat_map(|t| t.bins.iter().enumerate().filter(|(_, &c)| c > 0))
        .map(|(i, _)| i)
        .collect();
    let lo = used.iter().min().copied().unwrap_or(0);
    let hi = used.iter().max().copied().unwrap_or(0) + 1;
    let share = |t: &Track, i: usize| {
        let total: u64 = t.bins.iter().sum();
        100.0 * t.bins[i] as f64 / total.max(1) as f64
    };
    let top_share = data
        .tracks
        .values()
        .flat_map(|t| (lo..hi).map(move |i| share(t, i)))
        .fold(1.0f64, f64::max);
    let mut chart = ChartBuilder::on(&bottom)
        .caption("RTT distribution", ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(bin_low_ms(lo)..bin_low_ms(hi), 0f64..top_share * 1.1)?;
    chart
        .configure_mesh()
        .x_desc("RTT (ms)")
        .y_desc("replies (%)")
        .draw()?;
    for (n, t) in data.tracks.values().enumerate() {
        let color = Palette99::pick(n).to_rgba();
        // A step outline per responder, so several stay readable overlaid.
        let mut steps = vec![(bin_low_ms(lo), 0.0)];
        for i in lo..hi {
            steps.push((bin_low_ms(i), share(t, i)));
            steps.push((bin_low_ms(i + 1), share(t, i)));
        }
        steps.push((bin_low_ms(hi), 0.0));
        chart.draw_series(LineSeries::new(steps, color.stroke_width(2)))?;
    }
    root.present()?;
    Ok(())
}

/// `--plot`: collects every link's samples during the run; the run draws
/// it once every link has ended.
#[derive(Default)]
pub struct Plot {
    data: Rc<RefCell<PlotData>>,
}

impl Plot {
    /// The reporter of the next link.
    pub fn link(&self) -> PlotLink {
        let mut data = self.data.borrow_mut();
        data.links.push(String::new());
        PlotLink {
            data: self.data.clone(),
            index: data.links.len() - 1,
        }
    }

    /// Draws the SVG document.
    pub fn svg(&self) -> Result<String, String> {
        self.data.borrow().svg()
    }
}

/// One link's samples into the [`Plot`].
pub struct PlotLink {
    data: Rc<RefCell<PlotData>>,
    index: usize,
}

impl Observer for PlotLink {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.data.borrow_mut().links[self.index] = info.link.clone();
        Ok(())
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if let Event::Match(e) = event {
            self.data.borrow_mut().on_event(self.index, e);
        }
        Ok(())
    }
}

impl Reporter for PlotLink {
    fn summary(&mut self, _: &LinkSummary, _: &Verdict) -> io::Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reply(responder: SysComp, sent_at: Nanos, rtt: Nanos) -> MatchEvent {
        MatchEvent::Reply {
            responder,
            seq: 0,
            rtt,
            sent_at,
            at: sent_at + rtt,
            out_of_order: false,
            first_from_responder: false,
        }
    }

    #[test]
    fn a_long_run_merges_spans_and_keeps_every_sample() {
        let r = SysComp::new(1, 1);
        let mut d = PlotData::default();
        d.links.push("sim:".into());
        // One hour at 100 Hz, every tenth lost.
        for i in 0..360_000u64 {
            let at = i * 10_000_000;
            if i % 10 == 0 {
                d.on_event(
                    0,
                    &MatchEvent::Lost {
                        responder: r,
                        seq: 0,
                        sent_at: at,
                        at,
                    },
                );
            } else {
                d.on_event(0, &reply(r, at, 20_000_000));
            }
        }
        let t = &d.tracks[&(0, r)];
        assert!(t.spans.len() <= SPANS);
        assert_eq!(t.spans.iter().map(|s| s.replies).sum::<u64>(), 324_000);
        assert_eq!(t.spans.iter().map(|s| s.lost).sum::<u64>(), 36_000);
        assert_eq!(t.bins.iter().sum::<u64>(), 324_000);
        assert_eq!(bin(20_000_000), bin(20_400_000));
        assert_ne!(bin(20_000_000), bin(21_000_000));
    }

    #[test]
    fn the_svg_has_a_line_per_responder_and_marks_losses() {
        let mut d = PlotData {
            links: vec!["sim:".into()],
            ..PlotData::default()
        };
        for (n, id) in [SysComp::new(1, 1), SysComp::new(2, 1)]
            .into_iter()
            .enumerate()
        {
            for i in 0..50u64 {
                d.on_event(
                    0,
                    &reply(id, i * 100_000_000, (10 + n as u64 * 5 + i % 3) * 1_000_000),
                );
            }
            d.on_event(
                0,
                &MatchEvent::Lost {
                    responder: id,
                    seq: 0,
                    sent_at: 5_000_000_000,
                    at: 7_000_000_000,
                },
            );
        }
        let svg = d.svg().unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..80]);
        for text in [
            "1/1",
            "2/1",
            "RTT over time",
            "RTT distribution",
            "mavping sim:",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        assert!(svg.matches("<polyline").count() >= 4);
    }

    #[test]
    fn several_links_share_one_plot_with_labelled_lines() {
        let mut d = PlotData {
            links: vec!["sim:".into(), "udpout:10.0.0.2:14550".into()],
            ..PlotData::default()
        };
        for link in 0..2 {
            for i in 0..20u64 {
                d.on_event(link, &reply(SysComp::new(1, 1), i * 100_000_000, 5_000_000));
            }
        }
        let svg = d.svg().unwrap();
        for text in ["mavping, 2 links", "sim: 1/1", "udpout:10.0.0.2:14550 1/1"] {
            assert!(svg.contains(text), "{text} missing");
        }
    }
}
