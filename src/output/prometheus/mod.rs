//! Metrics in the Prometheus text format: per-responder counters and RTT
//! histogram, RADIO_STATUS gauges, LINK_NODE_STATUS counters, and what `mavping serve` adds (a
//! continuous link's state, one `/probe`'s result, the exporter's health).
//! The one renderer of every exposition mavping serves.
//!
//! A [`Metrics`] follows one link's session as an engine [`Observer`].
//! `--prometheus` serves the run's links at `/metrics` while it goes on
//! ([`PrometheusExporter`]); memory is fixed per responder, radio and
//! source (the matcher, the radio table and the source table bound how
//! many there are), whatever the run length. A passive run's per-source
//! figures and an echo run's loss by direction come from the table of
//! sources the engine tells once a second ([`sources`]).

mod exposition;
mod link_node;
mod passive;
mod render;
mod sources;

use std::cell::{Ref, RefCell};
use std::collections::BTreeMap;
use std::io;
use std::net::SocketAddr;
use std::rc::Rc;

use hyper::StatusCode;

use super::http::{self, Head, Limits, Reply, Replying};
use super::{Event, Reporter, StartInfo};
use crate::engine::clock_offset::ClockSummary;
use crate::engine::link_node::LinkNodeReport;
use crate::engine::matcher::MatchEvent;
use crate::engine::observe::{CommandEvent, RadioHeard};
use crate::engine::radio::{RadioKind, RadioReport, SinceBootCounter, MAX_RADIOS};
use crate::engine::summary::passive::{PassiveSummary, TableSummary};
use crate::engine::summary::{CommandSummary, Direction, LinkSummary, ProbeName, Summary};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;
pub(crate) use render::{render, render_probe, render_serve, Health, ProbeResult};

/// Upper bounds of the RTT histogram, in seconds: from loopback (sub-ms)
/// to a congested 57600-baud radio (seconds).
pub(crate) const BUCKETS_S: [f64; 14] = [
    0.000_5, 0.001, 0.002_5, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
];

/// What a [`Metrics`] stands for, which decides how its counts are typed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scope {
    /// A run or a continuous link: counters that only grow (`_total`).
    Run,
    /// One `/probe`: that probe's counts (as gauges) and histogram, under
    /// names of their own, so `rate()` is never applied to figures that
    /// start afresh each scrape.
    Probe,
}

#[derive(Debug, Default, Clone)]
struct Series {
    sent: u64,
    received: u64,
    lost: u64,
    late: u64,
    duplicate: u64,
    /// Non-cumulative counts per bucket; the last one is +Inf.
    buckets: [u64; BUCKETS_S.len() + 1],
    rtt_sum_s: f64,
    last_rtt_s: Option<f64>,
    /// From the summary at the end (the HDR histogram's figures).
    p50_s: Option<f64>,
    p99_s: Option<f64>,
    clock_offset_s: Option<f64>,
    /// `--probe auto`: whether it is measured by TIMESYNC (else PING).
    via_timesync: Option<u8>,
    split: Split,
    /// It answered a request of the link's current session (in time or
    /// late).
    answering: bool,
}

/// Where a responder's loss by direction comes from.
#[derive(Debug, Default, Clone, Copy)]
enum Split {
    /// Made at each scrape while the run goes on.
    #[default]
    Live,
    /// The summary's own, once the run has ended (`None`: it found none).
    AtEnd(Option<Direction>),
}

impl Series {
    fn observe(&mut self, rtt: Nanos) {
        let s = rtt as f64 / 1e9;
        let i = BUCKETS_S
            .iter()
            .position(|&b| s <= b)
            .unwrap_or(BUCKETS_S.len());
        self.buckets[i] += 1;
        self.rtt_sum_s += s;
        self.last_rtt_s = Some(s);
    }

    fn decided(&mut self, received: Option<Nanos>) {
        self.sent += 1;
        match received {
            Some(rtt) => {
                self.answering = true;
                self.received += 1;
                self.observe(rtt);
            }
            None => self.lost += 1,
        }
    }

    fn loss_ratio(&self) -> Option<f64> {
        (self.sent > 0).then(|| self.lost as f64 / self.sent as f64)
    }

    /// Its loss by direction, from its requests and its own frames'
    /// sequence (`downlink`), as the summary splits it.
    fn direction(&self, downlink: Option<&sources::SourceSeries>) -> Option<Direction> {
        match self.split {
            Split::AtEnd(at_end) => at_end,
            Split::Live => Direction::of_sequence(self.loss_ratio()?, self.sent, &downlink?.seq()),
        }
    }
}

