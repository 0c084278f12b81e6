//! Round trips recovered from a telemetry log: logs planned exchange by
//! exchange (`tlog_writer.py`'s `exchanges`, every RTT and fate known),
//! and logs MAVProxy wrote while mavping pinged a pymavlink responder
//! through it, held against the responder's truth and mavping's own
//! figures of the same run.

use serde_json::{json, Value};

use crate::common::*;
use crate::tlog::{read, tlog, write_log, Scratch};

/// The GCS pings, syncs and commands 1/1; 1/1 syncs with the GCS (as
/// ArduPilot does); our own ids ping 1/1 as a log mavping recorded would
/// show; 2/1 streams telemetry beside, and the log runs on after the last
/// request's timeout. Off QGroundControl's milliseconds, everything is
/// 124 µs later (on MAVProxy's 4 µs grid): stamps that are no whole
/// milliseconds, the same RTTs.
fn exchange_plan(stamps: &str) -> Value {
    let mut plan = json!({
        "start_us": 1_764_500_000_000_000u64,
        "stamps": stamps,
        "sources": [{"sysid": 2, "compid": 1, "rate": 20, "frames": 600, "phase_us": 0}],
        "exchanges": [
            {"kind": "ping", "requester": [255, 190], "responder": [1, 1], "count": 40,
             "period_us": 250_000, "phase_us": 1_000, "rtt_us": 40_000, "rtt_step_us": 3_000,
             "drop": [3, 17], "dup": [5, 20], "late": [9], "late_us": 2_500_000,
             "orphan": [30], "link": [3, 0]},
            {"kind": "timesync", "requester": [255, 190], "responder": [1, 1], "count": 30,
             "period_us": 333_000, "phase_us": 2_000, "rtt_us": 25_000, "rtt_step_us": 1_000,
             "drop": [4], "dup": [11], "orphan": [0], "link": [3, 0]},
            {"kind": "timesync", "requester": [1, 1], "responder": [255, 190], "count": 10,
             "period_us": 1_000_000, "phase_us": 500_000, "rtt_us": 5_000, "drop": [2],
             "link": [0, 3]},
            {"kind": "command", "requester": [255, 190], "responder": [1, 1], "count": 6,
             "period_us": 4_000_000, "phase_us": 3_000, "command": 511, "rtt_us": 60_000,
             "retransmit": {"2": 2}, "retry_us": 1_000_000, "drop": [4], "link": [3, 0]},
            {"kind": "ping", "requester": [250, 190], "responder": [1, 1], "count": 20,
             "period_us": 500_000, "phase_us": 4_000, "rtt_us": 35_000, "drop": [6],
             "link": [3, 0]}
        ]
    });
    if stamps != "ms" {
        for list in ["sources", "exchanges"] {
            for x in plan[list].as_array_mut().unwrap() {
                x["phase_us"] = json!(x["phase_us"].as_u64().unwrap() + 124);
            }
        }
    }
    plan
}

fn ids(v: &Value) -> String {
    format!("{}/{}", v["sysid"], v["compid"])
}

fn pair<'a>(rt: &'a Value, kind: &str, from: &str, to: &str) -> &'a Value {
    rt["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["kind"] == kind && ids(&p["requester"]) == from && ids(&p["responder"]) == to)
        .unwrap_or_else(|| panic!("no {kind} {from} -> {to} in {rt}"))
}

fn requests<'a>(rt: &'a Value, kind: &str, from: &str) -> &'a Value {
    rt["requesters"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["kind"] == kind && ids(&r["requester"]) == from)
        .unwrap_or_else(|| panic!("no {kind} requests from {from} in {rt}"))
}

/// The value at quantile `q` of `sorted` (nearest rank).
fn nearest_rank(sorted: &[f64], q: f64) -> f64 {
    let rank = ((q * sorted.len() as f64).ceil() as usize).max(1);
    sorted[rank - 1]
}

