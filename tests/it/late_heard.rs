//! Responders heard late: a satellite link whose replies all come after the
//! timeout, one that answers only after the first requests were lost, and
//! a run stopped with requests in flight. Every request is counted once per
//! responder (not charged, sent or in flight) and the text says which were
//! not charged. In virtual time: a 35 s one-way delay takes no wall time.

use serde_json::Value;

use crate::common::*;

/// Each responder's figures that must add up to the run's requests.
fn figures(s: &Value, id: &str) -> [u64; 7] {
    let r = responder(s, id);
    [
        "not_charged",
        "sent",
        "in_flight",
        "received",
        "lost",
        "late",
        "duplicate",
    ]
    .map(|k| n(r, k))
}

#[test]
fn replies_that_all_come_late_are_charged_as_lost_and_late() {
    // PING throughout (auto would move an unanswered PX4 to TIMESYNC).
    // A request every 30 s, 70 s round trip, 2 s timeout: replies to 0 and
    // 1 come (late) within the run, the others after it ends.
    let link = "sim:?delay=35s&clock=virtual";
    let (code, out, err) =
        run_mavping(&["--json", "--probe", "ping", "-c", "5", "-i", "30s", link]);
    assert_eq!(code, 1, "nothing came in time: {out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(n(&s, "requests"), 5);
    // not charged, sent, in flight, received, lost, late, duplicate
    assert_eq!(figures(&s, "1/1"), [0, 5, 0, 0, 5, 2, 0], "{s}");
    let lost = json_lines(&out)
        .iter()
        .filter(|e| e["type"] == "lost")
        .count();
    assert_eq!(lost, 5, "a lost event for every request: {out}");

    let (_, text, _) = run_mavping(&["--probe", "ping", "-c", "5", "-i", "30s", link]);
    assert!(
        text.contains(
            "1/1 (quadrotor, px4): 5 sent, 0 received, 5 lost (100.0%), 2 late, 0 duplicate, 0 out of order\n"
        ),
        "{text}"
    );
}

#[test]
fn requests_before_the_first_answer_are_not_charged_and_the_text_says_so() {
    // The link is out for the first 40 s (requests 0-3), then answers every
    // request in time (70 s round trip, 80 s timeout).
    let link = "sim:?delay=35s&outage=0s+40s&clock=virtual";
    let args = [
        "--probe", "ping", "-c", "10", "-i", "10s", "-W", "80s", link,
    ];
    let (code, out, err) = run_mavping(&[&["--json", "-q"][..], &args].concat());
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(n(&s, "requests"), 10);
    assert_eq!(figures(&s, "1/1"), [4, 6, 0, 6, 0, 0, 0], "{s}");

    let (_, text, _) = run_mavping(&args);
    assert!(
        text.contains(
            "1/1 (quadrotor, px4): 6 sent, 6 received, 0 lost (0.0%), 0 late, 0 duplicate, \
             0 out of order; 4 earlier requests not charged (sent before its first answer)\n"
        ),
        "{text}"
    );
}

#[test]
fn a_run_stopped_early_counts_every_request_once() {
    // As above, stopped at 125 s: 4 not charged, replies to 4 (at 110 s)
    // and 5 (120 s) received, 6-9 still within their 80 s timeout.
    let link = "sim:?delay=35s&outage=0s+40s&clock=virtual";
    let args = ["-c", "10", "-i", "10s", "-W", "80s", "-w", "125s", link];
    let (code, out, err) = run_mavping(&[&["--json", "-q"][..], &args].concat());
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!((n(&s, "requests"), n(&s, "in_flight")), (10, 4), "{s}");
    assert_eq!(figures(&s, "1/1"), [4, 2, 4, 2, 0, 0, 0], "{s}");

    let (_, text, _) = run_mavping(&args);
    assert!(
        text.contains("10 requests sent in 125.000 s, 4 still in flight (not counted)\n"),
        "{text}"
    );
    assert!(
        text.contains(
            "2 sent, 2 received, 0 lost (0.0%), 0 late, 0 duplicate, 0 out of order, \
             4 in flight; 4 earlier requests not charged (sent before its first answer)\n"
        ),
        "{text}"
    );
}

#[test]
fn responders_first_heard_at_different_times_match_the_links_ground_truth() {
    // Seeded so that 2/1's first exchanges are lost and 1/1's are not.
    let link = "sim:?responders=2&loss=30%&seed=3&clock=virtual";
    let (code, out, err) = run_mavping(&["--json", "-q", "-v", "-c", "200", "-i", "10ms", link]);
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    let requests = n(&s, "requests");
    for id in ["1/1", "2/1"] {
        let truth = |k| sim_truth(&err, id, k);
        let [not_charged, sent, in_flight, received, lost, ..] = figures(&s, id);
        assert_eq!(truth("answered"), requests, "{id}");
        assert_eq!(not_charged, truth("dropped_before_first"), "{id}: {s}");
        assert_eq!(sent, requests - truth("dropped_before_first"), "{id}: {s}");
        assert_eq!(received, truth("delivered"), "{id}: {s}");
        assert_eq!(
            lost,
            truth("dropped") - truth("dropped_before_first"),
            "{id}"
        );
        assert_eq!(not_charged + sent + in_flight, requests, "{id}: {s}");
    }
    assert_eq!(n(responder(&s, "1/1"), "not_charged"), 0, "{s}");
    assert!(n(responder(&s, "2/1"), "not_charged") > 0, "{s}");
}
