//! Metrics in the Prometheus text format: per-responder counters and RTT
//! histogram, RADIO_STATUS gauges, and what `mavping serve` adds (a
//! continuous link's state, one `/probe`'s result, the exporter's health).
//! The one renderer of every exposition mavping serves.
//!
//! A [`Metrics`] follows one link's session as an engine [`Observer`].
//! `--prometheus` serves the run's links at `/metrics` while it goes on
//! ([`PrometheusExporter`]); memory is fixed per responder and radio (the
//! matcher and the radio table bound how many there are), whatever the run
//! length.

use std::cell::{Ref, RefCell};
use std::collections::BTreeMap;
use std::fmt::{Display, Write as _};
use std::io;
use std::net::SocketAddr;
use std::rc::Rc;

use hyper::StatusCode;

use super::http::{self, Head, Limits, Reply, Replying};
use super::{Event, Observer, Reporter, StartInfo};
use crate::engine::commands::CommandEvent;
use crate::engine::matcher::MatchEvent;
use crate::engine::radio::{RadioReport, MAX_RADIOS, UNKNOWN};
use crate::engine::summary::{LinkSummary, Summary};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;

/// Upper bounds of the RTT histogram, in seconds: from loopback (sub-ms)
/// to a congested 57600-baud radio (seconds).
pub const BUCKETS_S: [f64; 14] = [
    0.000_5, 0.001, 0.002_5, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
];

/// What a [`Metrics`] stands for, which decides how its counts are typed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
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
                self.received += 1;
                self.observe(rtt);
            }
            None => self.lost += 1,
        }
    }

    fn loss_ratio(&self) -> Option<f64> {
        (self.sent > 0).then(|| self.lost as f64 / self.sent as f64)
    }
}

/// One link's metrics.
#[derive(Debug, Default)]
pub struct Metrics {
    link: String,
    probe: &'static str,
    responders: BTreeMap<SysComp, Series>,
    /// The latest RADIO_STATUS of each radio heard.
    radios: BTreeMap<SysComp, RadioReport>,
    /// A continuous link of `mavping serve`: open now, and how often it
    /// was reopened after breaking.
    state: Option<LinkState>,
}

#[derive(Debug, Default, Clone, Copy)]
struct LinkState {
    up: bool,
    restarts: u64,
}

impl Metrics {
    /// A continuous link's metrics, named `link` before its first session
    /// (so a link that never opens still shows `mavping_link_up 0`).
    pub fn continuous(link: &str, probe: &'static str) -> Self {
        Metrics {
            link: link.to_string(),
            probe,
            state: Some(LinkState::default()),
            ..Metrics::default()
        }
    }

    /// A continuous link opened (`true`) or broke (`false`).
    pub fn set_up(&mut self, up: bool) {
        let state = self.state.get_or_insert_with(LinkState::default);
        state.up = up;
    }

    /// Whether a continuous link is open now.
    pub fn is_up(&self) -> bool {
        self.state.is_some_and(|s| s.up)
    }

    /// A continuous link is being reopened after it broke.
    pub fn restarted(&mut self) {
        self.state.get_or_insert_with(LinkState::default).restarts += 1;
    }

    pub fn on_start(&mut self, info: &StartInfo) {
        self.link = info.link.clone();
        self.probe = info.probe;
    }

    pub fn on_event(&mut self, e: &MatchEvent) {
        match *e {
            MatchEvent::Reply { responder, rtt, .. } => {
                self.responders
                    .entry(responder)
                    .or_default()
                    .decided(Some(rtt));
            }
            MatchEvent::Lost { responder, .. } => {
                self.responders.entry(responder).or_default().decided(None);
            }
            // A late reply was already counted sent and lost when its
            // timeout passed.
            MatchEvent::Late { responder, .. } => {
                self.responders.entry(responder).or_default().late += 1;
            }
            MatchEvent::Duplicate { responder, .. } => {
                self.responders.entry(responder).or_default().duplicate += 1;
            }
            MatchEvent::Stale { .. } => {}
        }
    }

