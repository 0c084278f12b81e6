//! When things are not normal: a listening run nobody answers, diagnoses
//! built from what was heard (against pymavlink peers and MAVSDK's own
//! mavsdk_server), TIMESYNC bounds that hold the truth (pymavlink's wall
//! clock, MAVProxy's system_time), outputs checked before the first
//! request, and usage errors that help.

use std::time::Duration;

use serde_json::Value;

use crate::common::*;

fn codes(summary: &Value) -> Vec<String> {
    summary["hints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| h["code"].as_str().unwrap().to_string())
        .collect()
}

fn hint<'a>(summary: &'a Value, code: &str) -> &'a str {
    summary["hints"]
        .as_array()
        .unwrap()
        .iter()
        .find(|h| h["code"] == code)
        .and_then(|h| h["text"].as_str())
        .unwrap_or_else(|| panic!("no {code} hint in {summary}"))
}

#[test]
fn a_listening_run_with_a_count_ends_when_nobody_sends() {
    // 5 requests at 100 ms plus the 2 s timeout: it gives up after 2.5 s.
    for scheme in ["udpin", "udp", "tcpin"] {
        let port = if scheme == "tcpin" {
            free_tcp_port()
        } else {
            free_udp_port()
        };
        let link = format!("{scheme}:127.0.0.1:{port}");
        let (code, out, err) = run_mavping(&["-c", "5", "-i", "100ms", &link]);
        assert_eq!(code, 1, "{out}\n{err}");
        let shown = if scheme == "udp" { "udpin" } else { scheme };
        assert!(
            out.contains(&format!(
                "\nno MAVLink system heard on {shown}:127.0.0.1:{port} in 2.5 s\n"
            )),
            "{out}"
        );
    }
    // --wait, and JSON: the same facts, schema-valid.
    let port = free_udp_port();
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "--wait",
        "300ms",
        &format!("udpin:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 1, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(s["no_peer_heard_s"], 0.3);
    assert_eq!(codes(&s), ["no_peer_heard"]);
    assert_eq!(s["requests"], 0);
}

#[test]
fn mavsdk_server_answers_our_default_ids_and_is_diagnosed_on_qgcs() {
    let server = venv_program("mavsdk_server");
    let dir = std::env::temp_dir();
    let port = free_udp_port();
    let _mavsdk = Program::start_on_udp(
        &server,
        &["-p", "0", &format!("udpin://127.0.0.1:{port}")],
        &dir,
        port,
    );
    let link = format!("udpout:127.0.0.1:{port}");
    let as_qgc = |expected: &[&str]| {
        let (code, out, err) = run_mavping(&[
            "--json", "-q", "-c", "3", "-i", "100ms", "-W", "500ms", "--sysid", "255", "--compid",
            "190", &link,
        ]);
        assert_eq!(code, 1, "{out}\n{err}");
        let s = checked_summary(&out);
        assert_eq!(codes(&s), expected, "{s}");
        hint(&s, "our_ids_are_qgcs").to_string()
    };
    // QGroundControl's ids: MAVSDK drops every frame, nothing comes back
    // at all (a fresh mavsdk_server sends nothing until it has discovered
    // a system), and the summary says why that may be.
    let text = as_qgc(&["nothing_heard", "our_ids_are_qgcs"]);
    assert!(text.ends_with("try --sysid 250"), "{text}");
    // Our default ids (250/190): MAVSDK answers as 245/190.
    let (code, out, err) = run_mavping(&["--json", "-q", "-c", "4", "-i", "100ms", &link]);
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    let r = responder(&s, "245/190");
    assert_eq!((n(r, "sent"), n(r, "received")), (4, 4), "{s}");
}

/// A pymavlink responder (PX4-like unless told) that never answers PING.
fn silent_run(peer_args: &[&str], mavping_args: &[&str]) -> Value {
    let port = free_udp_port();
    let udpin = format!("udpin:127.0.0.1:{port}");
    let mut args = vec![udpin.as_str(), "--no-ping"];
    args.extend_from_slice(peer_args);
    let _peer = Peer::start("responder.py", &args);
    let link = format!("udpout:127.0.0.1:{port}");
    let mut all = vec!["--json", "-q", "-c", "3", "-i", "100ms", "-W", "300ms"];
    all.extend_from_slice(mavping_args);
    all.push(&link);
    let (code, out, err) = run_mavping(&all);
    assert_eq!(code, 1, "{out}\n{err}");
    checked_summary(&out)
}

#[test]
fn a_silent_system_is_diagnosed_by_what_it_showed() {
    let s = silent_run(&["--autopilot", "3"], &["--probe", "ping"]);
    assert_eq!(codes(&s), ["timesync_only"], "{s}");
    assert!(hint(&s, "timesync_only").ends_with("try --probe timesync"));
    let s = silent_run(&["--autopilot", "3"], &["--probe", "timesync"]);
    assert_eq!(codes(&s), ["sysid_enforced"], "{s}");
    let s = silent_run(&["--autopilot", "12"], &["--probe", "ping"]);
    assert_eq!(codes(&s), ["never_answered"], "{s}");
    assert!(hint(&s, "never_answered").contains("ignores our ids 250/190"));
    let s = silent_run(&["--autopilot", "12", "--mavlink1"], &["--probe", "ping"]);
    assert_eq!(codes(&s), ["mavlink1_only"], "{s}");
}

#[test]
fn a_signing_peer_without_our_key_is_named_not_mistaken_for_ardupilot() {
    let port = free_udp_port();
    // Signs everything, refuses our unsigned requests, sends HEARTBEAT.
    let _peer = Peer::start(
        "signed_peer.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--key",
            "secret",
            "--sysid",
            "8",
            "--heartbeat-hz",
            "20",
        ],
    );
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "3",
        "-i",
        "200ms",
        "-W",
        "300ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 1, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(codes(&s), ["signed_no_key"], "{s}");
    assert_eq!(
        hint(&s, "signed_no_key"),
        "frames from 8/1 are signed and we have no key: pass --signing-key"
    );
    let signing = &s["signing"];
    assert_eq!(signing["key"], false, "{s}");
    assert!(n(signing, "signed_unchecked") > 0, "{s}");
}

