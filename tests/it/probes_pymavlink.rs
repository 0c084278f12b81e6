//! TIMESYNC and command probes against pymavlink peers, and `mavping
//! respond` checked by pymavlink's own decoding, over real UDP sockets.

use std::process::Stdio;
use std::time::Duration;

use crate::common::*;

/// "  clock offset -1795426178.236208 s ± ..." -> ns.
fn clock_offset_ns(stdout: &str) -> i128 {
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("clock offset "))
        .unwrap_or_else(|| panic!("no clock line: {stdout}"));
    let value = line.split_whitespace().nth(2).unwrap();
    let (sign, digits) = value.split_at(1);
    let (secs, micros) = digits.split_once('.').unwrap();
    let ns =
        secs.parse::<i128>().unwrap() * 1_000_000_000 + micros.parse::<i128>().unwrap() * 1_000;
    if sign == "-" {
        -ns
    } else {
        ns
    }
}

/// "drift +49.79 ± 0.31 ppm" -> 49.79
fn drift_ppm(stdout: &str) -> f64 {
    let tail = stdout.split(", drift ").nth(1).expect(stdout);
    tail.split_whitespace()
        .next()
        .unwrap()
        .parse()
        .expect(stdout)
}

/// The numbers of a summary line, in order ("3 commands, 3 acknowledged").
fn numbers(line: &str) -> Vec<u64> {
    line.split(|c: char| !c.is_ascii_digit())
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect()
}

fn line_starting<'a>(stdout: &'a str, prefix: &str) -> &'a str {
    stdout
        .lines()
        .find(|l| l.trim_start().starts_with(prefix))
        .unwrap_or_else(|| panic!("no line starting {prefix:?}: {stdout}"))
}

/// Runs a pymavlink script that exits by itself; returns its JSON line.
fn run_peer(script: &str, args: &[&str]) -> serde_json::Value {
    let child = std::process::Command::new(python())
        .arg("-u")
        .arg(peer_script(script))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let (code, out, _) = wait_output(child, Duration::from_secs(30));
    assert_eq!(code, 0, "{script}: {out}");
    serde_json::from_str(out.lines().last().unwrap()).unwrap()
}

#[test]
fn timesync_against_an_ardupilot_like_peer_counts_exactly_and_finds_its_clock() {
    let port = free_udp_port();
    // Never answers PING; drops TIMESYNC requests 2 and 5; 20 ms per reply.
    let peer = Peer::start(
        "ardupilot_like.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--drop",
            "2,5",
            "--delay-ms",
            "20",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "--probe",
        "timesync",
        "-c",
        "10",
        "-i",
        "0.1",
        "-W",
        "500ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!(
        (c.sent, c.received, c.lost, c.late, c.duplicate, c.stale),
        (10, 8, 2, 0, 0, 0),
        "{out}"
    );
    // The peer holds each reply 20 ms: RTT is that plus loopback and Python.
    let rtt = numbers(line_starting(&out, "rtt min/mean/max"));
    let (min_ms, max_ms) = (rtt[0] as f64 + rtt[1] as f64 / 1e3, rtt[4] as f64);
    assert!(min_ms >= 20.0 && max_ms < 60.0, "{out}");
    let truth = peer.finish();
    assert_eq!(truth["timesync_requests"], 10);
    assert_eq!(truth["replies"], 8);
    assert_eq!(truth["ping_ignored"], 0);
    // Their clock counts from their start; ours (ts1) is the wall clock.
    // The peer reads its clock as it answers, after its 20 ms sleep, so
    // the NTP midpoint puts it 10 ms early: the bound is ± RTT/2.
    let measured = clock_offset_ns(&out);
    let expected = i128::from(truth["offset_ns"].as_i64().unwrap());
    let error_ms = (measured - expected) as f64 / 1e6;
    assert!(
        (error_ms - 10.0).abs() < 2.0,
        "offset {measured} vs truth {expected}: {error_ms} ms\n{out}"
    );
}