    /// `--probe command`: a command target is a responder whose requests
    /// are commands; acknowledged is received, failed is lost, and the
    /// time to ACK its RTT.
    pub fn on_command(&mut self, e: &CommandEvent) {
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
                self.responders.entry(from).or_default().late += 1;
            }
            CommandEvent::DuplicateAck { from, .. } => {
                self.responders.entry(from).or_default().duplicate += 1;
            }
            CommandEvent::Send { .. } | CommandEvent::Skipped { .. } => {}
        }
    }

    /// A RADIO_STATUS: its figures replace the radio's last ones.
    pub fn on_radio(&mut self, id: SysComp, report: RadioReport) {
        if self.radios.len() < MAX_RADIOS || self.radios.contains_key(&id) {
            self.radios.insert(id, report);
        }
    }

    /// The figures known only at the end (percentiles from the HDR
    /// histogram, TIMESYNC clock offsets), so a last scrape or a `/probe`
    /// has them.
    pub fn on_summary(&mut self, summary: &Summary) {
        for r in &summary.responders {
            let s = self.responders.entry(r.id).or_default();
            if let Some(c) = &r.clock {
                s.clock_offset_s = Some(c.offset_ns as f64 / 1e9);
            }
            if let Some(rtt) = &r.rtt {
                s.p50_s = Some(rtt.p50_us / 1e6);
                s.p99_s = Some(rtt.p99_us / 1e6);
            }
        }
    }

    /// The exposition of this link alone, as `--prometheus` serves it.
    pub fn render(&self) -> String {
        render(&[self])
    }

    fn labels(&self, id: SysComp) -> String {
        format!(
            "link=\"{}\",probe=\"{}\",sysid=\"{}\",compid=\"{}\"",
            escape(&self.link),
            self.probe,
            id.sysid,
            id.compid
        )
    }

    fn radio_labels(&self, id: SysComp) -> String {
        format!(
            "link=\"{}\",sysid=\"{}\",compid=\"{}\"",
            escape(&self.link),
            id.sysid,
            id.compid
        )
    }
}

impl Observer for Metrics {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.on_start(info);
        Ok(())
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        match event {
            Event::Match(e) => self.on_event(e),
            Event::Command(e) => self.on_command(e),
            Event::Radio { id, report, .. } => self.on_radio(*id, *report),
            Event::Heard { .. } | Event::WaitingForPeer => {}
        }
        Ok(())
    }
}

impl Reporter for Metrics {
    fn summary(&mut self, summary: &LinkSummary, _: &Verdict) -> io::Result<()> {
        if let LinkSummary::Echo(summary) = summary {
            self.on_summary(summary);
        }
        Ok(())
    }
}

/// Text being written in the exposition format: a family's `HELP` and
/// `TYPE` lines, then its samples.
#[derive(Default)]
struct Exposition(String);

impl Exposition {
    fn header(&mut self, name: &str, kind: &str, help: &str) {
        let _ = writeln!(self.0, "# HELP {name} {help}\n# TYPE {name} {kind}");
    }

    fn sample(&mut self, name: &str, labels: &str, value: impl Display) {
        let _ = if labels.is_empty() {
            writeln!(self.0, "{name} {value}")
        } else {
            writeln!(self.0, "{name}{{{labels}}} {value}")
        };
    }

    /// A family with its samples; nothing at all when it has none.
    fn family<V: Display>(
        &mut self,
        name: &str,
        kind: &str,
        help: &str,
        samples: impl IntoIterator<Item = (String, V)>,
    ) {
        let mut samples = samples.into_iter().peekable();
        if samples.peek().is_none() {
            return;
        }
        self.header(name, kind, help);
        for (labels, value) in samples {
            self.sample(name, &labels, value);
        }
    }
}