#[test]
fn no_probe_hint_while_requests_are_still_in_flight() {
    let port = free_udp_port();
    let run = start_mavping(&["--json", "-i", "500ms", &format!("udpin:127.0.0.1:{port}")]);
    // It sends HEARTBEAT at once (PX4-like) and holds every reply 5 s.
    let _peer = Peer::start(
        "responder.py",
        &[&format!("udpout:127.0.0.1:{port}"), "--delay-ms", "5000"],
    );
    std::thread::sleep(Duration::from_millis(1500));
    signal(run.child.id(), "INT");
    let (code, out, err) = run.wait(Duration::from_secs(30));
    assert_eq!(code, 1, "{out}\n{err}");
    let s = checked_summary(&out);
    assert!(s["interrupted"].as_bool().unwrap(), "{s}");
    assert_eq!(codes(&s), ["too_early"], "{s}");
}

/// The causal bounds of a TIMESYNC run against `link`, and its estimate.
fn clock_bounds(link: &str) -> (i64, i64, i64) {
    let (code, out, err) = run_mavping(&[
        "--json", "-q", "--probe", "timesync", "-c", "50", "-i", "20ms", link,
    ]);
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    let clock = &s["responders"][0]["clock"];
    let get = |k: &str| clock[k].as_i64().unwrap_or_else(|| panic!("{k}: {s}"));
    (get("lower_ns"), get("offset_ns"), get("upper_ns"))
}