/// Every exchange's counts exactly as planned, its RTTs' min, max and
/// mean exactly, its quantiles within the histogram's 3 digits.
fn assert_exchanges(rt: &Value, truth: &Value) {
    for ex in truth["exchanges"].as_array().unwrap() {
        let kind = ex["kind"].as_str().unwrap();
        let (from, to) = (
            ex["requester"].as_str().unwrap(),
            ex["responder"].as_str().unwrap(),
        );
        let p = pair(rt, kind, from, to);
        let why = format!("{kind} {from} -> {to}: {p}\ntruth: {ex}");
        for key in [
            "matched",
            "after_retransmission",
            "unanswered",
            "late",
            "duplicate",
        ] {
            assert_eq!(p[key], ex[key], "{key}: {why}");
        }
        // A TIMESYNC reply names no requester (pymavlink's dialect, as
        // ArduPilot): one with no request is nobody's.
        let orphans = if kind == "timesync" {
            rt["pairs"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|p| p["kind"] == kind && ids(&p["requester"]) == "0/0")
                .filter(|p| ids(&p["responder"]) == to)
                .map(|p| p["no_request"].as_u64().unwrap())
                .sum()
        } else {
            p["no_request"].as_u64().unwrap()
        };
        assert_eq!(orphans, ex["no_request"], "no_request: {why}");
        let r = requests(rt, kind, from);
        assert_eq!(r["requests"], ex["requests"], "{why}\n{r}");
        assert_eq!(r["repeats"], ex["repeats"], "{why}\n{r}");
        assert_eq!(r["evicted"], 0, "{r}");
        assert_eq!(r["in_flight_at_end"], 0, "{r}");
        let mut rtts: Vec<f64> = ex["rtts_us"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        rtts.sort_by(f64::total_cmp);
        let rtt = &p["rtt"];
        let f = |k: &str| rtt[k].as_f64().unwrap();
        assert_eq!(f("min"), rtts[0], "{why}");
        assert_eq!(f("max"), *rtts.last().unwrap(), "{why}");
        let mean = rtts.iter().sum::<f64>() / rtts.len() as f64;
        assert!((f("mean") - mean).abs() < 1e-6 * mean, "mean {mean}: {why}");
        for (k, q) in [("p50", 0.5), ("p90", 0.9), ("p99", 0.99)] {
            let want = nearest_rank(&rtts, q);
            assert!(
                (f(k) - want).abs() <= 0.001 * want,
                "{k} {} against {want}: {why}",
                f(k)
            );
        }
    }
}

#[test]
fn planned_exchanges_are_matched_exactly_whatever_the_stamps() {
    let dir = Scratch::new("rtt-plan");
    for (stamps, resolution_us) in [("us", 1), ("ms", 1000), ("mavproxy", 1)] {
        let path = dir.path(&format!("{stamps}.tlog"));
        let truth = write_log(&path, &exchange_plan(stamps));
        let (code, summary, err) = read(&[], &tlog(&path));
        assert_eq!(code, 0, "{stamps}: {err}");
        let rt = &summary["round_trips"];
        assert_eq!(rt["resolution_us"], resolution_us, "{stamps}");
        assert_eq!(rt["timeout_s"], 2.0);
        assert_eq!(rt["untracked"], 0);
        assert_exchanges(rt, &truth);
        // Nothing in a log is an echo of ours: our ids are a source there
        // (a log `--tlog` recorded), and their requests are matched.
        assert!(
            summary["sources"]
                .as_array()
                .unwrap()
                .iter()
                .any(|s| ids(&s["source"]) == "250/190"),
            "{stamps}"
        );
        assert_eq!(summary["own_frames"], 0, "{stamps}");
    }
}

#[test]
fn the_text_summary_states_the_stamps_resolution_and_a_line_per_exchange() {
    let dir = Scratch::new("rtt-text");
    let path = dir.path("qgc.tlog");
    write_log(&path, &exchange_plan("ms"));
    let (code, out, err) = run_mavping(&[&tlog(&path)]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains(
            "round trips recovered from the log's stamps (whole milliseconds, as QGroundControl \
             writes them; unanswered after 2s):"
        ),
        "{out}"
    );
    // 40 pings: 2 never answered, 1 answered after the timeout, 1 reply
    // with no request: 36 matched, RTTs 40 ms + 3 ms x (k % 10).
    let line = out
        .lines()
        .find(|l| l.starts_with("  ping 255/190 -> 1/1: "))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(
        line.starts_with(
            "  ping 255/190 -> 1/1: 36 matched, 3 unanswered, 1 late, 2 duplicate, 1 with no \
             request in the log; rtt n=36 min/p50/p90/p99/max = 40.000/"
        ),
        "{line}"
    );
    assert!(line.ends_with("/67.000 ms"), "{line}");
    assert!(
        out.contains(
            "  command 255/190 -> 1/1: 5 matched, 1 of them after a retransmission (measured from \
             the last attempt), 1 unanswered; rtt n=5"
        ),
        "{out}"
    );
    assert!(
        out.contains("  requests: command from 255/190: 6 (2 retransmissions)"),
        "{out}"
    );
    // -W sets the timeout: at 3 s the late reply is matched.
    let (code, out, _) = run_mavping(&["-W", "3s", &tlog(&path)]);
    assert_eq!(code, 0);
    assert!(
        out.contains("  ping 255/190 -> 1/1: 37 matched, 2 unanswered, 2 duplicate, 1 with no"),
        "{out}"
    );
}

/// A live mavping run through MAVProxy (`--out` to mavping, its master a
/// responder started by `start` on MAVProxy's master port) with MAVProxy
/// logging: mavping's JSON summary, the responder's truth (`finish`), and
/// the log's passive summary.
fn through_mavproxy<R>(
    name: &str,
    start: impl FnOnce(u16) -> R,
    finish: impl FnOnce(R) -> Value,
    probe: &[&str],
) -> (Value, Value, Value) {
    let dir = Scratch::new(name);
    let (master, out) = (free_udp_port(), free_udp_port());
    let mavproxy = Program::start_on_udp(
        &venv_program("mavproxy.py"),
        &[
            &format!("--master=udpin:127.0.0.1:{master}"),
            &format!("--out=udpout:127.0.0.1:{out}"),
            "--logfile=session.tlog",
            "--non-interactive",
            "--cmd=set flushlogs 1",
        ],
        &dir.0,
        master,
    );
    let responder = start(master);
    // MAVProxy learns where its master is from the responder's first
    // HEARTBEAT: a request forwarded before that would go nowhere.
    std::thread::sleep(std::time::Duration::from_secs(1));
    let mut args = vec!["--json", "-q"];
    args.extend_from_slice(probe);
    let link = format!("udpin:127.0.0.1:{out}");
    args.push(&link);
    let (code, stdout, err) = run_mavping(&args);
    assert_eq!(code, 0, "{stdout}{err}");
    let live = json_lines(&stdout)
        .into_iter()
        .find(|l| l["type"].as_str().is_some_and(|t| t.ends_with("summary")))
        .unwrap_or_else(|| panic!("no summary: {stdout}"));
    std::thread::sleep(std::time::Duration::from_millis(500));
    let truth = finish(responder);
    std::thread::sleep(std::time::Duration::from_millis(500));
    drop(mavproxy);
    let (code, log, err) = read(&[], &tlog(&dir.path("session.tlog")));
    assert_eq!(code, 0, "{err}");
    (live, truth, log)
}

/// A pymavlink responder from tests/peers, on MAVProxy's master port.
fn python_peer(script: &'static str, args: &'static [&'static str]) -> impl FnOnce(u16) -> Peer {
    move |master| {
        let mut all = vec![format!("udpout:127.0.0.1:{master}")];
        all.extend(args.iter().map(|a| a.to_string()));
        let all: Vec<&str> = all.iter().map(String::as_str).collect();
        Peer::start(script, &all)
    }
}

/// The live run's figures for responder 1/1.
fn live_counts(live: &Value) -> (u64, u64, u64) {
    let r = live["responders"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| ids(&r["responder"]) == "1/1")
        .unwrap_or_else(|| panic!("no 1/1 in {live}"));
    let n = |k: &str| r[k].as_u64().unwrap_or_else(|| panic!("{k} in {r}"));
    (n("received"), n("lost"), n("duplicate"))
}

#[test]
fn mavproxy_logs_mavpings_pings_and_a_responders_replies_matched_as_it_answered() {
    // responder.py waits 30 ms before each reply, never answers seqs 3
    // and 7, answers 5 twice.
    let (live, truth, log) = through_mavproxy(
        "rtt-mavproxy-ping",
        python_peer(
            "responder.py",
            &["--delay-ms", "30", "--drop", "3,7", "--dup", "5"],
        ),
        Peer::finish,
        &["-c", "15", "-i", "0.2s"],
    );
    let rt = &log["round_trips"];
    let p = pair(rt, "ping", "250/190", "1/1");
    let why = format!("{p}\nresponder: {truth}\nlive: {live}");
    assert_eq!(truth["ping_requests"], 15, "{why}");
    assert_eq!(p["matched"], truth["replies"], "{why}");
    assert_eq!(p["unanswered"], truth["dropped"], "{why}");
    assert_eq!(p["duplicate"], truth["duplicated"], "{why}");
    assert_eq!(requests(rt, "ping", "250/190")["requests"], 15);
    // The log saw what mavping saw.
    let (received, lost, duplicate) = live_counts(&live);
    assert_eq!(
        (received, lost, duplicate),
        (
            p["matched"].as_u64().unwrap(),
            p["unanswered"].as_u64().unwrap(),
            p["duplicate"].as_u64().unwrap()
        ),
        "{why}"
    );
    // The RTT figures are MAVProxy's stamps, not checked here: it stamps
    // a forwarded request after writing it on, in Python among other
    // threads, and was seen 10 ms late (docs/tlog.md). The planned logs
    // check the figures exactly.
    assert!(p["rtt"].is_object(), "{why}");
}

#[test]
fn mavproxy_logs_timesync_with_an_ardupilot_like_responder_matched_by_ts1() {
    // ArduPilot's replies carry no targets: ts1 alone finds the request.
    let (live, truth, log) = through_mavproxy(
        "rtt-mavproxy-timesync",
        python_peer("ardupilot_like.py", &["--delay-ms", "20", "--drop", "2,9"]),
        Peer::finish,
        &["--probe", "timesync", "-c", "12", "-i", "0.25s"],
    );
    let rt = &log["round_trips"];
    let p = pair(rt, "timesync", "250/190", "1/1");
    let why = format!("{p}\nresponder: {truth}\nlive: {live}");
    assert_eq!(truth["timesync_requests"], 12, "{why}");
    assert_eq!(p["matched"], truth["replies"], "{why}");
    assert_eq!(p["unanswered"], truth["dropped"], "{why}");
    assert_eq!(p["duplicate"], 0, "{why}");
    assert_eq!(requests(rt, "timesync", "250/190")["requests"], 12);
    let (received, lost, _) = live_counts(&live);
    assert_eq!(
        (received, lost),
        (
            p["matched"].as_u64().unwrap(),
            p["unanswered"].as_u64().unwrap()
        ),
        "{why}"
    );
    assert!(p["rtt"].is_object(), "{why}");
}

#[test]
fn mavproxy_logs_mavpings_commands_with_their_retransmissions() {
    // `mavping respond` drops a quarter of its ACKs (seeded): mavping
    // re-sends those commands (confirmation 1, 2, ...).
    let (live, truth, log) = through_mavproxy(
        "rtt-mavproxy-command",
        |master| Respond::start(&["--drop", "25", &format!("udpout:127.0.0.1:{master}")]),
        |r| {
            let (code, counts) = r.finish();
            assert_eq!(code, 0);
            json!(counts)
        },
        &["--probe", "command", "-c", "12", "-i", "0.5s"],
    );
    let rt = &log["round_trips"];
    let p = pair(rt, "command", "250/190", "1/1");
    let r = requests(rt, "command", "250/190");
    let target = &live["targets"][0];
    let why = format!(
        "{p}
{r}
respond: {truth}
live: {target}"
    );
    // respond's counts: requests, ping, timesync, command, retransmissions, ...
    let (commands, retransmissions) = (truth[3].as_u64().unwrap(), truth[4].as_u64().unwrap());
    assert!(retransmissions > 0, "{why}");
    assert_eq!(r["requests"], target["commands"], "{why}");
    assert_eq!(
        r["requests"].as_u64().unwrap() + retransmissions,
        commands,
        "{why}"
    );
    assert_eq!(r["repeats"].as_u64(), Some(retransmissions), "{why}");
    assert_eq!(p["matched"], target["acknowledged"], "{why}");
    assert_eq!(p["unanswered"], target["failed"], "{why}");
    // Acknowledged at a later attempt than the first: after a
    // retransmission.
    let later: u64 = target["attempts"].as_array().unwrap()[1..]
        .iter()
        .map(|n| n.as_u64().unwrap())
        .sum();
    assert_eq!(p["after_retransmission"].as_u64(), Some(later), "{why}");
}