/// A per-responder figure: its names as a run and as a probe, its help,
/// and its value.
type Count = (&'static str, &'static str, &'static str, fn(&Series) -> u64);
type Gauge = (&'static str, &'static str, fn(&Series) -> Option<f64>);

const COUNTS: [Count; 5] = [
    (
        "mavping_sent_total",
        "mavping_probe_sent",
        "Requests in the responder's window whose fate is decided (received + lost).",
        |s| s.sent,
    ),
    (
        "mavping_received_total",
        "mavping_probe_received",
        "Replies received within the timeout.",
        |s| s.received,
    ),
    (
        "mavping_lost_total",
        "mavping_probe_lost",
        "Requests not answered within the timeout.",
        |s| s.lost,
    ),
    (
        "mavping_late_total",
        "mavping_probe_late",
        "First replies after the timeout (each also counted lost).",
        |s| s.late,
    ),
    (
        "mavping_duplicate_total",
        "mavping_probe_duplicate",
        "Second and later replies to the same request.",
        |s| s.duplicate,
    ),
];

const GAUGES: [Gauge; 4] = [
    (
        "mavping_last_rtt_seconds",
        "Round-trip time of the latest reply within the timeout.",
        |s| s.last_rtt_s,
    ),
    (
        "mavping_rtt_p50_seconds",
        "Median round-trip time (HDR histogram; at the end of a run or probe).",
        |s| s.p50_s,
    ),
    (
        "mavping_rtt_p99_seconds",
        "99th percentile round-trip time (HDR histogram; at the end of a run or probe).",
        |s| s.p99_s,
    ),
    (
        "mavping_clock_offset_seconds",
        "Responder's clock minus ours (TIMESYNC probe, at the end of a run or probe).",
        |s| s.clock_offset_s,
    ),
];

/// RADIO_STATUS figures, raw as the radio sends them (255: unknown, left out).
type RadioGauge = (&'static str, &'static str, fn(&RadioReport) -> Option<u16>);

const RADIO: [RadioGauge; 7] = [
    (
        "mavping_radio_rssi",
        "Local signal strength, raw RADIO_STATUS units (SiK: dBm = raw / 1.9 - 127).",
        |r| known(r.rssi),
    ),
    (
        "mavping_radio_remote_rssi",
        "Remote signal strength, raw RADIO_STATUS units.",
        |r| known(r.remrssi),
    ),
    (
        "mavping_radio_noise",
        "Local background noise, raw RADIO_STATUS units.",
        |r| known(r.noise),
    ),
    (
        "mavping_radio_remote_noise",
        "Remote background noise, raw RADIO_STATUS units.",
        |r| known(r.remnoise),
    ),
    (
        "mavping_radio_txbuf_percent",
        "Free space in the radio's transmit buffer, percent.",
        |r| known(r.txbuf),
    ),
    (
        "mavping_radio_rxerrors",
        "The radio's receive error count (its own 16-bit counter, which wraps).",
        |r| Some(r.rxerrors),
    ),
    (
        "mavping_radio_fixed",
        "Packets the radio's error correction repaired (its own 16-bit counter).",
        |r| Some(r.fixed),
    ),
];

fn known(raw: u8) -> Option<u16> {
    (raw != UNKNOWN).then_some(u16::from(raw))
}

/// Every link's per-responder and radio families, each family once with
/// a series per link and responder told apart by their labels.
fn write_links(out: &mut Exposition, links: &[&Metrics], scope: Scope) {
    let series = || {
        links
            .iter()
            .flat_map(|m| m.responders.iter().map(move |(id, s)| (m.labels(*id), s)))
    };
    for (run_name, probe_name, help, value) in COUNTS {
        let (name, kind) = match scope {
            Scope::Run => (run_name, "counter"),
            Scope::Probe => (probe_name, "gauge"),
        };
        out.family(name, kind, help, series().map(|(l, s)| (l, value(s))));
    }
    if scope == Scope::Probe {
        out.family(
            "mavping_probe_loss_ratio",
            "gauge",
            "Lost over sent in this probe (0 to 1).",
            series().filter_map(|(l, s)| Some((l, s.loss_ratio()?))),
        );
    }
    let name = match scope {
        Scope::Run => "mavping_rtt_seconds",
        Scope::Probe => "mavping_probe_rtt_seconds",
    };
    if series().next().is_some() {
        out.header(
            name,
            "histogram",
            "Round-trip time of replies within the timeout.",
        );
    }
    for (labels, s) in series() {
        let mut cumulative = 0;
        for (i, count) in s.buckets.iter().enumerate() {
            cumulative += count;
            let le = BUCKETS_S
                .get(i)
                .map_or_else(|| "+Inf".to_string(), |b| b.to_string());
            out.sample(
                &format!("{name}_bucket"),
                &format!("{labels},le=\"{le}\""),
                cumulative,
            );
        }
        out.sample(&format!("{name}_sum"), &labels, s.rtt_sum_s);
        out.sample(&format!("{name}_count"), &labels, s.received);
    }
    for (name, help, value) in GAUGES {
        out.family(
            name,
            "gauge",
            help,
            series().filter_map(|(l, s)| Some((l, value(s)?))),
        );
    }
    for (name, help, value) in RADIO {
        let radios = links.iter().flat_map(|m| {
            m.radios
                .iter()
                .filter_map(move |(id, r)| Some((m.radio_labels(*id), value(r)?)))
        });
        out.family(name, "gauge", help, radios);
    }
}

/// The exposition of one or several links of a run (`--prometheus`).
pub fn render(links: &[&Metrics]) -> String {
    let mut out = Exposition::default();
    write_links(&mut out, links, Scope::Run);
    out.0
}

/// The continuous links' state (`mavping serve`).
fn write_link_states(out: &mut Exposition, links: &[&Metrics]) {
    let states = || {
        links.iter().filter_map(|m| {
            let state = m.state?;
            Some((format!("link=\"{}\"", escape(&m.link)), state))
        })
    };
    out.family(
        "mavping_link_up",
        "gauge",
        "1 while the continuous link is open, 0 while it is down and being retried.",
        states().map(|(l, s)| (l, u8::from(s.up))),
    );
    out.family(
        "mavping_link_restarts_total",
        "counter",
        "Times the continuous link was reopened after it broke or could not be opened.",
        states().map(|(l, s)| (l, s.restarts)),
    );
}

/// What `mavping serve` says about itself at `/metrics`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Health {
    /// `/probe` requests that ran a probe...
    pub probes: u64,
    /// ...of which failed (`mavping_probe_success` 0).
    pub probes_failed: u64,
    /// `/probe` requests refused (400: bad or forbidden; 503: too many).
    pub probes_refused: u64,
    pub probes_running: u64,
    /// Links open now: continuous links up and probes' links.
    pub open_links: u64,
    pub reloads: u64,
    pub reloads_failed: u64,
    pub last_reload_ok: bool,
}

