//! `--prometheus ADDR:PORT`: the run's per-responder counters and RTT
//! histogram, served at `/metrics` in the Prometheus text format while the
//! run goes on, so many mavping instances can feed one Prometheus.
//!
//! The reporter updates shared state from `event()`; a tokio task answers
//! scrapes from it. Memory is fixed per responder (the matcher bounds how
//! many there are), whatever the run length.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};

use super::{Event, Observer, Reporter, StartInfo};
use crate::engine::matcher::MatchEvent;
use crate::engine::summary::{LinkSummary, Summary};
use crate::engine::Nanos;
use crate::frame::SysComp;
use crate::verdict::Verdict;

/// Upper bounds of the RTT histogram, in seconds: from loopback (sub-ms)
/// to a congested 57600-baud radio (seconds).
pub const BUCKETS_S: [f64; 14] = [
    0.000_5, 0.001, 0.002_5, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0,
];

/// A request larger than this is not a scrape.
const MAX_REQUEST: usize = 8 * 1024;
/// A client that sends nothing for this long is dropped.
const READ_TIMEOUT: Duration = Duration::from_secs(10);

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
}

/// A metric family: name, help and its value in a responder's series.
type Family<T> = (&'static str, &'static str, fn(&Series) -> T);

/// Everything `/metrics` shows.
#[derive(Debug, Default)]
pub struct Metrics {
    link: String,
    probe: &'static str,
    responders: BTreeMap<SysComp, Series>,
}

impl Metrics {
    pub fn on_start(&mut self, info: &StartInfo) {
        self.link = info.link.clone();
        self.probe = info.probe;
    }

