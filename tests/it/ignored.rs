//! Why a vehicle we hear well ignores us (issue 43), against peers that
//! ignore us for one known cause each: pymavlink's own signing check with
//! its signing clock 3 minutes ahead of ours, a vehicle that obeys its
//! ground station 255 only, a MAVLink 1-only vehicle, and a relay that
//! forwards the vehicle's frames but drops everything we send. Each
//! unanswered command or download names its cause by what was heard.

use serde_json::Value;

use crate::common::*;

const HEX_KEY: &str = "00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff";

/// A `--probe command` run's JSON summary (every line held to the schema).
fn command(link: &str, extra: &[&str]) -> (i32, Value) {
    let mut args = vec![
        "--json",
        "-q",
        "--probe",
        "command",
        "--target",
        "1/1",
        "-c",
        "1",
        "--retry-interval",
        "200ms",
        "--retries",
        "2",
        link,
    ];
    args.extend_from_slice(extra);
    let (code, out, err) = run_mavping(&args);
    let lines = json_lines(&out);
    assert_schema(&lines);
    let summary = lines
        .into_iter()
        .find(|l| l["type"] == "command_summary")
        .unwrap_or_else(|| panic!("no command_summary: {out}\n{err}"));
    (code, summary)
}

/// A `--probe params` run's JSON summary that gives up soon.
fn params(link: &str, extra: &[&str]) -> (i32, Value) {
    let mut args = vec![
        "--json",
        "-q",
        "--probe",
        "params",
        "-W",
        "300ms",
        "-i",
        "100ms",
        "--retries",
        "1",
        link,
    ];
    args.extend_from_slice(extra);
    let (code, out, err) = run_mavping(&args);
    let lines = json_lines(&out);
    assert_schema(&lines);
    let summary = lines
        .into_iter()
        .find(|l| l["type"] == "transfer_summary")
        .unwrap_or_else(|| panic!("no transfer_summary: {out}\n{err}"));
    (code, summary)
}

