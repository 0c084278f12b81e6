//! mavping answers the vehicle's clock questions as a ground station does
//! (issue 40): a pymavlink vehicle (`tests/peers/clock_vehicle.py`) asks
//! TIMESYNC and PING of the ground while mavping probes it, and counts
//! every reply it gets, request by request. Each request is answered
//! exactly once, from mavping's ids, and the summary's count is the
//! vehicle's; `--no-answer` answers none.

use serde_json::Value;

use crate::common::*;

/// A run of mavping probing a clock vehicle for 3 s while the vehicle asks
/// 5 TIMESYNC and 5 PING requests a second for 2 s: mavping's summary and
/// the vehicle's truth.
fn asked(extra: &[&str]) -> (i32, Value, Value) {
    let port = free_udp_port();
    let link = format!("udpin:127.0.0.1:{port}");
    let vehicle = Peer::start(
        "clock_vehicle.py",
        &[&link, "--answer-ping", "--attitude-hz", "20"],
    );
    let target = format!("udpout:127.0.0.1:{port}");
    let mut args = vec!["-c", "30", "-i", "0.1", "--json", &target];
    args.extend(extra);
    let (code, out, err) = run_mavping(&args);
    let truth = vehicle.finish();
    assert!(code == 0, "mavping failed ({code}): {err}\n{out}");
    (code, checked_summary(&out), truth)
}

fn count(v: &Value, key: &str) -> u64 {
    v[key]
        .as_u64()
        .unwrap_or_else(|| panic!("no count {key} in {v}"))
}

#[test]
fn every_timesync_and_ping_request_of_the_vehicle_is_answered_once_from_our_ids() {
    let (_, summary, truth) = asked(&[]);
    let answered = &summary["answered"];
    for kind in ["timesync", "ping"] {
        let requests = count(&truth, &format!("{kind}_requests"));
        // 2 s at 5 a second; the schedule is the vehicle's.
        assert!((9..=11).contains(&requests), "{truth}");
        assert_eq!(
            count(&truth, &format!("{kind}_replies")),
            requests,
            "{truth}"
        );
        assert_eq!(count(&truth, &format!("{kind}_duplicates")), 0, "{truth}");
        assert_eq!(count(&truth, &format!("{kind}_unknown")), 0, "{truth}");
        assert_eq!(
            count(answered, &format!("{kind}_requests")),
            requests,
            "{summary}"
        );
    }
    assert_eq!(count(answered, "unanswered"), 0);
    assert_eq!(count(answered, "commands"), 0);
    // From our own ids, the ones the start line names.
    let ours = &summary["ours"];
    assert_eq!(
        truth["reply_from"],
        serde_json::json!([[ours["sysid"], ours["compid"]]]),
        "{truth}"
    );
    // mavping's own probe went on meanwhile: the vehicle answered it.
    assert!(count(&truth, "answered_ping") + count(&truth, "answered_timesync") >= 25);
}

#[test]
fn with_no_answer_the_vehicle_gets_no_reply_and_the_summary_says_nothing() {
    let (_, summary, truth) = asked(&["--no-answer"]);
    assert!(count(&truth, "timesync_requests") >= 9, "{truth}");
    assert_eq!(count(&truth, "timesync_replies"), 0, "{truth}");
    assert_eq!(count(&truth, "ping_replies"), 0, "{truth}");
    assert!(summary.get("answered").is_none(), "{summary}");
}
