//! `--prometheus` beside the packet sequence: a `--passive` run's
//! per-source counters scraped over HTTP from a running mavping, exactly
//! what a pymavlink vehicle that drops, doubles and swaps frames and goes
//! silent did; and an echo run's loss by direction against the simulated
//! link's per-direction truth. Every exposition passes promtool.

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::common::*;

/// A `mavping --prometheus 127.0.0.1:0 ARGS...` run whose standard output
/// and error are kept, scraped while it goes on and then stopped with
/// Ctrl-C (SIGINT), as a person would.
struct Scraped {
    child: Child,
    host: String,
    stdout: Option<JoinHandle<String>>,
    stderr: Arc<Mutex<String>>,
}

impl Scraped {
    fn start(args: &[&str]) -> Scraped {
        let mut child = mavping()
            .args(["--prometheus", "127.0.0.1:0"])
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut out = child.stdout.take().unwrap();
        let stdout = std::thread::spawn(move || {
            let mut text = String::new();
            out.read_to_string(&mut text).unwrap();
            text
        });
        let mut err = BufReader::new(child.stderr.take().unwrap());
        let mut seen = String::new();
        let host = loop {
            let mut line = String::new();
            assert!(err.read_line(&mut line).unwrap() > 0, "no address: {seen}");
            if let Some(rest) = line
                .trim()
                .strip_prefix("mavping: serving metrics at http://")
            {
                break rest.strip_suffix("/metrics").unwrap().to_string();
            }
            seen.push_str(&line);
        };
        let stderr = Arc::new(Mutex::new(seen));
        let sink = stderr.clone();
        std::thread::spawn(move || {
            for line in err.lines().map_while(Result::ok) {
                let mut all = sink.lock().unwrap();
                all.push_str(&line);
                all.push('\n');
            }
        });
        Scraped {
            child,
            host,
            stdout: Some(stdout),
            stderr,
        }
    }