    pub fn on_event(&mut self, e: &MatchEvent) {
        match *e {
            MatchEvent::Reply { responder, rtt, .. } => {
                let s = self.responders.entry(responder).or_default();
                s.sent += 1;
                s.received += 1;
                s.observe(rtt);
            }
            MatchEvent::Lost { responder, .. } => {
                let s = self.responders.entry(responder).or_default();
                s.sent += 1;
                s.lost += 1;
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

    /// The clock offsets known at the end (TIMESYNC), so a last scrape
    /// before exit has them.
    pub fn on_summary(&mut self, summary: &Summary) {
        for r in &summary.responders {
            if let Some(c) = &r.clock {
                self.responders.entry(r.id).or_default().clock_offset_s =
                    Some(c.offset_ns as f64 / 1e9);
            }
        }
    }

    /// The exposition, in the Prometheus text format 0.0.4.
    pub fn render(&self) -> String {
        render(std::slice::from_ref(self))
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
}

/// The exposition of one or several links (each family once, a series per
/// link and responder, told apart by the `link` label).
pub fn render(links: &[Metrics]) -> String {
    let series = || {
        links
            .iter()
            .flat_map(|m| m.responders.iter().map(move |(id, s)| (m.labels(*id), s)))
    };
    let mut out = String::new();
    let counters: [Family<u64>; 5] = [
        (
            "mavping_sent_total",
            "Requests in the responder's window whose fate is decided.",
            |s| s.sent,
        ),
        (
            "mavping_received_total",
            "Replies received within the timeout.",
            |s| s.received,
        ),
        (
            "mavping_lost_total",
            "Requests not answered within the timeout.",
            |s| s.lost,
        ),
        (
            "mavping_late_total",
            "First replies after the timeout (each also counted lost).",
            |s| s.late,
        ),
        (
            "mavping_duplicate_total",
            "Second and later replies to the same request.",
            |s| s.duplicate,
        ),
    ];
    for (name, help, value) in counters {
        let _ = writeln!(out, "# HELP {name} {help}\n# TYPE {name} counter");
        for (labels, s) in series() {
            let _ = writeln!(out, "{name}{{{labels}}} {}", value(s));
        }
    }
    let name = "mavping_rtt_seconds";
    let _ = writeln!(
        out,
        "# HELP {name} Round-trip time of replies within the timeout.\n# TYPE {name} histogram"
    );
    for (labels, s) in series() {
        let mut cumulative = 0;
        for (i, count) in s.buckets.iter().enumerate() {
            cumulative += count;
            let le = BUCKETS_S
                .get(i)
                .map_or_else(|| "+Inf".to_string(), |b| b.to_string());
            let _ = writeln!(out, "{name}_bucket{{{labels},le=\"{le}\"}} {cumulative}");
        }
        let _ = writeln!(out, "{name}_sum{{{labels}}} {}", s.rtt_sum_s);
        let _ = writeln!(out, "{name}_count{{{labels}}} {}", s.received);
    }
    let gauges: [Family<Option<f64>>; 2] = [
        (
            "mavping_last_rtt_seconds",
            "Round-trip time of the latest reply within the timeout.",
            |s| s.last_rtt_s,
        ),
        (
            "mavping_clock_offset_seconds",
            "Responder's clock minus ours (TIMESYNC probe, at the end of the run).",
            |s| s.clock_offset_s,
        ),
    ];
    for (name, help, value) in gauges {
        let _ = writeln!(out, "# HELP {name} {help}\n# TYPE {name} gauge");
        for (labels, s) in series() {
            if let Some(v) = value(s) {
                let _ = writeln!(out, "{name}{{{labels}}} {v}");
            }
        }
    }
    out
}

/// Label values escape backslash, double quote and newline.
fn escape(value: &str) -> String {
    value
        .replace('\\', "\\\\")
        .replace('"', "\\\"")
        .replace('\n', "\\n")
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic elsewhere must not take the exporter down with it.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// One link's view of the served metrics.
pub struct PrometheusReporter {
    metrics: Arc<Mutex<Vec<Metrics>>>,
    index: usize,
}

impl PrometheusReporter {
    /// Starts serving `listener` on the current tokio runtime.
    pub fn serve(listener: std::net::TcpListener) -> io::Result<(Self, SocketAddr)> {
        listener.set_nonblocking(true)?;
        let listener = TcpListener::from_std(listener)?;
        let addr = listener.local_addr()?;
        let metrics = Arc::new(Mutex::new(vec![Metrics::default()]));
        let shared = metrics.clone();
        tokio::spawn(async move {
            loop {
                // Accept errors (out of file descriptors, a reset before
                // accept) concern one client, not the run.
                let Ok((stream, _)) = listener.accept().await else {
                    continue;
                };
                tokio::spawn(answer(stream, shared.clone()));
            }
        });
        Ok((PrometheusReporter { metrics, index: 0 }, addr))
    }

    /// The reporter of the `index`-th of several links (0 is this one's),
    /// served at the same address.
    pub fn link(&self, index: usize) -> Self {
        let mut all = lock(&self.metrics);
        if all.len() <= index {
            all.resize_with(index + 1, Metrics::default);
        }
        PrometheusReporter {
            metrics: self.metrics.clone(),
            index,
        }
    }

    fn this(&self) -> MutexGuard<'_, Vec<Metrics>> {
        lock(&self.metrics)
    }
}

/// One HTTP/1.1 exchange, then the connection closes.
async fn answer(mut stream: TcpStream, metrics: Arc<Mutex<Vec<Metrics>>>) {
    let mut buf = Vec::with_capacity(1024);
    let head = tokio::time::timeout(READ_TIMEOUT, async {
        let mut chunk = [0u8; 1024];
        loop {
            if buf.windows(4).any(|w| w == b"\r\n\r\n") || buf.len() > MAX_REQUEST {
                return true;
            }
            match stream.read(&mut chunk).await {
                Ok(0) | Err(_) => return false,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            }
        }
    })
    .await;
    if head != Ok(true) {
        return;
    }
    let line = buf.split(|&b| b == b'\r').next().unwrap_or_default();
    let line = String::from_utf8_lossy(line);
    let mut parts = line.split(' ');
    let (method, target) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
    let path = target.split('?').next().unwrap_or("");
    let (status, body) = match (method, path) {
        ("GET" | "HEAD", "/metrics") => ("200 OK", render(&lock(&metrics))),
        ("GET" | "HEAD", "/") => ("200 OK", "mavping: metrics at /metrics\n".to_string()),
        ("GET" | "HEAD", _) => ("404 Not Found", "not found\n".to_string()),
        _ => ("405 Method Not Allowed", "only GET\n".to_string()),
    };
    let mut response = format!(
        "HTTP/1.1 {status}\r\nContent-Type: text/plain; version=0.0.4; charset=utf-8\r\n\
         Content-Length: {}\r\nConnection: close\r\n\r\n",
        body.len()
    );
    if method != "HEAD" {
        response.push_str(&body);
    }
    let _ = stream.write_all(response.as_bytes()).await;
    let _ = stream.shutdown().await;
}

impl Observer for PrometheusReporter {
    fn start(&mut self, info: &StartInfo) -> io::Result<()> {
        self.this()[self.index].on_start(info);
        Ok(())
    }

    fn event(&mut self, event: &Event<'_>) -> io::Result<()> {
        if let Event::Match(e) = event {
            self.this()[self.index].on_event(e);
        }
        Ok(())
    }
}

impl Reporter for PrometheusReporter {
    fn summary(&mut self, summary: &LinkSummary, _: &Verdict) -> io::Result<()> {
        if let LinkSummary::Echo(summary) = summary {
            self.this()[self.index].on_summary(summary);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
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
        let text = render(&[a, b]);
        assert_eq!(text.matches("# TYPE mavping_lost_total counter").count(), 1);
        for link in ["sim:", "udpout:127.0.0.1:1"] {
            let line = format!(
                "mavping_lost_total{{link=\"{link}\",probe=\"ping\",sysid=\"1\",compid=\"1\"}} 1"
            );
            assert!(text.lines().any(|x| x == line), "{line} not in\n{text}");
        }
    }
}