/// One radio: its latest RADIO_STATUS, and its error counters turned into
/// counters that only grow (the radio's own are 16 bits and wrap, and
/// start again from 0 when it restarts).
#[derive(Debug, Clone, Copy)]
struct RadioSeries {
    latest: RadioReport,
    /// What the radio is, as the run judges it so far: what its fields
    /// mean.
    kind: RadioKind,
    rxerrors: SinceBootCounter,
    fixed: SinceBootCounter,
}

impl RadioSeries {
    fn new(kind: RadioKind) -> Self {
        RadioSeries {
            latest: RadioReport::default(),
            kind,
            rxerrors: SinceBootCounter::default(),
            fixed: SinceBootCounter::default(),
        }
    }

    fn record(&mut self, report: RadioReport, kind: RadioKind) {
        self.kind = kind;
        self.latest = report;
        self.rxerrors.record(report.rxerrors);
        self.fixed.record(report.fixed);
    }
}

/// One link's metrics.
#[derive(Debug, Default)]
pub(crate) struct Metrics {
    link: String,
    /// `None` before a session starts (an unopened link's metrics).
    probe: Option<ProbeName>,
    responders: BTreeMap<SysComp, Series>,
    /// Each radio heard.
    radios: BTreeMap<SysComp, RadioSeries>,
    /// Each node heard by its LINK_NODE_STATUS.
    link_nodes: link_node::Nodes,
    /// Each source's packet sequence (a passive run's figures; an echo
    /// run's responders' downlink).
    sources: sources::Sources,
    /// Open now, and (a continuous link of `mavping serve`) how often it
    /// was reopened after breaking; `None` before a session starts.
    state: Option<LinkState>,
    requests: Requests,
}

/// Requests the link put on the wire, whoever answered them: in the
/// sessions before (a continuous link reopened), and in this one so far.
#[derive(Debug, Default, Clone, Copy)]
struct Requests {
    earlier: u64,
    session: u64,
}

impl Requests {
    fn total(self) -> u64 {
        self.earlier + self.session
    }
}

#[derive(Debug, Default, Clone, Copy)]
struct LinkState {
    up: bool,
    restarts: u64,
}

impl Metrics {
    /// A continuous link's metrics, named `link` before its first session
    /// (so a link that never opens still shows `mavping_link_up 0`).
    pub(crate) fn continuous(link: &str, probe: ProbeName) -> Self {
        Metrics {
            link: link.to_string(),
            probe: Some(probe),
            state: Some(LinkState::default()),
            ..Metrics::default()
        }
    }

    /// A run's link that could not be opened: down from the start.
    pub(crate) fn unopened(link: &str) -> Self {
        Metrics {
            link: link.to_string(),
            state: Some(LinkState::default()),
            ..Metrics::default()
        }
    }

    /// A link opened (`true`) or broke (`false`).
    pub(crate) fn set_up(&mut self, up: bool) {
        let state = self.state.get_or_insert_with(LinkState::default);
        state.up = up;
    }

    /// Whether a continuous link is open now.
    pub(crate) fn is_up(&self) -> bool {
        self.state.is_some_and(|s| s.up)
    }

    /// A continuous link is being reopened after it broke.
    pub(crate) fn restarted(&mut self) {
        self.state.get_or_insert_with(LinkState::default).restarts += 1;
    }

    pub(crate) fn on_start(&mut self, info: &StartInfo) {
        self.link = info.link.clone();
        self.probe = Some(info.probe);
        self.set_up(true);
        // A continuous link's new session: its sequences start afresh,
        // its counters go on.
        self.sources.carry();
        self.requests.earlier += std::mem::take(&mut self.requests.session);
        for s in self.responders.values_mut() {
            s.split = Split::Live;
            s.answering = false;
        }
    }

    /// Whether the link sends requests (a passive one does not); `None`
    /// before a session starts.
    fn sends(&self) -> bool {
        self.probe.is_some_and(|p| p != ProbeName::Passive)
    }

    /// Responders that answered in the link's current session.
    fn answering(&self) -> usize {
        self.responders.values().filter(|s| s.answering).count()
    }

    /// The table of sources, as told while the session goes on (`ended`
    /// false) or in its summary.
    pub(crate) fn on_sources(&mut self, table: &TableSummary, ended: bool) {
        self.sources.update(table, ended);
    }