fn codes(summary: &Value) -> Vec<&str> {
    summary["hints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| h["code"].as_str().unwrap())
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

/// The one target's counts: (commands, acknowledged).
fn acked(summary: &Value) -> (u64, u64) {
    let t = &summary["targets"][0];
    (
        t["commands"].as_u64().unwrap(),
        t["acknowledged"].as_u64().unwrap(),
    )
}

/// A signing timestamp (10 µs units since 2015) as the hint writes it.
fn utc(stamp: u64) -> String {
    let at = std::time::UNIX_EPOCH
        + std::time::Duration::from_secs(1_420_070_400)
        + std::time::Duration::from_micros(stamp * 10);
    humantime::format_rfc3339_millis(at).to_string()
}

/// The number after `before` in `text`, up to the next space.
fn number_after(text: &str, before: &str) -> f64 {
    let at = text
        .find(before)
        .unwrap_or_else(|| panic!("{before:?} in {text}"))
        + before.len();
    let rest = &text[at..];
    rest[..rest.find(' ').unwrap()].parse().unwrap()
}

#[test]
fn a_vehicle_whose_signing_clock_is_3_minutes_ahead_refuses_ours_and_the_hint_says_by_how_much() {
    let port = free_udp_port();
    let link = format!("udpout:127.0.0.1:{port}");
    let peer = Peer::start(
        "signed_peer.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--key",
            HEX_KEY,
            "--heartbeat-hz",
            "10",
            "--clock-offset",
            "180",
            "--stamps",
        ],
    );
    let (code, s) = command(&link, &["--signing-key", HEX_KEY]);
    let truth = peer.finish();
    assert_eq!(code, 1, "{s}");
    assert_eq!(acked(&s), (1, 0), "{s}");
    // pymavlink's own check refused every command of ours (3 attempts)
    // and acknowledged none.
    assert_eq!(truth["rejected_commands"], 3, "{truth}");
    assert_eq!((&truth["commands"], &truth["acks"]), (&0.into(), &0.into()));
    assert_eq!(codes(&s), ["signing_clock_behind"], "{s}");
    let text = hint(&s, "signing_clock_behind");
    assert!(
        text.starts_with("our signing clock is ")
            && text
                .contains(" s behind 1/1 (quadrotor, px4)'s: its newest signature timestamp is ")
            && text.ends_with(
                "MAVLink 2 signing refuses a new stream more than 60 s behind the receiver's \
                 clock, so our signed frames are dropped as too old: set this computer's clock \
                 (or the vehicle's) right"
            ),
        "{text}"
    );
    // Its newest stamp is one the peer sent; ours was read as it came, on
    // the same wall clock 180 s behind the peer's, so the difference is
    // 180 s less the time it took to arrive (never more).
    let sent: Vec<String> = truth["stamps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| utc(t.as_u64().unwrap()))
        .collect();
    let theirs = &text[text.find("timestamp is ").unwrap() + 13..][..24];
    assert!(sent.iter().any(|t| t == theirs), "{theirs} not in {sent:?}");
    let behind = number_after(text, "our signing clock is ");
    assert!((179.0..=180.0).contains(&behind), "{text}");
}

#[test]
fn a_vehicle_behind_us_answers_and_a_download_from_one_ahead_names_the_clock() {
    let port = free_udp_port();
    let peer = Peer::start(
        "signed_peer.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--key",
            HEX_KEY,
            "--heartbeat-hz",
            "10",
            "--clock-offset",
            "-240",
        ],
    );
    // Behind us by 4 minutes: it takes our newer stamps, and answers.
    let link = format!("udpout:127.0.0.1:{port}");
    let (code, s) = command(&link, &["--signing-key", HEX_KEY]);
    assert_eq!((code, acked(&s)), (0, (1, 1)), "{s}");
    assert!(codes(&s).is_empty(), "{s}");
    peer.finish();

    let port = free_udp_port();
    let peer = Peer::start(
        "signed_peer.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--key",
            HEX_KEY,
            "--heartbeat-hz",
            "10",
            "--clock-offset",
            "180",
        ],
    );
    let link = format!("udpout:127.0.0.1:{port}");
    let (code, s) = params(&link, &["--signing-key", HEX_KEY]);
    let truth = peer.finish();
    assert_eq!(code, 1, "{s}");
    assert_eq!(s["last"]["ending"], "no_answer", "{s}");
    // Every PING beside the download refused too, none answered.
    assert_eq!(truth["replies"], 0, "{truth}");
    assert!(truth["rejected_pings"].as_u64().unwrap() > 0, "{truth}");
    assert_eq!(
        codes(&s),
        ["transfer_no_answer", "signing_clock_behind"],
        "{s}"
    );
    let behind = number_after(hint(&s, "signing_clock_behind"), "our signing clock is ");
    assert!((179.0..=180.0).contains(&behind), "{s}");
}

#[test]
fn a_vehicle_that_obeys_gcs_255_only_is_named_by_the_frames_it_addressed_to_255() {
    let port = free_udp_port();
    let link = format!("udpout:127.0.0.1:{port}");
    let peer = Peer::start(
        "picky_vehicle.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--gcs-sysid", "255"],
    );
    let (code, ignored) = command(&link, &[]);
    let (code_255, obeyed) = command(&link, &["--sysid", "255"]);
    // It serves no parameters: a download from it is named the same way.
    let (_, download) = params(&link, &[]);
    let truth = peer.finish();
    assert_eq!(
        codes(&download),
        ["transfer_no_answer", "sysid_enforced"],
        "{download}"
    );
    assert!(
        hint(&download, "sysid_enforced").ends_with("try --sysid 255"),
        "{download}"
    );
    assert_eq!(code, 1, "{ignored}");
    assert_eq!(acked(&ignored), (1, 0), "{ignored}");
    // Every command of 250's was ignored: the 3 attempts of the first run.
    assert_eq!(truth["ignored"], serde_json::json!({"250": 3}), "{truth}");
    assert_eq!(codes(&ignored), ["sysid_enforced"], "{ignored}");
    let text = hint(&ignored, "sysid_enforced");
    assert!(
        text.starts_with(
            "1/1 (quadrotor, ardupilotmega) addressed its frames to another ground station \
             and none to us (250): "
        ) && text.contains(" to system 255 (COMMAND_ACK, PING); ")
            && text.ends_with("try --sysid 255"),
        "{text}"
    );
    // As 255, each command is acknowledged and nothing is hinted.
    assert_eq!(code_255, 0, "{obeyed}");
    assert_eq!(acked(&obeyed), (1, 1), "{obeyed}");
    assert_eq!(truth["acks"], 1, "{truth}");
    assert!(codes(&obeyed).is_empty(), "{obeyed}");
}

