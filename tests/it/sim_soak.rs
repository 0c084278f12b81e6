//! The simulated soak, CI-sized: six simulated hours in a few seconds on
//! the virtual clock, with loss, duplication, reordering, delay spikes past
//! the timeout and an outage every hour, the PING seq wrapping past
//! 2^32 on the way. Every count equals the link's ground truth; RSS at the
//! end equals RSS after the first simulated hour within 1 MiB. The week at
//! 10 Hz and the day at 1 kHz are scripts/sim-soak.sh.

use std::io::{BufRead, BufReader, Read};
use std::process::Stdio;

use serde_json::Value;

use crate::common::*;

fn rss_kb(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmRSS:"))
                .and_then(|v| v.split_whitespace().next()?.parse().ok())
        })
        .unwrap_or(0)
}

#[test]
fn six_simulated_hours_match_the_ground_truth_with_flat_memory() {
    const COUNT: u64 = 6 * 3600;
    const FIRST_SEQ: u64 = (1 << 32) - 20_000;
    let link = "sim:?delay=40ms&jitter=10ms&loss=2%&dup=1%&reorder=2%&hold=100ms&spike=0.5%\
                &spike_delay=3s&outage=20m+2m&outage_every=1h&seed=5&clock=virtual";
    let mut child = mavping()
        .args(["--json", "-q", "-v", "-Q", "1h", "-c", &COUNT.to_string()])
        .args([
            "-i",
            "1s",
            "-W",
            "1s",
            "--first-seq",
            &FIRST_SEQ.to_string(),
            link,
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    let mut stderr = child.stderr.take().unwrap();
    let errors = std::thread::spawn(move || {
        let mut s = String::new();
        stderr.read_to_string(&mut s).unwrap();
        s
    });
    // (simulated hour, RSS when its interim summary was read)
    let mut rss: Vec<(f64, u64)> = Vec::new();
    let mut summary = Value::Null;
    for line in BufReader::new(child.stdout.take().unwrap()).lines() {
        let event: Value = serde_json::from_str(&line.unwrap()).unwrap();
        match event["type"].as_str() {
            Some("interim") => rss.push((event["t_s"].as_f64().unwrap() / 3600.0, rss_kb(pid))),
            Some("summary") => summary = event,
            _ => {}
        }
    }
    assert!(child.wait().unwrap().success());
    let err = errors.join().unwrap();
    let s = summary;
    assert_schema(std::slice::from_ref(&s));

    assert_eq!((n(&s, "requests"), n(&s, "in_flight")), (COUNT, 0), "{s}");
    const { assert!(FIRST_SEQ + COUNT > 1 << 32, "the seq wraps inside the run") };
    let r = responder(&s, "1/1");
    let truth = |k| sim_truth(&err, "1/1", k);
    let before = truth("dropped_before_first");
    assert_eq!(truth("answered"), COUNT);
    assert!(truth("outage") >= 6 * 120 - 6, "six outages: {err}");
    assert!(truth("spiked") > 50 && truth("duplicated") > 100, "{err}");
    assert_eq!(n(r, "not_charged"), before, "{r}");
    assert_eq!(n(r, "sent"), COUNT - before, "{r}");
    assert_eq!(n(r, "received"), truth("delivered"), "{r}");
    assert_eq!(
        n(r, "lost"),
        truth("dropped") - before + truth("spiked"),
        "{r}"
    );
    assert_eq!(n(r, "late"), truth("spiked_arrived"), "{r}");
    assert_eq!(n(r, "duplicate"), truth("duplicates_arrived"), "{r}");
    assert_eq!(n(r, "stale"), 0, "{r}");

    // The first interim comes after the first simulated hour; the last one
    // read while mavping still ran is (nearly) its end.
    let (first_h, first) = rss[0];
    let &(last_h, last) = rss.iter().rev().find(|(_, kb)| *kb > 0).unwrap();
    assert!(first_h >= 1.0 && last_h >= 4.0, "{rss:?}");
    assert!(
        first.abs_diff(last) <= 1024,
        "RSS {first} kB at {first_h} h, {last} kB at {last_h} h: {rss:?}"
    );
}