    pub(crate) fn on_event(&mut self, e: &MatchEvent) {
        match *e {
            MatchEvent::Reply { responder, rtt, .. } => {
                let auto = self.probe == Some(ProbeName::Auto);
                let s = self.responders.entry(responder).or_default();
                s.decided(Some(rtt));
                // PING until its clock says TIMESYNC (told with its first
                // reply, in the same report).
                if auto && s.via_timesync.is_none() {
                    s.via_timesync = Some(0);
                }
            }
            MatchEvent::Lost { responder, .. } => {
                self.responders.entry(responder).or_default().decided(None);
            }
            // A late reply was already counted sent and lost when its
            // timeout passed.
            MatchEvent::Late { responder, .. } => {
                let s = self.responders.entry(responder).or_default();
                s.late += 1;
                s.answering = true;
            }
            MatchEvent::Duplicate { responder, .. } => {
                let s = self.responders.entry(responder).or_default();
                s.duplicate += 1;
                s.answering = true;
            }
            MatchEvent::Stale { .. } => {}
        }
    }

    /// `--probe command`: a command target is a responder whose requests
    /// are commands; acknowledged is received, failed is lost, and the
    /// time to ACK its RTT.
    pub(crate) fn on_command(&mut self, e: &CommandEvent) {
        match *e {
            CommandEvent::Acked {
                target,
                time_to_ack,
                ..
            } => self
                .responders
                .entry(target)
                .or_default()
                .decided(Some(time_to_ack)),
            CommandEvent::Failed { target, .. } => {
                self.responders.entry(target).or_default().decided(None);
            }
            CommandEvent::LateAck { from, .. } => {
                let s = self.responders.entry(from).or_default();
                s.late += 1;
                s.answering = true;
            }
            CommandEvent::DuplicateAck { from, .. } => {
                let s = self.responders.entry(from).or_default();
                s.duplicate += 1;
                s.answering = true;
            }
            CommandEvent::Send { .. } | CommandEvent::Skipped { .. } => {}
        }
    }

    /// A RADIO_STATUS from a radio of `kind`: its figures replace the
    /// radio's last ones.
    pub(crate) fn on_radio(&mut self, id: SysComp, report: RadioReport, kind: RadioKind) {
        if self.radios.len() < MAX_RADIOS || self.radios.contains_key(&id) {
            self.radios
                .entry(id)
                .or_insert_with(|| RadioSeries::new(kind))
                .record(report, kind);
        }
    }

    /// A TIMESYNC responder's clock offset so far, carried from the run's
    /// start to `at` along the measured drift (none until it is measured).
    pub(crate) fn on_clock(&mut self, id: SysComp, at: Nanos, clock: &ClockSummary) {
        let auto = self.probe == Some(ProbeName::Auto);
        if let Some(s) = self.responders.get_mut(&id) {
            // Only TIMESYNC replies give a clock.
            if auto {
                s.via_timesync = Some(1);
            }
            let drift_ns = clock.drift_ppm.unwrap_or(0.0) * 1e-6 * at as f64;
            s.clock_offset_s = Some((clock.offset_ns as f64 + drift_ns) / 1e9);
        }
    }

    /// The figures known only at the end (percentiles from the HDR
    /// histogram), so a last scrape or a `/probe` has them.
    pub(crate) fn on_summary(&mut self, summary: &Summary) {
        for r in &summary.responders {
            let s = self.responders.entry(r.id).or_default();
            // The live figure, when there is one, is the later.
            if let (None, Some(c)) = (s.clock_offset_s, &r.clock) {
                s.clock_offset_s = Some(c.offset_ns as f64 / 1e9);
            }
            if let Some(rtt) = &r.rtt {
                s.p50_s = Some(rtt.p50_us / 1e6);
                s.p99_s = Some(rtt.p99_us / 1e6);
            }
            s.split = Split::AtEnd(r.direction);
            if let Some(p) = r.probe {
                s.via_timesync = Some(u8::from(p == ProbeName::Timesync));
            }
        }
    }

    #[cfg(test)]
    /// The exposition of this link alone, as `--prometheus` serves it.
    pub(crate) fn render(&self) -> String {
        render(&[self])
    }
}

