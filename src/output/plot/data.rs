//! The samples a plot is drawn from: each responder's RTT and losses in
//! time spans that widen as the run goes on, and its RTT distribution;
//! each sweep, passive source and flight, per link.

use std::collections::BTreeMap;

use super::flight::{self, FlightTrack};
use super::frame::{self, PlotError};
use super::passive::{self, SourceTrack};
use super::spans::Bins;
use super::{c2, draw, sweep, transfer};
use crate::engine::age::SourceAge;
use crate::engine::c2::C2Report;
use crate::engine::matcher::MatchEvent;
use crate::engine::pair::PairSummary;
use crate::engine::summary::passive::TableSummary;
use crate::engine::summary::ResponderSummary;
use crate::engine::sweep::verdict::SweepSummary;
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::output::windows::Window;

/// Time spans kept per responder.
pub(crate) const SPANS: usize = 1024;
/// Width of a span at the start: fine enough for 1 kHz pinging.
const FIRST_SPAN_NS: Nanos = 1_000_000;
/// Distribution bins per decade (4% wide), from 10 µs to 100 s.
pub(super) const BINS_PER_DECADE: usize = 60;
const LOWEST_US: f64 = 10.0;
const BINS: usize = 7 * BINS_PER_DECADE;

#[derive(Debug, Clone)]
pub(super) struct Track {
    pub(super) spans: Bins,
    pub(super) bins: [u64; BINS],
    /// The run's own figures for it, for the legend: known once the
    /// link's summary came.
    pub(super) summary: Option<ResponderSummary>,
}

impl Track {
    fn new() -> Self {
        Track {
            spans: Bins::new(FIRST_SPAN_NS as f64, 1e9, SPANS),
            bins: [0; BINS],
            summary: None,
        }
    }
}

pub(super) fn bin(rtt: Nanos) -> usize {
    let us = (rtt as f64 / 1e3).max(LOWEST_US);
    let i = ((us / LOWEST_US).log10() * BINS_PER_DECADE as f64) as usize;
    i.min(BINS - 1)
}

pub(super) fn bin_low_ms(i: usize) -> f64 {
    LOWEST_US * 10f64.powf(i as f64 / BINS_PER_DECADE as f64) / 1e3
}

/// The samples a plot is drawn from: every link's responders.
#[derive(Debug, Default)]
pub(crate) struct PlotData {
    /// Each link's name, by its place on the command line.
    pub(super) links: Vec<String>,
    pub(super) tracks: BTreeMap<(usize, SysComp), Track>,
    /// Each sweeping link's steps, once its summary came.
    sweeps: BTreeMap<usize, SweepSummary>,
    /// A passive run's sources (at most its table's, per link).
    sources: BTreeMap<(usize, SysComp), SourceTrack>,
    /// A telemetry log's flight, window by window, per link.
    pub(super) flights: BTreeMap<usize, FlightTrack>,
    /// A download run's downloads, per link.
    pub(super) downloads: BTreeMap<usize, transfer::Downloads>,
    /// The C2 link report of each link whose run made one.
    pub(super) c2: BTreeMap<usize, C2Report>,
}

impl PlotData {
    pub(crate) fn on_event(&mut self, link: usize, e: &MatchEvent) {
        let (MatchEvent::Reply { responder, .. } | MatchEvent::Lost { responder, .. }) = *e else {
            return;
        };
        let track = self
            .tracks
            .entry((link, responder))
            .or_insert_with(Track::new);
        match *e {
            MatchEvent::Reply { sent_at, rtt, .. } => {
                let span = track.spans.at(sent_at as f64);
                span.rtt_ns.0 += rtt as f64;
                span.rtt_ns.1 += 1;
                track.bins[bin(rtt)] += 1;
            }
            MatchEvent::Lost { sent_at, .. } => track.spans.at(sent_at as f64).lost += 1,
            _ => {}
        }
    }

    /// The plot's title: `kind` (as the command line names it) and the
    /// link, or how many.
    fn title(&self, kind: &str) -> String {
        match self.links.as_slice() {
            [one] => format!("mavping{kind} {one}"),
            several => format!("mavping{kind}, {} links", several.len()),
        }
    }

