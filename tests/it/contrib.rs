//! `contrib/`: the alerting rules pass their promtool unit tests, the
//! scrape configuration is valid, and every metric the Grafana dashboard
//! queries is one `mavping serve` really exposes.

use std::collections::BTreeSet;
use std::path::PathBuf;

use crate::common::{assert_promtool_clean, promtool, sample, samples, Server};

fn contrib(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("contrib")
        .join(path)
}

fn promtool_ok(args: &[&str]) -> String {
    let out = promtool()
        .args(args)
        .current_dir(contrib("prometheus"))
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "promtool {args:?}:\n{text}");
    text
}

#[test]
fn the_alerting_rules_pass_their_unit_tests() {
    let checked = promtool_ok(&["check", "rules", "mavping.rules.yml"]);
    assert!(checked.contains("SUCCESS: 11 rules found"), "{checked}");
    let tested = promtool_ok(&["test", "rules", "mavping.rules.test.yml"]);
    assert!(tested.contains("SUCCESS"), "{tested}");
}

#[test]
fn the_scrape_configuration_is_valid() {
    promtool_ok(&["check", "config", "prometheus.yml"]);
}

/// Every `mavping_...` name in the dashboard's queries.
fn dashboard_metrics() -> BTreeSet<String> {
    let text = std::fs::read_to_string(contrib("grafana/mavping-dashboard.json")).unwrap();
    let dashboard: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut names = BTreeSet::new();
    for panel in dashboard["panels"].as_array().unwrap() {
        for target in panel["targets"].as_array().into_iter().flatten() {
            let expr = target["expr"].as_str().unwrap();
            let mut rest = expr;
            while let Some(i) = rest.find("mavping_") {
                let name: String = rest[i..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                rest = &rest[i + name.len()..];
                names.insert(name);
            }
        }
    }
    names
}

#[test]
fn every_metric_the_dashboard_uses_is_exposed() {
    let used = dashboard_metrics();
    assert!(used.len() > 20, "{used:?}");
    // A continuous link with a radio; a TIMESYNC probe (clock offset) and
    // one that fails (a failure reason).
    let server = Server::start(&[
        "--allow",
        "sim:**",
        "--link",
        "sim:?radio=on&delay=1ms&jitter=0ms",
    ]);
    let one = [("sysid", "1"), ("compid", "1")];
    let start = std::time::Instant::now();
    let metrics = loop {
        let m = server.get("/metrics").body;
        if sample(&m, "mavping_received_total", &one).is_some()
            && samples(&m).iter().any(|s| s.name == "mavping_radio_rssi")
        {
            break m;
        }
        assert!(start.elapsed().as_secs() < 30, "{m}");
        std::thread::sleep(std::time::Duration::from_millis(100));
    };
    let timesync = server
        .get("/probe?target=sim%3A%3Fradio%3Don&probe=timesync&count=5&interval=10ms")
        .body;
    let failing = server
        .get("/probe?target=sim%3A%3Floss%3D100%25&count=2&interval=10ms&timeout=50ms")
        .body;
    assert_eq!(sample(&failing, "mavping_probe_success", &[]), Some(0.0));
    let mut exposed = BTreeSet::new();
    for text in [&metrics, &timesync, &failing] {
        assert_promtool_clean(text);
        exposed.extend(samples(text).into_iter().map(|s| s.name));
    }
    let missing: Vec<&String> = used.difference(&exposed).collect();
    assert!(
        missing.is_empty(),
        "the dashboard queries {missing:?}, which mavping does not expose"
    );
}