impl Reporter for Metrics {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.on_start(info);
        Ok(())
    }

    fn matched(&mut self, e: &MatchEvent) -> io::Result<()> {
        self.on_event(e);
        Ok(())
    }

    fn command(&mut self, e: &CommandEvent) -> io::Result<()> {
        self.on_command(e);
        Ok(())
    }

    fn radio(&mut self, radio: &RadioHeard<'_>) -> io::Result<()> {
        self.on_radio(radio.id, radio.report, radio.judgement.kind);
        Ok(())
    }

    fn link_node(
        &mut self,
        id: SysComp,
        _: Nanos,
        report: &LinkNodeReport,
        _: bool,
    ) -> io::Result<()> {
        self.link_nodes.record(id, *report);
        Ok(())
    }

    fn clock(&mut self, id: SysComp, at: Nanos, clock: &ClockSummary) -> io::Result<()> {
        self.on_clock(id, at, clock);
        Ok(())
    }

    fn link_failed(&mut self, _: Nanos, _: &str) -> io::Result<()> {
        self.set_up(false);
        Ok(())
    }

    fn sources(&mut self, _: Nanos, table: &TableSummary) -> io::Result<()> {
        self.on_sources(table, false);
        Ok(())
    }

    fn progress(&mut self, _: Nanos, requests: u64) -> io::Result<()> {
        self.requests.session = requests;
        Ok(())
    }

    fn echo_summary(&mut self, summary: &Summary, _: &Verdict) -> io::Result<()> {
        self.requests.session = summary.requests;
        self.on_summary(summary);
        Ok(())
    }

    fn passive_summary(&mut self, summary: &PassiveSummary, _: &Verdict) -> io::Result<()> {
        self.on_sources(&summary.table, true);
        Ok(())
    }

    fn command_summary(&mut self, summary: &CommandSummary, _: &Verdict) -> io::Result<()> {
        self.requests.session = summary.targets.iter().map(|t| t.commands).sum();
        Ok(())
    }
}

/// One link's metrics, written by its session and read by scrapes; every
/// part of a run or a server lives on one thread.
#[derive(Debug, Clone, Default)]
pub struct SharedMetrics(Rc<RefCell<Metrics>>);

impl SharedMetrics {
    pub(crate) fn new(metrics: Metrics) -> Self {
        SharedMetrics(Rc::new(RefCell::new(metrics)))
    }

    pub(crate) fn get(&self) -> Ref<'_, Metrics> {
        self.0.borrow()
    }

    pub(crate) fn update(&self, f: impl FnOnce(&mut Metrics)) {
        f(&mut self.0.borrow_mut());
    }
}

impl Reporter for SharedMetrics {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.0.borrow_mut().start(info)
    }

    fn tell(&mut self, event: &Event<'_>) -> io::Result<()> {
        self.0.borrow_mut().tell(event)
    }

    fn summary(&mut self, summary: &LinkSummary, verdict: &Verdict) -> io::Result<()> {
        self.0.borrow_mut().summary(summary, verdict)
    }
}

/// Renders several shared links at once.
pub(crate) fn borrow_all(links: &[SharedMetrics]) -> Vec<Ref<'_, Metrics>> {
    links.iter().map(SharedMetrics::get).collect()
}

/// `--prometheus`: the run's links at `/metrics` while the run goes on.
#[derive(Default)]
pub struct PrometheusExporter {
    links: Rc<RefCell<Vec<SharedMetrics>>>,
}

impl PrometheusExporter {
    /// Starts serving `listener` on the current `LocalSet`.
    pub(crate) fn serve(listener: std::net::TcpListener) -> io::Result<(Self, SocketAddr)> {
        let listener = http::listener(listener)?;
        let addr = listener.local_addr()?;
        let exporter = PrometheusExporter::default();
        http::serve(listener, Limits::default(), exporter.handler());
        Ok((exporter, addr))
    }

    /// What answers each request: `/metrics` renders every link as it is
    /// now. Also the fuzz target's way in.
    pub fn handler(&self) -> impl Fn(Head) -> Replying + 'static {
        let links = self.links.clone();
        move |head: Head| -> Replying {
            let reply = match head.uri.path() {
                "/metrics" => {
                    let links = links.borrow();
                    let all = borrow_all(&links);
                    let refs: Vec<&Metrics> = all.iter().map(|m| &**m).collect();
                    Reply::metrics(render(&refs))
                }
                "/" => Reply::text(StatusCode::OK, "mavping: metrics at /metrics\n"),
                _ => Reply::text(StatusCode::NOT_FOUND, "not found\n"),
            };
            Box::pin(std::future::ready(reply))
        }
    }

    /// Every link as it is now, as `/metrics` would show it.
    pub(crate) fn render_now(&self) -> String {
        let links = self.links.borrow();
        let all = borrow_all(&links);
        let refs: Vec<&Metrics> = all.iter().map(|m| &**m).collect();
        render(&refs)
    }

    /// The reporter of the `index`-th link, served at the same address.
    pub fn link(&self, index: usize) -> SharedMetrics {
        let mut links = self.links.borrow_mut();
        if links.len() <= index {
            links.resize_with(index + 1, SharedMetrics::default);
        }
        links[index].clone()
    }
}