#[test]
fn timesync_bounds_hold_the_true_offset_every_time() {
    // pymavlink answering with the wall clock: true offsets 0 and +100 s,
    // 20 runs each, the two peers measured side by side.
    let check = |offset_s: i64| {
        let port = free_udp_port();
        let offset = offset_s.to_string();
        let _peer = Peer::start(
            "ardupilot_like.py",
            &[
                &format!("udpin:127.0.0.1:{port}"),
                "--clock",
                "unix",
                "--offset-s",
                &offset,
            ],
        );
        let truth = offset_s * 1_000_000_000;
        for run in 0..20 {
            let (lower, estimate, upper) = clock_bounds(&format!("udpout:127.0.0.1:{port}"));
            assert!(
                lower <= truth && truth <= upper,
                "run {run}: truth {truth} outside [{lower}, {upper}]"
            );
            assert!(lower <= estimate && estimate <= upper);
        }
    };
    std::thread::scope(|scope| {
        let zero = scope.spawn(|| check(0));
        let hundred = scope.spawn(|| check(100));
        zero.join().unwrap();
        hundred.join().unwrap();
    });
}

#[test]
fn timesync_bounds_through_mavproxy_hold_its_clock() {
    // MAVProxy's system_time module answers TIMESYNC from its master link
    // with time.time() in ns plus 1234 (a double: ~256 ns steps), once its
    // target system is ours.
    let mavproxy = venv_program("mavproxy.py");
    let dir = std::env::temp_dir().join(format!("mavping-mavproxy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let port = free_udp_port();
    let _mavproxy = Program::start_on_udp(
        &mavproxy,
        &[
            &format!("--master=udpin:127.0.0.1:{port}"),
            "--non-interactive",
            "--load-module=system_time",
            "--target-system=250",
            "--target-component=190",
        ],
        &dir,
        port,
    );
    for run in 0..3 {
        let (lower, _, upper) = clock_bounds(&format!("udpout:127.0.0.1:{port}"));
        assert!(
            lower - 256 <= 1234 && 1234 <= upper + 256,
            "run {run}: MAVProxy's +1234 ns outside [{lower}, {upper}]"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn output_paths_are_checked_before_the_first_request() {
    let dir = std::env::temp_dir();
    let dir = dir.to_str().unwrap();
    for flag in ["--hgrm", "--samples", "--plot"] {
        let path = if flag == "--plot" {
            format!("{dir}/no-such-dir/x.svg")
        } else {
            dir.to_string()
        };
        let (code, out, err) = run_mavping(&["-c", "1000", "-i", "1ms", flag, &path, "sim:"]);
        assert_eq!(code, 2, "{flag}: {out}\n{err}");
        assert!(out.is_empty(), "{flag}: nothing was measured: {out}");
        assert!(
            err.starts_with(&format!("mavping: cannot write {flag} {path}: ")),
            "{flag}: {err}"
        );
    }
}

#[test]
fn usage_errors_say_what_is_missing_and_what_was_meant() {
    let (code, _, err) = run_mavping(&[]);
    assert_eq!(code, 2);
    assert!(
        err.starts_with("mavping: missing CONNECTION: where to ping, for example:\n"),
        "{err}"
    );
    let examples: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("  mavping "))
        .collect();
    assert_eq!(examples.len(), 3, "{err}");
    assert!(
        examples[0].starts_with("  mavping udp:127.0.0.1:14550"),
        "{err}"
    );
    let (code, _, err) = run_mavping(&["--cuont", "3", "sim:"]);
    assert_eq!(code, 2);
    assert_eq!(
        err.trim(),
        "mavping: unexpected argument '--cuont' found; a similar argument exists: '--count' (see --help)"
    );
    // -4 and -6 are address families, not connection strings.
    let (code, _, err) = run_mavping(&["-6", "-c", "1", "udpout:127.0.0.1:14550"]);
    assert_eq!(code, 2);
    assert_eq!(
        err.trim(),
        "mavping: cannot resolve 127.0.0.1:14550: no IPv6 address (-6)"
    );
    let (code, _, err) = run_mavping(&["-4", "-6", "sim:"]);
    assert_eq!(code, 2);
    assert!(err.contains("cannot be used with"), "{err}");
}

#[test]
fn equal_rtts_make_one_histogram_row() {
    let (code, out, _) = run_mavping(&["-q", "-c", "5", "sim:?jitter=0ms&clock=virtual"]);
    assert_eq!(code, 0, "{out}");
    let rows: Vec<&str> = out.lines().filter(|l| l.contains(" ms |")).collect();
    assert_eq!(
        rows,
        ["     20.000 ms |########################################| 5"],
        "{out}"
    );
}

/// Hints where a run fails with evidence but said nothing (issue 28, 11).
/// A pymavlink responder that holds every reply 800 ms, pinged with a
/// 300 ms timeout: every reply is late.
#[test]
fn replies_that_all_come_after_the_timeout_say_raise_it() {
    let port = free_udp_port();
    let _peer = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--delay-ms", "800"],
    );
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "-c",
        "3",
        "-i",
        "1s",
        "-W",
        "300ms",
        &format!("udpout:127.0.0.1:{port}"),
    ]);
    assert_eq!(code, 1, "{out}\n{err}");
    let s = checked_summary(&out);
    let r = responder(&s, "1/1");
    assert_eq!(n(r, "received"), 0, "{s}");
    let late = n(r, "late");
    assert!(
        late >= 2,
        "replies to the first two arrive before the end: {s}"
    );
    assert_eq!(codes(&s), ["replies_late"], "{s}");
    assert_eq!(
        hint(&s, "replies_late"),
        format!(
            "1/1: all {late} of its replies came after the 0.3 s timeout (counted lost): its \
             round trip is longer than that; raise -W"
        )
    );
}

/// A peer that sends every datagram back: our own frames, no system.
#[test]
fn our_own_frames_sent_back_are_named_a_loopback() {
    let echo = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = echo.local_addr().unwrap().port();
    let mirror = echo.try_clone().unwrap();
    let echoed = std::thread::spawn(move || {
        let mut buf = [0u8; 2048];
        let mut count = 0u64;
        mirror
            .set_read_timeout(Some(Duration::from_secs(3)))
            .unwrap();
        while let Ok((len, from)) = mirror.recv_from(&mut buf) {
            mirror.send_to(&buf[..len], from).unwrap();
            count += 1;
        }
        count
    });
    let link = format!("udpout:127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&["--json", "-q", "-c", "3", "-i", "200ms", &link]);
    assert_eq!(code, 1, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(codes(&s), ["own_frames_echoed"], "{s}");
    let sent_back = echoed.join().unwrap();
    assert!(
        hint(&s, "own_frames_echoed").contains(&format!("our own ({sent_back} from 250/190)")),
        "{s} (the peer sent back {sent_back})"
    );
}

/// A command to 1/1 on a link where only 7/1 is heard (a pymavlink vehicle
/// with system id 7, sending HEARTBEAT).
#[test]
fn a_command_to_a_target_never_heard_names_the_one_that_was() {
    let port = free_udp_port();
    let _peer = Peer::start(
        "responder.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--sysid", "7"],
    );
    let link = format!("udpout:127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&[
        "--json",
        "-q",
        "--probe",
        "command",
        "--target",
        "1/1",
        "-c",
        "2",
        "--retries",
        "1",
        &link,
    ]);
    assert_eq!(code, 1, "{out}\n{err}");
    let events = json_lines(&out);
    assert_schema(&events);
    let s = events
        .iter()
        .find(|e| e["type"] == "command_summary")
        .unwrap();
    assert_eq!(codes(s), ["wrong_target"], "{s}");
    assert!(
        hint(s, "wrong_target").ends_with("but 7/1 (quadrotor, px4) was heard: try --target 7/1"),
        "{s}"
    );
}

/// Nothing heard, but the only request is still within its timeout: too
/// early, not "nothing heard" (scripting.md's promise).
#[test]
fn a_run_that_ends_before_any_timeout_is_too_early_even_with_nothing_heard() {
    let silent = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let port = silent.local_addr().unwrap().port();
    let link = format!("udpout:127.0.0.1:{port}");
    let (code, out, err) = run_mavping(&["--json", "-q", "-c", "2", "-w", "0.5", &link]);
    assert_eq!(code, 1, "{out}\n{err}");
    let s = checked_summary(&out);
    assert_eq!(codes(&s), ["too_early"], "{s}");
    assert!(hint(&s, "too_early").contains("2 s timeout"), "{s}");
}
