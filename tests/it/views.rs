//! The views beside the text output, run as a user runs them: `--prometheus`
//! scraped over HTTP and checked by a real parser and by promtool, `--plot`
//! written to a file and rendered to pixels (`--live` is in `live.rs`).

use std::process::Command;
use std::time::{Duration, Instant};

use assert_cmd::cargo::cargo_bin;

use crate::common::{
    assert_promtool_clean, checked_summary, http_get, n, responder, Exporting, Rendered, Response,
};
use prometheus_parse::{Scrape, Value};

/// Generous bound for something that normally takes a fraction of a second;
/// reaching it fails the test instead of hanging it.
const PATIENCE: Duration = Duration::from_secs(20);

fn counter(scrape: &Scrape, name: &str, sysid: &str) -> f64 {
    scrape
        .samples
        .iter()
        .find(|s| s.metric == name && s.labels.get("sysid") == Some(sysid))
        .map_or_else(
            || panic!("no {name} for sysid {sysid}"),
            |s| match s.value {
                Value::Counter(v) | Value::Gauge(v) | Value::Untyped(v) => v,
                _ => panic!("{name} is not a counter: {:?}", s.value),
            },
        )
}

#[test]
fn prometheus_metrics_are_served_while_the_run_goes_on() {
    let run = Exporting::start(&[
        "-i",
        "0.01",
        "-W",
        "200ms",
        "sim:?responders=2&loss=20%&delay=1ms&jitter=1ms&seed=4",
    ]);
    let host = run.host.clone();

    // Scrape until both responders have lost something: the run goes on
    // with no count, so the numbers only grow.
    let start = Instant::now();
    let (head, body) = loop {
        let Response { head, body, .. } = http_get(&host, "/metrics", &[]);
        let scrape = Scrape::parse(body.lines().map(|l| Ok(l.to_string()))).unwrap();
        let lost = |id| {
            let present = scrape
                .samples
                .iter()
                .any(|s| s.metric == "mavping_lost_total" && s.labels.get("sysid") == Some(id));
            if present {
                counter(&scrape, "mavping_lost_total", id)
            } else {
                0.0
            }
        };
        if lost("1") > 0.0 && lost("2") > 0.0 {
            break (head, body);
        }
        assert!(
            start.elapsed() < PATIENCE,
            "no losses after {PATIENCE:?}:\n{body}"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(head.starts_with("HTTP/1.1 200 OK"), "{head}");
    assert!(
        head.to_ascii_lowercase()
            .contains("content-type: text/plain; version=0.0.4"),
        "{head}"
    );

    let scrape = Scrape::parse(body.lines().map(|l| Ok(l.to_string()))).unwrap();
    for id in ["1", "2"] {
        let sent = counter(&scrape, "mavping_sent_total", id);
        let received = counter(&scrape, "mavping_received_total", id);
        let lost = counter(&scrape, "mavping_lost_total", id);
        assert_eq!(sent, received + lost, "{body}");
        assert!(received > 0.0);
        counter(&scrape, "mavping_late_total", id);
        counter(&scrape, "mavping_duplicate_total", id);
        let last = counter(&scrape, "mavping_last_rtt_seconds", id);
        assert!(last > 0.0 && last < 1.0, "last RTT {last} s");
        let hist = scrape
            .samples
            .iter()
            .find(|s| s.metric == "mavping_rtt_seconds" && s.labels.get("sysid") == Some(id))
            .expect("an RTT histogram");
        assert_eq!(hist.labels.get("compid"), Some("1"));
        assert_eq!(hist.labels.get("probe"), Some("auto"));
        // prometheus-parse splits label values on `=` and `,`, which the
        // link's query string has: that label is checked on the raw text
        // (and its syntax by promtool below).
        assert!(
            body.contains(&format!(
                "mavping_rtt_seconds_count{{link=\"sim:?responders=2&delay=1ms&jitter=1ms&loss=20%&dup=0%&reorder=0%&seed=4\",probe=\"auto\",sysid=\"{id}\",compid=\"1\"}}"
            )),
            "{body}"
        );
        let Value::Histogram(buckets) = &hist.value else {
            panic!("not a histogram: {:?}", hist.value)
        };
        let inf = buckets.last().unwrap();
        assert!(inf.less_than.is_infinite());
        assert_eq!(inf.count, received, "{body}");
        assert!(buckets.windows(2).all(|w| w[0].count <= w[1].count));
    }

    assert_promtool_clean(&body);

    assert_eq!(http_get(&host, "/nothing", &[]).status, 404);
}

#[test]
fn a_port_in_use_is_a_usage_error_with_the_os_reason() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let out = Command::new(cargo_bin("mavping"))
        .args(["-c", "1", "--prometheus", &addr, "sim:?clock=virtual"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim(),
        format!("mavping: --prometheus {addr}: Address already in use (os error 98)")
    );
    assert!(out.stdout.is_empty(), "nothing is sent before the check");
}

/// Okabe–Ito blue and vermillion: the first two responders' colours.
const BLUE: u32 = 0x0072B2;
const VERMILLION: u32 = 0xD55E00;

#[test]
fn the_plot_shows_each_responder_and_the_losses() {
    let dir = std::env::temp_dir().join(format!("mavping-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rtt.svg");
    let out = Command::new(cargo_bin("mavping"))
        .args(["--json", "-c", "200", "-i", "0.05", "--plot"])
        .arg(&path)
        .arg("sim:?responders=2&loss=10%&jitter=5ms&seed=3&clock=virtual")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let svg = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    for text in ["1/1", "2/1", "RTT over time", "RTT distribution", "lost"] {
        assert!(svg.contains(text), "{text} is not in the plot");
    }
    // The legend has the run's own figures: the summary's loss and
    // percentiles, as the JSON summary gives them.
    let summary = checked_summary(&String::from_utf8_lossy(&out.stdout));
    for id in ["1/1", "2/1"] {
        let r = responder(&summary, id);
        let sent = n(r, "sent");
        let loss = 100.0 * r["loss_ratio"].as_f64().unwrap();
        let p50 = r["rtt_us"]["p50"].as_f64().unwrap() / 1e3;
        let p99 = r["rtt_us"]["p99"].as_f64().unwrap() / 1e3;
        assert!(loss > 0.0, "{id} lost nothing: {r}");
        for figure in [
            sent.to_string(),
            format!("{loss:.2}"),
            format!("{p50:.3}"),
            format!("{p99:.3}"),
        ] {
            assert!(
                svg.contains(&format!("\n{figure}\n")),
                "{id}: {figure} not in the legend"
            );
        }
    }

    // As a viewer shows it: text drawn, each responder in its own colour,
    // nothing in the pure red every loss used to be.
    let png = Rendered::of(&svg, "two-responders");
    assert!(
        png.png.starts_with(b"\x89PNG") && png.png.len() > 20_000,
        "{}",
        png.path.display()
    );
    assert!(png.colours.len() > 50, "{} colours", png.colours.len());
    for (name, rgb) in [("blue", BLUE), ("vermillion", VERMILLION)] {
        assert!(
            png.count(rgb) > 200,
            "little {name} in {}",
            png.path.display()
        );
    }
    assert_eq!(png.count(0xFF0000), 0, "{}", png.path.display());
    assert!(
        png.dark_in_rows(0..40) > 300,
        "no title text in {}",
        png.path.display()
    );
}

#[test]
fn the_plot_of_a_passive_run_shows_each_sources_rate_and_loss() {
    let dir = std::env::temp_dir().join(format!("mavping-passive-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("passive.svg");
    // Two vehicles losing 5% of their frames, the second silent for 8 s
    // from 40 s: its rate falls to nothing there.
    let out = Command::new(cargo_bin("mavping"))
        .args(["--passive", "-w", "120", "--json", "--plot"])
        .arg(&path)
        .arg(
            "sim:?clock=virtual&responders=2&stream=ATTITUDE@50,GLOBAL_POSITION_INT@5\
             &loss_down=5%&dup_down=2%&reorder_down=2%&outage=40s+8s&seed=3",
        )
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let svg = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    for text in [
        "mavping --passive sim:",
        "frames a second, by source",
        "sequence loss per span",
        "time since start (s)",
        "1/1",
        "2/1",
    ] {
        assert!(svg.contains(text), "{text} is not in the plot");
    }
    // The legend has the run's own figures, as the JSON summary gives them.
    let stdout = String::from_utf8_lossy(&out.stdout);
    let events = crate::common::json_lines(&stdout);
    crate::common::assert_schema(&events);
    let summary = events
        .iter()
        .find(|e| e["type"] == "passive_summary")
        .expect("a passive summary");
    for s in summary["sources"].as_array().unwrap() {
        let c = &s["counts"];
        assert!(n(c, "lost") > 0, "{s}");
        for figure in [
            n(c, "received").to_string(),
            n(c, "lost").to_string(),
            format!("{:.2}", s["loss_pct"].as_f64().unwrap()),
            n(c, "duplicate").to_string(),
            format!("{:.1}", s["frames_per_s"].as_f64().unwrap()),
        ] {
            assert!(
                svg.contains(&format!("\n{figure}\n")),
                "{figure} not in the legend: {s}"
            );
        }
    }

    let png = Rendered::of(&svg, "passive-two-sources");
    assert!(
        png.png.starts_with(b"\x89PNG") && png.png.len() > 20_000,
        "{}",
        png.path.display()
    );
    for (name, rgb) in [("blue", BLUE), ("vermillion", VERMILLION)] {
        assert!(
            png.count(rgb) > 200,
            "little {name} in {}",
            png.path.display()
        );
    }
    assert_eq!(png.count(0xFF0000), 0, "{}", png.path.display());
    assert!(
        png.dark_in_rows(0..40) > 300,
        "no title text in {}",
        png.path.display()
    );
}