#[test]
fn a_mavlink1_only_vehicle_reads_none_of_our_mavlink2_and_answers_mavlink1() {
    let port = free_udp_port();
    let link = format!("udpout:127.0.0.1:{port}");
    let peer = Peer::start(
        "picky_vehicle.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--mavlink1"],
    );
    let (code, v2) = command(&link, &[]);
    let (code_v1, v1) = command(&link, &["--mavlink", "1"]);
    let (_, download) = params(&link, &[]);
    let truth = peer.finish();
    assert_eq!(
        codes(&download),
        ["transfer_no_answer", "mavlink1_only"],
        "{download}"
    );
    assert_eq!(code, 1, "{v2}");
    assert_eq!(acked(&v2), (1, 0), "{v2}");
    assert_eq!(codes(&v2), ["mavlink1_only"], "{v2}");
    let text = hint(&v2, "mavlink1_only");
    assert!(
        text.starts_with("1/1 (quadrotor, ardupilotmega) sent MAVLink 1 only (")
            && text.ends_with(
                "frames) and our requests are MAVLink 2, which it may not read: try --mavlink 1"
            ),
        "{text}"
    );
    assert_eq!(code_v1, 0, "{v1}");
    assert_eq!(acked(&v1), (1, 1), "{v1}");
    assert!(codes(&v1).is_empty(), "{v1}");
    // What it could not read: the first run's 3 attempts; read: the
    // second's (the download asks no command).
    assert_eq!(
        (&truth["unread_commands"], &truth["acks"]),
        (&3.into(), &1.into()),
        "{truth}"
    );
}

/// A relay in front of `vehicle_port` that drops every frame we send
/// after the first (its plan always delivers a stream's first frame: our
/// HEARTBEAT, which tells the vehicle where to send), and forwards all
/// the vehicle sends.
fn filter(vehicle_port: u16) -> (Peer, String) {
    let vehicle = format!("127.0.0.1:{vehicle_port}");
    let mut relay = Peer::start(
        "fault_relay.py",
        &["--vehicle", &vehicle, "--drop-up", "1.0"],
    );
    let port = relay.read_line();
    (relay, format!("udpout:127.0.0.1:{port}"))
}

/// The relay's uplink figures: (frames from us, dropped).
fn uplink(truth: &Value) -> (u64, u64) {
    let up = &truth["up"][0];
    (
        up["frames"].as_u64().unwrap(),
        up["dropped"].as_u64().unwrap(),
    )
}

