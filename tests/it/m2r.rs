//! `m2r://`: mavping against a vehicle behind a mavlink2rest-shaped
//! WebSocket (tests/peers/m2r_peer.py: every message a JSON text as
//! mavlink2rest writes it, what mavping sends read strictly as
//! mavlink2rest reads it), and against what is not one.

use crate::common::*;

/// `-c COUNT` of `probe` over m2r:// to a peer dropping a seeded quarter
/// of its answers: mavping's counts are the peer's truth.
fn counts_equal_the_peer_s_truth(probe: &str, kind: &str) {
    let port = free_tcp_port();
    let peer = Peer::start(
        "m2r_peer.py",
        &[&port.to_string(), "--drop", "0.25", "--seed", "5"],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "40",
        "-i",
        "20ms",
        "-W",
        "500ms",
        "--probe",
        probe,
        "--json",
        "-q",
        &format!("m2r://127.0.0.1:{port}"),
    ]);
    let truth = peer.finish();
    assert!(code == 0 || code == 1, "{out}\n{err}");
    let t = |k: &str| n(&truth, &format!("{kind}_{k}"));
    // Every request sent reached the vehicle as a message it could read.
    assert_eq!(
        (t("requests"), n(&truth, "not_converted")),
        (40, 0),
        "{truth}"
    );
    assert!(t("dropped") > 0 && t("replies") > 0, "{truth}");
    let s = checked_summary(&out);
    assert_eq!(
        s["link"],
        format!("m2r://127.0.0.1:{port}/v1/ws/mavlink"),
        "{s}"
    );
    let r = responder(&s, "1/1");
    assert_eq!(
        (
            n(r, "sent"),
            n(r, "received"),
            n(r, "lost"),
            n(r, "duplicate")
        ),
        (40, t("replies"), t("dropped"), 0),
        "{r}\n{truth}"
    );
}

#[test]
fn ping_counts_over_mavlink2rest_json_are_the_vehicle_s_truth() {
    counts_equal_the_peer_s_truth("ping", "ping");
}

#[test]
fn timesync_counts_over_mavlink2rest_json_are_the_vehicle_s_truth() {
    counts_equal_the_peer_s_truth("timesync", "timesync");
}

#[test]
fn texts_that_are_no_message_and_unknown_types_are_skipped_and_counted() {
    let port = free_tcp_port();
    let peer = Peer::start(
        "m2r_peer.py",
        &[&port.to_string(), "--junk", "3", "--unknown", "4"],
    );
    let (code, out, err) = run_mavping(&[
        "-c",
        "5",
        "-i",
        "20ms",
        "-W",
        "500ms",
        "--probe",
        "ping",
        "--json",
        "-q",
        &format!("m2r://127.0.0.1:{port}"),
    ]);
    let truth = peer.finish();
    assert_eq!(code, 0, "{out}\n{err}");
    let s = checked_summary(&out);
    let r = responder(&s, "1/1");
    assert_eq!((n(r, "sent"), n(r, "received")), (5, 5), "{r}");
    let f = &s["frames"];
    assert_eq!(
        n(f, "skipped_bytes"),
        n(&truth, "junk_bytes"),
        "{f} {truth}"
    );
    assert_eq!(n(f, "unknown_id"), n(&truth, "unknown"), "{f} {truth}");
    assert_eq!((n(&truth, "junk"), n(&truth, "unknown")), (3, 4));
    // Each kind told once, however many came.
    assert_eq!(
        err.matches("skipped a text that is no message").count(),
        1,
        "{err}"
    );
    assert_eq!(
        err.matches("a type this build does not know").count(),
        1,
        "{err}"
    );
}

#[test]
fn nothing_but_junk_ends_the_link_in_one_line() {
    let port = free_tcp_port();
    let _peer = Peer::start("m2r_peer.py", &[&port.to_string(), "--junk", "25"]);
    let (code, out, err) = run_mavping(&["-c", "3", &format!("m2r://127.0.0.1:{port}")]);
    assert_eq!(code, 2, "{out}\n{err}");
    // The first junk is told as skipped; the twentieth ends the link.
    let last = err.lines().last().unwrap_or_default();
    assert_eq!(err.lines().count(), 2, "{err}");
    assert!(
        last.contains("20 messages and no MAVLink message among them")
            && last.contains("junk 19: not a MAVLink message")
            && last.contains("is it a mavlink2rest WebSocket?"),
        "{err}"
    );
}

#[test]
fn a_binary_websocket_client_to_the_json_peer_says_it_is_m2r() {
    let port = free_tcp_port();
    let _peer = Peer::start("m2r_peer.py", &[&port.to_string()]);
    let (code, out, err) = run_mavping(&[
        "-c",
        "3",
        "-W",
        "300ms",
        &format!("ws://127.0.0.1:{port}/v1/ws/mavlink"),
    ]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("text message where MAVLink's binary frames were expected")
            && err.contains("m2r://"),
        "{err}"
    );
}

#[test]
fn m2r_to_a_binary_websocket_server_says_it_is_ws() {
    let port = free_tcp_port();
    let _responder = Peer::start("responder.py", &[&format!("wsserver:127.0.0.1:{port}")]);
    let (code, out, err) = run_mavping(&[
        "-c",
        "3",
        "-W",
        "300ms",
        &format!("m2r://127.0.0.1:{port}/"),
    ]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!(
            "m2r://127.0.0.1:{port}/v1/ws/mavlink: it sent MAVLink's binary frames"
        )) && err.contains("a binary WebSocket endpoint is ws://"),
        "{err}"
    );
}

#[test]
fn a_path_without_a_websocket_says_so() {
    let port = free_tcp_port();
    let peer = Peer::start("m2r_peer.py", &[&port.to_string()]);
    let (code, out, err) = run_mavping(&["-c", "1", &format!("m2r://127.0.0.1:{port}/mavlink")]);
    assert_eq!(code, 2, "{out}\n{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("HTTP 404") && err.contains("no WebSocket at that path"),
        "{err}"
    );
    assert_eq!(n(&peer.finish(), "refused"), 1);
}

#[test]
fn bad_m2r_urls_exit_2_in_one_line() {
    for (url, says) in [
        ("m2r://:8088/", "missing host"),
        ("m2r://127.0.0.1:0/", "not a port"),
        ("m2r://127.0.0.1:http/", "not a port"),
        ("m2rs://[::1/", "missing ']'"),
        ("m2r:127.0.0.1:8088", "unknown form"),
    ] {
        let (code, out, err) = run_mavping(&["-c", "1", url]);
        assert_eq!(code, 2, "{url}: {out}\n{err}");
        assert_eq!(err.lines().count(), 1, "{url}: {err}");
        assert!(
            err.contains(says) && err.contains("m2r://HOST"),
            "{url}: {err}"
        );
    }
}