#[test]
fn sim_clock_offset_and_drift_match_the_truth() {
    // 2,000 exchanges over 100 s of virtual time, 2 ms of jitter per leg.
    let (code, out, _) = run_mavping(&[
        "--probe",
        "timesync",
        "-q",
        "-c",
        "2000",
        "-i",
        "50ms",
        "sim:?offset=-3.25s&drift=80&clock=virtual&seed=4",
    ]);
    assert_eq!(code, 0, "{out}");
    let offset_ms = clock_offset_ns(&out) as f64 / 1e6;
    assert!((offset_ms + 3250.0).abs() < 0.5, "{out}");
    assert!((drift_ppm(&out) - 80.0).abs() < 2.0, "{out}");
    let c = text_counts(&out, "1/1").expect(&out);
    assert_eq!((c.sent, c.received), (2000, 2000));
}

#[test]
fn command_acked_on_the_third_attempt() {
    let port = free_udp_port();
    let peer = Peer::start(
        "commander.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--ack-on", "3"],
    );
    let (code, out, err) = run_mavping(&[
        "--probe",
        "command",
        "--target",
        "1/1",
        "-c",
        "3",
        "-i",
        "0.5",
        "--retry-interval",
        "100ms",
        "--retries",
        "4",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let counts = numbers(line_starting(&out, "1/1: "));
    // 1/1, then commands, acknowledged, failed, skipped, late, duplicate.
    assert_eq!(counts, vec![1, 1, 3, 3, 0, 0, 0, 0], "{out}");
    assert_eq!(
        line_starting(&out, "attempts until ack").trim(),
        "attempts until ack: 3x3",
        "{out}"
    );
    // Acknowledged after the third transmission, 200 ms after the first.
    let tta = numbers(line_starting(&out, "time to ack min/mean/max"));
    let (min_ms, max_ms) = (tta[0], tta[4]);
    assert!(min_ms >= 200 && max_ms < 230, "{out}");
    assert!(out.contains("ack results: accepted 3"), "{out}");
    let truth = peer.finish();
    assert_eq!(truth["commands"], 9);
    assert_eq!(truth["acks"], 3);
    assert_eq!(truth["commands_ids"], serde_json::json!([512]));
    assert_eq!(
        truth["by_confirmation"],
        serde_json::json!({"0": 3, "1": 3, "2": 3})
    );
}

#[test]
fn command_never_acked_counts_failures_and_exits_1() {
    let port = free_udp_port();
    let peer = Peer::start(
        "commander.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--never"],
    );
    let (code, out, err) = run_mavping(&[
        "--probe",
        "command",
        "-c",
        "2",
        "-i",
        "0.4",
        "--retry-interval",
        "50ms",
        "--retries",
        "2",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 1, "{out}\n{err}");
    let counts = numbers(line_starting(&out, "1/1: "));
    assert_eq!(counts, vec![1, 1, 2, 0, 2, 0, 0, 0], "{out}");
    assert_eq!(out.matches("no ack from 1/1").count(), 2, "{out}");
    let truth = peer.finish();
    assert_eq!(truth["commands"], 6);
    assert_eq!(truth["acks"], 0);
}

#[test]
fn respond_answers_a_pymavlink_prober_exactly() {
    let port = free_udp_port();
    let respond = Respond::start(&[
        "--sysid",
        "7",
        "--compid",
        "3",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    let f = run_peer(
        "prober.py",
        &[
            &format!("udpout:127.0.0.1:{port}"),
            "--responder",
            "7/3",
            "--count",
            "30",
        ],
    );
    assert_eq!(f["ping_ok"], 30, "{f}");
    assert_eq!(f["timesync_ok"], 30, "{f}");
    assert_eq!(f["acks_ok"], 2, "{f}");
    for bad in ["ping_bad", "timesync_bad", "acks_bad", "other_source"] {
        assert_eq!(f[bad], 0, "{bad}: {f}");
    }
    assert_eq!(f["tc1_rising"], true, "{f}");
    assert!(f["heartbeats"].as_u64().unwrap() >= 1, "{f}");
    let (code, counts) = respond.finish();
    assert_eq!(code, 0);
    assert_eq!(counts, vec![62, 30, 30, 2, 1, 62, 0, 0]);
}

#[test]
fn respond_link_emulation_matches_its_ground_truth() {
    let port = free_udp_port();
    let respond = Respond::start(&[
        "--drop",
        "30",
        "--dup",
        "20",
        "--delay",
        "5ms",
        "--jitter",
        "2ms",
        "--seed",
        "11",
        "--no-ping",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    let f = run_peer(
        "prober.py",
        &[&format!("udpout:127.0.0.1:{port}"), "--count", "40"],
    );
    let (code, c) = respond.finish();
    assert_eq!(code, 0);
    let (requests, ping, timesync, command, _, sent, dropped, duplicated) =
        (c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]);
    // --no-ping: PINGs are not requests it answers.
    assert_eq!((ping, timesync, command), (0, 40, 2), "{c:?}");
    assert_eq!(f["ping_ok"], 0, "{f}");
    assert!(dropped > 0 && duplicated > 0, "{c:?}");
    // Exactly what it says it sent arrived, and every reply was correct.
    assert_eq!(sent, requests - dropped + duplicated, "{c:?}");
    let received = f["timesync_ok"].as_u64().unwrap() + f["acks_ok"].as_u64().unwrap();
    assert_eq!(received, sent, "{f} vs {c:?}");
    assert_eq!(f["timesync_bad"], 0, "{f}");
    assert_eq!(f["acks_bad"], 0, "{f}");
}

#[test]
fn mavping_measures_mavping_respond() {
    let port = free_udp_port();
    let respond = Respond::start(&[
        "--drop",
        "25",
        "--seed",
        "2",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    let (code, out, err) = run_mavping(&[
        "--probe",
        "timesync",
        "-c",
        "40",
        "-i",
        "0.01",
        "-W",
        "300ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let (_, truth) = respond.finish();
    let c = text_counts(&out, "1/1").expect(&out);
    // Its window starts at its first answer: requests before it that it
    // dropped are outside; every drop after it is a loss.
    assert_eq!(truth[2], 40);
    assert_eq!(c.received, truth[5]);
    assert_eq!(c.received + c.lost, c.sent);
    assert!(c.lost > 0 && c.lost <= truth[6], "{out}\n{truth:?}");
}

/// `mavping respond` on a serial port: a pty pair ("null-modem cable")
/// with a pymavlink prober on the far end, both at 57600 baud.
#[test]
fn respond_answers_a_pymavlink_prober_over_a_pty() {
    let mut bridge = Peer::start("pty_bridge.py", &[]);
    let line = bridge.read_line();
    let (a, b) = line.split_once(' ').expect("two pty paths");
    let respond = Respond::start(&[
        "--sysid",
        "7",
        "--compid",
        "3",
        &format!("serial:{a}:57600"),
    ]);
    let f = run_peer(
        "prober.py",
        &[b, "--baud", "57600", "--responder", "7/3", "--count", "30"],
    );
    assert_eq!(f["ping_ok"], 30, "{f}");
    assert_eq!(f["timesync_ok"], 30, "{f}");
    assert_eq!(f["acks_ok"], 2, "{f}");
    for bad in ["ping_bad", "timesync_bad", "acks_bad", "other_source"] {
        assert_eq!(f[bad], 0, "{bad}: {f}");
    }
    let (code, counts) = respond.finish();
    assert_eq!(code, 0);
    assert_eq!(counts, vec![62, 30, 30, 2, 1, 62, 0, 0]);
}

/// The default probe against the ArduPilot-like peer: its TIMESYNC
/// requests and replies, by its own count, against what mavping charged.
fn auto_against_ardupilot_like(autopilot: &str) -> String {
    let port = free_udp_port();
    let peer = Peer::start(
        "ardupilot_like.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--drop",
            "4,7",
            "--autopilot",
            autopilot,
        ],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "30",
        "-i",
        "0.1",
        "-W",
        "500ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(
        out.contains("PING 10/s (TIMESYNC where PING is not answered)"),
        "{out}"
    );
    assert!(out.contains("1/1 (quadrotor, "), "{out}");
    assert!(out.contains(") via TIMESYNC: "), "{out}");
    let c = text_counts(&out, "1/1").expect(&out);
    let truth = peer.finish();
    // Every TIMESYNC request it saw is charged (its first was answered, so
    // the window opens there), and only those: the PINGs before are not.
    let requests = truth["timesync_requests"].as_u64().unwrap();
    assert!(requests >= 8, "{truth}\n{out}");
    assert_eq!(truth["ping_ignored"], 30, "{truth}");
    assert_eq!(
        (c.sent, c.received, c.lost, c.late, c.duplicate, c.stale),
        (requests, truth["replies"].as_u64().unwrap(), 2, 0, 0, 0),
        "{truth}\n{out}"
    );
    out
}

#[test]
fn auto_measures_an_ardupilot_on_the_first_try() {
    let out = auto_against_ardupilot_like("3");
    // Its clock too, as --probe timesync would.
    assert!(out.contains("  clock offset "), "{out}");
    assert!(!out.contains("hint:"), "{out}");
}

#[test]
fn auto_switches_a_silent_px4_heartbeat_after_three_unanswered_pings() {
    // Says PX4, answers TIMESYNC only: asked by TIMESYNC once 3 PINGs went
    // unanswered for a whole timeout (500 ms).
    auto_against_ardupilot_like("12");
}

#[test]
fn auto_picks_a_probe_per_responder_on_one_link() {
    // One listening link, two peers: `mavping respond` (answers PING, 1/1)
    // and the ArduPilot-like peer (TIMESYNC only, 2/1).
    let port = free_udp_port();
    let listen = format!("udp:127.0.0.1:{port}");
    let pinger = start_mavping(&[
        "--json", "-c", "30", "-i", "0.1", "-W", "500ms", "--wait", "20s", &listen,
    ]);
    std::thread::sleep(Duration::from_millis(300));
    let ardupilot = Peer::start(
        "ardupilot_like.py",
        &[&format!("udpout:127.0.0.1:{port}"), "--sysid", "2"],
    );
    let respond = Respond::start(&[&format!("udpout:127.0.0.1:{port}")]);
    let (code, out, err) = pinger.wait(Duration::from_secs(30));
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(s["probe"], "auto");
    let px4 = responder(&s, "1/1");
    let ardu = responder(&s, "2/1");
    assert_eq!(px4["probe"], "ping", "{s}");
    assert_eq!(ardu["probe"], "timesync", "{s}");
    let truth = ardupilot.finish();
    let (_, counts) = respond.finish();
    // Exact for both: each charged what it answered, by its own count.
    assert_eq!(
        n(ardu, "sent"),
        truth["timesync_requests"].as_u64().unwrap(),
        "{s}"
    );
    assert_eq!(
        n(ardu, "received"),
        truth["replies"].as_u64().unwrap(),
        "{s}"
    );
    assert_eq!(n(ardu, "lost"), 0, "{s}");
    // respond's counts: requests, ping, timesync, ...: it answered every
    // PING it got and no TIMESYNC reply of its counted for it.
    assert_eq!(n(px4, "sent"), counts[1], "{s}\n{counts:?}");
    assert_eq!(n(px4, "received"), counts[1], "{s}\n{counts:?}");
    assert_eq!(n(px4, "duplicate"), 0, "{s}");
    assert!(ardu["clock"].is_object() && px4["clock"].is_null(), "{s}");
}

#[test]
fn sim_ping_off_is_an_ardupilot_measured_by_timesync() {
    let link = "sim:?ping=off&clock=virtual&loss=10%&seed=3";
    let (code, out, err) = run_mavping(&["-v", "--json", "-q", "-c", "200", "-i", "50ms", link]);
    assert!(code <= 1, "{out}\n{err}");
    let s = checked_summary(&out);
    let r = responder(&s, "1/1");
    assert_eq!(r["identity"]["autopilot_name"], "ardupilotmega", "{s}");
    assert_eq!(r["probe"], "timesync", "{s}");
    // The sim's own count of what it answered and dropped, after the first
    // request it answered (those before are not charged).
    let answered = sim_truth(&err, "1/1", "answered");
    let dropped = sim_truth(&err, "1/1", "dropped");
    let before = sim_truth(&err, "1/1", "dropped_before_first");
    assert_eq!(n(r, "received"), answered - dropped, "{s}\n{err}");
    assert_eq!(n(r, "lost"), dropped - before, "{s}\n{err}");
    assert_eq!(n(r, "sent") + n(r, "not_charged"), 200, "{s}");
    assert!(n(r, "lost") > 5, "{s}");
}

#[test]
fn probe_ping_keeps_pinging_an_ardupilot_and_says_try_timesync() {
    let (code, out, _) = run_mavping(&["--probe", "ping", "-c", "5", "-i", "0.1", "sim:?ping=off"]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains("from 250/190: PING 10/s, timeout"), "{out}");
    assert!(out.contains("no replies"), "{out}");
    assert!(
        out.contains("never answered PING; ArduPilot answers only TIMESYNC: try --probe timesync"),
        "{out}"
    );
}