#[test]
fn a_filter_that_drops_what_we_send_leaves_a_command_and_a_download_answered_by_nothing() {
    let port = free_udp_port();
    let vehicle = Peer::start("picky_vehicle.py", &[&format!("udpin:127.0.0.1:{port}")]);
    let (relay, link) = filter(port);
    let (code, s) = command(&link, &[]);
    let relay_truth = relay.finish();
    let truth = vehicle.finish();
    assert_eq!(code, 1, "{s}");
    assert_eq!(acked(&s), (1, 0), "{s}");
    // Our HEARTBEAT went through, nothing after it: no command reached it.
    let (frames, dropped) = uplink(&relay_truth);
    assert_eq!(dropped, frames - 1, "{relay_truth}");
    assert_eq!(truth["acks"], 0, "{truth}");
    assert_eq!(codes(&s), ["never_answered"], "{s}");
    let text = hint(&s, "never_answered");
    assert!(
        text.starts_with("1/1 (quadrotor, ardupilotmega) is heard (")
            && text.ends_with(
                "frames) but answered nothing of ours: not the REQUEST_MESSAGE command, and \
                 none of its frames was addressed to us (250/190): a router or filter between \
                 may drop what we send, or the vehicle ignores it"
            ),
        "{text}"
    );

    // A download from a vehicle that serves parameters, behind the same
    // filter: neither its request nor a PING or TIMESYNC beside it answered.
    let port = free_udp_port();
    let vehicle = Peer::start("transfer_vehicle.py", &[&port.to_string()]);
    let (relay, link) = filter(port);
    let args = [
        "--json",
        "-q",
        "--probe",
        "params",
        "-W",
        "700ms",
        "-i",
        "100ms",
        "--retries",
        "2",
        &link,
    ];
    let (code, out, err) = run_mavping(&args);
    let relay_truth = relay.finish();
    vehicle.finish();
    let lines = json_lines(&out);
    assert_schema(&lines);
    let s = lines
        .into_iter()
        .find(|l| l["type"] == "transfer_summary")
        .unwrap_or_else(|| panic!("no transfer_summary: {out}\n{err}"));
    assert_eq!(code, 1, "{s}");
    assert_eq!(s["last"]["ending"], "no_answer", "{s}");
    let (frames, dropped) = uplink(&relay_truth);
    assert_eq!(dropped, frames - 1, "{relay_truth}");
    assert_eq!(codes(&s), ["transfer_no_answer", "never_answered"], "{s}");
    let text = hint(&s, "never_answered");
    assert!(
        text.starts_with("1/1 (quadrotor, ardupilotmega) is heard (")
            && text.contains(
                "frames) but answered nothing of ours: not the request for the parameter list, \
                 nor any of our "
            )
            && text.ends_with(
                "PING and TIMESYNC requests, and none of its frames was addressed to us \
                 (250/190): a router or filter between may drop what we send, or the vehicle \
                 ignores it"
            ),
        "{text}"
    );
}

/// An echo run's summary (PING or TIMESYNC), its lines held to the schema.
fn echo(link: &str, extra: &[&str]) -> (i32, Value) {
    let mut args = vec!["-c", "4", "-i", "100ms", "-W", "300ms", "--json", link];
    args.extend_from_slice(extra);
    let (code, out, err) = run_mavping(&args);
    let lines = json_lines(&out);
    assert_schema(&lines);
    let summary = lines
        .into_iter()
        .find(|l| l["type"] == "summary")
        .unwrap_or_else(|| panic!("no summary: {out}{err}"));
    (code, summary)
}

#[test]
fn an_echo_probe_left_unanswered_gets_the_same_evidence() {
    // The vehicle whose signing clock is 3 minutes ahead refuses our PINGs.
    let port = free_udp_port();
    let link = format!("udpout:127.0.0.1:{port}");
    let peer = Peer::start(
        "signed_peer.py",
        &[
            &format!("udpin:127.0.0.1:{port}"),
            "--key",
            HEX_KEY,
            "--heartbeat-hz",
            "10",
            "--clock-offset",
            "180",
        ],
    );
    let (code, s) = echo(&link, &["--probe", "ping", "--signing-key", HEX_KEY]);
    peer.finish();
    assert_eq!(code, 1, "{s}");
    assert!(codes(&s).contains(&"signing_clock_behind"), "{s}");
    let behind = number_after(hint(&s, "signing_clock_behind"), "our signing clock is ");
    assert!((179.0..=180.5).contains(&behind), "{behind}");

    // The vehicle that answers GCS 255 only leaves our TIMESYNCs unanswered:
    // named by the frames it addressed to 255, not guessed.
    let port = free_udp_port();
    let link = format!("udpout:127.0.0.1:{port}");
    let peer = Peer::start(
        "picky_vehicle.py",
        &[&format!("udpin:127.0.0.1:{port}"), "--gcs-sysid", "255"],
    );
    let (code, s) = echo(&link, &["--probe", "timesync"]);
    peer.finish();
    assert_eq!(code, 1, "{s}");
    let text = hint(&s, "sysid_enforced");
    assert!(
        text.contains("addressed its frames to another ground station and none to us (250)")
            && text.ends_with("try --sysid 255"),
        "{text}"
    );
}