    /// The windows of a passive link's sources, and the oldest frame's age
    /// (ms) of each source with stamped frames in them.
    pub(crate) fn on_windows(&mut self, link: usize, windows: &[Window], ages: &[(SysComp, f64)]) {
        for w in windows {
            let track = self
                .sources
                .entry((link, w.source))
                .or_insert_with(|| SourceTrack::new(w.radio));
            track.window(w);
            if let Some(&(_, ms)) = ages.iter().find(|(s, _)| *s == w.source) {
                track.age(w, ms);
            }
        }
    }

    /// The pair report told at `at` (its links by place on the command
    /// line): each link's part in each source heard on several.
    /// Only a passive run's sources are drawn: a probe run's page is its
    /// responders'.
    pub(crate) fn on_pair(&mut self, at: Nanos, summary: &PairSummary) {
        for source in &summary.sources {
            for link in &source.links {
                if let Some(track) = self.sources.get_mut(&(link.link, source.source)) {
                    track.paired(at, link);
                }
            }
        }
    }

    /// The run's own figures for each source of a passive `link`: its
    /// table's, and its headline ages'.
    pub(crate) fn on_sources(&mut self, link: usize, table: &TableSummary, ages: &[SourceAge]) {
        for s in &table.sources {
            if let Some(t) = self.sources.get_mut(&(link, s.source)) {
                t.summary = Some(s.clone());
            }
        }
        for a in ages {
            if let Some(t) = self.sources.get_mut(&(link, a.source)) {
                t.age_p99_ms = Some(a.headline.p99_ms);
            }
        }
    }

    /// A responder's legend entry; with several links, its link too.
    pub(super) fn label(&self, link: usize, id: SysComp) -> String {
        match self.links.len() {
            1 => id.to_string(),
            _ => format!("{} {id}", self.links.get(link).map_or("?", String::as_str)),
        }
    }

    /// Draws the SVG document: the C2 link report's page when the run
    /// made one (the first link's that did), else RTT and loss against
    /// the offered rate for a sweep, else RTT over time and its
    /// distribution.
    pub(crate) fn svg(&self) -> Result<String, PlotError> {
        if let Some((&link, report)) = self.c2.iter().next() {
            let name = self.links.get(link).map_or("?", String::as_str);
            return c2::svg(name, report);
        }
        // A log's flight report (the first log's, if there are several).
        if let Some((&link, track)) = self.flights.iter().find(|(_, t)| !t.is_empty()) {
            let name = self.links.get(link).map_or("?", String::as_str);
            return flight::svg(&flight::title(name, track), track);
        }
        if !self.downloads.is_empty() {
            let flat: BTreeMap<(usize, u32), &transfer::DownloadTrack> = self
                .downloads
                .iter()
                .flat_map(|(&link, d)| d.iter().map(move |(&n, t)| ((link, n), t)))
                .collect();
            let entries = frame::entries(&flat, |(link, n), _| match self.links.len() {
                1 => format!("download {n}"),
                _ => format!(
                    "{} download {n}",
                    self.links.get(link).map_or("?", String::as_str)
                ),
            });
            let entries: Vec<_> = entries
                .into_iter()
                .map(|e| frame::Entry {
                    label: e.label,
                    look: e.look,
                    track: *e.track,
                })
                .collect();
            return transfer::svg(&self.title(" downloads"), &entries);
        }
        if !self.sources.is_empty() {
            let entries = frame::entries(&self.sources, |(link, id), track| {
                let radio = if track.radio { " (radio)" } else { "" };
                format!("{}{radio}", self.label(link, id))
            });
            return passive::svg(&self.title(" --passive"), &entries);
        }
        if self.sweeps.is_empty() {
            let entries = frame::entries(&self.tracks, |(link, id), _| self.label(link, id));
            return draw::svg(&self.title(""), &entries);
        }
        let entries = frame::entries(&self.sweeps, |link, _| {
            self.links.get(link).cloned().unwrap_or_default()
        });
        sweep::svg(&self.title(" sweep"), &entries)
    }

