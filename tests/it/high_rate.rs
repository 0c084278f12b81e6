//! Counts stay exact at high rate: 100,000 PINGs through the simulated
//! link (against its own ground truth) and 300,000 at 300,000 a second
//! through UDP loopback (against `mavping respond`'s own counts), where
//! requests and replies travel in GSO batches that GRO hands up whole.

use std::io::{BufRead, BufReader, Read};
use std::process::Stdio;
use std::time::Duration;

use crate::common::*;
use mavping::engine::matcher::Window;
use mavping::engine::observe::Unobserved;
use mavping::engine::probe::echo;
use mavping::engine::probe::ping::PingProbe;
use mavping::engine::session::Controls;
use mavping::engine::summary::EchoSummary;
use mavping::engine::SessionConfig;
use mavping::frame::{SysComp, Version};
use mavping::transport::sim::{SimLink, SimParams};

#[test]
fn hundred_thousand_pings_through_the_simulated_link_match_its_ground_truth() {
    let params =
        SimParams::parse("?responders=3&loss=3%&dup=2%&reorder=2%&hold=5ms&jitter=3ms&seed=21")
            .unwrap();
    let cfg = SessionConfig {
        link_name: "sim".into(),
        ours: SysComp::new(255, 190),
        interval: Duration::from_micros(100),
        count: Some(100_000),
        deadline: None,
        wait: None,
        interim: None,
        timeout: Duration::from_millis(200),
        version: Version::V2,
        heartbeat: true,
        answer: true,
        capacity: 8192,
        window: Window::FirstAnswer,
        first_seq: u32::MAX - 10_000, // and the sequence wraps on the way
        precise_pacing: false,
        signing: None,
        sweep: None,
        wire: None,
        radio_type: mavping::engine::radio::RadioType::Auto,
        c2: None,
    };
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    let (outcome, truth) = runtime.block_on(async {
        let mut link = SimLink::new(params);
        let probe = PingProbe::new(0);
        let controls = Controls::default();
        let outcome = echo::run(&cfg, &mut link, probe, &mut Unobserved, &controls).await;
        (outcome, link.truth())
    });
    let summary = outcome
        .summary
        .get::<EchoSummary>()
        .expect("an echo probe's summary");
    assert_eq!(summary.requests, 100_000);
    for (id, t) in truth {
        let c = summary
            .responders
            .iter()
            .find(|r| r.id == id)
            .unwrap()
            .counts;
        assert_eq!(t.answered, 100_000, "{id}");
        assert_eq!(c.sent, t.answered - t.dropped_before_first, "{id}");
        assert_eq!(c.received, t.delivered, "{id}");
        assert_eq!(c.lost, t.dropped - t.dropped_before_first, "{id}");
        assert_eq!(c.duplicate, t.duplicates_arrived, "{id}");
        assert!(t.duplicated - t.duplicates_arrived <= 3, "{id}: {t:?}");
        assert_eq!((c.late, c.stale), (0, 0), "{id}");
        assert!(
            c.out_of_order > 0 && c.lost > 2_000 && c.duplicate > 1_000,
            "{id}: {c:?}"
        );
    }
}

#[test]
fn three_hundred_thousand_pings_a_second_over_loopback_match_the_responders_counts() {
    let port = free_udp_port();
    let mut respond = mavping()
        .args(["respond", &format!("udpin:127.0.0.1:{port}")])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut respond_out = BufReader::new(respond.stdout.take().unwrap());
    let mut line = String::new();
    respond_out.read_line(&mut line).unwrap();
    // A long timeout: on a loaded machine a debug-build responder may queue
    // replies for a while; every one must still arrive before its request
    // is decided, so the two sides' counts can be held against each other.
    // (A debug build falls behind 300k/s; the bursts only grow.)
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "300000",
        "--rate",
        "300000",
        "-W",
        "5s",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    signal(respond.id(), "TERM");
    let mut rest = String::new();
    respond_out.read_to_string(&mut rest).unwrap();
    let _ = respond.wait();
    assert_eq!(code, 0, "{err}");
    let summary: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let r = &summary["responders"][0];
    let n = |k: &str| r[k].as_u64().unwrap();
    // "respond 1/1: N requests (...), M replies sent, 0 dropped, 0 duplicated"
    let replies_sent: u64 = rest
        .split(" replies sent")
        .next()
        .and_then(|s| s.rsplit(", ").next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("respond said: {rest}"));
    assert_eq!(summary["requests"], 300_000);
    assert_eq!(n("sent"), n("received") + n("lost"));
    // Every reply the responder sent is accounted for exactly once.
    assert_eq!(
        replies_sent,
        n("received") + n("late") + n("duplicate"),
        "{r}"
    );
    assert_eq!(n("stale"), 0);
}