/// `mavping serve`'s `/metrics`: its health, then its continuous links.
pub fn render_serve(links: &[&Metrics], health: &Health) -> String {
    let mut out = Exposition::default();
    let one = |v: u64| [(String::new(), v)];
    for (name, kind, help, value) in [
        (
            "mavping_exporter_probes_total",
            "counter",
            "/probe requests that ran a probe.",
            health.probes,
        ),
        (
            "mavping_exporter_probes_failed_total",
            "counter",
            "Probes that ran and failed (mavping_probe_success 0).",
            health.probes_failed,
        ),
        (
            "mavping_exporter_probes_refused_total",
            "counter",
            "/probe requests refused: bad or forbidden (400) or too many at once (503).",
            health.probes_refused,
        ),
        (
            "mavping_exporter_probes_running",
            "gauge",
            "Probes running now.",
            health.probes_running,
        ),
        (
            "mavping_exporter_open_links",
            "gauge",
            "Links open now: continuous links that are up and the links of running probes.",
            health.open_links,
        ),
        (
            "mavping_exporter_config_reloads_total",
            "counter",
            "Configuration reloads asked for (SIGHUP).",
            health.reloads,
        ),
        (
            "mavping_exporter_config_reloads_failed_total",
            "counter",
            "Reloads refused because the new configuration was invalid (the old one stays).",
            health.reloads_failed,
        ),
        (
            "mavping_exporter_config_last_reload_successful",
            "gauge",
            "1 when the configuration in use is the one last read from the file.",
            u64::from(health.last_reload_ok),
        ),
    ] {
        out.family(name, kind, help, one(value));
    }
    write_link_states(&mut out, links);
    write_links(&mut out, links, Scope::Run);
    out.0
}

/// How one `/probe` ended.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeResult {
    pub success: bool,
    pub duration_s: f64,
    /// Why it failed: `open_failed`, `link_failed`, or a broken check
    /// (`no_reply`, `max_loss`, ...), each once.
    pub reasons: Vec<&'static str>,
    /// Requests put on the wire, and those still undecided when the
    /// probe's time was up.
    pub requests: u64,
    pub in_flight: u64,
    /// The error, for a person reading the exposition (a comment line).
    pub message: Option<String>,
}

/// One `/probe`'s answer: its result, then its link's figures.
pub fn render_probe(metrics: &Metrics, result: &ProbeResult) -> String {
    let mut out = Exposition::default();
    if let Some(message) = &result.message {
        // A comment: ignored by Prometheus, read by whoever curls.
        let _ = writeln!(out.0, "# mavping: {}", message.replace('\n', " "));
    }
    let one = |v: f64| [(String::new(), v)];
    out.family(
        "mavping_probe_success",
        "gauge",
        "1 when a responder answered and every threshold of the module held.",
        one(f64::from(u8::from(result.success))),
    );
    out.family(
        "mavping_probe_failure",
        "gauge",
        "1 for each reason the probe failed (open_failed, link_failed, no_reply, max_loss, ...).",
        result
            .reasons
            .iter()
            .map(|r| (format!("reason=\"{r}\""), 1)),
    );
    out.family(
        "mavping_probe_duration_seconds",
        "gauge",
        "How long the probe took, opening the link included.",
        one(result.duration_s),
    );
    out.family(
        "mavping_probe_requests",
        "gauge",
        "Requests the probe put on the wire.",
        one(result.requests as f64),
    );
    out.family(
        "mavping_probe_in_flight",
        "gauge",
        "Requests still undecided when the probe's time was up (counted neither received nor lost).",
        one(result.in_flight as f64),
    );
    write_links(&mut out, &[metrics], Scope::Probe);
    out.0
}