/// A PING run's start on `link`, for the tests here and in `render`.
#[cfg(test)]
fn test_start(link: &str) -> StartInfo {
    use crate::engine::observe::RunKind;
    use std::time::Duration;
    StartInfo {
        link: link.into(),
        probe: ProbeName::Ping,
        ours: SysComp::new(255, 190),
        interval: Duration::from_secs(1),
        timeout: Duration::from_secs(2),
        count: None,
        run: RunKind::Echo,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_and_histogram_follow_the_events() {
        let mut m = Metrics::default();
        m.on_start(&test_start("udpout:\"a\\b\""));
        let r = SysComp::new(1, 1);
        let reply = |seq, rtt| MatchEvent::Reply {
            responder: r,
            seq,
            rtt,
            sent_at: 0,
            at: rtt,
            out_of_order: false,
            first_from_responder: seq == 0,
        };
        m.on_event(&reply(0, 800_000));
        m.on_event(&reply(1, 30_000_000));
        m.on_event(&MatchEvent::Lost {
            responder: r,
            seq: 2,
            sent_at: 0,
            at: 0,
        });
        m.on_event(&MatchEvent::Late {
            responder: r,
            seq: 2,
            rtt: 20_000_000_000,
            sent_at: 0,
            at: 0,
        });
        m.on_event(&MatchEvent::Duplicate {
            responder: r,
            seq: 1,
            rtt: 1,
            sent_at: 0,
            at: 0,
        });
        let text = m.render();
        let l = r#"link="udpout:\"a\\b\"",probe="ping",sysid="1",compid="1""#;
        for line in [
            format!("mavping_sent_total{{{l}}} 3"),
            format!("mavping_received_total{{{l}}} 2"),
            format!("mavping_lost_total{{{l}}} 1"),
            format!("mavping_late_total{{{l}}} 1"),
            format!("mavping_duplicate_total{{{l}}} 1"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.0005\"}} 0"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.001\"}} 1"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.025\"}} 1"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"0.05\"}} 2"),
            format!("mavping_rtt_seconds_bucket{{{l},le=\"+Inf\"}} 2"),
            format!("mavping_rtt_seconds_count{{{l}}} 2"),
            format!("mavping_last_rtt_seconds{{{l}}} 0.03"),
        ] {
            assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
        }
        let sum: f64 = text
            .lines()
            .find_map(|x| x.strip_prefix(&format!("mavping_rtt_seconds_sum{{{l}}} ")))
            .unwrap()
            .parse()
            .unwrap();
        assert!((sum - 0.0308).abs() < 1e-12, "{sum}");
        assert!(!text.contains("mavping_clock_offset_seconds{"));
    }

    /// A continuous link's requests go on across its sessions; who answers
    /// is its current session's.
    #[test]
    fn requests_add_up_across_sessions_and_responders_are_the_sessions() {
        let mut m = Metrics::continuous("udpout:h:1", ProbeName::Ping);
        let link = r#"link="udpout:h:1",probe="ping""#;
        let has = |m: &Metrics, line: String| {
            let text = m.render();
            assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
        };
        has(&m, format!("mavping_requests_total{{{link}}} 0"));
        has(&m, format!("mavping_responders{{{link}}} 0"));
        let _ = m.start(&test_start("udpout:h:1"));
        let _ = m.tell(&Event::Progress { at: 0, requests: 3 });
        m.on_event(&MatchEvent::Reply {
            responder: SysComp::new(1, 1),
            seq: 0,
            rtt: 1,
            sent_at: 0,
            at: 1,
            out_of_order: false,
            first_from_responder: true,
        });
        has(&m, format!("mavping_requests_total{{{link}}} 3"));
        has(&m, format!("mavping_responders{{{link}}} 1"));
        // Reopened: nobody has answered the new session yet.
        let _ = m.start(&test_start("udpout:h:1"));
        let _ = m.tell(&Event::Progress { at: 0, requests: 2 });
        has(&m, format!("mavping_requests_total{{{link}}} 5"));
        has(&m, format!("mavping_responders{{{link}}} 0"));
        // A passive link sends nothing: neither family.
        let passive = Metrics::continuous("udpin:0.0.0.0:1", ProbeName::Passive);
        assert!(!passive.render().contains("mavping_requests_total"));
    }
}