    /// A link's sweep, drawn instead of its RTT over time.
    pub(crate) fn on_sweep(&mut self, link: usize, sweep: &SweepSummary) {
        if sweep.kind == "sweep" {
            self.sweeps.insert(link, sweep.clone());
        }
    }

    /// The run's own figures for each responder of `link`, for the legend.
    pub(crate) fn on_summary(&mut self, link: usize, responders: &[ResponderSummary]) {
        for r in responders {
            if let Some(t) = self.tracks.get_mut(&(link, r.id)) {
                t.summary = Some(r.clone());
            }
        }
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
        assert!(t.spans.bins.len() <= SPANS);
        assert_eq!(
            t.spans.bins.iter().map(|s| s.rtt_ns.1).sum::<u64>(),
            324_000
        );
        assert_eq!(t.spans.bins.iter().map(|s| s.lost).sum::<i64>(), 36_000);
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
        // Every loss is marked in its responder's own colour and shape
        // (a cross in blue, a triangle in vermillion), none in pure red.
        assert!(!svg.contains("#FF0000"), "a loss drawn in red");
        assert!(svg.contains(r##"stroke="#0072B2""##));
        assert!(svg.contains(r##"fill="#D55E00""##));
    }

    fn figures(received: u64, lost: u64, rtt_ms: &[u64]) -> ResponderSummary {
        let mut rtt = crate::engine::stats::RttStats::new();
        for &ms in rtt_ms {
            rtt.record(ms * 1_000_000);
        }
        let counts = crate::engine::matcher::Counts {
            sent: received + lost,
            received,
            lost,
            ..Default::default()
        };
        ResponderSummary {
            id: SysComp::new(1, 1),
            counts,
            loss_ratio: counts.loss_ratio(),
            rtt: rtt.summary(),
            histogram: Vec::new(),
            identity: None,
            probe: None,
            clock: None,
            direction: None,
            split: None,
        }
    }

    #[test]
    fn the_legend_shows_the_summary_figures_beside_the_charts() {
        let r = SysComp::new(1, 1);
        let mut d = PlotData {
            links: vec!["sim:".into()],
            ..PlotData::default()
        };
        let rtts: Vec<u64> = (1..=100).collect();
        for (i, &ms) in rtts.iter().enumerate() {
            d.on_event(0, &reply(r, i as u64 * 100_000_000, ms * 1_000_000));
        }
        let svg = d.svg().unwrap();
        // Before the summary, the figures are unknown, not made up.
        assert!(svg.contains("\n-\n"), "no placeholder");

        d.on_summary(0, &[figures(100, 300, &rtts)]);
        let svg = d.svg().unwrap();
        for text in ["responder", "sent", "loss %", "p50 ms", "p99 ms"] {
            assert!(svg.contains(&format!("\n{text}\n")), "{text} missing");
        }
        // 400 sent, 75 % lost; the percentiles are the summary's own.
        let p50 = figures(100, 300, &rtts).rtt.unwrap().p50_us / 1e3;
        for text in ["400", "75.00", &format!("{p50:.3}")] {
            assert!(svg.contains(&format!("\n{text}\n")), "{text} missing");
        }
        // The legend has a band of its own below the charts: its first row
        // is lower than anything a chart draws.
        let legend_y = y_of(&svg, "\nresponder\n");
        let lowest_chart_text = y_of(&svg, "RTT (ms, log scale");
        assert!(
            legend_y > lowest_chart_text + 20,
            "{legend_y} {lowest_chart_text}"
        );
    }

    /// The `y` of the `<text>` element holding `text`.
    fn y_of(svg: &str, text: &str) -> i64 {
        let at = svg.find(text).unwrap_or_else(|| panic!("{text} missing"));
        let tag = &svg[svg[..at].rfind("<text").unwrap()..at];
        let y = tag.split(" y=\"").nth(1).unwrap();
        y[..y.find('"').unwrap()].parse().unwrap()
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