    /// Scrapes `/metrics` until `ready` holds (30 s at most).
    fn scrape_until(&self, what: &str, ready: impl Fn(&str) -> bool) -> String {
        let start = Instant::now();
        loop {
            let body = http_get(&self.host, "/metrics", &[]).body;
            if ready(&body) {
                return body;
            }
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "not {what}:\n{body}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Ctrl-C; the exit code, standard output and error.
    fn stop(mut self) -> (i32, String, String) {
        signal(self.child.id(), "INT");
        let code = self.child.wait().unwrap().code().unwrap_or(-1);
        let out = self.stdout.take().unwrap().join().unwrap();
        // The stderr thread ends with the pipe.
        std::thread::sleep(Duration::from_millis(100));
        let err = self.stderr.lock().unwrap().clone();
        (code, out, err)
    }
}

impl Drop for Scraped {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The line of `type` in a `--json` run's output.
fn json_line(stdout: &str, kind: &str) -> Value {
    let line = stdout
        .lines()
        .find(|l| l.contains(&format!("\"type\":\"{kind}\"")))
        .unwrap_or_else(|| panic!("no {kind} in\n{stdout}"));
    serde_json::from_str(line).unwrap()
}

#[test]
fn a_passive_run_exports_each_sources_counts_exactly_as_the_vehicle_made_them() {
    let port = free_udp_port();
    // 600 frames at 100/s: 4 numbered and not sent, 2 sent twice, 2 pairs
    // swapped, and after frame 450, 300 numbered and not sent (3 s, more
    // than the 8-bit sequence spans: it proves 300 modulo 256 of them).
    let mut vehicle = Peer::start(
        "vehicle.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--frames",
            "600",
            "--rate",
            "100",
            "--drop",
            "10,11,12,200",
            "--dup",
            "50,300",
            "--swap",
            "100,400",
            "--silence",
            "450:300",
        ],
    );
    let link = format!("udpout:127.0.0.1:{port}");
    let run = Scraped::start(&["--passive", "--json", &link]);
    let one = [("link", link.as_str()), ("sysid", "1"), ("compid", "1")];
    let value = |body: &str, name: &str| sample(body, name, &one);

    // While it streams: heard, and not silent.
    let body = run.scrape_until("the vehicle heard", |m| {
        value(m, "mavping_source_received_total").is_some_and(|v| v > 50.0)
    });
    assert_promtool_clean(&body);
    assert!(body.contains("# TYPE mavping_source_received_total counter"));
    assert!(body.contains("# TYPE mavping_source_silent gauge"));
    assert_eq!(value(&body, "mavping_source_silent"), Some(0.0));
    // Its silence after frame 450, while it lasts.
    let body = run.scrape_until("the vehicle's silence", |m| {
        value(m, "mavping_source_silent") == Some(1.0)
    });
    assert_eq!(value(&body, "mavping_source_silences_total"), Some(1.0));

    let truth: Value = serde_json::from_str(&vehicle.read_line()).unwrap();
    let sent = truth["sent"].as_f64().unwrap();
    assert_eq!(truth["dropped"], 4, "{truth}");
    assert_eq!(truth["silenced"], 300, "{truth}");
    // The drops and what the sequence proves of the silence.
    let lost = f64::from(4 + 300 % 256);
    // It has sent its last frame: once mavping calls it silent, nothing
    // is pending and every counter is final.
    let body = run.scrape_until("every frame counted and the vehicle silent", |m| {
        value(m, "mavping_source_received_total") == Some(sent)
            && value(m, "mavping_source_silences_total") == Some(2.0)
    });
    assert_promtool_clean(&body);
    let exact = [
        ("mavping_source_received_total", sent),
        ("mavping_source_lost_total", lost),
        ("mavping_source_lost_pending", 0.0),
        ("mavping_source_duplicate_total", 2.0),
        ("mavping_source_reordered_total", 2.0),
        // The 300 frames it did not send: a silence whose gap is counted,
        // the count going on across it (no restart).
        ("mavping_source_resyncs_total", 0.0),
        ("mavping_source_silent", 1.0),
        // pymavlink's arithmetic: the drops, 255 a duplicate, 256 a swap,
        // the silence modulo 256.
        (
            "mavping_source_pymavlink_lost_total",
            f64::from(4 + 2 * 255 + 2 * 256 + 300 % 256),
        ),
    ];
    for (name, want) in exact {
        assert_eq!(value(&body, name), Some(want), "{name}\n{body}");
    }
    let numbered = sent - 2.0 + lost;
    assert_eq!(
        value(&body, "mavping_source_loss_ratio"),
        Some(lost / numbered)
    );
    assert_eq!(
        value(&body, "mavping_source_pymavlink_loss_ratio"),
        Some(1070.0 / (sent + 1070.0))
    );
    let silent_s = value(&body, "mavping_source_silence_seconds_total").unwrap();
    assert!(silent_s > 3.0, "{silent_s}");

    // The run's own summary, after Ctrl-C, says the same of every counter.
    let (code, out, err) = run.stop();
    assert_eq!(code, 0, "{out}{err}");
    let summary = json_line(&out, "passive_summary");
    let s = summary["sources"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["source"]["sysid"] == 1)
        .unwrap_or_else(|| panic!("{summary}"));
    for (name, key) in [
        ("mavping_source_received_total", "received"),
        ("mavping_source_lost_total", "lost"),
        ("mavping_source_duplicate_total", "duplicate"),
        ("mavping_source_reordered_total", "reordered"),
        ("mavping_source_resyncs_total", "resyncs"),
    ] {
        assert_eq!(value(&body, name), s["counts"][key].as_f64(), "{name}: {s}");
    }
    assert_eq!(
        value(&body, "mavping_source_bytes_total"),
        s["bytes"].as_f64()
    );
    assert_eq!(
        value(&body, "mavping_source_silences_total"),
        s["silence_count"].as_f64()
    );
    assert_eq!(
        value(&body, "mavping_source_pymavlink_lost_total"),
        s["pymav"]["loss"].as_f64()
    );
}

#[test]
fn an_echo_run_exports_its_loss_by_direction_as_the_link_lost_it() {
    // Requests lost on the way up, frames on the way down, beside the
    // vehicle's telemetry.
    let link = "sim:?stream=ATTITUDE@50&loss_up=10%&loss_down=5%&seed=7";
    let run = Scraped::start(&["-i", "10ms", "-W", "500ms", "-q", "--json", "-v", link]);
    // The run's only link (its label is the connection string as mavping
    // prints it, every default spelled out).
    let l = [("sysid", "1"), ("compid", "1")];
    let dir = |body: &str, d: &str| {
        let mut labels = l.to_vec();
        labels.push(("direction", d));
        sample(body, "mavping_direction_loss_ratio", &labels)
    };
    let body = run.scrape_until("1500 requests decided and a split", |m| {
        sample(m, "mavping_sent_total", &l).is_some_and(|v| v >= 1500.0) && dir(m, "up").is_some()
    });
    assert_promtool_clean(&body);
    let sent = sample(&body, "mavping_sent_total", &l).unwrap();
    let lost = sample(&body, "mavping_lost_total", &l).unwrap();
    let (round_trip, down, up) = (
        dir(&body, "round_trip").unwrap(),
        dir(&body, "down").unwrap(),
        dir(&body, "up").unwrap(),
    );
    let stderr = sample(
        &body,
        "mavping_direction_loss_stderr",
        &[l.as_slice(), &[("direction", "up")]].concat(),
    )
    .unwrap();
    assert_eq!(
        sample(&body, "mavping_direction_split_consistent", &l),
        Some(1.0)
    );
    // The round trip is the counters' own ratio; up is the formula on the
    // two others.
    assert_eq!(round_trip, lost / sent);
    assert!((up - (1.0 - (1.0 - round_trip) / (1.0 - down))).abs() < 1e-12);

    let (code, out, err) = run.stop();
    assert_eq!(code, 0, "{out}{err}");
    let truth = |k| sim_truth(&err, "1/1", k) as f64;
    // The whole run's truth: the share the link dropped each way. A
    // scrape a second before the end holds the same ratios within their
    // standard errors.
    let down_truth = truth("down_dropped") / truth("down_sent");
    let up_truth =
        truth("up_requests_dropped") / json_line(&out, "summary")["requests"].as_f64().unwrap();
    assert!(
        (down - down_truth).abs() < 0.02,
        "down {down} vs {down_truth}"
    );
    assert!(
        (up - up_truth).abs() < 3.0 * stderr,
        "up {up} ± {stderr} vs {up_truth}"
    );
    assert!(stderr > 0.003 && stderr < 0.03, "{stderr}");
    // And the summary's own split agrees with the exported one.
    let d = &json_line(&out, "summary")["responders"][0]["direction"];
    let final_up = d["uplink_loss"].as_f64().unwrap();
    assert!((final_up - up).abs() < 3.0 * stderr, "{d} vs {up}");
}
