//! `mavping serve` scraped by a real Prometheus server (Debian's
//! `prometheus` package): a continuous link and a `/probe` target, each
//! against a pymavlink responder with known drops, and a passive link
//! listening to a pymavlink vehicle that drops, doubles and swaps frames.
//! What Prometheus stores and answers through its HTTP query API must
//! equal the peers' ground truth.

use std::path::PathBuf;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::common::{
    free_tcp_port, free_udp_port, http_get, prometheus_tool, sample, signal, Peer, Server,
    SilentPeer,
};

/// Prometheus starts, scrapes every two seconds and needs two scrapes of
/// each job; far more than that means something is broken.
pub const PATIENCE: Duration = Duration::from_secs(90);

/// A Prometheus server with its own data directory; killed and cleaned
/// up when dropped (also the TLS tests' in serve_secure.rs).
pub struct Prometheus {
    pub child: Child,
    dir: PathBuf,
    pub addr: String,
}

impl Prometheus {
    /// A server of its own for the test `name` (tests run side by side).
    pub fn start(name: &str, config: &str) -> Prometheus {
        let dir =
            std::env::temp_dir().join(format!("mavping-prometheus-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("prometheus.yml");
        std::fs::write(&file, config).unwrap();
        let addr = format!("127.0.0.1:{}", free_tcp_port());
        let child = prometheus_tool("prometheus")
            .arg(format!("--config.file={}", file.display()))
            .arg(format!(
                "--storage.tsdb.path={}",
                dir.join("data").display()
            ))
            .arg(format!("--web.listen-address={addr}"))
            .arg("--log.level=warn")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        Prometheus { child, dir, addr }
    }

    /// An instant query through the HTTP API, evaluated at `time` (Unix
    /// seconds) when given: its result vector.
    pub fn query(&self, promql: &str, time: Option<f64>) -> Vec<Value> {
        let mut path = format!(
            "/api/v1/query?query={}",
            form_urlencoded::byte_serialize(promql.as_bytes()).collect::<String>()
        );
        if let Some(t) = time {
            path.push_str(&format!("&time={t}"));
        }
        let r = http_get(&self.addr, &path, &[]);
        assert_eq!(r.status, 200, "{promql}: {}", r.body);
        let v: Value = serde_json::from_str(&r.body).unwrap();
        assert_eq!(v["status"], "success", "{promql}: {v}");
        v["data"]["result"].as_array().unwrap().clone()
    }

    /// The one value `promql` gives at `time`.
    pub fn value(&self, promql: &str, time: f64) -> f64 {
        let result = self.query(promql, Some(time));
        assert_eq!(result.len(), 1, "{promql}: {result:?}");
        result[0]["value"][1].as_str().unwrap().parse().unwrap()
    }

    pub fn ready(&self) -> bool {
        std::net::TcpStream::connect(&self.addr).is_ok()
            && http_get(&self.addr, "/-/ready", &[]).status == 200
    }
}

impl Drop for Prometheus {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[test]
fn a_real_prometheus_scrapes_links_and_probes_and_sees_the_ground_truth() {
    // The continuous link's responder drops three early requests; the probe
    // target's drops two of the ten requests of every probe, the first
    // one included (a probe charges it all the same). A second continuous
    // link sends to a socket that never answers.
    let (link_port, probe_port) = (free_udp_port(), free_udp_port());
    let mut silent = SilentPeer::bind();
    let link_responder = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{link_port}"), "--drop", "2,5,9"],
    );
    let probe_responder = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{probe_port}"), "--drop", "0,4"],
    );
    let config = std::env::temp_dir().join(format!("mavping-serve-{}.toml", std::process::id()));
    std::fs::write(
        &config,
        format!(
            r#"
allow = ["udpout:127.0.0.1:*"]

[module.fleet]
count = 10
interval = "20ms"
timeout = "300ms"
max_loss = "50%"

[[link]]
link = "udpout:127.0.0.1:{link_port}"
name = "radio-a"
interval = "100ms"
timeout = "300ms"

[[link]]
link = "udpout:127.0.0.1:{silent_port}"
name = "silent"
interval = "100ms"
timeout = "300ms"
"#,
            silent_port = silent.port()
        ),
    )
    .unwrap();
    let server = Server::start(&["--config", config.to_str().unwrap()]);
    std::fs::remove_file(&config).unwrap();
    let probe_target = format!("udpout:127.0.0.1:{probe_port}");
    // Both patterns of contrib/prometheus/prometheus.yml, on loopback.
    let prometheus = Prometheus::start(
        "links-and-probes",
        &format!(
            r"
global:
  scrape_interval: 2s
  scrape_timeout: 2s
scrape_configs:
  - job_name: mavping_links
    static_configs:
      - targets: ['{serve}']
  - job_name: mavping_probe
    metrics_path: /probe
    params:
      module: [fleet]
    static_configs:
      - targets: ['{probe_target}']
    relabel_configs:
      - source_labels: [__address__]
        target_label: __param_target
      - source_labels: [__param_target]
        target_label: instance
      - target_label: __address__
        replacement: {serve}
",
            serve = server.addr
        ),
    );

    let start = Instant::now();
    while !prometheus.ready() {
        assert!(start.elapsed() < PATIENCE, "prometheus did not start");
        std::thread::sleep(Duration::from_millis(200));
    }
    // Two scrapes of each job, and enough requests on the link that its
    // three drops are decided (request 9's timeout is long past once 15
    // requests are).
    let now = loop {
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_secs_f64();
        let scrapes = prometheus.query("count_over_time(up[5m]) >= 2", Some(now));
        let sent = prometheus.query(r#"mavping_sent_total{link="radio-a"} >= 15"#, Some(now));
        if scrapes.len() == 2 && sent.len() == 1 {
            break now;
        }
        assert!(
            start.elapsed() < PATIENCE,
            "no two scrapes of each job within {PATIENCE:?}: {scrapes:?} {sent:?}\n{}",
            server.stderr()
        );
        std::thread::sleep(Duration::from_millis(500));
    };

    for job in ["mavping_links", "mavping_probe"] {
        assert_eq!(
            prometheus.value(&format!("up{{job=\"{job}\"}}"), now),
            1.0,
            "{job}"
        );
    }
    assert_eq!(
        prometheus.value(
            &format!("mavping_probe_success{{instance=\"{probe_target}\"}}"),
            now
        ),
        1.0
    );
    assert_eq!(
        prometheus.value(r#"mavping_link_up{link="radio-a"}"#, now),
        1.0
    );
    let probe_loss = prometheus.value(
        &format!("mavping_probe_loss_ratio{{instance=\"{probe_target}\",sysid=\"1\"}}"),
        now,
    );
    let link = r#"{link="radio-a",sysid="1",compid="1"}"#;
    let lost = prometheus.value(&format!("mavping_lost_total{link}"), now);
    let sent = prometheus.value(&format!("mavping_sent_total{link}"), now);
    let received = prometheus.value(&format!("mavping_received_total{link}"), now);
    let link_loss = prometheus.value(
        &format!("mavping_lost_total{link} / mavping_sent_total{link}"),
        now,
    );
    assert_eq!(sent, received + lost);
    // The shipped rule's expression (without its `for`) picks the link
    // nobody answers, and only it.
    let unanswered = prometheus.query(&rule_expr("MavlinkLinkUnanswered"), Some(now));
    assert_eq!(unanswered.len(), 1, "{unanswered:?}");
    assert_eq!(unanswered[0]["metric"]["link"], "silent", "{unanswered:?}");
    let silent_requests = prometheus.value(r#"mavping_requests_total{link="silent"}"#, now);
    assert!(silent_requests >= 15.0, "{silent_requests}");
    assert_eq!(
        prometheus.value(r#"mavping_responders{link="radio-a"}"#, now),
        1.0
    );

    // No probe may be cut short, which killing Prometheus mid-scrape (its
    // connection closed) or ending a responder would do: freeze Prometheus
    // (no new scrape starts; one under way keeps its connection), let the
    // last probe finish, then read the ground truth.
    signal(prometheus.child.id(), "STOP");
    while sample(
        &server.get("/metrics").body,
        "mavping_exporter_probes_running",
        &[],
    ) != Some(0.0)
    {
        assert!(start.elapsed() < PATIENCE, "a probe never ended");
        std::thread::sleep(Duration::from_millis(100));
    }
    let link_truth = link_responder.finish();
    let probe_truth = probe_responder.finish();
    // Exactly the requests the responders did not answer.
    assert_eq!(
        lost,
        link_truth["dropped"].as_f64().unwrap(),
        "{link_truth}"
    );
    assert_eq!(link_loss, link_truth["dropped"].as_f64().unwrap() / sent);
    let truth_ratio =
        probe_truth["dropped"].as_f64().unwrap() / probe_truth["ping_requests"].as_f64().unwrap();
    assert_eq!(probe_loss, truth_ratio, "{probe_truth}");
    assert_eq!(probe_loss, 0.2);
    // What Prometheus stored was sent: the silent peer counted at least that.
    assert!(silent.pings() as f64 >= silent_requests);
    drop(prometheus);
}

/// The `expr` of the alerting rule `alert` in contrib/prometheus.
fn rule_expr(alert: &str) -> String {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("contrib/prometheus/mavping.rules.yml");
    let text = std::fs::read_to_string(path).unwrap();
    let rule = text
        .split("- alert: ")
        .find(|r| r.starts_with(alert))
        .unwrap_or_else(|| panic!("no rule {alert}"));
    let expr = rule.split_once("expr: |").expect("a block expr").1;
    expr.lines()
        .take_while(|l| !l.trim_start().starts_with("for:"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Unix seconds now.
fn now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

#[test]
fn a_real_prometheus_scrapes_a_passive_link_and_sees_what_the_vehicle_did() {
    let port = free_udp_port();
    // 400 frames at 100/s: 3 numbered and not sent, 2 sent twice, one pair
    // swapped, and after frame 250, 200 numbered and not sent (2 s: a
    // silence, yet within the 8-bit sequence, which proves all 200).
    let mut vehicle = Peer::start(
        "vehicle.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--frames",
            "400",
            "--rate",
            "100",
            "--drop",
            "20,21,300",
            "--dup",
            "60,320",
            "--swap",
            "150",
            "--silence",
            "250:200",
        ],
    );
    let config =
        std::env::temp_dir().join(format!("mavping-serve-passive-{}.toml", std::process::id()));
    std::fs::write(
        &config,
        format!(
            r#"
[[link]]
link = "udpout:127.0.0.1:{port}"
name = "vehicle"
passive = true
"#
        ),
    )
    .unwrap();
    // Prometheus first, scraping where the server will listen, so that it
    // sees the vehicle's frames as they come.
    let listen = format!("127.0.0.1:{}", free_tcp_port());
    let prometheus = Prometheus::start(
        "passive",
        &format!(
            r"
global:
  scrape_interval: 1s
  scrape_timeout: 1s
scrape_configs:
  - job_name: mavping_links
    static_configs:
      - targets: ['{listen}']
"
        ),
    );
    let start = Instant::now();
    while !prometheus.ready() {
        assert!(start.elapsed() < PATIENCE, "prometheus did not start");
        std::thread::sleep(Duration::from_millis(200));
    }
    let server = Server::start(&["--listen", &listen, "--config", config.to_str().unwrap()]);
    std::fs::remove_file(&config).unwrap();
    // The vehicle has sent its last frame; Prometheus then scrapes the
    // source silent with every frame counted.
    let truth: Value = serde_json::from_str(&vehicle.read_line()).unwrap();
    let sent = truth["sent"].as_u64().unwrap();
    assert_eq!(truth["dropped"], 3, "{truth}");
    assert_eq!(truth["silenced"], 200, "{truth}");
    let lost: u64 = 3 + 200;
    let source = r#"{link="vehicle",sysid="1",compid="1"}"#;
    let at = loop {
        let t = now();
        let done = prometheus.query(
            &format!(
                "mavping_source_received_total{source} == {sent} \
                 and on() mavping_source_silent{source} == 1"
            ),
            Some(t),
        );
        if done.len() == 1 {
            break t;
        }
        assert!(
            start.elapsed() < PATIENCE,
            "Prometheus never saw all {sent} frames: {:?}\n{}",
            prometheus.query(r#"{__name__=~"mavping_source_.*"}"#, Some(t)),
            server.stderr()
        );
        std::thread::sleep(Duration::from_millis(500));
    };
    // Samples arrived all along, not only at the end.
    let over_time = |f: &str| {
        prometheus.value(
            &format!("{f}_over_time(mavping_source_received_total{source}[5m])"),
            at,
        )
    };
    assert!(over_time("count") >= 3.0, "{} samples", over_time("count"));
    assert!(over_time("min") < sent as f64, "{}", over_time("min"));
    let value = |name: &str| prometheus.value(&format!("{name}{source}"), at);
    assert_eq!(value("mavping_source_lost_total"), lost as f64);
    assert_eq!(value("mavping_source_lost_pending"), 0.0);
    assert_eq!(value("mavping_source_duplicate_total"), 2.0);
    assert_eq!(value("mavping_source_reordered_total"), 1.0);
    // The 200 frames not sent: a silence whose gap is counted, the count
    // going on across it (no restart), and the one since the last frame.
    assert_eq!(value("mavping_source_resyncs_total"), 0.0);
    assert_eq!(value("mavping_source_silences_total"), 2.0);
    assert_eq!(
        value("mavping_source_pymavlink_lost_total"),
        f64::from(3 + 2 * 255 + 256 + 200)
    );
    let numbered = (sent - 2 + lost) as f64;
    assert_eq!(value("mavping_source_loss_ratio"), lost as f64 / numbered);
    assert_eq!(
        prometheus.value(r#"mavping_link_up{link="vehicle"}"#, at),
        1.0
    );
    drop(prometheus);
}