/// Label values escape backslash, double quote and newline.
fn escape(value: &str) -> String {
    value
        .replace('\\', "\\\\")
        .replace('"', "\\\"")
        .replace('\n', "\\n")
}

/// One link's metrics, written by its session and read by scrapes; every
/// part of a run or a server lives on one thread.
#[derive(Debug, Clone, Default)]
pub struct SharedMetrics(Rc<RefCell<Metrics>>);

impl SharedMetrics {
    pub fn new(metrics: Metrics) -> Self {
        SharedMetrics(Rc::new(RefCell::new(metrics)))
    }

    pub fn get(&self) -> Ref<'_, Metrics> {
        self.0.borrow()
    }

    pub fn update(&self, f: impl FnOnce(&mut Metrics)) {
        f(&mut self.0.borrow_mut());
    }
}

impl Observer for SharedMetrics {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.0.borrow_mut().start(info)
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        self.0.borrow_mut().event(event)
    }
}

impl Reporter for SharedMetrics {
    fn summary(&mut self, summary: &LinkSummary, verdict: &Verdict) -> io::Result<()> {
        self.0.borrow_mut().summary(summary, verdict)
    }
}

/// Renders several shared links at once.
pub fn borrow_all(links: &[SharedMetrics]) -> Vec<Ref<'_, Metrics>> {
    links.iter().map(SharedMetrics::get).collect()
}

/// `--prometheus`: the run's links at `/metrics` while the run goes on.
pub struct PrometheusExporter {
    links: Rc<RefCell<Vec<SharedMetrics>>>,
}

impl PrometheusExporter {
    /// Starts serving `listener` on the current `LocalSet`.
    pub fn serve(listener: std::net::TcpListener) -> io::Result<(Self, SocketAddr)> {
        let listener = http::listener(listener)?;
        let addr = listener.local_addr()?;
        let links: Rc<RefCell<Vec<SharedMetrics>>> = Rc::default();
        let shared = links.clone();
        http::serve(listener, Limits::default(), move |head: Head| -> Replying {
            let reply = match head.uri.path() {
                "/metrics" => {
                    let links = shared.borrow();
                    let all = borrow_all(&links);
                    let refs: Vec<&Metrics> = all.iter().map(|m| &**m).collect();
                    Reply::metrics(render(&refs))
                }
                "/" => Reply::text(StatusCode::OK, "mavping: metrics at /metrics\n"),
                _ => Reply::text(StatusCode::NOT_FOUND, "not found\n"),
            };
            Box::pin(std::future::ready(reply))
        });
        Ok((PrometheusExporter { links }, addr))
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

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    fn info(link: &str) -> StartInfo {
        StartInfo {
            link: link.into(),
            probe: "ping",
            ours: SysComp::new(255, 190),
            interval: Duration::from_secs(1),
            timeout: Duration::from_secs(2),
            count: None,
            command: None,
        }
    }

    #[test]
    fn counters_and_histogram_follow_the_events() {
        let mut m = Metrics::default();
        m.on_start(&info("udpout:\"a\\b\""));
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

    #[test]
    fn several_links_are_series_of_one_family() {
        let mut a = Metrics::default();
        a.on_start(&info("sim:"));
        let mut b = Metrics::default();
        b.on_start(&info("udpout:127.0.0.1:1"));
        for m in [&mut a, &mut b] {
            m.on_event(&MatchEvent::Lost {
                responder: SysComp::new(1, 1),
                seq: 0,
                sent_at: 0,
                at: 0,
            });
        }
        let text = render(&[&a, &b]);
        assert_eq!(text.matches("# TYPE mavping_lost_total counter").count(), 1);
        for link in ["sim:", "udpout:127.0.0.1:1"] {
            let line = format!(
                "mavping_lost_total{{link=\"{link}\",probe=\"ping\",sysid=\"1\",compid=\"1\"}} 1"
            );
            assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
        }
    }
}
